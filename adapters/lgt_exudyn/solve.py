"""Drop-in replacement for ``exudyn.SolveDynamic`` on the bridge's integrators.

The bridge plugs into Exudyn's own step loop (``MainSolverImplicitSecondOrder.
SetUserFunctionNewton``): Exudyn keeps its time loop, sensors, solution file and
final state; each of its steps is computed by the bridge from the state at the
start of the step. Adaptive methods take as many internal steps as their error
control needs between two Exudyn output steps.
"""
import time


from lgt_bridge.errors import InputError, StepError
from lgt_bridge.integrators.base import StepFailed
from lgt_bridge.simulate import Driver, _check_inputs, make_stepper

from .model import ExudynModel

ADAPTIVE = ("dopri5", "dop853")


def SolveDynamic(mbs, simulationSettings=None, solverType=None, updateInitialValues=False,
                 storeSolver=True, showHints=False, showCausingItems=True, autoAssemble=True, *,
                 method="dopri5", group="SE3", chart="exp", rtol=None, atol=None, rho_inf=0.9,
                 project=True, verbose=False, accelerations=True):
    """Like ``exudyn.SolveDynamic`` (same positional arguments; ``solverType`` is
    ignored), integrated by the bridge with ``method``/``group``/``chart``.

    Honours ``timeIntegration.startTime``, ``endTime``, ``numberOfSteps`` (the output
    step; fixed-step methods step with it), ``automaticStepSize`` with
    ``relativeTolerance``/``absoluteTolerance`` for adaptive methods (``rtol``/``atol``
    override them), sensors and the solution file as configured. Returns True, and
    leaves the final state in the system (``accelerations``: also the engine's
    accelerations after each output step, one more f evaluation each, for the solution
    file and acceleration sensors). A failed step raises StepError with the
    system at the last good state; statistics are in ``mbs.sys['lgtBridgeStats']``.
    """
    import exudyn as exu
    if simulationSettings is None:
        simulationSettings = exu.SimulationSettings()
    if not getattr(mbs, "systemIsConsistent", False) and autoAssemble:
        mbs.Assemble()
    model = ExudynModel(mbs)
    ti = simulationSettings.timeIntegration
    t0, t1, n = float(ti.startTime), float(ti.endTime), int(ti.numberOfSteps)
    if n <= 0:
        raise InputError(f"simulationSettings.timeIntegration.numberOfSteps = {n} must be positive.")
    h_out = (t1 - t0) / n
    adaptive = method in ADAPTIVE or str(method).startswith("scipy:")
    if adaptive and ti.automaticStepSize:
        rtol = rtol if rtol is not None else float(ti.relativeTolerance)
        atol = atol if atol is not None else float(ti.absoluteTolerance)
    rtol = 1e-6 if rtol is None else rtol
    atol = 1e-8 if atol is None else atol
    dt = None if method in ADAPTIVE else h_out
    _check_inputs(model, (t0, t1), method, dt if dt is not None else h_out, rtol, atol, None, None,
                  None, 1)
    stepper, dt = make_stepper(model, method, group, chart, dt=dt, rtol=rtol, atol=atol,
                               project=project, rho_inf=rho_inf, span=(t0, t1))
    drv = Driver(model, stepper, dt, t0, model.q0, model.V0, t_end=t1)
    sd = mbs.systemData
    failure = []
    wall0 = time.perf_counter()

    def newton(solver, mbs_, settings):
        h = solver.it.currentStepSize
        ts = sd.GetTime(exu.ConfigurationType.StartOfStep)
        try:
            q_out, V_out = drv.advance_to(ts + h)
        except StepFailed as exc:
            failure.append(str(exc))
            model.write_back(stepper.q, stepper.V, drv.t)
            solver.it.endTime = drv.t          # stop Exudyn's loop at the last good state
            return True
        model.write_back(q_out, V_out, ts + h)
        if accelerations:      # Exudyn's solution file and acceleration sensors read them
            sd.SetODE2Coordinates_tt(model.accelerations(q_out, V_out, ts + h))
        return True

    solver = exu.MainSolverImplicitSecondOrder()
    solver.SetUserFunctionNewton(mbs, newton)
    ti_auto = ti.automaticStepSize
    ti.automaticStepSize = False                 # Exudyn steps at the output interval
    try:
        solver.SolveSystem(mbs, simulationSettings)
    finally:
        ti.automaticStepSize = ti_auto
    st = dict(method=method, group=group, chart=chart, n_steps=drv.n_steps, n_f=stepper.prob.n_f,
              n_rejected=stepper.n_rejected, n_newton=stepper.n_newton,
              wall_s=time.perf_counter() - wall0, exudyn_steps=n, success=not failure,
              message=failure[0] if failure else "reached endTime")
    if stepper.projector is not None:
        st["constraint_after_projection"] = stepper.projector.max_after
    mbs.sys["lgtBridgeStats"] = st
    if storeSolver:
        mbs.sys["dynamicSolver"] = solver
    if verbose:
        print(f"lgt-bridge: {method} on {group}/{chart}: {drv.n_steps} steps, {stepper.prob.n_f} "
              f"f evaluations, {st['wall_s']:.3f} s")
    if failure:
        raise StepError(f"lgt_bridge SolveDynamic: {failure[0]} The system is left at t = {drv.t:.9g}.")
    if updateInitialValues:
        sd.SetODE2Coordinates(sd.GetODE2Coordinates(), exu.ConfigurationType.Initial)
        sd.SetODE2Coordinates_t(sd.GetODE2Coordinates_t(), exu.ConfigurationType.Initial)
    return True
