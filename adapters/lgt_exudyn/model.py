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
from lgt_bridge.errors import InputError, LGTError, ModelError
from lgt_bridge.groups.batch import hat
from lgt_bridge.model import Layout, Model, RigidBody, combine_iteration, solve_kkt

RIGID = {"RigidBodyEP": params.QUAT_WXYZ, "RigidBodyRotVecLG": params.ROTVEC,
         "RigidBodyRxyz": params.RXYZ}
#: node types whose ODE2 coordinates are a vector space (q̇ = v)
VECTOR = ("Point", "Point2D", "RigidBody2D", "GenericODE2", "1D", "PointSlope1", "PointSlope12",
          "PointSlope23", "Point2DSlope1", "Point3DSlope1", "Point3DSlope23")
_EPS_GAMMA = 1e-5


def _exudyn():
    import exudyn
    return exudyn


def _engine_error(model, what, exc):
    """The ModelError for an exception Exudyn raised while ``what`` evaluated the model (a
    user function that failed, an evaluation Exudyn rejects), or None when ``exc`` is not
    Exudyn's (a bug: it keeps its traceback)."""
    if not type(exc).__module__.startswith("exudyn"):
        return None
    text = str(exc).split("\nAt:")[0]           # Exudyn appends a traceback after "At:"
    lines = [ln.strip() for ln in text.strip().splitlines() if ln.strip()]
    msg = " ".join(lines) if lines else type(exc).__name__
    if len(msg) > 300:
        msg = msg[:300] + "..."
    t = model.sd.GetTime()
    return ModelError(f"Exudyn raised while lgt_bridge evaluated the model ({what}) at "
                      f"t = {t:.9g}: {msg}. If a user function failed, "
                      "fix it (run the script with Exudyn's own solver to see it in context).")


def _engine_call(method):
    """Turn an exception Exudyn raises inside ``method`` into a ModelError naming the time
    and Exudyn's message (:func:`_engine_error`); the original stays chained (``--debug``
    shows it)."""
    import functools

    @functools.wraps(method)
    def call(self, *args):
        try:
            return method(self, *args)
        except LGTError:
            raise
        except Exception as exc:
            err = _engine_error(self, method.__name__, exc)
            if err is None:
                raise
            raise err from exc
    return call


class ExudynModel(Model):
    """An assembled Exudyn ``MainSystem`` as a model for :func:`lgt_bridge.simulate.simulate`.

    backend: 'numba' (compiled conversions, :mod:`.kernels`) or 'numpy' (the reference
    methods below); default $LGT_BRIDGE_BACKEND, else numba. Build the model again after
    ``mbs.Assemble()``: the compiled path writes through views of Exudyn's state."""

    _ODE1 = False

    def __new__(cls, mbs=None, *args, **kwargs):
        # a system with ODE1 coordinates gets the subclass that integrates them alongside
        if cls is ExudynModel and getattr(mbs, "systemIsConsistent", False) and mbs.systemData.ODE1Size():
            cls = ExudynModelODE1
        return super().__new__(cls)

    def __init__(self, mbs, simulationSettings=None, backend=None):
        from lgt_bridge import backend as _backend
        self._compiled = _backend.compiled(backend)
        self._P = None                  # the kernels' pack (built at the first f)
        self._Mbar_inv = None
        self._Mbar_pd = None            # M̄ constant and positive definite (checked once)
        exu = _exudyn()
        self.exu, self.mbs = exu, mbs
        if not getattr(mbs, "systemIsConsistent", False):
            raise InputError("Exudyn system is not assembled (mbs.systemIsConsistent is False); "
                             "call mbs.Assemble() before wrapping it.")
        sd = self.sd = mbs.systemData
        self.n2, n1, self.nae = sd.ODE2Size(), sd.ODE1Size(), sd.AEsize()
        if n1 and not self._ODE1:
            raise InputError(
                f"Exudyn system has {n1} ODE1 coordinates (first-order states) in "
                f"{_items_with(mbs, sd.GetObjectLTGODE1)}: lgt_bridge integrates second-order (ODE2) "
                "systems only and cannot integrate first-order states alongside yet. Run this model "
                "with Exudyn's own exu.SolveDynamic (e.g. the default generalized-alpha solver).")
        bodies, vq, ep_ae = [], [], []
        self.kinds = []
        iv = 0
        self.vidx_of_q = np.full(self.n2, -1)
        for i in range(sd.NumberOfNodes()):
            node = mbs.GetNode(i)
            typ = node["nodeType"]
            try:
                idx = list(sd.GetNodeLTGODE2(i))
            except Exception:                           # nodes without ODE2 coordinates
                idx = []
            if typ in RIGID:
                par = RIGID[typ]
                bodies.append(RigidBody(par, tuple(idx[:3]), tuple(idx[3:]), tuple(range(iv, iv + 6)),
                                        node.get("name", f"node{i}")))
                self.kinds.append((typ, np.array(idx), iv))
                iv += 6
                if typ == "RigidBodyEP":
                    ep_ae += list(sd.GetNodeLTGAE(i))
            elif typ == "PointGround" or not len(idx):
                continue                                       # no ODE2 coordinates
            elif typ in VECTOR:
                for k in idx:
                    vq.append(k)
                    self.vidx_of_q[k] = iv
                    iv += 1
            else:
                raise InputError(f"Exudyn node {i} ({node.get('name', '')!r}) has type {typ!r}, which "
                                 f"lgt_bridge does not support; supported rigid nodes: {sorted(RIGID)}, "
                                 f"vector-space nodes: {list(VECTOR)}. Run this model with Exudyn's own "
                                 "exu.SolveDynamic, or build it from supported nodes.")
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
        self._ae0 = self.solver.GetODE2size() + self.solver.GetODE1size()    # first AE row
        self._jac_zero = np.zeros((self._ae0 + self.nae, self._ae0 + self.nae))
        self.q0 = np.array(sd.GetODE2Coordinates()) + self.ref
        self.V0 = self.twist_from_rates(self.q0, np.array(sd.GetODE2Coordinates_t()))
        self.t0 = float(sd.GetTime())
        self._classify_constraints()
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
        if sd.DataSize():
            # contact/friction states: Exudyn's own discontinuous iteration after each step
            self.post_step = self._post_newton
            self._disc_tol = float(s.timeIntegration.discontinuous.iterationTolerance)
        self._detect_constant_mass()
        if any(typ == "RigidBodyRxyz" for typ, _, _ in self.kinds):
            # Exudyn's ODE2 Jacobian does not see the adapter's Ḣ V term of Rxyz nodes (C_t was
            # 170 % off on a spring-loaded Rxyz body): generalized-α differences the step instead
            self.iteration_matrix = None

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

    def _post_newton(self, q, V, t):
        """Exudyn's discontinuous iteration at the end of a step (its PostNewton: contact and
        friction states updated from the state (q, V, t)); True when they changed by more
        than timeIntegration.discontinuous.iterationTolerance."""
        self.write_back(q, V, t)
        return float(self.solver.PostNewton(self.mbs, self._eval_settings)) > self._disc_tol

    def discontinuous_state(self):
        return np.array(self.sd.GetDataCoordinates())

    def set_discontinuous_state(self, d):
        self.sd.SetDataCoordinates(d)

    def _init_solver(self):
        """The evaluator: its own solver object, writing no files and no sensors."""
        s = self._eval_settings = self.exu.SimulationSettings()
        s.solution.file.write = False
        s.solution.sensors.active = False
        s.show.computationTime = False
        s.show.statistics = False
        # the bridge computes its own initial accelerations; Exudyn's would fail (with a
        # warning) on redundant constraints
        s.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
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

    def _H_pinv(self, q):
        """The pseudo-inverse of H(q), block by block (H is a permutation of per-node
        blocks: identities and each rotation's 4x3 or 3x3 block)."""
        Hp = np.zeros((self.nv, self.n2))
        Hp[self._lin_v, self._pos_q] = 1.0
        for typ, (rq, wv) in self._types.items():
            Hp[wv[:, :, None], rq[:, None, :]] = np.linalg.pinv(self._rot_blocks(typ, q[rq]))
        Hp[self._vv, self._vq] = 1.0
        return Hp

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
        from scipy.sparse import csr_matrix
        self._Mbar = None
        S, mbs = self.solver, self.mbs
        Ms = []
        if not self.nv:                  # no ODE2 coordinates (a purely first-order system)
            self._Mbar = np.zeros((0, 0))
            return
        for k in range(3):
            q = self.q0 if k == 0 else self._moved(self.q0, rng.normal(size=self.nv), 0.7)
            self.sd.SetODE2Coordinates(q - self.ref)
            S.ComputeMassMatrix(mbs)
            M = np.array(S.GetSystemMassMatrix())
            H, Hp = csr_matrix(self.H(q)), csr_matrix(self._H_pinv(q))    # a few entries per row
            Mb = np.asarray((H.T @ (H.T @ M).T).T)                         # Hᵀ M H
            back = np.asarray((Hp.T @ (Hp.T @ Mb).T).T)                    # H⁺ᵀ M̄ H⁺
            if np.abs(M - back).max() > 1e-12 * max(1.0, np.abs(M).max()):
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

    def _ae_jacobian(self, c_pos=1.0, c_vel=1.0):
        """Exudyn's AE Jacobian at the written state: c_pos ∂C/∂q + c_vel ∂C/∂q̇ (all AE
        rows, n2 columns) and the AE-AE diagonal (1 on rows Exudyn keeps as λ = 0)."""
        S = self.solver
        S.SetSystemJacobian(self._jac_zero)
        S.ComputeJacobianAE(self.mbs, c_pos, c_vel, 0.0, False)
        J = np.array(S.GetSystemJacobian())
        a = self._ae0
        return J[a:, :self.n2], np.diagonal(J[a:, a:]).copy()

    def _Cq(self):
        """The kept rows of the AE Jacobian: ∂C/∂q on position rows, ∂C/∂q̇ on velocity-level
        rows (each row has only one of the two, so one call with both factors gives both)."""
        return self._ae_jacobian(1.0, 1.0 if len(self.velocity_rows) else 0.0)[0][self.ae_keep]

    # ------------------------------------------------------------------ constraint classes
    def _classify_constraints(self):
        """Sort Exudyn's algebraic equations (apart from the Euler-parameter norms): rows
        Exudyn keeps as λ = 0 (``constrainedAxes`` zeros: zero Jacobian row, unit AE
        diagonal) are dropped; rows with a velocity Jacobian are velocity-level
        (nonholonomic: rolling); rows that depend linearly on others at q0 (redundant
        closed loops) are set aside; and the constraints are time-dependent when their
        residual at q0 changes with the time written into the system."""
        self.velocity_rows = ()
        self.time_dependent_constraints = False
        self.inactive_rows, self.redundant_rows = [], []
        self._velocity_level, self._exudyn_gt = True, False
        if not self.n_constraints:
            return
        qd0 = self.rates_from_twist(self.q0, self.V0)
        self._write(self.q0, qd0, self.t0)
        Cp, diag = self._ae_jacobian(1.0, 0.0)
        Cv, _ = self._ae_jacobian(0.0, 1.0)
        keep = []
        for i in self.ae_keep:
            if Cp[i].any() or Cv[i].any():
                keep.append(i)
            elif diag[i] == 1.0:
                self.inactive_rows.append(int(i))
            else:
                self.redundant_rows.append(int(i))
        keep = np.array(keep, int)
        vel = np.array([Cv[i].any() for i in keep], bool)
        self._velocity_level = self._can_evaluate_velocity_level()
        if vel.any() and not self._velocity_level:
            raise InputError(f"Exudyn model: {self._ae_owners([int(i) for i in keep[vel]])} has velocity-level "
                             "constraint equations, but Exudyn cannot evaluate the model's algebraic "
                             f"equations at velocity level ({self._velocity_level_error}); lgt_bridge needs "
                             "them. Run this model with Exudyn's own exu.SolveDynamic.")
        A = (Cp[keep] + Cv[keep]) @ self.H(self.q0)
        ind = _independent_rows(A)
        self.redundant_rows += [int(i) for i in keep[~ind]]
        self.ae_keep, vel = keep[ind], vel[ind]
        self.n_constraints = len(self.ae_keep)
        self.velocity_rows = tuple(int(k) for k in np.flatnonzero(vel))
        self.time_dependent_constraints = self._detect_time_dependence()
        self._write(self.q0, qd0, self.t0)
        if self.redundant_rows:
            import warnings

            from lgt_bridge.errors import ModelNote
            warnings.warn(ModelNote(
                f"Exudyn model: {len(self.redundant_rows)} of its {len(self.redundant_rows) + self.n_constraints} "
                f"constraint equations are redundant at the initial state (algebraic equations "
                f"{self.redundant_rows}: {self._ae_owners(self.redundant_rows)}); lgt_bridge sets them "
                "aside and enforces the others (the motion is the same; their Lagrange multipliers "
                "are not unique)."), stacklevel=3)

    def _can_evaluate_velocity_level(self):
        """False when Exudyn refuses the velocity-level algebraic equations (e.g. a generic
        joint with ``offsetUserFunction_t``: NotImplementedFeatureError); then A V comes
        from the Jacobian and ∂g/∂t from differences in time."""
        try:
            self.solver.ComputeAlgebraicEquations(self.mbs, True)
            return True
        except Exception as exc:          # Exudyn raises its own (non-Python) exception types
            self._velocity_level_error = str(exc).strip().splitlines()[-1][:200]
            return False

    def project_initial(self, q0, V0, t0, tol=1e-12, max_iter=60):
        """The initial state moved onto the constraints the way Exudyn's own solver moves it
        in its first step (its limit for small steps): positions to the q₁ on g(q₁, t0) = 0
        with M(q₁) Δ = C_q(q₁)ᵀ μ, Δ the step in each node's own coordinates (the plain
        difference for Euler parameters, positions, angles and vector coordinates; the
        body-frame increment for RotVecLG nodes) with Exudyn's mass matrix and its
        Euler-parameter rows; then velocities M-orthogonally onto A V = b at q₁. Returns
        (q, V, report) as :func:`lgt_bridge.integrators.constraints.project_initial`."""
        from lgt_bridge.integrators.constraints import project_initial as generic
        if not self.n_constraints:
            return q0, V0, None
        rows = np.array(sorted(self.ep_ae) + [int(self.ae_keep[k]) for k in self.position_rows], int)
        n2 = self.n2
        q2 = self._project_positions(q0[:n2], t0, rows, tol, max_iter)
        q = q0 if q2 is None else np.concatenate([q2, q0[n2:]])
        q1, V1, rep = generic(self, q, V0, t0)             # velocities (positions already hold)
        if q is q0 and rep is None:
            return q0, V0, None
        g0 = self._ae_residual_rows(q0[:n2], t0, rows)
        b = self.velocity_rhs(q0, t0)
        rv = self.constraint_jacobian(q0) @ V0 - (0.0 if b is None else b)
        after = float(np.abs(self._ae_residual_rows(q1[:n2], t0, rows)).max()) if len(rows) else 0.0
        self.write_back(q1, V1, t0)
        return q1, V1, dict(
            position_residual=float(np.abs(g0).max()) if len(g0) else 0.0,
            velocity_residual=float(np.abs(rv).max()) if len(rv) else 0.0,
            position=float(np.abs(q1 - q0).max()), velocity=float(np.abs(V1 - V0).max()),
            position_residual_after=after,
            velocity_residual_after=(rep or {}).get("velocity_residual_after", 0.0))

    def _project_positions(self, q0, t0, rows, tol, max_iter):
        """Exudyn's first-step rule for positions (see :meth:`project_initial`); None when
        q0 already satisfies the constraints."""
        z = np.zeros(self.n2)
        g = self._ae_residual_rows(q0, t0, rows)
        if not len(g) or np.abs(g).max() <= tol:
            return None
        q, D = q0, np.zeros(self.n2)
        nae = len(rows)
        for _ in range(max_iter):
            self._write(q, z, t0)
            self.solver.ComputeMassMatrix(self.mbs)
            M = np.array(self.solver.GetSystemMassMatrix())
            C = self._ae_jacobian(1.0, 0.0)[0][rows]
            K = np.block([[M, C.T], [C, np.zeros((nae, nae))]])
            rhs = np.concatenate([np.zeros(self.n2), C @ D - g])
            D_new = np.linalg.lstsq(K, rhs, rcond=1e-13)[0][:self.n2]
            step = np.abs(D_new - D).max()
            D = D_new
            q = self._plus(q0, D)
            g = self._ae_residual_rows(q, t0, rows)
            if np.abs(g).max() <= tol and step <= 1e-12 * (1.0 + np.abs(D).max()):
                return q
        raise InputError(f"Exudyn model: the initial positions violate the constraints by "
                         f"{np.abs(self._ae_residual_rows(q0, t0, rows)).max():.3g} and could not be "
                         f"moved onto them ({max_iter} iterations left {np.abs(g).max():.3g}); "
                         "start the model closer to a consistent configuration.")

    def _ae_residual_rows(self, q, t, rows):
        self._write(q, np.zeros(self.n2), t)
        self.solver.ComputeAlgebraicEquations(self.mbs, False)
        return np.array(self.solver.GetSystemResidual())[self._ae0:][rows]

    def _plus(self, q0, D):
        """q0 moved by D in Exudyn's own increments: plain addition, except RotVecLG
        rotations, R = R0 exp(Dθ) (body frame)."""
        q = q0 + D
        if "RigidBodyRotVecLG" in self._moving:
            qi, vi = self._moving["RigidBodyRotVecLG"]
            tw = np.zeros(vi.shape)
            tw[:, :3] = D[qi[:, 3:]]
            tw[:, 3:] = D[qi[:, :3]]
            q[qi] = self._lgt(RIGID["RigidBodyRotVecLG"]).tau(q0[qi], tw)
        return q

    def _ae_owners(self, rows):
        """'Object k (TypeName)' for each object owning one of the AE ``rows``."""
        sd, names = self.sd, []
        for k in range(sd.NumberOfObjects()):
            try:
                ltg = set(sd.GetObjectLTGAE(k))
            except Exception:                       # objects without algebraic equations
                continue
            if ltg & set(rows):
                o = self.mbs.GetObject(k)
                names.append(f"object {k} {o.get('name', '')!r} ({o.get('objectType', '?')})")
        return ", ".join(names) or "unknown objects"

    def _ae_residual(self, q, qd, t, velocity_level):
        self._write(q, qd, t)
        self.solver.ComputeAlgebraicEquations(self.mbs, velocity_level)
        return np.array(self.solver.GetSystemResidual())[self._ae0:][self.ae_keep]

    def _detect_time_dependence(self):
        """True when the constraint residual at q0 (positions, and velocities at rest)
        changes with time; then also whether Exudyn's velocity-level residual carries
        ∂g/∂t (offset user functions with their ``_t`` derivative) — if not, the bridge
        differentiates g in time itself."""
        q, z = self.q0, np.zeros(self.n2)
        ts = self.t0 + np.array([0.0, 0.1234567, 0.7654321])
        gp = [self._ae_residual(q, z, t, False) for t in ts]
        gv = [self._ae_residual(q, z, t, True) for t in ts] if self._velocity_level else gp[:1]
        scale = 1e-13 * (1.0 + np.abs(gp[0]).max() + np.abs(gv[0]).max())
        self._exudyn_gt = False
        if all(np.abs(g - gp[0]).max() <= scale for g in gp) and all(
                np.abs(g - gv[0]).max() <= scale for g in gv):
            return False
        if not self._velocity_level:
            return True
        pos = self.position_rows
        ok = True
        for t in ts:
            gt = self._gt_fd(q, t)[pos]
            ev = self._ae_residual(q, z, t, True)[pos]
            ok &= bool(np.abs(gt - ev).max() <= 1e-6 * (1.0 + np.abs(gt).max()))
        self._exudyn_gt = ok
        return True

    def _gt_fd(self, q, t):
        """∂g/∂t at (q, t) by central differences of the position-level residual."""
        e = 1e-6 * max(1.0, abs(t))
        z = np.zeros(self.n2)
        return (self._ae_residual(q, z, t + e, False) - self._ae_residual(q, z, t - e, False)) / (2 * e)

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
            gam = self._gamma(q, V, t)
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

    def _AV_at(self, q, V, t):
        """A(q) V - b(q, t) from Exudyn's velocity-level constraint residual C_q q̇_e + ∂g/∂t
        (a vector: no dense Jacobian transfer)."""
        if not self._velocity_level:                    # A V from the Jacobian, + ∂g/∂t
            self._write(q, self.rates_from_twist(q, V), t)
            r = self._Cq() @ self.rates_from_twist(q, V)
            return r + self._gt_fd(q, t) if self.time_dependent_constraints else r
        r = self._ae_residual(q, self.rates_from_twist(q, V), t, True)
        if self.time_dependent_constraints and not self._exudyn_gt:
            pos = self.position_rows
            r[pos] += self._gt_fd(q, t)[pos] - self._ae_residual(q, np.zeros(self.n2), t, True)[pos]
        return r

    def _gamma(self, q, V, t):
        """γ = d/dt (A(q) V - b(q, t)) at fixed V (Exudyn does not provide it): central
        differences of A V - b along the path (τ(q, sV), t + s), whose twist is V for all s."""
        vmax = max(1.0, float(np.abs(V).max()))
        eps = _EPS_GAMMA / vmax
        td = self.time_dependent_constraints
        if td and not self._exudyn_gt:
            return self._gamma_second_difference(q, V, t, 1e-3 / vmax)
        dt = eps if td else 0.0
        return (self._AV_at(self._moved(q, V, eps), V, t + dt)
                - self._AV_at(self._moved(q, V, -eps), V, t - dt)) / (2 * eps)

    def _gamma_second_difference(self, q, V, t, e):
        """γ when Exudyn's velocity-level residual lacks ∂g/∂t (an offset user function
        without its ``_t``): on position rows γ = φ''(0) for φ(s) = g(τ(q, sV), t + s),
        by second differences with Richardson extrapolation (error O(e⁴) + rounding/e²);
        velocity-level rows by central differences of Exudyn's residual."""
        z = np.zeros(self.n2)
        phi = {k: self._ae_residual(self._moved(q, V, k * e), z, t + k * e, False) for k in (-2, -1, 0, 1, 2)}
        d1 = (phi[1] - 2 * phi[0] + phi[-1]) / e ** 2
        d2 = (phi[2] - 2 * phi[0] + phi[-2]) / (4 * e ** 2)
        gam = (4 * d1 - d2) / 3
        if self.velocity_rows:
            vr = list(self.velocity_rows)
            ev = _EPS_GAMMA / max(1.0, float(np.abs(V).max()))
            cv = [self._ae_residual(self._moved(q, V, k * ev), self.rates_from_twist(self._moved(q, V, k * ev), V),
                                    t + k * ev, True)[vr] for k in (1, -1)]
            gam[vr] = (cv[0] - cv[1]) / (2 * ev)
        return gam

    # ------------------------------------------------------------------ model protocol
    @_engine_call
    def f(self, q, V, t):
        if not self.nv:
            self._write(q, np.zeros(0), t)
            return np.zeros(0)
        if self._compiled:
            P = self._P if self._P is not None else self._pack()
            q, V = np.ascontiguousarray(q, float), np.ascontiguousarray(V, float)
            if P.plain_f is not None:
                return P.plain_f(q, V, float(t))
            return self._kernels.f_compiled(self, P, q, V, float(t))
        M, Q, A, gam = self._evaluate(q, V, t)
        if A is None:
            return np.linalg.solve(M, Q)
        return solve_kkt(M, A, Q, -gam)[0]

    @_engine_call
    def mass_matrix(self, q):
        if self._Mbar is not None:
            return self._Mbar.copy()
        return self._evaluate(q, np.zeros(self.nv), self.sd.GetTime(), need_gamma=False)[0]

    @_engine_call
    def forces(self, q, V, t):
        if self._compiled and self.nv:
            return self._forces_compiled(q, V, t)[0]
        return self._evaluate(q, V, t, need_gamma=False)[1]

    def _forces_compiled(self, q, V, t):
        """(Q̄, M̄) from the kernels: one state write, ComputeODE2RHS (and ComputeMassMatrix when
        M̄ is not constant); the state stays written. Fresh arrays."""
        P = self._P if self._P is not None else self._pack()
        K, S, mbs = self._kernels, self.solver, self.mbs
        q, V = np.ascontiguousarray(q, float), np.ascontiguousarray(V, float)
        K.write(P.I, P.W, q, V, 0.0, P.qpos, P.qvel)
        self.sd.SetTime(t)
        S.ComputeODE2RHS(mbs)
        Qbar = np.empty(self.nv)
        if P.constant_mass:
            K.forces(P.I, P.W, q, V, S.GetSystemResidual(), P.empty, Qbar, P.empty)
            Mbar = self._Mbar
        else:
            S.ComputeMassMatrix(mbs)
            Mbar = np.empty((self.nv, self.nv))
            K.forces(P.I, P.W, q, V, S.GetSystemResidual(), S.GetSystemMassMatrix(), Qbar, Mbar)
        self.n_eval += 1
        return Qbar, Mbar

    @_engine_call
    def iteration_matrix(self, q, V, t, c_acc, c_vel, c_pos):
        """M̄ c_acc + C_t c_vel + K_t c_pos for generalized-α's Newton matrix, in the twists V and
        the SO(3)xR³ increments z (the derivatives of R = M̄ V̇ - Q̄(q(z), V, t)), from Exudyn's
        own Jacobians of its ODE2 right-hand side Q_e (ComputeJacobianODE2RHS, loads included):

            C_t ≈ -Hᵀ (∂Q_e/∂q̇_e) H,     K_t ≈ -Hᵀ (∂Q_e/∂q_e) H

        (q̇_e = H V, and H is also ∂q_e/∂z at z = 0). Left out: (∂Hᵀ/∂z) of the residual and
        the velocity dependence of the Ḣ V term (EP and Rxyz rotations), and the joints'
        geometric stiffness; measured against central differences of M̄ V̇ - Q̄ on a spring-loaded
        body (tests/test_exudyn_iteration.py): C_t to 3e-8, K_t to 0.1 % (RotVecLG) and 4 % (EP),
        so generalized-α's modified Newton still contracts (it refreshes the matrix when it does
        not). Models with Rxyz nodes do not get it (see __init__). Kept for the calls at the same
        (q, V, t)."""
        key = (float(t), np.asarray(q, float).tobytes(), np.asarray(V, float).tobytes())
        cached = getattr(self, "_it_cache", None)
        if cached is None or cached[0] != key:
            S, n2 = self.solver, self.n2
            H = self.H(np.asarray(q, float))
            Mbar = self._forces_compiled(q, V, t)[1] if self._compiled else self._evaluate(q, V, t, False)[0]
            self._write(np.asarray(q, float), H @ np.asarray(V, float), t)
            parts = [Mbar]
            for fq, fv in ((0.0, 1.0), (1.0, 0.0)):
                S.ComputeJacobianODE2RHS(self.mbs, fq, fv, 1.0, 2)
                J = np.asarray(S.GetSystemJacobian())[:n2, :n2]
                parts.append(-(H.T @ (J @ H)))
            cached = self._it_cache = (key, parts)
        return combine_iteration(cached[1], c_acc, c_vel, c_pos)

    def constraints(self, q):
        return self.constraints_at(q, self.sd.GetTime())

    @_engine_call
    def constraints_at(self, q, t):
        """Exudyn's position-level residuals g(q, t) of the kept rows (0 on velocity-level rows)."""
        if not self.n_constraints:
            return np.zeros(0)
        self.sd.SetODE2Coordinates(q - self.ref)
        self.sd.SetTime(t)
        self.solver.ComputeAlgebraicEquations(self.mbs, False)
        g = np.array(self.solver.GetSystemResidual())[self._ae0:][self.ae_keep]
        if self.velocity_rows:
            g[list(self.velocity_rows)] = 0.0
        return g

    @_engine_call
    def velocity_rhs(self, q, t):
        """b(q, t) in A V = b: -∂g/∂t of time-dependent rows (None otherwise)."""
        if not self.time_dependent_constraints:
            return None
        z = np.zeros(self.nv)
        return -self._AV_at(q, z, t)

    @_engine_call
    def constraint_jacobian(self, q):
        if not self.n_constraints:
            return np.zeros((0, self.nv))
        self.sd.SetODE2Coordinates(q - self.ref)
        if self._compiled:
            P = self._pack()
            S = self.solver
            S.SetSystemJacobian(self._jac_zero)
            S.ComputeJacobianAE(self.mbs, 1.0, 1.0 if len(self.velocity_rows) else 0.0, 0.0, False)
            A = np.empty((self.n_constraints, self.nv))
            self._kernels.constraint_matrix(P.I, P.W, np.ascontiguousarray(q, float), S.GetSystemJacobian(),
                                            P.rows, A)
            return A
        return self._Cq() @ self.H(q)

    def solve_mass(self, q, B):
        """M̄⁻¹ B: through the cached inverse when the twist mass matrix is constant."""
        if self._Mbar is None:
            return np.linalg.solve(ExudynModel.mass_matrix.__wrapped__(self, q), B)
        if self._Mbar_inv is None:
            self._Mbar_inv = np.linalg.inv(self._Mbar)
        return self._Mbar_inv @ B

    def check_mass_matrix(self, q):
        """InputError when the twist mass matrix at q is singular or indefinite (as
        ``simulate`` checks every model before the first step); a constant positive definite
        M̄ is checked once, by a Cholesky factorization, for all later runs."""
        from lgt_bridge.validation import MASS_CHECK_MAX_NV, mass_defects, mass_message
        if self._Mbar is not None:
            if self._Mbar_pd is None:
                try:
                    np.linalg.cholesky(self._Mbar)
                    self._Mbar_pd = True
                except np.linalg.LinAlgError:
                    self._Mbar_pd = False
            if self._Mbar_pd:
                return
        if self.layout.nv > MASS_CHECK_MAX_NV:
            return
        M = self.mass_matrix(q)
        A = self.constraint_jacobian(q) if self.n_constraints else None
        d = mass_defects(M, A)
        if d:
            raise InputError(mass_message(d, [self.layout.owner("V", i) for i, _ in d]))

    def reset_caches(self):
        """Drop what the model builds on its first runs (the kernels' pack and the f built on
        it, the cached M̄⁻¹ and M̄'s definiteness): the next run pays what a run on a fresh
        model pays (benchmarks), and a system assembled again is packed again."""
        self._P = None
        self._Mbar_inv = None
        self._Mbar_pd = None
        self.__dict__.pop("f", None)

    def _pack(self):
        if self._P is None:
            from . import kernels
            self._kernels = kernels
            P = self._P = kernels.pack(self)
            P.plain_f = plain = kernels.plain_f(self, P)
            if plain is not None and type(self) is ExudynModel:
                # unconstrained, constant M̄: f is the kernels' closure from now on (the
                # same calls as below, with nothing looked up per call)
                contiguous = np.ascontiguousarray

                def f(q, V, t):
                    try:
                        return plain(contiguous(q, float), contiguous(V, float), float(t))
                    except Exception as exc:
                        err = _engine_error(self, "f", exc)
                        if err is None:
                            raise
                        raise err from exc
                self.f = f
        return self._P

    @_engine_call
    def constraint_gamma(self, q, V, t=None):
        if not self.n_constraints:
            return np.zeros(0)
        return self._gamma(q, V, self.sd.GetTime() if t is None else t)

    @_engine_call
    def accelerations(self, q, V, t):
        """Exudyn's ODE2 accelerations q̈_e = H V̇ + Ḣ V at (q, V, t)."""
        Vd = self.f(q, V, t)
        return self.H(q) @ Vd + self.Hdot_V(q, V)

    def write_back(self, q, V, t):
        if self._compiled and self.nv:
            P = self._pack()
            self._kernels.write(P.I, P.W, np.ascontiguousarray(q, float), np.ascontiguousarray(V, float),
                                0.0, P.qpos, P.qvel)
            self.sd.SetTime(t)
            return
        self._write(q, self.rates_from_twist(q, V), t)


#: rows of the normalized constraint Jacobian whose pivot falls below this count as dependent
RANK_TOL = 1e-9


def _independent_rows(A):
    """Boolean mask of a maximal set of linearly independent rows of A (pivoted QR of the
    row-normalized Aᵀ: the rows picked first are kept)."""
    from scipy.linalg import qr
    n = A.shape[0]
    if n == 0:
        return np.ones(0, bool)
    norms = np.linalg.norm(A, axis=1)
    An = A / np.where(norms > 0, norms, 1.0)[:, None]
    _, R, piv = qr(An.T, mode="economic", pivoting=True)
    d = np.abs(np.diagonal(R))
    rank = int(np.sum(d > RANK_TOL * max(d.max(initial=0.0), 1e-300)))
    mask = np.zeros(n, bool)
    mask[piv[:rank]] = True
    return mask


def _items_with(mbs, ltg):
    """'object 3 'name' (Type), ...' for the objects whose ``ltg(k)`` (coordinate indices) is not empty."""
    sd, names = mbs.systemData, []
    for k in range(sd.NumberOfObjects()):
        try:
            has = len(ltg(k)) > 0
        except Exception:                   # objects without coordinates of that kind
            has = False
        if has:
            o = mbs.GetObject(k)
            names.append(f"object {k} {o.get('name', '')!r} ({o.get('objectType', '?')})")
    return ", ".join(names[:6]) + (", ..." if len(names) > 6 else "") if names else "its nodes"


class ExudynModelODE1(ExudynModel):
    """An Exudyn system with ODE1 coordinates y (first-order states: controllers, filters,
    hydraulics), ẏ = Exudyn's ODE1 right-hand side. Each y_i is carried as the *rate* of a
    vector-space pair: V gets the n1 entries y (V̇_y = ẏ) and q gets n1 entries that hold
    ∫y dt, which nothing reads; so every method integrates y with the rest of the state
    (generalized-α as its trapezoidal-like update of a rate). The ODE2 part is
    :class:`ExudynModel`'s, with y written into Exudyn before each evaluation (ODE2 forces
    may depend on it)."""

    _ODE1 = True
    #: generalized-α builds its Newton matrix by finite differences (the ODE1 rows have no
    #: analytic Jacobian here)
    iteration_matrix = None

    def __init__(self, mbs, simulationSettings=None, backend=None):
        super().__init__(mbs, simulationSettings, backend)
        sd = self.sd
        self.n1 = sd.ODE1Size()
        self.ref1 = np.zeros(self.n1)        # Exudyn's system vector of ODE1 references is empty
        for i in range(sd.NumberOfNodes()):
            try:
                idx = list(sd.GetNodeLTGODE1(i))
            except Exception:                  # nodes without ODE1 coordinates
                continue
            if idx:
                self.ref1[idx] = np.ravel(self.mbs.GetNode(i).get("referenceCoordinates", np.zeros(len(idx))))
        y0 = np.array(sd.GetODE1Coordinates()) + self.ref1
        lay = self.layout2 = self.layout
        n2, nv, n1 = lay.nq, lay.nv, self.n1
        self.layout = Layout(n2 + n1, nv + n1, lay.bodies, lay.vector_q + tuple(range(n2, n2 + n1)),
                             lay.vector_v + tuple(range(nv, nv + n1)))
        self.q0 = np.concatenate([self.q0, np.zeros(n1)])
        self.V0 = np.concatenate([self.V0, y0])
        if not np.isfinite(y0).all():
            raise InputError("Exudyn initial ODE1 coordinates are not finite; fix the ODE1 nodes' "
                             "initialCoordinates.")

    def _split(self, q, V=None):
        n2, nv = self.n2, self.nv
        return (q[:n2], None if V is None else V[:nv], None if V is None else V[nv:])

    def _set_y(self, y):
        self.sd.SetODE1Coordinates(np.asarray(y, float) - self.ref1)

    def _ydot(self):
        self.solver.ComputeODE1RHS(self.mbs)
        return np.array(self.solver.GetSystemResidual())[self.n2:self.n2 + self.n1]

    @_engine_call
    def f(self, q, V, t):
        q2, V2, y = self._split(q, V)
        self._set_y(y)
        Vd = ExudynModel.f.__wrapped__(self, q2, V2, t)       # leaves (q, q̇, t) written
        return np.concatenate([Vd, self._ydot()])

    @_engine_call
    def forces(self, q, V, t):
        q2, V2, y = self._split(q, V)
        self._set_y(y)
        Q = ExudynModel.forces.__wrapped__(self, q2, V2, t)
        self._write(q2, self.rates_from_twist(q2, V2), t)
        return np.concatenate([Q, self._ydot()])

    @_engine_call
    def mass_matrix(self, q):
        M = ExudynModel.mass_matrix.__wrapped__(self, q[:self.n2])
        out = np.eye(self.nv + self.n1)
        out[:self.nv, :self.nv] = M
        return out

    def solve_mass(self, q, B):
        B = np.asarray(B, float)
        out = B.copy()
        out[:self.nv] = ExudynModel.solve_mass(self, q[:self.n2], B[:self.nv])
        return out

    def constraints(self, q):
        return ExudynModel.constraints(self, q[:self.n2])

    @_engine_call
    def constraints_at(self, q, t):
        return ExudynModel.constraints_at.__wrapped__(self, q[:self.n2], t)

    @_engine_call
    def velocity_rhs(self, q, t):
        return ExudynModel.velocity_rhs.__wrapped__(self, q[:self.n2], t)

    @_engine_call
    def constraint_jacobian(self, q):
        A = ExudynModel.constraint_jacobian.__wrapped__(self, q[:self.n2])
        return np.hstack([A, np.zeros((A.shape[0], self.n1))])

    @_engine_call
    def constraint_gamma(self, q, V, t=None):
        q2, V2, y = self._split(q, V)
        return ExudynModel.constraint_gamma.__wrapped__(self, q2, V2, t)

    @_engine_call
    def accelerations(self, q, V, t):
        """Exudyn's ODE2 accelerations (the ODE1 rates are not part of them)."""
        q2, V2, y = self._split(q, V)
        Vd = self.f(q, V, t)[:self.nv]
        return self.H(q2) @ Vd + self.Hdot_V(q2, V2)

    def write_back(self, q, V, t):
        q2, V2, y = self._split(q, V)
        ExudynModel.write_back(self, q2, V2, t)
        self._set_y(y)

    def check_mass_matrix(self, q):
        """The ODE2 part's mass matrix (the ODE1 block is the identity)."""
        from lgt_bridge.validation import mass_defects, mass_message
        q2 = q[:self.n2]
        M = ExudynModel.mass_matrix.__wrapped__(self, q2)
        A = ExudynModel.constraint_jacobian.__wrapped__(self, q2) if self.n_constraints else None
        d = mass_defects(M, A)
        if d:
            raise InputError(mass_message(d, [self.layout2.owner("V", i) for i, _ in d]))
