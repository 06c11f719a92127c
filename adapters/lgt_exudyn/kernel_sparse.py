"""Compiled sparse constraint rows and index-1 solve of :class:`lgt_exudyn.ExudynModel`
(numba; imported only when used), on the structure of :mod:`.sparse`:

* :func:`joint_rows` (T, q, V, J, Jf, aval, gam): A's values (in its CSR pattern) and γ of
  joint rows in closed form. Every row of the joints :mod:`.sparse` knows is g = u·w with
  u = R₀a (or a fixed axis) and w = p₁ - p₀ (TRANSLATION: p = r + R b a marker's point) or
  w = R₁b (ROTATION); with ω body-fixed, d/dt(R b) = R(ω × b), so y·R(ω × b) = ω·(b × Rᵀy)
  gives ∂/∂ω and ∂/∂ṙ = ±u, and γ = d/dt(A V)|_V = ü·w + 2 u̇·ẇ + u·ẅ at constant V;
* :func:`sparse_solve` (T, off, w, I, io, F, fo, aval, Qbar, gam, Vd) -> flag: V̇ =
  M̄⁻¹(Q̄ - Aᵀλ), (A M̄⁻¹ Aᵀ) λ = A M̄⁻¹ Q̄ + γ, as :func:`.kernel_solve.solve` but with A
  sparse (CSR), M̄⁻¹Aᵀ on its pattern, and S = A M̄⁻¹ Aᵀ in the rows' reverse Cuthill–McKee
  order factorized in its envelope (:func:`lgt_bridge.kernels.linalg.envelope_cholesky`);
  work in proportion to the nonzeros of A, S and L. Flags as ``solve``'s (1: finish with
  :func:`.kernels.sparse_fallback`); λ stays in F's LAM section, in the model's row order;
* :func:`sparse_correction` (T, off, w, I, io, F, fo, aval, r, out) -> flag: out =
  M̄⁻¹Aᵀ(A M̄⁻¹ Aᵀ)⁻¹ r, the projections' step on the same structure.

The numpy references are Exudyn's dense Jacobian mapped to twists (C_q H), the γ
differences of :mod:`.constraints` and ``lgt_bridge.model.solve_kkt``;
tests/test_exudyn_sparse.py holds them equal. Plain loops: ``NUMBA_DISABLE_JIT=1`` runs the
same source interpreted.
"""
import numpy as np
from numba import njit

from lgt_bridge.kernels import guard_cache, linalg
from lgt_bridge.kernels.linalg import envelope_cholesky, envelope_solve
from lgt_bridge.kernels.rotations import to_quat

from . import kernel_tables
from . import kernel_solve
from .kernel_solve import PIVOT_TOL, block_miq
from .kernel_tables import CODE, NROT, NV_, POS, ROT, TWIST
from .sparse import (ACOL, APTR, BOFF, BPTR, BSLOT, ESTART, FIRST, LAM, MDIAG, MINV, MOFF, MSIZE, PA, PB, PERM, PN, PPTR,
                     RHS, SENV, SIDX, SPTR, YVAL)

guard_cache(__file__, extra=(linalg.__file__, kernel_tables.__file__, kernel_solve.__file__))

_V = "float64[::1]"
_M = "float64[:, ::1]"
_I = "int64[::1]"
_T = "int64[:, ::1]"


@njit(cache=True, error_model="numpy")
def _rotation(T, q, g, R):
    """R[g] = the rotation matrix of the node in T's row g."""
    r3 = q[T[g, ROT + 3]] if T[g, NROT] == 4 else 0.0
    p0, p1, p2, p3 = to_quat(T[g, CODE], q[T[g, ROT]], q[T[g, ROT + 1]], q[T[g, ROT + 2]], r3)
    R[g, 0, 0], R[g, 0, 1], R[g, 0, 2] = 1.0 - 2.0 * (p2 * p2 + p3 * p3), 2.0 * (p1 * p2 - p0 * p3), 2.0 * (p1 * p3 + p0 * p2)
    R[g, 1, 0], R[g, 1, 1], R[g, 1, 2] = 2.0 * (p1 * p2 + p0 * p3), 1.0 - 2.0 * (p1 * p1 + p3 * p3), 2.0 * (p2 * p3 - p0 * p1)
    R[g, 2, 0], R[g, 2, 1], R[g, 2, 2] = 2.0 * (p1 * p3 - p0 * p2), 2.0 * (p2 * p3 + p0 * p1), 1.0 - 2.0 * (p1 * p1 + p2 * p2)


@njit(cache=True, error_model="numpy")
def _vector(R, g, V, iv, Jf, i, c, x):
    """The world vector of the local vector Jf[i, c:c+3] on node g (R[g], ω = V[iv:iv+3]) and
    its first two time derivatives at constant ω: x[0] = R b, x[1] = R(ω × b), x[2] =
    R(ω × (ω × b)); the vector itself (and zeros) when g < 0 (the ground)."""
    b0, b1, b2 = Jf[i, c], Jf[i, c + 1], Jf[i, c + 2]
    if g < 0:
        x[0, 0], x[0, 1], x[0, 2] = b0, b1, b2
        for k in range(3):
            x[1, k] = 0.0
            x[2, k] = 0.0
        return
    w0, w1, w2 = V[iv], V[iv + 1], V[iv + 2]
    c0, c1, c2 = w1 * b2 - w2 * b1, w2 * b0 - w0 * b2, w0 * b1 - w1 * b0
    d0, d1, d2 = w1 * c2 - w2 * c1, w2 * c0 - w0 * c2, w0 * c1 - w1 * c0
    for k in range(3):
        x[0, k] = R[g, k, 0] * b0 + R[g, k, 1] * b1 + R[g, k, 2] * b2
        x[1, k] = R[g, k, 0] * c0 + R[g, k, 1] * c1 + R[g, k, 2] * c2
        x[2, k] = R[g, k, 0] * d0 + R[g, k, 1] * d1 + R[g, k, 2] * d2


@njit(cache=True, error_model="numpy")
def _omega_cols(R, g, Jf, i, c, y, aval, p, scale):
    """aval[p:p+3] += scale * (b × Rᵀy), b = Jf[i, c:c+3] (∂/∂ω of y·R(ω × b))."""
    b0, b1, b2 = Jf[i, c], Jf[i, c + 1], Jf[i, c + 2]
    z0 = R[g, 0, 0] * y[0] + R[g, 1, 0] * y[1] + R[g, 2, 0] * y[2]
    z1 = R[g, 0, 1] * y[0] + R[g, 1, 1] * y[1] + R[g, 2, 1] * y[2]
    z2 = R[g, 0, 2] * y[0] + R[g, 1, 2] * y[1] + R[g, 2, 2] * y[2]
    aval[p] += scale * (b1 * z2 - b2 * z1)
    aval[p + 1] += scale * (b2 * z0 - b0 * z2)
    aval[p + 2] += scale * (b0 * z1 - b1 * z0)


@njit(f"void({_T}, {_V}, {_V}, {_T}, {_M}, {_V}, {_V})", cache=True, error_model="numpy")
def joint_rows(T, q, V, J, Jf, aval, gam):
    """A's values in its pattern (per row: ω then ṙ of marker 0's node, then of marker 1's,
    ground sides left out) and γ of the joint rows J = (T rows of the markers' nodes or -1,
    kind, T row of the node u turns with or -1), Jf = (marker 0's position, marker 1's
    position or b, a) (:func:`.sparse.joint_rows`), at (q, V). With p = r + R b the markers'
    points and u = R₀a, w = R₁b: TRANSLATION rows g = u·(p₁ - p₀), ROTATION rows g = u·w;
    γ = ü·w + 2 u̇·ẇ + u·ẅ at constant V (w = p₁ - p₀ on TRANSLATION rows)."""
    R = np.empty((T.shape[0], 3, 3))
    done = np.zeros(T.shape[0], np.bool_)
    x0, x1, xu = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    w, wd, wdd = np.empty(3), np.empty(3), np.empty(3)
    p, last = 0, -1
    for i in range(J.shape[0]):
        g0, g1, kind, gu = J[i, 0], J[i, 1], J[i, 2], J[i, 3]
        for g in (g0, g1):
            if g >= 0 and not done[g]:
                _rotation(T, q, g, R)
                done[g] = True
        iv0 = T[g0, TWIST] if g0 >= 0 else 0
        iv1 = T[g1, TWIST] if g1 >= 0 else 0
        _vector(R, gu, V, iv0, Jf, i, 6, xu)                   # u, u̇, ü
        same = kind == 0 and last >= 0 and J[last, 0] == g0 and J[last, 1] == g1
        for k in range(6):
            same = same and Jf[last, k] == Jf[i, k]
        if kind == 0 and not same:                          # w = p₁ - p₀ (kept for the joint's next rows)
            last = i
            _vector(R, g0, V, iv0, Jf, i, 0, x0)
            _vector(R, g1, V, iv1, Jf, i, 3, x1)
            for k in range(3):
                r0 = q[T[g0, POS + k]] if g0 >= 0 else 0.0
                r1 = q[T[g1, POS + k]] if g1 >= 0 else 0.0
                v0 = V[iv0 + 3 + k] if g0 >= 0 else 0.0
                v1 = V[iv1 + 3 + k] if g1 >= 0 else 0.0
                w[k] = r1 + x1[0, k] - r0 - x0[0, k]
                wd[k] = v1 + x1[1, k] - v0 - x0[1, k]
                wdd[k] = x1[2, k] - x0[2, k]
        elif kind == 1:                                     # w = R₁b
            last = -1
            _vector(R, g1, V, iv1, Jf, i, 3, x1)
            for k in range(3):
                w[k], wd[k], wdd[k] = x1[0, k], x1[1, k], x1[2, k]
        s = 0.0
        for k in range(3):
            s += xu[2, k] * w[k] + 2.0 * xu[1, k] * wd[k] + xu[0, k] * wdd[k]
        gam[i] = s
        u = xu[0]
        for side in range(2):
            g = g0 if side == 0 else g1
            if g < 0:
                continue
            for k in range(6):
                aval[p + k] = 0.0
            if kind == 0:                                   # u·(ṙ + R(ω × b)), signed
                sg = 1.0 if side == 1 else -1.0
                _omega_cols(R, g, Jf, i, 3 * side, u, aval, p, sg)
                for k in range(3):
                    aval[p + 3 + k] = sg * u[k]
                if side == 0 and gu >= 0:                   # u̇·w = (R₀(ω₀ × a))·w
                    _omega_cols(R, gu, Jf, i, 6, w, aval, p, 1.0)
            elif side == 0:                                 # (R₀(ω₀ × a))·w
                _omega_cols(R, g, Jf, i, 6, w, aval, p, 1.0)
            else:                                           # u·R₁(ω₁ × b)
                _omega_cols(R, g, Jf, i, 3, u, aval, p, 1.0)
            p += 6


@njit(cache=True, error_model="numpy")
def _factor(I, io, F, fo, aval):
    """Y = M̄⁻¹Aᵀ (slot block by slot block) and the envelope Cholesky factor of
    S = A M̄⁻¹ Aᵀ (rows permuted) into F; True when it is well positive definite (PIVOT_TOL)."""
    bptr, boff, bslot = I[io[BPTR]:io[BPTR + 1]], I[io[BOFF]:io[BOFF + 1]], I[io[BSLOT]:io[BSLOT + 1]]
    sptr, sidx, pptr = I[io[SPTR]:io[SPTR + 1]], I[io[SIDX]:io[SIDX + 1]], I[io[PPTR]:io[PPTR + 1]]
    pa, pb, pn = I[io[PA]:io[PA + 1]], I[io[PB]:io[PB + 1]], I[io[PN]:io[PN + 1]]
    first, estart = I[io[FIRST]:io[FIRST + 1]], I[io[ESTART]:io[ESTART + 1]]
    moff, msize, mdiag = I[io[MOFF]:io[MOFF + 1]], I[io[MSIZE]:io[MSIZE + 1]], I[io[MDIAG]:io[MDIAG + 1]]
    yval, S, minv = F[fo[YVAL]:fo[YVAL + 1]], F[fo[SENV]:fo[SENV + 1]], F[fo[MINV]:fo[MINV + 1]]
    nc = first.shape[0]
    if aval.shape[0] != yval.shape[0]:
        raise ValueError("sparse solve: aval needs the pattern's entries")
    for b in range(bptr[nc]):                           # Y's blocks: M̄⁻¹ of the slot times A's
        o, m, n = boff[b], moff[bslot[b]], msize[bslot[b]]
        if mdiag[bslot[b]]:
            for r in range(n):
                yval[o + r] = minv[m + r] * aval[o + r]
            continue
        for r in range(n):
            t = 0.0
            for c in range(n):
                t += minv[m + n * r + c] * aval[o + c]
            yval[o + r] = t
    for p in range(nc):                                 # S (permuted) in its envelope
        si = estart[p] - first[p]
        for e in range(estart[p], estart[p + 1]):
            S[e] = 0.0
        for u in range(sptr[p], sptr[p + 1]):
            t = 0.0
            for v in range(pptr[u], pptr[u + 1]):       # the slots the two rows share
                x, y = pa[v], pb[v]
                for r in range(pn[v]):
                    t += aval[x + r] * yval[y + r]
            S[si + sidx[u]] = t
    ok, dmin, dmax = envelope_cholesky(S, first, estart)
    return ok and dmin > PIVOT_TOL * dmax


@njit(cache=True, error_model="numpy")
def _back(I, io, F, fo, out):
    """λ = S⁻¹ rhs (rhs permuted, in F) into F's LAM in the rows' order; out -= Y λ."""
    aptr, acol = I[io[APTR]:io[APTR + 1]], I[io[ACOL]:io[ACOL + 1]]
    perm, first, estart = I[io[PERM]:io[PERM + 1]], I[io[FIRST]:io[FIRST + 1]], I[io[ESTART]:io[ESTART + 1]]
    yval, S = F[fo[YVAL]:fo[YVAL + 1]], F[fo[SENV]:fo[SENV + 1]]
    rhs, lam = F[fo[RHS]:fo[RHS + 1]], F[fo[LAM]:fo[LAM + 1]]
    envelope_solve(S, first, estart, rhs)
    for p in range(perm.shape[0]):
        k = perm[p]
        lk = rhs[p]
        lam[k] = lk
        for e in range(aptr[k], aptr[k + 1]):
            out[acol[e]] -= yval[e] * lk


@njit(f"int64({_T}, {_I}, {_V}, {_I}, {_I}, {_V}, {_I}, {_V}, {_V}, {_V}, {_V})", cache=True,
      error_model="numpy")
def sparse_solve(T, off, w, I, io, F, fo, aval, Qbar, gam, Vd):
    """V̇ = M̄⁻¹(Q̄ - Aᵀλ), (A M̄⁻¹ Aᵀ) λ = A M̄⁻¹ Q̄ + γ with A in CSR (values ``aval``) and
    the constant M̄'s diagonal blocks packed. Returns 0; 1 when the envelope Cholesky factor
    of S has a non-positive or relatively small (PIVOT_TOL) pivot; M̄⁻¹Q̄ is then in
    w[OMIQ:] and A's values in ``aval`` (finish with ``sparse_fallback``)."""
    nv = off[NV_]
    aptr, acol = I[io[APTR]:io[APTR + 1]], I[io[ACOL]:io[ACOL + 1]]
    perm, rhs = I[io[PERM]:io[PERM + 1]], F[fo[RHS]:fo[RHS + 1]]
    nc = perm.shape[0]
    if Qbar.shape[0] != nv or Vd.shape[0] != nv or gam.shape[0] != nc:
        raise ValueError("sparse_solve: Qbar, Vd need nv entries, gam nc")
    if not _factor(I, io, F, fo, aval):
        block_miq(T, off, w, Qbar)
        return 1
    wm = block_miq(T, off, w, Qbar)
    for p in range(nc):
        i = perm[p]
        s = 0.0
        for e in range(aptr[i], aptr[i + 1]):
            s += aval[e] * w[wm + acol[e]]
        rhs[p] = s + gam[i]
    for j in range(nv):
        Vd[j] = w[wm + j]
    _back(I, io, F, fo, Vd)
    return 0


@njit(f"int64({_T}, {_I}, {_V}, {_I}, {_I}, {_V}, {_I}, {_V}, {_V}, {_V})", cache=True, error_model="numpy")
def sparse_correction(T, off, w, I, io, F, fo, aval, r, out):
    """out = M̄⁻¹Aᵀ (A M̄⁻¹ Aᵀ)⁻¹ r (the M̄-orthogonal correction a projection onto A x = r
    subtracts). Returns 0; 1 as :func:`sparse_solve` (redundant rows: solve densely)."""
    perm, rhs = I[io[PERM]:io[PERM + 1]], F[fo[RHS]:fo[RHS + 1]]
    if r.shape[0] != perm.shape[0] or out.shape[0] != off[NV_]:
        raise ValueError("sparse_correction: r needs nc entries, out nv")
    if not _factor(I, io, F, fo, aval):
        return 1
    for p in range(perm.shape[0]):
        rhs[p] = r[perm[p]]
    for j in range(out.shape[0]):
        out[j] = 0.0
    _back(I, io, F, fo, out)
    for j in range(out.shape[0]):
        out[j] = -out[j]
    return 0
