"""SO(3): exp/log, Cayley map and inverse, right-trivialized differentials, BCH.

Conventions (paper section 3, corrected in docs/paper_corrections.md)::

    exp x~   = I + sinc φ x~ + ½ β x~²                       β = sinc²(φ/2)
    dexp_x   = I + ½ β x~ + c3(φ) x~²                          c3 = (1 - sinc φ)/φ²
    dexp_x⁻¹ = I - ½ x~ + d(φ) x~²                             d = (1 - γ)/φ², γ = sinc φ/β
    cay c~   = I + σ (c~ + c~²) = (I - c~)⁻¹ (I + c~)          σ = 2/(1+|c|²)
    dcay_c   = σ (I + c~),   dcay_c⁻¹ = I/σ + ½ (c~² - c~)

Right-trivialized: (D_x ψ)(y) ψ(x)⁻¹ = (dψ_x y)~. Body angular velocity of
R(t) = R_k ψ(x(t)) is ω = dψ_{-x} ẋ.
"""
import numpy as np

from .. import _series
from .._checks import public
from . import quaternion as _q
from ._vec import EYE3, cross, dot, hat, norm, outer, vee

_hat, _vee = hat, vee


def _sq(x):
    """x~² = x xᵀ - |x|² I."""
    return outer(x, x) - dot(x, x)[:, None, None] * EYE3


def _exp(x):
    phi = norm(x)
    return (EYE3 + _series.sinc(phi)[:, None, None] * hat(x)
            + (0.5 * _series.beta(phi))[:, None, None] * _sq(x))


def _log(R):
    """Rotation vector with angle in [0, π] (exact at π via Shepperd's quaternion)."""
    return _q._to_rotvec(_q._from_matrix(R))


def _cay(c):
    sigma = 2.0 / (1.0 + dot(c, c))
    return EYE3 + sigma[:, None, None] * (hat(c) + _sq(c))


def _cay_inv(R):
    """Gibbs vector; ChartDomainError at a half-turn."""
    return _q._to_gibbs(_q._from_matrix(R), "R")


def _dexp(x):
    phi = norm(x)
    return EYE3 + (0.5 * _series.beta(phi))[:, None, None] * hat(x) + _series.c3(phi)[:, None, None] * _sq(x)


def _dexp_inv(x):
    return EYE3 - 0.5 * hat(x) + _series.d(norm(x))[:, None, None] * _sq(x)


def _dcay(c):
    sigma = 2.0 / (1.0 + dot(c, c))
    return sigma[:, None, None] * (EYE3 + hat(c))


def _dcay_inv(c):
    return (0.5 * (1.0 + dot(c, c)))[:, None, None] * EYE3 + 0.5 * (_sq(c) - hat(c))


# matrix-free products with a vector (the hot path of the integrators)
def _dexp_apply(x, v):
    phi = norm(x)
    xv = cross(x, v)
    return v + (0.5 * _series.beta(phi))[:, None] * xv + _series.c3(phi)[:, None] * cross(x, xv)


def _dexp_inv_apply(x, v):
    xv = cross(x, v)
    return v - 0.5 * xv + _series.d(norm(x))[:, None] * cross(x, xv)


def _dcay_apply(c, v):
    return (2.0 / (1.0 + dot(c, c)))[:, None] * (v + cross(c, v))


def _dcay_inv_apply(c, v):
    # ½ (I - c~ + c cᵀ) v
    return 0.5 * (v - cross(c, v) + dot(c, v)[:, None] * c)


def _bch(x1, x2):
    """Closed-form BCH on SO(3): exp(x~) = exp(x~1) exp(x~2) (paper eq. BCHSO3).

    Written through the half-angle (quaternion) form; the returned angle lies
    in [0, 2π], continuous in x1 and x2 (no re-wrapping).
    """
    p = _q._mul(_q._from_rotvec(x1), _q._from_rotvec(x2))
    s = norm(p[:, 1:])
    with np.errstate(invalid="ignore", divide="ignore"):
        f = np.where(s > 0.0, 2.0 * np.arctan2(s, p[:, 0]) / s, 2.0 / p[:, 0])
    return f[:, None] * p[:, 1:]


hat = public(("x", (3,)))(_hat)
vee = public(("X", (3, 3)))(_vee)
exp = public(("x", (3,)))(_exp)
log = public(("R", (3, 3)))(_log)
cay = public(("c", (3,)))(_cay)
cay_inv = public(("R", (3, 3)))(_cay_inv)
dexp = public(("x", (3,)))(_dexp)
dexp_inv = public(("x", (3,)))(_dexp_inv)
dcay = public(("c", (3,)))(_dcay)
dcay_inv = public(("c", (3,)))(_dcay_inv)
dexp_apply = public(("x", (3,)), ("v", (3,)))(_dexp_apply)
dexp_inv_apply = public(("x", (3,)), ("v", (3,)))(_dexp_inv_apply)
dcay_apply = public(("c", (3,)), ("v", (3,)))(_dcay_apply)
dcay_inv_apply = public(("c", (3,)), ("v", (3,)))(_dcay_inv_apply)
bch = public(("x1", (3,)), ("x2", (3,)))(_bch)
