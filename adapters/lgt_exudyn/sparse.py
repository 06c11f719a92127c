"""The sparse constraint rows of :class:`lgt_exudyn.ExudynModel`, worked out once per model
(numpy and scipy, at the first compiled f): the pattern of A = C_q H, the rows of the joints
whose Jacobian the kernels compute themselves, and the structure of the index-1 solve on a
constant block-diagonal M̄ — M̄⁻¹Aᵀ, the Schur complement S = A M̄⁻¹ Aᵀ in its rows reordered
by reverse Cuthill–McKee, and S's envelope (packed skyline storage, so a chain or a tree
factorizes in time and memory linear in its bodies). The kernels are
:mod:`.kernel_sparse`'s.

* :func:`joint_rows` (model): the kept rows, when every one of them belongs to a joint the
  kernels differentiate (:data:`ANALYTIC`: spherical, generic with any ``constrainedAxes``,
  revolute-z and prismatic-x joints between rigid bodies or the ground, their equations as
  :func:`joint_equations` reads them from Exudyn's sources): one row of ints (the T rows of
  the two markers' nodes, -1 for the ground; the kind of equation; the node its axis turns
  with) and one of floats (the markers' positions, the axes) per row, and A's pattern; else
  None;
* :func:`ltg_pattern` (model): A's pattern from the objects' coordinates (Exudyn's local to
  global maps) for any other model — its values then come from Exudyn's dense Jacobian;
* :func:`structure` (P, aptr, acol): A's pattern widened to whole slots (a rigid node's six
  twist columns, M̄'s diagonal blocks) and the integer and float buffers of
  :func:`.kernel_sparse.sparse_solve` (offsets named below).
"""
import numpy as np

from .kernel_tables import FOFF, MEMBER, OMBI, POS, RCOMP, RMEMBER, RPAIR, SIZE, START, TWIST

#: the joints whose rows the kernels compute (A and γ in closed form)
ANALYTIC = ("JointSpherical", "JointGeneric", "JointRevoluteZ", "JointPrismaticX")
#: markers on a body / a node at a local position (a node marker sits on the node)
BODY_MARKERS, NODE_MARKERS = ("BodyPosition", "BodyRigid"), ("NodePosition", "NodeRigid")
#: the kinds of rows (column 2 of J): u·(p₁ - p₀) and u·w (u on marker 0's side, w on 1's)
TRANSLATION, ROTATION = 0, 1

# sections of the int buffer I (offsets io[k]..io[k + 1]) and the float buffer F
(APTR, ACOL, BPTR, BOFF, BSLOT, PERM, SPTR, SIDX, PPTR, PA, PB, PN, FIRST, ESTART, MOFF, MSIZE, MDIAG,
 I_END) = range(18)
(YVAL, SENV, RHS, LAM, MINV, F_END) = range(6)


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


def _marker_frame(mk):
    """(local position, local rotation) of a body marker: its localHT when it has one."""
    if "localHT" in mk:
        H = np.asarray(mk["localHT"], float)
        return H[:3, 3].copy(), H[:3, :3].copy()
    return np.asarray(mk.get("localPosition", np.zeros(3)), float), np.eye(3)


def _marker_side(mbs, marker, rows):
    """(T row of the node or -1 for the ground, position, rotation) of a joint's marker: on a
    node, the position and rotation in the node's frame; on the ground, in the world; None
    when the kernels do not know the marker."""
    mk = mbs.GetMarker(marker)
    typ = mk["markerType"]
    if typ in BODY_MARKERS:
        body = mbs.GetObject(mk["bodyNumber"])
        b, Rm = _marker_frame(mk)
        if body["objectType"] == "Ground":
            R0 = np.asarray(body.get("referenceRotation", np.eye(3)), float)
            return -1, np.asarray(body.get("referencePosition", np.zeros(3)), float) + R0 @ b, R0 @ Rm
        if body["objectType"] != "RigidBody" or int(body["nodeNumber"]) not in rows:
            return None
        return rows[int(body["nodeNumber"])], b, Rm
    if typ in NODE_MARKERS and int(mk["nodeNumber"]) in rows:
        return rows[int(mk["nodeNumber"])], np.zeros(3), np.eye(3)
    return None


def _free_locked(c):
    return [k for k in range(3) if not c[k]], [k for k in range(3) if c[k]]


def joint_equations(o, C0, C1):
    """{row of the joint: (kind, u on marker 0's node (True) or in the world frame (False),
    a, b)} — the joint's algebraic equations as Exudyn writes them (CObjectJoint*.cpp):
    ``TRANSLATION``: (R₀a)·(p₁ - p₀) (a the world axis when u is not on the node),
    ``ROTATION``: (R₀a)·(R₁b); C0, C1 the joint frames (the markers' rotations times
    rotationMarker0/1) in their nodes' frames. Rows with λ = 0 (free axes) are left out;
    None for joints or options the kernels do not know."""
    typ = o["objectType"]
    if not o.get("activeConnector", True):
        return None
    E = np.eye(3)
    if typ == "JointSpherical":
        c = list(o.get("constrainedAxes", [1, 1, 1]))
        return {k: (TRANSLATION, False, E[k], None) for k in range(3) if c[k]}
    if typ == "JointRevoluteZ":
        out = {k: (TRANSLATION, False, E[k], None) for k in range(3)}
        out.update({3: (ROTATION, True, C0[:, 2], C1[:, 0]), 4: (ROTATION, True, C0[:, 2], C1[:, 1])})
        return out
    if typ == "JointPrismaticX":
        return {0: (TRANSLATION, True, C0[:, 1], None), 1: (TRANSLATION, True, C0[:, 2], None),
                2: (ROTATION, True, C0[:, 2], C1[:, 1]), 3: (ROTATION, True, C0[:, 2], C1[:, 0]),
                4: (ROTATION, True, C0[:, 0], C1[:, 1])}
    if typ != "JointGeneric" or o.get("alternativeConstraints", False) or o.get("offsetUserFunction", 0) != 0:
        return None
    c = [int(x) for x in o["constrainedAxes"]]
    glob = all(c[:3])
    out = {k: (TRANSLATION, not glob, E[k] if glob else C0[:, k], None) for k in range(3) if c[k]}
    free, locked = _free_locked(c[3:])
    if len(locked) == 3:
        out.update({3: (ROTATION, True, C0[:, 2], C1[:, 1]), 4: (ROTATION, True, C0[:, 2], C1[:, 0]),
                    5: (ROTATION, True, C0[:, 0], C1[:, 1])})
    elif len(locked) == 2:
        out.update({3 + k: (ROTATION, True, C0[:, free[0]], C1[:, k]) for k in locked})
    elif len(locked) == 1:
        out[3 + locked[0]] = (ROTATION, True, C0[:, free[0]], C1[:, free[1]])
    return out


def joint_rows(model, P):
    """(J, Jf, aptr, acol, nonzero) for the kept rows when all of them belong to :data:`ANALYTIC`
    joints: J (nc x 4 int64) = (T row of marker 0's node or -1, of marker 1's, kind, T row
    of the node u turns with or -1), Jf (nc x 9) = (marker 0's position, marker 1's position
    or, on ROTATION rows, b, then a) in the nodes' frames (the world's on the ground); A's
    pattern per row (ω, ṙ of marker 0's node, then of marker 1's, ground sides left out) and
    which of its entries can be nonzero. None otherwise (velocity-level or time-dependent rows, other joints or markers)."""
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
    J, Jf, cols, eqs, nz = np.zeros((cons.n, 4), np.int64), np.zeros((cons.n, 9)), [], {}, []
    for i, r in enumerate(cons.ae_keep):
        if int(r) not in owner:
            return None
        k, axis = owner[int(r)]
        o = mbs.GetObject(k)
        if o["objectType"] not in ANALYTIC:
            return None
        sides = [_marker_side(mbs, m, rows) for m in o["markerNumbers"]]
        if any(s is None for s in sides):
            return None
        if k not in eqs:
            C0 = sides[0][2] @ np.asarray(o.get("rotationMarker0", np.eye(3)), float)
            C1 = sides[1][2] @ np.asarray(o.get("rotationMarker1", np.eye(3)), float)
            eqs[k] = joint_equations(o, C0, C1)
        if eqs[k] is None or axis not in eqs[k]:
            return None
        kind, on_node, a, b = eqs[k][axis]
        (g0, p0, _), (g1, p1, _) = sides
        gu = g0 if on_node else -1
        J[i] = g0, g1, kind, gu
        Jf[i] = np.concatenate([p0, p1 if kind == TRANSLATION else b, a])
        cols.append([int(P.T[g, TWIST]) + j for g, _, _ in sides if g >= 0 for j in range(6)])
        # ṙ columns: none on ROTATION rows, u's nonzero entries when u is a fixed axis
        rdot = [on_node or a[j] != 0 for j in range(3)] if kind == TRANSLATION else [False] * 3
        nz.append([True] * 3 + rdot)
    aptr = np.concatenate([[0], np.cumsum([len(c) for c in cols])]).astype(np.int64)
    nonzero = np.array([f for i, c in enumerate(cols) for f in nz[i] * (len(c) // 6)], bool)
    return J, Jf, aptr, np.array([c for cs in cols for c in cs], np.int64), nonzero


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


def _slots(P):
    """The slots of the columns of V: the smallest groups closed under M̄'s diagonal blocks
    (the components of T) and the six twist columns of each rigid node, so that M̄ is
    block-diagonal over them and a joint's rows touch whole slots. (slot of each column,
    members of each slot sorted, the dense M̄⁻¹ of each slot)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    T, off, w, nv = P.T, P.off, P.w, P.nv
    comps, i, j = [], [], []
    for c in range(int(off[RCOMP]), int(off[RMEMBER])):
        m = [int(T[off[RMEMBER] + T[c, START] + k, MEMBER]) for k in range(int(T[c, SIZE]))]
        comps.append((c, m))
        i += m[:-1]
        j += m[1:]
    for g in range(int(off[RPAIR])):                                   # rigid nodes: six twist columns
        iv = int(T[g, TWIST])
        i += list(range(iv, iv + 5))
        j += list(range(iv + 1, iv + 6))
    G = coo_matrix((np.ones(len(i)), (i, j)), shape=(nv, nv))
    _, lab = connected_components(G, directed=False)
    order = np.argsort(lab, kind="stable")
    members = np.split(order, np.flatnonzero(np.diff(lab[order])) + 1)
    slot_of = np.empty(nv, np.int64)
    pos = np.empty(nv, np.int64)
    for s, m in enumerate(members):
        slot_of[m] = s
        pos[m] = np.arange(len(m))
    minv = [np.zeros((len(m), len(m))) for m in members]
    for c, m in comps:
        n = len(m)
        blk = w[off[OMBI] + T[c, FOFF]:off[OMBI] + T[c, FOFF] + n * n].reshape(n, n)
        s = slot_of[m[0]]
        minv[s][np.ix_(pos[m], pos[m])] = blk
    return slot_of, [np.asarray(m, np.int64) for m in members], minv


def structure(P, aptr, acol, nonzero=None):
    """(aptr, acol, I, io, F, fo): A's pattern widened to whole slots (:func:`_slots`; each
    row's slots one after another, members ascending) and the int buffer I (sections at io)
    and float buffer F (sections at fo) of the sparse index-1 solve on the pack P's constant
    M̄. Y = M̄⁻¹Aᵀ has A's pattern (each slot block times the slot's M̄⁻¹); an entry of
    S = A M̄⁻¹ Aᵀ is a sum over the slots its two rows share of dot products of contiguous
    blocks, each as long as the shorter of the two rows' blocks up to their last entry that
    can be nonzero (``nonzero``: a flag per entry of the given pattern, default all; a row's
    A_i·Y_k = A_k·Y_i); S's rows are reordered by reverse Cuthill-McKee and S stored in its
    envelope."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import reverse_cuthill_mckee
    nc = len(aptr) - 1
    slot_of, members, minv = _slots(P)
    rs = [sorted({int(slot_of[j]) for j in acol[aptr[i]:aptr[i + 1]]}) for i in range(nc)]
    size = np.array([len(m) for m in members], np.int64)
    aptr2 = np.concatenate([[0], np.cumsum([int(size[ss].sum()) for ss in rs])]).astype(np.int64)
    acol2 = np.concatenate([members[s] for ss in rs for s in ss] + [np.zeros(0, np.int64)]).astype(np.int64)
    can = set() if nonzero is not None else None
    if nonzero is not None:
        can = {(i, int(j)) for i in range(nc) for j, f in zip(acol[aptr[i]:aptr[i + 1]], nonzero[aptr[i]:aptr[i + 1]])
               if f}
    boff, bslot, where = [], [], {}                    # row blocks: value offset, slot, length in use
    for i, ss in enumerate(rs):
        o = int(aptr2[i])
        for s in ss:
            m = members[s]
            used = [k for k, j in enumerate(m) if can is None or (i, int(j)) in can]
            where[i, s] = (o, used[-1] + 1 if used else 0)
            boff.append(o)
            bslot.append(s)
            o += int(size[s])
    bptr = np.concatenate([[0], np.cumsum([len(ss) for ss in rs])]).astype(np.int64)
    # S's pattern: rows sharing a slot; reverse Cuthill-McKee for a small envelope
    B = csr_matrix((np.ones(len(bslot)), np.asarray(bslot, int), bptr), shape=(nc, len(members)))
    Spat = (B @ B.T).tocsr()
    perm = reverse_cuthill_mckee(Spat, symmetric_mode=True).astype(np.int64)
    iperm = np.empty(nc, np.int64)
    iperm[perm] = np.arange(nc)
    nbrs, pairs = [], []
    for p in range(nc):
        i = perm[p]
        ks = sorted(int(iperm[k]) for k in Spat.indices[Spat.indptr[i]:Spat.indptr[i + 1]] if iperm[k] <= p)
        nbrs.append(ks)
        for pk in ks:
            k = perm[pk]
            pp = []
            for s in rs[i]:
                if (k, s) in where:
                    (oi, ni), (ok, nk) = where[i, s], where[k, s]
                    if min(ni, nk):
                        pp.append((oi, ok, ni) if ni <= nk else (ok, oi, nk))
            pairs.append(pp)
    first = np.array([ks[0] for ks in nbrs], np.int64)
    estart = np.concatenate([[0], np.cumsum(np.arange(nc) - first + 1)]).astype(np.int64)
    sptr = np.concatenate([[0], np.cumsum([len(k) for k in nbrs])]).astype(np.int64)
    pptr = np.concatenate([[0], np.cumsum([len(pp) for pp in pairs])]).astype(np.int64)
    flat = [t for pp in pairs for t in pp]
    # each slot's M̄⁻¹: its diagonal when it is diagonal (rigid bodies in principal axes), else dense
    diag = np.array([not np.any(m - np.diag(np.diagonal(m))) for m in minv], np.int64)
    stored = [np.diagonal(m) if d else m.ravel() for m, d in zip(minv, diag)]
    moff = np.concatenate([[0], np.cumsum([len(m) for m in stored])]).astype(np.int64)
    I, io = _sections([aptr2, acol2, bptr, boff, bslot, perm, sptr, [k for ks in nbrs for k in ks], pptr,
                       [t[0] for t in flat], [t[1] for t in flat], [t[2] for t in flat], first, estart,
                       moff[:-1], size, diag])
    fo = np.concatenate([[0], np.cumsum([int(aptr2[-1]), int(estart[-1]), nc, nc, int(moff[-1])])]).astype(np.int64)
    F = np.zeros(int(fo[-1]))
    F[fo[MINV]:fo[MINV + 1]] = np.concatenate(stored + [np.zeros(0)])
    return aptr2, acol2, I, io, F, fo
