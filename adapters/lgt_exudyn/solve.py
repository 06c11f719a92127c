"""Drop-in replacement for ``exudyn.SolveDynamic`` on the bridge's integrators.

The bridge plugs into Exudyn's own step loop (``MainSolverImplicitSecondOrder.
SetUserFunctionNewton``): Exudyn keeps its time loop, sensors, solution file and
final state; each of its steps is computed by the bridge from the state at the
start of the step. Adaptive methods take as many internal steps as their error
control needs between two Exudyn output steps.
"""
import time


from lgt_bridge import auto as _auto
from lgt_bridge.errors import InputError, StepError
from lgt_bridge.integrators.base import StepFailed
from lgt_bridge.progress import simulation_bar
from lgt_bridge.simulate import Driver, _check_inputs, make_stepper

from .model import ExudynModel

ADAPTIVE = ("dopri5", "dop853")


def SolveDynamic(mbs, simulationSettings=None, solverType=None, updateInitialValues=False,
                 storeSolver=True, showHints=False, showCausingItems=True, autoAssemble=True, *,
                 method="dopri5", group="SE3", chart="exp", rtol=None, atol=None, rho_inf=0.9,
                 project=True, verbose=False, accelerations=True, progress=None):
    """Like ``exudyn.SolveDynamic`` (same positional arguments; ``solverType`` is
    ignored), integrated by the bridge with ``method``/``group``/``chart``.

    Honours ``timeIntegration.startTime``, ``endTime``, ``numberOfSteps`` (the output
    step; fixed-step methods step with it), ``automaticStepSize`` with
    ``relativeTolerance``/``absoluteTolerance`` for adaptive methods (``rtol``/``atol``
    override them; without either, 1e-6/1e-8), sensors and the solution file as configured.
    ``group``/``chart`` may be "auto" as in :func:`lgt_bridge.simulate`. ``progress``:
    a tqdm bar on stderr as in ``simulate`` (None: only for runs longer than about 1 s on a
    terminal, never in CI; True/False force it). ``verbose`` prints one line saying which
    method, group, chart and tolerances were used (see :func:`describe`). Returns True, and
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
    if not t1 > t0:
        raise InputError(f"simulationSettings.timeIntegration.endTime = {t1} must be greater than "
                         f"simulationSettings.timeIntegration.startTime = {t0}; set endTime > startTime.")
    h_out = (t1 - t0) / n
    adaptive = method in ADAPTIVE or str(method).startswith("scipy:")
    tol_source = "given"
    if rtol is None or atol is None:
        tol_source = "default"
        if adaptive and ti.automaticStepSize:
            tol_source = "timeIntegration.relative/absoluteTolerance"
            rtol = rtol if rtol is not None else float(ti.relativeTolerance)
            atol = atol if atol is not None else float(ti.absoluteTolerance)
    rtol = 1e-6 if rtol is None else rtol
    atol = 1e-8 if atol is None else atol
    dt = None if method in ADAPTIVE else h_out
    _check_inputs(model, (t0, t1), method, dt if dt is not None else h_out, rtol, atol, None, None,
                  None, 1)
    group_asked, chart_asked = group, chart
    if _auto.wants_auto(group, chart):
        choice = _auto.choose(model, group, chart, method=method, project=project)
        group, chart = choice.groups, choice.charts
    stepper, dt = make_stepper(model, method, group, chart, dt=dt, rtol=rtol, atol=atol,
                               project=project, rho_inf=rho_inf, span=(t0, t1))
    drv = Driver(model, stepper, dt, t0, model.q0, model.V0, t_end=t1)
    bar = simulation_bar(progress, t0, t1, drv, stepper, desc="SolveDynamic")
    on_step = None if bar.mode is None else (lambda t, q, V: bar.step())
    sd = mbs.systemData
    failure = []
    wall0 = time.perf_counter()

    def newton(solver, mbs_, settings):
        h = solver.it.currentStepSize
        ts = sd.GetTime(exu.ConfigurationType.StartOfStep)
        try:
            q_out, V_out = drv.advance_to(ts + h, on_step)
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
        bar.close()
    st = dict(method=method, group=_summary(group, group_asked), chart=_summary(chart, chart_asked),
              rtol=rtol if adaptive else None, atol=atol if adaptive else None,
              tolerance_source=tol_source if adaptive else None, dt=None if adaptive else h_out,
              n_steps=drv.n_steps, n_f=stepper.prob.n_f,
              n_rejected=stepper.n_rejected, n_newton=stepper.n_newton,
              wall_s=time.perf_counter() - wall0, exudyn_steps=n, success=not failure,
              message=failure[0] if failure else "reached endTime")
    if stepper.projector is not None:
        st["constraint_after_projection"] = stepper.projector.max_after
    mbs.sys["lgtBridgeStats"] = st
    if storeSolver:
        mbs.sys["dynamicSolver"] = solver
    if verbose:
        print(f"lgt-bridge: SolveDynamic {describe(st)}: {drv.n_steps} steps, {stepper.prob.n_f} "
              f"f evaluations, {st['wall_s']:.3f} s")
    if failure:
        raise StepError(f"lgt_bridge SolveDynamic: {failure[0]} The system is left at t = {drv.t:.9g}.")
    if updateInitialValues:
        sd.SetODE2Coordinates(sd.GetODE2Coordinates(), exu.ConfigurationType.Initial)
        sd.SetODE2Coordinates_t(sd.GetODE2Coordinates_t(), exu.ConfigurationType.Initial)
    return True


def _summary(resolved, asked):
    """A group/chart for the statistics: the value, or for "auto" what it chose ("auto→SE3")."""
    if isinstance(resolved, str):
        return resolved
    picked = sorted(set(resolved))
    return ("auto→" if asked == "auto" else "") + ",".join(picked)


def describe(st):
    """One line: method, group, chart and tolerances (or step) of a SolveDynamic run."""
    if st.get("rtol") is not None:
        src = {"given": "", "default": " (bridge default)"}.get(
            st["tolerance_source"], f" (from simulationSettings.{st['tolerance_source']})")
        tol = f"rtol={st['rtol']:g}, atol={st['atol']:g}{src}"
    else:
        tol = f"fixed step {st['dt']:g} s (from endTime/numberOfSteps)"
    return f"{st['method']} on {st['group']}/{st['chart']}, {tol}"
