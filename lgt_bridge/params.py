"""Absolute parameterizations α: engine coordinates -> rigid-body pose.

A body's absolute coordinates are ``q_i = (r, θ)``: the position first, as both
Exudyn and Pinocchio store it, then the rotation parameters θ:

* :class:`Quaternion` — unit quaternion, ν = 7, element order ``"wxyz"``
  (Exudyn's Euler parameters) or ``"xyzw"`` (Pinocchio), chosen per body;
* :class:`RotationVector` — ν = 6 (Exudyn ``NodeRigidBodyRotVecLG``);
* :class:`TaitBryanXYZ` — ν = 6, R = Rx(θ0) Ry(θ1) Rz(θ2) (Exudyn ``RotXYZ``);
* :class:`TaitBryanZYX` — ν = 6, R = Rz(θ0) Ry(θ1) Rx(θ2) (Pinocchio ``JointModelSphericalZYX``).

``from_quat`` is α⁻¹ on the rotation: it returns the branch continuous with the
previous value (DESIGN.md): the quaternion sign with p·p_prev > 0; the rotation
vector of norm <= π (at exactly π, the sign nearest the previous); Tait-Bryan
angles unwrapped to the branch and 2π shift nearest the previous angles.
``omega_from_rates``/``rates_from_omega`` map θ̇ <-> body angular velocity ω;
they are singular where the parameterization is (‖ρ‖ = 2π, cos θ1 = 0).
"""
import numpy as np

from . import _checks
from .errors import ChartDomainError, InputError
from .groups import quaternion as _q
from .groups import so3 as _so3
from .groups._vec import EYE3, cross, dot, hat, norm

_TWO_PI = 2.0 * np.pi
_ORDERS = {"wxyz": [0, 1, 2, 3], "xyzw": [3, 0, 1, 2]}    # scalar-first from engine order
_TO_ENGINE = {"wxyz": [0, 1, 2, 3], "xyzw": [1, 2, 3, 0]}


class Parameterization:
    """Base class; subclasses define the rotation part. Positions are 3 floats."""

    name = "?"
    nrot = 0

    @property
    def nu(self):
        return 3 + self.nrot

    def __repr__(self):
        return f"{type(self).__name__}({self.name!r})"

    # --- internal batched maths on the rotation block (N, nrot) -----------------
    def _to_quat(self, rot):
        raise NotImplementedError

    def _from_quat(self, p, prev):
        raise NotImplementedError

    def _omega_from_rates(self, rot, rot_dot):
        raise NotImplementedError

    def _rates_from_omega(self, rot, omega):
        raise NotImplementedError

    def _validate_rot(self, rot, name):
        pass

    # --- public API (single body or batch) ---------------------------------------
    def validate(self, q, name="q"):
        """Check shape (N, ν) or (ν,), finiteness and the rotation constraint."""
        arr, single = _checks.batch(q, (self.nu,), name)
        self._validate_rot(arr[:, 3:], name)
        return arr, single

    def _rot(self, rot, name):
        arr, single = _checks.batch(rot, (self.nrot,), name)
        self._validate_rot(arr, name)
        return arr, single

    def alpha(self, q):
        """α(q): the pose as a 4x4 homogeneous matrix [R, r; 0, 1]."""
        arr, single = self.validate(q)
        C = np.zeros((len(arr), 4, 4))
        C[:, :3, :3] = _q._to_matrix(self._to_quat(arr[:, 3:]))
        C[:, :3, 3] = arr[:, :3]
        C[:, 3, 3] = 1.0
        return _checks.unbatch(C, single)

    def alpha_inv(self, C, prev):
        """α⁻¹(C): coordinates of the pose C, on the branch continuous with ``prev``."""
        Cb, single = _checks.batch(C, (4, 4), "C")
        _checks.rotation_matrix(Cb[:, :3, :3], "C")
        prevb, _ = self.validate(prev, "prev")
        p = _q._from_matrix(Cb[:, :3, :3])
        out = np.concatenate([Cb[:, :3, 3], self._from_quat(p, np.broadcast_to(prevb[:, 3:], (len(p), self.nrot)))], axis=1)
        return _checks.unbatch(out, single)

    def to_quat(self, rot):
        arr, single = self._rot(rot, "rot")
        return _checks.unbatch(self._to_quat(arr), single)

    def from_quat(self, p, prev):
        pb, single = _checks.batch(p, (4,), "p")
        _checks.unit_quaternion(pb, "p")
        prevb, _ = self._rot(prev, "prev")
        return _checks.unbatch(self._from_quat(pb, np.broadcast_to(prevb, (len(pb), self.nrot))), single)

    def omega_from_rates(self, rot, rot_dot):
        """Body angular velocity ω from the parameter rates θ̇."""
        arr, single = self._rot(rot, "rot")
        rd, _ = _checks.batch(rot_dot, (self.nrot,), "rot_dot")
        return _checks.unbatch(self._omega_from_rates(arr, rd), single)

    def rates_from_omega(self, rot, omega):
        """Parameter rates θ̇ from the body angular velocity ω (singular where α is)."""
        arr, single = self._rot(rot, "rot")
        om, _ = _checks.batch(omega, (3,), "omega")
        self._check_regular(arr)
        return _checks.unbatch(self._rates_from_omega(arr, om), single)

    def _check_regular(self, rot):
        pass


class Quaternion(Parameterization):
    """Unit quaternion + position, ν = 7, stored ``"wxyz"`` or ``"xyzw"``."""

    nrot = 4

    def __init__(self, order="wxyz"):
        if order not in _ORDERS:
            raise InputError(f"Quaternion order {order!r} is not supported; use 'wxyz' "
                             "(Exudyn Euler parameters) or 'xyzw' (Pinocchio).")
        self.order = order
        self.name = f"quat_{order}"
        self._perm = _ORDERS[order]
        self._back = _TO_ENGINE[order]

    def _validate_rot(self, rot, name):
        _checks.unit_quaternion(rot, name + " (quaternion part)")

    def _to_quat(self, rot):
        return rot if self.order == "wxyz" else rot[:, self._perm]

    def _engine(self, p):
        return p if self.order == "wxyz" else p[:, self._back]

    def _from_quat(self, p, prev):
        s = np.where(dot(p, self._to_quat(prev)) < 0.0, -1.0, 1.0)
        return self._engine(p * s[:, None])

    def G(self, rot):
        """3x4 map ω = G(p) ṗ (scalar-first columns reordered to the engine order)."""
        arr, single = self._rot(rot, "rot")
        p = self._to_quat(arr)
        G = 2.0 * np.concatenate([-p[:, 1:, None], p[:, 0, None, None] * EYE3 - hat(p[:, 1:])], axis=2)
        G = G if self.order == "wxyz" else G[:, :, self._back]
        return _checks.unbatch(G, single)

    def _omega_from_rates(self, rot, rot_dot):
        p, pd = self._to_quat(rot), self._to_quat(rot_dot)
        # ω = 2 (p0 ṗv - ṗ0 pv - pv x ṗv)   (vector part of 2 p* ⊗ ṗ)
        return 2.0 * (p[:, :1] * pd[:, 1:] - pd[:, :1] * p[:, 1:] - cross(p[:, 1:], pd[:, 1:]))

    def _rates_from_omega(self, rot, omega):
        p = self._to_quat(rot)
        # ṗ = ½ p ⊗ (0, ω)
        pd = 0.5 * np.concatenate([-dot(p[:, 1:], omega)[:, None],
                                   p[:, :1] * omega + cross(p[:, 1:], omega)], axis=1)
        return self._engine(pd)


class RotationVector(Parameterization):
    """Rotation vector ρ + position, ν = 6; α⁻¹ keeps ‖ρ‖ <= π."""

    nrot = 3
    name = "rotvec"

    def _to_quat(self, rot):
        return _q._from_rotvec(rot)

    def _from_quat(self, p, prev):
        rho = _q._to_rotvec(p)
        # at exactly a half-turn both ±ρ have norm π: take the one nearest prev
        tie = (norm(rho) > np.pi - 1e-12) & (dot(rho, prev) < 0.0)
        return np.where(tie[:, None], -rho, rho)

    def _omega_from_rates(self, rot, rot_dot):
        return _so3._dexp_apply(-rot, rot_dot)

    def _rates_from_omega(self, rot, omega):
        return _so3._dexp_inv_apply(-rot, omega)

    def _check_regular(self, rot):
        phi = norm(rot)
        k = np.round(phi / _TWO_PI)
        bad = (k > 0) & (np.abs(phi - k * _TWO_PI) < 1e-8)
        if bad.any():
            i = int(np.argmax(bad))
            raise ChartDomainError(f"rot: body {i} rotation vector has norm {phi[i]:.12g} = 2πk, where "
                                   "the rotation-vector rates are singular; re-wrap it to norm <= π.")


class TaitBryanXYZ(Parameterization):
    """Tait-Bryan angles (θ0, θ1, θ2), R = Rx(θ0) Ry(θ1) Rz(θ2) (Exudyn RotXYZ)."""

    nrot = 3
    name = "rxyz"
    #: below this abs(cos θ1) the split of θ0 + θ2 is taken from the previous θ0
    GIMBAL_TOL = 1e-9

    def _to_quat(self, rot):
        # p = px(θ0) ⊗ py(θ1) ⊗ pz(θ2), multiplied out (tests: scipy 'XYZ', Exudyn RotXYZ)
        h = 0.5 * rot
        c, s = np.cos(h), np.sin(h)
        ca, cb, cc, sa, sb, sc = c[:, 0], c[:, 1], c[:, 2], s[:, 0], s[:, 1], s[:, 2]
        cacb, sasb, sacb, casb = ca * cb, sa * sb, sa * cb, ca * sb
        return np.stack([cacb * cc - sasb * sc, sacb * cc + casb * sc,
                         casb * cc - sacb * sc, cacb * sc + sasb * cc], axis=1)

    def _from_quat(self, p, prev):
        p0, p1, p2, p3 = p[:, 0], p[:, 1], p[:, 2], p[:, 3]
        R00 = 1.0 - 2.0 * (p2 * p2 + p3 * p3)
        R01 = 2.0 * (p1 * p2 - p0 * p3)
        R02 = 2.0 * (p1 * p3 + p0 * p2)
        R12 = 2.0 * (p2 * p3 - p0 * p1)
        R22 = 1.0 - 2.0 * (p1 * p1 + p2 * p2)
        cb = np.hypot(R00, R01)                       # |cos θ1|, accurate near the lock
        a1 = np.arctan2(-R12, R22)
        b1 = np.arctan2(np.clip(R02, -1.0, 1.0), cb)
        c1 = np.arctan2(-R01, R00)
        # branch one (a, b, c), shifted by 2πk towards prev; where it lands far from
        # prev (passing the lock) try branch two (a + π, π - b, c + π) as well
        out = np.stack([a1, b1, c1], axis=1)
        out += _TWO_PI * np.round((prev - out) * (1.0 / _TWO_PI))
        far = ((out - prev) ** 2).sum(axis=1) > 0.25
        if far.any():
            pf, of = prev[far], out[far]
            two = np.stack([a1[far] + np.pi, np.pi - b1[far], c1[far] + np.pi], axis=1)
            two += _TWO_PI * np.round((pf - two) * (1.0 / _TWO_PI))
            nearer = ((two - pf) ** 2).sum(axis=1) < ((of - pf) ** 2).sum(axis=1)
            out[far] = np.where(nearer[:, None], two, of)
        lock = cb < self.GIMBAL_TOL
        if lock.any():
            out[lock] = self._at_lock(_q._to_matrix(p[lock]), out[lock], prev[lock])
        return out

    @staticmethod
    def _at_lock(R, ang, prev):
        """At gimbal lock only θ0 ± θ2 is defined: keep θ0 = previous θ0."""
        a, b = prev[:, 0], ang[:, 1]
        ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
        z, o = np.zeros_like(a), np.ones_like(a)
        Rx = np.stack([o, z, z, z, ca, -sa, z, sa, ca], axis=1).reshape(-1, 3, 3)
        Ry = np.stack([cb, z, sb, z, o, z, -sb, z, cb], axis=1).reshape(-1, 3, 3)
        M = np.swapaxes(Rx @ Ry, 1, 2) @ R
        c = np.arctan2(M[:, 1, 0], M[:, 0, 0])
        c = c + _TWO_PI * np.round((prev[:, 2] - c) / _TWO_PI)
        return np.stack([a, b, c], axis=1)

    def G(self, rot):
        """3x3 map ω = G(θ) θ̇ (Exudyn RotXYZ2GLocal)."""
        arr, single = self._rot(rot, "rot")
        c1, s1, c2, s2 = np.cos(arr[:, 1]), np.sin(arr[:, 1]), np.cos(arr[:, 2]), np.sin(arr[:, 2])
        z, o = np.zeros_like(c1), np.ones_like(c1)
        G = np.stack([c1 * c2, s2, z, -c1 * s2, c2, z, s1, z, o], axis=1).reshape(-1, 3, 3)
        return _checks.unbatch(G, single)

    def _omega_from_rates(self, rot, rd):
        c1, s1, c2, s2 = np.cos(rot[:, 1]), np.sin(rot[:, 1]), np.cos(rot[:, 2]), np.sin(rot[:, 2])
        return np.stack([c1 * c2 * rd[:, 0] + s2 * rd[:, 1],
                         -c1 * s2 * rd[:, 0] + c2 * rd[:, 1],
                         s1 * rd[:, 0] + rd[:, 2]], axis=1)

    def _rates_from_omega(self, rot, w):
        c1, s1, c2, s2 = np.cos(rot[:, 1]), np.sin(rot[:, 1]), np.cos(rot[:, 2]), np.sin(rot[:, 2])
        with np.errstate(divide="ignore", invalid="ignore"):
            a = (c2 * w[:, 0] - s2 * w[:, 1]) / c1
        return np.stack([a, s2 * w[:, 0] + c2 * w[:, 1], w[:, 2] - s1 * a], axis=1)

    def _check_regular(self, rot):
        bad = np.abs(np.cos(rot[:, 1])) < 1e-12
        if bad.any():
            i = int(np.argmax(bad))
            raise ChartDomainError(f"rot: body {i} is at gimbal lock (θ1 = {rot[i, 1]:.12g} = ±π/2), "
                                   "where Tait-Bryan rates do not exist; integrate through the "
                                   "bridge (lgt_bridge.tau) instead of θ̇ = G⁻¹ω.")


class TaitBryanZYX(TaitBryanXYZ):
    """Tait-Bryan angles (θ0, θ1, θ2), R = Rz(θ0) Ry(θ1) Rx(θ2) (Pinocchio's spherical-ZYX joint).

    Its transpose is an x-y-z set: R(θ0, θ1, θ2) = R_xyz(-θ2, -θ1, -θ0)ᵀ, so α and α⁻¹ are the
    x-y-z ones on the conjugate quaternion with the angles reversed and negated (an isometry
    of the angles: branch continuity and the gimbal lock at cos θ1 = 0 carry over; at the lock
    θ2 keeps its previous value)."""

    name = "rzyx"

    def _to_quat(self, rot):
        p = super()._to_quat(-rot[:, ::-1])
        return p * np.array([1.0, -1.0, -1.0, -1.0])

    def _from_quat(self, p, prev):
        conj = p * np.array([1.0, -1.0, -1.0, -1.0])
        return -super()._from_quat(conj, -prev[:, ::-1])[:, ::-1]

    def G(self, rot):
        """3x3 map ω = G(θ) θ̇ (body ω; Pinocchio's motion subspace of the ZYX joint)."""
        arr, single = self._rot(rot, "rot")
        s1, c1, s2, c2 = np.sin(arr[:, 1]), np.cos(arr[:, 1]), np.sin(arr[:, 2]), np.cos(arr[:, 2])
        z, o = np.zeros_like(c1), np.ones_like(c1)
        G = np.stack([-s1, z, o, s2 * c1, c2, z, c2 * c1, -s2, z], axis=1).reshape(-1, 3, 3)
        return _checks.unbatch(G, single)

    def _omega_from_rates(self, rot, rd):
        return np.einsum("nij,nj->ni", self.G(rot).reshape(-1, 3, 3), rd)

    def _rates_from_omega(self, rot, w):
        s1, c1, s2, c2 = np.sin(rot[:, 1]), np.cos(rot[:, 1]), np.sin(rot[:, 2]), np.cos(rot[:, 2])
        with np.errstate(divide="ignore", invalid="ignore"):
            a = (s2 * w[:, 1] + c2 * w[:, 2]) / c1
        return np.stack([a, c2 * w[:, 1] - s2 * w[:, 2], w[:, 0] + s1 * a], axis=1)


QUAT_WXYZ = Quaternion("wxyz")
QUAT_XYZW = Quaternion("xyzw")
ROTVEC = RotationVector()
RXYZ = TaitBryanXYZ()
RZYX = TaitBryanZYX()

_BY_NAME = {"quat": QUAT_WXYZ, "quat_wxyz": QUAT_WXYZ, "wxyz": QUAT_WXYZ, "ep": QUAT_WXYZ,
            "quat_xyzw": QUAT_XYZW, "xyzw": QUAT_XYZW,
            "rotvec": ROTVEC, "rotation_vector": ROTVEC,
            "rxyz": RXYZ, "tait_bryan_xyz": RXYZ, "tait_bryan": RXYZ,
            "rzyx": RZYX, "tait_bryan_zyx": RZYX}


def get(param):
    """A Parameterization from an instance or a name ('quat', 'quat_xyzw', 'rotvec', 'rxyz', 'rzyx')."""
    if isinstance(param, Parameterization):
        return param
    try:
        return _BY_NAME[str(param).lower()]
    except KeyError:
        raise InputError(f"unknown absolute parameterization {param!r}; use one of "
                         f"{sorted(set(_BY_NAME))} or a Parameterization instance.") from None
