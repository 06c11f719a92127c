"""PinocchioModel: a Pinocchio model as an lgt_bridge model.

q is Pinocchio's own configuration vector. Each free-flyer joint is a rigid body
(position, then the quaternion in Pinocchio's ``x y z w`` order); its 6 entries of
V are (ω body, ṙ inertial), angular first, where Pinocchio's velocity is
(v_lin body, ω body) with ṙ = R v_lin. A spherical joint is a rotation-only body
(its quaternion, and ω, which is Pinocchio's joint velocity as is). Continuous joints
(URDF ``continuous``: ``JointModelRUBX/Y/Z``, ``RevoluteUnboundedUnaligned``; q = (cos θ,
sin θ), v = θ̇) are circle coordinates, stepped on SO(2). A planar joint (q = (x, y, cos θ,
sin θ), v = (v_xy in the joint frame, ω)) is stepped on SO(2)×R²: its (x, y) are vector
coordinates with rates ṗ = R(θ) v_xy in the parent frame, its (cos θ, sin θ) a circle
coordinate with rate ω. A spherical-ZYX joint (q = three z-y-x angles, v = their rates) is a
rotation-only body with the z-y-x parameterization (``params.RZYX``), its V = ω in the child
frame = G(q) v: the angles are written back through τ and go through ±π/2 continuously; f
maps ω to Pinocchio's v = G⁻¹ω, so its accuracy is bounded near cos θ1 = 0 (as Exudyn's Rxyz
nodes; generalized-α differences its Newton matrix on such models). Joints whose
configuration space is a vector space (nq = nv: revolute, prismatic, translation, universal,
ellipsoid, helical) are vector-space blocks; a composite joint is split into its components.
f(q, V, t) = Pinocchio's ABA, with r̈ = R (a_lin + ω × v_lin) for the roots.

Constraints (RigidConstraintModel, 3-D/6-D, to the world or loop closures): f from
constraintDynamics, A(q) from Pinocchio's frame Jacobians and γ(q, V) from its frame
accelerations. Generalized-α's Newton matrix (:meth:`PinocchioModel.iteration_matrix`) comes
from Pinocchio's analytic RNEA derivatives, mapped to the twist coordinates.

Backends (:mod:`lgt_bridge.backend`, fixed when the model is built): with numba, f converts
V to Pinocchio's v and ABA's a to V̇ by two compiled calls (:mod:`lgt_pinocchio.kernels`)
over a preallocated v; with numpy it runs the readable reference (``_f_numpy``).
"""
import numpy as np

from lgt_bridge import backend as _backend
from lgt_bridge import lgt as _lgt
from lgt_bridge.lgt import circle_tau
from lgt_bridge import params
from lgt_bridge.errors import InputError
from lgt_bridge.groups import quaternion as _q
from lgt_bridge.groups.batch import cross
from lgt_bridge.model import CIRCLE_NORM_TOL, Layout, Model, RigidBody, combine_iteration

#: continuous joints: q = (cos θ, sin θ), v = θ̇ (SO(2))
CIRCLE_JOINTS = ("JointModelRUBX", "JointModelRUBY", "JointModelRUBZ", "JointModelRevoluteUnboundedUnaligned")
#: joints Pinocchio steps as vector spaces (q̇ = v) that still have no τ of their own here
NOT_YET = {"JointModelMimic": "a mimic joint has no coordinates of its own"}
#: joints integrated as vector spaces (q̇ = v)
VECTOR_JOINTS = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelPX", "JointModelPY",
                 "JointModelPZ", "JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned",
                 "JointModelTranslation", "JointModelHelicalX", "JointModelHelicalY", "JointModelHelicalZ")


_F64 = np.dtype(np.float64)
_K = None           # lgt_pinocchio.kernels (imports numba), loaded by the first compiled model


#: the planar rotation's generator: J v = (-v_y, v_x), R(θ) = exp(θ J)
_J2 = np.array([[0.0, -1.0], [1.0, 0.0]])


def _zyx_Gdot_v(th, v):
    """Ġ θ̇ of the z-y-x angles th at rates v (ω̇ = G θ̈ + Ġ θ̇; checked against Pinocchio's
    joint acceleration in tests)."""
    s1, c1, s2, c2 = np.sin(th[1]), np.cos(th[1]), np.sin(th[2]), np.cos(th[2])
    ad, bd, cd = v
    return np.array([-c1 * bd * ad,
                     (c2 * c1 * cd - s2 * s1 * bd) * ad - s2 * cd * bd,
                     (-s2 * c1 * cd - c2 * s1 * bd) * ad - c2 * cd * bd])


def _planar_R(q, iq):
    """R(θ) of the planar joint whose q starts at iq: q[iq + 2], q[iq + 3] = cos θ, sin θ."""
    c, s = q[iq + 2], q[iq + 3]
    return np.array([[c, -s], [s, c]])


def _simple_joint(name, iq, iv, nq, nv):
    """A joint stepped as circle or vector coordinates (not a rigid body, not refused)."""
    return name in CIRCLE_JOINTS or name in VECTOR_JOINTS or (nq == nv and name not in NOT_YET and name not in (
        "JointModelComposite", "JointModelFreeFlyer", "JointModelSpherical", "JointModelSphericalZYX"))


def _pin():
    import pinocchio
    return pinocchio


def _kernels():
    global _K
    if _K is None:
        from . import kernels
        _K = kernels
    return _K


def _check_pin_model(pin, model):
    if isinstance(model, pin.Model):
        return
    if isinstance(model, pin.Data):
        raise InputError("PinocchioModel: got a pinocchio.Data; pass the pinocchio.Model it was created "
                         "from (e.g. PinocchioModel(model), not PinocchioModel(data)): the adapter makes "
                         "its own Data with model.createData().")
    hint = " (a RobotWrapper: pass robot.model)" if isinstance(getattr(model, "model", None), pin.Model) else ""
    raise InputError(f"PinocchioModel: expected a pinocchio.Model, got a {type(model).__name__}{hint}.")


def _check_signature(fn, name, expected):
    """InputError unless ``fn`` can be called with three positional arguments (t, q, v)."""
    import inspect
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):       # builtins without a signature: checked by the first call
        return
    try:
        sig.bind(0.0, None, None)
    except TypeError:
        raise InputError(f"{name}: expected a callable {expected}; {getattr(fn, '__name__', name)}"
                         f"{sig} cannot be called with the three arguments (t, q, v).") from None


def _hat(x):
    return np.array([[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]])


def _cross3(a, b):
    """a × b for two 3-vectors (np.cross costs tens of µs on one pair)."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def _xyzw_matrix(x, y, z, w):
    """Rotation matrix of the unit quaternion stored x y z w."""
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _djr(e, ed):
    """(d/dt Jr(e)) ė for the right Jacobian of SO(3)'s exp, Jr(e) = I - a(θ) ẽ + b(θ) ẽ²,
    a = (1 - cos θ)/θ², b = (θ - sin θ)/θ³ (Ė = E (Jr ė)~ for E = exp(ẽ)):
    -ȧ e × ė + ḃ e × (e × ė) + b ė × (e × ė), ȧ = (a'/θ)(e·ė), ḃ = (b'/θ)(e·ė)."""
    th2 = float(e @ e)
    th = np.sqrt(th2)
    if th < 0.1:                                   # series: the closed forms cancel
        b = 1 / 6 - th2 / 120 + th2 * th2 / 5040
        ap = -1 / 12 + th2 / 180 - th2 * th2 / 6720
        bp = -1 / 60 + th2 / 1260 - th2 * th2 / 60480
    else:
        s, c = np.sin(th), np.cos(th)
        b = (th - s) / (th2 * th)
        ap = (th * s - 2 * (1 - c)) / (th2 * th2)
        bp = (th * (1 - c) - 3 * (th - s)) / (th2 * th2 * th)
    ee = float(e @ ed)
    exe = _cross3(e, ed)
    return -ap * ee * exe + bp * ee * _cross3(e, exe) + b * _cross3(ed, exe)


class PinocchioModel(Model):
    """A ``pinocchio.Model`` for :func:`lgt_bridge.simulate.simulate`.

    tau: None (zero), a vector of size nv, or ``tau(t, q, v)`` (Pinocchio's q and v).
    tau_derivatives: None or ``tau_derivatives(t, q, v) -> (dtau_dq, dtau_dv)``, the
    controller's Jacobians (nv x nv each; dtau_dq in Pinocchio's tangent coordinates, the
    columns of pin.integrate's increments): generalized-α's Newton matrix then uses them
    instead of 2 nv extra calls of tau per matrix (forward differences).
    fext: None or ``fext(t, q, v)`` returning one ``pinocchio.Force`` (or 6-vector
    (linear, angular)) per joint, ``model.njoints`` of them, in each joint's frame (a
    ``pinocchio.StdVec_Force`` is passed on without conversion: the cheapest form).
    q0, v0: initial state in Pinocchio's own coordinates (default: neutral, zero).
    backend: 'numba' or 'numpy' (default: $LGT_BRIDGE_BACKEND, else numba).

    With the compiled backend, ``tau`` and ``fext`` receive the caller's q and the model's
    own velocity buffer v, not copies: both are valid during the call only (copy them to
    keep them) and must not be written to. f returns a new array either way.
    """

    def __init__(self, model, *, tau=None, fext=None, constraints=None, q0=None, v0=None, backend=None,
                 tau_derivatives=None):
        pin = self.pin = _pin()
        _check_pin_model(pin, model)
        self.compiled = _backend.compiled(backend)
        self.model, self.data = model, model.createData()
        bodies, vq, vv, cq, cv = [], [], [], [], []
        self.roots, self.balls, self.planars, self.zyx = [], [], [], []
        for j, jm in enumerate(model.joints):
            if j == 0:
                continue
            name, iq, iv = jm.shortname(), jm.idx_q, jm.idx_v
            parts = [(name, iq, iv, jm.nq, jm.nv)]
            if name == "JointModelComposite":
                comps = jm.extract().joints
                # components carry the model's indices once the composite is in a model
                oq, ov = (0, 0) if comps[0].idx_q == iq and comps[0].idx_v == iv else (iq, iv)
                parts = [(c.shortname(), oq + c.idx_q, ov + c.idx_v, c.nq, c.nv) for c in comps]
                bad = [p[0] for p in parts if not _simple_joint(*p)]
                if bad:
                    raise InputError(f"Pinocchio joint {j} ({model.names[j]!r}) is a composite joint with a "
                                     f"{bad[0]} component; lgt_bridge splits composite joints into revolute, "
                                     "prismatic, continuous and other vector-space components only. Build "
                                     "that component as a joint of its own (a body of zero mass between).")
            if all(_simple_joint(*p) for p in parts):
                for cname, ciq, civ, cnq, cnv in parts:
                    if cname in CIRCLE_JOINTS:
                        cq.append((ciq, ciq + 1))
                        cv.append(civ)
                    else:
                        vq += list(range(ciq, ciq + cnq))
                        vv += list(range(civ, civ + cnv))
            elif name == "JointModelPlanar":
                # SO(2)xR²: (x, y) vector coordinates with rates ṗ (parent frame), (c, s) a circle
                vq += [iq, iq + 1]
                vv += [iv, iv + 1]
                cq.append((iq + 2, iq + 3))
                cv.append(iv + 2)
                self.planars.append((iq, iv))
            elif name == "JointModelSphericalZYX":
                # rotation-only body on the z-y-x angles; V = ω (child frame) = G(q) v
                bodies.append(RigidBody(params.RZYX, (), tuple(range(iq, iq + 3)), tuple(range(iv, iv + 3)),
                                        model.names[j]))
                self.zyx.append((iq, iv))
            elif name == "JointModelFreeFlyer":
                bodies.append(RigidBody(params.QUAT_XYZW, tuple(range(iq, iq + 3)), tuple(range(iq + 3, iq + 7)),
                                        tuple(range(iv, iv + 6)), model.names[j]))
                self.roots.append((iq, iv))
            elif name == "JointModelSpherical":
                # rotation-only body: q = x y z w quaternion, v = ω in the joint frame (= body ω)
                bodies.append(RigidBody(params.QUAT_XYZW, (), tuple(range(iq, iq + 4)),
                                        tuple(range(iv, iv + 3)), model.names[j]))
                self.balls.append((iq, iv))
            else:
                why = NOT_YET.get(name, "it is not a joint type lgt_bridge knows")
                raise InputError(f"Pinocchio joint {j} ({model.names[j]!r}) is a {name} (nq = {jm.nq}, "
                                 f"nv = {jm.nv}): {why}. lgt_bridge supports free-flyers, spherical joints, "
                                 "continuous joints (RUBX/Y/Z), composite joints of those, and joints whose "
                                 f"configuration space is a vector space ({', '.join(VECTOR_JOINTS[:6])}, ...). "
                                 "Integrate this model with Pinocchio's own loop, or replace the joint.")
        self.layout = Layout(model.nq, model.nv, bodies, tuple(vq), tuple(vv), circle_q=tuple(cq),
                             circle_v=tuple(cv))
        self.nq, self.nv = model.nq, model.nv
        self._riq = np.array([r[0] for r in self.roots], int)
        self._riv = np.array([r[1] for r in self.roots], int)
        self._convert = bool(self.roots or self.planars or self.zyx)     # V and v differ somewhere
        if self.zyx:
            # generalized-α's analytic matrix has no blocks for G(q)⁻¹: it differences the step
            self.iteration_matrix = None
        self._tau = tau
        if callable(tau):
            _check_signature(tau, "tau", "tau(t, q, v) returning the joint torques (size nv)")
        if callable(fext):
            _check_signature(fext, "fext", "fext(t, q, v) returning one force per joint")
        elif fext is not None:
            raise InputError(f"fext: expected None or a callable fext(t, q, v) returning one force per "
                             f"joint, got a {type(fext).__name__}.")
        if tau_derivatives is not None:
            if not callable(tau):
                raise InputError("tau_derivatives is given but tau is not a callable tau(t, q, v); drop "
                                 "tau_derivatives (a constant tau has none) or pass the controller as tau.")
            _check_signature(tau_derivatives, "tau_derivatives",
                             "tau_derivatives(t, q, v) returning (dtau_dq, dtau_dv), each nv x nv")
        self._tau_derivatives = tau_derivatives
        if tau is not None and not callable(tau):
            tau = np.asarray(tau, float)
            if tau.shape != (self.nv,) or not np.isfinite(tau).all():
                raise InputError(f"tau: expected a finite vector of size nv = {self.nv} or a callable "
                                 f"tau(t, q, v), got shape {tau.shape}.")
            self._tau = tau
        self._fext = fext
        q0 = pin.neutral(model) if q0 is None else np.asarray(q0, float)
        v0 = np.zeros(self.nv) if v0 is None else np.asarray(v0, float)
        if q0.shape != (self.nq,) or v0.shape != (self.nv,):
            raise InputError(f"q0/v0: expected sizes nq = {self.nq}, nv = {self.nv}; got "
                             f"{q0.shape}, {v0.shape}.")
        for name, arr in (("q0", q0), ("v0", v0)):
            if not np.isfinite(arr).all():
                i = int(np.flatnonzero(~np.isfinite(arr))[0])
                kind = "q" if name == "q0" else "v"
                raise InputError(f"{name}: entry {i} ({self.joint_of(kind, i)}) is {arr[i]}; give a "
                                 "finite initial state.")
        for b in bodies:
            b.validate(q0, f"q0 of joint {b.name!r}")
        for c, _ in cq:
            if not abs(np.hypot(q0[c], q0[c + 1]) - 1.0) <= CIRCLE_NORM_TOL:
                raise InputError(f"q0: {self.joint_of('q', c)} is a continuous joint whose (cos θ, sin θ) = "
                                 f"({q0[c]!r}, {q0[c + 1]!r}) is not of unit norm; give (cos θ, sin θ) "
                                 "(pin.neutral(model) and pin.randomConfiguration(model) do).")
        self.q0 = q0
        self.V0 = self.twist_from_v(q0, v0)
        self._move = _lgt.LGT(params.QUAT_XYZW, "SO3xR3", "exp")     # q moved by a twist increment
        self._move_ball = _lgt.RotationLGT(params.QUAT_XYZW, "exp")
        self._move_zyx = _lgt.RotationLGT(params.RZYX, "exp")
        self._setup_constraints(constraints or [], fext)
        if self.compiled:
            K = _kernels()
            self._jt = K.joint_table(self.roots, self.planars, self.zyx)
            self._kW, self._kv = K.work_array(self._jt, self.nv)
            self.f = self._f_compiled = self._build_f()
        # validate the inputs once now, so a wrong tau or fext fails before any step
        self._torques(0.0, q0, v0)
        if tau_derivatives is not None:
            self._tau_jacobians(0.0, q0, v0)
        if fext is not None:
            self._forces(0.0, q0, v0)

    def joint_of(self, kind, index):
        """The joint that owns entry ``index`` of q (kind 'q') or of v / V (kind 'v'), for messages:
        "joint 'l_hip_pitch' (Pinocchio joint 3)"."""
        for j in range(1, self.model.njoints):
            jm = self.model.joints[j]
            i0, n = (jm.idx_q, jm.nq) if kind == "q" else (jm.idx_v, jm.nv)
            if i0 <= index < i0 + n:
                return f"joint {self.model.names[j]!r} (Pinocchio joint {j})"
        return f"{kind}[{index}]"

    def check_mass_matrix(self, q):
        """InputError when Pinocchio's joint-space mass matrix (CRBA) at q is singular or
        indefinite (e.g. links with zero inertia, as in example-robot-data's iCub and Romeo),
        naming the joints; with constraints, on the motions they allow. Called by
        :func:`lgt_bridge.simulate.simulate` before the first step."""
        from lgt_bridge.validation import mass_defects
        q = np.asarray(q, float)
        M = self.pin.crba(self.model, self.data, q)
        M = np.triu(M) + np.triu(M, 1).T
        A = None
        if self.n_constraints:
            # A is with respect to V; v = T V, so with respect to v it is A T⁻¹
            A = np.linalg.solve(self._T(q).T, self.constraint_jacobian(q).T).T
        defects = mass_defects(M, A)
        if not defects:
            return
        i, lam = defects[0]
        names = list(dict.fromkeys(self.joint_of("v", k) for k, _ in defects))
        more = ""
        if len(defects) > 1:
            more = (f"; {len(defects)} such directions, in {', '.join(names[:6])}"
                    + (", ..." if len(names) > 6 else ""))
        kind = "indefinite" if lam < 0 else "singular"
        raise InputError(
            f"Pinocchio mass matrix (crba) at q0 is {kind}: the motion of {names[0]} (v index {i}) "
            f"has {'negative' if lam < 0 else 'no'} inertia (scaled eigenvalue {lam:.2g}){more}. "
            "Its acceleration is undefined and an integrator would fail or crawl to max_steps. "
            "Give the links moved by these joints positive inertias, or set a rotor inertia "
            "(e.g. model.armature[:] = 1e-3 for every joint; model.armature[idx_v] for one) "
            "before wrapping the model.")

    # --- Pinocchio velocity (v_lin body, ω body) <-> model twist (ω body, ṙ inertial) ---------
    def _quats(self, q):
        p = q[self._riq[:, None] + np.arange(3, 7)]          # (k, 4) x y z w
        return p[:, [3, 0, 1, 2]]

    def v_from_twist(self, q, V):
        """Pinocchio's v of the model twist V at q (a new array)."""
        if not self.compiled:
            return self._v_from_twist_numpy(q, V)
        q = np.ascontiguousarray(q, dtype=np.float64)
        V = np.ascontiguousarray(V, dtype=np.float64)
        W = self._kW.copy()
        (_K or _kernels()).v_from_twist(q, V, self._jt, W)
        return W[self._kv].copy()

    def _v_from_twist_numpy(self, q, V):
        v = V.copy()
        if len(self.roots):
            p = self._quats(q)
            i = self._riv[:, None]
            v[i + np.arange(3)] = _q._rotate(_q._conj(p), V[i + np.arange(3, 6)])
            v[i + np.arange(3, 6)] = V[i + np.arange(3)]
        for iq, iv in self.planars:
            v[iv:iv + 2] = _planar_R(q, iq).T @ V[iv:iv + 2]
        for iq, iv in self.zyx:
            v[iv:iv + 3] = params.RZYX._rates_from_omega(q[None, iq:iq + 3], V[None, iv:iv + 3])[0]
        return v

    def twist_from_v(self, q, v):
        V = np.array(v, float)
        if len(self.roots):
            p = self._quats(q)
            i = self._riv[:, None]
            V[i + np.arange(3)] = v[i + np.arange(3, 6)]
            V[i + np.arange(3, 6)] = _q._rotate(p, v[i + np.arange(3)])
        for iq, iv in self.planars:
            V[iv:iv + 2] = _planar_R(q, iq) @ v[iv:iv + 2]
        for iq, iv in self.zyx:
            V[iv:iv + 3] = params.RZYX.G(q[iq:iq + 3]) @ v[iv:iv + 3]
        return V

    # --- inputs -------------------------------------------------------------------------------
    def _torques(self, t, q, v):
        if self._tau is None:
            return np.zeros(self.nv)
        tau = np.asarray(self._tau(t, q, v) if callable(self._tau) else self._tau, float)
        if tau.shape != (self.nv,):
            raise InputError(f"tau(t, q, v) returned shape {tau.shape}; expected ({self.nv},).")
        return tau

    def _forces(self, t, q, v):
        pin = self.pin
        fs = self._fext(t, q, v)
        if len(fs) != self.model.njoints:
            raise InputError(f"fext(t, q, v) returned {len(fs)} forces; Pinocchio needs one per joint, "
                             f"model.njoints = {self.model.njoints} (entry 0, the universe, is ignored). "
                             "Pinocchio does not check this itself and would read garbage.")
        if type(fs) is pin.StdVec_Force:
            return fs                                 # already Pinocchio's own container
        out = pin.StdVec_Force()
        for k, f in enumerate(fs):
            if isinstance(f, pin.Force):
                out.append(f)
            else:
                f = np.asarray(f, float)
                if f.shape != (6,) or not np.isfinite(f).all():
                    raise InputError(f"fext: force {k} must be a pinocchio.Force or a finite 6-vector "
                                     f"(linear, angular), got {f!r}.")
                out.append(pin.Force(f[:3], f[3:]))
        return out

    # --- constraints ------------------------------------------------------------------------------
    def _setup_constraints(self, constraints, fext):
        """RigidConstraintModels (3-D/6-D contacts, loop closures): f from Pinocchio's
        constraintDynamics; g(q) = position difference of the two constraint frames in the
        world (6-D: and the rotation vector log(R₂ᵀR₁) between them); A = ∂g/∂V from
        Pinocchio's frame Jacobians and γ from its frame accelerations
        (:meth:`constraint_jacobian`, :meth:`constraint_gamma`)."""
        pin = self.pin
        self.cms = pin.StdVec_RigidConstraintModel()
        self.cds = pin.StdVec_RigidConstraintData()
        for k, cm in enumerate(constraints):
            if not isinstance(cm, pin.RigidConstraintModel):
                raise InputError(f"constraints[{k}] is a {type(cm).__name__}; pass "
                                 "pinocchio.RigidConstraintModel objects.")
            if cm.type not in (pin.ContactType.CONTACT_3D, pin.ContactType.CONTACT_6D):
                raise InputError(f"constraints[{k}]: contact type {cm.type} is not supported (3D or 6D).")
            self.cms.append(cm)
            self.cds.append(cm.createData())
        self.n_constraints = int(sum(cm.residualSize() for cm in self.cms))
        if not self.n_constraints:
            return
        if fext is not None:
            raise InputError("fext together with constraints is not supported (Pinocchio's "
                             "constraintDynamics takes no external forces); express the loads as tau.")
        # (constraint model, 6-D?, first row); the placements are read from it at each call,
        # as constraintDynamics reads them
        self._crows, row = [], 0
        for cm in self.cms:
            six = cm.type == pin.ContactType.CONTACT_6D
            self._crows.append((cm, six, row))
            row += 6 if six else 3
        self._cdata = self.model.createData()       # kinematics of g, A, γ (f keeps self.data)
        pin.initConstraintDynamics(self.model, self.data, self.cms, self.cds)
        self.prox = pin.ProximalSettings(1e-12, 1e-12, 50)
        g0 = self.constraints(self.q0)
        if np.abs(g0).max() > 1e-6:
            k = int(np.argmax(np.abs(g0) > 1e-6))
            raise InputError(f"constraint residual component {k} is {g0[k]:.3g} at q0: the constraint "
                             "frames do not coincide; set joint2_placement to where joint1's frame is "
                             "at q0 (or start from a configuration that satisfies the constraints).")

    def _frame(self, j, pl):
        """World placement of the frame ``pl`` on joint j (j = 0: the world) after kinematics."""
        return pl if j == 0 else self._cdata.oMi[j] * pl

    def _constraint_frames(self):
        """(joint1, placement1, joint2, placement2, 6-D?, first row) per constraint."""
        for cm, six, r in self._crows:
            yield cm.joint1_id, cm.joint1_placement, cm.joint2_id, cm.joint2_placement, six, r

    def constraints(self, q):
        if not self.n_constraints:
            return np.zeros(0)
        pin = self.pin
        pin.forwardKinematics(self.model, self._cdata, np.asarray(q, float))
        out = np.empty(self.n_constraints)
        for j1, pl1, j2, pl2, six, r in self._constraint_frames():
            M1, M2 = self._frame(j1, pl1), self._frame(j2, pl2)
            out[r:r + 3] = M1.translation - M2.translation
            if six:
                out[r + 3:r + 6] = pin.log3(M2.rotation.T @ M1.rotation)
        return out

    def _times_T(self, G, q):
        """G T(q) (a new array): Pinocchio-v columns to twist columns, without forming T."""
        A = np.array(G, float)
        for iq, iv in self.roots:
            A[:, iv:iv + 3] = G[:, iv + 3:iv + 6]
            A[:, iv + 3:iv + 6] = G[:, iv:iv + 3] @ _xyzw_matrix(*q[iq + 3:iq + 7]).T
        for iq, iv in self.planars:
            A[:, iv:iv + 2] = G[:, iv:iv + 2] @ _planar_R(q, iq).T
        for iq, iv in self.zyx:
            A[:, iv:iv + 3] = np.linalg.solve(params.RZYX.G(q[iq:iq + 3]).T, G[:, iv:iv + 3].T).T
        return A

    def constraint_jacobian(self, q):
        """A(q) = ∂g/∂V (ġ = A V) from Pinocchio's frame Jacobians: with J_i the
        LOCAL_WORLD_ALIGNED Jacobian of constraint frame i (world linear velocity of its
        origin, world ω), the position rows are (J₁ - J₂)_lin T and the rotation rows of a
        6-D constraint, e = log(E), E = R₂ᵀR₁, are Jlog3(E) R₁ᵀ (J₁ - J₂)_ang T (ė =
        Jr(e)⁻¹ w with Ė = E w~, w = R₁ᵀ(ω₁ - ω₂) in the world), where v = T(q) V."""
        if not self.n_constraints:
            return np.zeros((0, self.nv))
        pin, model, d = self.pin, self.model, self._cdata
        q = np.asarray(q, float)
        pin.computeJointJacobians(model, d, q)
        G = np.zeros((self.n_constraints, self.nv))
        lwa = pin.LOCAL_WORLD_ALIGNED
        for j1, pl1, j2, pl2, six, r in self._constraint_frames():
            J = pin.getFrameJacobian(model, d, j1, pl1, lwa)
            if j2:
                J = J - pin.getFrameJacobian(model, d, j2, pl2, lwa)
            G[r:r + 3] = J[:3]
            if six:
                R1 = self._frame(j1, pl1).rotation
                E = self._frame(j2, pl2).rotation.T @ R1
                G[r + 3:r + 6] = pin.Jlog3(E) @ (R1.T @ J[3:])
        return self._times_T(G, q)

    def _frame_motion(self, j, pl):
        """(R, ω world, classical acceleration of the origin (world), α world) of the frame
        ``pl`` on joint j after forwardKinematics(q, v, a) on the constraint data."""
        if j == 0:
            z = np.zeros(3)
            return pl.rotation, z, z, z
        d = self._cdata
        R = (d.oMi[j] * pl).rotation
        vf, af = pl.actInv(d.v[j]), pl.actInv(d.a[j])
        w = vf.angular
        return R, R @ w, R @ (af.linear + _cross3(w, vf.linear)), R @ af.angular

    def constraint_gamma(self, q, V):
        """γ(q, V) = (d/dt A) V, so that g̈ = A V̇ + γ: the second derivative of g along the
        motion with V̇ = 0. In Pinocchio's coordinates V̇ = 0 is the acceleration
        a₀ = Ṫ V (-ω × v_lin on each free-flyer, zero elsewhere), so γ comes from one
        forwardKinematics(q, v, a₀) and the frames' classical accelerations: p̈₁ - p̈₂ on the
        position rows; on the rotation rows of a 6-D constraint
        ë = Jr(e)⁻¹ (ẇ - (∂Jr(e)[ė]) ė) with ẇ = -ω₁ × w + R₁ᵀ(α₁ - α₂) (world α)."""
        if not self.n_constraints:
            return np.zeros(0)
        pin = self.pin
        q, V = np.asarray(q, float), np.asarray(V, float)
        v = self.v_from_twist(q, V)
        pin.forwardKinematics(self.model, self._cdata, q, v, self._TdV(v, q))
        out = np.empty(self.n_constraints)
        for j1, pl1, j2, pl2, six, r in self._constraint_frames():
            R1, w1, p1, al1 = self._frame_motion(j1, pl1)
            R2, w2, p2, al2 = self._frame_motion(j2, pl2)
            out[r:r + 3] = p1 - p2
            if six:
                E = R2.T @ R1
                Jl = pin.Jlog3(E)
                w = R1.T @ (w1 - w2)
                wd = -_cross3(R1.T @ w1, w) + R1.T @ (al1 - al2)
                ed = Jl @ w
                out[r + 3:r + 6] = Jl @ (wd - _djr(pin.log3(E), ed))
        return out

    def _moved(self, q, d):
        out = q.copy()
        for iq, iv in self.roots:
            out[iq:iq + 7] = self._move.tau(q[iq:iq + 7][None], d[iv:iv + 6][None])[0]
        for iq, iv in self.balls:
            mb = self._move_ball
            out[iq:iq + 4] = mb.tau_pose(mb.base(q[iq:iq + 4][None]), d[iv:iv + 3][None])[0][0]
        for iq, iv in self.zyx:
            mz = self._move_zyx
            out[iq:iq + 3] = mz.tau_pose(mz.base(q[iq:iq + 3][None]), d[iv:iv + 3][None])[0][0]
        vq = list(self.layout.vector_q)
        out[vq] = q[vq] + d[list(self.layout.vector_v)]
        if self.layout.circle_q:
            cq = np.array(self.layout.circle_q)
            out[cq] = circle_tau(q[cq], d[list(self.layout.circle_v)])
        return out

    # finite-difference references of A and γ (tests hold the analytic ones to them)
    def _constraint_jacobian_fd(self, q, eps=1e-6):
        """A by central differences of g along each twist direction through τ (SO(3)xR³ exp)."""
        A = np.zeros((self.n_constraints, self.nv))
        for k in range(self.nv):
            e = np.zeros(self.nv)
            e[k] = eps
            A[:, k] = (self.constraints(self._moved(q, e)) - self.constraints(self._moved(q, -e))) / (2 * eps)
        return A

    def _constraint_gamma_fd(self, q, V, eps=2e-3):
        """γ = d²/ds² g(τ(q, s V)) at s = 0 (V is constant along that curve: ω body and ṙ
        inertial), by the 7-point central stencil (error O(eps⁶))."""
        c = np.array([2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0]) / 180.0
        V = np.asarray(V, float)
        g = [self.constraints(self._moved(q, s * eps * V)) for s in range(-3, 4)]
        return sum(ck * gk for ck, gk in zip(c, g)) / eps ** 2

    def _T(self, q):
        """v = T(q) V (Pinocchio velocity from the model twist)."""
        T = np.eye(self.nv)
        if len(self.roots):
            R = _q._to_matrix(self._quats(q))
            for k, (_, iv) in enumerate(self.roots):
                T[iv:iv + 6, iv:iv + 6] = 0.0
                T[iv:iv + 3, iv + 3:iv + 6] = R[k].T
                T[iv + 3:iv + 6, iv:iv + 3] = np.eye(3)
        for iq, iv in self.planars:
            T[iv:iv + 2, iv:iv + 2] = _planar_R(q, iq).T
        for iq, iv in self.zyx:
            T[iv:iv + 3, iv:iv + 3] = np.linalg.inv(params.RZYX.G(q[iq:iq + 3]))
        return T

    def mass_matrix(self, q):
        """M̄ = Tᵀ M T in twist coordinates (Pinocchio's CRBA, symmetrized)."""
        M = self.pin.crba(self.model, self.data, q)
        M = np.triu(M) + np.triu(M, 1).T
        T = self._T(q)
        return T.T @ M @ T

    def forces(self, q, V, t):
        """Q̄ with M̄ V̇ = Q̄ (+ constraint forces): Tᵀ (τ - rnea(q, v, 0, fext) - M Ṫ V), where
        v = T V and Ṫ V = (-ω × v_lin, 0) on each free-flyer (d/dt of Rᵀ ṙ at fixed ṙ)."""
        pin = self.pin
        v = self.v_from_twist(q, V)
        tau = self._torques(t, q, v)
        z = np.zeros(self.nv)
        if self._fext is None:
            b = pin.rnea(self.model, self.data, q, v, z)
        else:
            b = pin.rnea(self.model, self.data, q, v, z, self._forces(t, q, v))
        M = pin.crba(self.model, self.data, q)
        M = np.triu(M) + np.triu(M, 1).T
        return self._T(q).T @ (tau - b - M @ self._TdV(v, q))

    def _TdV(self, v, q):
        """Ṫ V: Pinocchio's acceleration at V̇ = 0, (-ω × v_lin, 0) on each free-flyer
        (d/dt of Rᵀṙ at fixed ṙ), (-ω J v_xy, 0) on each planar joint, -G(q)⁻¹ Ġ θ̇ on each
        spherical-ZYX joint, zero elsewhere."""
        TdV = np.zeros(self.nv)
        for iq, iv in self.zyx:
            th = q[iq:iq + 3]
            TdV[iv:iv + 3] = -np.linalg.solve(params.RZYX.G(th), _zyx_Gdot_v(th, v[iv:iv + 3]))
        for _, iv in self.roots:
            TdV[iv:iv + 3] = _cross3(v[iv:iv + 3], v[iv + 3:iv + 6])
        for _, iv in self.planars:
            TdV[iv:iv + 2] = -v[iv + 2] * (_J2 @ v[iv:iv + 2])
        return TdV

    # --- generalized-α: the iteration matrix ------------------------------------------------------
    def iteration_matrix(self, q, V, t, c_acc, c_vel, c_pos, lam=None, Vdot=None):
        """M c_acc + C_t c_vel + K_t c_pos for generalized-α's analytic Newton matrix, in
        V = (ω body, ṙ inertial) and the SO(3)xR³ increments z = (δθ body, δr inertial):
        the derivatives of the residual R = M̄ V̇ - Q̄ (+ Aᵀλ) = Tᵀ r(q, v, a) (+ Aᵀλ), with
        r = rnea(q, v, a) - u(t, q, v) (u: tau and the joint torques of fext), v = T V and
        a = T V̇ + Ṫ V, from Pinocchio's analytic RNEA derivatives (∂r/∂q in its tangent
        coordinates, ∂r/∂v, ∂r/∂a = M):

            M̄   = Tᵀ M T
            C_t = Tᵀ (∂r/∂v T + M ∂a/∂V)
            K_t = Tᵀ (∂r/∂q T + ∂r/∂v ∂v/∂z + M ∂a/∂z) + (∂Tᵀ/∂z) r + ∂(Aᵀλ)/∂z

        (Pinocchio's tangent increment of a free-flyer or planar joint is T z to first order;
        ∂v/∂z, ∂a/∂z, ∂a/∂V and ∂Tᵀ/∂z are nonzero on those only: v_lin = Rᵀṙ turns with δθ).
        ∂u/∂q and ∂u/∂v from ``tau_derivatives`` when given, else by forward differences when
        tau or fext is a callable. Models with spherical-ZYX joints have no analytic matrix.

        The derivatives are taken at V̇ = ``Vdot``, by default at the acceleration Newton
        converges to: ABA's, M̄⁻¹(Q̄ - Aᵀλ) given the constraint forces ``lam``, else
        constraintDynamics'. With ``lam`` the constraints' geometric stiffness ∂(Aᵀλ)/∂z is
        included, by central differences of the analytic A. The three matrices are computed
        once per (q, V, t, lam) and kept for the next calls (generalized-α asks for each)."""
        key = (float(t), np.asarray(q, float).tobytes(), np.asarray(V, float).tobytes(),
               None if lam is None or not self.n_constraints else np.asarray(lam, float).tobytes(),
               None if Vdot is None else np.asarray(Vdot, float).tobytes())
        cached = getattr(self, "_it_cache", None)
        if cached is None or cached[0] != key:
            with np.errstate(over="ignore", invalid="ignore"):   # a diverging iterate: genalpha
                parts = self._iteration_parts(q, V, t, lam, Vdot)  # checks the matrix is finite
            cached = self._it_cache = (key, parts)
        return combine_iteration(cached[1], c_acc, c_vel, c_pos)

    def _user_force(self, t, q, v):
        """u(t, q, v): tau plus the joint torques of fext (Jᵀ f = rnea(q, v, 0) - rnea(q, v, 0, fext))."""
        u = np.array(self._torques(t, q, v), float)
        if self._fext is not None:
            pin, d = self.pin, self._it_data
            z = np.zeros(self.nv)
            u += pin.rnea(self.model, d, q, v, z) - pin.rnea(self.model, d, q, v, z, self._forces(t, q, v))
        return u

    def _tau_jacobians(self, t, q, v):
        """(dtau_dq, dtau_dv) from the user's tau_derivatives, checked."""
        try:
            dq, dv = self._tau_derivatives(t, q, v)
        except (TypeError, ValueError) as exc:
            raise InputError(f"tau_derivatives(t, q, v) must return a pair (dtau_dq, dtau_dv): {exc}") from None
        dq, dv = np.asarray(dq, float), np.asarray(dv, float)
        shape = (self.nv, self.nv)
        if dq.shape != shape or dv.shape != shape or not (np.isfinite(dq).all() and np.isfinite(dv).all()):
            raise InputError(f"tau_derivatives(t, q, v) returned arrays of shapes {dq.shape} and {dv.shape}; "
                             f"expected two finite ({self.nv}, {self.nv}) matrices (dtau_dq in Pinocchio's "
                             "tangent coordinates, dtau_dv).")
        return dq, dv

    def _user_force_derivatives(self, t, q, v, u0):
        """(∂u/∂q in Pinocchio's tangent coordinates, ∂u/∂v): tau's from tau_derivatives when
        given, the rest (fext's joint torques, or a tau without derivatives) by forward
        differences from u0 = u(t, q, v) (2 nv calls per matrix); None when u is constant."""
        analytic = self._tau_derivatives is not None
        if (not callable(self._tau) or analytic) and self._fext is None:
            return self._tau_jacobians(t, q, v) if analytic else None
        pin, model, nv = self.pin, self.model, self.nv
        force = self._user_force
        if analytic:                                 # difference fext's part only
            u0 = u0 - self._torques(t, q, v)

            def force(t, q, v):
                return self._user_force(t, q, v) - self._torques(t, q, v)
        Dq, Dv = np.empty((nv, nv)), np.empty((nv, nv))
        e, vp = np.zeros(nv), v.copy()
        h = 1.5e-8                                   # ≈ √eps: q's tangent is O(1)
        for k in range(nv):
            e[k] = h
            Dq[:, k] = (force(t, pin.integrate(model, q, e), v) - u0) / h
            e[k] = 0.0
            hv = h * max(1.0, abs(v[k]))
            vp[k] = v[k] + hv
            Dv[:, k] = (force(t, q, vp) - u0) / (vp[k] - v[k])
            vp[k] = v[k]
        if analytic:
            dq, dv = self._tau_jacobians(t, q, v)
            Dq += dq
            Dv += dv
        return Dq, Dv

    def _iteration_parts(self, q, V, t, lam=None, Vdot=None):
        """(M̄, C_t, K_t) of :meth:`iteration_matrix` as dense arrays."""
        pin, model = self.pin, self.model
        if getattr(self, "_it_data", None) is None:
            self._it_data = model.createData()
        d = self._it_data
        q = np.array(q, float)
        V = np.asarray(V, float)
        v = self.v_from_twist(q, V)
        T = self._T(q)
        nc = self.n_constraints
        u = self._user_force(t, q, v)
        residual = True                    # r(q, v, a) ≠ 0 at a: (∂Tᵀ/∂z) r is needed
        if Vdot is not None:
            a = T @ np.asarray(Vdot, float) + self._TdV(v, q)
        elif nc and lam is not None:
            # Tᵀ r + Aᵀλ = 0 with T orthogonal: r = -T Aᵀλ, a = aba(u - T Aᵀλ)
            a = np.array(pin.aba(model, d, q, v, u - T @ (self.constraint_jacobian(q).T @ np.asarray(lam, float))))
        elif nc:
            a = np.array(pin.constraintDynamics(model, self.data, q, v, self._torques(t, q, v),
                                                self.cms, self.cds, self.prox))
        else:
            a = np.array(pin.aba(model, d, q, v, u))
            residual = False
        r = pin.rnea(model, d, q, v, a) - u if residual else None
        dq, dv, Mp = (np.array(x) for x in pin.computeRNEADerivatives(model, d, q, v, a))
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        du = self._user_force_derivatives(t, q, v, u)
        if du is not None:
            dq -= du[0]
            dv -= du[1]
        # ∂v/∂z, ∂a/∂z, ∂a/∂V on the free-flyers (rows v_lin; z and V columns (θ | ω, ṙ))
        Nv, Na, Ea = np.zeros((self.nv, self.nv)), np.zeros((self.nv, self.nv)), np.zeros((self.nv, self.nv))
        dT = np.zeros((self.nv, self.nv))
        if len(self.roots):
            R = _q._to_matrix(self._quats(q))
            for k, (_, iv) in enumerate(self.roots):
                lin, ang = slice(iv, iv + 3), slice(iv + 3, iv + 6)
                vl, w, al = v[lin], v[ang], a[lin]
                Hv, Hw = _hat(vl), _hat(w)
                Nv[lin, lin] = Hv
                Na[lin, lin] = _hat(al + _cross3(w, vl)) - Hw @ Hv        # a_lin = Rᵀr̈ - ω × Rᵀṙ
                Ea[lin, lin] = Hv
                Ea[lin, ang] = -Hw @ R[k].T
                if r is not None:
                    dT[ang, lin] = -R[k] @ _hat(r[lin])                  # (Tᵀ r)_ṙ = R r_lin
        for iq, iv in self.planars:
            # planar: v_xy = R(θ)ᵀ ṗ and a_xy = R(θ)ᵀ p̈ - ω J v_xy turn with δθ (column iv + 2)
            R2, xy, th = _planar_R(q, iq), slice(iv, iv + 2), iv + 2
            Nv[xy, th] = -_J2 @ v[xy]
            Na[xy, th] = -_J2 @ a[xy]
            Ea[xy, xy] = -v[th] * (_J2 @ R2.T)
            Ea[xy, th] = -_J2 @ v[xy]
            if r is not None:
                dT[xy, th] = R2 @ (_J2 @ r[xy])                          # (Tᵀ r)_ṗ = R r_xy
        Tt = T.T
        M = Tt @ Mp @ T
        C = Tt @ (dv @ T + Mp @ Ea)
        K = Tt @ (dq @ T + dv @ Nv + Mp @ Na) + dT
        if nc and lam is not None:
            K += self._geometric_stiffness(q, np.asarray(lam, float))
        return M, C, K

    def _geometric_stiffness(self, q, lam, eps=1e-6):
        """∂(A(q)ᵀλ)/∂z by central differences of the analytic A along the increments."""
        G = np.empty((self.nv, self.nv))
        e = np.zeros(self.nv)
        for k in range(self.nv):
            e[k] = eps
            G[:, k] = (self.constraint_jacobian(self._moved(q, e)).T @ lam
                       - self.constraint_jacobian(self._moved(q, -e)).T @ lam) / (2 * eps)
            e[k] = 0.0
        return G

    # --- model protocol ---------------------------------------------------------------------------
    def f(self, q, V, t):
        """V̇ = f(q, V, t): one Pinocchio ABA (constraintDynamics with constraints); a new array.
        (A compiled model replaces this by the closure of :meth:`_build_f` on the instance.)"""
        if self.compiled:
            return self._f_compiled(q, V, t)
        return self._f_numpy(q, V, t)

    def _build_f(self):
        """The compiled-backend f as a closure over its constants (no attribute look-ups per
        call): V -> v by one kernel call into the work array, Pinocchio, then a -> V̇ in place
        by a second (ABA's a is a new array, so it is returned as V̇)."""
        K = _kernels()
        v_from_twist, vdot_from_a = K.v_from_twist, K.vdot_from_a_unchecked
        pin, model, data = self.pin, self.model, self.data
        jt, W = self._jt, self._kW
        v_buf = W[self._kv]
        has_roots = self._convert
        tau_c = np.zeros(self.nv) if self._tau is None else self._tau
        tau_call = callable(tau_c)
        nv_shape = (self.nv,)
        checked_tau, forces = self._checked_tau, self._forces
        check_sizes = self._check_sizes
        ndarray, F64, contiguous = np.ndarray, _F64, np.ascontiguousarray
        if self.n_constraints:
            cms, cds, prox = self.cms, self.cds, self.prox
            dynamics = pin.constraintDynamics

            def engine(q, v, tau, t):
                return dynamics(model, data, q, v, tau, cms, cds, prox)
        elif self._fext is not None:
            aba = pin.aba

            def engine(q, v, tau, t):
                return aba(model, data, q, v, tau, forces(t, q, v))
        else:
            engine = None
            aba = pin.aba

        def f(q, V, t):
            if has_roots:
                try:
                    v_from_twist(q, V, jt, W)
                except (TypeError, ValueError):        # not float64 C-contiguous, or the wrong size
                    q, V = contiguous(q, dtype=F64), contiguous(V, dtype=F64)
                    check_sizes(q, V)
                    v_from_twist(q, V, jt, W)
                v = v_buf
            else:
                if type(q) is not ndarray or q.dtype is not F64:
                    q = contiguous(q, dtype=F64)
                if type(V) is not ndarray or V.dtype is not F64:
                    V = contiguous(V, dtype=F64)
                if V.shape != nv_shape:
                    check_sizes(q, V)
                v = V                                  # the same in both coordinates
            tau = tau_c
            if tau_call:
                tau = tau(t, q, v)
                if type(tau) is not ndarray or tau.dtype is not F64 or tau.shape != nv_shape:
                    tau = checked_tau(tau)
            a = aba(model, data, q, v, tau) if engine is None else engine(q, v, tau, t)
            if has_roots:
                vdot_from_a(jt, W, a)                  # in place (jt: int64 table; W, a: float64 vectors)
            return a

        f.__doc__ = PinocchioModel.f.__doc__
        return f

    def _checked_tau(self, tau):
        tau = np.ascontiguousarray(tau, dtype=np.float64)
        if tau.shape != (self.nv,):
            raise InputError(f"tau(t, q, v) returned shape {tau.shape}; expected ({self.nv},).")
        return tau

    def _check_sizes(self, q, V):
        if np.shape(q) != (self.model.nq,) or np.shape(V) != (self.nv,):
            raise InputError(f"PinocchioModel.f: q has shape {np.shape(q)} and V {np.shape(V)}; this model needs "
                             f"q of shape ({self.model.nq},) and V of shape ({self.nv},) (the twist layout of "
                             "model.layout).")

    def _f_numpy(self, q, V, t):
        self._check_sizes(q, V)
        pin = self.pin
        v = self._v_from_twist_numpy(q, V)
        tau = self._torques(t, q, v)
        if self.n_constraints:
            a = pin.constraintDynamics(self.model, self.data, q, v, tau, self.cms, self.cds, self.prox)
        elif self._fext is None:
            a = pin.aba(self.model, self.data, q, v, tau)
        else:
            a = pin.aba(self.model, self.data, q, v, tau, self._forces(t, q, v))
        Vd = np.array(a)
        if len(self.roots):
            i = self._riv[:, None]
            vl, w = v[i + np.arange(3)], v[i + np.arange(3, 6)]
            Vd[i + np.arange(3)] = a[i + np.arange(3, 6)]
            Vd[i + np.arange(3, 6)] = _q._rotate(self._quats(q), a[i + np.arange(3)] + cross(w, vl))
        for iq, iv in self.planars:
            Vd[iv:iv + 2] = _planar_R(q, iq) @ (a[iv:iv + 2] + v[iv + 2] * _J2 @ v[iv:iv + 2])
        for iq, iv in self.zyx:
            Vd[iv:iv + 3] = params.RZYX.G(q[iq:iq + 3]) @ a[iv:iv + 3] + _zyx_Gdot_v(q[iq:iq + 3], v[iv:iv + 3])
        return Vd

    def pin_state(self, q, V):
        """(q, v) in Pinocchio's own coordinates, for pin.forwardKinematics, frames, viewers."""
        return np.array(q, float), self.v_from_twist(np.asarray(q, float), np.asarray(V, float))

    # --- diagnostics ------------------------------------------------------------------------------
    def energy(self, q, V):
        pin = self.pin
        v = self.v_from_twist(q, V)
        return pin.computeKineticEnergy(self.model, self.data, q, v) + pin.computePotentialEnergy(self.model, self.data, q)

    def spatial_momentum(self, q, V):
        """Total spatial momentum (linear, angular about the world origin) in the world frame."""
        pin = self.pin
        v = self.v_from_twist(q, V)
        pin.forwardKinematics(self.model, self.data, q, v)
        h = pin.Force.Zero()
        for j in range(1, self.model.njoints):
            h += self.data.oMi[j].act(self.model.inertias[j] * self.data.v[j])
        return np.concatenate([h.linear, h.angular])
