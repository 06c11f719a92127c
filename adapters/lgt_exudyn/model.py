"""ExudynModel: an assembled Exudyn MainSystem as an lgt_bridge model.

q is Exudyn's total ODE2 coordinates (reference + current). Each 3-D rigid node
owns 6 entries of V, (ω body, ṙ inertial); every other ODE2 coordinate is a
vector-space entry. Exudyn's own M, Q and C_q (evaluated at the state and time
written into the system, so loads, springs and user functions work) are mapped to
twist coordinates through q̇_e = H(q) V:

    M̄ = Hᵀ M H,   Q̄ = Hᵀ (Q - M Ḣ V),   A = C_q H,   γ = d/dt(A V)|_V

The Euler-parameter normalization equations are dropped: τ keeps quaternions unit.
Engine velocity coordinates: EP nodes ṗ = ½ p ⊗ (0, ω); RotVecLG nodes (ṙ, ω);
Rxyz nodes θ̇ = G(θ)⁻¹ ω.
"""
import numpy as np

from lgt_bridge import lgt as _lgt
from lgt_bridge import params
from lgt_bridge.errors import InputError
from lgt_bridge.groups._vec import hat
from lgt_bridge.model import Layout, Model, RigidBody, solve_kkt

RIGID = {"RigidBodyEP": params.QUAT_WXYZ, "RigidBodyRotVecLG": params.ROTVEC,
         "RigidBodyRxyz": params.RXYZ}
#: node types whose ODE2 coordinates are a vector space (q̇ = v)
VECTOR = ("Point", "Point2D", "RigidBody2D", "GenericODE2", "Point3DSlope1", "Point3DSlope23",
          "Point2DSlope1", "PointGround")
_EPS_GAMMA = 1e-5


def _exudyn():
    import exudyn
    return exudyn


class ExudynModel(Model):
    """An assembled Exudyn ``MainSystem`` as a model for :func:`lgt_bridge.simulate.simulate`."""

    def __init__(self, mbs, simulationSettings=None):
        exu = _exudyn()
        self.exu, self.mbs = exu, mbs
        if not getattr(mbs, "systemIsConsistent", False):
            raise InputError("Exudyn system is not assembled (mbs.systemIsConsistent is False); "
                             "call mbs.Assemble() before wrapping it.")
        sd = self.sd = mbs.systemData
        self.n2, n1, self.nae = sd.ODE2Size(), sd.ODE1Size(), sd.AEsize()
        if n1:
            raise InputError(f"Exudyn system has {n1} ODE1 coordinates (first-order objects); "
                             "lgt_bridge integrates second-order (ODE2) systems only.")
        if sd.DataSize():
            raise InputError(f"Exudyn system has {sd.DataSize()} data coordinates (contact or friction "
                             "states); these need Exudyn's discontinuous iteration and are not supported.")
        bodies, vq, ep_ae = [], [], []
        self.kinds = []
        iv = 0
        self.vidx_of_q = np.full(self.n2, -1)
        for i in range(sd.NumberOfNodes()):
            node = mbs.GetNode(i)
            typ = node["nodeType"]
            idx = list(sd.GetNodeLTGODE2(i))
            if typ in RIGID:
                par = RIGID[typ]
                bodies.append(RigidBody(par, tuple(idx[:3]), tuple(idx[3:]), tuple(range(iv, iv + 6)),
                                        node.get("name", f"node{i}")))
                self.kinds.append((typ, np.array(idx), iv))
                iv += 6
                if typ == "RigidBodyEP":
                    ep_ae += list(sd.GetNodeLTGAE(i))
            elif typ in VECTOR or typ.startswith("Point") or typ.startswith("Generic"):
                for k in idx:
                    vq.append(k)
                    self.vidx_of_q[k] = iv
                    iv += 1
            else:
                raise InputError(f"Exudyn node {i} ({node.get('name', '')!r}) has type {typ!r}, which "
                                 f"lgt_bridge does not support; supported rigid nodes: {sorted(RIGID)}, "
                                 f"vector-space nodes: {list(VECTOR)}.")
        self.layout = Layout(self.n2, iv, bodies, tuple(vq), tuple(self.vidx_of_q[vq]))
        self.nv = iv
        self.ae_keep = np.array(sorted(set(range(self.nae)) - set(ep_ae)), int)
        self.n_constraints = len(self.ae_keep)
        self.ep_ae = ep_ae
        self._index_tables()
        s = simulationSettings if simulationSettings is not None else exu.SimulationSettings()
        self.settings = s
        self.solver = exu.MainSolverImplicitSecondOrder()
        self._init_solver()
        self.ref = np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))
        self._jac_zero = np.zeros((self.solver.GetODE2size() + self.nae, self.solver.GetODE2size() + self.nae))
        self.q0 = np.array(sd.GetODE2Coordinates()) + self.ref
        self.V0 = self.twist_from_rates(self.q0, np.array(sd.GetODE2Coordinates_t()))
        for k, b in enumerate(bodies):
            if self.kinds[k][0] == "RigidBodyEP":
                self._check_euler_parameters(b)
            b.param.validate(self.q0[[*b.pos, *b.rot]], f"initial coordinates of Exudyn node '{b.name}'")
        if not np.isfinite(self.V0).all():
            i = int(np.flatnonzero(~np.isfinite(self.V0))[0])
            raise InputError(f"Exudyn initial velocities: entry {i} of {self.layout.owner('V', i)} is not "
                             "finite; fix the node's initial velocities.")
        self._so3xr3 = {}
        self.n_eval = 0
        self._detect_constant_mass()

    def _check_euler_parameters(self, b):
        """InputError when a node's total Euler parameters (reference + initial: Exudyn adds
        them component-wise) are not a unit quaternion, showing both parts."""
        from lgt_bridge._checks import QUAT_NORM_TOL
        rot = list(b.rot)
        p, ref = self.q0[rot], self.ref[rot]
        norm = float(np.sqrt(p @ p))
        if np.isfinite(norm) and abs(norm - 1.0) <= QUAT_NORM_TOL:
            return
        fmt = lambda a: "[" + ", ".join(f"{x:.6g}" for x in a) + "]"     # noqa: E731
        raise InputError(
            f"Exudyn node '{b.name}': its Euler parameters reference + initial coordinates = "
            f"{fmt(ref)} + {fmt(p - ref)} = {fmt(p)} have norm {norm:.12g} (off by {abs(norm - 1.0):.3g} "
            f"> {QUAT_NORM_TOL:g}). Exudyn adds referenceCoordinates and initialCoordinates component-"
            "wise, so their sum must be a unit quaternion: put the rotation in referenceCoordinates "
            "(or initialRotationMatrix of CreateRigidBody) and leave the initial rotation "
            "coordinates at zero, or make the sum unit.")

    def _init_solver(self):
        """The evaluator: its own solver object, writing no files and no sensors."""
        s = self.exu.SimulationSettings()
        s.solution.file.write = False
        s.solution.sensors.active = False
        s.show.computationTime = False
        s.show.statistics = False
        self.solver.InitializeSolver(self.mbs, s)

    # ------------------------------------------------------------------ velocity maps
    def _index_tables(self):
        """Per node type: q rows of position/rotation and V columns of ω/ṙ, batched."""
        self._pos_q = np.array([k[1][:3] for k in self.kinds], int).reshape(-1, 3)
        self._lin_v = np.array([k[2] + np.arange(3, 6) for k in self.kinds], int).reshape(-1, 3)
        self._types = {}
        for typ in RIGID:
            sel = [k for k in self.kinds if k[0] == typ]
            if sel:
                self._types[typ] = (np.array([k[1][3:] for k in sel]), np.array([k[2] + np.arange(3) for k in sel]))
        self._vq = np.array(self.layout.vector_q, int)
        self._vv = np.array(self.layout.vector_v, int)
        self._moving = {}
        for typ in RIGID:
            sel = [k for k in self.kinds if k[0] == typ]
            if sel:
                self._moving[typ] = (np.array([k[1] for k in sel]), np.array([k[2] + np.arange(6) for k in sel]))

    @staticmethod
    def _rot_blocks(typ, rot):
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
        H[self._pos_q, self._lin_v] = 1.0
        for typ, (rq, wv) in self._types.items():
            H[rq[:, :, None], wv[:, None, :]] = self._rot_blocks(typ, q[rq])
        H[self._vq, self._vv] = 1.0
        return H

    def rates_from_twist(self, q, V):
        """Exudyn's ODE2 velocity coordinates q̇_e = H(q) V."""
        qd = np.zeros(self.n2)
        qd[self._pos_q] = V[self._lin_v]
        for typ, (rq, wv) in self._types.items():
            qd[rq] = np.einsum("nij,nj->ni", self._rot_blocks(typ, q[rq]), V[wv])
        qd[self._vq] = V[self._vv]
        return qd

    def twist_from_rates(self, q, qd):
        V = np.zeros(self.nv)
        for (typ, idx, iv), b in zip(self.kinds, self.layout.bodies):
            V[iv + 3:iv + 6] = qd[idx[:3]]
            if typ == "RigidBodyRotVecLG":
                V[iv:iv + 3] = qd[idx[3:]]
            else:
                V[iv:iv + 3] = b.param._omega_from_rates(q[idx[3:]][None], qd[idx[3:]][None])[0]
        V[self._vv] = qd[self._vq]
        return V

    def Hdot_V(self, q, V):
        """Ḣ(q, q̇) V: the part of q̈_e not from V̇."""
        out = np.zeros(self.n2)
        for (typ, idx, iv), b in zip(self.kinds, self.layout.bodies):
            w = V[iv:iv + 3]
            if typ == "RigidBodyEP":
                out[idx[3:]] = -0.25 * (w @ w) * q[idx[3:]]
            elif typ == "RigidBodyRxyz":
                th = q[idx[3:]]
                d = b.param._rates_from_omega(th[None], w[None])[0]
                c1, s1 = np.cos(th[1]), np.sin(th[1])
                a, bb, cc = d
                da = (-cc * bb + a * s1 * bb) / c1
                db = cc * a * c1
                dc = -c1 * bb * a - s1 * da
                out[idx[3:]] = [da, db, dc]
        return out

    def _Hplus_Hdot_V(self, q, V):
        """H⁺ Ḣ V with H⁺ the left inverse of H (EP: 2G(p), which annihilates Ḣ V = -¼|ω|² p;
        Rxyz: G(θ); identity elsewhere)."""
        out = np.zeros(self.nv)
        if "RigidBodyRxyz" in self._types:
            hv = self.Hdot_V(q, V)
            rq, wv = self._types["RigidBodyRxyz"]
            th = q[rq]
            c1, s1, c2, s2 = np.cos(th[:, 1]), np.sin(th[:, 1]), np.cos(th[:, 2]), np.sin(th[:, 2])
            d = hv[rq]
            out[wv] = np.stack([c1 * c2 * d[:, 0] + s2 * d[:, 1], -c1 * s2 * d[:, 0] + c2 * d[:, 1],
                                s1 * d[:, 0] + d[:, 2]], axis=1)
        return out

    def _detect_constant_mass(self, rng=np.random.default_rng(7)):
        """Cache M̄ when the twist mass matrix is the same at q0 and two other configurations
        and the engine's M equals H⁺ᵀ M̄ H⁺ there (rigid bodies with the node at the centre
        of mass); then Exudyn's mass matrix is never evaluated again."""
        self._Mbar = None
        S, mbs = self.solver, self.mbs
        Ms = []
        for k in range(3):
            q = self.q0 if k == 0 else self._moved(self.q0, rng.normal(size=self.nv), 0.7)
            self.sd.SetODE2Coordinates(q - self.ref)
            S.ComputeMassMatrix(mbs)
            M = np.array(S.GetSystemMassMatrix())
            H = self.H(q)
            Mb = H.T @ M @ H
            Hp = np.linalg.pinv(H)
            if np.abs(M - Hp.T @ Mb @ Hp).max() > 1e-12 * max(1.0, np.abs(M).max()):
                break
            Ms.append(Mb)
        else:
            if all(np.abs(m - Ms[0]).max() <= 1e-12 * max(1.0, np.abs(Ms[0]).max()) for m in Ms):
                self._Mbar = 0.5 * (Ms[0] + Ms[0].T)
        self.sd.SetODE2Coordinates(self.q0 - self.ref)

    # ------------------------------------------------------------------ engine access
    def _write(self, q, qd, t):
        sd = self.sd
        sd.SetODE2Coordinates(q - self.ref)
        sd.SetODE2Coordinates_t(qd)
        sd.SetTime(t)

    def _Cq(self):
        S = self.solver
        S.SetSystemJacobian(self._jac_zero)
        S.ComputeJacobianAE(self.mbs, 1.0, 0.0, 0.0, False)
        n = self.solver.GetODE2size()
        return np.array(S.GetSystemJacobian())[n:, :n][self.ae_keep]

    def _evaluate(self, q, V, t, need_gamma=True):
        """Exudyn's M, Q, C_q at (q, V, t) mapped to twists: (M̄, Q̄, A, γ)."""
        S, mbs = self.solver, self.mbs
        H = self.H(q)
        qd = H @ V
        self._write(q, qd, t)
        S.ComputeODE2RHS(mbs)
        Q = np.array(S.GetSystemResidual())[:self.n2]
        if self._Mbar is None:
            S.ComputeMassMatrix(mbs)
            M = np.array(S.GetSystemMassMatrix())
            Mb = H.T @ M @ H
            Qb = H.T @ (Q - M @ self.Hdot_V(q, V))
        else:
            # constant twist mass matrix M̄ and M = H⁺ᵀ M̄ H⁺: Hᵀ M Ḣ V = M̄ H⁺ Ḣ V
            Mb = self._Mbar
            Qb = H.T @ Q - Mb @ self._Hplus_Hdot_V(q, V)
        self.n_eval += 1
        if not self.n_constraints:
            return Mb, Qb, None, None
        A = self._Cq() @ H
        if need_gamma:
            gam = self._gamma(q, V)
            self._write(q, qd, t)                         # leave the evaluated state in the system
            return Mb, Qb, A, gam
        return Mb, Qb, A, None

    def _lgt(self, param):
        if param.name not in self._so3xr3:
            self._so3xr3[param.name] = _lgt.LGT(param, "SO3xR3", "exp")
        return self._so3xr3[param.name]

    def _moved(self, q, V, eps):
        """q moved along the twist V by eps: τ on SO(3)xR³ (batched per node type),
        additive for vector-space coordinates."""
        out = q.copy()
        for typ, (qi, vi) in self._moving.items():
            out[qi] = self._lgt(RIGID[typ]).tau(q[qi], eps * V[vi])
        out[self._vq] = q[self._vq] + eps * V[self._vv]
        return out

    def _AV_at(self, q, V):
        """A(q) V from Exudyn's velocity-level constraint residual C_q(q) q̇_e (a vector:
        no dense Jacobian transfer)."""
        self._write(q, self.rates_from_twist(q, V), self.sd.GetTime())
        self.solver.ComputeAlgebraicEquations(self.mbs, True)
        return np.array(self.solver.GetSystemResidual())[self.solver.GetODE2size():][self.ae_keep]

    def _gamma(self, q, V):
        """γ = d/dt (A(q) V) at fixed V (Exudyn does not provide it): central differences
        of A V along the path q(s) = τ(q, sV), whose twist is V for all s."""
        eps = _EPS_GAMMA / max(1.0, float(np.abs(V).max()))
        return (self._AV_at(self._moved(q, V, eps), V) - self._AV_at(self._moved(q, V, -eps), V)) / (2 * eps)

    # ------------------------------------------------------------------ model protocol
    def f(self, q, V, t):
        M, Q, A, gam = self._evaluate(q, V, t)
        if A is None:
            return np.linalg.solve(M, Q)
        return solve_kkt(M, A, Q, -gam)[0]

    def mass_matrix(self, q):
        if self._Mbar is not None:
            return self._Mbar.copy()
        return self._evaluate(q, np.zeros(self.nv), self.sd.GetTime(), need_gamma=False)[0]

    def forces(self, q, V, t):
        return self._evaluate(q, V, t, need_gamma=False)[1]

    def constraints(self, q):
        if not self.n_constraints:
            return np.zeros(0)
        self.sd.SetODE2Coordinates(q - self.ref)
        self.solver.ComputeAlgebraicEquations(self.mbs)
        n = self.solver.GetODE2size()
        return np.array(self.solver.GetSystemResidual())[n:][self.ae_keep]

    def constraint_jacobian(self, q):
        if not self.n_constraints:
            return np.zeros((0, self.nv))
        self.sd.SetODE2Coordinates(q - self.ref)
        return self._Cq() @ self.H(q)

    def constraint_gamma(self, q, V):
        return self._gamma(q, V) if self.n_constraints else np.zeros(0)

    def accelerations(self, q, V, t):
        """Exudyn's ODE2 accelerations q̈_e = H V̇ + Ḣ V at (q, V, t)."""
        Vd = self.f(q, V, t)
        return self.H(q) @ Vd + self.Hdot_V(q, V)

    def write_back(self, q, V, t):
        self._write(q, self.rates_from_twist(q, V), t)
