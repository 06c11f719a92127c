"""Compiled sparse constraint rows and index-1 solve of :class:`lgt_exudyn.ExudynModel`
(numba; imported only when used), on the structure of :mod:`.sparse`:

* :func:`joint_rows` (T, q, V, J, Jf, aval, gam): A's values (in its CSR pattern) and γ of
  spherical joints in closed form — the row of axis a is e_aᵀ(v₁ - v₀), v = ṙ + R(ω × b) the
  velocity of a marker at b on a node (ω body-fixed), so ∂/∂ṙ = ±e_aᵀ, ∂/∂ω = ∓(ũ R)[a]
  with u = R b, and γ = d/dt(A V)|_V = ±e_aᵀ R(ω × (ω × b)) summed over the two markers;
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
from numba import njit

from lgt_bridge.kernels import guard_cache, linalg
from lgt_bridge.kernels.linalg import envelope_cholesky, envelope_solve
from lgt_bridge.kernels.rotations import to_quat

from . import kernel_tables
from .kernel_solve import PIVOT_TOL
from .kernel_tables import CODE, FOFF, MEMBER, NROT, NV_, OMBI, OMIQ, RCOMP, RMEMBER, ROT, SIZE, START, TWIST
from .sparse import (ACOL, APTR, COMPOF, ESTART, FIRST, LAM, PERM, POSIN, RHS, SENV, SIDX, SPTR, XS, YCOL, YPTR,
                     YVAL)

guard_cache(__file__, extra=(linalg.__file__, kernel_tables.__file__))

_V = "float64[::1]"
_M = "float64[:, ::1]"
_I = "int64[::1]"
_T = "int64[:, ::1]"


@njit(f"void({_T}, {_V}, {_V}, {_T}, {_M}, {_V}, {_V})", cache=True, error_model="numpy")
def joint_rows(T, q, V, J, Jf, aval, gam):
    """A's values in its pattern (per row: ω then ṙ of marker 0's node, then of marker 1's,
    ground sides left out) and γ, of spherical-joint rows J (T rows of the markers' nodes or
    -1, axis) with the markers' local positions Jf, at (q, V)."""
    p = 0
    for i in range(J.shape[0]):
        ax = J[i, 2]
        g_sum = 0.0
        for side in range(2):
            g = J[i, side]
            if g < 0:
                continue
            sg = 1.0 if side == 1 else -1.0
            r3 = q[T[g, ROT + 3]] if T[g, NROT] == 4 else 0.0
            p0, p1, p2, p3 = to_quat(T[g, CODE], q[T[g, ROT]], q[T[g, ROT + 1]], q[T[g, ROT + 2]], r3)
            R00, R01, R02 = 1.0 - 2.0 * (p2 * p2 + p3 * p3), 2.0 * (p1 * p2 - p0 * p3), 2.0 * (p1 * p3 + p0 * p2)
            R10, R11, R12 = 2.0 * (p1 * p2 + p0 * p3), 1.0 - 2.0 * (p1 * p1 + p3 * p3), 2.0 * (p2 * p3 - p0 * p1)
            R20, R21, R22 = 2.0 * (p1 * p3 - p0 * p2), 2.0 * (p2 * p3 + p0 * p1), 1.0 - 2.0 * (p1 * p1 + p2 * p2)
            b0, b1, b2 = Jf[i, 3 * side], Jf[i, 3 * side + 1], Jf[i, 3 * side + 2]
            u0 = R00 * b0 + R01 * b1 + R02 * b2
            u1 = R10 * b0 + R11 * b1 + R12 * b2
            u2 = R20 * b0 + R21 * b1 + R22 * b2
            # row ax of ũ: (ũ R)[ax, k] = t · R[:, k]
            if ax == 0:
                t0, t1, t2 = 0.0, -u2, u1
                ra0, ra1, ra2 = R00, R01, R02
            elif ax == 1:
                t0, t1, t2 = u2, 0.0, -u0
                ra0, ra1, ra2 = R10, R11, R12
            else:
                t0, t1, t2 = -u1, u0, 0.0
                ra0, ra1, ra2 = R20, R21, R22
            aval[p] = -sg * (t0 * R00 + t1 * R10 + t2 * R20)
            aval[p + 1] = -sg * (t0 * R01 + t1 * R11 + t2 * R21)
            aval[p + 2] = -sg * (t0 * R02 + t1 * R12 + t2 * R22)
            for k in range(3):
                aval[p + 3 + k] = sg if k == ax else 0.0
            iv = T[g, TWIST]
            w0, w1, w2 = V[iv], V[iv + 1], V[iv + 2]
            c0, c1, c2 = w1 * b2 - w2 * b1, w2 * b0 - w0 * b2, w0 * b1 - w1 * b0
            d0, d1, d2 = w1 * c2 - w2 * c1, w2 * c0 - w0 * c2, w0 * c1 - w1 * c0
            g_sum += sg * (ra0 * d0 + ra1 * d1 + ra2 * d2)
            p += 6
        gam[i] = g_sum


@njit(cache=True, error_model="numpy")
def _factor(T, off, w, I, io, F, fo, aval):
    """Y = M̄⁻¹Aᵀ on its pattern and the envelope Cholesky factor of S = A M̄⁻¹ Aᵀ (rows
    permuted) into F; True when it is well positive definite (PIVOT_TOL)."""
    aptr, acol = I[io[APTR]:io[APTR + 1]], I[io[ACOL]:io[ACOL + 1]]
    yptr, ycol = I[io[YPTR]:io[YPTR + 1]], I[io[YCOL]:io[YCOL + 1]]
    perm, sptr, sidx = I[io[PERM]:io[PERM + 1]], I[io[SPTR]:io[SPTR + 1]], I[io[SIDX]:io[SIDX + 1]]
    first, estart = I[io[FIRST]:io[FIRST + 1]], I[io[ESTART]:io[ESTART + 1]]
    comp_of, pos_in = I[io[COMPOF]:io[COMPOF + 1]], I[io[POSIN]:io[POSIN + 1]]
    yval, S, x = F[fo[YVAL]:fo[YVAL + 1]], F[fo[SENV]:fo[SENV + 1]], F[fo[XS]:fo[XS + 1]]
    nc, mem = perm.shape[0], off[RMEMBER]
    if aval.shape[0] != acol.shape[0] or x.shape[0] != off[NV_] or off[RMEMBER] == off[RCOMP]:
        raise ValueError("sparse solve: aval needs the pattern's entries; M̄ packed")
    for k in range(nc):                                 # Y_k = M̄⁻¹ A_kᵀ on its pattern
        for e in range(aptr[k], aptr[k + 1]):
            x[acol[e]] += aval[e]
        for e in range(yptr[k], yptr[k + 1]):
            j = ycol[e]
            c = comp_of[j]
            a, n = T[c, START], T[c, SIZE]
            base = off[OMBI] + T[c, FOFF] + n * pos_in[j]
            s = 0.0
            for jj in range(n):
                s += w[base + jj] * x[T[mem + a + jj, MEMBER]]
            yval[e] = s
        for e in range(aptr[k], aptr[k + 1]):
            x[acol[e]] = 0.0
    for p in range(nc):                                 # S (permuted) in its envelope
        i = perm[p]
        for e in range(aptr[i], aptr[i + 1]):
            x[acol[e]] += aval[e]
        si = estart[p] - first[p]
        for e in range(estart[p], estart[p + 1]):
            S[e] = 0.0
        for u in range(sptr[p], sptr[p + 1]):
            pk = sidx[u]
            k = perm[pk]
            s = 0.0
            for e in range(yptr[k], yptr[k + 1]):
                s += x[ycol[e]] * yval[e]
            S[si + pk] = s
        for e in range(aptr[i], aptr[i + 1]):
            x[acol[e]] = 0.0
    ok, dmin, dmax = envelope_cholesky(S, first, estart)
    return ok and dmin > PIVOT_TOL * dmax


@njit(cache=True, error_model="numpy")
def _back(I, io, F, fo, out):
    """λ = S⁻¹ rhs (rhs permuted, in F) into F's LAM in the rows' order; out -= Y λ."""
    yptr, ycol = I[io[YPTR]:io[YPTR + 1]], I[io[YCOL]:io[YCOL + 1]]
    perm, first, estart = I[io[PERM]:io[PERM + 1]], I[io[FIRST]:io[FIRST + 1]], I[io[ESTART]:io[ESTART + 1]]
    yval, S = F[fo[YVAL]:fo[YVAL + 1]], F[fo[SENV]:fo[SENV + 1]]
    rhs, lam = F[fo[RHS]:fo[RHS + 1]], F[fo[LAM]:fo[LAM + 1]]
    envelope_solve(S, first, estart, rhs)
    for p in range(perm.shape[0]):
        k = perm[p]
        lk = rhs[p]
        lam[k] = lk
        for e in range(yptr[k], yptr[k + 1]):
            out[ycol[e]] -= yval[e] * lk


@njit(cache=True, error_model="numpy")
def _miq(T, off, w, Qbar):
    """M̄⁻¹Q̄ block by block into w[OMIQ:]; returns OMIQ's offset."""
    mem, wm = off[RMEMBER], off[OMIQ]
    for c in range(off[RCOMP], off[RMEMBER]):
        a, n = T[c, START], T[c, SIZE]
        base = off[OMBI] + T[c, FOFF]
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += w[base + n * i + j] * Qbar[T[mem + a + j, MEMBER]]
            w[wm + T[mem + a + i, MEMBER]] = s
    return wm


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
    if not _factor(T, off, w, I, io, F, fo, aval):
        _miq(T, off, w, Qbar)
        return 1
    wm = _miq(T, off, w, Qbar)
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
    if not _factor(T, off, w, I, io, F, fo, aval):
        return 1
    for p in range(perm.shape[0]):
        rhs[p] = r[perm[p]]
    for j in range(out.shape[0]):
        out[j] = 0.0
    _back(I, io, F, fo, out)
    for j in range(out.shape[0]):
        out[j] = -out[j]
    return 0
