"""Scalar rotation helpers for the kernels: the series coefficients of ``_series``, the
quaternion product and rotation, and α / α⁻¹ of every parameterization, one body at a
time on plain floats (numba keeps them in registers; tuples, no arrays).

Parameterization codes (see :data:`PARAM_CODES`): 0 quaternion wxyz, 1 quaternion xyzw,
2 rotation vector, 3 Tait-Bryan xyz, 4 Tait-Bryan zyx. The reference implementations are
``lgt_bridge.params`` and ``lgt_bridge.groups.quaternion``; tests hold them equal.
"""
import math

import numpy as np
from numba import njit

from .. import _series
from . import guard_cache

guard_cache(__file__)

PARAM_CODES = {"quat_wxyz": 0, "quat_xyzw": 1, "rotvec": 2, "rxyz": 3, "rzyx": 4}

_SINC = np.array(_series._SINC)
_C3 = np.array(_series._C3)
_D = np.array(_series._D)
_E = np.array(_series._E)
_L_SINC = np.array(_series._L_SINC)
_L_C3 = np.array(_series._L_C3)
_L_D = np.array(_series._L_D)
_L_E = np.array(_series._L_E)
_HCOS = np.array(_series._HCOS)
_L_HCOS = np.array(_series._L_HCOS)
SERIES_MAX = _series.SERIES_MAX
TWO_PI = 2.0 * math.pi
GIMBAL_TOL = 1e-9


@njit(cache=True, error_model="numpy")
def _horner(coef, lim, p2):
    n = 1
    while p2 > lim[n - 1]:
        n += 1
    out = 0.0
    for k in range(n - 1, -1, -1):
        out = out * p2 + coef[k]
    return out


@njit(cache=True, error_model="numpy")
def sinc(phi):
    if phi >= SERIES_MAX:
        return math.sin(phi) / phi
    return _horner(_SINC, _L_SINC, phi * phi)


@njit(cache=True, error_model="numpy")
def c3(phi):
    if phi >= SERIES_MAX:
        return (phi - math.sin(phi)) / phi ** 3
    return _horner(_C3, _L_C3, phi * phi)


@njit(cache=True, error_model="numpy")
def dser(phi):
    if phi >= SERIES_MAX:
        h = 0.5 * phi
        return (1.0 - h * math.cos(h) / math.sin(h)) / (phi * phi)
    return _horner(_D, _L_D, phi * phi)


@njit(cache=True, error_model="numpy")
def eser(phi):
    if phi >= SERIES_MAX:
        h = 0.5 * phi
        s, c = math.sin(h), math.cos(h)
        return ((h / s) ** 2 + h * c / s - 2.0) / phi ** 4
    return _horner(_E, _L_E, phi * phi)


@njit(cache=True, error_model="numpy")
def hcos(phi):
    if phi >= SERIES_MAX:
        s = math.sin(0.25 * phi) / phi
        return 2.0 * s * s
    return _horner(_HCOS, _L_HCOS, phi * phi)


@njit(cache=True, error_model="numpy")
def cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, error_model="numpy")
def qmul(a0, a1, a2, a3, b0, b1, b2, b3):
    return (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + b0 * a1 + a2 * b3 - a3 * b2,
            a0 * b2 + b0 * a2 + a3 * b1 - a1 * b3,
            a0 * b3 + b0 * a3 + a1 * b2 - a2 * b1)


@njit(cache=True, error_model="numpy")
def rotate(p0, p1, p2, p3, v0, v1, v2):
    """R(p) v = v + 2 p0 (p x v) + 2 p x (p x v)  (quaternion._rotate)."""
    t0, t1, t2 = cross(p1, p2, p3, v0, v1, v2)
    t0, t1, t2 = 2.0 * t0, 2.0 * t1, 2.0 * t2
    u0, u1, u2 = cross(p1, p2, p3, t0, t1, t2)
    return v0 + p0 * t0 + u0, v1 + p0 * t1 + u1, v2 + p0 * t2 + u2


@njit(cache=True, error_model="numpy")
def rotvec_minus_one(x0, x1, x2):
    """exp chart quaternion - 1 without cancellation; also returns φ and sinc(φ/2)."""
    phi2 = x0 * x0 + x1 * x1 + x2 * x2
    phi = math.sqrt(phi2)
    sh = sinc(0.5 * phi)
    return -phi2 * hcos(phi), 0.5 * sh * x0, 0.5 * sh * x1, 0.5 * sh * x2, phi, sh


@njit(cache=True, error_model="numpy")
def gibbs_minus_one(c0, c1, c2):
    c2n = c0 * c0 + c1 * c1 + c2 * c2
    s = math.sqrt(1.0 + c2n)
    return -c2n / (s * (1.0 + s)), c0 / s, c1 / s, c2 / s


@njit(cache=True, error_model="numpy")
def to_quat(code, r0, r1, r2, r3):
    """Scalar-first unit quaternion of rotation coordinates (r0, r1, r2[, r3])."""
    if code == 0:
        return r0, r1, r2, r3
    if code == 1:
        return r3, r0, r1, r2
    if code == 2:
        h = 0.5 * math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
        f = 0.5 * sinc(h)
        return math.cos(h), f * r0, f * r1, f * r2
    if code == 4:           # z-y-x: the conjugate of the x-y-z set (-r2, -r1, -r0)
        p0, p1, p2, p3 = _xyz_quat(-r2, -r1, -r0)
        return p0, -p1, -p2, -p3
    return _xyz_quat(r0, r1, r2)


@njit(cache=True, error_model="numpy")
def _xyz_quat(r0, r1, r2):
    h0, h1, h2 = 0.5 * r0, 0.5 * r1, 0.5 * r2
    ca, cb, cc = math.cos(h0), math.cos(h1), math.cos(h2)
    sa, sb, sc = math.sin(h0), math.sin(h1), math.sin(h2)
    cacb, sasb, sacb, casb = ca * cb, sa * sb, sa * cb, ca * sb
    return (cacb * cc - sasb * sc, sacb * cc + casb * sc,
            casb * cc - sacb * sc, cacb * sc + sasb * cc)


@njit(cache=True, error_model="numpy")
def _shift(a, prev):
    return a + TWO_PI * np.rint((prev - a) * (1.0 / TWO_PI))


@njit(cache=True, error_model="numpy")
def from_quat(code, p0, p1, p2, p3, q0, q1, q2, q3):
    """α⁻¹ on the rotation: the coordinates of p (4-tuple; the last unused for 3-parameter
    sets) on the branch continuous with the previous coordinates (q0, q1, q2[, q3])
    (params.*._from_quat)."""
    if code == 0:
        s = -1.0 if p0 * q0 + p1 * q1 + p2 * q2 + p3 * q3 < 0.0 else 1.0
        return s * p0, s * p1, s * p2, s * p3
    if code == 1:
        s = -1.0 if p0 * q3 + p1 * q0 + p2 * q1 + p3 * q2 < 0.0 else 1.0
        return s * p1, s * p2, s * p3, s * p0
    if code == 2:
        if p0 < 0.0:
            p0, p1, p2, p3 = -p0, -p1, -p2, -p3
        sn = math.sqrt(p1 * p1 + p2 * p2 + p3 * p3)
        f = 2.0 * math.atan2(sn, p0) / sn if sn > 0.0 else 2.0 / p0
        r0, r1, r2 = f * p1, f * p2, f * p3
        if (math.sqrt(r0 * r0 + r1 * r1 + r2 * r2) > math.pi - 1e-12
                and r0 * q0 + r1 * q1 + r2 * q2 < 0.0):
            r0, r1, r2 = -r0, -r1, -r2
        return r0, r1, r2, 0.0
    if code == 4:           # z-y-x: the x-y-z angles of the conjugate, reversed and negated
        o0, o1, o2 = _xyz_angles(p0, -p1, -p2, -p3, -q2, -q1, -q0)
        return -o2, -o1, -o0, 0.0
    o0, o1, o2 = _xyz_angles(p0, p1, p2, p3, q0, q1, q2)
    return o0, o1, o2, 0.0


@njit(cache=True, error_model="numpy")
def _xyz_angles(p0, p1, p2, p3, q0, q1, q2):
    """x-y-z angles of p on the branch continuous with (q0, q1, q2) (TaitBryanXYZ._from_quat)."""
    R00 = 1.0 - 2.0 * (p2 * p2 + p3 * p3)
    R01 = 2.0 * (p1 * p2 - p0 * p3)
    R02 = 2.0 * (p1 * p3 + p0 * p2)
    R12 = 2.0 * (p2 * p3 - p0 * p1)
    R22 = 1.0 - 2.0 * (p1 * p1 + p2 * p2)
    cb = math.hypot(R00, R01)
    a1 = math.atan2(-R12, R22)
    b1 = math.atan2(min(max(R02, -1.0), 1.0), cb)
    c1 = math.atan2(-R01, R00)
    o0, o1, o2 = _shift(a1, q0), _shift(b1, q1), _shift(c1, q2)
    dist = (o0 - q0) ** 2 + (o1 - q1) ** 2 + (o2 - q2) ** 2
    if dist > 0.25:
        t0, t1, t2 = _shift(a1 + math.pi, q0), _shift(math.pi - b1, q1), _shift(c1 + math.pi, q2)
        if (t0 - q0) ** 2 + (t1 - q1) ** 2 + (t2 - q2) ** 2 < dist:
            o0, o1, o2 = t0, t1, t2
    if cb < GIMBAL_TOL:
        # at the lock only θ0 ± θ2 is defined: keep θ0 = previous θ0 (TaitBryanXYZ._at_lock)
        a, b = q0, o1
        ca, sa, cbb, sbb = math.cos(a), math.sin(a), math.cos(b), math.sin(b)
        R10 = 2.0 * (p1 * p2 + p0 * p3)
        R20 = 2.0 * (p1 * p3 - p0 * p2)
        M00 = cbb * R00 + sa * sbb * R10 - ca * sbb * R20
        M10 = ca * R10 + sa * R20
        o0, o1, o2 = a, b, _shift(math.atan2(M10, M00), q2)
    return o0, o1, o2
