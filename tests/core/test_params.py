"""Absolute parameterizations α: against scipy's Rotation and Exudyn's RotXYZ,
their kinematic maps against finite differences, and branch continuity."""
import numpy as np
import pytest
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from scipy.spatial.transform import Rotation

from lgt_bridge import ChartDomainError, InputError, params
from lgt_bridge.groups import so3


angles = hnp.arrays(np.float64, 3, elements=st.floats(-7, 7))


def scipy_matrix(param, rot):
    if param.name == "quat_wxyz":
        return Rotation.from_quat(rot, scalar_first=True).as_matrix()
    if param.name == "quat_xyzw":
        return Rotation.from_quat(rot).as_matrix()
    if param.name == "rotvec":
        return Rotation.from_rotvec(rot).as_matrix()
    if param.name == "rzyx":
        return Rotation.from_euler("ZYX", rot).as_matrix()  # intrinsic z-y'-x'' (Pinocchio's ZYX joint)
    return Rotation.from_euler("XYZ", rot).as_matrix()      # intrinsic x-y'-z''


def sample_rot(param, rng):
    if param.nrot == 4:
        p = rng.normal(size=4)
        return p / np.linalg.norm(p)
    return rng.uniform(-3, 3, size=3)


ALL = [params.QUAT_WXYZ, params.QUAT_XYZW, params.ROTVEC, params.RXYZ, params.RZYX]


@pytest.mark.parametrize("param", ALL, ids=lambda p: p.name)
def test_alpha_matches_scipy(param, rng):
    for _ in range(50):
        rot = sample_rot(param, rng)
        r = rng.normal(size=3)
        C = param.alpha(np.concatenate([r, rot]))
        assert np.abs(C[:3, :3] - scipy_matrix(param, rot)).max() < 1e-14
        assert np.all(C[:3, 3] == r)


def test_rxyz_matches_exudyn():
    rbu = pytest.importorskip("exudyn.rigidBodyUtilities")
    rng = np.random.default_rng(1)
    for _ in range(50):
        a = rng.uniform(-4, 4, size=3)
        R = params.RXYZ.alpha(np.concatenate([np.zeros(3), a]))[:3, :3]
        assert np.abs(R - rbu.RotXYZ2RotationMatrix(a)).max() < 1e-14
        assert np.abs(params.RXYZ.G(a) - rbu.RotXYZ2GLocal(a)).max() < 1e-14


def test_quaternion_G_matches_exudyn():
    rbu = pytest.importorskip("exudyn.rigidBodyUtilities")
    p = np.array([0.3, -0.5, 0.1, 0.8])
    p /= np.linalg.norm(p)
    assert np.abs(params.QUAT_WXYZ.G(p) - rbu.EulerParameters2GLocal(p)).max() < 1e-15


@pytest.mark.parametrize("param", ALL, ids=lambda p: p.name)
def test_alpha_inv_round_trip(param, rng):
    for _ in range(50):
        q = np.concatenate([rng.normal(size=3), sample_rot(param, rng)])
        if param is params.ROTVEC:
            q[3:] *= min(1.0, 3.0 / np.linalg.norm(q[3:]))
        back = param.alpha_inv(param.alpha(q), prev=q)
        assert np.abs(back - q).max() < 1e-12


@pytest.mark.parametrize("param", ALL, ids=lambda p: p.name)
def test_kinematic_maps_against_finite_differences(param, rng):
    for _ in range(30):
        rot = sample_rot(param, rng)
        if param in (params.RXYZ, params.RZYX):
            rot[1] = np.clip(rot[1], -1.3, 1.3)
        omega = rng.normal(size=3)
        rd = param.rates_from_omega(rot, omega)
        if param.nrot == 4:
            assert abs(rd @ rot) < 1e-15          # tangent to the unit sphere
        h = 1e-6
        Rp = scipy_matrix(param, rot + h * rd if param.nrot == 3 else (rot + h * rd) / np.linalg.norm(rot + h * rd))
        Rm = scipy_matrix(param, rot - h * rd if param.nrot == 3 else (rot - h * rd) / np.linalg.norm(rot - h * rd))
        W = scipy_matrix(param, rot).T @ (Rp - Rm) / (2 * h)       # body: Rᵀ Ṙ = ω~
        assert np.abs(np.array([W[2, 1], W[0, 2], W[1, 0]]) - omega).max() < 1e-8
        assert np.abs(param.omega_from_rates(rot, rd) - omega).max() < 1e-12


def test_kinematic_maps_are_singular_where_the_parameterization_is():
    with pytest.raises(ChartDomainError, match="gimbal lock"):
        params.RXYZ.rates_from_omega([0.1, np.pi / 2, 0.3], [1.0, 0, 0])
    # the matrix G(θ) loses rank there
    assert abs(np.linalg.det(params.RXYZ.G([0.1, np.pi / 2, 0.3]))) < 1e-15
    with pytest.raises(ChartDomainError, match="2πk"):
        params.ROTVEC.rates_from_omega([0.0, 2 * np.pi, 0.0], [1.0, 0, 0])
    # dexp_{-ρ} is singular at |ρ| = 2π
    assert np.linalg.cond(so3.dexp(np.array([0.0, 2 * np.pi - 1e-7, 0.0]))) > 1e6


def test_quaternion_sign_continuity(rng):
    q = np.array([0.0, 0, 0, 1, 0, 0, 0])
    step = np.array([0, 0, 0, 0.3, 0.2, 0.1])
    from lgt_bridge import lgt
    prev = q[3:]
    for _ in range(100):   # ~ 3.7 rad per 10 steps: crosses p0 = 0 many times
        q = lgt.tau(q, step, "quat", "SO3xR3", "exp")
        assert q[3:] @ prev > 0
        prev = q[3:]


def test_rotvec_branch_across_pi_and_two_pi():
    """Rotating about a fixed axis: |ρ| stays <= π and jumps exactly when it crosses π."""
    from lgt_bridge import lgt
    n = np.array([0.0, 0.6, 0.8])
    q = np.zeros(6)
    angle = 0.0
    for _ in range(160):                         # 0.05 rad per step -> 8 rad (past π and 2π)
        q1 = lgt.tau(q, np.concatenate([0.05 * n, np.zeros(3)]), "rotvec", "SE3", "exp")
        angle += 0.05
        wrapped = (angle + np.pi) % (2 * np.pi) - np.pi
        assert np.abs(q1[3:] - wrapped * n).max() < 1e-12
        assert np.linalg.norm(q1[3:]) <= np.pi + 1e-12
        q = q1


def test_rotvec_tie_at_pi_follows_previous():
    n = np.array([1.0, 0, 0])
    for s in (1.0, -1.0):
        prev = s * (np.pi - 1e-3) * n
        got = params.ROTVEC.from_quat(np.array([0.0, 1, 0, 0]), prev)
        assert np.allclose(got, s * np.pi * n, atol=1e-15)


def test_tait_bryan_unwraps_across_pi_and_through_gimbal_lock():
    from lgt_bridge import lgt
    # θ0 about the body x axis: with θ1 = θ2 = 0, a body-x rotation adds to θ0 past ±π
    q = np.zeros(6)
    for k in range(1, 100):
        q = lgt.tau(q, [0.05, 0, 0, 0, 0, 0], "rxyz", "SO3xR3", "exp")
        assert abs(q[3] - 0.05 * k) < 1e-12 and np.abs(q[4:]).max() < 1e-12
    # θ1 increases through π/2 (gimbal lock) and beyond, continuously
    q = np.array([0, 0, 0, 0.2, 0.0, -0.4])
    prev = q.copy()
    for k in range(60):
        # body angular velocity that gives θ̇ = (0, 1, 0): ω = G(θ) e_y
        w = params.RXYZ.G(q[3:]) @ np.array([0.0, 1.0, 0.0])
        q = lgt.tau(q, np.concatenate([0.05 * w, np.zeros(3)]), "rxyz", "SO3xR3", "exp")
        assert np.abs(q[3:] - prev[3:]).max() < 0.06
        prev = q
    assert q[4] > np.pi / 2 + 1.0          # went through the singularity
    R = params.RXYZ.alpha(q)[:3, :3]
    assert np.isfinite(q).all() and abs(np.linalg.det(R) - 1) < 1e-12


def test_zyx_angles_pass_through_gimbal_lock_continuously():
    """Pinocchio's z-y-x set: θ1 driven through ±π/2 by ω = G(θ) e_y stays continuous and
    on the rotation the body turned to (checked against composing the increments as matrices)."""
    from lgt_bridge import lgt
    q = np.array([0, 0, 0, 0.3, 0.1, -0.5])
    prev, R = q.copy(), params.RZYX.alpha(q)[:3, :3]
    for k in range(60):
        w = params.RZYX.G(q[3:]) @ np.array([0.0, 1.0, 0.0])
        q = lgt.tau(q, np.concatenate([0.05 * w, np.zeros(3)]), "rzyx", "SO3xR3", "exp")
        R = R @ Rotation.from_rotvec(0.05 * w).as_matrix()
        assert np.abs(q[3:] - prev[3:]).max() < 0.06
        prev = q
    assert q[4] > np.pi / 2 + 1.0
    assert np.abs(params.RZYX.alpha(q)[:3, :3] - R).max() < 1e-12


def test_zyx_exactly_at_lock_keeps_previous_theta2():
    a = np.array([0.3, np.pi / 2, -0.2])
    got = params.RZYX.from_quat(params.RZYX.to_quat(a), prev=np.array([0.25, 1.55, -0.1]))
    R = params.RZYX.alpha(np.concatenate([np.zeros(3), got]))[:3, :3]
    assert np.abs(R - params.RZYX.alpha(np.concatenate([np.zeros(3), a]))[:3, :3]).max() < 1e-12
    assert abs(got[2] + 0.1) < 1e-12


def test_tait_bryan_exactly_at_lock_keeps_previous_theta0():
    a = np.array([0.3, np.pi / 2, -0.2])
    p = params.RXYZ.to_quat(a)
    got = params.RXYZ.from_quat(p, prev=np.array([0.25, 1.55, -0.1]))
    R = params.RXYZ.alpha(np.concatenate([np.zeros(3), got]))[:3, :3]
    assert np.abs(R - params.RXYZ.alpha(np.concatenate([np.zeros(3), a]))[:3, :3]).max() < 1e-12
    assert abs(got[0] - 0.25) < 1e-12


def test_params_by_name_and_bad_names():
    assert params.get("quat") is params.QUAT_WXYZ and params.get("xyzw") is params.QUAT_XYZW
    with pytest.raises(InputError, match="unknown absolute parameterization"):
        params.get("euler_zxz")
    with pytest.raises(InputError, match="order"):
        params.Quaternion("zyxw")
