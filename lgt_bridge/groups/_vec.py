"""Batched 3-vector helpers on (N, 3) arrays (faster than np.cross for small N)."""
import numpy as np

EYE3 = np.eye(3)
# Levi-Civita symbol as a (9, 3) matrix: (a ⊗ b).reshape(9) @ _EPS9 = a × b
_EPS = np.zeros((3, 3, 3))
_EPS[0, 1, 2] = _EPS[1, 2, 0] = _EPS[2, 0, 1] = 1.0
_EPS[0, 2, 1] = _EPS[2, 1, 0] = _EPS[1, 0, 2] = -1.0
_EPS9 = _EPS.transpose(1, 2, 0).reshape(9, 3).copy()
_SMALL = 32


def cross(a, b):
    """Row-wise a × b. Few bodies: one outer product and a matmul (fewest numpy
    calls); many bodies: column arithmetic (no fancy-index copies). See
    benchmarks/bench_lgt.py for the figures behind the switch."""
    if len(a) <= _SMALL:
        return (a[:, :, None] * b[:, None, :]).reshape(-1, 9) @ _EPS9
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    np.subtract(a1 * b2, a2 * b1, out=out[:, 0])
    np.subtract(a2 * b0, a0 * b2, out=out[:, 1])
    np.subtract(a0 * b1, a1 * b0, out=out[:, 2])
    return out


def dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def norm(a):
    return np.sqrt(dot(a, a))


def hat(x):
    """(N, 3) -> (N, 3, 3) skew-symmetric matrices with hat(x) @ y = x × y."""
    z = np.zeros(len(x))
    x0, x1, x2 = x[:, 0], x[:, 1], x[:, 2]
    return np.stack([z, -x2, x1, x2, z, -x0, -x1, x0, z], axis=1).reshape(-1, 3, 3)


def vee(X):
    return np.stack([X[:, 2, 1], X[:, 0, 2], X[:, 1, 0]], axis=1)


def matvec(A, v):
    return np.einsum("nij,nj->ni", A, v)


def outer(a, b):
    return a[:, :, None] * b[:, None, :]
