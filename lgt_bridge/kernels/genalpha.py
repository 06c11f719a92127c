"""Kernels of generalized-α (and radau5's rates) on the stage kernels' work array: the
state at given Ẇ (affine in it), the step's constants, the residual of the unconstrained
rows, a CSR product, and the fused Newton update of the residual in forces
(:mod:`lgt_bridge.integrators.genalpha`, :mod:`~lgt_bridge.integrators.genalpha_newton`).
The numpy references are in those modules; tests hold the two equal."""
import math

import numpy as np
from numba import njit

from . import guard_cache
from .charts import increment, rot_rates, se3_rates
from .linalg import dense_lu_solve, lu_solve
from .stage import NX_, OXD, convert, tau_state, views

guard_cache(__file__, extra=(__file__.replace("genalpha.py", "stage.py"), __file__.replace("genalpha.py", "linalg.py")))


@njit(cache=True, error_model="numpy")
def ga_state(Wd, sv, sp, Wa, dXa, tl, w, bt, vt, off, kin):
    """Generalized-α's state for the unknowns Ẇ (affine in them): W = Wa + sv Ẇ,
    X = dXa + sp Ẇ[tl] (sp per entry of X: the chart scale; tl: X's entries in V's layout),
    then τ, the model velocity and (``kin``: radau5's rates) Ẋ of every body into the work
    array, as stage_state."""
    X, W, q, V, W0, qk, pk, p = views(w, off)
    for j in range(W.shape[0]):
        W[j] = Wa[j] + sv * Wd[j]
    for j in range(X.shape[0]):
        X[j] = dXa[j] + sp[j] * Wd[tl[j]]
    tau_state(False, X, W, bt, vt, qk, pk, q, V, w[off[OXD]:off[OXD] + off[NX_]], p, kin)


@njit(cache=True, error_model="numpy")
def ga_affine(W, Wd, a, af, am, h, g, b, k, scale, tl, a0, Wa, dXa, sp):
    """Generalized-α's step constants (genalpha.GenAlpha._affine): a0 = (α_f Ẇ - α_m a)/(1 - α_m),
    Wa = W + h(1 - γ) a + hγ a0, dXa = scale · (hW + h²(½ - β) a + h²β a0)[tl], sp = h²βk scale."""
    for j in range(W.shape[0]):
        a0[j] = (af * Wd[j] - am * a[j]) / (1.0 - am)
        Wa[j] = W[j] + h * (1.0 - g) * a[j] + h * g * a0[j]
    hh = h * h
    for j in range(dXa.shape[0]):
        i = tl[j]
        dXa[j] = scale[j] * (h * W[i] + hh * (0.5 - b) * a[i] + hh * b * a0[i])
        sp[j] = hh * b * k * scale[j]


@njit(cache=True, error_model="numpy")
def ga_residual(Vd, Wd, r, w, bt, off):
    """r = Ẇ - Ẇ(V̇) at the state of the work array (generalized-α's unconstrained rows);
    the sum of r² (inf or NaN when r is not finite)."""
    X, W, q, V, W0, qk, pk, p = views(w, off)
    convert(2, Vd, W, p, bt, r)
    s = 0.0
    for j in range(r.shape[0]):
        r[j] = Wd[j] - r[j]
        s += r[j] * r[j]
    return s


@njit(cache=True, error_model="numpy")
def csr_matvec(indptr, indices, data, x, out):
    """out = S x for a CSR matrix (scipy's per-call overhead is ~3 µs)."""
    for i in range(out.shape[0]):
        acc = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            acc += data[k] * x[indices[k]]
        out[i] = acc


@njit(cache=True, error_model="numpy", inline="always")
def _force_residual(mp, mi, mv, A, Q, g, cg, z, r):
    """r = [M̄ Ẇ - Q + Aᵀλ; cg g] at z = (Ẇ, λ) (M̄ in CSR ``mp, mi, mv``, A dense nc x n);
    returns |r|² (not finite when r is not)."""
    n, nc = Q.shape[0], g.shape[0]
    s = 0.0
    for i in range(n):
        acc = -Q[i]
        for k in range(mp[i], mp[i + 1]):
            acc += mv[k] * z[mi[k]]
        for k in range(nc):
            acc += A[k, i] * z[n + k]
        r[i] = acc
        s += acc * acc
    for k in range(nc):
        r[n + k] = cg * g[k]
        s += r[n + k] * r[n + k]
    return s


@njit(cache=True, error_model="numpy", inline="always")
def _step_by(z, dz, n):
    """z -= dz; returns |dz[:n]|² (the update of Ẇ)."""
    d2 = 0.0
    for i in range(z.shape[0]):
        z[i] -= dz[i]
        if i < n:
            d2 += dz[i] * dz[i]
    return d2


@njit(cache=True, error_model="numpy")
def ga_force_newton(mp, mi, mv, A, Q, g, cg, lp, li, lv, up, ui, uv, perm, z, r,
                    sv, sp, Wa, dXa, tl, w, bt, vt, off, kin):
    """One Newton update of generalized-α's residual in forces with a constant mass matrix
    (CSR ``mp, mi, mv``) and no SE(3) body: r = [M̄ Ẇ - Q + Aᵀλ; cg g] at z = (Ẇ, λ) (A
    dense, nc x n), then z -= J⁻¹ r with the sparse LU factors of J (:func:`.linalg.lu_solve`'s
    arguments), then the state at the new Ẇ into the work array (:func:`ga_state`'s
    arguments after Ẇ: the next update's model call reads it; one kernel call less an
    update). Returns |ΔẆ|², or -1 when r is not finite (z and the state untouched). The
    numpy reference is GenAlpha._force_rows and the solver of ``genalpha_matrix.factorize``;
    tests hold them equal."""
    n = Q.shape[0]
    if not math.isfinite(_force_residual(mp, mi, mv, A, Q, g, cg, z, r)):
        return -1.0
    dz = np.empty(z.shape[0])
    lu_solve(lp, li, lv, up, ui, uv, perm, r, dz)
    d2 = _step_by(z, dz, n)
    ga_state(z[:n], sv, sp, Wa, dXa, tl, w, bt, vt, off, kin)
    return d2


@njit(cache=True, error_model="numpy")
def ga_force_newton_dense(mp, mi, mv, A, Q, g, cg, LU, piv, z, r, sv, sp, Wa, dXa, tl, w, bt, vt, off, kin):
    """:func:`ga_force_newton` with the dense LU factors of J (:func:`.linalg.dense_lu`: a
    Newton matrix of at most ``genalpha_matrix.DENSE_MAX`` unknowns, a small constrained model
    such as a pendulum, whose updates were ~30 µs of Python around ~4 µs of Exudyn), solved
    by :func:`.linalg.dense_lu_solve` with one right-hand side."""
    n, m = Q.shape[0], z.shape[0]
    if not math.isfinite(_force_residual(mp, mi, mv, A, Q, g, cg, z, r)):
        return -1.0
    dz = r.copy()
    dense_lu_solve(LU, piv, dz.reshape((m, 1)))
    d2 = _step_by(z, dz, n)
    ga_state(z[:n], sv, sp, Wa, dXa, tl, w, bt, vt, off, kin)
    return d2


@njit(cache=True, error_model="numpy")
def ga_force_newton_csr(mp, mi, mv, A, Q, g, cg, jp, ji, jv, z, r, sv, sp, Wa, dXa, tl, w, bt, vt, off, kin):
    """:func:`ga_force_newton` with J⁻¹ itself as a CSR matrix (``jp, ji, jv``: J falls apart
    into small blocks, inverted one by one: free bodies, ``genalpha_matrix._block_inverse``):
    the solve is a product (:func:`csr_matvec`'s arithmetic)."""
    n = Q.shape[0]
    if not math.isfinite(_force_residual(mp, mi, mv, A, Q, g, cg, z, r)):
        return -1.0
    dz = np.empty(z.shape[0])
    csr_matvec(jp, ji, jv, r, dz)
    d2 = _step_by(z, dz, n)
    ga_state(z[:n], sv, sp, Wa, dXa, tl, w, bt, vt, off, kin)
    return d2


@njit("void(float64[::1], float64[::1], float64, float64[::1])", cache=True, error_model="numpy")
def predict(x, x_prev, alternating, out):
    """out = 2 x - x_prev, but 0 where x and x_prev have opposite signs and both exceed
    ``alternating`` times x's RMS: generalized-α's Newton start (the numpy reference is
    :func:`lgt_bridge.integrators.genalpha_newton.predict`)."""
    n = x.shape[0]
    s = 0.0
    for i in range(n):
        s += x[i] * x[i]
    big = alternating * math.sqrt(s / n) if n else 0.0
    for i in range(n):
        a, b = x[i], x_prev[i]
        out[i] = 0.0 if (a * b < 0.0 and abs(a) > big and abs(b) > big) else 2.0 * a - b


@njit(cache=True, error_model="numpy", inline="always")
def _inv3(A, i0, j0, out, k0, l0):
    """out[k0:k0+3, l0:l0+3] = the inverse of A[i0:i0+3, j0:j0+3] (adjugate over the
    determinant: the blocks here are within a chart's domain, far from singular)."""
    a, b, c = A[i0, j0], A[i0, j0 + 1], A[i0, j0 + 2]
    d, e, f = A[i0 + 1, j0], A[i0 + 1, j0 + 1], A[i0 + 1, j0 + 2]
    g, h, k = A[i0 + 2, j0], A[i0 + 2, j0 + 1], A[i0 + 2, j0 + 2]
    c0, c1, c2 = e * k - f * h, f * g - d * k, d * h - e * g
    r = 1.0 / (a * c0 + b * c1 + c * c2)
    out[k0, l0], out[k0, l0 + 1], out[k0, l0 + 2] = c0 * r, (c * h - b * k) * r, (b * f - c * e) * r
    out[k0 + 1, l0], out[k0 + 1, l0 + 1], out[k0 + 1, l0 + 2] = c1 * r, (a * k - c * g) * r, (c * d - a * f) * r
    out[k0 + 2, l0], out[k0 + 2, l0 + 1], out[k0 + 2, l0 + 2] = c2 * r, (b * g - a * h) * r, (a * e - b * d) * r


@njit("void(int64, int64, float64[:, ::1], float64[:, :, ::1])", cache=True, error_model="numpy")
def dpsi_neg(code, kind, X, out):
    """out[b] = dψ_{−X[b]} of every body of a set, chart ``code``; ``kind`` 0: SO(3) (3x3),
    1: SO(3)×R³ (6x6, the identity on the translation), 2: SE(3) (6x6): the inverse of the
    matrix of dψ⁻¹_{−x}, whose columns are the stage kernels' rates of unit vectors
    (:func:`.charts.rot_rates`, :func:`.charts.se3_rates`). A batch of 36 bodies in numpy
    (the charts' ``dpsi``, the reference) costs 70-270 µs, a third of a Newton matrix."""
    m = out.shape[1]
    M = np.empty((m, m))
    for b in range(X.shape[0]):
        x0, x1, x2 = X[b, 0], X[b, 1], X[b, 2]
        phi = increment(code, x0, x1, x2)[4]
        for k in range(m):                              # column k: the rates of the unit vector e_k
            e0, e1, e2 = 1.0 if k == 0 else 0.0, 1.0 if k == 1 else 0.0, 1.0 if k == 2 else 0.0
            e3, e4, e5 = 1.0 if k == 3 else 0.0, 1.0 if k == 4 else 0.0, 1.0 if k == 5 else 0.0
            r0, r1, r2 = rot_rates(code, x0, x1, x2, e0, e1, e2, phi)
            M[0, k], M[1, k], M[2, k] = r0, r1, r2
            if m == 6:
                if kind == 2:
                    t0, t1, t2 = se3_rates(code, x0, x1, x2, X[b, 3], X[b, 4], X[b, 5], e0, e1, e2, e3, e4, e5, phi)
                else:
                    t0, t1, t2 = e3, e4, e5
                M[3, k], M[4, k], M[5, k] = t0, t1, t2
        # block lower triangular [[A, 0], [B, C]]: inv = [[A⁻¹, 0], [-C⁻¹ B A⁻¹, C⁻¹]]
        _inv3(M, 0, 0, out[b], 0, 0)
        if m == 6:
            _inv3(M, 3, 3, out[b], 3, 3)
            for i in range(3):
                for j in range(3):
                    out[b, i, 3 + j] = 0.0
                    s = 0.0
                    for k in range(3):
                        for l in range(3):
                            s += out[b, 3 + i, 3 + k] * M[3 + k, l] * out[b, l, j]
                    out[b, 3 + i, j] = -s

