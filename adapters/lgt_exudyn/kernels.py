"""Compiled kernels of :class:`lgt_exudyn.ExudynModel`'s f (numba; imported only when used).

ExudynModel maps Exudyn's ODE2 quantities to twists through q̇_e = H(q) V. H is block
sparse, and stored as

* identity pairs (q row, V column): rigid positions (ṙ), RotVecLG rotations (ω) and every
  vector-space coordinate;
* rotation blocks: for each EP / Rxyz node the 4 x 3 / 3 x 3 block B(q) of ṗ = B(p) ω /
  θ̇ = G(θ)⁻¹ ω (q rows of the node's rotation, V columns iv..iv+2),

so every product with H or Hᵀ is a copy loop plus a loop over small blocks (no dense H):
H V (Exudyn's velocities), Hᵀ x (forces, rows of C_q, rows of Hᵀ M).

A model is packed once (:func:`pack`) into an int64 table ``I`` (header, node table for τ,
vector-space table, identity pairs, rotation blocks, the diagonal blocks of M̄, an integer
scratch) and a float64 work array ``W`` (reference coordinates, the moved state, the
rotation blocks at the last q, M̄ and M̄⁻¹ per diagonal block, the buffers of the
constrained solve). Every kernel takes ``(I, W, ...)``: few arguments, since numba's
dispatch costs ≈ 0.1 µs per argument.

Kernels (one explicit signature each — numba compiles them afresh in every CI run, so
related cases share a kernel; arrays are float64 C-contiguous, M, Mbar, C, A 2-D):

* :func:`write` (I, W, q, V, eps, qpos, qvel) -> h: eps = 0: qpos = q - ref, qvel = H(q) V
  (``qpos``/``qvel`` may be Exudyn's own views ``GetODE2Coordinates(copy=False)``/``_t``);
  eps ≠ 0: q_m = τ(q, hV), h = eps / max(1, |V|∞), on SO(3)xR³ (exp) into ``W`` (view
  ``P.qm``), qpos = q_m - ref, qvel = H(q_m) V — one γ evaluation's state;
* :func:`forces` (I, W, q, V, Q, M, Qbar, Mbar): M 0 x 0: Q̄ = Hᵀ Q - M̄ H⁺ Ḣ V with the
  constant M̄ packed; M = Exudyn's mass matrix: Q̄ = Hᵀ(Q - M Ḣ V), Mbar = Hᵀ M H;
* :func:`constraint_matrix` (I, W, q, C, rows, A): A = C[rows, :n2] H (C may be Exudyn's
  whole system Jacobian, ``rows`` then the AE rows kept);
* :func:`gamma_fd` (rp, rm, rows, eps, gam): gam = (rp[rows] - rm[rows]) / (2 eps);
* :func:`solve` (I, W, Mbar, A, Qbar, gam, Vd) -> flag: V̇ = M̄⁻¹(Q̄ - Aᵀλ),
  (A M̄⁻¹ Aᵀ) λ = A M̄⁻¹ Q̄ + γ (so A V̇ = -γ; ``solve_kkt(M̄, A, Q̄, -γ)``), Cholesky of
  A M̄⁻¹ Aᵀ in the kernel; M̄⁻¹ from the packed diagonal blocks of the constant M̄ (Mbar
  0 x 0) or a dense Mbar factorized in the kernel.

* :func:`free_rhs` (I, W, q, V, Q, Qbar, Vd): :func:`forces` then :func:`solve` for an
  unconstrained model with a constant M̄ (one call instead of two; :func:`plain_f`).

Flags of :func:`solve`: 0 done; 1 the Schur complement is not (well) positive definite
(redundant constraints): W holds A M̄⁻¹ Aᵀ, its right-hand side, M̄⁻¹ Q̄ and M̄⁻¹ Aᵀ
(:func:`buffers`), finish with :func:`solve_fallback`; 2 Mbar is not positive definite.

:func:`f_compiled` shows the wiring: one ExudynModel.f from these kernels and Exudyn's calls.
The numpy reference is ExudynModel's own methods (H, rates_from_twist, _moved, _evaluate,
solve_kkt); tests/test_exudyn_kernels.py holds them equal (1e-13). Plain loops:
``NUMBA_DISABLE_JIT=1`` runs the same source interpreted.
"""
import math

import numpy as np
from numba import njit

from lgt_bridge.kernels.rotations import from_quat, qmul, rotvec_minus_one, to_quat
from lgt_bridge.kernels import guard_cache

guard_cache(__file__)

#: rotations.to_quat codes of Exudyn's rotation nodes
NODE_CODE = {"RigidBodyEP": 0, "RigidBodyRotVecLG": 2, "RigidBodyRxyz": 3}
#: kinds of rotation blocks: Euler parameters, Tait-Bryan xyz angles
G_EP, G_RXYZ = 1, 2
#: the Schur complement's Cholesky factor counts as singular below this relative pivot
#: (solve_schur: sqrt(SCHUR_RCOND))
PIVOT_TOL = math.sqrt(1e-11)

# header of I: sizes, then offsets into I (O*) and into W (W*)
(NB, NVEC, NID, NRG, NV, N2, NCOMP, NCMAX, ONODE, OVEC, OID, ORG, OCOFF, OCIDX, OCF, OISCR,
 WREF, WQM, WB, WT, WMIV, WMB, WMI, WY, WS, WL, WR, WDM, WZ) = range(29)
NH = 32
# node table row (τ): code, nrot, pos (3), rot (4, -1 unused), iv
NODE_W = 10
# rotation group row (H on EP / Rxyz rotations): kind, nrows, q rows (4, -1 unused), first V column
RG_W = 7


class Pack:
    """The packed tables of one ExudynModel: ``I``, ``W`` and named views of ``W``."""

    def __repr__(self):
        return (f"Pack(nv={int(self.I[NV])}, n2={int(self.I[N2])}, blocks of M̄={int(self.I[NCOMP])}, "
                f"constraints ≤ {int(self.I[NCMAX])})")


def _components(Mb):
    """Connected components of the nonzero pattern of M̄: (members, sizes), the members of
    each component sorted and one component after another, ordered by their first index.
    Every index takes the smallest label among its neighbours until nothing changes, so
    each ends with its component's first index."""
    i, j = np.nonzero(Mb)
    lab = np.arange(Mb.shape[0])
    while True:
        new = lab.copy()
        np.minimum.at(new, i, lab[j])
        new = new[new]                          # new[k] ≤ k lies in k's component: jump there
        if (new == lab).all():
            break
        lab = new
    order = np.argsort(lab, kind="stable")
    return order.astype(np.int64), np.unique(lab, return_counts=True)[1].astype(np.int64)


def _flat(rows):
    return np.array(rows, np.int64).reshape(-1) if rows else np.zeros(0, np.int64)


def pack(model, nc_max=None, views=True):
    """Tables and work buffers of an ExudynModel (reads kinds, _vq, _vv, ref, _Mbar, nv, n2;
    also sd, ae_keep and _ae0 when present, for :func:`f_compiled`).

    ``nc_max``: the largest number of constraint rows a solve will see (default the model's
    ``n_constraints``). ``views``: also keep Exudyn's writable coordinate views as ``P.qpos``
    and ``P.qvel`` (valid until the system is assembled again)."""
    nv, n2 = int(model.nv), int(model.n2)
    vq = [int(i) for i in model._vq]
    vv = [int(i) for i in model._vv]
    nodes, ident, rgroups = [], [], []
    for typ, idx, iv in model.kinds:
        idx, iv = [int(i) for i in idx], int(iv)
        nrot = len(idx) - 3
        rot = idx[3:] + [-1] * (4 - nrot)
        nodes.append([NODE_CODE[typ], nrot, *idx[:3], *rot, iv])
        ident += [[idx[k], iv + 3 + k] for k in range(3)]
        if typ == "RigidBodyRotVecLG":
            ident += [[idx[3 + k], iv + k] for k in range(3)]
        else:
            rgroups.append([G_EP if typ == "RigidBodyEP" else G_RXYZ, nrot, *rot, iv])
    ident += [[a, b] for a, b in zip(vq, vv)]
    Mb = getattr(model, "_Mbar", None)
    cidx, sizes = _components(Mb) if Mb is not None else (np.zeros(0, np.int64), np.zeros(0, np.int64))
    if nc_max is None:
        nc_max = int(getattr(model, "n_constraints", getattr(model, "nae", 0)))
    nc = int(nc_max)
    coff = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    cf = np.concatenate([[0], np.cumsum(sizes ** 2)]).astype(np.int64)

    # I: header, nodes, vectors (iq, iv), identity pairs (iq, iv), rotation groups, component
    # offsets, members, float offsets, integer scratch
    parts = [np.zeros(NH, np.int64), _flat(nodes), _flat([[a, b] for a, b in zip(vq, vv)]),
             _flat(ident), _flat(rgroups), coff, cidx, cf, np.zeros(max(nc, 1), np.int64)]
    off = np.concatenate([[0], np.cumsum([len(p) for p in parts])])
    I = np.concatenate(parts).astype(np.int64)
    I[NB], I[NVEC], I[NID], I[NRG], I[NV], I[N2], I[NCOMP], I[NCMAX] = (
        len(nodes), len(vq), len(ident), len(rgroups), nv, n2, len(sizes), nc)
    I[ONODE:OISCR + 1] = off[1:9]

    # W: ref, q_m, rotation blocks, scratch T, M̄⁻¹Q̄, M̄ blocks, M̄⁻¹ blocks, Y, S, L, r,
    # dense M̄ factor, z and u (n2 each)
    dense = Mb is None
    wsizes = [n2, n2, 12 * len(rgroups), max(nv, 12), nv, int(cf[-1]), int(cf[-1]), nc * nv, nc * nc, nc * nc,
              nc, nv * nv if dense else 0, 2 * n2]
    woff = np.concatenate([[0], np.cumsum(wsizes)]).astype(np.int64)
    I[WREF:WZ + 1] = woff[:-1]
    W = np.zeros(int(woff[-1]))
    W[woff[0]:woff[0] + n2] = np.asarray(model.ref, float)
    for size in np.unique(sizes):         # components of one size are inverted in one call
        cs = np.flatnonzero(sizes == size)
        idx = cidx[coff[cs][:, None] + np.arange(size)]                  # (k, size)
        blks = Mb[idx[:, :, None], idx[:, None, :]]                       # (k, size, size)
        inv = np.linalg.inv(blks)
        inv = 0.5 * (inv + np.swapaxes(inv, 1, 2))
        at = (cf[cs][:, None] + np.arange(size * size)[None, :]).reshape(-1)
        W[woff[5] + at] = blks.reshape(-1)
        W[woff[6] + at] = inv.reshape(-1)

    P = Pack()
    P.I, P.W, P.nv, P.n2, P.nc_max, P.constant_mass = I, W, nv, n2, nc, not dense
    P.ref = W[woff[0]:woff[0] + n2]
    P.qm = W[woff[1]:woff[1] + n2]
    P.Qbar = np.zeros(nv)
    P.Mbar = np.zeros((nv, nv)) if dense else None
    P.A, P.gam = np.zeros((nc, nv)), np.zeros(nc)
    P.A0, P.gam0 = np.zeros((0, nv)), np.zeros(0)          # the unconstrained solve's arguments
    P.empty = np.zeros((0, 0))                               # M, Mbar of the constant-M̄ case
    sd = getattr(model, "sd", None)
    if views and sd is not None:
        P.qpos = sd.GetODE2Coordinates(copy=False)
        P.qvel = sd.GetODE2Coordinates_t(copy=False)
    rows = getattr(model, "ae_keep", None)
    if rows is not None and hasattr(model, "_ae0"):
        P.rows = np.asarray(rows, np.int64) + int(model._ae0)    # kept AE rows in Exudyn's system vectors
    return P


_V = "float64[::1]"
_M = "float64[:, ::1]"
_I = "int64[::1]"


# ---------------------------------------------------------------------------- H and Hᵀ
@njit(cache=True, error_model="numpy")
def _blocks(I, W, q):
    """The 4 x 3 block B (row-major) of every EP / Rxyz rotation at q into W[WB:]."""
    og, wb = I[ORG], I[WB]
    for g in range(I[NRG]):
        o, b = og + RG_W * g, wb + 12 * g
        if I[o] == G_EP:
            p0, p1, p2, p3 = q[I[o + 2]], q[I[o + 3]], q[I[o + 4]], q[I[o + 5]]
            # ṗ = B ω, B = [-½ pᵥᵀ; ½ (p0 I + p̃ᵥ)]
            W[b], W[b + 1], W[b + 2] = -0.5 * p1, -0.5 * p2, -0.5 * p3
            W[b + 3], W[b + 4], W[b + 5] = 0.5 * p0, 0.5 * -p3, 0.5 * p2
            W[b + 6], W[b + 7], W[b + 8] = 0.5 * p3, 0.5 * p0, 0.5 * -p1
            W[b + 9], W[b + 10], W[b + 11] = 0.5 * -p2, 0.5 * p1, 0.5 * p0
        else:
            t1, t2 = q[I[o + 3]], q[I[o + 4]]
            c1, s1, c2, s2 = math.cos(t1), math.sin(t1), math.cos(t2), math.sin(t2)
            # θ̇ = G(θ)⁻¹ ω
            W[b], W[b + 1], W[b + 2] = c2 / c1, -s2 / c1, 0.0
            W[b + 3], W[b + 4], W[b + 5] = s2, c2, 0.0
            W[b + 6], W[b + 7], W[b + 8] = -s1 * c2 / c1, s1 * s2 / c1, 1.0


@njit(cache=True, error_model="numpy")
def _rates(I, W, V, qvel):
    """qvel = H V (the rotation blocks in W)."""
    oi = I[OID]
    for k in range(I[NID]):
        qvel[I[oi + 2 * k]] = V[I[oi + 2 * k + 1]]
    og, wb = I[ORG], I[WB]
    for g in range(I[NRG]):
        o, b = og + RG_W * g, wb + 12 * g
        iv = I[o + 6]
        w0, w1, w2 = V[iv], V[iv + 1], V[iv + 2]
        for i in range(I[o + 1]):
            qvel[I[o + 2 + i]] = W[b + 3 * i] * w0 + W[b + 3 * i + 1] * w1 + W[b + 3 * i + 2] * w2


@njit(cache=True, error_model="numpy")
def _Ht(I, W, x, out):
    """out = Hᵀ x (x on q rows, out on V columns; the rotation blocks in W)."""
    oi = I[OID]
    for k in range(I[NID]):
        out[I[oi + 2 * k + 1]] = x[I[oi + 2 * k]]
    og, wb = I[ORG], I[WB]
    for g in range(I[NRG]):
        o, b = og + RG_W * g, wb + 12 * g
        iv = I[o + 6]
        for k in range(3):
            s = 0.0
            for i in range(I[o + 1]):
                s += W[b + 3 * i + k] * x[I[o + 2 + i]]
            out[iv + k] = s


@njit(cache=True, error_model="numpy")
def _rxyz_rates_dot(I, o, q, V):
    """Rxyz group at row o of I: (cos, sin of θ1, θ2, Ḣ V) with θ̇ = G⁻¹ω (ExudynModel.Hdot_V)."""
    iv = I[o + 6]
    t1, t2 = q[I[o + 3]], q[I[o + 4]]
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
@njit(f"float64({_I}, {_V}, {_V}, {_V}, float64, {_V}, {_V})", cache=True, error_model="numpy")
def write(I, W, q, V, eps, qpos, qvel):
    """eps = 0: qpos = q - ref, qvel = H(q) V (Exudyn's coordinates and velocities);
    returns 0.

    eps ≠ 0: the moved state of one γ difference, q_m = τ(q, hV) on SO(3)xR³ with the exp
    chart (ExudynModel._moved) and h = eps / max(1, max|V|) (the step of
    ExudynModel._gamma for eps = ±1e-5), into W's q_m block (``P.qm``); qpos = q_m - ref,
    qvel = H(q_m) V; returns h."""
    n2, wr, wm = I[N2], I[WREF], I[WQM]
    if q.shape[0] != n2 or V.shape[0] != I[NV] or qpos.shape[0] != n2 or qvel.shape[0] != n2:
        raise ValueError("write: q, qpos, qvel need n2 entries and V nv entries")
    if eps == 0.0:
        for k in range(n2):
            qpos[k] = q[k] - W[wr + k]
        _blocks(I, W, q)
        _rates(I, W, V, qvel)
        return 0.0
    vmax = 1.0
    for k in range(V.shape[0]):
        vmax = max(vmax, abs(V[k]))
    eps = eps / vmax
    qm = W[wm:wm + n2]
    on = I[ONODE]
    for b in range(I[NB]):
        o = on + NODE_W * b
        code, nrot, iv = I[o], I[o + 1], I[o + 9]
        for c in range(3):
            qm[I[o + 2 + c]] = q[I[o + 2 + c]] + eps * V[iv + 3 + c]
        r0, r1, r2 = q[I[o + 5]], q[I[o + 6]], q[I[o + 7]]
        r3 = q[I[o + 8]] if nrot == 4 else 0.0
        k0, k1, k2, k3 = to_quat(code, r0, r1, r2, r3)
        d0, d1, d2, d3, phi, sh = rotvec_minus_one(eps * V[iv], eps * V[iv + 1], eps * V[iv + 2])
        m0, m1, m2, m3 = qmul(k0, k1, k2, k3, d0, d1, d2, d3)
        o0, o1, o2, o3 = from_quat(code, k0 + m0, k1 + m1, k2 + m2, k3 + m3, r0, r1, r2, r3)
        qm[I[o + 5]], qm[I[o + 6]], qm[I[o + 7]] = o0, o1, o2
        if nrot == 4:
            qm[I[o + 8]] = o3
    ov = I[OVEC]
    for k in range(I[NVEC]):
        iq, iv = I[ov + 2 * k], I[ov + 2 * k + 1]
        qm[iq] = q[iq] + eps * V[iv]
    for k in range(n2):
        qpos[k] = qm[k] - W[wr + k]
    _blocks(I, W, qm)
    _rates(I, W, V, qvel)
    return eps


# ---------------------------------------------------------------------------- forces
@njit(f"void({_I}, {_V}, {_V}, {_V}, {_V}, {_M}, {_V}, {_M})", cache=True, error_model="numpy")
def forces(I, W, q, V, Q, M, Qbar, Mbar):
    """Generalized forces in twist coordinates. Q: Exudyn's residual (its first n2 entries
    are read).

    M with 0 rows (the constant M̄ packed): Q̄ = Hᵀ Q - M̄ H⁺ Ḣ V (H⁺ Ḣ V is G(θ) Ḣ V on
    Rxyz rotations, 0 elsewhere); Mbar is not touched. M = Exudyn's dense n2 x n2 mass
    matrix: Q̄ = Hᵀ(Q - M Ḣ V) and Mbar = Hᵀ M H (row by row: M̄[p] = Hᵀ (Hᵀ M)[p])."""
    n2, nv = I[N2], I[NV]
    const = M.shape[0] == 0
    if (q.shape[0] != n2 or V.shape[0] != nv or Qbar.shape[0] != nv or Q.shape[0] < n2 or not (
            const or (M.shape[0] == n2 and M.shape[1] == n2 and Mbar.shape[0] == nv and Mbar.shape[1] == nv))):
        raise ValueError("forces: wrong sizes (q n2, Q ≥ n2, V and Qbar nv; M 0 x 0 or n2 x n2 with Mbar nv x nv)")
    if const and I[NCOMP] == 0 and nv > 0:
        raise ValueError("forces: no constant mass matrix packed; pass Exudyn's M")
    _blocks(I, W, q)
    og, wb = I[ORG], I[WB]
    if const:
        _Ht(I, W, Q, Qbar)
        y = W[I[WT]:I[WT] + nv]
        any_y = False
        for g in range(I[NRG]):
            o = og + RG_W * g
            if I[o] == G_RXYZ:
                if not any_y:
                    for k in range(nv):
                        y[k] = 0.0
                    any_y = True
                c1, s1, c2, s2, da, db, dc = _rxyz_rates_dot(I, o, q, V)
                iv = I[o + 6]
                y[iv] = c1 * c2 * da + s2 * db
                y[iv + 1] = -c1 * s2 * da + c2 * db
                y[iv + 2] = s1 * da + dc
        if not any_y:
            return
        co, ci, cf, wmb = I[OCOFF], I[OCIDX], I[OCF], I[WMB]
        for c in range(I[NCOMP]):
            a, e = I[co + c], I[co + c + 1]
            n = e - a
            nz = False
            for j in range(n):
                if y[I[ci + a + j]] != 0.0:
                    nz = True
            if not nz:
                continue
            base = wmb + I[cf + c]
            for i in range(n):
                s = 0.0
                for j in range(n):
                    s += W[base + n * i + j] * y[I[ci + a + j]]
                Qbar[I[ci + a + i]] -= s
        return
    z = W[I[WZ]:I[WZ] + n2]
    u = W[I[WZ] + n2:I[WZ] + 2 * n2]
    for k in range(n2):
        z[k] = Q[k]
    for g in range(I[NRG]):
        o = og + RG_W * g
        if I[o] == G_EP:
            iv = I[o + 6]
            w0, w1, w2 = V[iv], V[iv + 1], V[iv + 2]
            f = -0.25 * (w0 * w0 + w1 * w1 + w2 * w2)
            h0, h1, h2, h3 = f * q[I[o + 2]], f * q[I[o + 3]], f * q[I[o + 4]], f * q[I[o + 5]]
        else:
            c1, s1, c2, s2, h0, h1, h2 = _rxyz_rates_dot(I, o, q, V)
            h3 = 0.0
        for r in range(n2):
            s = M[r, I[o + 2]] * h0 + M[r, I[o + 3]] * h1 + M[r, I[o + 4]] * h2
            if I[o + 1] == 4:
                s += M[r, I[o + 5]] * h3
            z[r] -= s
    _Ht(I, W, z, Qbar)
    oi = I[OID]
    for k in range(I[NID]):
        _Ht(I, W, M[I[oi + 2 * k]], Mbar[I[oi + 2 * k + 1]])
    for g in range(I[NRG]):
        o, b = og + RG_W * g, wb + 12 * g
        for a in range(3):
            for r in range(n2):
                s = 0.0
                for i in range(I[o + 1]):
                    s += W[b + 3 * i + a] * M[I[o + 2 + i], r]
                u[r] = s
            _Ht(I, W, u, Mbar[I[o + 6] + a])


# ---------------------------------------------------------------------------- constraints
@njit(f"void({_I}, {_V}, {_V}, {_M}, {_I}, {_M})", cache=True, error_model="numpy")
def constraint_matrix(I, W, q, C, rows, A):
    """A[i] = C[rows[i], :n2] H(q): the constraint Jacobian in twist coordinates."""
    nc, nv = rows.shape[0], I[NV]
    if q.shape[0] != I[N2] or A.shape[0] != nc or A.shape[1] != nv or C.shape[1] < I[N2]:
        raise ValueError("constraint_matrix: A must be len(rows) x nv, C have at least n2 columns")
    _blocks(I, W, q)
    for i in range(nc):
        _Ht(I, W, C[rows[i]], A[i])


@njit(f"void({_V}, {_V}, {_I}, float64, {_V})", cache=True, error_model="numpy")
def gamma_fd(rp, rm, rows, eps, gam):
    """gam = (rp[rows] - rm[rows]) / (2 eps): γ from the two velocity-level residuals."""
    d = 2.0 * eps
    for i in range(rows.shape[0]):
        gam[i] = (rp[rows[i]] - rm[rows[i]]) / d


# ---------------------------------------------------------------------------- solves
@njit(cache=True, error_model="numpy")
def _cholesky(W, s0, l0, n):
    """L Lᵀ = S for S = W[s0:] and L = W[l0:] (n x n, row-major; S's lower triangle read;
    s0 = l0 factorizes in place). Returns (ok, smallest, largest diagonal entry of L); not
    ok when a pivot is not positive."""
    dmax, dmin = 0.0, np.inf
    for j in range(n):
        rj = l0 + n * j
        s = W[s0 + n * j + j]
        for k in range(j):
            s -= W[rj + k] * W[rj + k]
        if not s > 0.0:
            return False, 0.0, dmax
        d = math.sqrt(s)
        W[rj + j] = d
        dmax, dmin = max(dmax, d), min(dmin, d)
        for i in range(j + 1, n):
            ri = l0 + n * i
            s = W[s0 + n * i + j]
            for k in range(j):
                s -= W[ri + k] * W[rj + k]
            W[ri + j] = s / d
    return True, dmin, dmax


@njit(cache=True, error_model="numpy")
def _chol_solve(W, l0, n, x0):
    """W[x0:x0+n] = (L Lᵀ)⁻¹ W[x0:x0+n] in place, L = W[l0:] (n x n lower, row-major)."""
    for i in range(n):
        s = W[x0 + i]
        for k in range(i):
            s -= W[l0 + n * i + k] * W[x0 + k]
        W[x0 + i] = s / W[l0 + n * i + i]
    for i in range(n - 1, -1, -1):
        s = W[x0 + i]
        for k in range(i + 1, n):
            s -= W[l0 + n * k + i] * W[x0 + k]
        W[x0 + i] = s / W[l0 + n * i + i]


@njit(f"int64({_I}, {_V}, {_M}, {_M}, {_V}, {_V}, {_V})", cache=True, error_model="numpy")
def solve(I, W, Mbar, A, Qbar, gam, Vd):
    """V̇ = M̄⁻¹(Q̄ - Aᵀλ), (A M̄⁻¹ Aᵀ) λ = A M̄⁻¹ Q̄ + γ (A V̇ = -γ, as
    ``solve_kkt(M̄, A, Q̄, -γ)``); A may have 0 rows (V̇ = M̄⁻¹ Q̄).

    Mbar with 0 rows: M̄⁻¹ from the packed diagonal blocks of the constant M̄ (rows of A
    are multiplied only on the blocks they touch); else Mbar (nv x nv) is factorized here.
    Returns 0; 1 when the Cholesky factor of A M̄⁻¹ Aᵀ has a non-positive or relatively
    small (PIVOT_TOL) pivot — finish with :func:`solve_fallback`; 2 when Mbar is not
    positive definite."""
    nv, nc = I[NV], A.shape[0]
    const = Mbar.shape[0] == 0
    if (A.shape[1] != nv or Qbar.shape[0] != nv or Vd.shape[0] != nv or gam.shape[0] != nc
            or nc > I[NCMAX] or nc > nv):
        raise ValueError("solve: A must be nc x nv with nc ≤ the packed nc_max, Qbar and Vd nv, gam nc")
    if const and I[NCOMP] == 0 and nv > 0:
        raise ValueError("solve: no constant mass matrix packed; pass M̄")
    if not const and (Mbar.shape[0] != nv or Mbar.shape[1] != nv or I[WZ] - I[WDM] != nv * nv):
        raise ValueError("solve: Mbar must be nv x nv, and the model packed without a constant M̄")
    wm, wy, ws, wr = I[WMIV], I[WY], I[WS], I[WR]
    for i in range(nc * nc):
        W[ws + i] = 0.0
    if const:
        co, ci, cf, wmi = I[OCOFF], I[OCIDX], I[OCF], I[WMI]
        touch = I[OISCR]
        for c in range(I[NCOMP]):
            a, e = I[co + c], I[co + c + 1]
            n = e - a
            base = wmi + I[cf + c]
            for i in range(n):
                s = 0.0
                for j in range(n):
                    s += W[base + n * i + j] * Qbar[I[ci + a + j]]
                W[wm + I[ci + a + i]] = s
            # rows of A touching this block: Y[k, block] = M̄_c⁻¹ A[k, block], S += A Y on them
            nt = 0
            for k in range(nc):
                nz = False
                for j in range(n):
                    if A[k, I[ci + a + j]] != 0.0:
                        nz = True
                        break
                if nz:
                    I[touch + nt] = k
                    nt += 1
                else:
                    for j in range(n):
                        W[wy + nv * k + I[ci + a + j]] = 0.0
            for u in range(nt):
                k = I[touch + u]
                for i in range(n):
                    s = 0.0
                    for j in range(n):
                        s += W[base + n * i + j] * A[k, I[ci + a + j]]
                    W[wy + nv * k + I[ci + a + i]] = s
            for u in range(nt):
                i = I[touch + u]
                for v in range(u + 1):       # the touch list runs in row order: i ≥ k
                    k = I[touch + v]
                    s = 0.0
                    for j in range(n):
                        m = I[ci + a + j]
                        s += A[i, m] * W[wy + nv * k + m]
                    W[ws + nc * i + k] += s
    else:
        wd = I[WDM]
        for i in range(nv):                 # M̄ into its factor's place, factorized there
            for j in range(nv):
                W[wd + nv * i + j] = Mbar[i, j]
        ok, dmin, dmax = _cholesky(W, wd, wd, nv)
        if not ok:
            return 2
        for j in range(nv):
            W[wm + j] = Qbar[j]
        _chol_solve(W, wd, nv, wm)
        for k in range(nc):
            for j in range(nv):
                W[wy + nv * k + j] = A[k, j]
            _chol_solve(W, wd, nv, wy + nv * k)
        for i in range(nc):
            for k in range(i + 1):
                s = 0.0
                for j in range(nv):
                    s += A[i, j] * W[wy + nv * k + j]
                W[ws + nc * i + k] = s
    if nc == 0:
        for j in range(nv):
            Vd[j] = W[wm + j]
        return 0
    for i in range(nc):
        for k in range(i):
            W[ws + nc * k + i] = W[ws + nc * i + k]
        s = 0.0
        for j in range(nv):
            s += A[i, j] * W[wm + j]
        W[wr + i] = s + gam[i]
    ok, dmin, dmax = _cholesky(W, ws, I[WL], nc)
    if not ok or not dmin > PIVOT_TOL * dmax:
        return 1
    lt = I[WT]                      # λ in the scratch T (≥ nv ≥ nc entries)
    for i in range(nc):
        W[lt + i] = W[wr + i]
    _chol_solve(W, I[WL], nc, lt)
    for j in range(nv):
        Vd[j] = W[wm + j]
    for k in range(nc):
        lk = W[lt + k]
        if lk != 0.0:
            for j in range(nv):
                Vd[j] -= W[wy + nv * k + j] * lk
    return 0


@njit(f"void({_I}, {_V}, {_V}, {_V}, {_V}, {_V}, {_V})", cache=True, error_model="numpy")
def free_rhs(I, W, q, V, Q, Qbar, Vd):
    """:func:`forces` and :func:`solve` of an unconstrained model with its constant M̄ packed,
    in one call: Q̄ from Exudyn's residual Q, then V̇ = M̄⁻¹ Q̄ into Vd."""
    none = np.zeros((0, 0))
    forces(I, W, q, V, Q, none, Qbar, none)
    solve(I, W, none, np.zeros((0, I[NV])), Qbar, np.zeros(0), Vd)


def buffers(P, nc):
    """(S, r, Miv, Y) a solve left in W for nc constraint rows: A M̄⁻¹ Aᵀ, A M̄⁻¹ Q̄ + γ,
    M̄⁻¹ Q̄ and M̄⁻¹ Aᵀ transposed (nc x nv)."""
    I, W, nv = P.I, P.W, P.nv
    return (W[I[WS]:I[WS] + nc * nc].reshape(nc, nc), W[I[WR]:I[WR] + nc],
            W[I[WMIV]:I[WMIV] + nv], W[I[WY]:I[WY] + nc * nv].reshape(nc, nv))


def solve_fallback(P, nc, Vd):
    """After a solve returned 1: λ by lgt_bridge.model.solve_schur (minimum norm for
    redundant constraints) from the buffers the kernel left; V̇ = M̄⁻¹Q̄ - M̄⁻¹Aᵀλ into Vd."""
    from lgt_bridge.model import solve_schur
    S, r, Miv, Y = buffers(P, nc)
    lam = solve_schur(S, r)
    np.subtract(Miv, Y.T @ lam, out=Vd)
    return Vd


# ---------------------------------------------------------------------------- wiring
_EPS_GAMMA = 1e-5


def plain_f(model, P):
    """f of an unconstrained model with a constant M̄ packed (free bodies, trees of vector
    coordinates): :func:`f_compiled`'s calls for that case with everything looked up once,
    as a closure (q, V float64 C-contiguous), forces and solve in one kernel call
    (:func:`free_rhs`). None for any other model."""
    if model.n_constraints or not P.constant_mass or not P.nv:
        return None
    S, mbs, sd = model.solver, model.mbs, model.sd
    compute, residual, set_time = S.ComputeODE2RHS, S.GetSystemResidual, sd.SetTime
    I, W, qpos, qvel, Qbar, nv = P.I, P.W, P.qpos, P.qvel, P.Qbar, P.nv

    def f(q, V, t):
        write(I, W, q, V, 0.0, qpos, qvel)
        set_time(t)
        compute(mbs)
        Vd = np.empty(nv)
        free_rhs(I, W, q, V, residual(), Qbar, Vd)
        model.n_eval += 1
        return Vd
    return f


def f_compiled(model, P, q, V, t):
    """ExudynModel.f from the kernels and Exudyn's calls (the compiled backend's f).

    P = pack(model) (nc_max = model.n_constraints, Exudyn's views); q, V float64
    C-contiguous. The two γ evaluations come first and the state itself last, so that the
    system ends at (q, V, t) after three writes instead of four."""
    S, mbs, sd = model.solver, model.mbs, model.sd
    I, W, qpos, qvel = P.I, P.W, P.qpos, P.qvel
    nc = model.n_constraints
    if nc:
        td = model.time_dependent_constraints
        if (td and not model._exudyn_gt) or not model._velocity_level:
            gam = model._gamma(q, V, t)                       # numpy path (second differences)
        else:
            eps = write(I, W, q, V, _EPS_GAMMA, qpos, qvel)   # moved by +h, h = 1e-5 / max(1, |V|∞)
            sd.SetTime(t + eps if td else t)
            S.ComputeAlgebraicEquations(mbs, True)
            rp = S.GetSystemResidual()
            write(I, W, q, V, -_EPS_GAMMA, qpos, qvel)
            sd.SetTime(t - eps if td else t)
            S.ComputeAlgebraicEquations(mbs, True)
            gam = P.gam
            gamma_fd(rp, S.GetSystemResidual(), P.rows, eps, gam)
    write(I, W, q, V, 0.0, qpos, qvel)
    sd.SetTime(t)
    S.ComputeODE2RHS(mbs)
    Q = S.GetSystemResidual()
    if P.constant_mass:
        M = Mbar = P.empty
    else:
        S.ComputeMassMatrix(mbs)
        M, Mbar = S.GetSystemMassMatrix(), P.Mbar
    forces(I, W, q, V, Q, M, P.Qbar, Mbar)
    model.n_eval += 1
    if nc:
        S.SetSystemJacobian(model._jac_zero)
        S.ComputeJacobianAE(mbs, 1.0, 1.0 if len(model.velocity_rows) else 0.0, 0.0, False)
        A = P.A
        constraint_matrix(I, W, q, S.GetSystemJacobian(), P.rows, A)
    else:
        A, gam = P.A0, P.gam0
    Vd = np.empty(P.nv)
    flag = solve(I, W, Mbar, A, P.Qbar, gam, Vd)
    if flag == 1:
        solve_fallback(P, len(gam), Vd)
    elif flag == 2:
        from lgt_bridge.errors import ModelError
        raise ModelError(f"Exudyn model: the twist mass matrix is not positive definite at t = {t:.9g}; "
                         "give every moving body a positive mass and positive principal inertias.")
    return Vd
