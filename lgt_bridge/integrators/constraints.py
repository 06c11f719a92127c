"""Projection onto the constraint manifold after an explicit step.

Position: Gauss-Newton on a local increment δ (per body a rotation vector in the
body frame and an inertial translation, i.e. SO(3)xR³ exp coordinates, which is
what the twist Jacobian A(q) differentiates), minimum M-norm, on the position rows
g(q, t) of the constraints:
    δ = -M⁻¹Aₚᵀ (Aₚ M⁻¹Aₚᵀ)⁺ g(q, t),    q <- τ(q, δ)
Velocity, on every row (velocity-level rows included):
    V <- V - M⁻¹Aᵀ (A M⁻¹Aᵀ)⁺ (A V - b(q, t))
with b = -∂g/∂t for time-dependent constraints (zero otherwise). ⁺ is the
minimum-norm solve of :func:`lgt_bridge.model.solve_schur` (redundant constraints); both
steps come from the model's ``constraint_schur`` (dense by default, sparse where a model has
sparse rows). The residuals before and after are kept for the result's statistics.
"""
import warnings

import numpy as np

from ..errors import ModelNote
from .problem import make_problem


#: the rounding floor's factor: 4 eps (np.finfo costs ~2 µs a call, once per step here)
_EPS4 = 4 * float(np.finfo(float).eps)


class Projector:
    """``tol``: the position residual at which the Gauss-Newton iteration stops; None (the
    default) iterates to the rounding floor: until max|g| ≤ 4 eps (1 + max|q|) or the
    residual stops falling (less than halved by an iteration). A fixed absolute tolerance
    looser than that fought tight error control: near a singular configuration of a
    mechanism (the IFToMM double four-bar with its bars in line) the index-1 accelerations
    change by the residual over σ², σ the smallest singular value of A: 1e-12 left there
    moved f by 300x its size, at the rounding floor it stays put."""

    #: an iteration that cut the residual below this fraction of it keeps its Jacobian and
    #: factor for the next (simplified Gauss-Newton: the next residual is at the rounding
    #: floor, or near it, either way); a slower one has the next take them afresh
    REUSE_BELOW = 1e-3

    def __init__(self, model, tol=None, max_iter=12):
        self.model = model
        self.tol, self.max_iter = tol, max_iter
        self.prob = make_problem(model, "SO3xR3", "exp")
        self.rows = model.position_rows
        self.all_rows = len(self.rows) == model.n_constraints
        self.max_before = 0.0
        self.max_after = 0.0
        self.max_vel_after = 0.0
        self.iterations = 0

    def _g(self, q, t):
        g = self.model.constraints_at(q, t)
        return g if self.all_rows else g[self.rows]

    def _schur(self, q):
        """(Aₚ, correct) of the position rows (``Model.constraint_schur``)."""
        return self.model.constraint_schur(q, None if self.all_rows else self.rows)

    def positions(self, q, t):
        """q moved onto g(q, t) = 0 (position rows); returns (q, residual before, after)."""
        g = self._g(q, t)
        before = gmax = float(np.abs(g).max()) if len(g) else 0.0
        tol = self.tol if self.tol is not None else _EPS4 * (1.0 + float(np.abs(q).max()))
        correct = None
        for k in range(self.max_iter):
            if not len(g) or gmax <= tol:
                break
            if correct is None:
                correct = self._schur(q)[1]
            d = correct(g)
            self.prob.start(q)
            q_new, _ = self.prob.configuration(self.prob.to_local(-d))
            g_new = self._g(q_new, t)
            g_new_max = float(np.abs(g_new).max())
            self.iterations += 1
            if self.tol is None and k and not g_new_max < 0.5 * gmax:
                if g_new_max < gmax:                # at the rounding floor: keep the better one
                    q, g, gmax = q_new, g_new, g_new_max
                break
            if not g_new_max < self.REUSE_BELOW * gmax:
                correct = None      # a slow contraction: the next iteration at a fresh Jacobian
            q, g, gmax = q_new, g_new, g_new_max
        return q, before, gmax

    def velocities(self, q, V, t):
        """V moved onto A(q) V = b(q, t); returns (V, residual after)."""
        m = self.model
        A, correct = m.constraint_schur(q)
        r = A @ V
        b = m.velocity_rhs(q, t)
        if b is not None:
            r = r - b
        V = V - correct(r)
        r = A @ V
        if b is not None:
            r = r - b
        return V, float(np.abs(r).max())

    def __call__(self, q, V, t=None):
        q, before, after = self.positions(q, t)
        V, vel = self.velocities(q, V, t)
        self.max_before = max(self.max_before, before)
        self.max_after = max(self.max_after, after)
        self.max_vel_after = max(self.max_vel_after, vel)
        return q, V


def note_initial_projection(rep, t0):
    """Warn (a ModelNote, pointing at the user's call) that the initial state was moved onto
    the constraints, by how much: ``rep`` is :func:`project_initial`'s report."""
    warnings.warn(ModelNote(
        f"the initial state at t = {t0:g} violates the constraints (positions by "
        f"{rep['position_residual']:.3g}, velocities by {rep['velocity_residual']:.3g}); it was moved "
        f"onto them before the first step: q by up to {rep['position']:.3g}, V by up to "
        f"{rep['velocity']:.3g} (the model's own rule where it has one: Exudyn's first implicit step, "
        "Pinocchio's loop closure). Make the "
        "initial state consistent to silence this note."), stacklevel=5)


def project_initial(model, q0, V0, t0, tol=1e-10):
    """(q, V, report): the initial state moved onto g(q, t0) = 0 and A V = b when it
    violates them (inconsistent initial conditions, as Exudyn scripts often have:
    Exudyn's own implicit solver corrects them in its first step). ``report`` is None
    when nothing had to move, else a dict with the residuals before and the size of the
    corrections: ``position``/``velocity`` (largest change of q and V entries) and
    ``position_residual``/``velocity_residual`` (largest violation before)."""
    if not model.n_constraints:
        return q0, V0, None
    pr = Projector(model, tol=1e-13, max_iter=20)
    g = pr._g(q0, t0)
    A = model.constraint_jacobian(q0)
    b = model.velocity_rhs(q0, t0)
    rv = A @ V0 - (0.0 if b is None else b)
    gmax = float(np.abs(g).max()) if len(g) else 0.0
    vmax = float(np.abs(rv).max()) if len(rv) else 0.0
    scale_v = 1.0 + float(np.abs(V0).max())
    if gmax <= tol and vmax <= tol * scale_v:
        return q0, V0, None
    q, _, after = pr.positions(q0, t0)
    V, vel = pr.velocities(q, V0, t0)
    rep = dict(position_residual=gmax, velocity_residual=vmax,
               position=float(np.abs(q - q0).max()), velocity=float(np.abs(V - V0).max()),
               position_residual_after=after, velocity_residual_after=vel)
    return q, V, rep
