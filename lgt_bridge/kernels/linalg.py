"""Compiled dense linear algebra shared by the kernels: one Cholesky factorization and its
solve, on flat row-major n x n blocks of a float64 array (a slice of a work array), and the
same on a packed envelope (skyline) storage for large sparse matrices (:func:`envelope_cholesky`).

A symmetric positive definite S may have a row envelope ``first`` (``first[i]``: the first
nonzero column of row i of its lower triangle, which the factor keeps); an empty ``first``
means dense. The factor overwrites S's lower triangle with L (S = L Lᵀ), with 1 / L_ii on
the diagonal, so that both solves multiply. The numpy reference is ``np.linalg.cholesky``
and ``np.linalg.solve``; tests hold them equal. Plain loops: ``NUMBA_DISABLE_JIT=1`` runs
the same source interpreted. :func:`lu_solve`: the triangular solves of a sparse LU
factorization (SuperLU's CSC factors), without scipy's per-call overhead; :func:`band_lu`:
such factors from a banded LU with partial pivoting (no sparse LU set-up per matrix).
"""
import math

import numpy as np
from numba import njit

from . import guard_cache

guard_cache(__file__)


@njit(cache=True, error_model="numpy")
def cholesky(S, n, first):
    """S (flat n x n, row-major) <- its Cholesky factor L in place (lower triangle, with
    1 / L_ii on the diagonal; the upper triangle is not touched). Reads S's lower triangle
    within the envelope ``first`` (empty: dense). Returns (ok, smallest, largest L_ii); not
    ok, and S left part-factorized, when a pivot is not positive."""
    dense = first.shape[0] == 0
    dmin, dmax = np.inf, 0.0
    for i in range(n):
        fi = 0 if dense else first[i]
        ri = n * i
        for j in range(fi, i + 1):
            rj = n * j
            s = S[ri + j]
            for k in range(fi if dense else max(fi, first[j]), j):
                s -= S[ri + k] * S[rj + k]
            if j < i:
                S[ri + j] = s * S[rj + j]
            elif s > 0.0:
                d = math.sqrt(s)
                dmin, dmax = min(dmin, d), max(dmax, d)
                S[ri + i] = 1.0 / d
            else:
                return False, 0.0, dmax
    return True, dmin, dmax


@njit(cache=True, error_model="numpy")
def cholesky_solve(L, n, first, x):
    """x <- (L Lᵀ)⁻¹ x in place, L from :func:`cholesky` (same ``n`` and ``first``)."""
    dense = first.shape[0] == 0
    for i in range(n):                      # L y = x
        s = x[i]
        for k in range(0 if dense else first[i], i):
            s -= L[n * i + k] * x[k]
        x[i] = s * L[n * i + i]
    for i in range(n - 1, -1, -1):          # Lᵀ x = y, column by column of Lᵀ (rows of L)
        x[i] *= L[n * i + i]
        xi = x[i]
        for k in range(0 if dense else first[i], i):
            x[k] -= L[n * i + k] * xi


@njit(cache=True, error_model="numpy")
def envelope_cholesky(S, first, start):
    """The Cholesky factor of a symmetric positive definite matrix in packed envelope
    storage, in place: row i of the lower triangle holds columns first[i]..i at
    S[start[i]:start[i + 1]] (start[i + 1] = start[i] + i - first[i] + 1; n = len(first)).
    The factor keeps the envelope; as :func:`cholesky`, 1 / L_ii on the diagonal. Memory and
    work grow with the envelope, not with n² (a banded matrix: n times its band). Returns
    (ok, smallest, largest L_ii); not ok when a pivot is not positive."""
    n = first.shape[0]
    dmin, dmax = np.inf, 0.0
    for i in range(n):
        fi, si = first[i], start[i] - first[i]          # S[si + j] is entry (i, j)
        for j in range(fi, i + 1):
            sj = start[j] - first[j]
            s = S[si + j]
            for k in range(max(fi, first[j]), j):
                s -= S[si + k] * S[sj + k]
            if j < i:
                S[si + j] = s * S[sj + j]
            elif s > 0.0:
                d = math.sqrt(s)
                dmin, dmax = min(dmin, d), max(dmax, d)
                S[si + i] = 1.0 / d
            else:
                return False, 0.0, dmax
    return True, dmin, dmax


@njit(cache=True, error_model="numpy")
def envelope_solve(L, first, start, x):
    """x <- (L Lᵀ)⁻¹ x in place, L from :func:`envelope_cholesky` (same ``first``, ``start``)."""
    n = first.shape[0]
    for i in range(n):                      # L y = x
        si = start[i] - first[i]
        s = x[i]
        for k in range(first[i], i):
            s -= L[si + k] * x[k]
        x[i] = s * L[si + i]
    for i in range(n - 1, -1, -1):          # Lᵀ x = y
        si = start[i] - first[i]
        x[i] *= L[si + i]
        xi = x[i]
        for k in range(first[i], i):
            x[k] -= L[si + k] * xi


@njit(cache=True, error_model="numpy")
def lu_solve(lp, li, lv, up, ui, uv, perm, b, x):
    """x <- the solution of A x = b from a sparse LU factorization Pr A Pc = L U (SuperLU's
    factors in CSC, as ``genalpha_matrix._lu_solver`` arranges them: ``lp, li, lv`` the
    entries of L below its unit diagonal, ``up, ui, uv`` of U with each column's diagonal
    entry first, the others in any order) and ``perm`` = (perm_r, perm_c) stacked: Pr b has
    b[i] at perm_r[i], and x[i] is y[perm_c[i]] for the solution y of L U y = Pr b. No
    branch in the inner loops. The numpy reference is ``scipy.sparse.linalg.splu(A).solve``;
    tests hold them equal."""
    n = b.shape[0]
    y = np.empty(n)
    for i in range(n):
        y[perm[i]] = b[i]
    for j in range(n):                      # L y = Pr b, column by column
        yj = y[j]
        for k in range(lp[j], lp[j + 1]):
            y[li[k]] -= lv[k] * yj
    for j in range(n - 1, -1, -1):          # U y = y, column by column from the last
        k0 = up[j]
        yj = y[j] / uv[k0]
        y[j] = yj
        for k in range(k0 + 1, up[j + 1]):
            y[ui[k]] -= uv[k] * yj
    for i in range(n):
        x[i] = y[perm[n + i]]


@njit(cache=True, error_model="numpy")
def band_lu(ip, ix, v, pinv, kl, ku, lp, li, lv, up, ui, uv, perm):
    """The LU factorization with partial pivoting (LAPACK's gbtrf) of the n x n matrix B with
    B[pinv[i], pinv[j]] = A[i, j] for A in CSC (``ip, ix, v``) whose entries all lie within
    the band -kl <= pinv[j] - pinv[i] <= ku (a bandwidth-reducing order ``pinv``), written as
    the factors :func:`lu_solve` takes for A itself into ``lp, li, lv, up, ui, uv, perm``
    (lp, up: n + 1; li, lv: at least n·kl; ui, uv: at least n·(kl + ku + 1); perm: 2 n).
    Returns (ok, number of L entries, number of U entries). Work n·kl·(kl + ku), storage
    n·(2 kl + ku + 1), no sparse LU set-up per call. Row interchanges stay within kl rows;
    the multipliers of each column end at the rows the later interchanges move them to (so
    that Pr A Pc = L U). Not ok (a column without a nonzero pivot): a singular matrix. The
    numpy reference is ``scipy.sparse.linalg.splu``; tests hold the solutions equal."""
    n = pinv.shape[0]
    W = np.zeros((n, 2 * kl + ku + 1))        # row i holds columns i - kl .. i + kl + ku
    for jj in range(n):
        j = pinv[jj]
        for k in range(ip[jj], ip[jj + 1]):
            i = pinv[ix[k]]
            W[i, j - i + kl] += v[k]
    piv = np.empty(n, np.int64)
    for k in range(n):
        last = min(n - 1, k + kl)
        p, big = k, abs(W[k, kl])
        for i in range(k + 1, last + 1):
            a = abs(W[i, k - i + kl])
            if a > big:
                p, big = i, a
        piv[k] = p
        if big == 0.0:
            return False, 0, 0
        width = min(n - 1, k + kl + ku) - k + 1          # columns k .. k + width - 1
        Wk = W[k]
        if p != k:
            Wp, c = W[p], k - p + kl
            for t in range(width):
                a = Wk[kl + t]
                Wk[kl + t] = Wp[c + t]
                Wp[c + t] = a
        d = Wk[kl]
        for i in range(k + 1, last + 1):
            Wi, c = W[i], k - i + kl
            m = Wi[c] / d
            Wi[c] = m
            if m != 0.0:
                for t in range(1, width):
                    Wi[c + t] -= m * Wk[kl + t]
    # L by columns from the last: sigma[r] is where the interchanges after column j move row r
    sigma = np.arange(n)
    nl = 0
    for j in range(n - 1, -1, -1):
        for i in range(j + 1, min(n - 1, j + kl) + 1):
            if W[i, j - i + kl] != 0.0:
                li[nl] = sigma[i]
                lv[nl] = W[i, j - i + kl]
                nl += 1
        lp[j] = nl                            # the count after column j (reversed below)
        a = sigma[j]                          # then the interchange of column j itself
        sigma[j] = sigma[piv[j]]
        sigma[piv[j]] = a
    for x in range(nl // 2):                  # columns in order (rows within one: any order)
        y = nl - 1 - x
        li[x], li[y] = li[y], li[x]
        lv[x], lv[y] = lv[y], lv[x]
    for j in range(n):
        lp[j] = nl - lp[j]
    lp[n] = nl
    k = 0
    up[0] = 0
    for j in range(n):
        ui[k] = j                             # the diagonal first
        uv[k] = W[j, kl]
        k += 1
        for i in range(max(0, j - kl - ku), j):
            if W[i, j - i + kl] != 0.0:
                ui[k] = i
                uv[k] = W[i, j - i + kl]
                k += 1
        up[j + 1] = k
    for i in range(n):
        perm[i] = sigma[pinv[i]]              # row i of A: row pinv[i] of B, moved by every interchange
        perm[n + i] = pinv[i]
    return True, nl, k



@njit("int64(float64[:, ::1], int64[::1])", cache=True, error_model="numpy")
def dense_lu(A, piv):
    """A = P L U in place (partial pivoting, row interchanges in ``piv`` as LAPACK's getrf:
    row k swapped with piv[k]), for the small dense Newton matrices of generalized-α: scipy's
    lu_factor and lu_solve call OpenBLAS, whose threaded triangular solves cost ~15 ms a call
    on busy cores, and ~25 µs of Python each. Returns 0, or k + 1 when pivot k is exactly 0
    (singular). The numpy reference is scipy.linalg.lu_factor/lu_solve; tests hold them equal."""
    n = A.shape[0]
    for k in range(n):
        p, big = k, abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                p, big = i, abs(A[i, k])
        piv[k] = p
        if big == 0.0:
            return k + 1
        if p != k:
            for j in range(n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
        d = 1.0 / A[k, k]
        for i in range(k + 1, n):
            f = A[i, k] * d
            A[i, k] = f
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
    return 0


@njit("void(float64[:, ::1], int64[::1], float64[:, ::1])", cache=True, error_model="numpy")
def dense_lu_solve(LU, piv, B):
    """B ← A⁻¹ B for the factors of :func:`dense_lu` (each column of B a right-hand side)."""
    n, m = LU.shape[0], B.shape[1]
    for k in range(n):
        p = piv[k]
        if p != k:
            for c in range(m):
                B[k, c], B[p, c] = B[p, c], B[k, c]
    for c in range(m):
        for i in range(n):
            s = B[i, c]
            for j in range(i):
                s -= LU[i, j] * B[j, c]
            B[i, c] = s
        for i in range(n - 1, -1, -1):
            s = B[i, c]
            for j in range(i + 1, n):
                s -= LU[i, j] * B[j, c]
            B[i, c] = s / LU[i, i]
