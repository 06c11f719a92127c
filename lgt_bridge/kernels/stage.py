"""Stage kernels of the explicit steppers, over every body of a model in one call.

A model's bodies are described by an int64 table ``bt`` (one row per rigid body, see
:func:`body_table`) and its vector-space and circle coordinates by ``vt`` (rows
``(iq, iv, ix, js)``: js = -1 for a vector coordinate, q[iq] += X[ix]; else the sin entry of a
circle coordinate, (q[iq], q[js]) = (c, s) exp(i X[ix])).
One stage of an RKMK method is

    stage_state:       X = h Σ a_j KX_j,  W = W_0 + h Σ a_j KW_j,  q = τ(q_k, X),
                       V = model velocity of W,  KX_i = dψ⁻¹_{-X}(W)
    the model's f:     V̇ = f(q, V, t)
    stage_derivative:  KW_i = Ẇ from V̇ (SE(3): Rᵀr̈ - ω × Rᵀṙ), finiteness of KX_i, KW_i

A model may give f in its engine's own velocities (:class:`lgt_bridge.model.EngineVelocity`):
on the bodies whose ``ENGINE`` column is 1, the engine's velocity ``ve`` is the body-frame
twist (v_lin, ω) over the body's six twist entries and its f returns (v̇_lin, ω̇) there
(Pinocchio's free-flyers); :func:`stage` writes ``ve`` after each stage state and
:func:`stage_derivative` reads such a V̇, so that f needs no conversions of its own.

The numpy reference is :class:`lgt_bridge.integrators.local.LocalProblem` (τ from
``lgt.LGT.tau_pose``, rates from the ``groups`` modules); tests hold the two equal.
"""
import math

import numpy as np
from numba import njit

from . import guard_cache
from .charts import increment, rot_rates, se3_rates, translation, usage
from .rotations import cross, from_quat, qmul, rotate, to_quat
from .views import matrix

guard_cache(__file__)

# columns of the body table (ENGINE: 1 when f takes and gives this body's velocities in the
# engine's body-frame form, see the module's docstring)
PARAM, SE3, CHART, ROT_ONLY, XOFF, NROT, POS, ROT, TWIST, ENGINE = 0, 1, 2, 3, 4, 5, 6, 9, 13, 19
NCOL = 20

# the work array of a problem: one float64 vector holding, at these offsets (``off``),
# X, W, q, V (the current stage), W0 (the step's start), q_k and the quaternions p_k and p
# (4 per body), a scratch Ẋ and the engine's velocity ve; off[10:] = nX, nv, nq, nb and
# the number of ENGINE bodies. One array instead of ten keeps the kernels' argument lists
# short: a numba call costs ~0.1 µs per argument.
OX, OW, OQ, OV, OW0, OQK, OPK, OP, OXD, OVE, NX_, NV_, NQ_, NB_, NE_ = range(15)
NOFF = 15


def work_layout(nX, nv, nq, nb):
    """(off, size) of a work array for these sizes (no ENGINE body: :func:`with_engine`)."""
    sizes = [nX, nv, nq, nv, nv, nq, 4 * nb, 4 * nb, nX, nv]
    off = np.zeros(NOFF, np.int64)
    off[:10] = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    off[10:] = nX, nv, nq, nb, 0
    return off, int(sum(sizes))


def with_engine(bt, off, rows):
    """Copies of the body table and offsets with the body rows ``rows`` in the engine's
    velocity form (column ENGINE = 1)."""
    bt, off = bt.copy(), off.copy()
    bt[:, ENGINE] = 0
    bt[list(rows), ENGINE] = 1
    off[NE_] = len(rows)
    return bt, off


@njit(cache=True, error_model="numpy", inline="always")
def views(w, off):
    """X, W, q, V, W0, q_k, p_k (nb, 4), p (nb, 4) as views of the work array (the
    scratch Ẋ is ``w[off[OXD]:]``)."""
    nX, nv, nq, nb = off[NX_], off[NV_], off[NQ_], off[NB_]
    return (w[off[OX]:off[OX] + nX], w[off[OW]:off[OW] + nv], w[off[OQ]:off[OQ] + nq],
            w[off[OV]:off[OV] + nv], w[off[OW0]:off[OW0] + nv], w[off[OQK]:off[OQK] + nq],
            matrix(w[off[OPK]:], nb, 4), matrix(w[off[OP]:], nb, 4))


def body_table(sets, codes):
    """The int64 body table of a LocalProblem's body sets (``codes``: parameterization
    name -> kernel code)."""
    tabs = []
    for s in sets:
        n, nrot = len(s.ids), s.lgt.param.nrot
        t = np.full((n, NCOL), -1, np.int64)
        t[:, PARAM], t[:, SE3], t[:, CHART], t[:, ROT_ONLY] = codes[s.lgt.param.name], s.se3, s.chart.code, s.rot_only
        t[:, XOFF], t[:, NROT] = s.xidx[:, 0], nrot
        if s.rot_only:
            t[:, ROT:ROT + nrot] = s.qidx
        else:
            t[:, POS:POS + 3] = s.qidx[:, :3]
            t[:, ROT:ROT + nrot] = s.qidx[:, 3:]
        t[:, TWIST:TWIST + s.vidx.shape[1]] = s.vidx
        t[:, ENGINE] = 0
        tabs.append(t)
    return np.concatenate(tabs) if tabs else np.zeros((0, NCOL), np.int64)


@njit(cache=True, error_model="numpy")
def bases(bt, q, pk):
    """pk[b] = α(q) of every body (unit quaternion, scalar first)."""
    for b in range(bt.shape[0]):
        o = ROT
        r3 = q[bt[b, o + 3]] if bt[b, NROT] == 4 else 0.0
        p0, p1, p2, p3 = to_quat(bt[b, PARAM], q[bt[b, o]], q[bt[b, o + 1]], q[bt[b, o + 2]], r3)
        pk[b, 0], pk[b, 1], pk[b, 2], pk[b, 3] = p0, p1, p2, p3


@njit(cache=True, error_model="numpy", inline="always")
def stage_state(KX, KW, a, ns, h, W0, X, W, bt, vt, qk, pk, q, V, Xd, p):
    """Stage combination, τ, model velocity and local kinematics of every body.
    ``ns = 0``: the step's start (X = 0, q = q_k). Returns the largest |c| of the
    bounded-chart bodies' |x|/limit (> 1: a stage left its chart's domain)."""
    nX, nv = X.shape[0], W.shape[0]
    # row by row (contiguous, vectorized); the same sums in the same order as a @ K
    for j in range(nX):
        X[j] = 0.0
    for j in range(nv):
        W[j] = 0.0
    for i in range(ns):
        ai = a[i]
        if ai != 0.0:
            for j in range(nX):
                X[j] += ai * KX[i, j]
            for j in range(nv):
                W[j] += ai * KW[i, j]
    for j in range(nX):
        X[j] *= h
    for j in range(nv):
        W[j] = W0[j] + h * W[j]
    return tau_state(ns == 0, X, W, bt, vt, qk, pk, q, V, Xd, p, True)


@njit(cache=True, error_model="numpy", inline="always")
def tau_state(start, X, W, bt, vt, qk, pk, q, V, Xd, p, kin):
    """τ, model velocity and (``kin``) local kinematics Ẋ of every body at (X, W) (``start``:
    X = 0, q = q_k); returns the largest |x|/limit of the bounded-chart bodies (> 1: out of
    the chart's domain)."""
    cmax = 0.0
    for b in range(bt.shape[0]):
        se3, ch, ro, xo = bt[b, SE3] == 1, bt[b, CHART], bt[b, ROT_ONLY] == 1, bt[b, XOFF]
        nrot = bt[b, NROT]
        x0, x1, x2 = X[xo], X[xo + 1], X[xo + 2]
        k0, k1, k2, k3 = pk[b, 0], pk[b, 1], pk[b, 2], pk[b, 3]
        d0, d1, d2, d3, phi, sh = increment(ch, x0, x1, x2)
        cmax = max(cmax, usage(ch, x0, x1, x2))
        if start:
            p0, p1, p2, p3 = k0, k1, k2, k3
            for c in range(3):
                if not ro:
                    q[bt[b, POS + c]] = qk[bt[b, POS + c]]
            for c in range(nrot):
                q[bt[b, ROT + c]] = qk[bt[b, ROT + c]]
        else:
            m0, m1, m2, m3 = qmul(k0, k1, k2, k3, d0, d1, d2, d3)
            p0, p1, p2, p3 = k0 + m0, k1 + m1, k2 + m2, k3 + m3
            r = ROT
            prev3 = qk[bt[b, r + 3]] if nrot == 4 else 0.0
            o0, o1, o2, o3 = from_quat(bt[b, PARAM], p0, p1, p2, p3, qk[bt[b, r]], qk[bt[b, r + 1]],
                                       qk[bt[b, r + 2]], prev3)
            q[bt[b, r]], q[bt[b, r + 1]], q[bt[b, r + 2]] = o0, o1, o2
            if nrot == 4:
                q[bt[b, r + 3]] = o3
            if not ro:
                y0, y1, y2 = X[xo + 3], X[xo + 4], X[xo + 5]
                if se3:
                    t0, t1, t2 = translation(ch, x0, x1, x2, y0, y1, y2, d0, d1, d2, d3, phi, sh)
                    y0, y1, y2 = rotate(k0, k1, k2, k3, t0, t1, t2)
                i0, i1, i2 = bt[b, POS], bt[b, POS + 1], bt[b, POS + 2]
                q[i0], q[i1], q[i2] = qk[i0] + y0, qk[i1] + y1, qk[i2] + y2
        p[b, 0], p[b, 1], p[b, 2], p[b, 3] = p0, p1, p2, p3
        # velocities and local kinematics
        tw = TWIST
        w0, w1, w2 = W[bt[b, tw]], W[bt[b, tw + 1]], W[bt[b, tw + 2]]
        V[bt[b, tw]], V[bt[b, tw + 1]], V[bt[b, tw + 2]] = w0, w1, w2
        if not kin:                             # the velocities only (generalized-α)
            if not ro:
                j0, j1, j2 = bt[b, tw + 3], bt[b, tw + 4], bt[b, tw + 5]
                if se3:
                    V[j0], V[j1], V[j2] = rotate(p0, p1, p2, p3, W[j0], W[j1], W[j2])
                else:
                    V[j0], V[j1], V[j2] = W[j0], W[j1], W[j2]
            continue
        Xd[xo], Xd[xo + 1], Xd[xo + 2] = rot_rates(ch, x0, x1, x2, w0, w1, w2, phi)
        if ro:
            continue
        j0, j1, j2 = bt[b, tw + 3], bt[b, tw + 4], bt[b, tw + 5]
        u0, u1, u2 = W[j0], W[j1], W[j2]
        if se3:
            V[j0], V[j1], V[j2] = rotate(p0, p1, p2, p3, u0, u1, u2)
            Xd[xo + 3], Xd[xo + 4], Xd[xo + 5] = se3_rates(ch, x0, x1, x2, X[xo + 3], X[xo + 4], X[xo + 5],
                                                           w0, w1, w2, u0, u1, u2, phi)
        else:
            V[j0], V[j1], V[j2] = u0, u1, u2
            Xd[xo + 3], Xd[xo + 4], Xd[xo + 5] = u0, u1, u2
    for k in range(vt.shape[0]):
        iq, iv, ix, js = vt[k, 0], vt[k, 1], vt[k, 2], vt[k, 3]
        if js < 0:
            q[iq] = qk[iq] + X[ix]
        else:                                   # circle: (c, s) exp(i x), no norm drift
            x = X[ix]
            sh = math.sin(0.5 * x)
            cm1, sn = -2.0 * sh * sh, math.sin(x)
            c, s = qk[iq], qk[js]
            q[iq] = c + (c * cm1 - s * sn)
            q[js] = s + (s * cm1 + c * sn)
        V[iv] = W[iv]
        Xd[ix] = W[iv]
    return cmax


@njit(cache=True, error_model="numpy", inline="always")
def convert(mode, src, W, p, bt, out):
    """Velocity representations of SE(3) bodies (other entries copied):
    mode 0: W -> V (u -> R u);  1: V -> W (ṙ -> Rᵀ ṙ);
    mode 2: V̇ -> Ẇ (Rᵀ r̈ - ω × u);  3: Ẇ -> V̇ (R (u̇ + ω × u))."""
    for j in range(src.shape[0]):
        out[j] = src[j]
    for b in range(bt.shape[0]):
        if bt[b, SE3] != 1 or bt[b, ROT_ONLY] == 1:
            continue
        tw = TWIST
        j0, j1, j2 = bt[b, tw + 3], bt[b, tw + 4], bt[b, tw + 5]
        p0, p1, p2, p3 = p[b, 0], p[b, 1], p[b, 2], p[b, 3]
        s0, s1, s2 = src[j0], src[j1], src[j2]
        if mode == 0:
            out[j0], out[j1], out[j2] = rotate(p0, p1, p2, p3, s0, s1, s2)
            continue
        if mode == 1:
            out[j0], out[j1], out[j2] = rotate(p0, -p1, -p2, -p3, s0, s1, s2)
            continue
        c0, c1, c2 = cross(W[bt[b, tw]], W[bt[b, tw + 1]], W[bt[b, tw + 2]], W[j0], W[j1], W[j2])
        if mode == 2:
            r0, r1, r2 = rotate(p0, -p1, -p2, -p3, s0, s1, s2)
            out[j0], out[j1], out[j2] = r0 - c0, r1 - c1, r2 - c2
        else:
            out[j0], out[j1], out[j2] = rotate(p0, p1, p2, p3, s0 + c0, s1 + c1, s2 + c2)


@njit(cache=True, error_model="numpy", inline="always")
def engine_velocity(V, p, bt, ve):
    """ve = V, but on the ENGINE bodies the body-frame twist (v_lin = Rᵀṙ, ω) over the
    body's six twist entries (V has (ω, ṙ) there)."""
    for j in range(V.shape[0]):
        ve[j] = V[j]
    for b in range(bt.shape[0]):
        if bt[b, ENGINE] != 1:
            continue
        tw = TWIST
        i0, i1, i2, j0, j1, j2 = bt[b, tw], bt[b, tw + 1], bt[b, tw + 2], bt[b, tw + 3], bt[b, tw + 4], bt[b, tw + 5]
        x0, x1, x2 = rotate(p[b, 0], -p[b, 1], -p[b, 2], -p[b, 3], V[j0], V[j1], V[j2])
        ve[i0], ve[i1], ve[i2] = x0, x1, x2
        ve[j0], ve[j1], ve[j2] = V[i0], V[i1], V[i2]


@njit(cache=True, error_model="numpy", inline="always")
def stage_derivative(Vd, W, p, bt, KW, KX, i, ve, n_engine):
    """KW[i] = Ẇ from the model's V̇ (on ENGINE bodies the engine's (v̇_lin, ω̇) at the
    engine velocity ``ve``: ω̇, and r̈ = R (v̇_lin + ω × v_lin) on SO(3)×R³, v̇_lin itself on
    SE(3)); True when KX[i] and KW[i] are finite."""
    row = KW[i]
    convert(2, Vd, W, p, bt, row)
    if n_engine > 0:
        for b in range(bt.shape[0]):
            if bt[b, ENGINE] != 1:
                continue
            tw = TWIST
            i0, i1, i2 = bt[b, tw], bt[b, tw + 1], bt[b, tw + 2]
            j0, j1, j2 = bt[b, tw + 3], bt[b, tw + 4], bt[b, tw + 5]
            a0, a1, a2 = Vd[i0], Vd[i1], Vd[i2]
            row[i0], row[i1], row[i2] = Vd[j0], Vd[j1], Vd[j2]
            if bt[b, SE3] == 1:
                row[j0], row[j1], row[j2] = a0, a1, a2
            else:
                c0, c1, c2 = cross(W[i0], W[i1], W[i2], ve[i0], ve[i1], ve[i2])
                row[j0], row[j1], row[j2] = rotate(p[b, 0], p[b, 1], p[b, 2], p[b, 3], a0 + c0, a1 + c1, a2 + c2)
    ok = True
    for j in range(row.shape[0]):
        if not math.isfinite(row[j]):
            ok = False
    for j in range(KX.shape[1]):
        if not math.isfinite(KX[i, j]):
            ok = False
    return ok


def pack_tables(bt, vt, off):
    """The int64 inputs of :func:`stage` and :func:`step_end` as one array (one argument
    instead of three: a numba call costs ~50 ns per argument): off, the row counts of bt
    and vt, then bt and vt row by row."""
    return np.ascontiguousarray(np.concatenate([off, [bt.shape[0], vt.shape[0]], bt.ravel(), vt.ravel()]),
                                np.int64)


@njit(cache=True, error_model="numpy", inline="always")
def tables(I):
    """(bt, vt, off) of an array made by :func:`pack_tables` (views)."""
    nb, nv = I[NOFF], I[NOFF + 1]
    o = NOFF + 2 + nb * NCOL
    return matrix(I[NOFF + 2:], nb, NCOL), matrix(I[o:], nv, 4), I[:NOFF]


_V, _VC, _MC, _IC, _IMC = "float64[:]", "float64[::1]", "float64[:, ::1]", "int64[::1]", "int64[:, ::1]"


@njit(f"void({_MC}, {_MC}, {_MC}, {_VC}, {_IMC}, {_IMC}, {_VC}, {_MC}, {_MC}, {_MC})", cache=True,
      error_model="numpy")
def dense_states(w, FX, FW, W0, bt, vt, qk, pk, Q, V):
    """Rows r of (Q, V) at the local states X = Σ_i w[r, i] FX[i], W = W0 + Σ_i w[r, i] FW[i]:
    τ(q_k, X) and the model velocity of W for every body — a step's dense output at many
    times in one call. Entries no body or vector row writes keep q_k and W."""
    nX, nv = FX.shape[1], FW.shape[1]
    X, W, Xd, p = np.empty(nX), np.empty(nv), np.empty(nX), np.empty((bt.shape[0], 4))
    for r in range(w.shape[0]):
        for j in range(nX):
            X[j] = 0.0
        for j in range(nv):
            W[j] = 0.0
        for i in range(w.shape[1]):
            wi = w[r, i]
            for j in range(nX):
                X[j] += wi * FX[i, j]
            for j in range(nv):
                W[j] += wi * FW[i, j]
        for j in range(nv):
            W[j] += W0[j]
        Q[r, :] = qk
        V[r, :] = W
        tau_state(False, X, W, bt, vt, qk, pk, Q[r], V[r], Xd, p, False)


# explicit signatures (V̇ and the weights of any layout; the buffers C-contiguous): one
# compilation each, and an entry point without type dispatch for the steppers' own buffers
@njit(f"float64({_V}, {_MC}, {_MC}, {_V}, int64, float64, {_VC}, {_IC})", cache=True, error_model="numpy")
def stage(Vd, KX, KW, a, i, h, w, I):
    """One fused call per stage: when ``Vd`` is not empty, the stage derivative of stage
    i - 1 from the model's V̇ (KW[i-1]; -1.0 is returned when KX[i-1] or KW[i-1] is not
    finite); then, when ``a`` is not empty, the state of stage i (X, W, q, V, p in the work
    array, KX[i] = dψ⁻¹_{-X}(W)), returning the largest chart usage |x|/limit. ``I``: the
    body and vector tables and the work array's offsets (:func:`pack_tables`)."""
    bt, vt, off = tables(I)
    X, W, q, V, W0, qk, pk, p = views(w, off)
    ve = w[off[OVE]:off[OVE] + off[NV_]]
    if Vd.shape[0] > 0:
        if not stage_derivative(Vd, W, p, bt, KW, KX, i - 1, ve, off[NE_]):
            return -1.0
    if a.shape[0] == 0:
        return 0.0
    Xd = KX[i] if i < KX.shape[0] else w[off[OXD]:off[OXD] + off[NX_]]
    c = stage_state(KX, KW, a, i, h, W0, X, W, bt, vt, qk, pk, q, V, Xd, p)
    if off[NE_] > 0:
        engine_velocity(V, p, bt, ve)
    return c


@njit(cache=True, error_model="numpy")
def error_sums(KX, KW, e5, e3, X1, W1, W0, rtol, atol):
    """Σ (Σ_i e5_i K_i / sc)² and the same with e3, over y = (X, W), with the scale
    sc = atol + rtol·max(|y_k|, |y_{k+1}|) (X_k = 0)."""
    s5, s3 = 0.0, 0.0
    ns = e5.shape[0]
    for j in range(X1.shape[0]):
        a5, a3 = 0.0, 0.0
        for i in range(ns):
            a5 += e5[i] * KX[i, j]
            a3 += e3[i] * KX[i, j]
        sc = atol + rtol * abs(X1[j])
        s5 += (a5 / sc) ** 2
        s3 += (a3 / sc) ** 2
    for j in range(W1.shape[0]):
        a5, a3 = 0.0, 0.0
        for i in range(ns):
            a5 += e5[i] * KW[i, j]
            a3 += e3[i] * KW[i, j]
        sc = atol + rtol * max(abs(W0[j]), abs(W1[j]))
        s5 += (a5 / sc) ** 2
        s3 += (a3 / sc) ** 2
    return s5, s3


@njit(f"UniTuple(float64, 6)({_V}, {_MC}, {_MC}, {_MC}, int64, float64, {_VC}, {_IC}, float64, float64)",
      cache=True, error_model="numpy")
def step_end(Vd, KX, KW, T, i, h, w, I, rtol, atol):
    """The end of an embedded pair's step in one call: the derivative of stage i - 1 from
    the model's V̇ (when ``Vd`` is not empty), the end state with the weights b = T[0] (X1,
    W1, q1, V1, p in the work array), the error sums of the weights e5 = T[1], e3 = T[2]
    (:func:`error_sums`) and, when T has 5 rows, the stiffness test's sums (the error sums
    of T[3], T[4] with unit scale). Returns (status, s5, s3, num, den, sq): status -1.0 when
    the last stage's derivative is not finite (nothing else computed), sq = |q1|² + |V1|²
    (not finite when q1 or V1 is not)."""
    bt, vt, off = tables(I)
    X, W, q, V, W0, qk, pk, p = views(w, off)
    if Vd.shape[0] > 0:
        if not stage_derivative(Vd, W, p, bt, KW, KX, i - 1, w[off[OVE]:off[OVE] + off[NV_]], off[NE_]):
            return -1.0, 0.0, 0.0, 0.0, 0.0, 0.0
    b = T[0]
    stage_state(KX, KW, b, b.shape[0], h, W0, X, W, bt, vt, qk, pk, q, V, w[off[OXD]:off[OXD] + off[NX_]], p)
    s5, s3 = error_sums(KX, KW, T[1], T[2], X, W, W0, rtol, atol)
    num, den = 0.0, 0.0
    if T.shape[0] > 3:
        num, den = error_sums(KX, KW, T[3], T[4], KX[0], KW[0], KW[0], 0.0, 1.0)
    sq = 0.0
    for j in range(q.shape[0]):
        sq += q[j] * q[j]
    for j in range(V.shape[0]):
        sq += V[j] * V[j]
    return 0.0, s5, s3, num, den, sq
