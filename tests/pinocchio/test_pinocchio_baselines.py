"""The users' baselines on robots with continuous joints (PR2, Tiago): q̇ against a finite
difference of Pinocchio's own integrate, and the renormalized loops keeping every unit
constraint of q."""
import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from lgt_pinocchio import baselines as bl  # noqa: E402


def _model():
    """A free-flyer with a continuous joint (RUBX), a revolute one and another continuous one."""
    m = pin.Model()
    root = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    a = m.addJoint(root, pin.JointModelRUBX(), pin.SE3(np.eye(3), np.array([0.2, 0.0, 0.1])), "wheel")
    b = m.addJoint(a, pin.JointModelRY(), pin.SE3(np.eye(3), np.array([0.0, 0.3, 0.0])), "elbow")
    c = m.addJoint(b, pin.JointModelRUBZ(), pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.2])), "wrist")
    for j, mass in zip((root, a, b, c), (3.0, 0.5, 0.7, 0.4)):
        m.appendBodyToJoint(j, pin.Inertia.FromBox(mass, 0.2, 0.3, 0.1), pin.SE3.Identity())
    return m


def test_qdot_is_the_rate_of_pinocchios_integrate():
    m = _model()
    rng = np.random.default_rng(3)
    q = pin.randomConfiguration(m, -np.ones(m.nq), np.ones(m.nq))
    v = rng.normal(size=m.nv)
    eps = 1e-6
    fd = (pin.integrate(m, q, v * eps) - pin.integrate(m, q, -v * eps)) / (2 * eps)
    np.testing.assert_allclose(bl.qdot(m, q, v), fd, atol=1e-8)


def test_renormalized_loops_keep_quaternion_and_continuous_pairs_unit():
    m = _model()
    q0 = pin.neutral(m)
    v0 = np.array([0.1, 0.0, 0.2, 1.0, -2.0, 0.5, 3.0, -1.0, 2.0])
    for q, _ in (bl.dop853_renorm(m, q0, v0, 0.5, 1e-9), bl.rk4_renorm(m, q0, v0, 0.5, 1e-3)):
        assert abs(np.linalg.norm(q[3:7]) - 1) < 1e-15
        for i in (7, 10):                            # the (cos θ, sin θ) pairs
            assert abs(np.hypot(q[i], q[i + 1]) - 1) < 1e-15
    q_ref, _ = bl.dop853_renorm(m, q0, v0, 0.5, 1e-12)
    q_rk4, _ = bl.rk4_renorm(m, q0, v0, 0.5, 1e-3)
    assert np.abs(pin.difference(m, q_ref, q_rk4)).max() < 1e-9
    # independent of qdot: semi-implicit Euler on Pinocchio's own integrate converges to the
    # same motion at first order
    e = [np.abs(pin.difference(m, q_ref, bl.semi_implicit_euler(m, q0, v0, 0.5, dt)[0])).max()
         for dt in (1e-3, 5e-4)]
    assert e[0] < 5e-3 and 0.4 < e[1] / e[0] < 0.6, e
