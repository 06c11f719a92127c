"""Unit quaternions, scalar first: p = (p0, p1, p2, p3), as in the paper and
Exudyn's Euler parameters. Product (paper eq. Qmult), rotation matrix
R = I + 2 (p0 p~ + p~^2) (eq. QuatR), exp/log <-> rotation vector, Gibbs vector.
"""
import numpy as np

from .. import _series
from .._checks import public
from ..errors import ChartDomainError
from ._vec import EYE3, cross, dot, hat, norm

#: |p0| below this (relative to |p|) is a half-turn: no Gibbs vector exists.
HALF_TURN_TOL = 1e-12


def _mul(p, q):
    p0, pv, q0, qv = p[:, :1], p[:, 1:], q[:, :1], q[:, 1:]
    return np.concatenate([p0 * q0 - dot(pv, qv)[:, None],
                           p0 * qv + q0 * pv + cross(pv, qv)], axis=1)


def _conj(p):
    return p * np.array([1.0, -1.0, -1.0, -1.0])


def _rotate(p, v):
    """R(p) v without forming R: v + 2 p0 (p x v) + 2 p x (p x v)."""
    pv = p[:, 1:]
    t = 2.0 * cross(pv, v)
    return v + p[:, :1] * t + cross(pv, t)


def _to_matrix(p):
    P = hat(p[:, 1:])
    return EYE3 + 2.0 * (p[:, 0, None, None] * P + P @ P)


def _from_matrix(R):
    """Shepperd's method: pick the largest of 4 p0², 4 p1², 4 p2², 4 p3²."""
    n = len(R)
    tr = np.trace(R, axis1=1, axis2=2)
    diag = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], axis=1)
    k = np.argmax(diag, axis=1)
    p = np.empty((n, 4))
    # 4 p_k^2 = 1 + 2 R_kk - tr  (k = 1..3),   4 p0^2 = 1 + tr
    w = R[:, 2, 1] - R[:, 1, 2]
    x = R[:, 0, 2] - R[:, 2, 0]
    y = R[:, 1, 0] - R[:, 0, 1]
    a01 = R[:, 0, 1] + R[:, 1, 0]
    a02 = R[:, 0, 2] + R[:, 2, 0]
    a12 = R[:, 1, 2] + R[:, 2, 1]
    big = np.sqrt(np.maximum(1.0 + 2.0 * diag[np.arange(n), k] - tr, 0.0)) * 2.0  # = 4 |p_k|
    big[k == 0] = 2.0 * np.sqrt(np.maximum(1.0 + tr[k == 0], 0.0))
    cols = {0: (big / 4.0, w / big, x / big, y / big),
            1: (w / big, big / 4.0, a01 / big, a02 / big),
            2: (x / big, a01 / big, big / 4.0, a12 / big),
            3: (y / big, a02 / big, a12 / big, big / 4.0)}
    for j in range(4):
        m = k == j
        if m.any():
            p[m] = np.stack([c[m] for c in cols[j]], axis=1)
    p *= np.where(p[:, :1] < 0.0, -1.0, 1.0)
    return p


def _from_rotvec(x):
    """exp(0, x/2) = (cos(φ/2), ½ sinc(φ/2) x) (paper eq. Sp1exp)."""
    h = 0.5 * norm(x)
    return np.concatenate([np.cos(h)[:, None], (0.5 * _series.sinc(h))[:, None] * x], axis=1)


def _to_rotvec(p):
    """Rotation vector of norm in [0, π] (the sign of p is chosen with p0 >= 0)."""
    p = p * np.where(p[:, :1] < 0.0, -1.0, 1.0)
    s = norm(p[:, 1:])
    with np.errstate(invalid="ignore", divide="ignore"):
        f = np.where(s > 0.0, 2.0 * np.arctan2(s, p[:, 0]) / s, 2.0 / p[:, 0])
    return f[:, None] * p[:, 1:]


def _from_gibbs(c):
    """p0 = sqrt(σ/2), p = sqrt(σ/2) c with σ = 2/(1+|c|²) (docs/paper_corrections.md: QuatRodrigues)."""
    p0 = 1.0 / np.sqrt(1.0 + dot(c, c))
    return np.concatenate([p0[:, None], p0[:, None] * c], axis=1)


def _gibbs_minus_one(c):
    """_from_gibbs(c) - (1, 0, 0, 0) without cancellation: p0 - 1 = -|c|²/(s(1+s)), s = √(1+|c|²)."""
    c2 = dot(c, c)
    s = np.sqrt(1.0 + c2)
    return np.concatenate([(-c2 / (s * (1.0 + s)))[:, None], c / s[:, None]], axis=1)


def _rotvec_minus_one(x, phi=None, sh=None):
    """_from_rotvec(x) - (1, 0, 0, 0) without cancellation: cos(φ/2) - 1 = -2 sin²(φ/4).
    ``phi`` = |x| and ``sh`` = sinc(φ/2) may be passed when already computed."""
    phi = np.sqrt(dot(x, x)) if phi is None else phi
    sh = _series.sinc(0.5 * phi) if sh is None else sh
    return np.concatenate([(-2.0 * np.sin(0.25 * phi) ** 2)[:, None], (0.5 * sh)[:, None] * x], axis=1)


def _mul_near_identity(p, d):
    """p ⊗ (1 + d) computed as p + p ⊗ d. With d = (chart quaternion - 1) formed without
    cancellation, the rounding of the product no longer carries a bias of |ψ(x)| - 1
    into the norm: over 10⁶ repeated steps ‖p‖ - 1 stays ~1e-14 instead of ~1e-12."""
    return p + _mul(p, d)


def _to_gibbs(p, name="p"):
    """Gibbs vector c = p/p0 = tan(φ/2) n; undefined at a half-turn (p0 = 0)."""
    p0 = p[:, 0]
    bad = np.abs(p0) <= HALF_TURN_TOL * norm(p[:, 1:])
    if bad.any():
        i = int(np.argmax(bad))
        raise ChartDomainError(
            f"{name}: body {i} is a half-turn (p0 = {p0[i]:.3g}); the Gibbs vector / Cayley chart "
            "does not exist there. Use the exp chart or a smaller rotation increment.")
    return p[:, 1:] / p0[:, None]


def _from_axis_angle(axis, angle):
    n = axis / norm(axis)[:, None]
    return _from_rotvec(n * angle[:, None])


mul = public(("p", (4,)), ("q", (4,)))(_mul)
conj = public(("p", (4,)))(_conj)
rotate = public(("p", (4,)), ("v", (3,)))(_rotate)
to_matrix = public(("p", (4,)))(_to_matrix)
from_matrix = public(("R", (3, 3)))(_from_matrix)
from_rotvec = public(("x", (3,)))(_from_rotvec)
to_rotvec = public(("p", (4,)))(_to_rotvec)
from_gibbs = public(("c", (3,)))(_from_gibbs)
to_gibbs = public(("p", (4,)))(_to_gibbs)

__all__ = ["mul", "conj", "rotate", "to_matrix", "from_matrix", "from_rotvec", "to_rotvec",
           "from_gibbs", "to_gibbs"]
