"""Pinocchio's joints as the bridge's :class:`~lgt_bridge.model.Layout`, and the maps between
Pinocchio's velocities v and the bridge's twists V (the numpy reference of
:mod:`lgt_pinocchio.kernels`).

* free-flyer: a rigid body, q = (x y z, qx qy qz qw) (``params.QUAT_XYZW``), v = (v_lin body,
  ω body), V = (ω body, ṙ inertial) with ṙ = R v_lin;
* spherical: a rotation-only body on its x y z w quaternion, V = v = ω (body);
* spherical-ZYX: a rotation-only body on its z-y-x angles (``params.RZYX``), V = ω (child
  frame) = G(q) v; f maps ω to v = G⁻¹ω, so its accuracy is bounded near cos θ1 = 0;
* continuous (URDF ``continuous``: RUBX/Y/Z, RevoluteUnboundedUnaligned): q = (cos θ, sin θ),
  v = θ̇, a circle coordinate (SO(2));
* planar: q = (x, y, cos θ, sin θ), v = (v_xy joint frame, ω): (x, y) vector coordinates with
  rates ṗ = R(θ) v_xy (parent frame), (cos θ, sin θ) a circle coordinate with rate ω;
* every joint whose configuration space is a vector space (nq = nv: revolute, prismatic,
  translation, universal, ellipsoid, helical): vector coordinates, q̇ = v;
* a composite joint is split into its components (circle and vector ones only).

With v = T(q) V: :meth:`Joints.v_from_twist`, :meth:`Joints.twist_from_v`, :meth:`Joints.T`,
:meth:`Joints.times_T` (G T without forming T), :meth:`Joints.TdV` (Ṫ V, Pinocchio's
acceleration at V̇ = 0) and :meth:`Joints.vdot_from_a` (Pinocchio's a -> V̇).
"""
from functools import lru_cache

import numpy as np

from lgt_bridge import lgt, params
from lgt_bridge.errors import InputError
from lgt_bridge.groups.batch import conj, cross, rotate, to_matrix
from lgt_bridge.model import CIRCLE_NORM_TOL, Layout, RigidBody

#: continuous joints: q = (cos θ, sin θ), v = θ̇ (SO(2))
CIRCLE_JOINTS = ("JointModelRUBX", "JointModelRUBY", "JointModelRUBZ", "JointModelRevoluteUnboundedUnaligned")
#: joints Pinocchio steps as vector spaces (q̇ = v) that still have no τ of their own here
NOT_YET = {"JointModelMimic": "a mimic joint has no coordinates of its own"}
#: joints integrated as vector spaces (q̇ = v)
VECTOR_JOINTS = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelPX", "JointModelPY",
                 "JointModelPZ", "JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned",
                 "JointModelTranslation", "JointModelHelicalX", "JointModelHelicalY", "JointModelHelicalZ")
#: joints that are rigid bodies (or, planar, a body on SO(2)xR²), never vector coordinates
_BODY_JOINTS = ("JointModelComposite", "JointModelFreeFlyer", "JointModelSpherical", "JointModelSphericalZYX")

#: the planar rotation's generator: J v = (-v_y, v_x), R(θ) = exp(θ J)
J2 = np.array([[0.0, -1.0], [1.0, 0.0]])


def zyx_Gdot_v(th, v):
    """Ġ θ̇ of the z-y-x angles th at rates v (ω̇ = G θ̈ + Ġ θ̇; checked against Pinocchio's
    joint acceleration in tests)."""
    s1, c1, s2, c2 = np.sin(th[1]), np.cos(th[1]), np.sin(th[2]), np.cos(th[2])
    ad, bd, cd = v
    return np.array([-c1 * bd * ad,
                     (c2 * c1 * cd - s2 * s1 * bd) * ad - s2 * cd * bd,
                     (-s2 * c1 * cd - c2 * s1 * bd) * ad - c2 * cd * bd])


def planar_R(q, iq):
    """R(θ) of the planar joint whose q starts at iq: q[iq + 2], q[iq + 3] = cos θ, sin θ."""
    c, s = q[iq + 2], q[iq + 3]
    return np.array([[c, -s], [s, c]])


def _simple_joint(name, iq, iv, nq, nv):
    """A joint stepped as circle or vector coordinates (not a rigid body, not refused)."""
    return name in CIRCLE_JOINTS or name in VECTOR_JOINTS or (
        nq == nv and name not in NOT_YET and name not in _BODY_JOINTS)


def _parts(model, j, jm=None):
    """[(name, iq, iv, nq, nv)] of joint j (``jm``: model.joints[j], when at hand): the joint
    itself, or a composite's components."""
    jm = model.joints[j] if jm is None else jm
    name, iq, iv = jm.shortname(), jm.idx_q, jm.idx_v
    if name != "JointModelComposite":
        return [(name, iq, iv, jm.nq, jm.nv)]
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
    return parts


def _unsupported(model, j, name):
    jm = model.joints[j]
    why = NOT_YET.get(name, "it is not a joint type lgt_bridge knows")
    return InputError(f"Pinocchio joint {j} ({model.names[j]!r}) is a {name} (nq = {jm.nq}, "
                      f"nv = {jm.nv}): {why}. lgt_bridge supports free-flyers, spherical joints, "
                      "continuous joints (RUBX/Y/Z), composite joints of those, and joints whose "
                      f"configuration space is a vector space ({', '.join(VECTOR_JOINTS[:6])}, ...). "
                      "Integrate this model with Pinocchio's own loop, or replace the joint.")


@lru_cache(maxsize=None)
def _mover(kind):
    """The τ that moves a free-flyer ("move"), spherical ("ball") or spherical-ZYX ("zyx") joint's q
    by a twist increment (SO(3)xR³, exp chart)."""
    if kind == "move":
        return lgt.LGT(params.QUAT_XYZW, "SO3xR3", "exp")
    return lgt.RotationLGT(params.QUAT_XYZW if kind == "ball" else params.RZYX, "exp")


class Joints:
    """The joints of a ``pinocchio.Model`` in the bridge's terms: ``layout``, and the (iq, iv)
    of its free-flyer ``roots``, spherical ``balls``, ``planars`` and spherical-``zyx`` joints
    (the joints whose v and V differ: roots, planars, zyx). InputError on a joint it cannot
    step."""

    def __init__(self, model):
        self.model = model
        bodies, vq, vv, cq, cv = [], [], [], [], []
        self.roots, self.balls, self.planars, self.zyx = [], [], [], []
        #: the free-flyers' indices in layout.bodies (same order as roots)
        self.root_bodies = ()
        for j, jm in enumerate(model.joints):      # (iterating: model.joints[j] copies the joint each time)
            if j == 0:
                continue
            parts = _parts(model, j, jm)
            if all(_simple_joint(*p) for p in parts):
                for cname, ciq, civ, cnq, cnv in parts:
                    if cname in CIRCLE_JOINTS:
                        cq.append((ciq, ciq + 1))
                        cv.append(civ)
                    else:
                        vq += range(ciq, ciq + cnq)
                        vv += range(civ, civ + cnv)
                continue
            (name, iq, iv, _, _), = parts
            jname = model.names[j]
            if name == "JointModelPlanar":
                # SO(2)xR²: (x, y) vector coordinates with rates ṗ (parent frame), (c, s) a circle
                vq += [iq, iq + 1]
                vv += [iv, iv + 1]
                cq.append((iq + 2, iq + 3))
                cv.append(iv + 2)
                self.planars.append((iq, iv))
            elif name == "JointModelSphericalZYX":
                # rotation-only body on the z-y-x angles; V = ω (child frame) = G(q) v
                bodies.append(RigidBody(params.RZYX, (), tuple(range(iq, iq + 3)), tuple(range(iv, iv + 3)), jname))
                self.zyx.append((iq, iv))
            elif name == "JointModelFreeFlyer":
                self.root_bodies += (len(bodies),)
                bodies.append(RigidBody(params.QUAT_XYZW, tuple(range(iq, iq + 3)), tuple(range(iq + 3, iq + 7)),
                                        tuple(range(iv, iv + 6)), jname))
                self.roots.append((iq, iv))
            elif name == "JointModelSpherical":
                # rotation-only body: q = x y z w quaternion, v = ω in the joint frame (= body ω)
                bodies.append(RigidBody(params.QUAT_XYZW, (), tuple(range(iq, iq + 4)),
                                        tuple(range(iv, iv + 3)), jname))
                self.balls.append((iq, iv))
            else:
                raise _unsupported(model, j, name)
        self.nv = model.nv
        self.layout = Layout(model.nq, model.nv, bodies, tuple(vq), tuple(vv), circle_q=tuple(cq),
                             circle_v=tuple(cv))
        self._riq = np.array([r[0] for r in self.roots], int)
        self._riv = np.array([r[1] for r in self.roots], int)
        #: True when V and v differ somewhere (free-flyers, planar or spherical-ZYX joints)
        self.convert = bool(self.roots or self.planars or self.zyx)

    # q moved by a twist increment (made on first use, shared: τ objects hold no state)
    _move = property(lambda self: _mover("move"))
    _move_ball = property(lambda self: _mover("ball"))
    _move_zyx = property(lambda self: _mover("zyx"))

    def joint_of(self, kind, index):
        """The joint that owns entry ``index`` of q (kind 'q') or of v / V (kind 'v'), for messages:
        "joint 'l_hip_pitch' (Pinocchio joint 3)"."""
        for j in range(1, self.model.njoints):
            jm = self.model.joints[j]
            i0, n = (jm.idx_q, jm.nq) if kind == "q" else (jm.idx_v, jm.nv)
            if i0 <= index < i0 + n:
                return f"joint {self.model.names[j]!r} (Pinocchio joint {j})"
        return f"{kind}[{index}]"

    def validate(self, q0):
        """InputError when the rotations or continuous joints of q0 are not valid coordinates."""
        for b in self.layout.bodies:
            b.validate(q0, f"q0 of joint {b.name!r}")
        for c, _ in self.layout.circle_q:
            if not abs(np.hypot(q0[c], q0[c + 1]) - 1.0) <= CIRCLE_NORM_TOL:
                raise InputError(f"q0: {self.joint_of('q', c)} is a continuous joint whose (cos θ, sin θ) = "
                                 f"({q0[c]!r}, {q0[c + 1]!r}) is not of unit norm; give (cos θ, sin θ) "
                                 "(pin.neutral(model) and pin.randomConfiguration(model) do).")

    # --- Pinocchio velocity v <-> model twist V (v = T(q) V) ----------------------------------
    def quats(self, q):
        """The free-flyers' quaternions, scalar first, (n_roots, 4)."""
        p = q[self._riq[:, None] + np.arange(3, 7)]          # (k, 4) x y z w
        return p[:, [3, 0, 1, 2]]

    def v_from_twist(self, q, V):
        """Pinocchio's v of the model twist V at q (a new array)."""
        v = V.copy()
        if len(self.roots):
            i = self._riv[:, None]
            v[i + np.arange(3)] = rotate(conj(self.quats(q)), V[i + np.arange(3, 6)])
            v[i + np.arange(3, 6)] = V[i + np.arange(3)]
        for iq, iv in self.planars:
            v[iv:iv + 2] = planar_R(q, iq).T @ V[iv:iv + 2]
        for iq, iv in self.zyx:
            v[iv:iv + 3] = params.RZYX.rates_from_omega(q[iq:iq + 3], V[iv:iv + 3])
        return v

    def twist_from_v(self, q, v):
        """The model twist V of Pinocchio's v at q (a new array)."""
        V = np.array(v, float)
        if len(self.roots):
            i = self._riv[:, None]
            V[i + np.arange(3)] = v[i + np.arange(3, 6)]
            V[i + np.arange(3, 6)] = rotate(self.quats(q), v[i + np.arange(3)])
        for iq, iv in self.planars:
            V[iv:iv + 2] = planar_R(q, iq) @ v[iv:iv + 2]
        for iq, iv in self.zyx:
            V[iv:iv + 3] = params.RZYX.G(q[iq:iq + 3]) @ v[iv:iv + 3]
        return V

    def vdot_from_a(self, q, v, a):
        """V̇ of Pinocchio's acceleration a at (q, v) (a new array): (a_ang, R (a_lin + ω × v_lin))
        on free-flyers, (R (a_xy + ω J v_xy), a_ω) on planar joints, G a + Ġ v on ZYX joints."""
        Vd = np.array(a)
        if len(self.roots):
            i = self._riv[:, None]
            vl, w = v[i + np.arange(3)], v[i + np.arange(3, 6)]
            Vd[i + np.arange(3)] = a[i + np.arange(3, 6)]
            Vd[i + np.arange(3, 6)] = rotate(self.quats(q), a[i + np.arange(3)] + cross(w, vl))
        for iq, iv in self.planars:
            Vd[iv:iv + 2] = planar_R(q, iq) @ (a[iv:iv + 2] + v[iv + 2] * J2 @ v[iv:iv + 2])
        for iq, iv in self.zyx:
            Vd[iv:iv + 3] = params.RZYX.G(q[iq:iq + 3]) @ a[iv:iv + 3] + zyx_Gdot_v(q[iq:iq + 3], v[iv:iv + 3])
        return Vd

    def T(self, q):
        """T(q) with v = T(q) V, dense (nv x nv)."""
        T = np.eye(self.nv)
        if len(self.roots):
            R = to_matrix(self.quats(q))
            for k, (_, iv) in enumerate(self.roots):
                T[iv:iv + 6, iv:iv + 6] = 0.0
                T[iv:iv + 3, iv + 3:iv + 6] = R[k].T
                T[iv + 3:iv + 6, iv:iv + 3] = np.eye(3)
        for iq, iv in self.planars:
            T[iv:iv + 2, iv:iv + 2] = planar_R(q, iq).T
        for iq, iv in self.zyx:
            T[iv:iv + 3, iv:iv + 3] = np.linalg.inv(params.RZYX.G(q[iq:iq + 3]))
        return T

    def times_T(self, G, q):
        """G T(q) (a new array): Pinocchio-v columns to twist columns, without forming T."""
        A = np.array(G, float)
        if len(self.roots):
            R = to_matrix(self.quats(q))
            for k, (_, iv) in enumerate(self.roots):
                A[:, iv:iv + 3] = G[:, iv + 3:iv + 6]
                A[:, iv + 3:iv + 6] = G[:, iv:iv + 3] @ R[k].T
        for iq, iv in self.planars:
            A[:, iv:iv + 2] = G[:, iv:iv + 2] @ planar_R(q, iq).T
        for iq, iv in self.zyx:
            A[:, iv:iv + 3] = np.linalg.solve(params.RZYX.G(q[iq:iq + 3]).T, G[:, iv:iv + 3].T).T
        return A

    def TdV(self, v, q):
        """Ṫ V: Pinocchio's acceleration at V̇ = 0, (-ω × v_lin, 0) on each free-flyer
        (d/dt of Rᵀṙ at fixed ṙ), (-ω J v_xy, 0) on each planar joint, -G(q)⁻¹ Ġ θ̇ on each
        spherical-ZYX joint, zero elsewhere."""
        TdV = np.zeros(self.nv)
        for iq, iv in self.zyx:
            th = q[iq:iq + 3]
            TdV[iv:iv + 3] = -np.linalg.solve(params.RZYX.G(th), zyx_Gdot_v(th, v[iv:iv + 3]))
        if len(self.roots):
            i = self._riv[:, None]
            TdV[i + np.arange(3)] = cross(v[i + np.arange(3)], v[i + np.arange(3, 6)])
        for _, iv in self.planars:
            TdV[iv:iv + 2] = -v[iv + 2] * (J2 @ v[iv:iv + 2])
        return TdV

    def moved(self, q, d):
        """τ(q, d): q moved by the twist increment d (SO(3)xR³, exp chart)."""
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
            out[cq] = lgt.circle_tau(q[cq], d[list(self.layout.circle_v)])
        return out

