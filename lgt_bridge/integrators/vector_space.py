"""Geometrically consistent evaluation (paper §6.3): any scipy one-step solver
integrates the local ODE (X, W) over one macro step from X = 0; q is rebuilt
through τ. Multistep solvers (BDF, LSODA) are restarted every macro step."""
import numpy as np

from .base import StepFailed, Stepper

#: a macro step whose exp-chart rotation exceeds this (rad) is retried shorter (dexp⁻¹ is
#: singular at 2π); a bounded chart's macro step is held to its own stage limit
EXP_LIMIT = 2.5


def build(method, problem, o):
    """The stepper of ``scipy:<Name>`` (the registry's builder)."""
    return ScipyStepper(problem, method.name[6:], o["rtol"], o["atol"], o["projector"])


class ScipyStepper(Stepper):

    adaptive = False
    #: keep scipy's dense output of each macro step as ``dense`` (events ask for it; it costs
    #: DOP853 three more f per internal step, so runs without events do not compute it)
    keep_dense = False

    def __init__(self, problem, name, rtol, atol, projector=None):
        super().__init__(problem, projector)
        self.name, self.rtol, self.atol = name, rtol, atol
        self.n_internal = 0

    def step_size(self, dt, span):
        """The macro step: ``dt``, or by default a tenth of the span, at most half a radian of
        the fastest body's initial rotation."""
        if dt is not None:
            return dt
        V0 = self.prob.model.V0
        wmax = max([np.abs(V0[list(b.twist[:3])]).max() for b in self.prob.layout.bodies] + [1e-12])
        return min((span[1] - span[0]) / 10, 0.5 / wmax) if span else 0.5 / wmax

    def _fun(self, t, y):
        nX = self.prob.nX
        KX, KW, _, _ = self.prob.rhs(y[:nX], y[nX:], t)
        return np.concatenate([KX, KW])

    def attempt(self, t, h):
        from scipy.integrate import solve_ivp      # imported on first use: import lgt_bridge stays fast
        prob = self.prob
        y0 = np.concatenate([np.zeros(prob.nX), self.W])
        sol = solve_ivp(self._fun, (t, t + h), y0, method=self.name, rtol=self.rtol, atol=self.atol,
                        dense_output=self.keep_dense)
        if not sol.success or not np.isfinite(sol.y[:, -1]).all():
            if h > 1e-12 * max(1.0, abs(t)):
                self.n_rejected += 1
                return False, 0.5 * h
            raise StepFailed(f"scipy {self.name} failed at t = {t:.9g}: {sol.message}")
        self.n_internal += len(sol.t) - 1
        y1 = sol.y[:, -1]
        X1, W1 = y1[:prob.nX], y1[prob.nX:]
        over = any((s.chart.angle(np.sqrt((X1[s.xidx[:, :3]] ** 2).sum(axis=1)))
                    > (s.chart.max_angle if s.chart.bounded else EXP_LIMIT)).any() for s in prob.sets)
        if over:
            self.n_rejected += 1
            return False, 0.5 * h
        if self.keep_dense:
            self.dense = ScipyDense(prob, sol.sol, t, t + h)
        q1, quats = prob.configuration(X1)
        self.finish(t + h, q1, prob.model_velocity(W1, quats), W1, quats)
        return True, None


class ScipyDense:
    """scipy's dense output of one macro step on (X, W), through τ of the step's base (valid
    after the stepper has moved on, like the adaptive methods' dense output)."""

    def __init__(self, prob, sol, t0, t1):
        self.prob, self.sol, self.t0, self.t1 = prob, sol, t0, t1
        self.base = prob.snapshot()

    def __call__(self, t):
        y = self.sol(t)
        nX = self.prob.nX
        with self.prob.based_at(self.base) as prob:
            return prob.state_at(y[:nX], y[nX:])

    def many(self, ts):
        """Rows of (Q, V) at the times ``ts``, one at a time (scipy's dense output is kept
        for events only)."""
        out = [self(t) for t in ts]
        return np.array([q for q, _ in out]), np.array([V for _, V in out])
