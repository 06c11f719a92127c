"""A user function that fails inside Exudyn's own step loop (found running Exudyn's test
models through ``lgt-bridge run``): the drop-in says so in the bridge's own error, naming
the user function and its Python error, never Exudyn's raw exception, on every kind of
method (in Exudyn's loop, before the first step or between steps: a ModelError; inside a
step of the bridge: the StepError of a failed step, the state kept)."""
import functools

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.errors import LGTError, ModelError  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

import exudyn_sweep_models as sm  # noqa: E402

METHODS = ["dopri5", "rkmk4", "radau5", "genalpha", "scipy:RK45"]


def _exudyns_own_error(build):
    """Exudyn's own solver on the same model: it raises too (the model is at fault)."""
    mbs, s = build()
    with pytest.raises(Exception) as info:
        exu.SolveDynamic(mbs, s)
    assert type(info.value).__module__.startswith("exudyn")
    return mbs.systemData.GetTime()


@pytest.mark.parametrize("sensor", [False, True], ids=["no-outputs", "acceleration-sensor"])
@pytest.mark.parametrize("method", METHODS)
def test_a_user_function_of_an_older_signature_is_the_bridges_error(method, sensor):
    build = functools.partial(sm.spring_with_old_user_function, acceleration_sensor=sensor)
    _exudyns_own_error(build)
    mbs, s = build()
    with pytest.raises(LGTError) as info:
        SolveDynamic(mbs, s, method=method)
    msg = str(info.value)
    assert "springForceUserFunction" in msg and "TypeError" in msg and "fix it" in msg
    assert "Python file" not in msg and "lgt_exudyn" not in msg   # no pointer to a frame of ours
    assert "At:" not in msg                                       # Exudyn's traceback left out


@pytest.mark.parametrize("method", METHODS)
def test_a_pre_step_user_function_raising_mid_run_stops_where_exudyn_stops(method):
    t_exudyn = _exudyns_own_error(sm.prestep_raising_at)
    mbs, s = sm.prestep_raising_at()
    with pytest.raises(ModelError, match=r"PreStepUserFunction.*ValueError: controller input missing"):
        SolveDynamic(mbs, s, method=method)
    assert mbs.systemData.GetTime() == pytest.approx(t_exudyn, abs=1e-12) == pytest.approx(0.05)


@pytest.mark.parametrize("method", METHODS)
def test_an_offset_user_function_of_an_older_signature_is_the_bridges_error(method):
    """Exudyn calls a constraint's offset user function while the bridge reads the
    constraint Jacobian (before the first step): its TypeError was Exudyn's raw exception."""
    build = functools.partial(sm.driven_coordinate, old_signature=True)
    _exudyns_own_error(lambda: build()[:2])
    mbs, s, _ = build()
    with pytest.raises(ModelError) as info:
        SolveDynamic(mbs, s, method=method)
    msg = str(info.value)
    assert "offsetUserFunction" in msg and "TypeError" in msg and "fix it" in msg
    assert "Python file" not in msg and "lgt_exudyn" not in msg and "At:" not in msg


@pytest.mark.parametrize("method", METHODS)
def test_the_coordinate_driven_by_its_offset_user_function_follows_it(method):
    mbs, s, node = sm.driven_coordinate()
    SolveDynamic(mbs, s, method=method)
    u = mbs.GetNodeOutput(node, exu.OutputVariableType.Displacement)[0]
    assert u == pytest.approx(0.1 * 0.5 * (1 - np.cos(0.5 * np.pi * 1.0)), abs=1e-10)   # 0.05 at t = 1


def test_a_prestep_function_ending_the_run_is_said_as_exudyn_says_it():
    """A pre-step user function returning False ends Exudyn's loop early: the drop-in returns
    True as Exudyn's own solver does, at Exudyn's time and state, and its statistics' message
    says where the loop ended (it said "reached endTime")."""
    from exudyn.utilities import MassPoint, NodePoint
    from exudyn_special_models import _system, settings

    def build():
        mbs = _system()
        n = mbs.AddNode(NodePoint(referenceCoordinates=[0, 0, 0], initialVelocities=[1, 0, 0]))
        mbs.AddObject(MassPoint(mass=1, nodeNumber=n))
        mbs.SetPreStepUserFunction(lambda m, t: t < 0.05)
        mbs.Assemble()
        return mbs, settings(0.1, 100)
    mbs, s = build()
    assert mbs.SolveDynamic(s, showHints=False)
    t_ref, x_ref = mbs.systemData.GetTime(), mbs.systemData.GetODE2Coordinates()[0]
    mbs, s = build()
    assert SolveDynamic(mbs, s, method="dopri5") is True
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and "ended at t = 0.05" in st["message"]
    assert abs(mbs.systemData.GetTime() - t_ref) < 1e-12
    assert abs(mbs.systemData.GetODE2Coordinates()[0] - x_ref) < 1e-12
