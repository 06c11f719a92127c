"""The tables the Exudyn kernels (:mod:`.kernel_maps`, :mod:`.kernel_solve`) run on, packed
once per model (:func:`pack`), in the core kernels' convention (:mod:`lgt_bridge.kernels.stage`):
indices in an int64 table ``T`` with named columns, data and work buffers in one float64
array ``w`` at named offsets ``off``. Every kernel takes ``(T, off, w, ...)``: few arguments,
since numba's dispatch costs ≈ 0.1 µs per argument.

H (q̇_e = H V) is block sparse, and stored as

* identity pairs (q row, V column): rigid positions (ṙ), RotVecLG rotations (ω) and every
  vector-space coordinate;
* rotation blocks: for each EP / Rxyz node the 4 x 3 / 3 x 3 block B(q) of ṗ = B(p) ω /
  θ̇ = G(θ)⁻¹ ω (q rows of the node's rotation, V columns of its ω).

Rows of ``T`` (one section after another; ``off[R*]`` are the sections' first rows):

* nodes (τ and the rotation blocks): CODE (:data:`NODE_CODE`), NROT, POS (3), ROT (4; -1
  unused), TWIST (first V index); the nodes with a rotation block (EP, Rxyz) first, rows
  ``[0, off[RBLOCKS])``, block g of ``w[off[OB]:]`` belonging to row g;
* identity pairs from ``off[RPAIR]``: QROW, VCOL; the vector-space coordinates are the last
  ones, from ``off[RVEC]``;
* the diagonal blocks (connected components) of a constant M̄ from ``off[RCOMP]``: START
  (first member row), SIZE, FOFF (offset of its n x n block in the M̄ and M̄⁻¹ areas of w);
* their members (V indices, column MEMBER) from ``off[RMEMBER]``;
* an integer scratch (column 0) from ``off[RSCRATCH]`` to ``off[REND]``.

Float64 areas of ``w`` at ``off[O*]``: reference coordinates (OREF), the moved state of a γ
difference (OQM), the rotation blocks at the last q (OB, 12 per block), a scratch (OT), M̄⁻¹Q̄
(OMIQ), the constant M̄ and M̄⁻¹ per diagonal block (OMB, OMBI), M̄⁻¹Aᵀ transposed (OY),
A M̄⁻¹ Aᵀ (OS), its Cholesky factor (OL), its right-hand side (OR), a dense M̄'s factor
(ODM) and two n2 scratch vectors (OZ). Sizes: ``off[N2_]``, ``off[NV_]``, ``off[NC_]`` (the
largest number of constraint rows a solve may see).
"""
import numpy as np

#: lgt_bridge.kernels.rotations.to_quat codes of Exudyn's rotation nodes
NODE_CODE = {"RigidBodyEP": 0, "RigidBodyRotVecLG": 2, "RigidBodyRxyz": 3}
EP, RXYZ = NODE_CODE["RigidBodyEP"], NODE_CODE["RigidBodyRxyz"]

# columns of T: node rows; identity pair rows; component rows; member rows
CODE, NROT, POS, ROT, TWIST = 0, 1, 2, 5, 9
QROW, VCOL = 0, 1
START, SIZE, FOFF = 0, 1, 2
MEMBER = 0
NCOL = 10

# off: first rows of T's sections, sizes, offsets into w
(RBLOCKS, RPAIR, RVEC, RCOMP, RMEMBER, RSCRATCH, REND, N2_, NV_, NC_,
 OREF, OQM, OB, OT, OMIQ, OMB, OMBI, OY, OS, OL, OR, ODM, OZ, OEND) = range(24)


class Pack:
    """The packed tables of one ExudynModel: ``T``, ``off``, ``w``, named views of ``w`` and
    the buffers of the compiled f."""

    def __repr__(self):
        ncomp = int(self.off[RMEMBER] - self.off[RCOMP])
        return f"Pack(nv={self.nv}, n2={self.n2}, blocks of M̄={ncomp}, constraints ≤ {self.nc_max})"


def components(Mb):
    """Connected components of the nonzero pattern of M̄: (members, sizes), the members of
    each component sorted and one component after another, ordered by their first index.
    Every index takes the smallest label among its neighbours until nothing changes, so
    each ends with its component's first index."""
    i, j = np.nonzero(Mb)
    lab = np.arange(Mb.shape[0])
    if (i == j).all():                          # diagonal (free bodies in principal axes)
        return lab.astype(np.int64), np.ones(len(lab), np.int64)
    while True:
        new = lab.copy()
        np.minimum.at(new, i, lab[j])
        new = new[new]                          # new[k] ≤ k lies in k's component: jump there
        if (new == lab).all():
            break
        lab = new
    order = np.argsort(lab, kind="stable")
    return order.astype(np.int64), np.unique(lab, return_counts=True)[1].astype(np.int64)


def _blocks_by_size(Mb, members, sizes):
    """{size: (component indices, their diagonal blocks (k, size, size))} of M̄."""
    start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    out = {}
    for size in np.unique(sizes):
        cs = np.flatnonzero(sizes == size)
        idx = members[start[cs][:, None] + np.arange(size)]                 # (k, size)
        out[int(size)] = (cs, Mb[idx[:, :, None], idx[:, None, :]])
    return out


def positive_definite(Mb):
    """True when the symmetric M̄ has a Cholesky factor, found block by block: the
    factors of its diagonal blocks (the components), batched by size (a large block-diagonal
    M̄ costs its blocks, not a dense factorization)."""
    try:
        for _, blks in _blocks_by_size(Mb, *components(Mb)).values():
            np.linalg.cholesky(blks)
    except np.linalg.LinAlgError:
        return False
    return True


def _block_inverses(Mb, members, sizes):
    """{size: (component indices, blocks, inverses)} of the diagonal blocks of M̄, components
    of one size inverted in one call through their Cholesky factors; None when a block is not
    positive definite (singular or indefinite: it then has no inverse of its own)."""
    out = {}
    for size, (cs, blks) in _blocks_by_size(Mb, members, sizes).items():
        d = np.sqrt(np.abs(np.diagonal(blks, axis1=1, axis2=2)).max(axis=1))
        if size == 1:                           # 1 x 1: the same operations without LAPACK
            if not (blks > 0.0).all():
                return None
            L = np.sqrt(blks)
        else:
            try:
                L = np.linalg.cholesky(blks)
            except np.linalg.LinAlgError:
                return None
        # a factor with a pivot at rounding level is singular in all but name
        piv = np.diagonal(L, axis1=1, axis2=2).min(axis=1)
        if not (piv > 1e-7 * d).all():
            return None
        Li = 1.0 / L if size == 1 else np.linalg.inv(L)
        inv = np.swapaxes(Li, 1, 2) @ Li
        out[int(size)] = (cs, blks, 0.5 * (inv + np.swapaxes(inv, 1, 2)))
    return out


def sparse_inverse(Mb):
    """M̄⁻¹ as a scipy CSR matrix from the inverses of M̄'s diagonal blocks (large models:
    no dense inverse), or None when a block is not positive definite."""
    from scipy.sparse import csr_matrix
    members, sizes = components(Mb)
    inverses = _block_inverses(Mb, members, sizes)
    if inverses is None:
        return None
    start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    r, c, v = [], [], []
    for size, (cs, _, inv) in inverses.items():
        idx = members[start[cs][:, None] + np.arange(size)]                 # (k, size)
        r.append(np.repeat(idx, size, axis=1).ravel())
        c.append(np.tile(idx, (1, size)).ravel())
        v.append(inv.ravel())
    n = Mb.shape[0]
    return csr_matrix((np.concatenate(v), (np.concatenate(r), np.concatenate(c))), shape=(n, n))


def _rows(rows):
    """An int64 section of T from rows of one length (-1 in the columns they do not use)."""
    t = np.full((len(rows), NCOL), -1, np.int64)
    if len(rows):
        rows = np.asarray(rows, np.int64).reshape(len(rows), -1)
        t[:, :rows.shape[1]] = rows
    return t


#: the tables of :func:`pack` by nodes, sizes and M̄'s blocks (not their values); the
#: components and block inverses of M̄ by its value
_TABLES, _BLOCKS = {}, {}
_TABLES_MAX = 16
_NONE = np.zeros(0, np.int64)


def _kept(cache, key, make):
    got = cache.get(key)
    if got is None:
        if len(cache) >= _TABLES_MAX:
            cache.pop(next(iter(cache)))
        got = cache[key] = make()
    return got


def _mass_blocks(Mb):
    """(members, sizes, inverses) of M̄ (:func:`components`, :func:`_block_inverses`), kept by
    M̄'s value (a system built afresh with the same masses); inverses None when a block is
    not positive definite."""
    def make():
        members, sizes = components(Mb)
        return members, sizes, _block_inverses(Mb, members, sizes)
    return _kept(_BLOCKS, (Mb.shape, Mb.tobytes()), make)


def _tables(nodes, members, sizes, nv, n2, nc, dense):
    """(T, off, w without reference coordinates and M̄'s blocks, the blocks' offsets foff) of
    :func:`pack`."""
    vec = [[int(a), int(b)] for a, b in zip(nodes.vq, nodes.vv)]
    blocks, plain, ident = [], [], []
    for typ, idx, iv in nodes.kinds:
        idx, iv = [int(i) for i in idx], int(iv)
        nrot = len(idx) - 3
        row = [NODE_CODE[typ], nrot, *idx[:3], *idx[3:], *[-1] * (4 - nrot), iv]
        ident += [[idx[k], iv + 3 + k] for k in range(3)]
        if typ == "RigidBodyRotVecLG":
            ident += [[idx[3 + k], iv + k] for k in range(3)]
            plain.append(row)
        else:
            blocks.append(row)
    start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    foff = np.concatenate([[0], np.cumsum(sizes ** 2)]).astype(np.int64)
    sections = [_rows(blocks + plain), _rows(ident + vec), _rows(np.stack([start[:-1], sizes, foff[:-1]], 1)),
                _rows(members[:, None]), _rows(np.zeros((max(nc, 1), 1), np.int64))]
    first = np.cumsum([0] + [len(s) for s in sections])
    off = np.zeros(OEND + 1, np.int64)
    off[RBLOCKS] = len(blocks)
    off[RPAIR], off[RCOMP], off[RMEMBER], off[RSCRATCH], off[REND] = first[1:]
    off[RVEC] = off[RCOMP] - len(vec)
    off[N2_], off[NV_], off[NC_] = n2, nv, nc
    # w: ref, q_m, rotation blocks, scratch T, M̄⁻¹Q̄, M̄ blocks, M̄⁻¹ blocks, Y, S, L, r,
    # dense M̄ factor, z and u (n2 each)
    wsizes = [n2, n2, 12 * len(blocks), max(nv, 12), nv, int(foff[-1]), int(foff[-1]), nc * nv, nc * nc,
              nc * nc, nc, nv * nv if dense else 0, 2 * n2]
    off[OREF:OEND + 1] = np.concatenate([[0], np.cumsum(wsizes)])
    return np.concatenate(sections), off, np.zeros(int(off[OEND])), foff


def pack(model, nc_max=None, views=True):
    """Tables and work buffers of an ExudynModel (reads its node layout ``nodes``, ``ref``,
    ``Mbar`` (the constant twist mass matrix or None), ``nv``, ``n2``, ``n_constraints``;
    also ``sd``, ``cons`` and ``engine`` for :func:`.kernels.f_compiled`).

    ``nc_max``: the largest number of constraint rows a solve will see (default the model's
    ``n_constraints``). ``views``: also keep Exudyn's writable coordinate views as ``P.qpos``
    and ``P.qvel`` (valid until the system is assembled again)."""
    nodes = model.nodes
    nv, n2 = int(model.nv), int(model.n2)
    nc = int(model.n_constraints if nc_max is None else nc_max)
    members, sizes, inverses = _mass_blocks(model.Mbar) if model.Mbar is not None else (_NONE, _NONE, None)
    # no inverses: no constant M̄, or a diagonal block of M̄ is not positive definite (massless
    # coordinates, e.g. an ANCF beam section without torsional inertia): the kernels then
    # factorize the whole M̄ (dense Cholesky, flag 2 when it is not positive definite)
    dense = inverses is None
    if dense:
        members, sizes = _NONE, _NONE
    # the tables depend on the nodes, nc and M̄'s blocks alone: kept for the next model of that
    # kind (a system built afresh per run shares its NodeLayout), each model given copies
    # (the kernels write T's scratch rows and w)
    key = (id(nodes), nv, n2, nc, dense, members.tobytes(), sizes.tobytes())
    got = _TABLES.get(key)
    if got is None or got[0] is not nodes:     # (the entry is the NodeLayout's, not another's at its id)
        _TABLES.pop(key, None)
        got = _kept(_TABLES, key, lambda: (nodes, *_tables(nodes, members, sizes, nv, n2, nc, dense)))
    _, T, off, w, foff = got
    T, off, w = T.copy(), off.copy(), w.copy()
    w[off[OREF]:off[OREF] + n2] = np.asarray(model.ref, float)
    for size, (cs, blks, inv) in (inverses or {}).items():
        at = (foff[cs][:, None] + np.arange(size * size)[None, :]).reshape(-1)
        w[off[OMB] + at] = blks.reshape(-1)
        w[off[OMBI] + at] = inv.reshape(-1)

    P = Pack()
    P.T, P.off, P.w = T, off, w
    P.nv, P.n2, P.nc_max, P.constant_mass = nv, n2, nc, not dense
    P.ref = w[off[OREF]:off[OREF] + n2]
    P.qm = w[off[OQM]:off[OQM] + n2]
    P.Qbar = np.zeros(nv)
    P.Mbar = np.zeros((nv, nv)) if dense else None
    P.A, P.gam = np.zeros((nc, nv)), np.zeros(nc)
    P.A0, P.gam0 = np.zeros((0, nv)), np.zeros(0)          # the unconstrained solve's arguments
    P.empty = np.zeros((0, 0))                               # M, Mbar of the constant-M̄ case
    sd = getattr(model, "sd", None)
    if views and sd is not None:
        P.qpos = sd.GetODE2Coordinates(copy=False)
        P.qvel = sd.GetODE2Coordinates_t(copy=False)
    cons = getattr(model, "cons", None)
    if cons is not None:
        P.rows = np.asarray(cons.ae_keep, np.int64) + int(model.engine.ae0)   # kept AE rows, system vectors
    return P
