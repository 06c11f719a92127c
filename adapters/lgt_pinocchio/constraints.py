"""Pinocchio's RigidConstraintModels (3-D/6-D contacts to the world, loop closures) as the
bridge's constraints: f from Pinocchio's constraintDynamics; the residual g(q) = position
difference of the two constraint frames in the world (6-D: and the rotation vector
log(R₂ᵀR₁) between them); A = ∂g/∂V from Pinocchio's frame Jacobians and γ from its frame
accelerations; finite-difference references of A and γ that tests hold them to."""
import numpy as np

from lgt_bridge.errors import InputError
from lgt_bridge.groups.batch import cross


def _cross(a, b):
    return cross(a[None], b[None])[0]


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
    exe = _cross(e, ed)
    return -ap * ee * exe + bp * ee * _cross(e, exe) + b * _cross(ed, exe)


class Constraints:
    """The RigidConstraintModels of a model (``cms``, their data ``cds``, ``n`` rows), with
    the kinematics of g, A and γ on a Data of their own (f keeps the model's ``data``, on which
    constraintDynamics is initialized here). ``joints``: the model's
    :class:`lgt_pinocchio.joints.Joints` (A and γ in twist coordinates)."""

    def __init__(self, pin, model, data, joints, constraints, fext):
        self.pin, self.model, self.data, self.joints = pin, model, data, joints
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
        self.n = int(sum(cm.residualSize() for cm in self.cms))
        if not self.n:
            return
        if fext is not None:
            raise InputError("fext together with constraints is not supported (Pinocchio's "
                             "constraintDynamics takes no external forces); express the loads as tau.")
        # (constraint model, 6-D?, first row); the placements are read from it at each call,
        # as constraintDynamics reads them
        self._rows, row = [], 0
        for cm in self.cms:
            six = cm.type == pin.ContactType.CONTACT_6D
            self._rows.append((cm, six, row))
            row += 6 if six else 3
        self._cdata = model.createData()       # kinematics of g, A, γ (f keeps data)
        pin.initConstraintDynamics(model, data, self.cms, self.cds)
        self.prox = pin.ProximalSettings(1e-12, 1e-12, 50)

    def check(self, q0):
        """InputError when the constraints do not hold at q0."""
        if not self.n:
            return
        g0 = self.residual(q0)
        if np.abs(g0).max() > 1e-6:
            k = int(np.argmax(np.abs(g0) > 1e-6))
            raise InputError(f"constraint residual component {k} is {g0[k]:.3g} at q0: the constraint "
                             "frames do not coincide; set joint2_placement to where joint1's frame is "
                             "at q0 (or start from a configuration that satisfies the constraints).")

    def dynamics(self, q, v, tau):
        """Pinocchio's constraintDynamics: the joint accelerations a (on the model's data)."""
        return self.pin.constraintDynamics(self.model, self.data, q, v, tau, self.cms, self.cds, self.prox)

    def _frame(self, j, pl):
        """World placement of the frame ``pl`` on joint j (j = 0: the world) after kinematics."""
        return pl if j == 0 else self._cdata.oMi[j] * pl

    def _frames(self):
        """(joint1, placement1, joint2, placement2, 6-D?, first row) per constraint."""
        for cm, six, r in self._rows:
            yield cm.joint1_id, cm.joint1_placement, cm.joint2_id, cm.joint2_placement, six, r

    def residual(self, q):
        """g(q)."""
        if not self.n:
            return np.zeros(0)
        pin = self.pin
        pin.forwardKinematics(self.model, self._cdata, np.asarray(q, float))
        out = np.empty(self.n)
        for j1, pl1, j2, pl2, six, r in self._frames():
            M1, M2 = self._frame(j1, pl1), self._frame(j2, pl2)
            out[r:r + 3] = M1.translation - M2.translation
            if six:
                out[r + 3:r + 6] = pin.log3(M2.rotation.T @ M1.rotation)
        return out

    def jacobian(self, q):
        """A(q) = ∂g/∂V (ġ = A V) from Pinocchio's frame Jacobians: with J_i the
        LOCAL_WORLD_ALIGNED Jacobian of constraint frame i (world linear velocity of its
        origin, world ω), the position rows are (J₁ - J₂)_lin T and the rotation rows of a
        6-D constraint, e = log(E), E = R₂ᵀR₁, are Jlog3(E) R₁ᵀ (J₁ - J₂)_ang T (ė =
        Jr(e)⁻¹ w with Ė = E w~, w = R₁ᵀ(ω₁ - ω₂) in the world), where v = T(q) V."""
        nv = self.model.nv
        if not self.n:
            return np.zeros((0, nv))
        pin, model, d = self.pin, self.model, self._cdata
        q = np.asarray(q, float)
        pin.computeJointJacobians(model, d, q)
        G = np.zeros((self.n, nv))
        lwa = pin.LOCAL_WORLD_ALIGNED
        for j1, pl1, j2, pl2, six, r in self._frames():
            J = pin.getFrameJacobian(model, d, j1, pl1, lwa)
            if j2:
                J = J - pin.getFrameJacobian(model, d, j2, pl2, lwa)
            G[r:r + 3] = J[:3]
            if six:
                R1 = self._frame(j1, pl1).rotation
                E = self._frame(j2, pl2).rotation.T @ R1
                G[r + 3:r + 6] = pin.Jlog3(E) @ (R1.T @ J[3:])
        return self.joints.times_T(G, q)

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
        return R, R @ w, R @ (af.linear + _cross(w, vf.linear)), R @ af.angular

    def gamma(self, q, v):
        """γ(q, V) = (d/dt A) V at Pinocchio's v = T(q) V, so that g̈ = A V̇ + γ: the second
        derivative of g along the motion with V̇ = 0. In Pinocchio's coordinates V̇ = 0 is the
        acceleration a₀ = Ṫ V (-ω × v_lin on each free-flyer, zero elsewhere), so γ comes from
        one forwardKinematics(q, v, a₀) and the frames' classical accelerations: p̈₁ - p̈₂ on
        the position rows; on the rotation rows of a 6-D constraint
        ë = Jr(e)⁻¹ (ẇ - (∂Jr(e)[ė]) ė) with ẇ = -ω₁ × w + R₁ᵀ(α₁ - α₂) (world α)."""
        if not self.n:
            return np.zeros(0)
        pin = self.pin
        pin.forwardKinematics(self.model, self._cdata, q, v, self.joints.TdV(v, q))
        out = np.empty(self.n)
        for j1, pl1, j2, pl2, six, r in self._frames():
            R1, w1, p1, al1 = self._frame_motion(j1, pl1)
            R2, w2, p2, al2 = self._frame_motion(j2, pl2)
            out[r:r + 3] = p1 - p2
            if six:
                E = R2.T @ R1
                Jl = pin.Jlog3(E)
                w = R1.T @ (w1 - w2)
                wd = -_cross(R1.T @ w1, w) + R1.T @ (al1 - al2)
                ed = Jl @ w
                out[r + 3:r + 6] = Jl @ (wd - _djr(pin.log3(E), ed))
        return out


# finite-difference references of A and γ (tests hold the analytic ones to them), on a
# model's own g and increments (``model.constraints``, ``model._moved``)
def jacobian_fd(model, q, eps=1e-6):
    """A by central differences of g along each twist direction through τ (SO(3)xR³ exp)."""
    A = np.zeros((model.n_constraints, model.nv))
    for k in range(model.nv):
        e = np.zeros(model.nv)
        e[k] = eps
        A[:, k] = (model.constraints(model._moved(q, e)) - model.constraints(model._moved(q, -e))) / (2 * eps)
    return A


def gamma_fd(model, q, V, eps=2e-3):
    """γ = d²/ds² g(τ(q, s V)) at s = 0 (V is constant along that curve: ω body and ṙ
    inertial), by the 7-point central stencil (error O(eps⁶))."""
    c = np.array([2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0]) / 180.0
    V = np.asarray(V, float)
    g = [model.constraints(model._moved(q, s * eps * V)) for s in range(-3, 4)]
    return sum(ck * gk for ck, gk in zip(c, g)) / eps ** 2


def geometric_stiffness(model, q, lam, eps=1e-6):
    """∂(A(q)ᵀλ)/∂z by central differences of the model's A along the increments."""
    G = np.empty((model.nv, model.nv))
    e = np.zeros(model.nv)
    for k in range(model.nv):
        e[k] = eps
        G[:, k] = (model.constraint_jacobian(model._moved(q, e)).T @ lam
                   - model.constraint_jacobian(model._moved(q, -e)).T @ lam) / (2 * eps)
        e[k] = 0.0
    return G
