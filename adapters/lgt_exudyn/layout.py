"""Exudyn's nodes as lgt_bridge's state layout, and the velocity maps between Exudyn's ODE2
velocity coordinates and the bridge's twists.

Each 3-D rigid node owns 6 entries of V, (ω body, ṙ inertial); every other ODE2 coordinate
is a vector-space entry. Exudyn's velocity coordinates are q̇_e = H(q) V: EP nodes
ṗ = ½ p ⊗ (0, ω); RotVecLG nodes (ṙ, ω); Rxyz nodes θ̇ = G(θ)⁻¹ ω. These numpy methods are
the reference of the compiled kernels (:mod:`.kernel_maps`).
"""
import numpy as np

from lgt_bridge import lgt as _lgt
from lgt_bridge import params
from lgt_bridge.errors import InputError
from lgt_bridge.groups.batch import hat
from lgt_bridge.model import Layout, RigidBody

RIGID = {"RigidBodyEP": params.QUAT_WXYZ, "RigidBodyRotVecLG": params.ROTVEC,
         "RigidBodyRxyz": params.RXYZ}
#: node types whose ODE2 coordinates are a vector space (q̇ = v)
VECTOR = ("Point", "Point2D", "RigidBody2D", "GenericODE2", "1D", "PointSlope1", "PointSlope12",
          "PointSlope23", "Point2DSlope1", "Point3DSlope1", "Point3DSlope23")


def node_signature(mbs):
    """What a :class:`NodeLayout` is made of, read from the system: its ODE2 size and, per
    node, (node number, type, ODE2 coordinates, AE coordinates of Euler parameters, name)."""
    sd = mbs.systemData
    rows = []
    for i in range(sd.NumberOfNodes()):
        node = mbs.GetNode(i)
        typ = node["nodeType"]
        try:
            idx = tuple(int(k) for k in sd.GetNodeLTGODE2(i))
        except Exception:                           # nodes without ODE2 coordinates
            idx = ()
        ae = tuple(int(k) for k in sd.GetNodeLTGAE(i)) if typ == "RigidBodyEP" else ()
        rows.append((i, typ, idx, ae, node.get("name", f"node{i}")))
    return (int(sd.ODE2Size()), tuple(rows))


#: NodeLayouts by signature (systems built alike share one; the oldest dropped first)
_LAYOUTS = {}
_LAYOUTS_MAX = 16


def node_layout(mbs):
    """The :class:`NodeLayout` of an assembled system: one object for all systems whose nodes
    have the same :func:`node_signature` (a NodeLayout holds nothing else of the system), so
    a system built afresh for every run shares its layout, and what is kept on it (the
    bridge's layout analysis, the initial coordinates checked), with the last one."""
    sig = node_signature(mbs)
    got = _LAYOUTS.get(sig)
    if got is None:
        got = NodeLayout(mbs, sig)             # InputError for an unsupported node: nothing kept
        if len(_LAYOUTS) >= _LAYOUTS_MAX:
            _LAYOUTS.pop(next(iter(_LAYOUTS)))
        _LAYOUTS[sig] = got
    return got


class NodeLayout:
    """The ODE2 nodes of an assembled system: ``kinds`` (one ``(node type, q indices, first V
    index)`` per rigid node), ``layout`` (lgt_bridge's), ``nv``, ``n2``, ``ep_ae`` (the AE
    rows of the Euler-parameter normalizations), and the velocity maps H, H⁺, Ḣ V. Made from
    the nodes' :func:`node_signature` alone (``sig``: read from ``mbs`` when not given)."""

    def __init__(self, mbs, sig=None):
        self.n2, rows = node_signature(mbs) if sig is None else sig
        bodies, vq, ep_ae, kinds, vnode = [], [], [], [], []
        iv = 0
        vidx_of_q = np.full(self.n2, -1)
        for i, typ, idx, ae, name in rows:
            idx = list(idx)
            if typ in RIGID:
                bodies.append(RigidBody(RIGID[typ], tuple(idx[:3]), tuple(idx[3:]), tuple(range(iv, iv + 6)), name))
                kinds.append((typ, np.array(idx), iv))
                iv += 6
                ep_ae += list(ae)
            elif typ == "PointGround" or not len(idx):
                continue                                       # no ODE2 coordinates
            elif typ in VECTOR:
                for j, k in enumerate(idx):
                    vnode.append((i, typ, j))
                    vq.append(k)
                    vidx_of_q[k] = iv
                    iv += 1
            else:
                raise InputError(f"Exudyn node {i} ({name!r}) has type {typ!r}, which "
                                 f"lgt_bridge does not support; supported rigid nodes: {sorted(RIGID)}, "
                                 f"vector-space nodes: {list(VECTOR)}. Run this model with Exudyn's own "
                                 "exu.SolveDynamic, or build it from supported nodes.")
        self.kinds, self.ep_ae, self.nv = kinds, ep_ae, iv
        #: (node number, node type, coordinate of the node) of each vector-space velocity
        self.vector_nodes = vnode
        self.layout = Layout(self.n2, iv, bodies, tuple(vq), tuple(vidx_of_q[vq]))
        # per node type: q rows of position/rotation and V columns of ω/ṙ, batched
        self.pos_q = np.array([k[1][:3] for k in kinds], int).reshape(-1, 3)
        self.lin_v = np.array([k[2] + np.arange(3, 6) for k in kinds], int).reshape(-1, 3)
        self.types, self.moving = {}, {}
        for typ in RIGID:
            sel = [k for k in kinds if k[0] == typ]
            if sel:
                self.types[typ] = (np.array([k[1][3:] for k in sel]), np.array([k[2] + np.arange(3) for k in sel]))
                self.moving[typ] = (np.array([k[1] for k in sel]), np.array([k[2] + np.arange(6) for k in sel]))
        self.vq = np.array(self.layout.vector_q, int)
        self.vv = np.array(self.layout.vector_v, int)
        self._tau = {}
        self._valid = None             # (q0, ref) as bytes, the last pair check_initial passed

    def check_initial(self, q0, ref):
        """InputError when a node's initial coordinates are not valid (Euler parameters: the
        total of reference and initial coordinates must be a unit quaternion). The last pair
        that passed is not checked again (systems built alike share their NodeLayout)."""
        key = (q0.tobytes(), np.asarray(ref).tobytes())
        if key == self._valid:
            return
        for (typ, _, _), b in zip(self.kinds, self.layout.bodies):
            if typ == "RigidBodyEP":
                _check_euler_parameters(b, q0, ref)
            b.param.validate(q0[[*b.pos, *b.rot]], f"initial coordinates of Exudyn node '{b.name}'")
        self._valid = key

    # ------------------------------------------------------------------ velocity maps
    def owner(self, mbs, iv):
        """The Exudyn item behind velocity ``iv``, for messages: 'coordinate 3 of node 5
        (NodePointSlope23) of ObjectANCFBeam 2, 3' or the rigid body's name."""
        vv = list(self.vv)
        if iv not in vv:
            return self.layout.owner("V", iv)
        node, typ, j = self.vector_nodes[vv.index(iv)]
        objs = []
        for o in range(mbs.systemData.NumberOfObjects()):
            od = mbs.GetObject(o)
            nn = od.get("nodeNumbers", od.get("nodeNumber"))
            try:
                nn = [int(k) for k in nn]
            except TypeError:                       # one NodeIndex, or None
                nn = [] if nn is None else [int(nn)]
            if node in nn:
                typ_o = str(od.get("objectType", ""))
                objs.append((typ_o if typ_o.startswith("Object") else "Object" + typ_o, o))
        where = ""
        if objs:
            kinds = dict.fromkeys(k for k, _ in objs)
            where = " of " + "; ".join(f"{k} " + ", ".join(str(o) for kk, o in objs if kk == k)
                                     for k in kinds)
        return f"coordinate {j} of node {node} (Node{typ}){where}"

    @staticmethod
    def rot_blocks(typ, rot):
        """d(rotation coordinates)/dt = B ω per node: (k, nrot, 3)."""
        if typ == "RigidBodyEP":
            p0, pv = rot[:, 0], rot[:, 1:]
            B = np.empty((len(rot), 4, 3))
            B[:, 0, :] = -0.5 * pv
            B[:, 1:, :] = 0.5 * (p0[:, None, None] * np.eye(3) + hat(pv))
            return B
        if typ == "RigidBodyRxyz":
            c1, s1 = np.cos(rot[:, 1]), np.sin(rot[:, 1])
            c2, s2 = np.cos(rot[:, 2]), np.sin(rot[:, 2])
            z, o = np.zeros_like(c1), np.ones_like(c1)
            with np.errstate(divide="ignore", invalid="ignore"):
                return np.stack([c2 / c1, -s2 / c1, z, s2, c2, z, -s1 * c2 / c1, s1 * s2 / c1, o],
                                axis=1).reshape(-1, 3, 3)
        return np.broadcast_to(np.eye(3), (len(rot), 3, 3))

    def H(self, q):
        """Dense H(q) (n2 x nv): q̇_e = H V."""
        H = np.zeros((self.n2, self.nv))
        H[self.pos_q, self.lin_v] = 1.0
        for typ, (rq, wv) in self.types.items():
            H[rq[:, :, None], wv[:, None, :]] = self.rot_blocks(typ, q[rq])
        H[self.vq, self.vv] = 1.0
        return H

    def selection(self, rotvec=False):
        """Without rotation coordinates H is a 0/1 selection, H[qi[j], j] = 1: qi (nv), so
        that Hᵀ J H = J[qi][:, qi]; None with rotation coordinates (``rotvec``: except
        RotVecLG rotations, whose block of H is the identity too)."""
        got = self.__dict__.setdefault("_selection", {})
        if rotvec in got:
            return None if got[rotvec] is None else got[rotvec].copy()
        rot = [t for t in self.types if not (rotvec and t == "RigidBodyRotVecLG")]
        qi = None
        if not (rot or self.n2 != self.nv):
            qi = np.empty(self.nv, int)
            qi[self.lin_v.ravel()] = self.pos_q.ravel()
            for rq, wv in self.types.values():
                qi[wv.ravel()] = rq.ravel()
            qi[self.vv] = self.vq
        got[rotvec] = qi
        return None if qi is None else qi.copy()

    def H_sparse(self, q):
        """H(q) as a scipy CSR matrix (a few entries per row: large models)."""
        from scipy.sparse import csr_matrix
        r, c, v = [self.pos_q.ravel(), self.vq], [self.lin_v.ravel(), self.vv], [np.ones(self.pos_q.size + len(self.vq))]
        for typ, (rq, wv) in self.types.items():
            B = self.rot_blocks(typ, q[rq])
            r.append(np.broadcast_to(rq[:, :, None], B.shape).ravel())
            c.append(np.broadcast_to(wv[:, None, :], B.shape).ravel())
            v.append(B.ravel())
        return csr_matrix((np.concatenate(v), (np.concatenate(r), np.concatenate(c))), shape=(self.n2, self.nv))

    def increments(self, q):
        """∂q_e/∂(Exudyn's increments) as a scipy CSR matrix: the identity, except for the
        rotation coordinates ν of RotVecLG nodes, whose increments are body-frame rotations
        δθ (R(ν + dν) = R(ν) exp(δθ~), δθ = dexp₋ν dν): there dexp₋ν⁻¹."""
        from scipy.sparse import csr_matrix, identity
        if "RigidBodyRotVecLG" not in self.types:
            return identity(self.n2, format="csr")
        from lgt_bridge.groups import so3
        rq, _ = self.types["RigidBodyRotVecLG"]
        B = so3.dexp_inv(-q[rq])
        keep = np.ones(self.n2, bool)
        keep[rq.ravel()] = False
        d = np.flatnonzero(keep)
        r = np.concatenate([d, np.repeat(rq, 3, axis=1).ravel()])
        c = np.concatenate([d, np.tile(rq, (1, 3)).ravel()])
        return csr_matrix((np.concatenate([np.ones(len(d)), B.ravel()]), (r, c)), shape=(self.n2, self.n2))

    def H_pinv(self, q):
        """The pseudo-inverse of H(q), block by block (H is a permutation of per-node
        blocks: identities and each rotation's 4x3 or 3x3 block). Euler parameters in closed
        form: their block B = ½[-pᵥᵀ; p₀I + p̂ᵥ] has BᵀB = ¼|p|² I, so B⁺ = 4Bᵀ/|p|²; the
        rotation vector's block is the identity; Rxyz (singular at θ₁ = ±π/2) by SVD."""
        Hp = np.zeros((self.nv, self.n2))
        Hp[self.lin_v, self.pos_q] = 1.0
        for typ, (rq, wv) in self.types.items():
            if typ == "RigidBodyEP":
                rot = q[rq]
                B = self.rot_blocks(typ, rot)
                inv = 4.0 * B.transpose(0, 2, 1) / (rot * rot).sum(axis=1)[:, None, None]
            elif typ == "RigidBodyRxyz":
                inv = np.linalg.pinv(self.rot_blocks(typ, q[rq]))
            else:
                inv = np.broadcast_to(np.eye(3), (len(rq), 3, 3))
            Hp[wv[:, :, None], rq[:, None, :]] = inv
        Hp[self.vv, self.vq] = 1.0
        return Hp

    def rates_from_twist(self, q, V):
        """Exudyn's ODE2 velocity coordinates q̇_e = H(q) V."""
        qd = np.zeros(self.n2)
        qd[self.pos_q] = V[self.lin_v]
        for typ, (rq, wv) in self.types.items():
            qd[rq] = np.einsum("nij,nj->ni", self.rot_blocks(typ, q[rq]), V[wv])
        qd[self.vq] = V[self.vv]
        return qd

    def twist_from_rates(self, q, qd):
        """The twists V of Exudyn's ODE2 velocity coordinates q̇_e (ω = G(θ) θ̇; q valid)."""
        V = np.zeros(self.nv)
        for (typ, idx, iv), b in zip(self.kinds, self.layout.bodies):
            V[iv + 3:iv + 6] = qd[idx[:3]]
            if typ == "RigidBodyRotVecLG":
                V[iv:iv + 3] = qd[idx[3:]]
            else:
                V[iv:iv + 3] = b.param.G(q[idx[3:]]) @ qd[idx[3:]]
        V[self.vv] = qd[self.vq]
        return V

    def Hdot_V(self, q, V):
        """Ḣ(q, q̇) V: the part of q̈_e not from V̇."""
        out = np.zeros(self.n2)
        for typ, idx, iv in self.kinds:
            w = V[iv:iv + 3]
            if typ == "RigidBodyEP":
                out[idx[3:]] = -0.25 * (w @ w) * q[idx[3:]]
            elif typ == "RigidBodyRxyz":
                th = q[idx[3:]]
                a, bb, cc = self.rot_blocks(typ, th[None])[0] @ w           # θ̇ = G(θ)⁻¹ ω
                c1, s1 = np.cos(th[1]), np.sin(th[1])
                da = (-cc * bb + a * s1 * bb) / c1
                db = cc * a * c1
                dc = -c1 * bb * a - s1 * da
                out[idx[3:]] = [da, db, dc]
        return out

    def Hplus_Hdot_V(self, q, V):
        """H⁺ Ḣ V with H⁺ the left inverse of H (EP: 2G(p), which annihilates Ḣ V = -¼|ω|² p;
        Rxyz: G(θ); identity elsewhere)."""
        out = np.zeros(self.nv)
        if "RigidBodyRxyz" in self.types:
            hv = self.Hdot_V(q, V)
            rq, wv = self.types["RigidBodyRxyz"]
            th = q[rq]
            c1, s1, c2, s2 = np.cos(th[:, 1]), np.sin(th[:, 1]), np.cos(th[:, 2]), np.sin(th[:, 2])
            d = hv[rq]
            out[wv] = np.stack([c1 * c2 * d[:, 0] + s2 * d[:, 1], -c1 * s2 * d[:, 0] + c2 * d[:, 1],
                                s1 * d[:, 0] + d[:, 2]], axis=1)
        return out

    # ------------------------------------------------------------------ moving along twists
    def tau(self, typ):
        """The LGT map of a rigid node type on SO(3)xR³ with the exp chart."""
        if typ not in self._tau:
            self._tau[typ] = _lgt.LGT(RIGID[typ], "SO3xR3", "exp")
        return self._tau[typ]

    def moved(self, q, V, eps):
        """q moved along the twist V by eps: τ on SO(3)xR³ (batched per node type),
        additive for vector-space coordinates."""
        out = q.copy()
        for typ, (qi, vi) in self.moving.items():
            out[qi] = self.tau(typ).tau(q[qi], eps * V[vi])
        out[self.vq] = q[self.vq] + eps * V[self.vv]
        return out

    def perturbed(self, q, rng, size):
        """Another valid configuration near q (the constant-mass check's probes): every
        coordinate moved by size·N(0, 1), Euler parameters normalized again (a rotation
        vector or Rxyz angles moved are rotations as they are), drawn again while an Rxyz
        node's middle angle is near ±π/2 (|cos θ₁| < 0.3: H's gimbal lock, where the check's
        comparisons lose their digits)."""
        rxyz = self.types["RigidBodyRxyz"][0][:, 1] if "RigidBodyRxyz" in self.types else None
        for _ in range(50):
            out = q + size * rng.normal(size=len(q))
            if rxyz is None or (np.abs(np.cos(out[rxyz])) >= 0.3).all():
                break
        if "RigidBodyEP" in self.types:
            rq = self.types["RigidBodyEP"][0]
            p = out[rq]
            out[rq] = p / np.sqrt((p * p).sum(axis=1))[:, None]
        return out

    def plus(self, q0, D):
        """q0 moved by D in Exudyn's own increments: plain addition, except RotVecLG
        rotations, R = R0 exp(Dθ) (body frame)."""
        q = q0 + D
        if "RigidBodyRotVecLG" in self.moving:
            qi, vi = self.moving["RigidBodyRotVecLG"]
            tw = np.zeros(vi.shape)
            tw[:, :3] = D[qi[:, 3:]]
            tw[:, 3:] = D[qi[:, :3]]
            q[qi] = self.tau("RigidBodyRotVecLG").tau(q0[qi], tw)
        return q


#: above this many ODE2 coordinates constant_twist_mass multiplies by H and H⁺ as sparse matrices
DENSE_MASS_CHECK = 150


def constant_twist_mass(engine, nodes, q0, rng=np.random.default_rng(7)):
    """M̄ when the twist mass matrix is the same at q0 and two other configurations (drawn
    from ``rng``, one generator for the process by default) and the engine's M equals
    H⁺ᵀ M̄ H⁺ there (rigid bodies with the node at the centre of mass), else None; leaves q0
    written."""
    if not nodes.nv:                 # no ODE2 coordinates (a purely first-order system)
        return np.zeros((0, 0))
    if nodes.n2 > DENSE_MASS_CHECK:
        from scipy.sparse import csr_matrix as sparse       # H has a few entries per row
    else:
        sparse = np.asarray                                 # small: dense products are cheaper
    # H the same 0/1 permutation everywhere (RotVecLG and vector-space nodes only): Hᵀ M H
    # is M permuted, and H⁺ᵀ M̄ H⁺ = M exactly (H⁺ = Hᵀ), so only the probes' M are compared
    qi = nodes.selection(rotvec=True)
    Ms, Mbar = [], None
    for k in range(3):
        q = q0 if k == 0 else nodes.perturbed(q0, rng, 0.7)
        engine.sd.SetODE2Coordinates(q - engine.ref)
        M = engine.mass_matrix()
        if qi is not None:
            Ms.append(M)           # (compared as they are: permuting moves no entry's size)
            continue
        H, Hp = sparse(nodes.H(q)), sparse(nodes.H_pinv(q))
        Mb = np.asarray((H.T @ (H.T @ M).T).T)                         # Hᵀ M H
        back = np.asarray((Hp.T @ (Hp.T @ Mb).T).T)                    # H⁺ᵀ M̄ H⁺
        if np.abs(M - back).max() > 1e-12 * max(1.0, np.abs(M).max()):
            break
        Ms.append(Mb)
    else:
        tol = 1e-12 * max(1.0, np.abs(Ms[0]).max())
        if all(np.abs(m - Ms[0]).max() <= tol for m in Ms[1:]):
            M0 = Ms[0] if qi is None else Ms[0][qi[:, None], qi]
            Mbar = 0.5 * (M0 + M0.T)
    engine.sd.SetODE2Coordinates(q0 - engine.ref)
    return Mbar


def _check_euler_parameters(b, q0, ref):
    """InputError when a node's total Euler parameters (reference + initial: Exudyn adds
    them component-wise) are not a unit quaternion, showing both parts."""
    from lgt_bridge.validation import QUAT_NORM_TOL
    rot = list(b.rot)
    p, r = q0[rot], ref[rot]
    norm = float(np.sqrt(p @ p))
    if np.isfinite(norm) and abs(norm - 1.0) <= QUAT_NORM_TOL:
        return
    fmt = lambda a: "[" + ", ".join(f"{x:.6g}" for x in a) + "]"     # noqa: E731
    raise InputError(
        f"Exudyn node '{b.name}': its Euler parameters reference + initial coordinates = "
        f"{fmt(r)} + {fmt(p - r)} = {fmt(p)} have norm {norm:.12g} (off by {abs(norm - 1.0):.3g} "
        f"> {QUAT_NORM_TOL:g}). Exudyn adds referenceCoordinates and initialCoordinates component-"
        "wise, so their sum must be a unit quaternion: put the rotation in referenceCoordinates "
        "(or initialRotationMatrix of CreateRigidBody) and leave the initial rotation "
        "coordinates at zero, or make the sum unit.")
