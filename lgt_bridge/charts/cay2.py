"""The second-order Cayley chart (Wiener–Milenkovic parameters): ψ(X) = cay(X/2)².

The paper ("Remarks on coordinate maps") notes that a Cayley chart cannot describe large
rotations within a step and that the squared Cayley map mitigates this on SO(3) and SE(3).
With the Cayley map of :mod:`lgt_bridge.groups` (cay(c) = (I − ĉ)⁻¹(I + ĉ), angle 2·atan‖c‖),
cay2(x) = cay(x/2)² rotates by φ = 4·atan(‖x‖/2), so ‖x‖ = 2·tan(φ/4): the chart covers
every rotation below a full turn (Cayley: below a half-turn), and near the identity it
agrees with the Cayley chart to second order (log ψ(X) = 2X + O(‖X‖³), scale ½).

Derived here, each checked in tests against its definition (matrix products of cay,
finite differences of ψ, mpmath near the limit), with s = ‖x‖², a = x/2::

    quaternion   p = ((4 − s), 4x)/(4 + s)            (the square of (2, x)/√(4 + s); unit,
                                                        rational: no square root)
    SO(3)        ψ(x)  = I + 8/(4+s)² ((4 − s) x̃ + 4 x̃²)
                 ψ⁻¹(R) = 2 p_v/(1 + p₀)              (p₀ ≥ 0: the rotation of angle ≤ π)
                 dψ_x  = σ cay(a),  σ = 8/(4 + s)      (right-trivialized: (φ²)˙φ⁻² =
                 dψ_x⁻¹ = cay(a)ᵀ/σ                     (I + Ad_φ) φ̇φ⁻¹ with φ = cay(a),
                                                        I + cay(a) = 2 (I − ã)⁻¹)
    SE(3)        ψ(x, y) = (ψ(x), ½ (I + cay a)² y)   (cay(X/2) = (cay a, (I + cay a) y/2),
                                                        squared)
                 ψ⁻¹: y = ½ (I − ã)² t
                 dψ_X  = ½ (I + Ad_{cay(X/2)}) dcay_{X/2}
                 dψ_X⁻¹ = 2 dcay_{X/2}⁻¹ (I + Ad_{cay(X/2)})⁻¹,
                          (I + Ad_{(R₁,t₁)})⁻¹ (ω, v) = (P ω, P (v − t₁ × R₁ P ω)),  P = ½ (I − ã)
    SO(3)xR³     (ψ(x), y), dψ = diag(dψ_x, I)

One stage may rotate a body by at most 240° (‖x‖ ≤ 2·tan 60° = 2√3); a step of 1.2π per
step runs, where the Cayley chart must refuse it or shrink it.
"""
import math

import numpy as np

from ..groups import quaternion as _q
from ..groups import se3, so3
from ..groups._vec import EYE3, cross, dot, hat, matvec
from .base import Chart, GroupMaps, product_maps


def _so3_psi(x):
    s = dot(x, x)
    k = 8.0 / (4.0 + s) ** 2
    X = hat(x)
    return EYE3 + k[:, None, None] * ((4.0 - s)[:, None, None] * X + 4.0 * (X @ X))


def _so3_psi_inv(R):
    p = _q._from_matrix(R)
    p = np.where(p[:, :1] < 0.0, -p, p)
    return 2.0 * p[:, 1:] / (1.0 + p[:, :1])


def _so3_dpsi(x):
    return (8.0 / (4.0 + dot(x, x)))[:, None, None] * so3._cay(0.5 * x)


def _so3_dpsi_inv(x):
    return ((4.0 + dot(x, x)) / 8.0)[:, None, None] * np.swapaxes(so3._cay(0.5 * x), 1, 2)


def _half_rotate(x, v, sign=1.0):
    """cay(±x/2) v = v + (±4 x × v + 2 x × (x × v))/(4 + s)."""
    xv = cross(x, v)
    return v + (sign * 4.0 * xv + 2.0 * cross(x, xv)) / (4.0 + dot(x, x))[:, None]


def _so3_dpsi_apply(x, v):
    return (8.0 / (4.0 + dot(x, x)))[:, None] * _half_rotate(x, v)


def _so3_dpsi_inv_apply(x, v):
    return ((4.0 + dot(x, x)) / 8.0)[:, None] * _half_rotate(x, v, -1.0)


SO3_MAPS = GroupMaps(_so3_psi, _so3_psi_inv, _so3_dpsi, _so3_dpsi_inv, _so3_dpsi_apply,
                     _so3_dpsi_inv_apply)


def _translation(x, y):
    """½ (I + cay(x/2))² y."""
    w = y + _half_rotate(x, y)
    return 0.5 * (w + _half_rotate(x, w))


def _se3_psi(X):
    x, y = X[:, :3], X[:, 3:]
    return se3._assemble(_so3_psi(x), _translation(x, y))


def _se3_psi_inv(C):
    x = _so3_psi_inv(C[:, :3, :3])
    t = C[:, :3, 3]
    a = 0.5 * x
    u = t - cross(a, t)
    return np.concatenate([x, 0.5 * (u - cross(a, u))], axis=1)


def _one_plus_ad_inv(X, V):
    """(I + Ad_{cay(X/2)})⁻¹ V."""
    a = 0.5 * X[:, :3]
    C1 = se3._cay(0.5 * X)
    R1, t1 = C1[:, :3, :3], C1[:, :3, 3]
    w, v = V[:, :3], V[:, 3:]
    zw = 0.5 * (w - cross(a, w))
    u = v - cross(t1, matvec(R1, zw))
    return np.concatenate([zw, 0.5 * (u - cross(a, u))], axis=1)


def _se3_dpsi(X):
    return 0.5 * (np.eye(6) + se3._adjoint(se3._cay(0.5 * X))) @ se3._dcay(0.5 * X)


def _se3_dpsi_inv(X):
    A = np.eye(6) + se3._adjoint(se3._cay(0.5 * X))
    return 2.0 * se3._dcay_inv(0.5 * X) @ np.linalg.inv(A)


def _se3_dpsi_apply(X, V):
    D = se3._dcay_apply(0.5 * X, V)
    return 0.5 * (D + matvec(se3._adjoint(se3._cay(0.5 * X)), D))


def _se3_dpsi_inv_apply(X, V):
    return 2.0 * se3._dcay_inv_apply(0.5 * X, _one_plus_ad_inv(X, V))


def increment(x, y=None):
    """(quaternion of ψ(x) − 1 = (−2s, 4x)/(4 + s), ½ (I + cay(x/2))² y or None)."""
    s = dot(x, x)
    k = 1.0 / (4.0 + s)
    d = np.concatenate([(-2.0 * s * k)[:, None], (4.0 * k)[:, None] * x], axis=1)
    return d, None if y is None else _translation(x, y)


CAY2 = Chart(
    name="cay2", code=2, scale=0.5, max_angle=4.0 * math.pi / 3.0,
    angle=lambda n: 4.0 * np.arctan(0.5 * np.asarray(n, float)),
    coordinate=lambda phi: 2.0 * np.tan(0.25 * np.asarray(phi, float)),
    maps={"SE3": GroupMaps(_se3_psi, _se3_psi_inv, _se3_dpsi, _se3_dpsi_inv, _se3_dpsi_apply,
                           _se3_dpsi_inv_apply),
          "SO3xR3": product_maps(SO3_MAPS), "SO3": SO3_MAPS},
    increment=increment, title="second-order Cayley",
    describe="second-order Cayley map (Wiener-Milenkovic parameters); rational, a stage may "
             "rotate a body by up to 240°")
