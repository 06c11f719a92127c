"""Unchecked batched group math on (N, ...) float64 arrays, for adapters and kernels'
numpy references: the same functions the core uses internally, without input checks
(the checked single-body/batched API is in :mod:`so3`, :mod:`se3`, :mod:`quaternion`).

Quaternions are scalar first ``(p0, p1, p2, p3)``."""
from ._vec import cross, dot, hat, matvec, norm, outer, vee
from .quaternion import _conj as conj
from .quaternion import _mul as mul
from .quaternion import _rotate as rotate
from .quaternion import _to_matrix as to_matrix

__all__ = ["cross", "dot", "hat", "matvec", "norm", "outer", "vee", "conj", "mul", "rotate",
           "to_matrix"]
