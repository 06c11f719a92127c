"""SO(3)xR³, the direct product, with twists (ω body, ṙ inertial).

Elements are stored as 4x4 arrays [R, r; 0, 1] like SE(3), but multiply with
the direct-product law (R1, r1)(R2, r2) = (R1 R2, r1 + r2); the translation of
a chart increment is therefore resolved in the inertial frame (docs/paper_corrections.md, rprime2)::

    exp X = (exp x~, y),  cay X = (cay c~, d),  dψ_X = diag(dψ_x, I).
"""
import numpy as np

from .._checks import export_group6
from . import so3
from .se3 import _assemble, _blocks

_EYE = np.eye(3)


def _exp(X):
    return _assemble(so3._exp(X[:, :3]), X[:, 3:])


def _log(C):
    return np.concatenate([so3._log(C[:, :3, :3]), C[:, :3, 3]], axis=1)


def _cay(X):
    return _assemble(so3._cay(X[:, :3]), X[:, 3:])


def _cay_inv(C):
    return np.concatenate([so3._cay_inv(C[:, :3, :3]), C[:, :3, 3]], axis=1)


def _diag(A):
    Z = np.zeros_like(A)
    return _blocks(A, Z, Z, np.broadcast_to(_EYE, A.shape))


def _dexp(X):
    return _diag(so3._dexp(X[:, :3]))


def _dexp_inv(X):
    return _diag(so3._dexp_inv(X[:, :3]))


def _dcay(X):
    return _diag(so3._dcay(X[:, :3]))


def _dcay_inv(X):
    return _diag(so3._dcay_inv(X[:, :3]))


def _apply(rot):
    def fn(X, V):
        return np.concatenate([rot(X[:, :3], V[:, :3]), V[:, 3:]], axis=1)
    return fn


_dexp_apply = _apply(so3._dexp_apply)
_dexp_inv_apply = _apply(so3._dexp_inv_apply)
_dcay_apply = _apply(so3._dcay_apply)
_dcay_inv_apply = _apply(so3._dcay_inv_apply)


def _mul(C1, C2):
    return _assemble(C1[:, :3, :3] @ C2[:, :3, :3], C1[:, :3, 3] + C2[:, :3, 3])


def _inv(C):
    return _assemble(np.swapaxes(C[:, :3, :3], 1, 2), -C[:, :3, 3])


def _adjoint(C):
    return _diag(C[:, :3, :3])


export_group6(globals())
