"""Projection onto the constraint manifold after an explicit step.

Position: Gauss-Newton on a local increment δ (per body a rotation vector in the
body frame and an inertial translation, i.e. SO(3)xR³ exp coordinates, which is
what the twist Jacobian A(q) differentiates), minimum M-norm:
    δ = -M⁻¹Aᵀ (A M⁻¹Aᵀ)⁻¹ g(q),    q <- τ(q, δ)
Velocity: V <- V - M⁻¹Aᵀ (A M⁻¹Aᵀ)⁻¹ A V.
The residuals before and after are kept for the result's statistics.
"""
import numpy as np

from .local import make_problem


class Projector:

    def __init__(self, model, tol=1e-12, max_iter=10):
        self.model = model
        self.tol, self.max_iter = tol, max_iter
        self.prob = make_problem(model, "SO3xR3", "exp")
        self.max_before = 0.0
        self.max_after = 0.0
        self.max_vel_after = 0.0
        self.iterations = 0

    def _correction(self, q, r):
        A = self.model.constraint_jacobian(q)
        MiAt = self.model.solve_mass(q, A.T)
        return MiAt @ np.linalg.solve(A @ MiAt, r), A, MiAt

    def __call__(self, q, V):
        m = self.model
        g = m.constraints(q)
        self.max_before = max(self.max_before, float(np.abs(g).max()))
        for _ in range(self.max_iter):
            if np.abs(g).max() <= self.tol:
                break
            d, _, _ = self._correction(q, g)
            self.prob.start(q)
            q, _ = self.prob.configuration(self.prob.to_local(-d))
            g = m.constraints(q)
            self.iterations += 1
        A = m.constraint_jacobian(q)
        MiAt = m.solve_mass(q, A.T)
        V = V - MiAt @ np.linalg.solve(A @ MiAt, A @ V)
        self.max_after = max(self.max_after, float(np.abs(g).max()))
        self.max_vel_after = max(self.max_vel_after, float(np.abs(A @ V).max()))
        return q, V
