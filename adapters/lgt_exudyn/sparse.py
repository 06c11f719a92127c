"""The sparse constraint rows of :class:`lgt_exudyn.ExudynModel`, worked out once per model
(numpy and scipy, at the first compiled f): the pattern of A = C_q H, the rows of the joints
whose Jacobian the kernels compute themselves, and the structure of the index-1 solve on a
constant block-diagonal M̄ — M̄⁻¹Aᵀ, the Schur complement S = A M̄⁻¹ Aᵀ in its rows reordered
by reverse Cuthill–McKee, and S's envelope (packed skyline storage, so a chain or a tree
factorizes in time and memory linear in its bodies). The kernels are
:mod:`.kernel_sparse`'s.

* :func:`joint_rows` (model): the kept rows, when every one of them belongs to a joint the
  kernels differentiate (``JointSpherical`` between rigid bodies or the ground): one row of
  ints (the T rows of the two markers' nodes, -1 for the ground; the axis; the sign) and one
  of floats (the markers' local positions) per row, and A's pattern; else None;
* :func:`ltg_pattern` (model): A's pattern from the objects' coordinates (Exudyn's local to
  global maps) for any other model — its values then come from Exudyn's dense Jacobian;
* :func:`structure` (P, aptr, acol): the integer and float buffers of
  :func:`.kernel_sparse.sparse_solve` (offsets named below).
"""
import numpy as np

from .kernel_tables import MEMBER, POS, RCOMP, RMEMBER, RPAIR, SIZE, START, TWIST

#: the joints whose rows the kernels compute (A and γ in closed form)
ANALYTIC = ("JointSpherical",)
#: markers on a body / a node at a local position (a node marker sits on the node)
BODY_MARKERS, NODE_MARKERS = ("BodyPosition", "BodyRigid"), ("NodePosition", "NodeRigid")

# sections of the int buffer I (offsets io[k]..io[k + 1]) and the float buffer F
(APTR, ACOL, YPTR, YCOL, PERM, SPTR, SIDX, FIRST, ESTART, COMPOF, POSIN, I_END) = range(12)
(YVAL, SENV, RHS, LAM, XS, F_END) = range(6)


def _node_rows(model, P):
    """{Exudyn node number: row of the node in the pack's T} for the rigid nodes."""
    sd, T = model.sd, P.T
    first_q = {int(T[r, POS]): r for r in range(int(P.off[RPAIR]))}     # node rows: x coordinate -> row
    out = {}
    for i in range(sd.NumberOfNodes()):
        try:
            idx = list(sd.GetNodeLTGODE2(i))
        except Exception:                                               # no ODE2 coordinates
            continue
        if idx and int(idx[0]) in first_q and model.mbs.GetNode(i)["nodeType"].startswith("RigidBody"):
            out[i] = first_q[int(idx[0])]
    return out


def _marker_side(mbs, marker, rows):
    """(T row of the node or -1 for the ground, local position) of a joint's marker, or None
    when the kernels do not know the marker."""
    mk = mbs.GetMarker(marker)
    typ = mk["markerType"]
    if typ in BODY_MARKERS:
        body = mbs.GetObject(mk["bodyNumber"])
        b = np.asarray(mk.get("localPosition", np.zeros(3)), float)
        if body["objectType"] == "Ground":
            return -1, b
        if body["objectType"] != "RigidBody" or int(body["nodeNumber"]) not in rows:
            return None
        return rows[int(body["nodeNumber"])], b
    if typ in NODE_MARKERS and int(mk["nodeNumber"]) in rows:
        return rows[int(mk["nodeNumber"])], np.zeros(3)
    return None


def joint_rows(model, P):
    """(J, Jf, aptr, acol) for the kept rows when all of them belong to :data:`ANALYTIC`
    joints: J (nc x 4 int64) = (T row of marker 0's node or -1, of marker 1's, axis, 0),
    Jf (nc x 6) = the markers' local positions; A's pattern per row (ω, ṙ of marker 0's node,
    then of marker 1's, ground sides left out). None otherwise (velocity-level or
    time-dependent rows, other joints or markers)."""
    cons, mbs, sd = model.cons, model.mbs, model.sd
    if not cons.n or cons.nonholonomic or cons.time_dependent or not len(cons.ae_keep):
        return None
    owner = {}
    for k in range(sd.NumberOfObjects()):
        try:
            ltg = list(sd.GetObjectLTGAE(k))
        except Exception:                                               # no algebraic equations
            continue
        for axis, r in enumerate(ltg):
            owner[int(r)] = (k, axis)
    rows = _node_rows(model, P)
    J, Jf, cols = np.zeros((cons.n, 4), np.int64), np.zeros((cons.n, 6)), []
    for i, r in enumerate(cons.ae_keep):
        if int(r) not in owner:
            return None
        k, axis = owner[int(r)]
        o = mbs.GetObject(k)
        if o["objectType"] not in ANALYTIC:
            return None
        sides = [_marker_side(mbs, m, rows) for m in o["markerNumbers"]]
        if any(s is None for s in sides) or axis > 2:
            return None
        J[i] = sides[0][0], sides[1][0], axis, 0
        Jf[i] = np.concatenate([sides[0][1], sides[1][1]])
        cols.append([int(P.T[g, TWIST]) + j for g, _ in sides if g >= 0 for j in range(6)])
    aptr = np.concatenate([[0], np.cumsum([len(c) for c in cols])]).astype(np.int64)
    return J, Jf, aptr, np.array([c for cs in cols for c in cs], np.int64)


def ltg_pattern(model):
    """(aptr, acol): the columns of A each kept row may touch — the twist columns of the ODE2
    coordinates of the object owning the row (GetObjectLTGODE2), through H's pattern — or
    None when a kept row has no owner."""
    cons, sd, nodes = model.cons, model.sd, model.nodes
    vcols = [set() for _ in range(nodes.n2)]
    for typ, idx, iv in nodes.kinds:
        for k in idx[:3]:
            vcols[k].update(range(iv + 3, iv + 6))
        for k in idx[3:]:
            vcols[k].update(range(iv, iv + 3))
    for k, j in zip(nodes.vq, nodes.vv):
        vcols[k].add(int(j))
    row_cols = {}
    for k in range(sd.NumberOfObjects()):
        try:
            ae = list(sd.GetObjectLTGAE(k))
        except Exception:
            continue
        if not ae:
            continue
        cs = sorted(set().union(*[vcols[int(c)] for c in sd.GetObjectLTGODE2(k)]) if len(sd.GetObjectLTGODE2(k))
                    else set())
        for r in ae:
            row_cols[int(r)] = cs
    if any(int(r) not in row_cols for r in cons.ae_keep):
        return None
    cols = [row_cols[int(r)] for r in cons.ae_keep]
    aptr = np.concatenate([[0], np.cumsum([len(c) for c in cols])]).astype(np.int64)
    return aptr, np.array([c for cs in cols for c in cs], np.int64)


def _sections(parts):
    off = np.concatenate([[0], np.cumsum([len(p) for p in parts])]).astype(np.int64)
    return np.concatenate([np.asarray(p, np.int64) for p in parts] + [np.zeros(0, np.int64)]), off


def structure(P, aptr, acol):
    """The int buffer I (sections at io) and float buffer F (sections at fo) of the sparse
    index-1 solve for A's pattern (aptr, acol) on the pack P's constant M̄ (its diagonal
    blocks: the components of T)."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import reverse_cuthill_mckee
    T, off, nv = P.T, P.off, P.nv
    nc = len(aptr) - 1
    comp_of, pos_in = np.full(nv, -1, np.int64), np.zeros(nv, np.int64)
    members = []
    for c in range(int(off[RCOMP]), int(off[RMEMBER])):
        m = [int(T[off[RMEMBER] + T[c, START] + j, MEMBER]) for j in range(int(T[c, SIZE]))]
        members.append(m)
        comp_of[m] = c
        pos_in[m] = np.arange(len(m))
    # the components each row touches; Y = M̄⁻¹Aᵀ has their members
    rc = [sorted({int(comp_of[j]) - int(off[RCOMP]) for j in acol[aptr[i]:aptr[i + 1]]}) for i in range(nc)]
    ycols = [[j for c in cs for j in members[c]] for cs in rc]
    yptr = np.concatenate([[0], np.cumsum([len(c) for c in ycols])]).astype(np.int64)
    # S's pattern: rows sharing a component; reverse Cuthill-McKee for a small envelope
    B = csr_matrix((np.ones(sum(len(c) for c in rc)), np.concatenate([c for c in rc] + [[]]).astype(int),
                    np.concatenate([[0], np.cumsum([len(c) for c in rc])])), shape=(nc, len(members)))
    Spat = (B @ B.T).tocsr()
    perm = reverse_cuthill_mckee(Spat, symmetric_mode=True).astype(np.int64)
    iperm = np.empty(nc, np.int64)
    iperm[perm] = np.arange(nc)
    nbrs = []
    for p in range(nc):
        i = perm[p]
        ks = sorted(int(iperm[k]) for k in Spat.indices[Spat.indptr[i]:Spat.indptr[i + 1]] if iperm[k] <= p)
        nbrs.append(ks)
    first = np.array([ks[0] for ks in nbrs], np.int64)
    estart = np.concatenate([[0], np.cumsum(np.arange(nc) - first + 1)]).astype(np.int64)
    sptr = np.concatenate([[0], np.cumsum([len(k) for k in nbrs])]).astype(np.int64)
    I, io = _sections([aptr, acol, yptr, [j for c in ycols for j in c], perm, sptr, [k for ks in nbrs for k in ks],
                       first, estart, comp_of, pos_in])
    fo = np.concatenate([[0], np.cumsum([int(yptr[-1]), int(estart[-1]), nc, nc, nv])]).astype(np.int64)
    return I, io, np.zeros(int(fo[-1])), fo
