"""SE(3) with twists ordered (ω, v), elements as 4x4 homogeneous matrices.

::

    exp X  = [exp x~, dexp_x y; 0, 1]                      (paper eq. expSE31)
    dexp_X⁻¹ = [dexp_x⁻¹, 0; B(y), dexp_x⁻¹]               (eq. dexpInvSE3)
        B(y) = -½ y~ + d(φ) (x~ y~ + y~ x~) + e(φ) (xᵀy) x~²
    dexp_X = [D, 0; -D B D, D],  D = dexp_x                 (block inverse of the above)
    cay X  = (I - X^)⁻¹ (I + X^) = [cay c~, (I + cay c~) d; 0, 1]   (eq. CaySE31)
    dcay_X⁻¹ = [dcay_c⁻¹, 0; ½ (c~ - I) d~, ½ (I - c~)]      (eq. dCayInvSE3, docs/paper_corrections.md)
    dcay_X = [σ (I + c~), 0; 2 (I - c~)⁻¹ e~, 2 (I - c~)⁻¹],  e = (I + c~)⁻¹ d
"""
import numpy as np

from .. import _series
from .._checks import export_group6, public
from . import so3
from ._vec import EYE3, cross, dot, hat, matvec, norm

_LAST_ROW = np.array([0.0, 0.0, 0.0, 1.0])


def _assemble(R, r):
    C = np.zeros((len(R), 4, 4))
    C[:, :3, :3] = R
    C[:, :3, 3] = r
    C[:, 3] = _LAST_ROW
    return C


def _blocks(A, B, Cm, D):
    return np.concatenate([np.concatenate([A, B], axis=2), np.concatenate([Cm, D], axis=2)], axis=1)


def _exp(X):
    x, y = X[:, :3], X[:, 3:]
    return _assemble(so3._exp(x), so3._dexp_apply(x, y))


def _log(C):
    x = so3._log(C[:, :3, :3])
    return np.concatenate([x, so3._dexp_inv_apply(x, C[:, :3, 3])], axis=1)


def _cay(X):
    c, d = X[:, :3], X[:, 3:]
    R = so3._cay(c)
    return _assemble(R, d + matvec(R, d))


def _cay_inv(C):
    c = so3._cay_inv(C[:, :3, :3])
    t = C[:, :3, 3]
    return np.concatenate([c, 0.5 * (t - cross(c, t))], axis=1)


def _B(x, y):
    phi = norm(x)
    X, Y = hat(x), hat(y)
    return (-0.5 * Y + _series.d(phi)[:, None, None] * (X @ Y + Y @ X)
            + (_series.e(phi) * dot(x, y))[:, None, None] * (X @ X))


def _B_apply(x, y, w):
    phi = norm(x)
    xw = cross(x, w)
    return (-0.5 * cross(y, w) + _series.d(phi)[:, None] * (cross(x, cross(y, w)) + cross(y, xw))
            + (_series.e(phi) * dot(x, y))[:, None] * cross(x, xw))


def _dexp(X):
    x, y = X[:, :3], X[:, 3:]
    D = so3._dexp(x)
    Z = np.zeros_like(D)
    return _blocks(D, Z, -D @ _B(x, y) @ D, D)


def _dexp_inv(X):
    x, y = X[:, :3], X[:, 3:]
    Di = so3._dexp_inv(x)
    return _blocks(Di, np.zeros_like(Di), _B(x, y), Di)


def _dcay(X):
    c, d = X[:, :3], X[:, 3:]
    sigma = 2.0 / (1.0 + dot(c, c))
    top = so3._dcay(c)
    e = so3._dcay_inv_apply(c, d) * sigma[:, None]     # (I + c~)⁻¹ d = σ/2 (I - c~ + ccᵀ) d
    Linv2 = 2.0 * np.linalg.inv(EYE3 - hat(c))            # 2 (I - c~)⁻¹
    return _blocks(top, np.zeros_like(top), Linv2 @ hat(e), Linv2)


def _dcay_inv(X):
    c, d = X[:, :3], X[:, 3:]
    C = hat(c)
    return _blocks(so3._dcay_inv(c), np.zeros_like(C), 0.5 * (C - EYE3) @ hat(d), 0.5 * (EYE3 - C))


def _dexp_apply(X, V):
    x, y = X[:, :3], X[:, 3:]
    w, u = V[:, :3], V[:, 3:]
    Dw = so3._dexp_apply(x, w)
    return np.concatenate([Dw, so3._dexp_apply(x, u - _B_apply(x, y, Dw))], axis=1)


def _dexp_inv_apply(X, V):
    """[dexp_x⁻¹ w; B(y) w + dexp_x⁻¹ u], coefficients computed once."""
    x, y = X[:, :3], X[:, 3:]
    w, u = V[:, :3], V[:, 3:]
    phi = norm(x)
    dd, ee = _series.d(phi)[:, None], _series.e(phi)[:, None]
    xw, xu, yw = cross(x, w), cross(x, u), cross(y, w)
    xxw = cross(x, xw)
    top = w - 0.5 * xw + dd * xxw
    bot = (u - 0.5 * (xu + yw) + dd * (cross(x, xu) + cross(x, yw) + cross(y, xw))
           + (ee * dot(x, y)[:, None]) * xxw)
    return np.concatenate([top, bot], axis=1)


def _dcay_apply(X, V):
    c, d = X[:, :3], X[:, 3:]
    w, u = V[:, :3], V[:, 3:]
    sigma = (2.0 / (1.0 + dot(c, c)))[:, None]
    e = sigma * so3._dcay_inv_apply(c, d)
    v = u + cross(e, w)
    # 2 (I - c~)⁻¹ v = σ (v + c x v + (c·v) c)
    return np.concatenate([sigma * (w + cross(c, w)),
                           sigma * (v + cross(c, v) + dot(c, v)[:, None] * c)], axis=1)


def _dcay_inv_apply(X, V):
    c, d = X[:, :3], X[:, 3:]
    w, u = V[:, :3], V[:, 3:]
    z = u - cross(d, w)
    return np.concatenate([so3._dcay_inv_apply(c, w), 0.5 * (z - cross(c, z))], axis=1)


def _mul(C1, C2):
    return C1 @ C2


def _inv(C):
    Rt = np.swapaxes(C[:, :3, :3], 1, 2)
    return _assemble(Rt, -matvec(Rt, C[:, :3, 3]))


def _adjoint(C):
    R = C[:, :3, :3]
    return _blocks(R, np.zeros_like(R), hat(C[:, :3, 3]) @ R, R)


def _hat(X):
    """4x4 matrix of a twist (ω, v): [ω~, v; 0, 0]."""
    M = np.zeros((len(X), 4, 4))
    M[:, :3, :3] = hat(X[:, :3])
    M[:, :3, 3] = X[:, 3:]
    return M


hat6 = public(("X", (6,)))(_hat)
export_group6(globals())
