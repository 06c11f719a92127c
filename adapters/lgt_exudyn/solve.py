"""Drop-in replacement for ``exudyn.SolveDynamic`` on the bridge's integrators.

The bridge plugs into Exudyn's own step loop (``MainSolverImplicitSecondOrder.
SetUserFunctionNewton``): Exudyn keeps its time loop, sensors, solution file and
final state (so ``solution.file.writePeriod`` and ``solution.sensors.writePeriod`` work
as with Exudyn's own solvers); each of its steps is computed by the bridge from the
state at the start of the step. Adaptive methods step freely, as their error control
needs, and interpolate Exudyn's output steps with their dense output.
"""
import sys
import time
import warnings

import numpy as np

from lgt_bridge import events as _events
from lgt_bridge.errors import InputError, LGTError, ModelNote, StepError
from lgt_bridge.integrators import registry
from lgt_bridge.integrators.genalpha import Newmark
from lgt_bridge.lgt import DEFAULT_GROUP
from lgt_bridge.progress import simulation_bar
from lgt_bridge.simulation import Simulation
from lgt_bridge.validation import check_inputs

from .contact import note_explicit_law
from .engine import engine_error
from .hooks import general_contacts, refuse_sliding_joints
from .model import ExudynModel
from .outputs import OutputRows, outputs_read

_noted = set()          # one-time notes already printed in this process


def _note_once(key, text):
    if key not in _noted:
        _noted.add(key)
        print(f"lgt-bridge: note: {text}", file=sys.stderr)


def SolveDynamic(mbs, simulationSettings=None, solverType=None, updateInitialValues=False,
                 storeSolver=True, showHints=False, showCausingItems=True, autoAssemble=True, *,
                 method="dopri5", group=DEFAULT_GROUP, chart="exp", rtol=None, atol=None, rho_inf=None,
                 project=True, verbose=None, accelerations=None, progress=None, max_step="exudyn",
                 events=None):
    """Like ``exudyn.SolveDynamic``, integrated by the bridge with ``method``/``group``/``chart``.

    Exudyn's own step loop runs, each step computed by a :class:`lgt_bridge.Simulation`;
    sensors, the solution file and the final state behave as with Exudyn's solver.

    Parameters
    ----------
    mbs : exudyn.MainSystem
        The system (assembled here when ``autoAssemble`` and not yet consistent).
    simulationSettings : exudyn.SimulationSettings, optional
        Exudyn's settings; honoured from ``timeIntegration``:

        - ``startTime``, ``endTime``, ``numberOfSteps``: Exudyn's output step
          h = (endTime − startTime)/numberOfSteps. Fixed-step methods (euler, rkmk2, rkmk4,
          genalpha) step with h.
        - ``automaticStepSize``: True (Exudyn's default): dopri5/dop853 control their step by
          ``relativeTolerance`` (0 allowed: pure absolute tolerance) and ``absoluteTolerance``
          and, as Exudyn's own solvers, never step further than h (see ``max_step``); output
          times between steps come from dense output and never shorten steps. False:
          dopri5/dop853 take fixed steps of h with their own tableau (as Exudyn's DOPRI5
          does), unless ``rtol``/``atol`` are passed here, which always select error control.
          radau5 (implicit, for stiff models) always controls its step by the tolerances.
        - ``minimumStepSize`` (error control: a step the controller would shrink below it
          fails with StepError), ``initialStepSize`` (the first trial step when > 0; 0: the
          bridge's own starting-step estimate).
        - ``generalizedAlpha.useIndex2Constraints``: True enforces the constraints on
          velocities only, for every method (as Exudyn: an initial position violation stays,
          positions are never projected); False (default): positions and velocities.
        - ``verboseMode`` > 0: print the one-line description (as ``verbose=True``).
          ``realtime.active``/``simulateInRealtime``: ignored (one note).
    solverType : ignored
        ``method`` chooses the integrator (an explicit one with a damped GeneralContact: a
        ModelNote, :func:`.contact.note_explicit_law`).
    updateInitialValues : bool, default False
        As Exudyn: the final state becomes the system's initial state.
    storeSolver : bool, default True
        As Exudyn: the solver object is kept in ``mbs.sys["dynamicSolver"]``.
    showHints, showCausingItems
        Accepted for a drop-in call (the bridge's errors name the causing items themselves).
    autoAssemble : bool, default True
        Call ``mbs.Assemble()`` first when the system is not consistent.
    method, group, chart, rho_inf, project
        As :func:`lgt_bridge.simulate` (``group``/``chart`` may be "auto"); ``rho_inf``
        None (default): the settings' ``generalizedAlpha.spectralRadius`` (Exudyn's
        generalized-α has the same coefficients), or with ``generalizedAlpha.useNewmark``
        Newmark's method with its ``newmarkBeta``, ``newmarkGamma``
        (:class:`lgt_bridge.integrators.genalpha.Newmark`).
    rtol, atol : float, optional
        Override the settings' tolerances (a missing one comes from the settings, or, for
        dopri5/dop853 with automaticStepSize False, is the bridge's default rtol 1e-6 /
        atol 1e-8); ``stats["tolerance_source"]`` says per tolerance where it came from
        ("given", "settings", "default").
    verbose : bool, optional
        Print the one-line description (method, group, chart, tolerances and their source);
        None: as ``verboseMode``; False silences it.
    accelerations : bool, optional
        Also write the engine's accelerations after each output step (one more f evaluation
        each); None (default): only when an output reads them (the solution file with
        accelerations exported, acceleration sensors, or sensors of objects, loads and user
        functions, which may read forces); likewise the Lagrange multipliers of the state
        written, in Exudyn's algebraic coordinates (joint force sensors read them).
    progress : bool, optional
        A tqdm bar on stderr as in :func:`lgt_bridge.simulate`.
    max_step : "exudyn", float or None, default "exudyn"
        The largest adaptive step: "exudyn" is h (Exudyn's documented maximum step; a load
        pulse shorter than the run is then not stepped over); a number: another cap; None: no
        cap (smooth models, where the error control alone may take steps longer than h).
    events : callable or list of callable, optional
        Functions g(t, q, V) -> float on the bridge's model coordinates (q: the
        :class:`ExudynModel`'s, Exudyn's total coordinates of the nodes; V: the twists), with
        scipy's ``terminal``/``direction`` (:mod:`lgt_bridge.events`; checked before the first
        step). The bridge's steps then end on Exudyn's steps (as with a pre-step user
        function), so every crossing lies in the Exudyn step in which it is found. The
        crossings are in the statistics (``t_events``, ``q_events``, ``V_events``, per event
        function). A terminal event ends Exudyn's run at the located time: the system's state,
        time, accelerations and multipliers are those of the event, sensors record that last
        time, and the statistics' ``message`` names the event.

    Returns
    -------
    bool
        True, with the final state left in the system, its accelerations included;
        statistics in ``mbs.sys['lgtBridgeStats']``.

    Raises
    ------
    lgt_bridge.StepError
        A failed step, with the system at the last good state.
    lgt_bridge.InputError
        Bad settings or options, before the first step.

    Notes
    -----
    An explicit method held at its stability limit (a stiff spring or contact, an ANCF cable)
    whose rest of the run would need more than 20 times the steps of Exudyn's own solver
    (numberOfSteps, for that stretch) and more than 10 s at the pace so far stops within its
    first budget windows (about 2000 steps, fewer when steps are slow) with StepError, naming
    the step that limit allows and the stiffest mode; use method='radau5' or 'genalpha' there.
    A stiff run the caller can afford runs on, the statistics' ``stiff`` saying where its steps
    sat (lgt_bridge.diagnosis.unaffordable).

    Pre-step user functions (``mbs.SetPreStepUserFunction``) may change the model between
    Exudyn's steps: connectors switched on or off are classified again and the stepper rebuilt
    (``constraint_rows_rebuilt``); a constraint offset moved is spread over the step as a time
    dependence (the explicit methods follow it in position and velocity).
    """
    import exudyn as exu
    if simulationSettings is None:
        simulationSettings = exu.SimulationSettings()
    if not getattr(mbs, "systemIsConsistent", False) and autoAssemble:
        mbs.Assemble()
    refuse_sliding_joints(mbs)          # before the constraint rows are classified (and noted)
    model = ExudynModel(mbs, simulationSettings)
    note_explicit_law(mbs, solverType)
    ti = simulationSettings.timeIntegration
    t0, t1, n = float(ti.startTime), float(ti.endTime), int(ti.numberOfSteps)
    if n <= 0:
        raise InputError(f"simulationSettings.timeIntegration.numberOfSteps = {n} must be positive.")
    if not t1 > t0:
        raise InputError(f"simulationSettings.timeIntegration.endTime = {t1} must be greater than "
                         f"simulationSettings.timeIntegration.startTime = {t0}; set endTime > startTime.")
    h_out = (t1 - t0) / n
    auto_step = bool(ti.automaticStepSize)
    spec = registry.get(method)
    # automaticStepSize=False: Exudyn's DOPRI5 steps at h_out; so does ours, unless the
    # caller asked for error control by passing tolerances (a method without a fixed form,
    # radau5, is error-controlled whatever automaticStepSize says)
    fixed_tableau = spec.fixed_form and not auto_step and rtol is None and atol is None
    controlled = spec.adaptive and not fixed_tableau
    adaptive = spec.uses_tolerances and not fixed_tableau
    # where each tolerance comes from: given here, the script's settings, or the bridge default
    from_settings = adaptive and (auto_step or not spec.fixed_form)
    tol_source = {name: "given" if value is not None else "settings" if from_settings else "default"
                  for name, value in (("rtol", rtol), ("atol", atol))}
    rtol = float(rtol if rtol is not None else ti.relativeTolerance if from_settings else 1e-6)
    atol = float(atol if atol is not None else ti.absoluteTolerance if from_settings else 1e-8)
    h_min = float(ti.minimumStepSize) if controlled else 0.0
    if isinstance(max_step, str):
        if max_step != "exudyn":
            raise InputError(f"max_step = {max_step!r}: use 'exudyn' (endTime/numberOfSteps, as Exudyn), "
                             "a positive number, or None (no cap).")
        max_step = h_out
    if max_step is not None and not float(max_step) > 0.0:
        raise InputError(f"max_step = {max_step} must be positive, 'exudyn' or None.")
    h_cap = float(max_step) if (controlled and max_step is not None) else None
    h_init = float(ti.initialStepSize) if controlled and ti.initialStepSize > 0 else None
    if controlled:
        dt = h_init
    else:
        dt = h_out
    check_inputs(model, (t0, t1), method, dt if dt is not None else h_out, rtol, atol, None, None,
                  None, 1)
    realtime = getattr(ti, "realtime", None)
    if realtime is not None and realtime.active:
        _note_once("realtime", "simulationSettings.timeIntegration.realtime.active (simulateInRealtime) "
                   "is ignored by lgt_bridge's SolveDynamic: it runs as fast as it can.")
    group_asked, chart_asked = group, chart
    # a pre-step user function changes the model at Exudyn's step times (Exudyn calls it
    # once per step, before the step, with the step's end time): the bridge's steps then
    # end on Exudyn's steps instead of stepping over them with dense output
    prestep = _has_user_function(mbs, "GetPreStepUserFunction")
    # minimumStepSize: the floor of an error-controlled step and of genalpha's step halving;
    # with events the steps end on Exudyn's too, so a terminal event lies in the Exudyn step
    # in which it is found
    sim = Simulation(model, method=method, group=group, chart=chart, dt=dt, rtol=rtol, atol=atol,
                     t0=t0, t_end=None if (prestep or events is not None) else t1, project=project,
                     rho_inf=_rho_inf(ti.generalizedAlpha) if rho_inf is None else rho_inf,
                     fixed_steps=fixed_tableau, min_step=float(ti.minimumStepSize), max_step=h_cap,
                     checked=True)
    group, chart, stepper = sim.group, sim.chart, sim.stepper
    # Exudyn's own run takes numberOfSteps steps: an explicit method held at its stability
    # limit that needs far more stops early, saying so (lgt_bridge.diagnosis.unaffordable)
    sim.run_end = t1
    sim.reference_steps = (n, t0, t1, f"Exudyn's own solver (numberOfSteps = {n})")
    if hasattr(model, "locate_circle_contacts"):
        model.locate_circle_contacts = controlled   # (hooks.curve_circle_rows)
        model.locate_switches = controlled          # fixed steps: Exudyn's redos (hooks.py)
    if not controlled:
        sim.min_step = 0.0
    else:
        sim.min_step = h_min
        sim.h_event = max(sim.h_event, 4.0 * h_min)     # contact switches: located to ≥ 4 h_min
        sim.min_step_name = "simulationSettings.timeIntegration.minimumStepSize"
        sim.min_step_why = (f"the error control of {method} at rtol={rtol:g}, atol={atol:g} needs smaller steps "
                            "there (a stiff, discontinuous or non-smooth model). Loosen the tolerances, lower "
                            "minimumStepSize, or use method='genalpha'.")
    first_step = sim.first_step
    bar = simulation_bar(progress, t0, t1, sim, sim.stepper, desc="SolveDynamic")
    on_step = None if bar.mode is None else bar.hook      # (may be called once per bar.hook.stride steps)
    tracker = None if events is None else _events.Tracker(sim, events)   # checks g before a step
    if tracker is not None:
        on_step = tracker.hook(on_step or (lambda t, q, V: None))
    stopped = []            # the terminal event's message
    sd = mbs.systemData
    failure = []
    wall0 = time.perf_counter()
    # pre-step user functions: the residual where the last step ended, to see offsets moved
    g_end = [model.holonomic_residual(sim.q, sim.t)] if prestep else None
    rebuilt = [0]
    pending = []            # an exception inside the step, re-raised after Exudyn's loop
    rows = OutputRows(sim, t1, lambda: solver.it.currentStepSize)
    # the state a step ended on is in Exudyn already (the driver's write-back) unless
    # something evaluated the model since: an event function, or the pre-step residual
    rewrite_free = not prestep and tracker is None
    t_last = t1 - 1e-12 * max(1.0, abs(t1))

    # the data coordinates (contact and friction states) as the bridge's steps left them, and
    # Exudyn's step they were kept at: Exudyn's loop runs its own PostNewton on the output
    # state after each of its steps (repeating the step's call while that changes them),
    # which may lie before the bridge's last step and undo a switch the bridge has passed
    data = [np.array(sd.GetDataCoordinates()), None] if sd.DataSize() else None
    # a pre-step user function may set data coordinates itself (a friction's stick state): the
    # bridge's data are put back before it runs, so that its changes stay
    user_prestep = _restore_data_before(mbs, data) if (prestep and data is not None) else None

    def newton(solver, mbs_, settings):
        t_out = sd.GetTime()                 # the step's end: Exudyn's start of step + h
        if data is not None and t_out != data[1] and user_prestep is None:
            sd.SetDataCoordinates(data[0])
        try:
            if plain:                # an output the last bridge step covers: its state only
                i = rows.i
                if i < len(rows.t) and rows.t[i] == t_out and t_out < t_last:
                    rows.i = i + 1
                    plain[0](rows.Q[i], rows.V[i], t_out)
                    return True
            if prestep:              # the model may have changed: no stage carried over
                if model.rows_changed(sim.q, sim.V, sim.t):     # connectors switched on/off
                    rep = sim.rebuild()
                    rebuilt[0] += 1
                    g_end[0] = None
                    if rep is not None:
                        warnings.warn(ModelNote(
                            f"Exudyn model: constraints switched on at t = {sim.t:g} by the pre-step user "
                            f"function are violated (positions by {rep['position_residual']:.3g}, velocities "
                            f"by {rep['velocity_residual']:.3g}); the state was moved onto them (q by up to "
                            f"{rep['position']:.3g}, V by up to {rep['velocity']:.3g}), as Exudyn's implicit "
                            "solver closes them in its next step."), stacklevel=2)
                else:
                    sim.restart()
                if model.begin_step(sim.q, sim.t, t_out - sim.t, g_end[0]) and sim.stepper.projector is not None:
                    # an offset moved: the velocities start on the new targets (Exudyn's
                    # step applies the end time's offsets over the whole step)
                    V = sim.stepper.projector.velocities(sim.q, sim.V, sim.t)[0]
                    sim.stepper.set_state(sim.q, V)
            q_out, V_out = rows.at(t_out, on_step)
            if prestep:
                g_end[0] = model.holonomic_residual(q_out, t_out)
            # the state, and the accelerations (solution file, acceleration sensors) and
            # Lagrange multipliers (joint force sensors) of that state where outputs read them,
            # and for the final state
            last = t_out >= t_last
            if data is not None:
                data[0], data[1] = np.array(sd.GetDataCoordinates()), t_out
            if accelerations or multipliers or last or not (rows.written and rewrite_free):
                model.write_outputs(q_out, V_out, t_out, accelerations or last, multipliers or last)
        except _events.Terminal as stop:       # the state is at the event: Exudyn's run ends there
            stopped.append(stop.message)
            model.write_outputs(sim.q, sim.V, sim.t, True, True)
            solver.it.endTime = sim.t
        except (LGTError, np.linalg.LinAlgError) as exc:
            failure.append(str(exc) if not isinstance(exc, np.linalg.LinAlgError)
                           else f"a linear solve failed at t = {sim.t:.9g} ({exc}).")
            model.write_back(sim.stepper.q, sim.stepper.V, sim.t)
            solver.it.endTime = sim.t          # stop Exudyn's loop at the last good state
            return True
        except Exception as exc:
            # Exudyn's exception from a call of the bridge (a ModelError naming it) or a bug of
            # the bridge (its own traceback): raised after Exudyn's loop, not through it
            err = engine_error(sd, "SolveDynamic's step", exc)
            if err is not None:
                err.__cause__ = exc
            pending.append(err or exc)
            model.write_back(sim.stepper.q, sim.stepper.V, sim.t)
            solver.it.endTime = sim.t
            return True
        return True

    reads = outputs_read(mbs, simulationSettings)
    accelerations = reads["accelerations"] if accelerations is None else accelerations
    multipliers = reads["multipliers"]
    # outputs read the state alone, kept as the bridge's steps leave it: newton's first
    # lines write it (the state writer looked up once), nothing else in between
    plain = [model.writer()] if (sim.dense and rewrite_free and data is None
                                 and not (accelerations or multipliers)) else []
    solver = exu.MainSolverImplicitSecondOrder()
    if storeSolver:             # before the run, as Exudyn: user functions read it (its step size)
        mbs.sys["dynamicSolver"], mbs.sys["simulationSettings"] = solver, simulationSettings
    solver.SetUserFunctionNewton(mbs, newton)
    saved = [(ti, "automaticStepSize", auto_step)]
    ti.automaticStepSize = False                 # Exudyn steps at the output interval
    ga = ti.generalizedAlpha
    if not (accelerations or multipliers) and ga.computeInitialAccelerations:
        # Exudyn's own solve for the initial accelerations and multipliers (a dense
        # factorization of its whole system: 0.12 s on a 100-body chain) is read by no output
        saved.append((ga, "computeInitialAccelerations", True))
        ga.computeInitialAccelerations = False
    if realtime is not None and realtime.active:
        saved.append((realtime, "active", True))
        realtime.active = False
    try:
        solver.SolveSystem(mbs, simulationSettings)
    except LGTError:
        raise
    except Exception as exc:
        # Exudyn's own loop evaluates the model too (initial accelerations before the first
        # step, sensors, pre-/post-step user functions): a user function failing there
        # raises Exudyn's exception, said as the bridge's own evaluations say it
        err = engine_error(sd, "SolveDynamic's step loop", exc)
        if err is None:
            raise
        raise err from exc
    finally:
        for obj, name, value in saved:
            setattr(obj, name, value)
        if user_prestep is not None:
            mbs.SetPreStepUserFunction(user_prestep)
        bar.close()
    if pending:
        raise pending[0]
    if not (failure or stopped) and sd.GetTime() < t_last:
        # Exudyn's own loop ended early (a pre-step user function returned False, or its own
        # checks after a step stopped it): success as Exudyn says it, the message says where
        stopped.append(f"Exudyn's step loop ended at t = {sd.GetTime():.9g}, before endTime = {t1:g} (a pre-step "
                       "user function returned False, or Exudyn's own checks after a step stopped it)")
    stepper = sim.stepper
    st = dict(method=method, group=_summary(group, group_asked), chart=_summary(chart, chart_asked),
              rtol=rtol if adaptive else None, atol=atol if adaptive else None,
              tolerance_source=tol_source if adaptive else None, dt=None if adaptive else h_out,
              n_steps=sim.n_steps, n_f=stepper.prob.n_f,
              n_rejected=stepper.n_rejected, n_newton=stepper.n_newton,
              wall_s=time.perf_counter() - wall0, exudyn_steps=n, success=not failure,
              message=failure[0] if failure else stopped[0] if stopped else "reached endTime")
    if stepper.n_jacobians:
        st["n_jacobians"] = stepper.n_jacobians
    if getattr(stepper, "stiff", None) is not None:
        # the run was affordable, but the steps sat at the explicit method's stability limit
        st["stiff"] = sim.stats()["stiff"]
    if tracker is not None:
        st["t_events"], st["q_events"], st["V_events"] = tracker.close()
    if controlled:
        st.update(first_step=first_step, minimum_step=h_min, maximum_step=h_cap)
    if sim.initial_projection is not None:
        st["initial_projection"] = sim.initial_projection
    if sim.end_jump is not None:     # f jumps at endTime: the run ended at the left limit
        st["end_jump"] = sim.end_jump
    if model.redundant_rows:
        st["redundant_constraints"] = len(model.redundant_rows)
    if model.n_constraints or rebuilt[0]:
        st["constraints"] = ("index 2: velocity level only, positions not projected "
                             "(generalizedAlpha.useIndex2Constraints = True)" if model.index2 else
                             "index 3: positions and velocities")
    if rebuilt[0]:
        st["constraint_rows_rebuilt"] = rebuilt[0]
    if stepper.projector is not None:
        st["constraint_after_projection"] = stepper.projector.max_after
    mbs.sys["lgtBridgeStats"] = st
    if storeSolver:
        mbs.sys["dynamicSolver"] = solver
        # its step counters count the bridge's steps, as Exudyn's own adaptive solvers count
        # theirs (currentStepIndex - 1: steps taken; Exudyn's explicitLieGroupIntegratorTest.py
        # reads it): Exudyn's loop here only stepped from output to output
        solver.it.currentStepIndex = sim.n_steps + 1
        solver.it.rejectedAutomaticStepSizeSteps = stepper.n_rejected
    if verbose or (verbose is None and ti.verboseMode > 0):
        print(f"lgt-bridge: SolveDynamic {describe(st)}: {sim.n_steps} steps, {stepper.prob.n_f} "
              f"f evaluations, {st['wall_s']:.3f} s")
    if failure:
        located = stepper.dense_capable and hasattr(model, "switch_mode")     # GeneralContact switches
        gc = general_contacts(mbs, located, getattr(sim, "mode_chatter", False))
        raise StepError(f"lgt_bridge SolveDynamic: {failure[0]}{gc} The system is left "
                        f"at t = {sim.t:.9g}.")
    if updateInitialValues:
        sd.SetODE2Coordinates(sd.GetODE2Coordinates(), exu.ConfigurationType.Initial)
        sd.SetODE2Coordinates_t(sd.GetODE2Coordinates_t(), exu.ConfigurationType.Initial)
    return True


def _restore_data_before(mbs, data):
    """Set the system's pre-step user function to one that puts the bridge's data coordinates
    ``data[0]`` back and then calls the user's; returns the user's function (None when it is
    not a Python function, which is then left as it is)."""
    uf = mbs.GetPreStepUserFunction()
    if isinstance(uf, dict):                # Exudyn 1.13: {'function': f, 'type': 'Python'}
        uf = uf.get("function")
    if not callable(uf):
        return None
    sd = mbs.systemData

    def prestep(mbs_, t):
        sd.SetDataCoordinates(data[0])
        return uf(mbs_, t)
    mbs.SetPreStepUserFunction(prestep)
    return uf


def _rho_inf(ga):
    """genalpha's ``rho_inf`` from Exudyn's generalizedAlpha settings: the spectral radius, or
    Newmark's (β, γ) with ``useNewmark``."""
    if ga.useNewmark:
        return Newmark(float(ga.newmarkBeta), float(ga.newmarkGamma))
    return float(ga.spectralRadius)


def _has_user_function(mbs, getter):
    """True when the system has the user function ``getter`` returns (Exudyn returns 0 when unset)."""
    try:
        return bool(getattr(mbs, getter)())
    except Exception:
        return False


def _summary(resolved, asked):
    """A group/chart for the statistics: the value, or for "auto" what it chose ("auto→SE3")."""
    if isinstance(resolved, str):
        return resolved
    picked = sorted(set(resolved))
    return ("auto→" if asked == "auto" else "") + ",".join(picked)


#: a tolerance's source in words (given the name of its Exudyn setting)
_TOL_SOURCE = {"given": lambda setting: "given",
               "settings": lambda setting: f"from simulationSettings.timeIntegration.{setting}",
               "default": lambda setting: "bridge default"}


def describe(st):
    """One line: method, group, chart and tolerances (or step) of a SolveDynamic run."""
    if st.get("rtol") is not None:
        src = st["tolerance_source"]
        if src["rtol"] == src["atol"]:
            tol = f"rtol={st['rtol']:g}, atol={st['atol']:g} ({_TOL_SOURCE[src['rtol']]('relative/absoluteTolerance')})"
        else:
            tol = ", ".join(f"{k}={st[k]:g} ({_TOL_SOURCE[src[k]](setting)})" for k, setting in
                            (("rtol", "relativeTolerance"), ("atol", "absoluteTolerance")))
    elif registry.get(st["method"]).fixed_form:
        tol = f"fixed step {st['dt']:g} s (automaticStepSize=False: endTime/numberOfSteps)"
    else:
        tol = f"fixed step {st['dt']:g} s (from endTime/numberOfSteps)"
    return f"{st['method']} on {st['group']}/{st['chart']}, {tol}"
