"""Engine-free reference scenes in pure numpy: each models only what it needs.

* :func:`free_body` — torque-free rigid body (frame at the centre of mass);
* :func:`heavy_top` — the benchmark heavy top, either rotating about a fixed
  pivot (the body frame at the pivot, unconstrained rotation) or as a free body
  at its centre of mass held by a spherical joint (constrained);
* :func:`chain` — N bodies connected by spherical joints, hanging from a ground joint;
* :func:`pendulum` — a compound pendulum released from an angle (pivoted, or on a
  spherical joint), with its equivalent length for the elliptic-integral period.

All take ``param`` = "quat" (Exudyn Euler parameters), "quat_xyzw", "rotvec"
or "rxyz" for the absolute rotation coordinates.

The model they are built on, :class:`RigidBodySystem`, is in :mod:`.system`; the
scenes are in :mod:`.catalogue`.
"""
from .. import params as _params  # noqa: F401  (reached as scenes._params by tests)
from .catalogue import (HEAVY_TOP, _rot_coords, chain, free_bodies, free_body, heavy_top, pendulum,
                        principal_inertia, top_and_free_bodies)
from .system import GRAVITY, RigidBodySystem

__all__ = ["GRAVITY", "HEAVY_TOP", "RigidBodySystem", "chain", "free_bodies", "free_body", "heavy_top",
           "pendulum", "principal_inertia", "top_and_free_bodies"]
