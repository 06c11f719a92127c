"""The continuous extension of a fixed step for events (:mod:`lgt_bridge.events`): the cubic
Hermite interpolant of the local state (X, W) between the step's ends, mapped through τ of
the step's base, and τ⁻¹ (the local coordinates of a pose in a step's chart) that it needs
for the step's end."""
import numpy as np

from .groups import quaternion as _q


# --- the local coordinates of a pose: X = τ⁻¹(q_k, q) -----------------------------------------
def local_coordinates(prob, q):
    """X with τ(q_k, X) = q in the current step's chart (q_k: ``prob.q_k``): per body
    ψ⁻¹(α(q_k)⁻¹ α(q)), vector coordinates q - q_k, circle angles of (c, s)·(c_k, s_k)⁻¹."""
    qk = prob.q_k
    X = np.zeros(prob.nX)
    for s in prob.sets:
        par = s.lgt.param
        rk, r1 = qk[s.qidx], q[s.qidx]
        pk = par._to_quat(rk[:, -par.nrot:])
        p1 = par._to_quat(r1[:, -par.nrot:])
        R = _q._to_matrix(_q._mul(_q._conj(pk), p1))
        if s.rot_only:
            X[s.xidx] = s.chart.on("SO3").psi_inv(R)
            continue
        d = r1[:, :3] - rk[:, :3]
        if s.se3:
            d = _q._rotate(_q._conj(pk), d)
        C = np.zeros((len(R), 4, 4))
        C[:, :3, :3], C[:, :3, 3], C[:, 3, 3] = R, d, 1.0
        X[s.xidx] = s.chart.on(s.lgt.group).psi_inv(C)
    if len(prob.vq):
        X[prob.vx] = q[prob.vq] - qk[prob.vq]
    if len(prob.cv):
        ck, c1 = qk[prob.cq], q[prob.cq]
        X[prob.cx] = np.arctan2(c1[:, 1] * ck[:, 0] - c1[:, 0] * ck[:, 1],
                                c1[:, 0] * ck[:, 0] + c1[:, 1] * ck[:, 1])
    return X


class HermiteStep:
    """The continuous extension of a fixed step: the cubic Hermite interpolant of (X, W) in
    the chart of the step's base, through (0, W0) at t0 and (X1, W1) at t1 with the rates
    (Ẋ, Ẇ) of the local ODE at both ends, mapped through τ of the base. ``Wd0``: Ẇ at the
    start when known (the previous step's end: W is the body-frame velocity, the same in
    every step's chart), else one f. The end's Ẇ is kept as ``Wd1`` for the next step."""

    def __init__(self, prob, base, t0, W0, t1, q1, W1, Wd0=None):
        self.prob, self.base, self.t0, self.t1, self.h = prob, base, t0, t1, t1 - t0
        with prob.based_at(base):
            X1 = local_coordinates(prob, q1)
            Xd0, Wd, _, _ = prob.rhs(np.zeros(prob.nX), W0, t0, at_start=True) if Wd0 is None else \
                (prob.chart_scale * prob.to_local(W0), Wd0, None, None)
            Xd1, Wd1, _, _ = prob.rhs(X1, W1, t1)
        self.Wd1 = Wd1
        h = self.h
        # y(s) = y0 + s (h ẏ0) + s² (3Δ - 2h ẏ0 - h ẏ1) + s³ (h ẏ0 + h ẏ1 - 2Δ)
        self.cX = self._coef(np.zeros(prob.nX), X1, h * Xd0, h * Xd1)
        self.cW = self._coef(W0, W1, h * Wd, h * Wd1)

    @staticmethod
    def _coef(y0, y1, d0, d1):
        dy = y1 - y0
        return (y0, d0, 3.0 * dy - 2.0 * d0 - d1, d0 + d1 - 2.0 * dy)

    @staticmethod
    def _eval(c, s):
        return c[0] + s * (c[1] + s * (c[2] + s * c[3]))

    def local(self, t):
        s = (t - self.t0) / self.h
        return self._eval(self.cX, s), self._eval(self.cW, s)

    def __call__(self, t):
        X, W = self.local(t)
        with self.prob.based_at(self.base) as prob:
            return prob.state_at(X, W)


__all__ = ["HermiteStep", "local_coordinates"]
