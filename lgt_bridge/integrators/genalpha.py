"""Lie group generalized-α, index 3 (Brüls, Cardona, Arnold 2012; Arnold, Brüls,
Cardona 2015), on the local coordinates of the bridge:

    (1 - α_m) a_{k+1} = (1 - α_f) Ẇ_{k+1} + α_f Ẇ_k - α_m a_k
    W_{k+1} = W_k + h (1 - γ) a_k + h γ a_{k+1}
    ΔX      = h W_k + h² (½ - β) a_k + h² β a_{k+1},      q_{k+1} = τ(q_k, ΔX)
    M(q) V̇ - Q(q, V, t) + Aᵀ(q) λ = 0,    g(q) = 0          at t_{k+1}

ΔX is an increment in exponential coordinates; on a Cayley chart the step uses
cay(ΔX/2), which agrees with exp(ΔX) to O(|ΔX|³) and keeps second order.

solved by Newton in (Ẇ_{k+1}, λ) with the constraint rows scaled by 1/(h²β).
The iteration matrix comes from the model (``iteration_matrix(q, V, t, c_acc, c_vel,
c_pos)`` ≈ M c_acc + C_t c_vel + K_t c_pos) when every body is on SO(3)xR³, else it is a
finite-difference Jacobian in Ẇ (λ enters linearly through Aᵀ); either is reused across
iterations and steps while Newton converges.
Models without a mass matrix use the residual V̇ - f(q, V, t) (unconstrained only).
"""
import numpy as np
import scipy.linalg as sla

from ..errors import InputError
from .base import StepFailed, Stepper


def coefficients(rho_inf):
    if not 0.0 <= rho_inf <= 1.0:
        raise InputError(f"genalpha: rho_inf = {rho_inf} must lie in [0, 1] (1: no numerical "
                         "damping, 0: asymptotic annihilation).")
    am = (2 * rho_inf - 1) / (rho_inf + 1)
    af = rho_inf / (rho_inf + 1)
    gamma = 0.5 + af - am
    beta = 0.25 * (gamma + 0.5) ** 2
    return am, af, gamma, beta


class GenAlpha(Stepper):

    THETA = 0.1

    def __init__(self, problem, rho_inf=0.9, newton_tol=1e-10, newton_max=25):
        super().__init__(problem)
        self.am, self.af, self.gamma, self.beta = coefficients(rho_inf)
        self.tol, self.nmax = newton_tol, newton_max
        m = problem.model
        self.use_M = m.has_mass_matrix
        self.nc = m.n_constraints
        if self.nc and not self.use_M:
            raise InputError("genalpha on a constrained model needs mass_matrix and forces "
                             "from the model (index-3 residual M V̇ - Q + Aᵀλ).")
        self._lu = None
        self._lu_h = None
        # the model's own iteration matrix where the unknowns are its own increments and
        # accelerations (every body on SO(3)xR³; rotation-only bodies too)
        self._model_jacobian = (self.use_M and callable(getattr(m, "iteration_matrix", None))
                                and not any(s.se3 for s in problem.sets))
        self.Wd = None
        self._prev = None
        self.n_jacobians = 0

    def start(self, t0):
        """Initial accelerations from the index-1 solve: Ẇ_0, a_0 = Ẇ_0."""
        prob = self.prob
        quats = prob.start_quats
        Vd = prob.model.f(self.q, self.V, t0)
        prob.n_f += 1
        self.Wd = prob.group_acceleration(Vd, self.W, quats)
        self.a = self.Wd.copy()
        self.lam = np.zeros(self.nc)

    def _state(self, Wd1, h):
        a1 = ((1 - self.af) * Wd1 + self.af * self.Wd - self.am * self.a) / (1 - self.am)
        W1 = self.W + h * (1 - self.gamma) * self.a + h * self.gamma * a1
        dX = self.prob.to_local(h * self.W + h * h * (0.5 - self.beta) * self.a + h * h * self.beta * a1)
        return a1, W1, dX * self.prob.chart_scale

    def _residual(self, Wd1, lam, t1, h):
        prob, m = self.prob, self.prob.model
        a1, W1, dX = self._state(Wd1, h)
        q1, quats = prob.configuration(dX)
        V1 = prob.model_velocity(W1, quats)
        Vd1 = prob.model_acceleration(Wd1, W1, quats)
        prob.n_f += 1
        if self.use_M:
            Rd = m.mass_matrix(q1) @ Vd1 - m.forces(q1, V1, t1)
            A = None
            if self.nc:
                A = m.constraint_jacobian(q1)
                Rd = Rd + A.T @ lam
                return np.concatenate([Rd, m.constraints(q1) / (h * h * self.beta)]), A, q1, V1
            return Rd, A, q1, V1
        return Vd1 - m.f(q1, V1, t1), None, q1, V1

    def _jacobian(self, Wd1, lam, t1, h, r0, A):
        if self._model_jacobian:
            return self._jacobian_from_model(Wd1, lam, t1, h, A)
        n = len(Wd1)
        J = np.zeros((n + self.nc, n + self.nc))
        # q moves by h²β·e: scale e so that it moves by ~√eps, or the g/(h²β) rows are noise
        scale = 1.5e-8 / min(1.0, h * h * self.beta)
        for j in range(n):
            e = scale * max(1.0, abs(Wd1[j]))
            Wp = Wd1.copy()
            Wp[j] += e
            J[:, j] = (self._residual(Wp, lam, t1, h)[0] - r0) / e
        if self.nc:
            J[:n, n:] = A.T
        self._factor(J, t1, h)

    def _factor(self, J, t1, h):
        self.n_jacobians += 1
        if not np.isfinite(J).all():
            self._lu = None
            raise StepFailed(f"genalpha: Newton diverged at t = {t1:.9g} (h = {h:.3g}): the iteration "
                             "matrix is not finite; reduce dt.")
        self._lu = sla.lu_factor(J)
        self._lu_h = h

    def _jacobian_from_model(self, Wd1, lam, t1, h, A):
        """Iteration matrix from the model: ∂R_dyn/∂V̇ = M c_acc + C_t c_vel + K_t c_pos with
        c_acc = 1, c_vel = hγ(1-α_f)/(1-α_m), c_pos = h²β(1-α_f)/(1-α_m) (T(ΔX) ≈ I), and the
        constraint rows A (1-α_f)/(1-α_m) (the g/(h²β) scaling cancels c_pos)."""
        m = self.prob.model
        _, W1, dX = self._state(Wd1, h)
        q1, quats = self.prob.configuration(dX)
        V1 = self.prob.model_velocity(W1, quats)
        k = (1 - self.af) / (1 - self.am)
        Jd = m.iteration_matrix(q1, V1, t1, 1.0, h * self.gamma * k, h * h * self.beta * k)
        n = len(Wd1)
        J = np.zeros((n + self.nc, n + self.nc))
        J[:n, :n] = Jd
        if self.nc:
            A = m.constraint_jacobian(q1) if A is None else A
            J[:n, n:] = A.T
            J[n:, :n] = A * k
        self._factor(J, t1, h)

    def attempt(self, t, h):
        """Modified Newton: the stored iteration matrix is refreshed at the current
        iterate whenever the contraction factor ‖Δz_k‖/‖Δz_{k-1}‖ exceeds THETA
        (the body-frame unknowns of SE(3) make it rotate with fast-spinning bodies)."""
        if self.Wd is None:
            self.start(t)
        t1 = t + h
        n = len(self.W)
        # predictor: linear extrapolation of the accelerations of the last two steps
        if self._prev is not None and self._prev[0] == h:
            Wd1 = 2.0 * self.Wd - self._prev[1]
            lam = 2.0 * self.lam - self._prev[2]
        else:
            Wd1, lam = self.Wd.copy(), self.lam.copy()
        if self._lu is None or self._lu_h != h:
            r, A, _, _ = self._residual(Wd1, lam, t1, h)
            self._jacobian(Wd1, lam, t1, h, r, A)
        prev, converged, finite = None, False, True
        for it in range(self.nmax):
            r, A, q1, V1 = self._residual(Wd1, lam, t1, h)
            if not np.isfinite(r).all():
                finite = False
                break
            dz = -sla.lu_solve(self._lu, r)
            Wd1 = Wd1 + dz[:n]
            lam = lam + dz[n:]
            self.n_newton += 1
            # converge on the velocity change h·ΔẆ: Ẇ itself carries rounding noise
            # of size eps/(h²β) from the scaled constraint rows
            size = h * np.linalg.norm(dz[:n])
            if size <= self.tol * (1.0 + np.linalg.norm(self.W)):
                converged = True
                break
            if prev is not None and size > self.THETA * prev:
                r, A, _, _ = self._residual(Wd1, lam, t1, h)
                self._jacobian(Wd1, lam, t1, h, r, A)
                prev = None
            else:
                prev = size
        if not converged:
            self._lu = None
            why = "diverged (non-finite residual)" if not finite else f"did not converge in {self.nmax} iterations"
            raise StepFailed(f"genalpha: Newton {why} at t = {t1:.9g} (h = {h:.3g}); reduce dt.")
        a1, W1, dX = self._state(Wd1, h)
        q1, quats = self.prob.configuration(dX)
        V1 = self.prob.model_velocity(W1, quats)
        self._prev = (h, self.Wd, self.lam)
        self.Wd, self.a, self.lam = Wd1, a1, lam
        self.finish(t1, q1, V1, W1, quats)
        return True, None
