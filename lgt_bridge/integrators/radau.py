"""Radau IIA of order 5 on the local coordinates: the implicit, L-stable, stiffly accurate
three-stage collocation method (Hairer & Wanner, Solving ODEs II, IV.8) run as RKMK on the
local ODE y = (X, W) from X = 0,

    Z_i = h Σ_j a_ij F(y_k + Z_i, t + c_j h),   F(X, W, t) = (dψ⁻¹_{-X}(W), Ẇ(f(τ(q_k, X), V, t))),
    y_{k+1} = y_k + Z_3  (c_3 = 1),             q_{k+1} = τ(q_k, X_{k+1}).

For stiff models (PD-controlled robots, stiff springs) whose explicit methods are held to
tiny steps by stability: it takes steps sized by accuracy alone, at order 5.

* Simplified Newton on the collocation system, with the Jacobian J = ∂F/∂y at the start of a
  step (from the model's own M, C_t, K_t on unconstrained models, :func:`model_jacobian`;
  else forward differences of F, nX + nv evaluations of f), transformed by the eigenvectors
  of A⁻¹ into one real and one complex linear system of the size of y (Hairer's trick);
  J and their LU factors are kept across steps while Newton contracts and h is unchanged
  (dense LAPACK LU, SuperLU above SPARSE_MIN unknowns).
* Error estimate of Hairer's RADAU5: err = (γ/h - J)⁻¹ (F(y_k) + Σ e_i Z_i / h), from the
  embedded third-order formula with an explicit first node; predictive (Gustafsson) step-size
  control. Starting guess: the previous step's collocation polynomial, extrapolated.
* Dense output: the collocation polynomial on (X, W) within the step, through τ of the step's
  base. Constrained models are projected after each step, as with the explicit methods.

The tableau is computed here from its nodes (a_ij = ∫_0^{c_i} ℓ_j, the eigen-decomposition of
A⁻¹, the error weights from the embedded formula's order conditions); tests/core/test_radau.py
checks it against the order conditions and Hairer's published error weights.
"""
import math

import numpy as np

from .base import ChartLimit, StepFailed, Stepper
from .control import initial_step, rms
from .genalpha_matrix import SPARSE_MIN, accepts, assemble

_EPS = np.finfo(float).eps


def _tableau():
    s6 = math.sqrt(6.0)
    c = np.array([(4.0 - s6) / 10.0, (4.0 + s6) / 10.0, 1.0])
    V = np.vander(c, 3, increasing=True)                   # V[i, k] = c_i^k
    integ = np.array([[ci ** (k + 1) / (k + 1) for k in range(3)] for ci in c])
    A = integ @ np.linalg.inv(V)                            # a_ij = ∫_0^{c_i} ℓ_j (collocation)
    w, v = np.linalg.eig(np.linalg.inv(A))
    r = int(np.argmin(np.abs(w.imag)))
    k = int(np.argmax(w.imag))
    gamma, mu = float(w[r].real), complex(w[k])
    # A⁻¹ T = T diag(γ, [[α, β], [-β, α]]) with T = [v_r, Re v_μ, Im v_μ]: on u = w_2 + i w_3
    # the 2x2 block multiplies by conj(μ) = α - iβ
    T = np.column_stack([v[:, r].real, v[:, k].real, v[:, k].imag])
    TI = np.linalg.inv(T)
    # embedded formula: weight 1/γ on an explicit node at 0, order 3 -> error weights E with
    # err = (γ/h - J)⁻¹ (F_0 + Eᵀ Z / h)
    g0 = 1.0 / gamma
    bhat = np.linalg.solve(V.T, [1.0 - g0, 0.5, 1.0 / 3.0])
    E = np.linalg.solve(A.T, bhat - A[-1]) / g0
    # dense output: Z(θ) = Σ_k θ^(k+1) Σ_i P[i, k] Z_i, the cubic through (0, 0) and (c_i, Z_i)
    P = np.linalg.inv(V * c[:, None]).T
    return c, A, gamma, mu.conjugate(), T, TI, E, P


C, A, GAMMA, MU, T, TI, E, P = _tableau()
#: T⁻¹ A⁻¹ T: γ, and conj(μ) = α - iβ acting on w2 + i w3 as [[α, β], [-β, α]]
LAMBDA = np.array([[GAMMA, 0.0, 0.0], [0.0, MU.real, -MU.imag], [0.0, MU.imag, MU.real]])


def build(method, problem, o):
    """radau5's stepper (the registry's builder)."""
    return Radau5(problem, o["rtol"], o["atol"], o["projector"])


class Radau5(Stepper):
    """Radau IIA (5) with error control on (X, W); see the module docstring."""

    adaptive = True
    dense_capable = True
    NEWTON_MAXITER = 6
    MIN_FACTOR, MAX_FACTOR = 0.2, 10.0
    DIVERGED_HINT = ("Lower rtol/atol or the first step, or check the model's f there. The result "
                     "keeps every step before it.")

    def __init__(self, problem, rtol, atol, projector=None):
        super().__init__(problem, projector)
        self.rtol, self.atol = rtol, atol
        self.nX = problem.nX
        self.n = problem.nX + problem.nv
        # Hairer's RADAU5 Newton tolerance on the scaled norm, from the size of the tolerance:
        # rtol, or atol when rtol = 0 (pure absolute tolerance), at least 100 eps (rtol = 0
        # itself would make the tolerance 10 eps / 0: Newton stopping after two iterations)
        rt = max(rtol if rtol > 0.0 else atol, 100.0 * _EPS)
        self.newton_tol = max(10.0 * _EPS / rt, min(0.03, math.sqrt(rt)))
        self.J = None
        self._jac_current = False
        self._lu = None                        # (h, real solver, complex solver)
        self._Jsp = None                       # (J, its sparse copy) on large systems
        self.n_jacobians = 0
        self.n_lu = 0
        self.dense = None
        self._f0 = None                        # F(0, W_k) at the current step's start
        self._h_old = self._err_old = None
        self._rejected = False
        self.climit = 1.0 if problem.bounded else np.inf     # stage chart usage |x|/limit
        m = problem.model
        # the model's M, C_t, K_t give J exactly on unconstrained models (a constrained model's
        # f solves for its constraint forces: its J is differenced)
        self._analytic = (not m.n_constraints and m.has_mass_matrix
                          and callable(getattr(m, "iteration_matrix", None)))
        self._kin = None
        self._sparse_kw = self._analytic and accepts(m.iteration_matrix, "sparse")
        if self._analytic:
            from .genalpha_matrix import Kinematics
            self._kin = Kinematics(problem)

    # --- state -----------------------------------------------------------------------
    def set_state(self, q, V, W=None, quats=None, copy=True):
        super().set_state(q, V, W, quats, copy)
        self._f0 = None

    def restore(self, snap):
        super().restore(snap)
        self.dense = None

    def _F(self, X, W, t):
        F = self.prob.rates(np.ascontiguousarray(X), W, t)
        if not np.isfinite(F).all():
            return None
        return F

    def initial_step(self, t):
        """The starting step (:func:`.control.initial_step`) for the embedded order 3."""
        return initial_step(self._F, self.nX, self.W, t, self.rtol, self.atol, 4, f0=self._start_rates(t))

    def _start_rates(self, t):
        if self._f0 is None:
            f0 = self._F(np.zeros(self.nX), self.W, t)
            if f0 is None:
                vmax = float(np.abs(self.V).max(initial=0.0))
                raise StepFailed(f"radau5: the model's f is not finite at the step's start t = {t:.9g} "
                                 f"(|V| = {vmax:.3g}); check the model's f there.")
            self._f0 = f0
        return self._f0

    # --- Jacobian and factors ---------------------------------------------------------
    def _jacobian(self, t, f0):
        """J = ∂F/∂y at (0, W_k): from the model's own derivatives when it has them
        (:func:`model_jacobian`), else forward differences of F (nX + nv evaluations of f)."""
        if self._analytic:
            J = model_jacobian(self.prob, self._kin, self.q, self.V, self.W, f0, t, self._sparse_kw)
            if np.isfinite(J.data if hasattr(J, "tocsc") else J).all():
                self.J = J
                self._jac_current = True
                self._lu = None
                self.n_jacobians += 1
                return
        self._fd_jacobian(t, f0)

    def _fd_jacobian(self, t, f0):
        n, nX, Wk = self.n, self.nX, self.W
        J = np.empty((n, n))
        X = np.zeros(nX)
        for j in range(n):
            if j < nX:
                d = math.sqrt(_EPS)
                X[j] = d
                F = self._F(X, Wk, t)
                X[j] = 0.0
            else:
                d = math.sqrt(_EPS) * max(1.0, abs(Wk[j - nX]))
                W = Wk.copy()
                W[j - nX] += d
                F = self._F(X, W, t)
            if F is None:
                raise StepFailed(f"radau5: the model's f is not finite next to the state at t = {t:.9g} "
                                 "(Jacobian by differences); check the model's f there.")
            J[:, j] = (F - f0) / d
        self.J = J
        self._jac_current = True
        self._lu = None
        self.n_jacobians += 1

    def _factors(self, h):
        """LU factors of γ/h - J and conj(μ)/h - J as solvers (LAPACK's getrf/getrs called
        directly: scipy.linalg.lu_solve's wrappers cost ~5 µs a call, getrs ~1 µs)."""
        if self._lu is not None and self._lu[0] == h:
            return self._lu[1], self._lu[2]
        n = self.n
        if n > SPARSE_MIN:
            return self._sparse_factors(h)
        from scipy.linalg import lapack
        solvers = []
        for mu, getrf, getrs in ((GAMMA, lapack.dgetrf, lapack.dgetrs), (MU, lapack.zgetrf, lapack.zgetrs)):
            A = -self.J if mu is GAMMA else -self.J.astype(complex)
            A.flat[::n + 1] += mu / h
            lu, piv, info = getrf(A, overwrite_a=True)
            if info != 0 or not np.isfinite(lu).all():
                raise StepFailed(f"radau5: the Newton matrix is singular or not finite at h = {h:.3g} "
                                 "(the model's Jacobian); reduce the first step or check the model's f.")
            solvers.append(_Solver(getrs, lu, piv))
        self._lu = (h, *solvers)
        self.n_lu += 1
        return solvers

    def _sparse_factors(self, h):
        """Large systems: J kept sparse (bodies that do not interact give blocks), SuperLU."""
        from scipy import sparse
        from scipy.sparse.linalg import splu
        if self._Jsp is None or self._Jsp[0] is not self.J:
            self._Jsp = (self.J, sparse.csc_matrix(self.J))
        J, eye = self._Jsp[1], sparse.identity(self.n, format="csc")
        try:
            lr = splu((GAMMA / h) * eye - J)
            lc = splu((MU / h) * eye - J.astype(complex))
        except RuntimeError as exc:
            raise StepFailed(f"radau5: the Newton matrix is singular at h = {h:.3g} ({exc}); reduce the "
                             "first step or check the model's f.") from None
        self._lu = (h, lr.solve, lc.solve)
        self.n_lu += 1
        return lr.solve, lc.solve

    # --- one step ---------------------------------------------------------------------
    def _guess(self, t, h):
        """Z at the new nodes from the last step's collocation polynomial (X: relative to
        its end, which is this step's base), else 0."""
        d = self.dense
        if d is None or abs(d.t1 - t) > 1e-12 * max(1.0, abs(t)):
            return np.zeros((3, self.n))
        th = 1.0 + C * h / d.h
        Y = d.local(th)                        # (3, n): (X, W) of the last step's polynomial
        Y1 = d.local(np.array([1.0]))[0]
        return Y - Y1

    def _collocation(self, t, h, Z0, scale, lr, lc):
        """Simplified Newton on the collocation system: (converged, iterations, Z, rate) or
        raises ChartLimit."""
        nX, Wk = self.nX, self.W
        Wt = TI @ Z0
        Z = Z0
        F = np.empty((3, self.n))
        dW = np.empty((3, self.n))
        lam_h = LAMBDA / h
        inv_scale = 1.0 / scale
        ts = [t + float(c) * h for c in C]
        old, rate = None, None
        for k in range(self.NEWTON_MAXITER):
            for i in range(3):
                X = Z[i, :nX]
                if self.climit < np.inf:
                    c = self.prob.chart_usage(X)
                    if c > self.climit:
                        raise ChartLimit.at(self.prob, c, X)
                Fi = self._F(X, Wk + Z[i, nX:], ts[i])
                if Fi is None:
                    return False, k + 1, Z, rate
                F[i] = Fi
            self.n_newton += 1
            # (Λ/h - I⊗J) ΔW = T⁻¹F - (Λ/h) W: the first row real, rows 2 + i 3 complex
            R = TI @ F - lam_h @ Wt
            dW[0] = lr(R[0])
            dc = lc(R[1] + 1j * R[2])
            dW[1], dW[2] = dc.real, dc.imag
            size = rms(dW * inv_scale)
            if old is not None:
                rate = size / old
                if rate >= 1.0 or rate ** (self.NEWTON_MAXITER - k) / (1.0 - rate) * size > self.newton_tol:
                    return False, k + 1, Z, rate
            Wt = Wt + dW
            Z = T @ Wt
            if size == 0.0 or (rate is not None and rate / (1.0 - rate) * size < self.newton_tol):
                return True, k + 1, Z, rate
            old = size
        return False, self.NEWTON_MAXITER, Z, rate

    def attempt(self, t, h):
        try:
            return self._attempt(t, h)
        except ChartLimit as lim:
            self.n_rejected += 1
            self._rejected = True
            return False, lim.shrink(h)

    def _attempt(self, t, h):
        nX, Wk = self.nX, self.W
        f0 = self._start_rates(t)
        yk = np.concatenate([np.zeros(nX), Wk])
        scale = self.atol + self.rtol * np.abs(yk)
        if self.J is None:
            self._jacobian(t, f0)
        while True:
            lr, lc = self._factors(h)
            ok, n_iter, Z, rate = self._collocation(t, h, self._guess(t, h), scale, lr, lc)
            if ok:
                break
            if self._jac_current:              # Newton fails with a fresh Jacobian: shorter step
                self.n_rejected += 1
                self._rejected = True
                self._lu = None
                return False, 0.5 * h
            self._jacobian(t, f0)
        y1 = yk + Z[2]
        ZE = (E @ Z) / h
        err = lr(f0 + ZE)
        esc = self.atol + self.rtol * np.maximum(np.abs(yk), np.abs(y1))
        en = rms(err / esc)
        if en > 1.0 and (self._rejected or self._h_old is None):
            # the estimate of the first or a rejected step, filtered once more (stiff components)
            Fe = self._F(err[:nX], Wk + err[nX:], t)
            if Fe is not None:
                en = rms(lr(Fe + ZE) / esc)
        safety = 0.9 * (2 * self.NEWTON_MAXITER + 1) / (2 * self.NEWTON_MAXITER + n_iter)
        if not math.isfinite(en) or en > 1.0:
            self.n_rejected += 1
            self._rejected = True
            fac = self.MIN_FACTOR if not math.isfinite(en) else max(self.MIN_FACTOR, safety * en ** -0.25)
            return False, h * fac
        # accepted
        X1, W1 = y1[:nX].copy(), y1[nX:].copy()
        q1, V1 = self.prob.state_at(X1, W1)
        self.dense = RadauDense(self, t, h, Z)
        recompute = n_iter > 2 and rate is not None and rate > 1e-3
        if self._err_old is None or self._h_old is None or en == 0.0:
            mult = 1.0
        else:
            mult = h / self._h_old * (self._err_old / en) ** 0.25
        fac = min(1.0, mult) * (en ** -0.25 if en > 0.0 else self.MAX_FACTOR)
        fac = min(self.MAX_FACTOR, safety * fac)
        if self._rejected:
            fac = min(fac, 1.0)                 # no growth right after a rejection (RADAU5's rule)
        if not recompute and fac < 1.2:
            fac = 1.0                           # keep the factors
        self._h_old, self._err_old = h, en
        self._rejected = False
        self.finish(t + h, q1, V1, W1)
        if recompute:
            self.J = None                       # a fresh Jacobian at the next step's start
        self._jac_current = False
        return True, h * fac


def model_jacobian(prob, kin, q, V, W, f0, t, sparse_kw=False):
    """∂F/∂y at y = (0, W) of the local ODE (step start: q = q_k, V, W its velocities, f0 =
    F there), from the model's M, C_t = -∂Q/∂V and K_t = ∂(M V̇ - Q)/∂z
    (``iteration_matrix``; z = (δθ body, δr inertial) increments of SO(3)xR³), for an
    unconstrained model, where δV̇ = -M⁻¹ (K_t δz + C_t δV). A body's local increment δX moves
    it by ξ = dψ_0 δX (body frame). SO(3)xR³ and rotation-only bodies, vector and circle
    coordinates: z = ξ, V = W, Ẇ = V̇. SE(3) bodies (W = (ω, u = Rᵀṙ)): z = (ξ_ω, R ξ_v),
    V = (ω, R u) with ∂(R u)/∂ξ_ω = -R ũ, and Ẇ_v = Rᵀ V̇_v - ω × u with ∂/∂ξ_ω = (Rᵀ V̇_v)~,
    ∂/∂ω = ũ, ∂/∂u = -ω~. The kinematic rows at X = 0, both charts (dψ⁻¹_{-X}(W) = S (W +
    ½ [X, W]) + O(X²)): ∂Ẋ/∂W = S (the chart scale), ∂Ẋ_ω/∂X_ω = -½ ω~ and on SE(3) also
    ∂Ẋ_v/∂X_ω = -½ ũ, ∂Ẋ_v/∂X_v = -½ ω~. Dense for small models, scipy.sparse (per-body
    blocks, M by SuperLU) for large ones (``sparse_kw``: the model's iteration_matrix takes
    ``sparse``). tests/core/test_radau.py holds it against differences of F."""
    from ..groups._vec import hat
    m = prob.model
    nX, nv = prob.nX, len(W)
    big = nX + nv > SPARSE_MIN
    quats = prob.start_quats
    kw = {"sparse": big} if sparse_kw else {}
    mats = [m.iteration_matrix(q, V, t, *c, **kw) for c in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))]
    if big:
        from scipy import sparse
        M, Ct, Kt = (sparse.csr_matrix(x) for x in mats)
    else:
        M, Ct, Kt = (x.toarray() if hasattr(x, "toarray") else np.asarray(x, float) for x in mats)
    Vd = prob.model_acceleration(f0[nX:], W, quats)
    parts = {k: [] for k in ("Zx", "Vx", "Ex", "Vw", "Pr", "Ew", "Kx")}
    vec = np.asarray(kin.vector_v, int)
    one = (vec, vec, np.ones(len(vec)))
    parts["Zx"].append(one)
    Rs = iter(kin.rotations(quats))
    se3_rows = np.zeros(nv, bool)

    def add(name, v, B):
        nb, k = v.shape
        parts[name].append((np.broadcast_to(v[:, :, None], (nb, k, k)).ravel(),
                            np.broadcast_to(v[:, None, :], (nb, k, k)).ravel(), B.ravel()))
    for s, dpsi in zip(prob.sets, kin.dpsi):
        v = s.vidx
        nb, k = v.shape
        D0 = dpsi(np.zeros((nb, k)))                             # ξ = dψ_0 δX
        kx = np.zeros((nb, k, k))                                # ∂Ẋ/∂X at X = 0 (X's layout)
        kx[:, :3, :3] = -0.5 * hat(W[s.wang])
        if s.se3:
            kx[:, 3:, :3] = -0.5 * hat(W[s.wlin])
            kx[:, 3:, 3:] = kx[:, :3, :3]
        add("Kx", s.xidx, kx)
        if not s.se3:
            add("Zx", v, D0)
            continue
        se3_rows[v.ravel()] = True
        R = next(Rs)
        w, u = W[s.wang], W[s.wlin]
        blk = np.zeros((nb, 6, 6))
        blk[:, :3, :3] = np.eye(3)
        blk[:, 3:, 3:] = R
        add("Zx", v, blk @ D0)
        add("Vw", v, blk)
        add("Pr", v, np.transpose(blk, (0, 2, 1)))
        blk = np.zeros((nb, 6, 6))
        blk[:, 3:, :3] = -R @ hat(u)
        add("Vx", v, blk @ D0)
        blk = np.zeros((nb, 6, 6))
        blk[:, 3:, :3] = hat(np.einsum("bji,bj->bi", R, Vd[s.wlin]))
        add("Ex", v, blk @ D0)
        blk = np.zeros((nb, 6, 6))
        blk[:, 3:, :3] = hat(u)
        blk[:, 3:, 3:] = -hat(w)
        add("Ew", v, blk)
    plain = np.flatnonzero(~se3_rows)                              # V = W, Ẇ = V̇ there
    for name in ("Vw", "Pr"):
        parts[name].append((plain, plain, np.ones(len(plain))))
    shape = (nv, nv)
    Zx, Vx, Ex, Vw, Pr, Ew = (assemble(shape, parts[k], big) for k in ("Zx", "Vx", "Ex", "Vw", "Pr", "Ew"))
    if big:
        from scipy import sparse
        from scipy.sparse.linalg import splu
        lu = splu(sparse.csc_matrix(M))
        MiK, MiC = (sparse.csr_matrix(lu.solve(x.toarray())) for x in (Kt, Ct))
    else:
        MiK, MiC = np.split(np.linalg.solve(M, np.hstack([Kt, Ct])), 2, axis=1)
    tl = prob.local_index
    JWX = Ex - Pr @ (MiK @ Zx + MiC @ Vx)
    JWW = Ew - Pr @ (MiC @ Vw)
    JXX = assemble((nX, nX), parts["Kx"], big)
    if big:
        from scipy import sparse
        JXW = sparse.csr_matrix((prob.chart_scale, (np.arange(nX), tl)), shape=(nX, nv))
        return sparse.bmat([[JXX, JXW], [sparse.csr_matrix(JWX)[:, tl], JWW]], format="csc")
    J = np.zeros((nX + nv, nX + nv))
    J[:nX, :nX] = JXX
    J[np.arange(nX), nX + tl] = prob.chart_scale
    J[nX:, :nX] = JWX[:, tl]
    J[nX:, nX:] = JWW
    return J


class _Solver:
    """x = A⁻¹ b from A's LAPACK LU factors."""

    def __init__(self, getrs, lu, piv):
        self.getrs, self.lu, self.piv = getrs, lu, piv

    def __call__(self, b):
        return self.getrs(self.lu, self.piv, b)[0]


class RadauDense:
    """The collocation polynomial of one accepted step on (X, W), through τ of the step's
    own base (valid after the stepper has moved on)."""

    def __init__(self, stepper, t, h, Z):
        self.st, self.t0, self.h, self.t1 = stepper, t, h, t + h
        self.nX, self.W0 = stepper.nX, stepper.W
        self.coef = P.T @ Z                     # (3, n): Z(θ) = Σ_k θ^(k+1) coef[k]
        self.base = stepper.prob.snapshot()

    def local(self, th):
        """(X, W) at the step fractions ``th`` (array): rows of [X, W]."""
        th = np.asarray(th, float)[:, None]
        Zt = th * (self.coef[0] + th * (self.coef[1] + th * self.coef[2]))
        Zt[:, self.nX:] += self.W0
        return Zt

    def __call__(self, t):
        y = self.local([(t - self.t0) / self.h])[0]
        with self.st.prob.based_at(self.base) as prob:
            return prob.state_at(y[:self.nX], y[self.nX:])

    def many(self, ts):
        """Rows of (Q, V) at the times ``ts``: the polynomial (weights θ, θ², θ³) and τ of
        the step's base in one call (:meth:`LocalProblem.dense_states`)."""
        th = (np.asarray(ts, float) - self.t0) / self.h
        w = np.cumprod(np.repeat(th[:, None], 3, axis=1), axis=1)
        c, nX = self.coef, self.nX
        return self.st.prob.dense_states(w, c[:, :nX], c[:, nX:], self.W0, self.base)
