"""What every stepper shares: the local problem, the state, failure reporting."""
import contextlib
import math

import numpy as np

from ..errors import StepError

#: the context of a problem whose arithmetic never warns (the compiled kernels'): not entered
NULL_CONTEXT = contextlib.nullcontext()


class StepFailed(Exception):
    """Internal: a step could not be completed; the driver turns it into a result."""

    def __init__(self, message, error=StepError, diverged=False):
        super().__init__(message)
        self.error = error
        self.diverged = diverged        # the step blew up (an adaptive method retries smaller)


class ChartLimit(Exception):
    """Internal: a stage would leave its chart's domain (a Cayley chart's coordinates grow
    without bound towards its singular rotation). ``usage``: |x|/limit (> 1); ``chart``,
    ``angle``, ``limit``: the worst body's chart and its rotation and the chart's limit, in
    degrees. Fixed-step methods report it; adaptive methods retry a shorter step."""

    def __init__(self, usage, chart, angle, limit):
        super().__init__(chart.name)
        self.usage, self.chart, self.angle, self.limit = usage, chart, angle, limit

    @classmethod
    def at(cls, problem, usage, X=None):
        return cls(usage, *problem.chart_overrun(X))

    def shrink(self, h):
        """A step that keeps the stage short of the limit: 80 % of the one that reached it
        (the rotation of a stage grows about linearly with h)."""
        return 0.8 * h * self.limit / self.angle

    def message(self, t, h):
        end = "a half-turn" if self.chart.max_angle < 3.0 else "a full turn"
        return (f"{self.chart.title} chart ({self.chart.name!r}) at t = {t:.9g}: a stage of the step h = {h:.3g} rotates a "
                f"body by {self.angle:.0f}°, beyond the {self.limit:.0f}° a stage may take in this chart "
                f"(it degenerates towards {end}). Reduce dt, or use chart='exp', chart='cay2' "
                "(up to 240° per stage) or an adaptive method.")


#: what to do about a diverging explicit step (and the generic advice for any method)
DIVERGED_HINT = ("dt is beyond the method's stability limit for the stiffest mode (a stiff spring or "
                 "contact, a fast rotation): reduce dt, or use method='genalpha' (implicit) or an "
                 "adaptive method ('dopri5', 'dop853'). The result keeps every step before it.")


def diverged_message(t, detail, h=None, until=False, hint=DIVERGED_HINT):
    """StepFailed text of a step that diverged: what blew up, where, and what to do."""
    step = f"the step to t = {t:.9g}" if until else f"the step from t = {t:.9g}"
    if h is not None:
        step += f" (dt = {h:.3g})"
    return f"{step} diverged: {detail}. {hint}"


def norm(x):
    """Euclidean norm without floating-point warnings (inf for an overflowing sum)."""
    m = float(np.max(np.abs(x), initial=0.0))
    if m == 0.0 or not math.isfinite(m):
        return m
    y = x / m
    return m * math.sqrt(y.dot(y))


def first_nonfinite(layout, kind, arr):
    i = int(np.flatnonzero(~np.isfinite(arr))[0])
    return layout.owner(kind, i)


class Stepper:
    """The contract every method's stepper keeps (the simulation object relies on nothing
    else):

    - ``set_state(q, V)``, ``snapshot()``/``restore(snap)``: the state between steps, in the
      model's coordinates (``q``, ``V``; ``W`` the integrator's velocities);
    - ``attempt(t, h) -> (accepted, h_new)``: one step from t; an adaptive method declines
      and proposes a shorter step, a fixed one returns ``h_new = None``; a failure raises
      :class:`StepFailed`;
    - ``adaptive``: it chooses its steps (``initial_step(t)`` gives the first);
    - ``dense_capable`` and ``dense``: a continuous extension of the last accepted step,
      ``dense(t) -> (q, V)`` for t within it (None before the first step);
    - ``step_size(dt, span)``: the fixed (or macro) step to use when ``dt`` is given or not;
    - ``min_step``: the shortest step a method that halves failing steps may take;
    - counters: ``n_rejected``, ``n_newton``, ``n_jacobians``, and ``prob.n_f``;
    - ``projector``: the projection onto the constraints after each step, or None;
    - optionally ``keep_dense`` (False): a stepper whose dense output costs extra computes it
      only when this is set (scipy's macro steps, for events);
    - ``step_rates()``: (Ẇ at the start, Ẇ at the end) of the last accepted step where the
      step computed them anyway (stages, generalized-α's unknowns), else None (events use
      them to see turning points of g inside a step at no cost in f);
    - ``restart_at(q, V, t)``: continue from another state inside the last step (a terminal
      event), forgetting what the step carried to the next one;
    - ``h_stable``: the longest step an explicit adaptive method may grow to, the stability
      limit of the stiffest mode its steps measured (inf: no such limit known);
    - ``landing_steps``, ``landing_grows``: an adaptive method's last stretch to a target, when
      its proposed step covers it in at most that many steps, is taken in equal steps; after
      such a shortened step the proposal carried on may grow from its error (else it is only
      shrunk).
    """

    adaptive = False
    h_stable = math.inf
    landing_steps, landing_grows = 2, False
    dense_capable = False
    dense = None
    n_jacobians = 0
    min_step = 0.0
    DIVERGED_HINT = DIVERGED_HINT      # what a diverged step of this method suggests

    def initial_step(self, t):
        """The first trial step of an adaptive method."""
        raise NotImplementedError(f"{type(self).__name__} takes the steps it is given")

    def step_size(self, dt, span):
        """The step a driver should use: ``dt`` (None for an adaptive method)."""
        return dt

    def __init__(self, problem, projector=None):
        self.prob = problem
        self.projector = projector
        self.n_rejected = 0
        self.n_newton = 0

    def set_state(self, q, V, W=None, quats=None, copy=True):
        """Start (or restart) from model coordinates (q, V); a step that ends at (q, V)
        passes its W and body quaternions along so they need not be recomputed
        (``copy=False``: q and V are fresh arrays the stepper may keep)."""
        self.q = np.array(q, float) if copy else q
        self.prob.start(self.q, quats)
        self.V = np.array(V, float) if copy else V
        self.W = self.prob.group_velocity(self.V, self.prob.start_quats) if W is None else W

    def step_rates(self):
        """(Ẇ at the start, Ẇ at the end) of the last accepted step, when known without an f."""
        return None

    def restart_at(self, q, V, t):
        """Continue from (q, V) at t, a state inside the last step (a terminal event's)."""
        self.set_state(q, V)

    def snapshot(self):
        """What :meth:`restore` needs to take the last step again from its start."""
        return self.q.copy(), self.V.copy()

    def restore(self, snap):
        self.set_state(*snap)

    def check_finite(self, t, q, V):
        if math.isfinite(q.dot(q) + V.dot(V)):       # one reduction; inf/NaN propagate
            return
        for kind, arr in (("q", q), ("V", V)):
            if not np.isfinite(arr).all():
                # every stage derivative was finite (checked per stage): the step itself overflowed
                raise StepFailed(diverged_message(
                    t, f"the end state has non-finite {kind} in {first_nonfinite(self.prob.layout, kind, arr)}"
                       " although every stage derivative was finite", until=True, hint=self.DIVERGED_HINT),
                    diverged=True)

    def finish(self, t1, q1, V1, W1=None, quats=None, checked=False):
        """Accept (q1, V1) at t1, after projection onto the constraints if the model has them
        (``checked``: the caller has already checked them finite)."""
        if not checked:
            self.check_finite(t1, q1, V1)
        if self.projector is not None:
            q1, V1 = self.projector(q1, V1, t1)
            W1 = quats = None
        self.set_state(q1, V1, W1, quats, copy=False)
