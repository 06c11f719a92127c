"""Runge-Kutta-Munthe-Kaas: an explicit tableau on the local ODE (X, W) from X = 0,
q_{k+1} = τ(q_k, X_{k+1}). Fixed step (euler, rkmk2, rkmk4) and Dormand-Prince
5(4) with an embedded error estimate on (X, W) and a PI step-size controller."""
import numpy as np

from ..errors import ChartDomainError
from .base import StepFailed, Stepper, first_nonfinite

#: a stage whose Cayley coordinates exceed this (|c| = tan(φ/2): φ = 90°) is refused
CAYLEY_LIMIT = 1.0


class ExplicitRK(Stepper):

    def __init__(self, problem, tableau, projector=None):
        super().__init__(problem, projector)
        self.tab = tableau
        self.KX = np.zeros((tableau.stages, problem.nX))
        self.KW = np.zeros((tableau.stages, problem.nv))
        self._k1 = None                        # FSAL: the first stage of the next step

    def set_state(self, q, V, W=None, quats=None):
        super().set_state(q, V, W, quats)
        self._k1 = None

    def stages(self, t, h):
        """All stages of one step; returns (X1, W1)."""
        prob, tab, KX, KW = self.prob, self.tab, self.KX, self.KW
        A, c = tab.A, tab.c
        X0 = np.zeros(prob.nX)
        for i in range(tab.stages):
            if i == 0:
                if self._k1 is not None:
                    KX[0], KW[0] = self._k1
                else:
                    KX[0], KW[0], q, V = prob.rhs(X0, self.W, t, at_start=True)
                    self._check_stage(KX[0], KW[0], t, t, q, V)
                continue
            else:
                X = h * (A[i, :i] @ KX[:i])
                W = self.W + h * (A[i, :i] @ KW[:i])
                if prob.max_cayley(X) > CAYLEY_LIMIT:
                    raise _CayleyLimit(prob.max_cayley(X))
            KX[i], KW[i], q, V = prob.rhs(X, W, t + c[i] * h)
            self._check_stage(KX[i], KW[i], t, t + c[i] * h, q, V)
        X1 = h * (tab.b @ KX)
        W1 = self.W + h * (tab.b @ KW)
        return X1, W1

    def _check_stage(self, KX, KW, t, ts, q, V):
        if not (np.isfinite(KW).all() and np.isfinite(KX).all()):
            self.check_finite(ts, q, V)
            where = first_nonfinite(self.prob.layout, "V", KW) if not np.isfinite(KW).all() else "the kinematics"
            raise StepFailed(f"non-finite acceleration of {where} in the step from t = {t:.9g} "
                             f"(stage time {ts:.9g}): the model returned NaN/inf for a "
                             "finite state. The result keeps every step before it.")

    def end_state(self, X1, W1):
        """(q1, V1, W1, quats) at the end of the step."""
        q1, quats = self.prob.configuration(X1)
        return q1, self.prob.model_velocity(W1, quats), W1, quats


class _CayleyLimit(Exception):
    def __init__(self, c):
        self.c = c


class FixedRK(ExplicitRK):
    """Fixed steps. A step beyond the stability limit of the stiffest mode shows as a
    velocity change that grows geometrically from step to step (by |R(hλ)| > 1);
    GROWTH-fold growth over RUN consecutive steps is reported as instability (a
    resolved physical growth at rate λ grows by e^{λh} ≈ 1 + λh per step)."""

    GROWTH, RUN = 2.0, 5
    _dW, _grow = None, 0

    def _check_growth(self, t, h, W1):
        dW = float(np.linalg.norm(W1 - self.W))
        if self._dW is not None and dW > self.GROWTH * self._dW and dW > 1e-300:
            self._grow += 1
        else:
            self._grow = 0
        self._dW = dW
        if self._grow >= self.RUN:
            raise StepFailed(f"unstable at t = {t + h:.9g}: the velocity change per step grew more than "
                             f"{self.GROWTH:g}-fold in each of {self.RUN} consecutive steps (last |ΔV| = "
                             f"{dW:.3g}); dt = {h:.3g} is beyond this method's stability limit for the "
                             "stiffest mode. Reduce dt, or use genalpha or an adaptive method.")

    def attempt(self, t, h):
        try:
            X1, W1 = self.stages(t, h)
        except _CayleyLimit as lim:
            raise StepFailed(
                f"Cayley chart at t = {t:.9g}: a stage of the step h = {h:.3g} rotates a body by "
                f"{2 * np.degrees(np.arctan(lim.c)):.0f}° (|c| = {lim.c:.3g} > {CAYLEY_LIMIT}); "
                "the chart degenerates towards a half-turn. Reduce dt, or use chart='exp' or an "
                "adaptive method.", ChartDomainError) from None
        if not (np.isfinite(X1).all() and np.isfinite(W1).all()):
            raise StepFailed(f"non-finite state at t = {t + h:.9g}; reduce dt.")
        self._check_growth(t, h, W1)
        self.finish(t + h, *self.end_state(X1, W1))
        return True, None      # fixed step: the driver goes back to dt after a shortened landing step


class AdaptiveRK(ExplicitRK):
    """Embedded pair with PI control (Hairer-Wanner's DOPRI5 constants)."""

    adaptive = True
    SAFETY, FACMIN, FACMAX = 0.9, 0.2, 10.0
    ALPHA, BETA = 0.17, 0.04

    def __init__(self, problem, tableau, rtol, atol, projector=None, first_step=None):
        super().__init__(problem, tableau, projector)
        self.rtol, self.atol = rtol, atol
        self.h_next = first_step
        self._err_prev = 1e-4
        self._facmax = self.FACMAX
        self.db = tableau.b - tableau.b_err

    def _norm(self, y, scale):
        return float(np.sqrt(np.mean((y / scale) ** 2)))

    def initial_step(self, t):
        """Hairer-Nørsett-Wanner's starting step (II.4), on y = (X, W) with X = 0."""
        prob = self.prob
        KX, KW, _, _ = prob.rhs(np.zeros(prob.nX), self.W, t)
        y0 = np.concatenate([np.zeros(prob.nX), self.W])
        f0 = np.concatenate([KX, KW])
        sc = self.atol + self.rtol * np.abs(y0)
        d0, d1 = self._norm(y0, sc), self._norm(f0, sc)
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        KX1, KW1, _, _ = prob.rhs(h0 * KX, self.W + h0 * KW, t + h0)
        d2 = self._norm(np.concatenate([KX1, KW1]) - f0, sc) / h0
        h1 = max(1e-6, h0 * 1e-3) if max(d1, d2) <= 1e-15 else (0.01 / max(d1, d2)) ** (1 / 5)
        return min(100 * h0, h1)

    def attempt(self, t, h):
        prob, tab = self.prob, self.tab
        try:
            X1, W1 = self.stages(t, h)
        except _CayleyLimit:
            self.n_rejected += 1
            self._facmax = 1.0
            return False, 0.25 * h
        err = h * np.concatenate([self.db @ self.KX, self.db @ self.KW])
        y1 = np.concatenate([X1, W1])
        scale = self.atol + self.rtol * np.maximum(np.abs(np.concatenate([np.zeros(prob.nX), self.W])), np.abs(y1))
        en = self._norm(err, scale)
        if not np.isfinite(en):
            self.n_rejected += 1
            return False, 0.25 * h
        if en <= 1.0:
            fac = self.SAFETY * en ** -self.ALPHA * self._err_prev ** self.BETA if en > 0 else self._facmax
            fac = min(self._facmax, max(self.FACMIN, fac))
            self._err_prev = max(en, 1e-4)
            self._facmax = self.FACMAX
            k_last = (self.KX[-1].copy(), self.KW[-1].copy())
            self.finish(t + h, *self.end_state(X1, W1))
            if tab.fsal and self.projector is None:
                self._k1 = (prob.chart_scale * prob.to_local(self.W), k_last[1])
            return True, h * fac
        self.n_rejected += 1
        self._facmax = 1.0
        return False, h * max(self.FACMIN, self.SAFETY * en ** (-1.0 / tab.order))
