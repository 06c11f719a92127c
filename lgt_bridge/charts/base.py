"""What a chart is: ψ of every group, its differentials, its domain, its kernel code.

A chart ψ maps local coordinates X (rotation part x first) to a group element near the
identity, with ψ(-X) = ψ(X)⁻¹ and ψ(X) = I + X/scale + O(X²) (``scale``: the exp chart 1,
the Cayley charts ½). Every chart gives, for each group G of :data:`GROUPS`, the numpy
maps on (N, n) batches (:class:`GroupMaps`): ψ and ψ⁻¹, the right-trivialized
differential dψ_X ((D_X ψ)(δ) ψ(X)⁻¹ = (dψ_X δ)^) and its inverse, as matrices and as
matrix-free products. τ (``lgt.py``) and the integrators use only these and
:meth:`Chart.increment`; the compiled kernels branch on :attr:`Chart.code`
(``kernels/charts.py``), and tests hold the two equal.
"""
import math
from dataclasses import dataclass, field

import numpy as np

#: the groups every chart covers: SE(3), the direct product SO(3)xR³, and SO(3) alone
#: (rotation-only bodies: spherical joints)
GROUPS = ("SE3", "SO3xR3", "SO3")


@dataclass(frozen=True)
class GroupMaps:
    """ψ, ψ⁻¹, dψ, dψ⁻¹ (matrices) and dψ·v, dψ⁻¹·v of one chart on one group."""

    psi: object
    psi_inv: object
    dpsi: object
    dpsi_inv: object
    dpsi_apply: object
    dpsi_inv_apply: object


@dataclass(frozen=True)
class Chart:
    """One chart. ``max_angle``: the largest rotation (rad) one stage of a step may make in
    it before the chart degenerates (inf: no limit; a Cayley chart's coordinates grow
    without bound towards its singular rotation). ``angle(n)``/``coordinate(φ)``: the
    rotation angle of rotation coordinates of norm n, and back."""

    name: str
    code: int
    scale: float
    max_angle: float
    angle: object
    coordinate: object
    maps: dict = field(repr=False)
    increment: object = field(repr=False)
    title: str = ""
    describe: str = ""

    @property
    def limit(self):
        """Norm of the rotation coordinates at ``max_angle`` (inf: unbounded)."""
        return math.inf if math.isinf(self.max_angle) else float(self.coordinate(self.max_angle))

    @property
    def bounded(self):
        return not math.isinf(self.max_angle)

    def on(self, group):
        """The :class:`GroupMaps` of this chart on ``group`` ("SE3", "SO3xR3", "SO3")."""
        return self.maps[group]


def product_maps(so3):
    """The maps of the direct product SO(3)xR³ from a chart's maps on SO(3):
    ψ(x, y) = (ψ(x), y), dψ = diag(dψ_x, I)."""
    from ..groups.se3 import _assemble, _blocks
    eye = np.eye(3)

    def diag(A):
        Z = np.zeros_like(A)
        return _blocks(A, Z, Z, np.broadcast_to(eye, A.shape))

    def apply(rot):
        return lambda X, V: np.concatenate([rot(X[:, :3], V[:, :3]), V[:, 3:]], axis=1)

    return GroupMaps(
        psi=lambda X: _assemble(so3.psi(X[:, :3]), X[:, 3:]),
        psi_inv=lambda C: np.concatenate([so3.psi_inv(C[:, :3, :3]), C[:, :3, 3]], axis=1),
        dpsi=lambda X: diag(so3.dpsi(X[:, :3])),
        dpsi_inv=lambda X: diag(so3.dpsi_inv(X[:, :3])),
        dpsi_apply=apply(so3.dpsi_apply),
        dpsi_inv_apply=apply(so3.dpsi_inv_apply))
