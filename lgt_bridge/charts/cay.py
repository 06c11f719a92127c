"""The Cayley chart: ψ(c) = (I − ĉ)⁻¹(I + ĉ), ‖c‖ = tan(φ/2) (Gibbs vectors); rational,
no trigonometric functions, singular at a half-turn, so one stage may rotate a body by at
most 90° (‖c‖ ≤ 1)."""
import math

import numpy as np

from ..groups import quaternion as _q
from ..groups import se3, so3, so3xr3
from .base import Chart, GroupMaps


def _maps(m, inv):
    return GroupMaps(m._cay, inv, m._dcay, m._dcay_inv, m._dcay_apply, m._dcay_inv_apply)


def increment(x, y=None):
    """(quaternion of cay(x) − 1, (I + cay x) y or None)."""
    d = _q._gibbs_minus_one(x)
    if y is None:
        return d, None
    dp = d.copy()
    dp[:, 0] += 1.0
    return d, y + _q._rotate(dp, y)


CAY = Chart(
    name="cay", code=1, scale=0.5, max_angle=0.5 * math.pi,
    angle=lambda n: 2.0 * np.arctan(n), coordinate=lambda phi: np.tan(0.5 * np.asarray(phi, float)),
    maps={"SE3": _maps(se3, se3._cay_inv), "SO3xR3": _maps(so3xr3, so3xr3._cay_inv),
          "SO3": _maps(so3, so3._cay_inv)},
    increment=increment, title="Cayley",
    describe="Cayley map (Gibbs vectors); rational, a stage may rotate a body by at most 90°")
