"""Why a run stops early: the diagnoses :class:`~.simulation.Simulation` gives when its
steps collapse or its step budget runs out.

- :func:`singular_configuration` — a mechanism at a singular configuration (its constraint
  Jacobian loses rank), where an explicit method's steps collapse;
- :func:`unaffordable` — a run that cannot afford to finish (beyond ``max_steps``, or, with
  the steps the caller's own engine takes for it, an explicit method at its stability limit
  needing far more), checked at the simulation's budget ticks: a stiff model at an explicit
  method's stability limit (:func:`stability_limit`, from Hairer's test or the model's
  Jacobian), a force that jumps at the state (sign(v) friction sticking) holding the error
  control, or a fast motion it must resolve;
- :func:`jump_at_end` — a model whose f jumps in time at the run's end (a load switched on
  at the end time), which every step landing there sees (:func:`jump_size_at_end`: how far);
- :func:`step_too_small` — the failure of a step below ``min_step``, with the cause one of
  the above finds;
- :func:`max_steps_message` — what reaching ``max_steps`` means.

Each takes the simulation and reads its state (``model``, ``stepper``, ``t``, ``t_end``,
``n_steps``, ``max_steps``, ``method``); none changes it, except the budget marks
:func:`unaffordable` keeps between its calls (and :func:`stability_limit`'s evaluations of f
next to the state, which count in ``n_f``; the model is written back at the state after them).
"""
import numpy as np


def registry_implicit(method):
    """True when ``method`` is an implicit method of the registry (False for unknown names)."""
    from .integrators import registry
    try:
        return registry.get(method).implicit
    except Exception:
        return False


def singular_configuration(sim):
    """Why an explicit method's steps collapsed, when the cause is a singular configuration
    of a mechanism (its constraint Jacobian A loses rank: bars in line, a linkage at a dead
    point): the index-1 accelerations there respond to the smallest error of a stage's
    state as 1/σ², so the explicit steps shrink with the distance to it and cannot cross.
    (Measured on the IFToMM double four-bar at 1e-12: the error estimate stays near 1 while
    the step falls from 5e-7 to 8e-8, then a stage near the point gives 5e4; the motion
    itself passes the point, as Exudyn's own fixed-step solver shows.) None when A keeps
    its rank (and for unconstrained models and index-3 methods)."""
    m, st = sim.model, sim.stepper
    if not m.n_constraints or st.projector is None:
        return None
    try:
        U, sv, _ = np.linalg.svd(np.asarray(m.constraint_jacobian(st.q), float))
        sv0 = np.linalg.svd(np.asarray(m.constraint_jacobian(sim._q_start), float), compute_uv=False)
    except Exception:
        return None
    top, top0 = float(sv.max(initial=0.0)), float(sv0.max(initial=0.0))
    if top == 0.0:
        return None
    small = np.flatnonzero(sv < sim.SINGULAR_RATIO * top)
    n0 = int((sv0 < sim.SINGULAR_RATIO * top0).sum())     # redundant from the start
    if len(small) <= n0:
        return None
    k = int(small[0])
    lost = len(small) - n0
    rows = [int(i) for i in np.argsort(-np.abs(U[:, k]))[:4] if abs(U[i, k]) > 0.2]
    own = getattr(m, "constraint_owners", None)
    who = own(rows) if own is not None else f"constraint rows {rows}"
    values = "value falls" if lost == 1 else f"{lost} values fall"
    return (f"the mechanism reaches a singular configuration there: the constraint Jacobian loses rank "
            f"({values} towards zero, to {sv[k]:.2g} = {sv[k] / top:.1g} of the largest or below; "
            f"rows mostly of {who}), as at a dead point or a bifurcation of a linkage (bars in line). "
            "The motion itself can pass it, but the index-1 accelerations an explicit method integrates "
            "respond to a stage's distance from the constraints as 1/σ²: the error estimate stops "
            "falling as the step shrinks, so at this tolerance the steps cannot cross it. Use "
            "method='genalpha' (index 3, fixed steps, as multibody engines' own solvers step through "
            "such points), or loosen the tolerances.")


#: rejected attempts per accepted step, over a budget window, from which the error control
#: is taken to be fighting a jump of the forces rather than resolving a motion (a smooth
#: motion, however fast, costs the PI controller a few rejections per hundred steps; the
#: Coulomb oscillator sticking under sign(v) friction costs 1.4 per step)
CHATTER_REJECTIONS = 0.5
#: a window in which at least this fraction of the steps ended at a located switch of the
#: model's mode: the mode chatters, switching again at once after each switch
CHATTER_SWITCHES = 0.5


def jump_size_at_end(sim):
    """How far f jumps in time at the end time t_end at the current state (max-abs over
    its entries), when the run stands within the last millionth of it before t_end and the
    jump exceeds 1e-6 of f; else None (not near t_end, no jump, or f failing there)."""
    t1, t = sim.t_end, sim.t
    if t1 is None or not 0.0 < t1 - t <= 1e-6 * max(1.0, abs(t1)):
        return None
    q, V = np.array(sim.q, float), np.array(sim.V, float)
    try:
        a = np.asarray(sim.model.f(q, V, t), float)
        b = np.asarray(sim.model.f(q, V, t1), float)
    except Exception:                     # (a diagnosis: the run's own error stands)
        return None
    d = float(np.abs(b - a).max()) if a.shape == b.shape else 0.0
    return d if d > 1e-6 * max(1.0, float(np.abs(a).max())) else None


def jump_at_end(sim):
    """Why the steps collapsed just before the end of the run, when the cause is f jumping
    in time at the end time t_end at the same state (a load switched at t_end, as
    ``np.heaviside(t - t_end, 1)``): each step landing on t_end has a stage there and its error
    estimate sees the jump, at any step size. A sentence, or None (see
    :func:`jump_size_at_end`). (A run normally steps around such a jump to its left limit,
    :mod:`.end_jump`; this says why when even that step fails.)"""
    d = jump_size_at_end(sim)
    if d is None:
        return None
    return (f"the model's accelerations jump by {d:.3g} between t = {sim.t:.9g} and the end time "
            f"{sim.t_end:.9g} at the same state (a load switched on or off at the end time?): every step "
            "landing on the end time sees the jump in its error estimate. End the run before the switch, "
            "move the switch away from the end time, or loosen the tolerances.")


#: an explicit method's steps at or above this share of the step its stability region allows
#: for the model's dominant eigenvalues (:func:`.integrators.stability.jacobian_limit`) are held
#: by stability (steps the accuracy holds sit far below it: 0.08 of it on a geometrically exact
#: beam at rtol 1e-8; steps at the limit at 0.6 to 1)
AT_LIMIT = 0.4
#: steps beyond this multiple of that step are not held by the modes the Jacobian shows (a
#: contact that just closed, felt by the differences, not yet by the steps): Hairer's test speaks
ABOVE_LIMIT = 1.5
#: a run whose caller's own engine takes a known number of steps for it (``reference_steps``:
#: Exudyn's numberOfSteps through the drop-in) is stopped when an explicit method is held at its
#: stability limit and the rest of the run needs more than STIFF_RATIO times the engine's steps
#: for the same stretch (an implicit step costs a few f, an explicit one 6 to 12: the explicit run
#: then costs several times the implicit one) ...
STIFF_RATIO = 20
#: ... and would take more than STIFF_WALL seconds at the pace of the last window (a short run
#: at the stability limit just runs)
STIFF_WALL = 10.0
#: such a run needing more than NOTE_RATIO times the engine's steps (and STIFF_WALL s) goes on,
#: with a note (an implicit method would take far less)
NOTE_RATIO = 2
#: checks of the stability limit for that note at most (a hydraulic cylinder's Jacobian by
#: differences showed a spurious 1e8 1/s at one state; Hairer's test held at later ones)
NOTE_TRIES = 10
#: a fixed-step run (genalpha, rkmk4, …) is looked at every SLOW_EVERY s of wall time
#: (:func:`slow_tick`); once it has gone SLOW_AFTER s, a rest that needs more than SLOW_WALL s
#: at the pace of the last SLOW_AFTER s is said once in a ModelNote, with where a step's time
#: goes, and it goes on (a genalpha run of 512 contacting spheres took 188 s for what Exudyn's
#: own solver does in 0.3 s, silently: ten Newton matrices a step)
SLOW_AFTER, SLOW_WALL, SLOW_EVERY = 5.0, 60.0, 1.0


def budget_tick(sim):
    """Every ``sim._budget_unit`` accepted steps: the next unit, the largest of BUDGET_UNITS
    whose steps take up to BUDGET_WALL s at the pace of the last one, and the budget check
    (:func:`unaffordable`, raising StepFailed) when the run's end is known."""
    now = _clock()
    n0, w0 = sim._budget_clock
    if sim.n_steps > n0:
        per = (now - w0) / (sim.n_steps - n0)
        units = sim.BUDGET_UNITS
        sim._budget_unit = next((u for u in reversed(units) if u * per <= sim.BUDGET_WALL), units[0])
    sim._budget_clock = (sim.n_steps, now)
    if sim.t_end is not None or sim.run_end is not None:
        why = unaffordable(sim)
        if why is not None:
            from .integrators.base import StepFailed
            raise StepFailed(why)


def unaffordable(sim):
    """Why a run cannot afford to finish, or None. Called at each of the simulation's budget
    checks (every ``_budget_unit`` accepted steps: up to BUDGET_WINDOW, fewer when steps are
    slow), it judges the mean step of the last window once it has been steady (within a
    factor 2 of the window before: no transient that may pass):

    - the rest at that step needs more than 4x the steps max_steps leaves: an explicit method
      held at its stability limit says so, with the step that limit allows; a window in which
      the error control rejected at least CHATTER_REJECTIONS attempts per accepted step is a
      force jumping at the state (sign(v) friction sticking at v = 0, a switching user
      function): the step does not grow again while the state sits on the jump, so the run
      stops once it needs more steps than max_steps leaves (no 4x margin), saying so;
    - with ``reference_steps`` (the steps the caller's own engine takes for the run, as
      Exudyn's numberOfSteps): an explicit method held at its stability limit whose rest
      needs more than STIFF_RATIO times the engine's steps for it and more than STIFF_WALL
      seconds at the pace so far (more than NOTE_RATIO times: it goes on, with a ModelNote).

    Held at the stability limit: Hairer's stiffness test (the stepper's ``stiff``) or the
    model's own Jacobian (:func:`stability_limit`)."""
    now = _clock()
    rej = sim.stepper.n_rejected
    marks = list(getattr(sim, "_budget_marks", None) or [])
    if len(marks) >= 2 and marks[-1][0] - marks[-2][0] < 0.5 * (sim.n_steps - marks[-1][0]):
        del marks[-1]       # a window much shorter than the next (the unit grew): one window
    marks = (marks + [(sim.n_steps, sim.t, rej, now)])[-3:]
    sim._budget_marks = marks
    end = sim.t_end if sim.t_end is not None else getattr(sim, "run_end", None)
    if len(marks) < 3 or end is None or not sim.t < end:
        return None
    (n0, t0, _, _), (n1, t1, rej1, w1) = marks[0], marks[1]
    window = sim.n_steps - n1
    h_now = (sim.t - t1) / max(window, 1)
    h_before = (t1 - t0) / max(n1 - n0, 1)
    if not (h_now > 0.0 and 0.5 * h_before <= h_now <= 2.0 * h_before):
        return None
    need = int(np.ceil((end - sim.t) / h_now))
    left = sim.max_steps - sim.n_steps
    explicit = not registry_implicit(sim.method)
    hairer = getattr(sim.stepper, "stiff", None)
    chatter = (rej - rej1) / max(window, 1)
    jumps = hairer is None and chatter >= CHATTER_REJECTIONS and explicit
    ref = getattr(sim, "reference_steps", None)
    wall_rest = need * (now - w1) / max(window, 1)
    over_max = need > (1 if jumps else 4) * left
    ref_rest = None
    if ref is not None and not over_max:
        n_ref, r0, r1 = ref[:3]
        ref_rest = max(1.0, n_ref * (end - sim.t) / (r1 - r0))
        if not (need > STIFF_RATIO * ref_rest and wall_rest > STIFF_WALL):
            if explicit and not jumps and need > NOTE_RATIO * ref_rest and wall_rest > STIFF_WALL:
                _note_stiff(sim, need, ref_rest, ref, wall_rest, h_now)
            return None
    elif not over_max:
        return None
    if singular_configuration(sim) is not None:
        return None     # short steps from a singular configuration: the min_step check says so
    switched = switch_chatter(sim, t1, window)
    limit = stability_limit(sim, h_now) if (explicit and not jumps and not switched) else None
    name = (ref[3] if len(ref) > 3 else "the engine's own steps") if ref is not None else None
    if ref_rest is not None and limit is None and not switched:
        # held by accuracy: the run is the caller's to afford (max_steps); said once
        if explicit and not getattr(sim, "_slow_noted", False):
            sim._slow_noted = True
            _warn_slow(sim, need, ref_rest, name, wall_rest, h_now)
        return None
    if ref_rest is not None:
        head = (f"{sim.method} stopped at t = {sim.t:.9g}: the rest of the run, to {end:.9g}, would need about "
                f"{need:d} more steps (its step has been steady at h ≈ {h_now:.3g} s over the last "
                f"{sim.n_steps - n0} steps), {need / ref_rest:.0f} times the {ref_rest:.0f} steps of {name} "
                f"for it, and about {_duration(wall_rest)} at the pace so far.")
    else:
        head = (f"{sim.method} cannot finish this run within max_steps = {sim.max_steps}: over the last "
                f"{sim.n_steps - n0} steps its step has been steady at h ≈ {h_now:.3g} s, and the rest of "
                f"the run, from t = {sim.t:.9g} to {end:.9g}, would need about {need:d} more steps "
                f"({left:d} left).")
    if switched:
        why = switched
    elif limit is not None:
        why = " " + limit
    elif jumps:
        why = (f" Its error control rejected {chatter:.2g} attempts per accepted step there: the model's "
               "forces jump at the state it sits on (sign(v) friction sticking at v = 0, a user function "
               "that switches), and no step over such a jump meets the tolerance. Regularize the jump "
               "(friction F·tanh(v/v_ε), or a proportional zone of the friction element), which makes the "
               "model stiff: then use method='radau5' or method='genalpha'; or run fixed steps (which "
               "chatter across the jump, first-order accurate there).")
    elif explicit:
        why = (" The error control holds the step there: a fast motion (a stiff spring or contact, a "
               "flexible body such as an ANCF cable, sign(v) friction) it must resolve. Use method='radau5' "
               "or method='genalpha' when that motion need not be resolved, loosen the tolerances, or raise "
               "max_steps.")
    else:
        why = " Loosen the tolerances, or raise max_steps."
    return head + why


def switch_chatter(sim, t_from, window):
    """The sentence saying that the model's mode chatters when at least CHATTER_SWITCHES of the
    ``window`` steps since ``t_from`` ended at a switch its SwitchLocator located (and
    ``sim.mode_chatter`` set), else None. Each cut step restarts at its switch, the mode
    switches back at once, and the next step is cut again: a contact pair at zero gap (a
    cable lying on a roll: Exudyn's reevingSystemOpen.py, dopri5 and radau5 held at 1e-17 s)."""
    loc = getattr(sim, "_switches", None)
    if loc is None or window <= 0:
        return None
    n = sum(1 for s in loc.t_switches[-window:] if s > t_from)
    if n < CHATTER_SWITCHES * window:
        return None
    sim.mode_chatter = True
    return (f" {n} of its last {window} steps ended at a located switch of the model's mode, which switched "
            "again at once: the mode chatters (a contact pair at zero gap, such as a cable lying on a roll, "
            "opening and closing), and a method with dense output (dopri5, dop853, radau5) cuts every step "
            "at the next switch. Use method='genalpha': it takes the mode at the start of each of its "
            "steps, as the engine's own solver does.")


def _note_stiff(sim, need, ref_rest, ref, wall_rest, h_now):
    """Once a run: a ModelNote when an explicit method held at its stability limit runs on (its
    rest needs fewer than STIFF_RATIO but more than NOTE_RATIO times the engine's steps and takes
    over STIFF_WALL s): how long, the limit, and the implicit methods that would not be held."""
    tries = getattr(sim, "_stiff_tries", 0)
    if tries >= NOTE_TRIES:
        return
    sim._stiff_tries = tries + 1
    limit = stability_limit(sim, h_now) if singular_configuration(sim) is None else None
    if limit is None:         # (not established at this state: asked again at a later check)
        return
    sim._stiff_tries = NOTE_TRIES
    import warnings
    from .errors import ModelNote
    name = ref[3] if len(ref) > 3 else "the engine's own steps"
    warnings.warn(ModelNote(
        f"{sim.method} at t = {sim.t:.9g}: the rest of the run needs about {need:d} more steps (h ≈ {h_now:.3g} s), "
        f"{need / ref_rest:.0f} times the {ref_rest:.0f} steps of {name} for it, about {_duration(wall_rest)} at the "
        f"pace so far; it goes on. {limit}"), stacklevel=2)


def _warn_slow(sim, need, ref_rest, name, wall_rest, h_now):
    """A ModelNote that an explicit run held by its accuracy (not its stability limit) will
    take far longer than the engine's own run: it goes on, and the note says what to do."""
    import warnings
    from .errors import ModelNote
    tol = f" at rtol={sim.rtol:g}" if getattr(sim, "rtol", None) else ""
    warnings.warn(ModelNote(
        f"{sim.method}{tol} at t = {sim.t:.9g}: the rest of the run needs about {need:d} more steps "
        f"(h ≈ {h_now:.3g} s), {need / ref_rest:.0f} times the {ref_rest:.0f} steps of {name} for it, about "
        f"{_duration(wall_rest)} at the pace so far. Its steps are held by its accuracy (a fast oscillation "
        "the error control resolves: a stiff spring, a flexible body's axial or shear mode), not by its "
        "stability limit, so it goes on. To trade that accuracy for time, use method='genalpha' (the "
        "script's own steps, damping such modes) or loosen the tolerances."), stacklevel=2)


def step_too_small(sim, underflow=False):
    """The StepFailed of a step size below what the run allows (1e-14 t, min_step), with
    its cause when one of the diagnoses above finds it, else the run's ``min_step_why``."""
    from .integrators.base import StepFailed
    if underflow:
        return StepFailed(f"step size underflow at t = {sim.t:.9g} (h = {sim.h:.3g})")
    return StepFailed(f"the step size fell to {sim.h:.3g} s at t = {sim.t:.9g}, below "
                      f"{sim.min_step_name} = {sim.min_step:g}: "
                      + (singular_configuration(sim) or jump_at_end(sim) or sim.min_step_why))


def stability_limit(sim, h):
    """The sentence saying that an explicit method's steps (h) sit at its stability limit,
    with the step that limit allows and the stiffest mode, or None when they do not: from
    the model's Jacobian at the current state (the dominant eigenvalues, the stability
    region along their rays: :func:`.integrators.stability.jacobian_limit`) when the steps
    are between AT_LIMIT and ABOVE_LIMIT of what it allows, else from Hairer's test (the
    stepper's ``stiff``). The model is written back at the stepper's state afterwards (the
    differences moved it)."""
    st = sim.stepper
    from .integrators.stability import jacobian_limit
    try:
        got = jacobian_limit(st, sim.t) if hasattr(st, "tab") else None
    finally:
        sim.model.write_back(st.q, st.V, sim.t)
    hairer = getattr(st, "stiff", None)
    if got is not None and AT_LIMIT * got[0] <= h <= ABOVE_LIMIT * got[0]:
        h_stab, lam = got
        w = abs(lam.imag)
        w, zeta = abs(lam.imag), max(0.0, -lam.real / abs(lam))
        mode = (f"the stiffest mode's rate |λ| ≈ {abs(lam):.3g} 1/s: the model's Jacobian has its largest "
                + (f"eigenvalues at λ ≈ {lam.real:.3g} ± {w:.3g}i 1/s, an oscillation of {w / (2 * np.pi):.3g} Hz "
                   f"with damping ratio {zeta:.2g}" if w > 1e-3 * abs(lam) else f"eigenvalue at λ ≈ {lam.real:.3g} 1/s")
                + f", where {sim.method} is stable for h|λ| ≤ {h_stab * abs(lam):.2f}")
    elif hairer is not None:
        h_stab, rho = hairer[1], hairer[2]
        mode = f"the stiffest mode's rate ρ ≈ {rho:.3g} 1/s, as Hairer's stiffness test measures it on the steps"
    else:
        return None
    return (f"Its steps sit at its stability limit, h ≈ {h_stab:.3g} s ({mode}), whatever the tolerances: "
            "the model is stiff for an explicit method. Use method='radau5' or method='genalpha' (implicit: "
            "their steps follow the accuracy, not the stiffest mode).")


def slow_tick(sim):
    """After an accepted step of a fixed-step run: every SLOW_EVERY s of wall time a sample of
    its progress, and from SLOW_AFTER s on the rest of the run at the pace of the last SLOW_AFTER
    s (a contact closing makes the steps slower at once: the pace of the whole run so far would
    hide it), said once when over :data:`SLOW_WALL`."""
    now = _clock()
    samples = getattr(sim, "_slow_samples", None)
    if samples and now < samples[-1][0] + SLOW_EVERY:
        return
    if getattr(sim, "_slow_noted", False):
        return
    st = sim.stepper
    here = (now, sim.n_steps, sim.t, (st.prob.n_f, st.n_newton, st.n_jacobians))
    if not samples or now - samples[-1][0] > 10.0 * SLOW_AFTER or sim.t < samples[-1][2]:
        sim._slow_samples = [here]          # (the first of a run, or a run of a kept simulation)
        return
    while len(samples) > 1 and now - samples[1][0] >= SLOW_AFTER:
        del samples[0]
    samples.append(here)
    w0, n0, t0, counts = samples[0]
    end = sim.t_end if sim.t_end is not None else getattr(sim, "run_end", None)
    if now - w0 < SLOW_AFTER or end is None or not t0 < sim.t < end:
        return
    rest = (end - sim.t) * (now - w0) / (sim.t - t0)
    if rest > SLOW_WALL:
        sim._slow_noted = True
        _note_slow(sim, end, rest, now - w0, sim.n_steps - n0, counts)


def _note_slow(sim, end, rest, elapsed, steps, counts):
    """The ModelNote of :func:`slow_tick`: how long the rest takes at the pace so far and where
    a step's time goes (f evaluations; genalpha's Newton matrices and updates)."""
    import warnings
    from .errors import ModelNote
    st = sim.stepper
    f0, u0, j0 = counts
    per = max(steps, 1)
    parts = [f"{(st.prob.n_f - f0) / per:.3g} evaluations of the model a step"]
    advice = ""
    if st.n_newton > u0:
        jac, upd = (st.n_jacobians - j0) / per, (st.n_newton - u0) / per
        parts.append(f"{upd:.3g} Newton updates and {jac:.3g} Newton matrices a step")
        if jac >= 1.0:
            ref = getattr(sim, "reference_steps", None)
            own = (ref[3].split(" (")[0] if ref is not None and len(ref) > 3 else "An engine's own solver")
            advice = (f" Newton's iteration matrix is made anew {jac:.3g} times a step: the forces "
                      "change faster than a kept matrix follows (contacts opening and closing, friction, "
                      "springs turning within a step), and each matrix costs a Jacobian of the model. "
                      f"{own} may keep its matrix across steps (modified Newton) and run such a model "
                      "faster; method='dopri5' may too, if the model is not stiff.")
    warnings.warn(ModelNote(
        f"{sim.method} at t = {sim.t:.9g}: the rest of the run, to t = {end:.9g}, needs about "
        f"{_duration(rest)} at the pace of the last {_duration(elapsed)} ({steps} steps, "
        f"{elapsed / per:.3g} s a step: {'; '.join(parts)}). It goes on.{advice}"), stacklevel=2)


def _duration(s):
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.0f} min" if s < 7200 else f"{s / 3600:.1f} h"


def _clock():
    import time
    return time.perf_counter()


def max_steps_message(sim):
    """What reaching max_steps means: the mean step so far, the steps the rest of the run
    would need at it, and for an explicit method the likely cause (a stiff model keeps an
    explicit method's steps at its stability limit) and what to use instead."""
    from .integrators import registry
    msg = f"max_steps = {sim.max_steps} reached at t = {sim.t:.9g}."
    t_end = sim.t_end
    if sim.n_steps and t_end is not None and sim.t > sim._t_start:
        h_mean = (sim.t - sim._t_start) / sim.n_steps
        msg += (f" The mean step so far is {h_mean:.3g} s; the rest of the run to t = {t_end:.9g} would "
                f"need about {int(np.ceil((t_end - sim.t) / h_mean)):d} more steps.")
    try:
        spec = registry.get(sim.method)
    except Exception:
        spec = None
    if spec is not None and not spec.implicit:
        msg += (" If the model is stiff (a stiff spring or contact, a flexible body such as an ANCF "
                "cable, sign(v) friction), an explicit method's steps sit at its stability limit "
                "whatever the tolerances: use method='radau5' or method='genalpha'.")
    else:
        msg += " Raise max_steps, or loosen the tolerances (or lengthen dt)."
    return msg
