"""Group maps against their defining identities: scipy.linalg.expm, the matrix
Cayley transform, quaternion products, and central finite differences."""
import numpy as np
import pytest
import scipy.linalg as sl
from hypothesis import given

from lgt_bridge import ChartDomainError
from lgt_bridge.groups import quaternion as quat
from lgt_bridge.groups import se3, so3, so3xr3

from strategies import rel, twist, unit_quat, vec3

TWO_PI = 2 * np.pi


def mcay(A):
    I = np.eye(len(A))
    return np.linalg.solve(I - A, I + A)


def se3_vee(M):
    return np.concatenate([[M[2, 1], M[0, 2], M[1, 0]], M[:3, 3]])


# ---------------------------------------------------------------- SO(3)
@given(vec3(TWO_PI - 1e-3))
def test_so3_exp_is_expm(x):
    assert np.abs(so3.exp(x) - sl.expm(so3.hat(x))).max() < 1e-13


@given(vec3(np.pi - 1e-7))
def test_so3_log_inverts_exp(x):
    assert np.abs(so3.log(so3.exp(x)) - x).max() < 1e-9 * max(1, 1 / (np.pi - np.linalg.norm(x)))


@given(vec3(np.pi, min_norm=np.pi))
def test_so3_log_at_exactly_pi(x):
    R = so3.exp(x)
    y = so3.log(R)
    assert abs(np.linalg.norm(y) - np.pi) < 1e-12
    assert np.abs(so3.exp(y) - R).max() < 1e-12


@given(vec3(30.0))
def test_so3_cay_is_matrix_cayley_and_inverts(c):
    R = so3.cay(c)
    assert np.abs(R - mcay(so3.hat(c))).max() < 1e-12
    assert rel(so3.cay_inv(R), c) < 1e-12 * max(1, np.linalg.norm(c) ** 2)


def test_so3_cay_inv_at_half_turn_raises():
    with pytest.raises(ChartDomainError, match="half-turn"):
        so3.cay_inv(so3.exp(np.array([0.0, np.pi, 0.0])))


def _fd_right(psi, x, v, h=1e-6):
    """vee( D_x ψ(v) ψ(x)⁻¹ ) by central differences on matrices."""
    M = (psi(x + h * v) - psi(x - h * v)) / (2 * h) @ np.linalg.inv(psi(x))
    return M


@given(vec3(TWO_PI - 0.3), vec3(1.0, min_norm=0.1))
def test_so3_dexp_is_fd_right_trivialized(x, v):
    M = _fd_right(so3.exp, x, v)
    assert np.abs(so3.vee(0.5 * (M - M.T)) - so3.dexp(x) @ v).max() < 1e-7
    assert np.abs(so3.dexp_apply(x, v) - so3.dexp(x) @ v).max() < 1e-13


@given(vec3(20.0), vec3(1.0, min_norm=0.1))
def test_so3_dcay_is_fd_right_trivialized(c, v):
    M = _fd_right(so3.cay, c, v, h=1e-7)
    ref = so3.vee(0.5 * (M - M.T))
    assert np.abs(ref - so3.dcay(c) @ v).max() < 1e-6 * max(1, np.linalg.norm(ref))
    assert np.abs(so3.dcay_apply(c, v) - so3.dcay(c) @ v).max() < 1e-13


@given(vec3(TWO_PI - 0.01), vec3(5.0))
def test_so3_inverse_differentials(x, v):
    cond = np.linalg.cond(so3.dexp(x))
    assert np.abs(so3.dexp(x) @ so3.dexp_inv(x) - np.eye(3)).max() < 1e-14 * cond * 10
    assert np.abs(so3.dexp_inv_apply(x, v) - so3.dexp_inv(x) @ v).max() < 1e-12 * cond * (1 + np.linalg.norm(v))
    assert np.abs(so3.dcay(x) @ so3.dcay_inv(x) - np.eye(3)).max() < 1e-13 * (1 + x @ x)
    assert np.abs(so3.dcay_inv_apply(x, v) - so3.dcay_inv(x) @ v).max() < 1e-12 * (1 + x @ x) * (1 + np.linalg.norm(v))


@given(vec3(3.0), vec3(3.0))
def test_so3_bch(x1, x2):
    x = so3.bch(x1, x2)
    assert np.abs(sl.expm(so3.hat(x)) - sl.expm(so3.hat(x1)) @ sl.expm(so3.hat(x2))).max() < 1e-12


def test_so3_bch_is_continuous_past_pi():
    # composing two rotations about one axis just adds angles, also beyond π
    n = np.array([0.0, 0.6, 0.8])
    assert np.allclose(so3.bch(2.0 * n, 1.9 * n), 3.9 * n, atol=1e-14)


# ---------------------------------------------------------------- quaternions
@given(unit_quat(), unit_quat())
def test_quaternion_product_is_matrix_product(p, q):
    assert np.abs(quat.to_matrix(quat.mul(p, q)) - quat.to_matrix(p) @ quat.to_matrix(q)).max() < 1e-14
    assert np.abs(quat.mul(p, quat.conj(p)) - [1, 0, 0, 0]).max() < 1e-15
    v = np.array([0.3, -1.0, 2.0])
    assert np.abs(quat.rotate(p, v) - quat.to_matrix(p) @ v).max() < 1e-14


@given(unit_quat())
def test_quaternion_matrix_round_trip_every_branch(p):
    back = quat.from_matrix(quat.to_matrix(p))
    assert min(np.abs(back - p).max(), np.abs(back + p).max()) < 1e-14


@pytest.mark.parametrize("axis", range(3))
def test_quaternion_from_matrix_at_half_turns(axis):
    x = np.zeros(3)
    x[axis] = np.pi
    p = quat.from_matrix(so3.exp(x))
    assert abs(p[0]) < 1e-15 and abs(abs(p[1 + axis]) - 1) < 1e-15


@given(vec3(TWO_PI))
def test_quaternion_rotvec(x):
    p = quat.from_rotvec(x)
    assert abs(np.linalg.norm(p) - 1) < 1e-15
    assert np.abs(quat.to_matrix(p) - sl.expm(so3.hat(x))).max() < 1e-13
    y = quat.to_rotvec(p)
    assert np.linalg.norm(y) <= np.pi + 1e-15
    assert np.abs(so3.exp(y) - so3.exp(x)).max() < 1e-13


@given(vec3(50.0))
def test_quaternion_gibbs(c):
    p = quat.from_gibbs(c)
    assert np.abs(quat.to_matrix(p) - so3.cay(c)).max() < 1e-13
    assert rel(quat.to_gibbs(p), c) < 1e-14 * (1 + c @ c)


def test_quaternion_gibbs_half_turn_raises():
    with pytest.raises(ChartDomainError, match="body 1"):
        quat.to_gibbs(np.array([[1.0, 0, 0, 0], [0.0, 0, 1, 0]]))


# ---------------------------------------------------------------- SE(3)
@given(twist(TWO_PI - 1e-3))
def test_se3_exp_is_expm_and_log_inverts(X):
    C = se3.exp(X)
    assert np.abs(C - sl.expm(se3.hat6(X))).max() < 1e-12 * (1 + np.abs(X).max())
    if np.linalg.norm(X[:3]) < np.pi - 1e-6:
        assert np.abs(se3.log(C) - X).max() < 1e-9


@given(twist(20.0))
def test_se3_cay_is_matrix_cayley_and_inverts(X):
    C = se3.cay(X)
    assert np.abs(C - mcay(se3.hat6(X))).max() < 1e-11 * (1 + np.abs(C).max())
    assert rel(se3.cay_inv(C), X) < 1e-11 * (1 + X[:3] @ X[:3])


def _se3_fd(psi, X, V, h=1e-6):
    M = (psi(X + h * V) - psi(X - h * V)) / (2 * h) @ np.linalg.inv(psi(X))
    return se3_vee(M)


@given(twist(TWO_PI - 0.3), twist(1.0, 1.0))
def test_se3_dexp_is_fd_right_trivialized(X, V):
    ref = _se3_fd(se3.exp, X, V)
    assert np.abs(ref - se3.dexp(X) @ V).max() < 1e-6 * (1 + np.abs(X).max())
    assert np.abs(se3.dexp_apply(X, V) - se3.dexp(X) @ V).max() < 1e-12 * (1 + np.abs(X).max())


@given(twist(10.0), twist(1.0, 1.0))
def test_se3_dcay_is_fd_right_trivialized(X, V):
    ref = _se3_fd(se3.cay, X, V, h=1e-7)
    assert np.abs(ref - se3.dcay(X) @ V).max() < 1e-6 * (1 + np.abs(ref).max())
    assert np.abs(se3.dcay_apply(X, V) - se3.dcay(X) @ V).max() < 1e-11 * (1 + np.abs(ref).max())


@given(twist(TWO_PI - 0.01), twist(2.0, 2.0))
def test_se3_inverse_differentials(X, V):
    s = 1 + np.abs(X).max() ** 2
    assert np.abs(se3.dexp(X) @ se3.dexp_inv(X) - np.eye(6)).max() < 1e-12 * s * np.linalg.cond(se3.dexp(X))
    assert np.abs(se3.dcay(X) @ se3.dcay_inv(X) - np.eye(6)).max() < 1e-12 * s
    assert np.abs(se3.dexp_inv_apply(X, V) - se3.dexp_inv(X) @ V).max() < 1e-10 * s * np.linalg.cond(se3.dexp(X))
    assert np.abs(se3.dcay_inv_apply(X, V) - se3.dcay_inv(X) @ V).max() < 1e-12 * s * (1 + np.abs(V).max())


@given(twist(3.0), twist(3.0), twist(3.0))
def test_se3_group_axioms(X1, X2, X3):
    A, B, C = se3.exp(X1), se3.exp(X2), se3.exp(X3)
    assert np.abs(se3.mul(se3.mul(A, B), C) - se3.mul(A, se3.mul(B, C))).max() < 1e-12
    assert np.abs(se3.mul(A, se3.inv(A)) - np.eye(4)).max() < 1e-13
    assert np.abs(se3.mul(A, se3.exp(np.zeros(6))) - A).max() == 0.0
    # adjoint: A exp(X) A⁻¹ = exp(Ad_A X)
    assert np.abs(A @ se3.exp(X2) @ se3.inv(A) - se3.exp(se3.adjoint(A) @ X2)).max() < 1e-11


# ---------------------------------------------------------------- SO(3)xR³
@given(twist(TWO_PI - 1e-3))
def test_so3xr3_exp_log_cay(X):
    C = so3xr3.exp(X)
    assert np.abs(C[:3, :3] - sl.expm(so3.hat(X[:3]))).max() < 1e-13 and np.all(C[:3, 3] == X[3:])
    if np.linalg.norm(X[:3]) < np.pi - 1e-6:
        assert np.abs(so3xr3.log(C) - X).max() < 1e-9
    D = so3xr3.cay(X)
    assert np.abs(D[:3, :3] - mcay(so3.hat(X[:3]))).max() < 1e-12
    assert rel(so3xr3.cay_inv(D), X) < 1e-12 * (1 + X[:3] @ X[:3])


def _dp_fd(psi, X, V, h=1e-6):
    """Right-trivialized derivative with the direct-product law."""
    P, M = psi(X + h * V), psi(X - h * V)
    C = psi(X)
    W = (P[:3, :3] - M[:3, :3]) / (2 * h) @ C[:3, :3].T
    return np.concatenate([[W[2, 1], W[0, 2], W[1, 0]], (P[:3, 3] - M[:3, 3]) / (2 * h)])


@pytest.mark.parametrize("chart", ["exp", "cay"])
@given(X=twist(3.0), V=twist(1.0, 1.0))
def test_so3xr3_differentials(chart, X, V):
    psi = getattr(so3xr3, chart)
    d, dinv = getattr(so3xr3, f"d{chart}"), getattr(so3xr3, f"d{chart}_inv")
    assert np.abs(_dp_fd(psi, X, V) - d(X) @ V).max() < 1e-6 * (1 + np.abs(X).max() ** 2)
    assert np.abs(d(X) @ dinv(X) - np.eye(6)).max() < 1e-12 * (1 + np.abs(X).max() ** 2) * np.linalg.cond(d(X))
    assert np.abs(getattr(so3xr3, f"d{chart}_inv_apply")(X, V) - dinv(X) @ V).max() < 1e-11 * (1 + np.abs(X).max() ** 2)
    assert np.abs(getattr(so3xr3, f"d{chart}_apply")(X, V) - d(X) @ V).max() < 1e-11 * (1 + np.abs(X).max() ** 2)


@given(twist(3.0), twist(3.0), twist(3.0))
def test_so3xr3_group_axioms(X1, X2, X3):
    A, B, C = so3xr3.exp(X1), so3xr3.exp(X2), so3xr3.exp(X3)
    assert np.abs(so3xr3.mul(so3xr3.mul(A, B), C) - so3xr3.mul(A, so3xr3.mul(B, C))).max() < 1e-12
    assert np.abs(so3xr3.mul(A, so3xr3.inv(A)) - np.eye(4)).max() < 1e-13
    lhs = so3xr3.mul(so3xr3.mul(A, so3xr3.exp(X2)), so3xr3.inv(A))
    assert np.abs(lhs - so3xr3.exp(so3xr3.adjoint(A) @ X2)).max() < 1e-11


# ---------------------------------------------------------------- batching
def test_batched_equals_per_body(rng):
    X = rng.normal(size=(50, 6)) * 2
    V = rng.normal(size=(50, 6))
    for mod in (se3, so3xr3):
        for name in ("exp", "cay", "dexp", "dexp_inv", "dcay", "dcay_inv"):
            f = getattr(mod, name)
            assert np.array_equal(f(X), np.stack([f(x) for x in X]))
        for name in ("dexp_inv_apply", "dcay_inv_apply"):
            f = getattr(mod, name)
            assert np.allclose(f(X, V), np.stack([f(x, v) for x, v in zip(X, V)]), rtol=0, atol=1e-14)


@pytest.mark.parametrize("n", [1, 5, 33, 1000])
def test_cross_product_in_both_regimes(n, rng):
    from lgt_bridge.groups._vec import cross
    a, b = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    assert np.abs(cross(a, b) - np.cross(a, b)).max() < 1e-15
