"""Compiled velocity maps of :class:`lgt_exudyn.ExudynModel` (numba; imported only when
used): Exudyn's state written from (q, V), forces and the constraint Jacobian mapped to
twists, γ's difference quotient. Every product with H or Hᵀ is a copy loop over identity
pairs plus a loop over small rotation blocks (no dense H); the tables are
:mod:`.kernel_tables`'.

Kernels (one explicit signature each — numba compiles them afresh in every CI run, so
related cases share a kernel; arrays are float64 C-contiguous, M, Mbar, C, A 2-D):

* :func:`write` (T, off, w, q, V, eps, qpos, qvel) -> h: eps = 0: qpos = q - ref,
  qvel = H(q) V (``qpos``/``qvel`` may be Exudyn's own views ``GetODE2Coordinates(copy=False)``
  / ``_t``); eps ≠ 0: q_m = τ(q, hV), h = eps / max(1, |V|∞), on SO(3)xR³ (exp) into ``w``
  (view ``P.qm``), qpos = q_m - ref, qvel = H(q_m) V — one γ evaluation's state;
* :func:`forces` (T, off, w, q, V, Q, M, Qbar, Mbar): M 0 x 0: Q̄ = Hᵀ Q - M̄ H⁺ Ḣ V with
  the constant M̄ packed; M = Exudyn's mass matrix: Q̄ = Hᵀ(Q - M Ḣ V), Mbar = Hᵀ M H;
* :func:`constraint_matrix` (T, off, w, q, C, rows, A): A = C[rows, :n2] H (C may be
  Exudyn's whole system Jacobian, ``rows`` then the AE rows kept);
* :func:`gamma_fd` (rp, rm, rows, eps, gam): gam = (rp[rows] - rm[rows]) / (2 eps).

The numpy reference is :class:`.layout.NodeLayout` (H, rates_from_twist, moved, Hdot_V).
Plain loops: ``NUMBA_DISABLE_JIT=1`` runs the same source interpreted.
"""
import math

from numba import njit

from lgt_bridge.kernels import guard_cache
from lgt_bridge.kernels.rotations import from_quat, qmul, rotvec_minus_one, to_quat

from .kernel_tables import (CODE, EP, FOFF, MEMBER, N2_, NROT, NV_, OB, OMB, OQM, OREF, OT, OZ, POS, QROW,
                            RBLOCKS, RCOMP, RMEMBER, ROT, RPAIR, RVEC, RXYZ, SIZE, START, TWIST, VCOL)

guard_cache(__file__)

_V = "float64[::1]"
_M = "float64[:, ::1]"
_I = "int64[::1]"
_T = "int64[:, ::1]"


# ---------------------------------------------------------------------------- H and Hᵀ
@njit(cache=True, error_model="numpy")
def _blocks(T, off, w, q):
    """The 4 x 3 block B (row-major) of every EP / Rxyz rotation at q into w[off[OB]:]."""
    for g in range(off[RBLOCKS]):
        b = off[OB] + 12 * g
        if T[g, CODE] == EP:
            p0, p1, p2, p3 = q[T[g, ROT]], q[T[g, ROT + 1]], q[T[g, ROT + 2]], q[T[g, ROT + 3]]
            # ṗ = B ω, B = [-½ pᵥᵀ; ½ (p0 I + p̃ᵥ)]
            w[b], w[b + 1], w[b + 2] = -0.5 * p1, -0.5 * p2, -0.5 * p3
            w[b + 3], w[b + 4], w[b + 5] = 0.5 * p0, 0.5 * -p3, 0.5 * p2
            w[b + 6], w[b + 7], w[b + 8] = 0.5 * p3, 0.5 * p0, 0.5 * -p1
            w[b + 9], w[b + 10], w[b + 11] = 0.5 * -p2, 0.5 * p1, 0.5 * p0
        else:
            t1, t2 = q[T[g, ROT + 1]], q[T[g, ROT + 2]]
            c1, s1, c2, s2 = math.cos(t1), math.sin(t1), math.cos(t2), math.sin(t2)
            # θ̇ = G(θ)⁻¹ ω
            w[b], w[b + 1], w[b + 2] = c2 / c1, -s2 / c1, 0.0
            w[b + 3], w[b + 4], w[b + 5] = s2, c2, 0.0
            w[b + 6], w[b + 7], w[b + 8] = -s1 * c2 / c1, s1 * s2 / c1, 1.0


@njit(cache=True, error_model="numpy")
def _rates(T, off, w, V, qvel):
    """qvel = H V (the rotation blocks in w)."""
    for r in range(off[RPAIR], off[RCOMP]):
        qvel[T[r, QROW]] = V[T[r, VCOL]]
    for g in range(off[RBLOCKS]):
        b, iv = off[OB] + 12 * g, T[g, TWIST]
        w0, w1, w2 = V[iv], V[iv + 1], V[iv + 2]
        for i in range(T[g, NROT]):
            qvel[T[g, ROT + i]] = w[b + 3 * i] * w0 + w[b + 3 * i + 1] * w1 + w[b + 3 * i + 2] * w2


@njit(cache=True, error_model="numpy")
def _Ht(T, off, w, x, out):
    """out = Hᵀ x (x on q rows, out on V columns; the rotation blocks in w)."""
    for r in range(off[RPAIR], off[RCOMP]):
        out[T[r, VCOL]] = x[T[r, QROW]]
    for g in range(off[RBLOCKS]):
        b, iv = off[OB] + 12 * g, T[g, TWIST]
        for k in range(3):
            s = 0.0
            for i in range(T[g, NROT]):
                s += w[b + 3 * i + k] * x[T[g, ROT + i]]
            out[iv + k] = s


@njit(cache=True, error_model="numpy")
def _rxyz_rates_dot(T, g, q, V):
    """Rxyz node in row g: (cos, sin of θ1, θ2, Ḣ V) with θ̇ = G⁻¹ω (NodeLayout.Hdot_V)."""
    iv = T[g, TWIST]
    t1, t2 = q[T[g, ROT + 1]], q[T[g, ROT + 2]]
    c1, s1, c2, s2 = math.cos(t1), math.sin(t1), math.cos(t2), math.sin(t2)
    w0, w1, w2 = V[iv], V[iv + 1], V[iv + 2]
    a = (c2 * w0 - s2 * w1) / c1
    bb = s2 * w0 + c2 * w1
    cc = w2 - s1 * a
    da = (-cc * bb + a * s1 * bb) / c1
    db = cc * a * c1
    dc = -c1 * bb * a - s1 * da
    return c1, s1, c2, s2, da, db, dc


# ---------------------------------------------------------------------------- state writes
@njit(f"float64({_T}, {_I}, {_V}, {_V}, {_V}, float64, {_V}, {_V})", cache=True, error_model="numpy")
def write(T, off, w, q, V, eps, qpos, qvel):
    """eps = 0: qpos = q - ref, qvel = H(q) V (Exudyn's coordinates and velocities);
    returns 0.

    eps ≠ 0: the moved state of one γ difference, q_m = τ(q, hV) on SO(3)xR³ with the exp
    chart (NodeLayout.moved) and h = eps / max(1, max|V|) (the step of
    ConstraintRows.gamma for eps = ±1e-5), into w's q_m area (``P.qm``); qpos = q_m - ref,
    qvel = H(q_m) V; returns h."""
    n2, wr = off[N2_], off[OREF]
    if q.shape[0] != n2 or V.shape[0] != off[NV_] or qpos.shape[0] != n2 or qvel.shape[0] != n2:
        raise ValueError("write: q, qpos, qvel need n2 entries and V nv entries")
    if eps == 0.0:
        for k in range(n2):
            qpos[k] = q[k] - w[wr + k]
        _blocks(T, off, w, q)
        _rates(T, off, w, V, qvel)
        return 0.0
    vmax = 1.0
    for k in range(V.shape[0]):
        vmax = max(vmax, abs(V[k]))
    eps = eps / vmax
    qm = w[off[OQM]:off[OQM] + n2]
    for b in range(off[RPAIR]):
        code, nrot, iv = T[b, CODE], T[b, NROT], T[b, TWIST]
        for c in range(3):
            qm[T[b, POS + c]] = q[T[b, POS + c]] + eps * V[iv + 3 + c]
        r0, r1, r2 = q[T[b, ROT]], q[T[b, ROT + 1]], q[T[b, ROT + 2]]
        r3 = q[T[b, ROT + 3]] if nrot == 4 else 0.0
        k0, k1, k2, k3 = to_quat(code, r0, r1, r2, r3)
        d0, d1, d2, d3, phi, sh = rotvec_minus_one(eps * V[iv], eps * V[iv + 1], eps * V[iv + 2])
        m0, m1, m2, m3 = qmul(k0, k1, k2, k3, d0, d1, d2, d3)
        o0, o1, o2, o3 = from_quat(code, k0 + m0, k1 + m1, k2 + m2, k3 + m3, r0, r1, r2, r3)
        qm[T[b, ROT]], qm[T[b, ROT + 1]], qm[T[b, ROT + 2]] = o0, o1, o2
        if nrot == 4:
            qm[T[b, ROT + 3]] = o3
    for r in range(off[RVEC], off[RCOMP]):
        iq, iv = T[r, QROW], T[r, VCOL]
        qm[iq] = q[iq] + eps * V[iv]
    for k in range(n2):
        qpos[k] = qm[k] - w[wr + k]
    _blocks(T, off, w, qm)
    _rates(T, off, w, V, qvel)
    return eps


# ---------------------------------------------------------------------------- forces
@njit(cache=True, error_model="numpy")
def _minus_Mbar_Hplus_Hdot_V(T, off, w, q, V, Qbar):
    """Qbar -= M̄ H⁺ Ḣ V with the constant M̄ packed (H⁺ Ḣ V is G(θ) Ḣ V on Rxyz rotations,
    0 elsewhere); only the diagonal blocks of M̄ that H⁺ Ḣ V touches are multiplied."""
    nv = off[NV_]
    y = w[off[OT]:off[OT] + nv]
    any_y = False
    for g in range(off[RBLOCKS]):
        if T[g, CODE] == RXYZ:
            if not any_y:
                for k in range(nv):
                    y[k] = 0.0
                any_y = True
            c1, s1, c2, s2, da, db, dc = _rxyz_rates_dot(T, g, q, V)
            iv = T[g, TWIST]
            y[iv] = c1 * c2 * da + s2 * db
            y[iv + 1] = -c1 * s2 * da + c2 * db
            y[iv + 2] = s1 * da + dc
    if not any_y:
        return
    mem = off[RMEMBER]
    for c in range(off[RCOMP], off[RMEMBER]):
        a, n = T[c, START], T[c, SIZE]
        nz = False
        for j in range(n):
            if y[T[mem + a + j, MEMBER]] != 0.0:
                nz = True
        if not nz:
            continue
        base = off[OMB] + T[c, FOFF]
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += w[base + n * i + j] * y[T[mem + a + j, MEMBER]]
            Qbar[T[mem + a + i, MEMBER]] -= s


@njit(f"void({_T}, {_I}, {_V}, {_V}, {_V}, {_V}, {_M}, {_V}, {_M})", cache=True, error_model="numpy")
def forces(T, off, w, q, V, Q, M, Qbar, Mbar):
    """Generalized forces in twist coordinates. Q: Exudyn's residual (its first n2 entries
    are read).

    M with 0 rows (the constant M̄ packed): Q̄ = Hᵀ Q - M̄ H⁺ Ḣ V; Mbar is not touched.
    M = Exudyn's dense n2 x n2 mass matrix: Q̄ = Hᵀ(Q - M Ḣ V) and Mbar = Hᵀ M H (row by
    row: M̄[p] = Hᵀ (Hᵀ M)[p])."""
    n2, nv = off[N2_], off[NV_]
    const = M.shape[0] == 0
    if (q.shape[0] != n2 or V.shape[0] != nv or Qbar.shape[0] != nv or Q.shape[0] < n2 or not (
            const or (M.shape[0] == n2 and M.shape[1] == n2 and Mbar.shape[0] == nv and Mbar.shape[1] == nv))):
        raise ValueError("forces: wrong sizes (q n2, Q ≥ n2, V and Qbar nv; M 0 x 0 or n2 x n2 with Mbar nv x nv)")
    if const and off[RMEMBER] == off[RCOMP] and nv > 0:
        raise ValueError("forces: no constant mass matrix packed; pass Exudyn's M")
    _blocks(T, off, w, q)
    if const:
        _Ht(T, off, w, Q, Qbar)
        _minus_Mbar_Hplus_Hdot_V(T, off, w, q, V, Qbar)
        return
    z = w[off[OZ]:off[OZ] + n2]
    u = w[off[OZ] + n2:off[OZ] + 2 * n2]
    for k in range(n2):
        z[k] = Q[k]
    for g in range(off[RBLOCKS]):
        if T[g, CODE] == EP:
            iv = T[g, TWIST]
            w0, w1, w2 = V[iv], V[iv + 1], V[iv + 2]
            f = -0.25 * (w0 * w0 + w1 * w1 + w2 * w2)
            h0, h1, h2, h3 = f * q[T[g, ROT]], f * q[T[g, ROT + 1]], f * q[T[g, ROT + 2]], f * q[T[g, ROT + 3]]
        else:
            c1, s1, c2, s2, h0, h1, h2 = _rxyz_rates_dot(T, g, q, V)
            h3 = 0.0
        for r in range(n2):
            s = M[r, T[g, ROT]] * h0 + M[r, T[g, ROT + 1]] * h1 + M[r, T[g, ROT + 2]] * h2
            if T[g, NROT] == 4:
                s += M[r, T[g, ROT + 3]] * h3
            z[r] -= s
    _Ht(T, off, w, z, Qbar)
    for r in range(off[RPAIR], off[RCOMP]):
        _Ht(T, off, w, M[T[r, QROW]], Mbar[T[r, VCOL]])
    for g in range(off[RBLOCKS]):
        b = off[OB] + 12 * g
        for a in range(3):
            for r in range(n2):
                s = 0.0
                for i in range(T[g, NROT]):
                    s += w[b + 3 * i + a] * M[T[g, ROT + i], r]
                u[r] = s
            _Ht(T, off, w, u, Mbar[T[g, TWIST] + a])


# ---------------------------------------------------------------------------- constraints
@njit(f"void({_T}, {_I}, {_V}, {_V}, {_M}, {_I}, {_M})", cache=True, error_model="numpy")
def constraint_matrix(T, off, w, q, C, rows, A):
    """A[i] = C[rows[i], :n2] H(q): the constraint Jacobian in twist coordinates."""
    nc = rows.shape[0]
    if q.shape[0] != off[N2_] or A.shape[0] != nc or A.shape[1] != off[NV_] or C.shape[1] < off[N2_]:
        raise ValueError("constraint_matrix: A must be len(rows) x nv, C have at least n2 columns")
    _blocks(T, off, w, q)
    for i in range(nc):
        _Ht(T, off, w, C[rows[i]], A[i])


@njit(f"void({_V}, {_V}, {_I}, float64, {_V})", cache=True, error_model="numpy")
def gamma_fd(rp, rm, rows, eps, gam):
    """gam = (rp[rows] - rm[rows]) / (2 eps): γ from the two velocity-level residuals."""
    d = 2.0 * eps
    for i in range(rows.shape[0]):
        gam[i] = (rp[rows[i]] - rm[rows[i]]) / d

