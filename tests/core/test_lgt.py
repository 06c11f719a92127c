"""LGT maps τ for all twelve pairings against α⁻¹(α(q)·ψ(X)) built from 4x4
matrices (scipy expm / matrix Cayley / the group law), and the local
kinematics against finite differences of the reconstructed motion."""
import itertools

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.spatial.transform import Rotation

from lgt_bridge import InputError, LGTError, lgt, params
from lgt_bridge.groups import se3

PARAMS = [params.QUAT_WXYZ, params.QUAT_XYZW, params.ROTVEC, params.RXYZ, params.RZYX]
PAIRINGS = list(itertools.product(PARAMS, lgt.GROUPS, lgt.CHARTS))
IDS = [f"{p.name}-{g}-{c}" for p, g, c in PAIRINGS]


def matrix_of(param, q):
    rot = q[3:]
    if param.name == "quat_wxyz":
        R = Rotation.from_quat(rot, scalar_first=True).as_matrix()
    elif param.name == "quat_xyzw":
        R = Rotation.from_quat(rot).as_matrix()
    elif param.name == "rotvec":
        R = Rotation.from_rotvec(rot).as_matrix()
    elif param.name == "rzyx":
        R = Rotation.from_euler("ZYX", rot).as_matrix()
    else:
        R = Rotation.from_euler("XYZ", rot).as_matrix()
    C = np.eye(4)
    C[:3, :3], C[:3, 3] = R, q[:3]
    return C


def psi_matrix(chart, X):
    """ψ(X) from its definition: the matrix exponential, the matrix Cayley transform
    (I - X^)⁻¹(I + X^), and the second-order Cayley map as the square of cay(X/2)."""
    if chart == "exp":
        return sl.expm(se3.hat6(X))
    if chart == "cay2":
        C = psi_matrix("cay", 0.5 * np.asarray(X))
        return C @ C
    A = se3.hat6(X)
    return np.linalg.solve(np.eye(4) - A, np.eye(4) + A)


def reference(param, group, chart, q, X):
    Ck = matrix_of(param, q)
    P = psi_matrix(chart, X)
    if group == "SE3":
        return Ck @ P
    # direct product: the chart increment's translation is X[3:] itself (ψ = (ψ_rot, y))
    C = np.eye(4)
    C[:3, :3] = Ck[:3, :3] @ P[:3, :3]
    C[:3, 3] = Ck[:3, 3] + X[3:]
    return C


def random_q(param, rng):
    r = rng.normal(size=3)
    if param.nrot == 4:
        p = rng.normal(size=4)
        return np.concatenate([r, p / np.linalg.norm(p)])
    rot = rng.uniform(-3, 3, size=3)
    if param is params.ROTVEC:
        rot *= min(1.0, 3.0 / np.linalg.norm(rot))
    if param in (params.RXYZ, params.RZYX):
        rot[1] = rng.uniform(-1.4, 1.4)
    return np.concatenate([r, rot])


@pytest.mark.parametrize("param,group,chart", PAIRINGS, ids=IDS)
def test_tau_is_alpha_inv_of_group_product(param, group, chart, rng):
    for k in range(40):
        q = random_q(param, rng)
        scale = [1e-9, 1e-3, 0.3, 1.5, 3.0][k % 5]
        X = np.concatenate([rng.normal(size=3) * scale, rng.normal(size=3)])
        out = lgt.tau(q, X, param, group, chart)
        ref = reference(param, group, chart, q, X)
        got = matrix_of(param, out)
        assert np.abs(got - ref).max() < 1e-12 * (1 + np.abs(ref).max())


@pytest.mark.parametrize("param,group,chart", PAIRINGS, ids=IDS)
def test_tau_batched_equals_per_body_and_identity_at_zero(param, group, chart, rng):
    Q = np.stack([random_q(param, rng) for _ in range(20)])
    X = rng.normal(size=(20, 6))
    out = lgt.tau(Q, X, param, group, chart)
    assert np.allclose(out, np.stack([lgt.tau(q, x, param, group, chart) for q, x in zip(Q, X)]),
                       rtol=0, atol=1e-14)
    # X = 0 is the identity; Tait-Bryan angles come back through atan2 (a few ulps of π)
    assert np.allclose(lgt.tau(Q, np.zeros((20, 6)), param, group, chart), Q, rtol=0, atol=8e-15)


def body_twist_fd(param, group, chart, q, X, Xdot, h=1e-6):
    """The twist of C(t) = C_k ψ(X + t Ẋ) at t = 0, by central differences on
    the reference matrices: (ω body, Rᵀṙ) on SE(3), (ω body, ṙ) on SO(3)xR³."""
    Cp = reference(param, group, chart, q, X + h * Xdot)
    Cm = reference(param, group, chart, q, X - h * Xdot)
    C = reference(param, group, chart, q, X)
    dC = (Cp - Cm) / (2 * h)
    R = C[:3, :3]
    W = R.T @ dC[:3, :3]
    w = np.array([W[2, 1], W[0, 2], W[1, 0]])
    v = R.T @ dC[:3, 3] if group == "SE3" else dC[:3, 3]
    return np.concatenate([w, v])


@pytest.mark.parametrize("group,chart", list(itertools.product(lgt.GROUPS, lgt.CHARTS)))
def test_local_kinematics_reproduce_the_twist(group, chart, rng):
    for _ in range(30):
        q = random_q(params.QUAT_WXYZ, rng)
        X = rng.normal(size=6) * 0.8
        V = rng.normal(size=6)
        Xdot = lgt.local_rates(X, V, group, chart)
        assert np.abs(body_twist_fd(params.QUAT_WXYZ, group, chart, q, X, Xdot) - V).max() < 1e-7
        assert np.abs(lgt.LGT("quat", group, chart).twist(X[None], Xdot[None])[0] - V).max() < 1e-12


@pytest.mark.parametrize("param,group,chart", PAIRINGS, ids=IDS)
def test_tau_rates_match_the_parameterization_kinematics(param, group, chart, rng):
    """d/dt τ(q_k, X(t)) with Ẋ = dψ⁻¹_{-X}(V) equals the absolute rates of V."""
    for _ in range(10):
        q = random_q(param, rng)
        X = rng.normal(size=6) * 0.3
        Vmodel = rng.normal(size=6)                               # (ω body, ṙ inertial)
        qX = lgt.tau(q, X, param, group, chart)
        Vg = lgt.to_group_twist(qX, Vmodel, param, group)
        assert np.abs(lgt.from_group_twist(qX, Vg, param, group) - Vmodel).max() < 1e-14
        Xdot = lgt.local_rates(X, Vg, group, chart)
        h = 1e-6
        qdot = (lgt.tau(q, X + h * Xdot, param, group, chart) - lgt.tau(q, X - h * Xdot, param, group, chart)) / (2 * h)
        assert np.abs(qdot[:3] - Vmodel[3:]).max() < 1e-7
        assert np.abs(param.omega_from_rates(qX[3:], qdot[3:]) - Vmodel[:3]).max() < 1e-7


def test_bad_input_is_rejected_with_library_errors():
    q = np.array([[0, 0, 0, 1.0, 0, 0, 0], [1, 2, 3, 1.0, 0, 0, 0]])
    X = np.zeros((2, 6))
    bad = q.copy()
    bad[1, 2] = np.nan
    with pytest.raises(InputError, match=r"q: body 1 has a non-finite"):
        lgt.tau(bad, X)
    bad = q.copy()
    bad[1, 3] = 1.00001
    with pytest.raises(InputError, match=r"body 1 quaternion .* \(off by 1e-05"):
        lgt.tau(bad, X)
    lgt.tau(np.array([0, 0, 0, 1 + 5e-7, 0, 0, 0]), np.zeros(6))     # within 1e-6: accepted
    with pytest.raises(InputError, match=r"X: got shape \(2, 5\)"):
        lgt.tau(q, np.zeros((2, 5)))
    Xi = X.copy()
    Xi[0, 4] = np.inf
    with pytest.raises(InputError, match="X: body 0"):
        lgt.tau(q, Xi)
    with pytest.raises(InputError, match="q has 2 bodies but X has 3"):
        lgt.tau(q, np.zeros((3, 6)))
    with pytest.raises(InputError, match="unknown group 'SE2'"):
        lgt.tau(q, X, group="SE2")
    with pytest.raises(InputError, match="unknown chart 'log'"):
        lgt.tau(q, X, chart="log")
    with pytest.raises(InputError, match="got shape"):
        lgt.tau(q[:, :6], X, "quat")
    with pytest.raises(LGTError):
        se3.exp(np.ones(5))
    with pytest.raises(InputError, match="C: body 0 is not a rotation matrix"):
        se3.log(np.diag([2.0, 1, 1, 1]))
    assert issubclass(InputError, ValueError) and issubclass(InputError, LGTError)


def test_cayley_tau_at_half_turn_has_no_singularity_but_inverse_raises():
    # the Cayley chart maps all of R³ (never reaches a half-turn); its inverse at a half-turn raises
    from lgt_bridge import ChartDomainError
    out = lgt.tau(np.array([0, 0, 0, 1.0, 0, 0, 0]), np.array([1e8, 0, 0, 0, 0, 0]), "quat", "SE3", "cay")
    assert abs(abs(out[4]) - 1) < 1e-15
    with pytest.raises(ChartDomainError):
        se3.cay_inv(se3.exp(np.array([np.pi, 0, 0, 0, 0, 0])))


@pytest.mark.parametrize("param", PARAMS, ids=lambda p: p.name)
@pytest.mark.parametrize("chart", lgt.CHARTS)
def test_rotation_only_lgt_is_the_rotation_part(param, chart, rng):
    """Rotation-only bodies (spherical joints): τ and rates equal the rotation part of
    the SO(3)xR³ pairing (whose rotation is independent of the translation)."""
    full, rot = lgt.LGT(param, "SO3xR3", chart), lgt.RotationLGT(param, chart)
    Q = np.stack([random_q(param, rng) for _ in range(10)])
    X = rng.normal(size=(10, 6)) * 0.7
    W = rng.normal(size=(10, 6))
    rows, p = rot.tau_pose(rot.base(Q[:, 3:]), X[:, :3])
    ref_rows, ref_p = full.tau_pose(full.base(Q), X)
    assert np.allclose(rows, ref_rows[:, 3:], rtol=0, atol=1e-14) and np.allclose(p, ref_p, rtol=0, atol=1e-15)
    assert np.allclose(rot.rates(X[:, :3], W[:, :3]), full.rates(X, W)[:, :3], rtol=0, atol=1e-14)
    assert np.allclose(rot.twist(X[:, :3], rot.rates(X[:, :3], W[:, :3])), W[:, :3], rtol=0, atol=1e-12)
