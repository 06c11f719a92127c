"""Batched 3-vector helpers on (N, 3) arrays (faster than np.cross for small N)."""
import numpy as np

_I1 = [1, 2, 0]
_I2 = [2, 0, 1]
EYE3 = np.eye(3)


def cross(a, b):
    return a[:, _I1] * b[:, _I2] - a[:, _I2] * b[:, _I1]


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
