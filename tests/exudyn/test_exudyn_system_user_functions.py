"""Exudyn's system-level user functions the bridge must honour: a PreNewtonResidualUserFunction
(``mbs.SetPreNewtonResidualUserFunction``) that sets a load from the state before each
residual (Exudyn's mainSystemUserFunctionsTest.py replicates a spring-damper so), and a
PostNewtonUserFunction that reads the solver from ``mbs.sys['dynamicSolver']`` during the run
(Exudyn's postNewtonStepContactTest.py).

The bridge never called it: the load kept its initial value 0 and the mass stayed where it
started (0.2 m at t = 2 through every method; Exudyn: -1.13e-3 m). Now it is called before each
ODE2 residual the bridge computes, as Exudyn calls it before each Newton residual."""
import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.errors import StepError  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

from exudyn_sweep_models import post_newton_contact, residual_spring  # noqa: E402


def _x(mbs, node):
    return float(np.ravel(mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates))[0])


def _oscillator(t):
    """The spring-damper's own motion (4 kg, k = 12000, d = 20, x0 = 0.2, v0 = 0)."""
    m, k, d = 4.0, 12000.0, 20.0
    delta, w = d / (2 * m), np.sqrt(k / m - (d / (2 * m)) ** 2)
    return 0.2 * np.exp(-delta * t) * (np.cos(w * t) + delta / w * np.sin(w * t))


def test_exudyns_own_solver_converges_to_the_spring_dampers_motion():
    """The reference: Exudyn's own solver on this model converges to the analytic motion (at
    first order: the load is set from the state before each Newton residual; measured 1.3e-4
    m at 5000 steps, 1.25e-5 m at 50000)."""
    errs = []
    for n in (5000, 50000):
        mbs, s, node = residual_spring(0.5, n)
        mbs.SolveDynamic(s)
        errs.append(abs(_x(mbs, node) - _oscillator(0.5)))
    assert errs[1] < errs[0] / 5 and errs[1] < 2e-5, errs


@pytest.mark.parametrize("method, tol", [("dopri5", 1e-7), ("genalpha", 2e-4)])
def test_a_residual_user_function_sets_its_load_at_every_state(method, tol):
    """The mass swings on the replicated spring as on a real one, to the analytic motion:
    dopri5 at the script's settings within 1e-7 m (measured 5e-12), genalpha at 1000 steps
    within 2e-4 m (measured 7.3e-5; Exudyn's own at those steps 1.6e-3)."""
    mbs, s, node = residual_spring(0.5, 1000)
    SolveDynamic(mbs, s, method=method)
    assert mbs.sys["lgtBridgeStats"]["success"]
    assert abs(_x(mbs, node) - _oscillator(0.5)) < tol


def test_a_residual_user_function_that_raises_is_named():
    """Its exception (not Exudyn's: the bridge calls it) ends the run with the bridge's error
    naming the function, the time and the exception; the steps before are kept."""
    mbs, s, node = residual_spring(0.5, 100, raising=True)
    with pytest.raises(StepError, match=r"PreNewtonResidualUserFunction raised at t = 0\.10\d*: AttributeError: "
                                        r".*Coordinate.*left at t = 0\.09\d*\.$"):
        SolveDynamic(mbs, s, method="dopri5")


def test_user_functions_read_the_solver_during_the_run():
    """Exudyn stores its solver in mbs.sys['dynamicSolver'] before the run, and a
    PostNewtonUserFunction reads its step size there; the bridge stored it after the run
    (the user function's KeyError ended the run at t = 0). Now dopri5 runs the bouncing mass,
    within 1e-5 m of Exudyn's own solver refined 10× further (measured 6e-7 m at 1000 output
    steps against 10000)."""
    mbs, s, node = post_newton_contact(0.5, 10000)
    mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.TrapezoidalIndex2)
    ref = mbs.GetNodeOutput(node, exu.OutputVariableType.Position)[1]
    mbs, s, node = post_newton_contact(0.5, 1000)
    SolveDynamic(mbs, s, method="dopri5")
    assert mbs.sys["lgtBridgeStats"]["success"]
    assert abs(mbs.GetNodeOutput(node, exu.OutputVariableType.Position)[1] - ref) < 1e-5


def test_a_redo_rejected_by_the_error_control_retries_with_the_steps_own_data():
    """The bouncing mass at the script's own 100 steps (Exudyn's largest step 5 ms): the
    contact closes within a step, PostNewton sets the data coordinate, the redo with the
    spring on is rejected by dopri5's error control, and the shorter retry began with the
    data left at 1: the spring pulled before the contact closed, every step up to the contact
    was cut down to h_event, and the mass ended 5.2e-4 m off Exudyn refined (at 1e-8 and
    1e-10 alike). The retry now starts with the step's own data: within 1e-5 m, as at 1000
    steps (measured 5.7e-7)."""
    mbs, s, node = post_newton_contact(0.5, 10000)
    mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.TrapezoidalIndex2)
    ref = mbs.GetNodeOutput(node, exu.OutputVariableType.Position)[1]
    mbs, s, node = post_newton_contact(0.5, 100)
    SolveDynamic(mbs, s, method="dopri5")
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and st["n_steps"] < 1000            # (measured 372; 387 before)
    assert abs(mbs.GetNodeOutput(node, exu.OutputVariableType.Position)[1] - ref) < 1e-5


def test_data_coordinates_a_pre_step_user_function_sets_are_kept():
    """Exudyn's lugreFrictionTest.py, pulled 10× faster: its pre-step user function switches
    the friction from stick to slip through a data coordinate. SolveDynamic put the bridge's
    own data back after that function had run, so the mass never slipped (3.0e-5 m at
    t = 1.5 through both methods, 2e-5 on the script itself against Exudyn's 1.94 m). Now
    genalpha at Exudyn's 3000 steps gives Exudyn's own result to 1e-7 m (measured 1e-9), and
    dopri5 lies within 1e-3 m of Exudyn refined 10× (measured 8e-5: the stick/slip decisions
    are taken at Exudyn's steps, so the motion depends on them)."""
    from exudyn_sweep_models import prestep_stick_slip
    mbs, s, node = prestep_stick_slip(1.5, 3000, speed=10.0)
    mbs.SolveDynamic(s)
    ref = _x(mbs, node)
    mbs, s, node = prestep_stick_slip(1.5, 30000, speed=10.0)
    mbs.SolveDynamic(s)
    refined = _x(mbs, node)
    assert refined > 0.2                                    # the mass slipped
    for method, target, tol in (("genalpha", ref, 1e-7), ("dopri5", refined, 1e-3)):
        mbs, s, node = prestep_stick_slip(1.5, 3000, speed=10.0)
        SolveDynamic(mbs, s, method=method)
        assert mbs.sys["lgtBridgeStats"]["success"]
        assert abs(_x(mbs, node) - target) < tol, (method, _x(mbs, node), target)
