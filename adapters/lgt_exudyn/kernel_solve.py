"""Compiled index-1 solve of :class:`lgt_exudyn.ExudynModel` (numba; imported only when
used): V̇ from the twist mass matrix M̄, the forces Q̄ and the constraint rows (A, γ), on the
tables of :mod:`.kernel_tables` and the core's Cholesky (:mod:`lgt_bridge.kernels.linalg`).

* :func:`solve` (T, off, w, Mbar, A, Qbar, gam, Vd) -> flag: V̇ = M̄⁻¹(Q̄ - Aᵀλ),
  (A M̄⁻¹ Aᵀ) λ = A M̄⁻¹ Q̄ + γ (so A V̇ = -γ; ``solve_kkt(M̄, A, Q̄, -γ)``); M̄⁻¹ from the
  packed diagonal blocks of the constant M̄ (Mbar 0 x 0) or an Mbar factorized here within its
  row envelope (:func:`row_envelope`: a block-diagonal M̄ costs its blocks).
  Flags: 0 done; 1 the Schur complement is not (well) positive definite (redundant
  constraints): w holds A M̄⁻¹ Aᵀ, its right-hand side, M̄⁻¹ Q̄ and M̄⁻¹ Aᵀ, finish with
  :func:`.kernels.solve_fallback`; 2 Mbar is not positive definite.
* :func:`free_rhs` (T, off, w, q, V, Q, Qbar, Vd): :func:`.kernel_maps.forces` then
  :func:`solve` for an unconstrained model with a constant M̄ (one call instead of two).

The numpy reference is ``lgt_bridge.model.solve_kkt``. Plain loops: ``NUMBA_DISABLE_JIT=1``
runs the same source interpreted.
"""
import math

import numpy as np
from numba import njit

from lgt_bridge.kernels import guard_cache, linalg
from lgt_bridge.kernels.linalg import cholesky, cholesky_solve
from lgt_bridge.model import SCHUR_RCOND

from . import kernel_maps
from .kernel_maps import forces
from .kernel_tables import (FOFF, MEMBER, NC_, NV_, ODM, OL, OMBI, OMIQ, OR, OS, OT, OY, OZ, RCOMP, RMEMBER,
                            RSCRATCH, SIZE, START)

guard_cache(__file__, extra=(linalg.__file__, kernel_maps.__file__))

#: the Schur complement's Cholesky factor counts as singular below this relative pivot
#: (as lgt_bridge.model.solve_schur)
PIVOT_TOL = math.sqrt(SCHUR_RCOND)

_V = "float64[::1]"
_M = "float64[:, ::1]"
_I = "int64[::1]"
_T = "int64[:, ::1]"


@njit(cache=True, error_model="numpy")
def block_miq(T, off, w, Qbar):
    """M̄⁻¹Q̄ block by block (the constant M̄'s packed diagonal blocks' inverses) into
    w[OMIQ:]; returns OMIQ's offset. Used by this module's and :mod:`.kernel_sparse`'s solves."""
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


@njit(cache=True, error_model="numpy")
def _schur_blocks(T, off, w, A, Qbar):
    """With the constant M̄'s diagonal blocks: M̄⁻¹Q̄ into w[OMIQ:] (:func:`block_miq`),
    Y = M̄⁻¹Aᵀ (transposed) into w[OY:] and the lower triangle of S = A M̄⁻¹ Aᵀ into w[OS:]
    (rows of A multiplied only on the blocks they touch)."""
    nv, nc = off[NV_], A.shape[0]
    wy, ws = off[OY], off[OS]
    mem, touch = off[RMEMBER], off[RSCRATCH]
    block_miq(T, off, w, Qbar)
    for c in range(off[RCOMP], off[RMEMBER]):
        a, n = T[c, START], T[c, SIZE]
        base = off[OMBI] + T[c, FOFF]
        # rows of A touching this block: Y[k, block] = M̄_c⁻¹ A[k, block], S += A Y on them
        nt = 0
        for k in range(nc):
            nz = False
            for j in range(n):
                if A[k, T[mem + a + j, MEMBER]] != 0.0:
                    nz = True
                    break
            if nz:
                T[touch + nt, 0] = k
                nt += 1
            else:
                for j in range(n):
                    w[wy + nv * k + T[mem + a + j, MEMBER]] = 0.0
        for u in range(nt):
            k = T[touch + u, 0]
            for i in range(n):
                s = 0.0
                for j in range(n):
                    s += w[base + n * i + j] * A[k, T[mem + a + j, MEMBER]]
                w[wy + nv * k + T[mem + a + i, MEMBER]] = s
        for u in range(nt):
            i = T[touch + u, 0]
            for v in range(u + 1):       # the touch list runs in row order: i ≥ k
                k = T[touch + v, 0]
                s = 0.0
                for j in range(n):
                    m = T[mem + a + j, MEMBER]
                    s += A[i, m] * w[wy + nv * k + m]
                w[ws + nc * i + k] += s


@njit(cache=True, error_model="numpy")
def row_envelope(Mbar):
    """The row envelope of the lower triangle of Mbar (n x n): first[i] the first nonzero
    column of row i (i for a row with only its diagonal), as :func:`lgt_bridge.kernels.linalg.cholesky`
    reads it."""
    n = Mbar.shape[0]
    first = np.empty(n, np.int64)
    for i in range(n):
        f = i
        for j in range(i):
            if Mbar[i, j] != 0.0:
                f = j
                break
        first[i] = f
    return first


@njit(f"int64({_T}, {_I}, {_V}, {_M}, {_M}, {_V}, {_V}, {_V})", cache=True, error_model="numpy")
def solve(T, off, w, Mbar, A, Qbar, gam, Vd):
    """V̇ = M̄⁻¹(Q̄ - Aᵀλ), (A M̄⁻¹ Aᵀ) λ = A M̄⁻¹ Q̄ + γ (A V̇ = -γ, as
    ``solve_kkt(M̄, A, Q̄, -γ)``); A may have 0 rows (V̇ = M̄⁻¹ Q̄).

    Mbar with 0 rows: M̄⁻¹ from the packed diagonal blocks of the constant M̄; else Mbar
    (nv x nv) is factorized here. Returns 0; 1 when the Cholesky factor of A M̄⁻¹ Aᵀ has a
    non-positive or relatively small (PIVOT_TOL) pivot — finish with ``solve_fallback``;
    2 when Mbar is not positive definite."""
    nv, nc = off[NV_], A.shape[0]
    const = Mbar.shape[0] == 0
    if (A.shape[1] != nv or Qbar.shape[0] != nv or Vd.shape[0] != nv or gam.shape[0] != nc
            or nc > off[NC_] or nc > nv):
        raise ValueError("solve: A must be nc x nv with nc ≤ the packed nc_max, Qbar and Vd nv, gam nc")
    if const and off[RMEMBER] == off[RCOMP] and nv > 0:
        raise ValueError("solve: no constant mass matrix packed; pass M̄")
    if not const and (Mbar.shape[0] != nv or Mbar.shape[1] != nv or off[OZ] - off[ODM] != nv * nv):
        raise ValueError("solve: Mbar must be nv x nv, and the model packed without a constant M̄")
    wm, wy, ws, wr = off[OMIQ], off[OY], off[OS], off[OR]
    dense = off[0:0]                        # an empty envelope: dense factors
    for i in range(nc * nc):
        w[ws + i] = 0.0
    if const:
        _schur_blocks(T, off, w, A, Qbar)
    else:
        L = w[off[ODM]:off[ODM] + nv * nv]
        for i in range(nv):                 # M̄ into its factor's place, factorized there
            for j in range(nv):
                L[nv * i + j] = Mbar[i, j]
        # within M̄'s row envelope: the same factor (the entries left of it stay exact zeros),
        # the work of its blocks (a kinematic tree next to point masses: 6 x 6 and diagonal)
        env = row_envelope(Mbar)
        if not cholesky(L, nv, env)[0]:
            return 2
        for j in range(nv):
            w[wm + j] = Qbar[j]
        cholesky_solve(L, nv, env, w[wm:wm + nv])
        for k in range(nc):
            y = w[wy + nv * k:wy + nv * (k + 1)]
            for j in range(nv):
                y[j] = A[k, j]
            cholesky_solve(L, nv, env, y)
        for i in range(nc):
            for k in range(i + 1):
                s = 0.0
                for j in range(nv):
                    s += A[i, j] * w[wy + nv * k + j]
                w[ws + nc * i + k] = s
    if nc == 0:
        for j in range(nv):
            Vd[j] = w[wm + j]
        return 0
    L = w[off[OL]:off[OL] + nc * nc]
    for i in range(nc):
        for k in range(i):
            w[ws + nc * k + i] = w[ws + nc * i + k]
        for k in range(i + 1):             # the factor reads the lower triangle
            L[nc * i + k] = w[ws + nc * i + k]
        s = 0.0
        for j in range(nv):
            s += A[i, j] * w[wm + j]
        w[wr + i] = s + gam[i]
    ok, dmin, dmax = cholesky(L, nc, dense)
    if not ok or not dmin > PIVOT_TOL * dmax:
        return 1
    lam = w[off[OT]:off[OT] + nc]           # λ in the scratch (≥ nv ≥ nc entries)
    for i in range(nc):
        lam[i] = w[wr + i]
    cholesky_solve(L, nc, dense, lam)
    for j in range(nv):
        Vd[j] = w[wm + j]
    for k in range(nc):
        lk = lam[k]
        if lk != 0.0:
            for j in range(nv):
                Vd[j] -= w[wy + nv * k + j] * lk
    return 0


@njit(f"void({_T}, {_I}, {_V}, {_V}, {_V}, {_V}, {_V}, {_V})", cache=True, error_model="numpy")
def free_rhs(T, off, w, q, V, Q, Qbar, Vd):
    """:func:`.kernel_maps.forces` and :func:`solve` of an unconstrained model with its
    constant M̄ packed, in one call: Q̄ from Exudyn's residual Q, then V̇ = M̄⁻¹ Q̄ into Vd."""
    none = np.zeros((0, 0))
    forces(T, off, w, q, V, Q, none, Qbar, none)
    solve(T, off, w, none, np.zeros((0, off[NV_])), Qbar, np.zeros(0), Vd)
