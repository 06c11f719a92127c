"""The exponential chart: ψ = exp (rotation vectors; no domain limit within a step)."""
import math

import numpy as np

from .. import _series
from ..groups import quaternion as _q
from ..groups import se3, so3, so3xr3
from ..groups._vec import cross, norm
from .base import Chart, GroupMaps


def _maps(m, log):
    return GroupMaps(m._exp, log, m._dexp, m._dexp_inv, m._dexp_apply, m._dexp_inv_apply)


def increment(x, y=None):
    """(quaternion of exp(x) − 1, dexp_x y or None). φ and sinc(φ/2) serve both."""
    phi = norm(x)
    sh = _series.sinc(0.5 * phi)
    d = _q._rotvec_minus_one(x, phi, sh)
    if y is None:
        return d, None
    xy = cross(x, y)
    return d, y + (0.5 * sh * sh)[:, None] * xy + _series.c3(phi)[:, None] * cross(x, xy)


EXP = Chart(
    name="exp", code=0, scale=1.0, max_angle=math.inf,
    angle=lambda n: np.asarray(n, float), coordinate=lambda phi: np.asarray(phi, float),
    maps={"SE3": _maps(se3, se3._log), "SO3xR3": _maps(so3xr3, so3xr3._log), "SO3": _maps(so3, so3._log)},
    increment=increment, title="exponential",
    describe="exponential coordinates (rotation vector); exact geodesics, no limit within a step")
