"""Why a run stops early: the diagnoses :class:`~.simulation.Simulation` gives when its
steps collapse or its step budget runs out.

- :func:`singular_configuration` — a mechanism at a singular configuration (its constraint
  Jacobian loses rank), where an explicit method's steps collapse;
- :func:`unaffordable` — a run that cannot finish within ``max_steps``, checked every
  ``BUDGET_WINDOW`` accepted steps: a stiff model at an explicit method's stability limit,
  a force that jumps at the state (sign(v) friction sticking) holding the error control,
  or a fast motion it must resolve;
- :func:`jump_at_end` — a model whose f jumps in time at the run's end (a load switched on
  at the end time), which every step landing there sees (:func:`jump_size_at_end`: how far);
- :func:`step_too_small` — the failure of a step below ``min_step``, with the cause one of
  the above finds;
- :func:`max_steps_message` — what reaching ``max_steps`` means.

Each takes the simulation and reads its state (``model``, ``stepper``, ``t``, ``t_end``,
``n_steps``, ``max_steps``, ``method``); none changes it, except the budget marks
:func:`unaffordable` keeps between its calls.
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


def unaffordable(sim):
    """Why a run cannot finish within max_steps, or None: checked every BUDGET_WINDOW
    accepted steps, from the mean step of the last window, once it has been steady (within
    a factor 2 of the window before: no transient that may pass) and the rest of the run at
    that step needs more than 4x the steps max_steps leaves. An explicit method that
    Hairer's stiffness test finds at its stability limit (the stepper's ``stiff``) says so,
    with the step that limit allows. A window in which the error control rejected at least
    CHATTER_REJECTIONS attempts per accepted step is a force jumping at the state (sign(v)
    friction sticking at v = 0, a switching user function): the step does not grow again
    while the state sits on the jump, so the run stops once it needs more steps than
    max_steps leaves (no 4x margin), saying so."""
    window = sim.BUDGET_WINDOW
    rej = sim.stepper.n_rejected
    t_prev, t_last, rej_last = getattr(sim, "_budget_marks", (None, sim._t_start, 0))
    sim._budget_marks = (t_last, sim.t, rej)
    if t_prev is None:
        return None
    h_now = (sim.t - t_last) / window
    h_before = (t_last - t_prev) / window
    if not (h_now > 0.0 and 0.5 * h_before <= h_now <= 2.0 * h_before):
        return None
    need = int(np.ceil((sim.t_end - sim.t) / h_now))
    left = sim.max_steps - sim.n_steps
    stiff = getattr(sim.stepper, "stiff", None)
    chatter = (rej - rej_last) / window
    jumps = stiff is None and chatter >= CHATTER_REJECTIONS and not registry_implicit(sim.method)
    if need <= (1 if jumps else 4) * left:
        return None
    if singular_configuration(sim) is not None:
        return None     # short steps from a singular configuration: the min_step check says so
    head = (f"{sim.method} cannot finish this run within max_steps = {sim.max_steps}: over the last "
            f"{2 * window} steps its step has been steady at h ≈ {h_now:.3g} s, and the rest of "
            f"the run, from t = {sim.t:.9g} to {sim.t_end:.9g}, would need about {need:d} more steps "
            f"({left:d} left).")
    if stiff is not None:
        _, h_stab, rho = stiff
        why = (f" Its steps sit at its stability limit, h ≈ {h_stab:.3g} s (the stiffest mode's rate "
               f"ρ ≈ {rho:.3g} 1/s), whatever the tolerances: the model is stiff for an explicit method. "
               "Use method='radau5' or method='genalpha' (implicit: their steps follow the accuracy, not "
               "the stiffest mode).")
    elif jumps:
        why = (f" Its error control rejected {chatter:.2g} attempts per accepted step there: the model's "
               "forces jump at the state it sits on (sign(v) friction sticking at v = 0, a user function "
               "that switches), and no step over such a jump meets the tolerance. Regularize the jump "
               "(friction F·tanh(v/v_ε), or a proportional zone of the friction element), which makes the "
               "model stiff: then use method='radau5' or method='genalpha'; or run fixed steps (which "
               "chatter across the jump, first-order accurate there).")
    elif not registry_implicit(sim.method):
        why = (" The error control holds the step there: a fast motion (a stiff spring or contact, a "
               "flexible body such as an ANCF cable, sign(v) friction) it must resolve. Use method='radau5' "
               "or method='genalpha' when that motion need not be resolved, loosen the tolerances, or raise "
               "max_steps.")
    else:
        why = " Loosen the tolerances, or raise max_steps."
    return head + why


def step_too_small(sim, underflow=False):
    """The StepFailed of a step size below what the run allows (1e-14 t, min_step), with
    its cause when one of the diagnoses above finds it, else the run's ``min_step_why``."""
    from .integrators.base import StepFailed
    if underflow:
        return StepFailed(f"step size underflow at t = {sim.t:.9g} (h = {sim.h:.3g})")
    return StepFailed(f"the step size fell to {sim.h:.3g} s at t = {sim.t:.9g}, below "
                      f"{sim.min_step_name} = {sim.min_step:g}: "
                      + (singular_configuration(sim) or jump_at_end(sim) or sim.min_step_why))


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
