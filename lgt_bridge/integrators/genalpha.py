"""Lie group generalized-α, index 3 (Brüls, Cardona, Arnold 2012; Arnold, Brüls,
Cardona 2015), on the local coordinates of the bridge:

    (1 - α_m) a_{k+1} = (1 - α_f) Ẇ_{k+1} + α_f Ẇ_k - α_m a_k
    W_{k+1} = W_k + h (1 - γ) a_k + h γ a_{k+1}
    ΔX      = h W_k + h² (½ - β) a_k + h² β a_{k+1},      q_{k+1} = τ(q_k, ΔX)
    M(q) V̇ - Q(q, V, t) + Aᵀ(q) λ = 0,    g(q, t) = 0       at t_{k+1}

(velocity-level rows of the constraints, nonholonomic, hold as A(q) V = b(q, t) instead).

ΔX is an increment in exponential coordinates; on a Cayley chart the step uses
cay(ΔX/2), which agrees with exp(ΔX) to O(|ΔX|³) and keeps second order.

Solved by modified Newton in (Ẇ_{k+1}, λ), the constraint rows scaled by 1/(h²β). The
residual's rows are those of Ẇ (the linear rows of an SE(3) body in its body frame, like
its unknowns u̇, so the iteration matrix does not turn with the bodies):
    M̄ Ẇ - Q + Aᵀλ                 a constant mass matrix M̄ (``Model.constant_mass``) and
                                   no SE(3) body, constrained or not (one product by M̄, the
                                   fused Newton update of :mod:`.genalpha_newton`; without
                                   constraints the same updates as in accelerations);
    Ẇ - Ẇ(f(q, V, t))             otherwise unconstrained (the model's own f);
    Ẇ - Ẇ(M⁻¹(Q - Aᵀλ))           constrained, when the model solves with M itself
                                   (it overrides ``solve_mass``);
    P (M V̇ - Q + Aᵀλ)             constrained otherwise (P: the rotation to body frames).

Iteration matrix, kept across iterations and steps while Newton contracts fast enough to
converge within BUDGET updates (:mod:`.newton_control`):
* models with ``mass_matrix`` and ``iteration_matrix(q, V, t, c_acc, c_vel, c_pos)``
  (M c_acc + C_t c_vel + K_t c_pos in V = (ω, ṙ) and the SO(3)xR³ increments (δθ body,
  δr inertial)): analytic and block-sparse, assembled per body from the model's M, C_t,
  K_t and A and the exact derivatives of the chart (dψ) and of the SE(3) velocity
  conversion (:mod:`.genalpha_matrix`). If the model's method takes ``lam`` it is asked
  for the joints' geometric stiffness ∂(Aᵀλ)/∂z too, if it takes ``sparse`` for a
  scipy.sparse matrix on large systems.
* every other model: finite differences of the residual in Ẇ (the λ columns from A),
  nv residual evaluations per refresh. Exact K_t and C_t matter (a stiff spring needs its
  K_t for Newton to converge), which M alone would not give, and the engine models that
  lack ``iteration_matrix`` have few coordinates.
Bodies that do not interact give a block-diagonal matrix, inverted per block; otherwise
sparse LU above SPARSE_MIN unknowns, dense LU below (:func:`.genalpha_matrix.factorize`).
"""
import math
from collections import namedtuple
from typing import NamedTuple

import numpy as np

from ..errors import InputError
from ..model import Model
from .base import StepFailed, Stepper
from .genalpha_matrix import (DENSE_MAX, SPARSE_MIN, DensePattern, Kinematics, accepts, coo, csr, factorize,
                              fd_matrix)
from .genalpha_newton import iterate, predict
from .newton_control import tolerances


# what a step's state needs besides Ẇ_{k+1}, in which it is affine:
# a_{k+1} = a0 + k Ẇ, W_{k+1} = W0 + s_v Ẇ, ΔX = dX0 + sp Ẇ (in X's layout, chart-scaled)
_Affine = namedtuple("_Affine", "h a0 W0 dX0 k s_v sp")


class Newmark(NamedTuple):
    """Newmark's method with (β, γ), given as ``rho_inf``: generalized-α with α_m = α_f = 0
    (the Exudyn drop-in's ``generalizedAlpha.useNewmark``; β = 1/4, γ = 1/2: the trapezoidal
    rule, no numerical damping)."""
    beta: float = 0.25
    gamma: float = 0.5


def coefficients(rho_inf):
    """(α_m, α_f, γ, β) of Chung and Hulbert's generalized-α for the spectral radius at
    infinity ``rho_inf``, or of Newmark's method for a :class:`Newmark`."""
    if isinstance(rho_inf, Newmark):
        beta, gamma = float(rho_inf.beta), float(rho_inf.gamma)
        if not (gamma >= 0.5 and 2.0 * beta >= gamma):
            raise InputError(f"genalpha: Newmark(beta={beta}, gamma={gamma}) is not unconditionally stable "
                             "(it needs 2 beta >= gamma >= 1/2; Exudyn's default: beta = 0.25, gamma = 0.5).")
        return 0.0, 0.0, gamma, beta
    if not 0.0 <= rho_inf <= 1.0:
        raise InputError(f"genalpha: rho_inf = {rho_inf} must lie in [0, 1] (1: no numerical "
                         "damping, 0: asymptotic annihilation).")
    am = (2 * rho_inf - 1) / (rho_inf + 1)
    af = rho_inf / (rho_inf + 1)
    gamma = 0.5 + af - am
    beta = 0.25 * (gamma + 0.5) ** 2
    return am, af, gamma, beta



def build(method, problem, o):
    """genalpha's stepper (the registry's builder): index-3, no projection."""
    return GenAlpha(problem, rho_inf=o["rho_inf"], newton_tol=o["newton_tol"])


class GenAlpha(Stepper):

    #: at most this many halvings of one step after Newton failures
    MAX_CUTS = 30
    DIVERGED_HINT = ("Reduce dt, or lower rho_inf for more numerical damping of the highest "
                     "frequencies. The result keeps every step before it.")

    def __init__(self, problem, rho_inf=0.9, newton_tol=1e-10, newton_max=25):
        super().__init__(problem)
        self.am, self.af, self.gamma, self.beta = coefficients(rho_inf)
        self.tol, self.nmax = newton_tol, newton_max
        m = problem.model
        self.use_M = m.has_mass_matrix
        self.nc = m.n_constraints
        self._vel_rows = np.array(m.velocity_rows, int) if len(m.velocity_rows) else None
        if self.nc and not self.use_M:
            raise InputError("genalpha on a constrained model needs mass_matrix and forces "
                             "from the model (index-3 residual M V̇ - Q + Aᵀλ).")
        # SE(3) bodies: the linear rows of the residual in the body frame (P = Rᵀ there)
        self.rotate_rows = any(s.se3 for s in problem.sets)
        # the residual in accelerations, or in forces (see the module docstring); in forces
        # with one product by a constant M̄ (no SE(3) body: V̇ = Ẇ)
        self._Mc = self._Mcsr = None
        if not self.rotate_rows and m.constant_mass is not None:
            from .genalpha_matrix import _csr_product
            from scipy.sparse import csr_matrix
            Mc = csr_matrix(m.constant_mass)
            self._Mc = _csr_product(Mc) if problem.compiled else Mc.__matmul__
            if problem.compiled:
                self._Mcsr = (Mc.indptr.astype(np.int64), Mc.indices.astype(np.int64),
                              np.ascontiguousarray(Mc.data, dtype=float))
        self.accel_form = self._Mc is None and (not self.nc or type(m).solve_mass is not Model.solve_mass)
        self.analytic = self.use_M and callable(getattr(m, "iteration_matrix", None))
        self._lam_kw = self.analytic and accepts(m.iteration_matrix, "lam")
        self._sparse_kw = self.analytic and accepts(m.iteration_matrix, "sparse")
        # large models: A as a scipy.sparse matrix where the model gives one
        self._sparse_A = bool(self.nc and problem.layout.nv + self.nc > SPARSE_MIN
                              and accepts(m.constraint_jacobian, "sparse"))
        self._kin = Kinematics(problem) if self.analytic else None
        # to_local is a permutation of the entries (V's layout -> X's): X = d[_to_local]
        self._to_local = problem.local_index
        # A the same at every q: read once (the fused Newton update takes it as it is)
        self._A_const = bool(self.nc and m.constant_constraint_jacobian and not self._sparse_A)
        self._A_fixed = None
        self._solve = None
        self._memo = {}               # factorize's memory of J's pattern
        self._pattern = None          # the kept pattern of a dense J (_dense_vector_matrix)
        self._lu_h = None
        self.Wd = None
        self._prev = None
        self._consts = None
        self.n_jacobians = 0
        self.min_step = 1e-8          # Exudyn's default timeIntegration.minimumStepSize
        self.cut_steps = 0
        self.n_floor = 0              # Newton solves ended at the rounding floor

    def snapshot(self):
        return (self.q.copy(), self.V.copy(), self.Wd, getattr(self, "a", None),
                getattr(self, "lam", None), self._prev)

    def restore(self, snap):
        self.set_state(snap[0], snap[1])
        self.Wd, self.a, self.lam, self._prev = snap[2:]
        self._consts = None

    def step_rates(self):
        """(Ẇ_k, Ẇ_{k+1}) of the last step: its unknowns, no f."""
        if self._prev is None or self.Wd is None:
            return None
        return self._prev[1], self.Wd

    def restart_at(self, q, V, t):
        """Continue from (q, V) at t inside the last step (a terminal event): Ẇ from f
        there (the constraint forces resolved, as at a start), and a = Ẇ + (a - Ẇ) with the
        step end's lag a - Ẇ ≈ Δα h Ẅ kept, so the auxiliary a stays consistent
        (a_n ≈ Ẇ(t_n + Δα h)); the predictor's history is dropped."""
        lag = None if (self.Wd is None or self.a is None) else self.a - self.Wd
        lam = getattr(self, "lam", None)
        self.set_state(q, V)
        self._prev, self._consts = None, None
        self.start(t)
        if lam is not None:
            self.lam = lam                    # the Newton guess of the first step
        if lag is not None:
            self.a = self.a + lag

    def start(self, t0):
        """Initial accelerations from the index-1 solve: Ẇ_0, a_0 = Ẇ_0."""
        prob = self.prob
        quats = prob.start_quats
        Vd = prob.model.f(self.q, self.V, t0)
        prob.n_f += 1
        self.Wd = prob.group_acceleration(Vd, self.W, quats)
        self.a = self.Wd.copy()
        self.lam = np.zeros(self.nc)

    @property
    def _k(self):
        return (1 - self.af) / (1 - self.am)

    def _affine(self, h):
        """The step's :data:`_Affine` parts, computed once per step."""
        c = self._consts
        if c is None or c.h != h:
            k, g, b = self._k, self.gamma, self.beta
            a0, Wa, dXa, sp = self.prob.ga_affine(self.W, self.Wd, self.a, self.af, self.am, h, g, b, k,
                                                  self._to_local)
            c = self._consts = _Affine(h, a0, Wa, dXa, k, h * g * k, sp)
        return c

    def _state(self, Wd1, h):
        """(W_{k+1}, ΔX in chart coordinates) for Ẇ_{k+1}."""
        c = self._affine(h)
        return c.W0 + c.s_v * Wd1, c.dX0 + c.sp * Wd1[self._to_local]

    def residual(self, Wd1, lam, t1, h):
        """The Newton residual at (Ẇ_{k+1}, λ) for the step of length h ending at t1."""
        self._consts = None
        return self._residual(Wd1, lam, t1, h)

    def _evaluate(self, Wd1, h):
        """(q, V, quats, W) at the step's end for Ẇ_{k+1}: one kernel call on the compiled
        backend, whose arrays are views of its work array (valid until the next call)."""
        c = self._affine(h)
        return self.prob.ga_state(Wd1, c.s_v, c.sp, c.W0, c.dX0, self._to_local)

    def _residual(self, Wd1, lam, t1, h):
        """The rows of the module docstring, then g/(h²β). Sets ``_finite``."""
        prob, m = self.prob, self.prob.model
        q1, V1, quats, W1 = self._evaluate(Wd1, h)
        prob.n_f += 1
        if self._Mc is not None:
            return self._force_rows(q1, V1, Wd1, lam, t1, h)
        if not self.nc:
            # the model's f sees the kernel's buffers, as in the explicit methods' stages
            r = np.empty(len(Wd1))
            self._finite = math.isfinite(prob.ga_residual(m.f(q1, V1, t1), Wd1, r, W1, quats))
            return r
        q1, V1, quats, W1 = q1.copy(), V1.copy(), quats.copy(), W1.copy()
        A = self._A(q1)
        Q = m.forces(q1, V1, t1) - A.T @ lam
        if self.accel_form:
            Rd = Wd1 - prob.group_acceleration(m.solve_mass(q1, Q), W1, quats)
        else:
            Rd = m.mass_matrix(q1) @ prob.model_acceleration(Wd1, W1, quats) - Q
            if self.rotate_rows:
                Rd = prob.group_velocity(Rd, quats)
        r = np.concatenate([Rd, self._constraint_rows(q1, V1, t1, h)])
        self._finite = bool(np.isfinite(r).all())
        return r

    def _force_rows(self, q1, V1, Wd1, lam, t1, h):
        """[M̄ Ẇ - Q + Aᵀλ; g/(h²β)] with the constant M̄ (no SE(3) body: V̇ = Ẇ), Q and g
        from one model call at the state."""
        m, n = self.prob.model, len(Wd1)
        Q, g = m.forces_and_constraints(q1, V1, t1)
        r = np.empty(n + self.nc)
        r[:n] = self._Mc(Wd1)
        r[:n] -= Q
        r[:n] += self._A(q1).T @ lam
        if self._vel_rows is None:
            np.multiply(g, 1.0 / (h * h * self.beta), out=r[n:])
        else:
            r[n:] = self._constraint_rows(q1, V1, t1, h, g)
        self._finite = math.isfinite(r.dot(r))
        return r

    def _A(self, q1):
        """The model's constraint Jacobian at q1 (scipy.sparse on large models that give it)."""
        m = self.prob.model
        return m.constraint_jacobian(q1, sparse=True) if self._sparse_A else m.constraint_jacobian(q1)

    def _constraint_rows(self, q1, V1, t1, h, g=None):
        """g(q, t)/(h²β) on position rows, (A V - b)/(h γ k) on velocity-level rows (their
        Jacobian in Ẇ is then A, like the position rows' A Z/(h²β)); ``g``: g(q, t) when
        the caller has it."""
        m = self.prob.model
        g = (m.constraints_at(q1, t1) if g is None else g) / (h * h * self.beta)
        if self._vel_rows is None:
            return g
        vr = self._vel_rows
        Av = self._A(q1)[vr] @ V1
        b = m.velocity_rhs(q1, t1)
        if b is not None:
            Av = Av - b[vr]
        g = np.array(g, float)
        g[vr] = Av / self._consts.s_v
        return g

    # --- iteration matrix -------------------------------------------------------------
    def iteration_matrix(self, Wd1, lam, t1, h):
        """∂(residual)/∂(Ẇ_{k+1}, λ) as Newton uses it (a dense array; for tests and
        diagnostics): analytic, L⁻¹J of :meth:`_matrices`, or by finite differences."""
        self._consts = None
        J, L = self._matrices(Wd1, lam, t1, h)
        J = J.toarray() if hasattr(J, "toarray") else J
        if L is None:
            return J
        return np.linalg.solve(L.toarray() if hasattr(L, "toarray") else L, J)

    def _matrices(self, Wd1, lam, t1, h):
        """(J, L) with the residual's Jacobian L⁻¹J (L = None: J itself)."""
        if self.analytic:
            return self._analytic_matrices(Wd1, lam, t1, h)
        return self._fd_matrix(Wd1, lam, t1, h), None

    def _analytic_matrices(self, Wd1, lam, t1, h):
        """J = [M D_a + C_t D_v + K_t Z, Aᵀ; A Z/(h²β), 0] in the model's rows
        (:mod:`.genalpha_matrix`) and L = diag(M Pᵀ or Pᵀ, I): the residual's rows are P
        (times M⁻¹ in the acceleration form) times these, so its Jacobian is L⁻¹J and Newton
        solves J dz = -L r (no M⁻¹ needed). Exact, except for (∂P) r and (∂M⁻¹) r, which
        vanish with the residual r, and what the model leaves out of its iteration_matrix."""
        prob, m = self.prob, self.prob.model
        W1, dX = self._state(Wd1, h)
        q1, quats = prob.configuration(dX)
        V1 = prob.model_velocity(W1, quats)
        aff = self._consts
        n, nc = len(Wd1), self.nc
        kw = {"sparse": n + nc > SPARSE_MIN} if self._sparse_kw else {}
        if self._lam_kw and nc:
            kw["lam"] = lam
        s_p = h * h * self.beta * aff.k
        if not prob.sets:
            # vector and circle coordinates only: Z = s_p I, D_v = s_v I, D_a = I, no P —
            # the model's own M + s_v C_t + s_p K_t, one matrix
            return self._vector_matrices(m.iteration_matrix(q1, V1, t1, 1.0, aff.s_v, s_p, **kw),
                                         q1, V1, t1, h, kw)
        Z, Dv, Da, Pt = self._kin.transforms(dX, W1, Wd1, quats, aff.s_v, s_p)
        M, Ct, Kt = (coo(m.iteration_matrix(q1, V1, t1, *coef, **kw))
                     for coef in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)))
        parts = [Da.rmul(*M), Dv.rmul(*Ct), Z.rmul(*Kt)]
        if self.accel_form:
            lparts = [M if Pt is None else Pt.rmul(*M)]
        else:
            lparts = None if Pt is None else [Pt.triples()]
        if nc:
            Ar, Ac, Av = coo(self._A(q1))
            parts.append((Ac, Ar + n, Av))                                         # Aᵀ
            pos = np.ones(len(Ar), bool)
            if self._vel_rows is not None:
                pos = ~np.isin(Ar, self._vel_rows)
                vr, vc, vv = Dv.rmul(Ar[~pos], Ac[~pos], Av[~pos])
                parts.append((vr + n, vc, vv / aff.s_v))                           # A D_v/(hγk)
            gr, gc, gv = Z.rmul(Ar[pos], Ac[pos], Av[pos])
            parts.append((gr + n, gc, gv / (h * h * self.beta)))                   # A Z/(h²β)
            if lparts is not None:
                lparts.append((np.arange(n, n + nc), np.arange(n, n + nc), np.ones(nc)))
        shape = (n + nc, n + nc)
        return csr(shape, parts), (None if lparts is None else csr(shape, lparts))

    def _vector_matrices(self, K, q1, V1, t1, h, kw):
        """(J, L) of :meth:`_analytic_matrices` on a model of vector and circle coordinates
        only: K = M + s_v C_t + s_p K_t, J = [K, Aᵀ; A s_p/(h²β) (A on velocity rows), 0],
        L = diag(M, I) in the acceleration form."""
        m, n, nc = self.prob.model, K.shape[0], self.nc
        if isinstance(K, np.ndarray) and not self.accel_form:
            return self._dense_vector_matrix(K, q1), None
        parts = [coo(K)]
        lparts = None
        if self.accel_form:
            lparts = [coo(m.iteration_matrix(q1, V1, t1, 1.0, 0.0, 0.0, **kw))]
        if nc:
            Ar, Ac, Av = coo(self._A(q1))
            scale = np.full(len(Ar), self._consts.k)                    # s_p/(h²β) = k
            if self._vel_rows is not None:
                scale[np.isin(Ar, self._vel_rows)] = 1.0                 # A D_v/(hγk) = A
            parts += [(Ac, Ar + n, Av), (Ar + n, Ac, Av * scale)]
            if lparts is not None:
                lparts.append((np.arange(n, n + nc), np.arange(n, n + nc), np.ones(nc)))
        shape = (n + nc, n + nc)
        return csr(shape, parts), (None if lparts is None else csr(shape, lparts))

    def _dense_vector_matrix(self, K, q1):
        """J of :meth:`_vector_matrices` from a dense K: assembled dense, then in a kept
        sparse pattern above DENSE_MAX (:class:`.genalpha_matrix.DensePattern`)."""
        n, nc = K.shape[0], self.nc
        J = np.zeros((n + nc, n + nc))
        J[:n, :n] = K
        if nc:
            A = self._A_fixed if self._A_fixed is not None else self._A(q1)
            A = A.toarray() if hasattr(A, "toarray") else np.asarray(A, float)
            J[:n, n:] = A.T
            J[n:, :n] = A
            if self._vel_rows is None:
                J[n:, :n] *= self._consts.k                             # s_p/(h²β) = k
            else:
                pos = np.setdiff1d(np.arange(nc), self._vel_rows)        # A D_v/(hγk) = A
                J[n + pos, :n] *= self._consts.k
        if n + nc <= DENSE_MAX:
            return J
        if self._pattern is None:
            self._pattern = DensePattern()
        return self._pattern.csc(J)

    def _fd_matrix(self, Wd1, lam, t1, h):
        return fd_matrix(self, Wd1, lam, t1, h)

    def _jacobian(self, Wd1, lam, t1, h):
        J, L = self._matrices(Wd1, lam, t1, h)
        self.n_jacobians += 1
        self._solve = None
        if not all(np.isfinite(X.data if hasattr(X, "tocsr") else X).all() for X in (J, L) if X is not None):
            raise StepFailed(f"genalpha: Newton diverged at t = {t1:.9g} (h = {h:.3g}): the iteration "
                             "matrix is not finite; reduce dt.")
        try:
            self._solve = factorize(J, L, compiled=self.prob.compiled, memo=self._memo)
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            raise StepFailed(f"genalpha: the iteration matrix is singular at t = {t1:.9g} "
                             f"(h = {h:.3g}): {exc}; check the constraints for redundancy or "
                             "reduce dt.") from None
        self._lu_h = h

    def attempt(self, t, h):
        """One step of length h; when Newton fails the step is declined and retried at half
        the length (down to ``min_step``), as Exudyn's own generalized-α does, and the
        step grows back (doubling, capped at dt by the driver) once it succeeds."""
        try:
            self._attempt(t, h)
        except StepFailed as exc:
            if h / 2 >= self.min_step and self.cut_steps < self.MAX_CUTS:
                self.n_rejected += 1
                self.cut_steps += 1
                self._solve, self._prev = None, None
                return False, 0.5 * h
            if self.cut_steps:
                what = str(exc).removesuffix("; reduce dt.").removesuffix(".")
                raise StepFailed(
                    f"{what}, after halving the step {self.cut_steps} times (min_step = "
                    f"{self.min_step:.3g}). Newton fails when the step is too long for the model's "
                    "fastest motion or stiffest spring, or when the model jumps (a force or user "
                    "function switching, a constraint locking): lower dt or min_step, or check the "
                    "model at this time.", exc.error, exc.diverged) from None
            raise
        grown = self.cut_steps > 0
        self.cut_steps = max(0, self.cut_steps - 1)
        return True, (2.0 * h if grown else None)

    def _attempt(self, t, h):
        """Modified Newton (:mod:`.newton_control`): the iteration matrix is kept across
        steps while the updates contract fast enough to converge within BUDGET updates, and
        refreshed at the current iterate otherwise (the body-frame unknowns of SE(3) make it
        rotate with fast-spinning bodies); a step begun on a kept matrix that fails (even if
        refreshed on the way, at an iterate the stale one sent away) is retried once from the
        predictor on a matrix taken there before it counts as failed."""
        if self.Wd is None:
            self.start(t)
        self._consts = None
        t1 = t + h
        # predictor: the accelerations of the last two steps extrapolated (genalpha_newton.predict)
        if self._prev is not None and _same(self._prev[0], h):
            Wd1 = predict(self.Wd, self._prev[1], self.prob.compiled)
            lam = predict(self.lam, self._prev[2], self.prob.compiled)
        else:
            Wd1, lam = self.Wd.copy(), self.lam.copy()
        kept = self._solve is not None and _same(self._lu_h, h)
        if not kept:
            self._jacobian(Wd1, lam, t1, h)
        tol, floor = tolerances(self.W, self.q, self.tol, h, self.beta, self.nc > 0)
        out = self._newton(Wd1, lam, t1, h, tol, floor)
        if out is None and kept:
            self._jacobian(Wd1, lam, t1, h)
            out = self._newton(Wd1, lam, t1, h, tol, floor)
        if out is None:
            self._solve = None
            why = self._why
            raise StepFailed(f"genalpha: Newton {why} at t = {t1:.9g} (h = {h:.3g}); reduce dt.",
                             diverged=False)
        Wd1, lam = out
        q1, V1, quats, W1 = (x.copy() for x in self._evaluate(Wd1, h))
        a1 = self._consts.a0 + self._consts.k * Wd1
        self._prev = (h, self.Wd, self.lam)
        self.Wd, self.a, self.lam = Wd1, a1, lam
        self.finish(t1, q1, V1, W1, quats)

    #: a kept iteration matrix is refreshed when the step would need more updates than this
    BUDGET = 10

    def _newton(self, Wd1, lam, t1, h, tol, floor):
        """Newton's updates from (Ẇ, λ) on the stored matrix (:mod:`.genalpha_newton`): the
        converged (Ẇ_{k+1}, λ), or None (the reason in ``_why``)."""
        return iterate(self, Wd1, lam, t1, h, tol, floor)


def _same(h0, h):
    """The same step size up to rounding (a step shortened to land on an output time by
    1e-16 keeps the iteration matrix and the predictor)."""
    return h0 is not None and abs(h - h0) <= 1e-9 * h
