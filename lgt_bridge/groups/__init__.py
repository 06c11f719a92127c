"""Lie group kernel: SO(3), unit quaternions, SE(3), SO(3)xR^3.

Every public function takes one element or a batch over bodies along axis 0.
The underscore-prefixed functions of each module are the same maths on
validated (N, ...) float64 batches; the rest of the package calls those.
"""
from . import batch, quaternion, se3, so3, so3xr3

__all__ = ["so3", "quaternion", "se3", "so3xr3", "batch"]
