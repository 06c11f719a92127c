"""Pinocchio's constraints as the bridge's constraints: f from Pinocchio's constraintDynamics; the
residual g(q) = position difference of the two constraint frames in the world (6-D: and the
rotation vector log(R₂ᵀR₁) between them); A = ∂g/∂V from Pinocchio's frame Jacobians and γ
from its frame accelerations; finite-difference references of A and γ that tests hold them to.

Taken: ``RigidConstraintModel`` (CONTACT_3D, CONTACT_6D; to the world or loop closures), and on
Pinocchio 4 its bilateral anchors ``PointAnchorConstraintModel`` (3-D) and
``FrameAnchorConstraintModel`` (6-D), also inside a generic ``ConstraintModel`` (converted with
Pinocchio's own ``convertToRigidConstraintModel``). Refused before any step, naming the class
and why: unilateral, friction and joint-limit constraints, compliant constraints and prescribed
(desired) offsets, velocities or accelerations. Pinocchio 3.x (``size()``, the three-argument
``initConstraintDynamics``, ``corrector``) and 4.x (``residualSize()``, four arguments,
``m_baumgarte_parameters``) are both handled here (:func:`rows_of`, :func:`init_dynamics`).

As Pinocchio means them: a constraint made by the four-argument constructor
``RigidConstraintModel(type, model, joint1_id, placement)`` (joint 2 the world at the default
identity) holds its frame where it is at q0 (Pinocchio constrains the frame's acceleration);
its world anchor is set there when the model is wrapped. Constraint rows that depend linearly
on the others at the (closed) initial configuration (a 3-D loop closing a planar mechanism) are
set aside with a :class:`~lgt_bridge.errors.ModelNote` (``redundant_rows``); Pinocchio's
proximal solver still receives every row."""

import warnings

import numpy as np

from lgt_bridge.errors import InputError, ModelNote
from lgt_bridge.groups.batch import cross

#: |g| at q0 below which a constraint counts as closed
CLOSED_TOL = 1e-9
#: rows of A(q0) whose pivot in a rank-revealing QR of the row-normalized Aᵀ falls below this
#: fraction of the largest are redundant
RANK_TOL = 1e-9

#: constraint classes of Pinocchio 4 that the bridge cannot run, and why
REFUSED = {
    "PointContactConstraintModel": "a unilateral contact with Coulomb friction (the contact force is "
    "the solution of a complementarity problem, and the contact opens and closes), which the bridge's "
    "smooth integrators of bilateral constraints cannot take; model a closed contact as a "
    "PointAnchorConstraintModel, or simulate it with Pinocchio's own ADMMConstraintSolver/PGSConstraintSolver",
    "JointLimitConstraintModel": "a unilateral joint limit (active only at its bound: an inequality, "
    "with impacts), which the bridge's integrators of bilateral constraints cannot take; keep the "
    "motion inside the limits with a joint torque (tau), or simulate it with Pinocchio's own "
    "ADMMConstraintSolver/PGSConstraintSolver",
    "JointFrictionConstraintModel": "dry joint friction (a set-valued force bounded by the friction "
    "limits, sticking and slipping), which the bridge's smooth integrators cannot take; model viscous "
    "friction as a joint torque tau(t, q, v) = -d v, or simulate it with Pinocchio's own "
    "ADMMConstraintSolver/PGSConstraintSolver",
}


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



def rows_of(cm):
    """Rows of a RigidConstraintModel: ``residualSize()`` on Pinocchio 4, ``size()`` on 3."""
    return cm.residualSize() if hasattr(cm, "residualSize") else cm.size()


def init_dynamics(pin, model, data, cms, cds):
    """Pinocchio's initConstraintDynamics: (model, data, models, datas) on 4, (model, data,
    models) on 3."""
    if hasattr(pin, "PointAnchorConstraintModel"):
        pin.initConstraintDynamics(model, data, cms, cds)
    else:
        pin.initConstraintDynamics(model, data, cms)


def corrector(cm):
    """The Baumgarte corrector of a RigidConstraintModel (Pinocchio 4: ``m_baumgarte_parameters``,
    3: ``corrector``)."""
    return cm.m_baumgarte_parameters if hasattr(cm, "m_baumgarte_parameters") else cm.corrector


def _is_zero(x):
    return not np.any(np.asarray(x, float))


def _rigid(pin, model, k, c):
    """The RigidConstraintModel that constraint ``c`` (item ``k`` of the user's list) is, or
    InputError naming its class and why the bridge cannot run it."""
    name = type(c).__name__
    generic = getattr(pin, "ConstraintModel", None)
    if generic is not None and isinstance(c, generic):
        c = c.extract()                      # Pinocchio 4's variant: the constraint it holds
        name = f"ConstraintModel holding a {type(c).__name__}"
    cls = type(c).__name__
    if cls in REFUSED:
        raise InputError(f"constraints[{k}] is a {name}: {REFUSED[cls]}.")
    if isinstance(c, pin.RigidConstraintModel):
        if c.type not in (pin.ContactType.CONTACT_3D, pin.ContactType.CONTACT_6D):
            raise InputError(f"constraints[{k}] is a RigidConstraintModel of type {c.type}; the bridge takes "
                             "CONTACT_3D and CONTACT_6D.")
        desired = {"desired_contact_placement": not c.desired_contact_placement.isIdentity(),
                   "desired_contact_velocity": not _is_zero(c.desired_contact_velocity.vector),
                   "desired_contact_acceleration": not _is_zero(c.desired_contact_acceleration.vector)}
        compliance = c.retrieveCompliance() if hasattr(c, "retrieveCompliance") else 0.0
        out = c
    elif cls in ("PointAnchorConstraintModel", "FrameAnchorConstraintModel"):
        desired = {f: not _is_zero(getattr(c, f)) for f in
                   ("desired_constraint_offset", "desired_constraint_velocity", "desired_constraint_acceleration")}
        compliance = c.retrieveCompliance()
        out = pin.convertToRigidConstraintModel(model, c, pin.LOCAL)
        bc, oc = c.baumgarte_corrector_parameters, corrector(out)
        oc.Kp, oc.Kd = bc.Kp, bc.Kd
    else:
        raise InputError(f"constraints[{k}] is a {name}; the bridge takes pinocchio.RigidConstraintModel "
                         "(CONTACT_3D/6D), PointAnchorConstraintModel and FrameAnchorConstraintModel.")
    set_ = [f for f, on in desired.items() if on]
    if set_:
        raise InputError(f"constraints[{k}] ({name}) has a nonzero {', '.join(set_)}: a prescribed motion "
                         "of the constraint, which the bridge does not take (its constraints make the two "
                         "frames coincide, with placements fixed when the model is wrapped); leave it at zero "
                         "(identity), and put a constant offset into joint2_placement.")
    if not _is_zero(compliance):
        raise InputError(f"constraints[{k}] ({name}) has a compliance of {np.asarray(compliance).tolist()}: a "
                         "soft constraint, which the bridge does not take (its constraints hold exactly); "
                         "set it to zero, or model the compliance as a joint torque or external force.")
    return out


def independent_rows(A):
    """Boolean mask of a maximal set of linearly independent rows of A (pivoted QR of the
    row-normalized Aᵀ: the rows picked first are kept; zero rows are dropped)."""
    from scipy.linalg import qr
    n = A.shape[0]
    if n == 0:
        return np.ones(0, bool)
    norms = np.linalg.norm(A, axis=1)
    scale = max(norms.max(), 1e-300)
    An = A / np.where(norms > RANK_TOL * scale, norms, np.inf)[:, None]
    _, R, piv = qr(An.T, mode="economic", pivoting=True)
    d = np.abs(np.diagonal(R))
    rank = int(np.sum(d > RANK_TOL * max(d.max(initial=0.0), 1e-300))) if d.max(initial=0.0) > 0 else 0
    mask = np.zeros(n, bool)
    mask[piv[:rank]] = True
    return mask


class Constraints:
    """The constraints of a model as Pinocchio RigidConstraintModels (``cms``, their data
    ``cds``), with the kinematics of g, A and γ on a Data of their own (f keeps the model's
    ``data``, on which constraintDynamics is initialized here). ``joints``: the model's
    :class:`lgt_pinocchio.joints.Joints` (A and γ in twist coordinates). ``n``: the rows the
    bridge enforces (``rows``: their indices among all ``n_all`` rows; :meth:`set_rows`).

    The user's constraint objects are copied when the model is wrapped (into Pinocchio's own
    vectors, which constraintDynamics and g, A, γ read): changing a placement afterwards does
    not change the wrapped model; wrap it again."""

    def __init__(self, pin, model, data, joints, constraints, q0, prox_settings=None):
        self.pin, self.model, self.data, self.joints = pin, model, data, joints
        if prox_settings is None and isinstance(constraints, list) and not constraints:
            # none (a model wrapped afresh per run): Pinocchio's vectors and settings, slow
            # to construct and unused without rows, are made on first access (__getattr__)
            self.names, self.redundant_rows, self.anchored = [], [], []
            self.n_all = self.n = 0
            self.rows = np.arange(0)
            return
        self.cms = pin.StdVec_RigidConstraintModel()
        self.cds = pin.StdVec_RigidConstraintData()
        self.names = []
        if hasattr(constraints, "createData"):          # one constraint, not in a list
            constraints = [constraints]
        try:
            constraints = list(constraints)
        except TypeError:
            raise InputError(f"constraints: expected a list of Pinocchio constraint models, got a "
                             f"{type(constraints).__name__}.") from None
        made = []                                  # (summed over a list: a StdVec's iterator is slow)
        for k, c in enumerate(constraints):
            cm = _rigid(pin, model, k, c)
            made.append(cm)
            self.cms.append(cm)
            self.cds.append(cm.createData())
            self.names.append(f"constraints[{k}] ({type(c).__name__} on joint {cm.joint1_id} "
                              f"{model.names[cm.joint1_id]!r}"
                              + (f" and joint {cm.joint2_id} {model.names[cm.joint2_id]!r})" if cm.joint2_id else
                                 " and the world)"))
        if prox_settings is not None and not isinstance(prox_settings, pin.ProximalSettings):
            raise InputError(f"prox_settings: expected a pinocchio.ProximalSettings (e.g. "
                             f"pin.ProximalSettings(1e-12, 1e-12, 50): accuracy, mu, max_iter), got a "
                             f"{type(prox_settings).__name__}.")
        self.prox = pin.ProximalSettings(1e-12, 1e-12, 50) if prox_settings is None else prox_settings
        self.n_all = self.n = int(sum(rows_of(cm) for cm in made))
        self.rows = np.arange(self.n)
        self.redundant_rows = []
        self.anchored = []
        if not self.n:
            return
        # (constraint model, 6-D?, first row): the wrapped copies in cms (references into
        # Pinocchio's vector), read at each call as constraintDynamics reads them
        self._rows, row = [], 0
        for cm in self.cms:
            six = cm.type == pin.ContactType.CONTACT_6D
            self._rows.append((cm, six, row))
            row += 6 if six else 3
        self._cdata = model.createData()       # kinematics of g, A, γ (f keeps data)
        self._anchor_defaults(np.asarray(q0, float))
        init_dynamics(pin, model, data, self.cms, self.cds)

    def __getattr__(self, name):
        """``cms``, ``cds`` and ``prox`` of a constraint-free model, made on first use."""
        if name == "cms":
            value = self.pin.StdVec_RigidConstraintModel()
        elif name == "cds":
            value = self.pin.StdVec_RigidConstraintData()
        elif name == "prox":
            value = self.pin.ProximalSettings(1e-12, 1e-12, 50)
        else:
            raise AttributeError(name)
        setattr(self, name, value)
        return value

    def _anchor_defaults(self, q0):
        """A constraint to the world left at the default identity placement (the four-argument
        constructor) holds its frame where it is at q0: its anchor is put there."""
        pin = self.pin
        pin.forwardKinematics(self.model, self._cdata, q0)
        for k, (cm, six, r) in enumerate(self._rows):
            if cm.joint2_id == 0 and cm.joint2_placement.isIdentity():
                M1 = self._frame(cm.joint1_id, cm.joint1_placement)
                g = M1.translation if not six else np.concatenate([M1.translation, pin.log3(M1.rotation)])
                if np.abs(g).max() > CLOSED_TOL:
                    cm.joint2_placement = M1.copy()
                    self.anchored.append(k)

    def set_rows(self, keep):
        """Enforce only the rows ``keep`` (a boolean mask over all rows) in g, A and γ; the others
        are redundant (a ModelNote names them)."""
        keep = np.asarray(keep, bool)
        self.rows = np.flatnonzero(keep)
        self.redundant_rows = [int(i) for i in np.flatnonzero(~keep)]
        self.n = len(self.rows)
        if self.redundant_rows:
            owners = sorted({self._owner(i) for i in self.redundant_rows})
            warnings.warn(ModelNote(
                f"Pinocchio model: {len(self.redundant_rows)} of its {self.n_all} constraint rows are redundant "
                f"at the initial configuration (rows {self.redundant_rows}, of {'; '.join(owners)}): they "
                "depend linearly on the others (e.g. a 3-D loop closing a planar mechanism). lgt_bridge sets "
                "them aside and enforces the others (the motion is the same; Pinocchio's proximal solver "
                "still gets every row, and the constraint forces are not unique)."), stacklevel=4)

    def _owner(self, row):
        for (cm, six, r), name in zip(self._rows, self.names):
            if r <= row < r + (6 if six else 3):
                return name
        return f"row {row}"

    def residual_all(self, q):
        """g(q) on every row (redundant ones included)."""
        pin = self.pin
        pin.forwardKinematics(self.model, self._cdata, np.asarray(q, float))
        out = np.empty(self.n_all)
        for j1, pl1, j2, pl2, six, r in self._frames():
            M1, M2 = self._frame(j1, pl1), self._frame(j2, pl2)
            out[r:r + 3] = M1.translation - M2.translation
            if six:
                out[r + 3:r + 6] = pin.log3(M2.rotation.T @ M1.rotation)
        return out

    def _keep(self, x):
        return x if self.n == self.n_all else x[self.rows]

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
        """g(q) on the enforced rows."""
        if not self.n:
            return np.zeros(0)
        return self._keep(self.residual_all(q))

    def jacobian(self, q):
        """A(q) = ∂g/∂V (ġ = A V) from Pinocchio's frame Jacobians: with J_i the
        LOCAL_WORLD_ALIGNED Jacobian of constraint frame i (world linear velocity of its
        origin, world ω), the position rows are (J₁ - J₂)_lin T and the rotation rows of a
        6-D constraint, e = log(E), E = R₂ᵀR₁, are Jlog3(E) R₁ᵀ (J₁ - J₂)_ang T (ė =
        Jr(e)⁻¹ w with Ė = E w~, w = R₁ᵀ(ω₁ - ω₂) in the world), where v = T(q) V."""
        nv = self.model.nv
        if not self.n:
            return np.zeros((0, nv))
        return self.joints.times_T(self._keep(self.jacobian_all(q)), q)

    def jacobian_all(self, q):
        """∂g/∂v (Pinocchio's v) on every row."""
        nv = self.model.nv
        pin, model, d = self.pin, self.model, self._cdata
        q = np.asarray(q, float)
        pin.computeJointJacobians(model, d, q)
        G = np.zeros((self.n_all, nv))
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
        return G

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
        out = np.empty(self.n_all)
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
        return self._keep(out)


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
