"""``simulate``: run a model on a bridge integrator and collect the result."""
from functools import partial
import time
from dataclasses import dataclass, field

import numpy as np

from . import auto as _auto
from .errors import ChartDomainError, InputError, ModelError, StepError
from .integrators import METHODS
from .integrators.base import StepFailed
from .integrators.constraints import Projector, project_initial
from .integrators.local import make_problem
from .integrators.rkmk import AdaptiveRK, FixedRK
from .integrators.tableaux import ADAPTIVE, FIXED
from .progress import simulation_bar
from .validation import check_inputs


@dataclass
class SimulationResult:
    """Output of :func:`simulate`: ``t`` (n,), ``q`` (n, nq) in the engine's own
    coordinates, ``V`` (n, nv) as (ω body, ṙ inertial) per body, ``success``,
    ``message`` and ``stats`` (n_steps, n_f, n_rejected, n_newton, wall_s, and
    the constraint residuals before/after projection where there are constraints)."""

    t: np.ndarray
    q: np.ndarray
    V: np.ndarray
    success: bool
    message: str
    stats: dict = field(default_factory=dict)
    method: str = ""
    group: object = ""
    chart: object = ""

    def raise_for_status(self):
        if not self.success:
            raise StepError(self.message)
        return self


def make_stepper(model, method, group="SE3", chart="exp", *, dt=None, rtol=1e-6, atol=1e-8,
                 project=True, rho_inf=0.9, newton_tol=1e-10, span=None):
    """The stepper object behind a method name, with its local problem and projector.
    Returns (stepper, dt) where dt is the (macro) step to use (None: adaptive, chosen
    by the stepper)."""
    prob = make_problem(model, group, chart)
    explicit = method != "genalpha"
    projector = Projector(model) if (explicit and project and model.n_constraints) else None
    if method in FIXED:
        return FixedRK(prob, FIXED[method], projector), dt
    if method in ADAPTIVE:
        return AdaptiveRK(prob, ADAPTIVE[method](), rtol, atol, projector, first_step=dt), dt
    if method == "radau5":
        from .integrators.radau import Radau5
        return Radau5(prob, rtol, atol, projector), dt
    if method == "genalpha":
        from .integrators.genalpha import GenAlpha
        return GenAlpha(prob, rho_inf=rho_inf, newton_tol=newton_tol), dt
    from .integrators.vector_space import ScipyStepper
    stepper = ScipyStepper(prob, method[6:], rtol, atol, projector)
    if dt is None:
        wmax = max([np.abs(model.V0[list(b.twist[:3])]).max() for b in model.layout.bodies] + [1e-12])
        dt = min((span[1] - span[0]) / 10, 0.5 / wmax) if span else 0.5 / wmax
    return stepper, dt


def _note_initial_projection(rep, t0):
    import warnings

    from .errors import ModelNote
    warnings.warn(ModelNote(
        f"the initial state at t = {t0:g} violates the constraints (positions by "
        f"{rep['position_residual']:.3g}, velocities by {rep['velocity_residual']:.3g}); it was moved "
        f"onto them before the first step: q by up to {rep['position']:.3g}, V by up to "
        f"{rep['velocity']:.3g} (as Exudyn's implicit solver does in its first step). Make the "
        "initial state consistent to silence this note."), stacklevel=4)


class Driver:
    """Advances a stepper to target times. Fixed steps of dt land on each target (the
    last step shortened); adaptive methods with a continuous extension step freely up
    to ``t_end`` and interpolate every target inside their last step (dense output:
    output times never shorten steps). Counts steps; raises StepFailed.

    ``consistent``: a constrained model's initial state is first moved onto its
    constraints when it violates them (the model's ``project_initial(q0, V0, t0)`` when it
    has one, else :func:`.integrators.constraints.project_initial`);
    ``initial_projection`` says how far (None: it was consistent)."""

    #: redos of one short step when the model's discontinuous states keep changing
    MAX_DISCONTINUOUS = 5

    def __init__(self, model, stepper, dt, t0, q0, V0, max_steps=1_000_000, t_end=None,
                 consistent=True):
        self.model, self.stepper = model, stepper
        self._post = getattr(model, "post_step", None)
        self.dt, self.t, self.max_steps = dt, float(t0), max_steps
        self.t_end = t_end
        self.dense = bool(getattr(stepper, "dense_capable", False)) and t_end is not None
        self.n_steps = 0
        self.n_redone = 0
        span = (t_end - self.t) if t_end is not None else (dt or 1.0) * 1e2
        self.h_event = 1e-7 * max(span, 1e-300)     # switches of discontinuous states located to this
        self.initial_projection = None
        if consistent and model.n_constraints:
            own = getattr(model, "project_initial", None)     # an engine's own rule, if it has one
            q0, V0, self.initial_projection = (own or partial(project_initial, model))(q0, V0, self.t)
            if self.initial_projection is not None:
                model.write_back(q0, V0, self.t)
                _note_initial_projection(self.initial_projection, self.t)
        stepper.set_state(q0, V0)
        self.h = dt if dt is not None else stepper.initial_step(self.t)

    def _step(self, target, on_step):
        st = self.stepper
        if self.n_steps >= self.max_steps:
            raise StepFailed(f"max_steps = {self.max_steps} reached at t = {self.t:.9g}")
        h_try = min(self.h, target - self.t)
        hit = target - (self.t + h_try) <= 1e-12 * max(1.0, abs(target))
        if hit:
            h_try = target - self.t
        post = self._post
        try:
            if post is None:
                accepted, h_new = st.attempt(self.t, h_try)
            else:
                accepted, h_new = self._attempt_discontinuous(h_try, post)
        except ModelError as exc:           # the engine raised: end the run, keep the steps
            raise StepFailed(str(exc), error=ModelError) from exc
        if accepted:
            self.n_steps += 1
            self.t = target if hit else self.t + h_try
            self.model.write_back(st.q, st.V, self.t)
            if st.adaptive:
                self.h = max(h_new, self.h) if hit and h_new < self.h else h_new
            else:
                self.h = min(h_new, self.dt) if h_new is not None else self.dt
            if on_step is not None:
                on_step(self.t, st.q, st.V)
        else:
            self.h = h_new
            if self.h < 1e-14 * max(1.0, abs(self.t)):
                raise StepFailed(f"step size underflow at t = {self.t:.9g} (h = {self.h:.3g})")

    def _attempt_discontinuous(self, h, post):
        """A step of a model with discontinuous states (contact, friction: the model's
        ``post_step(q, V, t)`` updates them from the step's end state and says whether they
        changed). A step over which they change is declined and retried at a quarter of its
        length, from its start and with the states of its start, until it is no longer than
        ``h_event``; that short step is then redone with the new states (as Exudyn's
        discontinuous iteration redoes its Newton step), up to MAX_DISCONTINUOUS times."""
        st, m = self.stepper, self.model
        snap, d0 = st.snapshot(), m.discontinuous_state()
        accepted, h_new = st.attempt(self.t, h)
        for _ in range(self.MAX_DISCONTINUOUS):
            if not accepted or not post(st.q, st.V, self.t + h):
                break
            st.restore(snap)
            if h > self.h_event:
                m.set_discontinuous_state(d0)
                return False, 0.25 * h
            self.n_redone += 1
            accepted, h_new = st.attempt(self.t, h)
        return accepted, h_new

    def advance_to(self, target, on_step=None):
        """Step until ``target`` is reached; returns (q, V) at ``target`` (interpolated
        within the last step when the method has dense output)."""
        st = self.stepper
        if not self.dense:
            while self.t < target:
                self._step(target, on_step)
            return st.q, st.V
        tol = 1e-12 * max(1.0, abs(target))
        while self.t < target - tol:
            self._step(self.t_end, on_step)
        if abs(self.t - target) <= tol or st.dense is None:
            return st.q, st.V
        return st.dense(target)


def simulate(model, t_span, *, method="rkmk4", group="SE3", chart="exp", dt=None, rtol=1e-6,
             atol=1e-8, q0=None, V0=None, t_eval=None, progress=None, max_steps=1_000_000,
             project=True, rho_inf=0.9, newton_tol=1e-10):
    """Integrate ``model`` over ``t_span`` with a Lie group method through τ.

    method: "euler", "rkmk2", "rkmk4" (fixed dt), "dopri5", "dop853" (adaptive: rtol/atol,
    dt = first step), "scipy:<Name>" (scipy solver inside macro steps of length dt),
    "radau5" (implicit Radau IIA of order 5, adaptive: rtol/atol, dt = first step; for stiff
    models such as PD-controlled robots), "genalpha" (fixed dt, index-3 constraints,
    numerical damping ``rho_inf``).
    group: "SE3", "SO3xR3" or "auto"; chart: "exp", "cay" or "auto" (one value or one
    per body). "auto" picks per body what the model's structure needs
    (:mod:`lgt_bridge.auto`); ``stats["auto"]`` says what it chose and why, and
    ``result.group``/``result.chart`` hold the resolved per-body lists.
    Constrained models with explicit methods are projected onto g = 0 and A V = b
    after every step, and an initial state that violates the constraints is projected
    before the first step (``stats["initial_projection"]`` says how far it moved);
    ``project=False`` turns both off.
    t_eval: output times; default: every step. Fixed-step methods land on them;
    dopri5, dop853 and radau5 interpolate them with their continuous extension (through τ),
    so output times never shorten their steps.
    progress: None (default) shows a tqdm bar on stderr (simulated time, steps, f
    evaluations, current step size, rate) once the run has taken more than about 1 s,
    and only when stderr is a terminal and the environment variable ``CI`` is unset;
    True always shows it, False never (:mod:`lgt_bridge.progress`).
    max_steps: the most accepted steps the run may take (default 10⁶); reaching it ends
    the run with ``success = False`` and a message saying so, keeping the steps computed.
    """
    t0, t1, q0, V0, t_eval = check_inputs(model, t_span, method, dt, rtol, atol, q0, V0, t_eval,
                                           max_steps)
    choice = None
    if _auto.wants_auto(group, chart):
        choice = _auto.choose(model, group, chart, method=method, project=project)
        group, chart = choice.groups, choice.charts
    stepper, dt = make_stepper(model, method, group, chart, dt=dt, rtol=rtol, atol=atol,
                               project=project, rho_inf=rho_inf, newton_tol=newton_tol, span=(t0, t1))
    wall0 = time.perf_counter()
    drv = Driver(model, stepper, dt, t0, q0, V0, max_steps, t_end=t1, consistent=project)
    q0, V0 = drv.stepper.q, drv.stepper.V
    ts, qs, Vs = [], [], []
    record_all = t_eval is None
    targets = [t1] if record_all else [t for t in t_eval if t > t0]
    if record_all or t_eval[0] == t0:
        ts.append(t0), qs.append(q0.copy()), Vs.append(V0.copy())
    bar = simulation_bar(progress, t0, t1, drv, stepper)

    def on_step(t, q, V):
        if record_all:
            ts.append(t), qs.append(q.copy()), Vs.append(V.copy())
        bar.step()

    success, message = True, "reached the end of t_span"
    try:
        for target in targets:
            q_out, V_out = drv.advance_to(target, on_step)
            if not record_all:
                ts.append(target), qs.append(np.array(q_out)), Vs.append(np.array(V_out))
        if drv.t < t1:
            drv.advance_to(t1, on_step)
    except StepFailed as exc:
        if exc.error is ChartDomainError:
            err = ChartDomainError(str(exc))
            err.result = _result(ts, qs, Vs, False, str(exc), stepper, drv.n_steps, wall0,
                                 method, group, chart, model)
            model.write_back(stepper.q, stepper.V, drv.t)
            bar.close()
            raise err from None
        success, message = False, str(exc)
        model.write_back(stepper.q, stepper.V, drv.t)
    bar.close()
    res = _result(ts, qs, Vs, success, message, stepper, drv.n_steps, wall0, method, group, chart, model)
    if drv.initial_projection is not None:
        res.stats["initial_projection"] = drv.initial_projection
    if choice is not None:
        res.stats["auto"] = choice.as_dicts()
    return res


def _result(ts, qs, Vs, success, message, stepper, n_steps, wall0, method, group, chart, model):
    projector = stepper.projector
    stats = dict(n_steps=n_steps, n_f=stepper.prob.n_f, n_rejected=stepper.n_rejected,
                 n_newton=stepper.n_newton, wall_s=time.perf_counter() - wall0)
    if projector is not None:
        stats.update(constraint_before_projection=projector.max_before,
                     constraint_after_projection=projector.max_after,
                     velocity_constraint_after_projection=projector.max_vel_after,
                     projection_iterations=projector.iterations)
    elif model.n_constraints and qs:
        rows = model.position_rows
        stats["constraint_residual"] = float(max(
            (np.abs(model.constraints_at(q, t)[rows]).max() if len(rows) else 0.0) for t, q in zip(ts, qs)))
    if hasattr(stepper, "n_jacobians"):
        stats["n_jacobians"] = stepper.n_jacobians
    nq, nv = model.layout.nq, model.layout.nv
    return SimulationResult(np.array(ts), np.array(qs).reshape(-1, nq), np.array(Vs).reshape(-1, nv),
                            success, message, stats, method, group, chart)
