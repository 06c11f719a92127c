"""Pinocchio joint types beyond free-flyers, spherical and revolute joints: continuous joints
(URDF ``continuous``: RUBX/Y/Z and RevoluteUnboundedUnaligned, q = (cos θ, sin θ), stepped on
SO(2) as circle coordinates), planar joints (SO(2)×R², v_xy in the joint frame converted to the
parent frame), spherical-ZYX joints (rotation-only bodies on the z-y-x angles, V = ω),
unaligned, translation, universal, ellipsoid and helical joints (vector spaces) and composite
joints (split into their components). Each model is checked
against an independent reference on Pinocchio's own (q, v): scipy's DOP853 at 1e-12 with
q̇ = d/dε pin.integrate(q, ε v) (4th-order central difference) and q renormalized by pin.normalize,
none of which touches lgt_bridge's circle or τ code."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lgt_bridge.errors import InputError
from lgt_bridge.lgt import circle_tau
from lgt_bridge.model import Layout
from lgt_bridge.simulate import simulate

pin = pytest.importorskip("pinocchio")

from lgt_pinocchio import PinocchioModel  # noqa: E402

PLACEMENT = pin.SE3(pin.utils.rpyToMatrix(0.1, -0.2, 0.3), np.array([0.05, 0.15, -0.1]))


# --- SO(2): the defining identities of circle_tau -------------------------------------------
@settings(max_examples=200, deadline=None)
@given(st.floats(-10, 10), st.floats(-10, 10))
def test_circle_tau_is_the_rotation_by_the_increment(theta, x):
    got = circle_tau(np.array([np.cos(theta), np.sin(theta)]), x)
    np.testing.assert_allclose(got, [np.cos(theta + x), np.sin(theta + x)], atol=4e-15)


def test_circle_tau_keeps_unit_norm_over_many_updates():
    """10⁵ steady increments (where a plain cos/sin product accumulates its rounding):
    the norm stays within 1e-13 of 1 and the angle within 1e-9 of the sum."""
    cs = np.array([[1.0, 0.0]])
    x = 2.0 * np.pi / 977.0 + 1e-3
    for _ in range(100_000):
        cs = circle_tau(cs, np.array([x]))
    assert abs(np.hypot(*cs[0]) - 1.0) < 1e-13
    ang = np.angle(np.exp(1j * 100_000 * x) * np.conj(cs[0, 0] + 1j * cs[0, 1]))
    assert abs(ang) < 1e-9


def test_layout_checks_circle_coordinates():
    with pytest.raises(InputError, match="circle"):
        Layout(2, 2, [], circle_q=((0, 1),), circle_v=())
    with pytest.raises(InputError, match="covered exactly once"):
        Layout(3, 1, [], circle_q=((0, 1),), circle_v=(0,))
    lay = Layout(2, 1, [], circle_q=((0, 1),), circle_v=(0,))
    with pytest.raises(InputError, match="cos θ² \\+ sin θ² = 1"):
        lay.validate_circles(np.array([1.0, 0.5]), "q0")


# --- models ---------------------------------------------------------------------------------
def _chain(joints, root=None):
    m = pin.Model()
    parent = 0
    rng = np.random.default_rng(11)
    for k, jm in enumerate(([root] if root is not None else []) + list(joints)):
        parent = m.addJoint(parent, jm, PLACEMENT, f"j{k}")
        I = pin.Inertia(0.5 + rng.random(), rng.normal(size=3) * 0.1,
                        np.diag(0.05 + 0.05 * rng.random(3)) + 0.01 * np.eye(3))
        m.appendBodyToJoint(parent, I, pin.SE3.Identity())
    return m


def every_joint():
    """A floating chain with every joint type the adapter steps besides free-flyers."""
    axis = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    comp = pin.JointModelComposite()
    comp.addJoint(pin.JointModelRX())
    comp.addJoint(pin.JointModelRUBY(), PLACEMENT)
    comp.addJoint(pin.JointModelPZ())
    joints = [pin.JointModelRUBX(), pin.JointModelRUBY(), pin.JointModelRUBZ(),
              pin.JointModelRevoluteUnboundedUnaligned(), pin.JointModelRevoluteUnaligned(axis),
              pin.JointModelPrismaticUnaligned(axis), pin.JointModelTranslation(),
              pin.JointModelUniversal(np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))]
    # joints of later Pinocchio versions (3.3 has neither), when the installed one has them
    joints += [make(*args) for name, args in (("JointModelEllipsoid", (0.1, 0.2, 0.3)), ("JointModelHX", (0.05,)))
               if (make := getattr(pin, name, None)) is not None]
    joints += [pin.JointModelSpherical(), comp, pin.JointModelPlanar(), pin.JointModelSphericalZYX()]
    return _chain(joints, root=pin.JointModelFreeFlyer())


def mobile_base():
    """A planar mobile base (fixed to the world) carrying a continuous and a revolute joint."""
    return _chain([pin.JointModelPlanar(), pin.JointModelRUBZ(), pin.JointModelRY()])


ARM_URDF = """<?xml version="1.0"?>
<robot name="pr2_like_arm">
  <link name="base"><inertial><mass value="5"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="torso"><inertial><origin xyz="0 0 0.2"/><mass value="3"/><inertia ixx="0.05" iyy="0.06" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="shoulder"><inertial><origin xyz="0.1 0 0"/><mass value="2"/><inertia ixx="0.02" iyy="0.03" izz="0.02" ixy="0.001" ixz="0" iyz="0"/></inertial></link>
  <link name="upper_arm"><inertial><origin xyz="0.2 0 0"/><mass value="1.5"/><inertia ixx="0.01" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="forearm"><inertial><origin xyz="0.15 0 0"/><mass value="1"/><inertia ixx="0.005" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="wrist"><inertial><origin xyz="0 0.02 0"/><mass value="0.4"/><inertia ixx="0.002" iyy="0.001" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="torso_lift" type="prismatic"><parent link="base"/><child link="torso"/><axis xyz="0 0 1"/><limit lower="0" upper="0.3" effort="100" velocity="1"/></joint>
  <joint name="shoulder_pan" type="revolute"><parent link="torso"/><child link="shoulder"/><origin xyz="0 0.2 0.4"/><axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="10" velocity="3"/></joint>
  <joint name="upper_arm_roll" type="continuous"><parent link="shoulder"/><child link="upper_arm"/><origin xyz="0.1 0 0"/><axis xyz="1 0 0"/></joint>
  <joint name="forearm_roll" type="continuous"><parent link="upper_arm"/><child link="forearm"/><origin xyz="0.4 0 0" rpy="0 0.3 0"/><axis xyz="1 0 0"/></joint>
  <joint name="wrist_roll" type="continuous"><parent link="forearm"/><child link="wrist"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/></joint>
</robot>"""


def pr2_like(free=False):
    return pin.buildModelFromXML(ARM_URDF, pin.JointModelFreeFlyer()) if free else pin.buildModelFromXML(ARM_URDF)


def start(m, seed=3):
    rng = np.random.default_rng(seed)
    pin.seed(seed)                                  # randomConfiguration draws from Pinocchio's own RNG
    lo = np.where(np.isfinite(m.lowerPositionLimit), m.lowerPositionLimit, -1.0).clip(-1, 1)
    hi = np.where(np.isfinite(m.upperPositionLimit), m.upperPositionLimit, 1.0).clip(-1, 1)
    return pin.randomConfiguration(m, lo, hi), rng.normal(size=m.nv)


def reference(m, q0, v0, T, tau=None):
    """Pinocchio's own (q, v) at T: DOP853 at 1e-12 on (q, v), q̇ by central differences of
    pin.integrate along v, q renormalized by pin.normalize at every evaluation."""
    from scipy.integrate import solve_ivp
    d = m.createData()
    zero = np.zeros(m.nv)

    def rhs(t, y):
        q, v = pin.normalize(m, y[:m.nq]), y[m.nq:]
        speed = np.linalg.norm(v)
        qd = np.zeros(m.nq)
        if speed > 0.0:       # 4th-order central difference along the unit direction: ~1e-13
            u, e = v / speed, 1e-3
            step = [pin.integrate(m, q, k * e * u) for k in (-2, -1, 1, 2)]
            qd = speed * (step[0] - 8.0 * step[1] + 8.0 * step[2] - step[3]) / (12.0 * e)
        return np.concatenate([qd, pin.aba(m, d, q, v, zero if tau is None else tau(t, q, v))])
    s = solve_ivp(rhs, (0.0, T), np.concatenate([q0, v0]), method="DOP853", rtol=1e-12, atol=1e-12)
    assert s.status == 0
    return pin.normalize(m, s.y[:m.nq, -1]), s.y[m.nq:, -1]


def gap(m, pm, r, ref):
    """Largest difference from the reference in Pinocchio's tangent space (q) and in v."""
    q, v = pm.pin_state(r.q[-1], r.V[-1])
    return float(np.abs(pin.difference(m, ref[0], q)).max()), float(np.abs(v - ref[1]).max())


MODELS = {"every_joint": every_joint, "pr2_like_arm": pr2_like, "pr2_like_floating": lambda: pr2_like(True),
          "mobile_base": mobile_base}


@pytest.mark.parametrize("name", list(MODELS))
def test_models_wrap_with_circle_coordinates(name):
    m = MODELS[name]()
    pm = PinocchioModel(m, q0=start(m)[0])
    n_cont = sum(j.shortname() in ("JointModelRUBX", "JointModelRUBY", "JointModelRUBZ",
                                   "JointModelRevoluteUnboundedUnaligned") for j in m.joints)
    n_comp = sum(1 for j in m.joints if j.shortname() == "JointModelComposite")    # one RUBY inside
    n_planar = sum(1 for j in m.joints if j.shortname() == "JointModelPlanar")
    assert len(pm.layout.circle_q) == n_cont + n_comp + n_planar
    assert len(pm.planars) == n_planar
    for (c, s), v in zip(pm.layout.circle_q, pm.layout.circle_v):
        assert s == c + 1 and 0 <= v < m.nv


@pytest.mark.parametrize("name", list(MODELS))
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_agrees_with_the_independent_reference(name, group):
    m = MODELS[name]()
    q0, v0 = start(m)
    T = 0.5
    ref = reference(m, q0, v0, T)
    pm = PinocchioModel(m, q0=q0, v0=v0)
    r = simulate(pm, (0.0, T), method="dop853", group=group, chart="exp", rtol=1e-12, atol=1e-12)
    assert r.success, r.message
    dq, dv = gap(m, pm, r, ref)
    assert dq < 1e-8 and dv < 1e-8 * max(1.0, np.abs(ref[1]).max())
    for c, s in pm.layout.circle_q:                   # stepped on SO(2): unit to round-off
        assert abs(np.hypot(r.q[-1, c], r.q[-1, s]) - 1.0) < 1e-14


def test_rkmk4_converges_at_fourth_order_through_the_circles():
    m = pr2_like()
    q0, v0 = start(m, seed=5)
    v0 = 4.0 * v0                                   # fast enough for errors well above the reference's
    T = 0.4
    ref = reference(m, q0, v0, T)
    pm = PinocchioModel(m, q0=q0, v0=v0)
    dts = [0.02, 0.01, 0.005]
    errs = [gap(m, pm, simulate(pm, (0.0, T), method="rkmk4", dt=dt), ref)[0] for dt in dts]
    slope = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert abs(slope - 4.0) < 0.3, (errs, slope)


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_genalpha_through_the_circles(group):
    """Generalized-α on the analytic matrix (RNEA derivatives): second order in q against
    the reference, under a PD torque on every actuated coordinate."""
    m = pr2_like(free=True)
    q0, v0 = start(m, seed=7)
    qref = q0.copy()

    def tau(t, q, v):
        out = -2.0 * v
        out[6:] += 20.0 * pin.difference(m, q, qref)[6:]
        return out
    T = 0.3
    ref = reference(m, q0, v0, T, tau)
    pm = PinocchioModel(m, q0=q0, v0=v0, tau=tau)
    errs = []
    for dt in (4e-3, 2e-3, 1e-3):
        r = simulate(pm, (0.0, T), method="genalpha", group=group, dt=dt)
        assert r.success, r.message
        errs.append(gap(m, pm, r, ref)[0])
    slope = np.polyfit(np.log([4e-3, 2e-3, 1e-3]), np.log(errs), 1)[0]
    assert 1.7 < slope < 2.5, (errs, slope)


@pytest.mark.parametrize("method", ["rkmk4", "dop853"])
def test_numpy_and_compiled_backends_agree_on_circles(method, monkeypatch):
    m = every_joint()
    q0, v0 = start(m)
    out = []
    for backend in ("numpy", "numba"):
        monkeypatch.setenv("LGT_BRIDGE_BACKEND", backend)
        pm = PinocchioModel(m, q0=q0, v0=v0, backend=backend)
        kw = dict(dt=5e-3) if method == "rkmk4" else dict(rtol=1e-9, atol=1e-9)
        r = simulate(pm, (0.0, 0.2), method=method, group="SE3", **kw)
        out.append(r)
    assert out[0].stats["n_f"] == out[1].stats["n_f"]
    # dop853's step sizes follow its error estimate, a difference of two solutions whose last
    # bits differ between backends (measured: step ends 2e-10 apart): compare where both end
    rows = slice(None) if method == "rkmk4" else slice(-1, None)
    np.testing.assert_allclose(out[1].q[rows], out[0].q[rows], rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[1].V[rows], out[0].V[rows], rtol=0, atol=1e-11 * np.abs(out[0].V).max())


# --- refused, with a clear message ------------------------------------------------------------
def test_non_unit_continuous_joint_is_refused_naming_it():
    m = pr2_like()
    q0 = pin.neutral(m)
    c = m.joints[m.getJointId("forearm_roll")].idx_q
    q0[c:c + 2] = [1.0, 0.3]
    with pytest.raises(InputError, match="forearm_roll.*unit norm"):
        PinocchioModel(m, q0=q0)


def test_mimic_joints_are_refused_with_the_reason():
    m = _chain([pin.JointModelRX(), pin.JointModelRY()])
    try:
        m2 = pin.transformJointIntoMimic(m, 1, 2, 2.0, 0.0)
    except Exception:                                  # no mimic joints in this Pinocchio
        pytest.skip("this Pinocchio has no transformJointIntoMimic")
    with pytest.raises(InputError, match="mimic"):
        PinocchioModel(m2)


@pytest.mark.parametrize("part", ["JointModelSpherical", "JointModelPlanar", "JointModelSphericalZYX"])
def test_composite_with_a_rigid_component_is_refused(part):
    comp = pin.JointModelComposite()
    comp.addJoint(pin.JointModelRX())
    comp.addJoint(getattr(pin, part)())
    with pytest.raises(InputError, match=f"composite joint with a {part} component"):
        PinocchioModel(_chain([comp]))


# --- spherical-ZYX joints: V = ω, written back through τ ----------------------------------------
def test_zyx_twist_and_its_rate_are_pinocchios_joint_motion():
    """V = ω of the child frame and V̇ = ω̇, against Pinocchio's own joint velocity and
    acceleration (forwardKinematics with v and a = ABA's), on both backends."""
    m = _chain([pin.JointModelSphericalZYX(), pin.JointModelRX()])
    q0, v0 = start(m, seed=9)
    for backend in ("numpy", "numba"):
        pm = PinocchioModel(m, q0=q0, v0=v0, backend=backend)
        d = m.createData()
        a = pin.aba(m, d, q0, v0, np.zeros(m.nv))
        pin.forwardKinematics(m, d, q0, v0, a)
        np.testing.assert_allclose(pm.V0[:3], d.v[1].angular, rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(pm.f(q0, pm.V0, 0.0)[:3], d.a[1].angular, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(pm.v_from_twist(q0, pm.V0), v0, rtol=1e-13, atol=1e-14)


def test_zyx_angles_go_through_the_lock_continuously():
    """A ball (isotropic inertia, centre on the joint, no gravity) on a ZYX joint spins at a
    constant body ω mostly about its y axis, so R(t) = R0 exp(t ω̂) exactly. θ1 passes ±π/2
    and on (Pinocchio's own q̇ = G⁻¹ω is singular there); the angles stay continuous and the
    rotation matches the exact one to the accuracy G⁻¹ allows near the lock."""
    from scipy.spatial.transform import Rotation

    from lgt_bridge.params import RZYX
    m = pin.Model()
    j = m.addJoint(0, pin.JointModelSphericalZYX(), pin.SE3.Identity(), "ball")
    m.appendBodyToJoint(j, pin.Inertia(2.0, np.zeros(3), 0.3 * np.eye(3)), pin.SE3.Identity())
    q0 = np.array([0.2, 1.2, 0.0])
    w = np.array([0.01, 2.0, 0.013])
    T = 0.6
    pm = PinocchioModel(m, q0=q0, v0=RZYX.rates_from_omega(q0, w))
    r = simulate(pm, (0.0, T), method="dop853", group="SO3xR3", rtol=1e-11, atol=1e-11,
                 t_eval=np.linspace(0, T, 61))
    assert r.success, r.message
    th1 = r.q[:, 1]
    # near the lock θ0 and θ2 turn fast (only their sum is defined there; measured 0.53 rad
    # between outputs) but never jump by a branch (π or 2π)
    assert th1.max() > np.pi / 2 + 0.2 and np.abs(np.diff(r.q, axis=0)).max() < 1.0
    assert np.abs(np.cos(th1)).min() < 0.05           # passed near the lock
    R0 = RZYX.alpha(np.concatenate([np.zeros(3), q0]))[:3, :3]
    for t, q in zip(r.t, r.q):
        exact = R0 @ Rotation.from_rotvec(t * w).as_matrix()
        assert np.abs(RZYX.alpha(np.concatenate([np.zeros(3), q]))[:3, :3] - exact).max() < 1e-7


# --- planar joints: the velocity conversion and generalized-α's matrix --------------------------
def test_planar_twist_is_the_parent_frame_velocity():
    """V's (x, y) entries are d/dt of q's (x, y) (what the vector coordinates are stepped
    with), checked against pin.integrate over a small time; V ↔ v round trip."""
    m = mobile_base()
    q0, v0 = start(m, seed=2)
    pm = PinocchioModel(m, q0=q0, v0=v0)
    (iq, iv), = pm.planars
    h = 1e-6
    rate = (pin.integrate(m, q0, h * v0) - pin.integrate(m, q0, -h * v0))[iq:iq + 2] / (2 * h)
    np.testing.assert_allclose(pm.V0[iv:iv + 2], rate, rtol=1e-8)
    np.testing.assert_allclose(pm.v_from_twist(q0, pm.V0), v0, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(pm._v_from_twist_numpy(q0, pm.V0), v0, rtol=1e-14, atol=1e-15)


@pytest.mark.parametrize("at", ["solution", "any_acceleration"])
def test_planar_iteration_matrix_against_differences_of_the_residual(at):
    from test_pinocchio_constraints import rel, residual_fd
    m = mobile_base()
    q0, v0 = start(m, seed=4)
    pm = PinocchioModel(m, q0=q0, v0=v0, tau=lambda t, q, v: -3.0 * v + np.sin(t))
    V, t = pm.V0 * 2.0, 0.2
    Vd = pm.f(q0, V, t) if at == "solution" else np.random.default_rng(1).normal(size=pm.nv)
    kw = {} if at == "solution" else {"Vdot": Vd}
    C = pm.iteration_matrix(q0, V, t, 0.0, 1.0, 0.0, **kw)
    K = pm.iteration_matrix(q0, V, t, 0.0, 0.0, 1.0, **kw)
    Cf, Kf = residual_fd(pm, q0, V, Vd, t)
    assert rel(C, Cf) < 1e-6 and rel(K, Kf) < 1e-6


def test_pr2_from_the_loaders():
    """PR2 as example-robot-data loads it (fixed base, URDF continuous joints) runs and agrees
    with the reference (skipped only without the loaders: pip install 'lgt-bridge[robots]')."""
    erd = pytest.importorskip("example_robot_data", reason="example-robot-data-loaders not installed "
                                                          "(pip install 'lgt-bridge[robots]')")
    robot = erd.load("pr2")
    m = robot.model
    assert any(j.shortname().startswith("JointModelRUB") for j in m.joints)
    q0 = np.array(robot.q0, float)
    v0 = 0.3 * np.random.default_rng(1).normal(size=m.nv)
    T = 0.05
    ref = reference(m, q0, v0, T)
    pm = PinocchioModel(m, q0=q0, v0=v0)
    r = simulate(pm, (0.0, T), method="dop853", group="SO3xR3", rtol=1e-12, atol=1e-12)
    assert r.success, r.message
    dq, dv = gap(m, pm, r, ref)
    assert dq < 1e-8 and dv < 1e-8 * max(1.0, np.abs(ref[1]).max())


# --- circles inside a closed loop: projection and generalized-α's constraint rows ---------------
def pinned_spatial_chain():
    """Continuous joints about z, y, x and a revolute joint, the last link's tip pinned to
    the world where it starts (a 3-D contact: one degree of freedom left), gravity on."""
    from test_pinocchio_constraints import C3, _constraint
    m = _chain([pin.JointModelRUBZ(), pin.JointModelRUBY(), pin.JointModelRUBX(), pin.JointModelRX()])
    q0, _ = start(m, seed=6)
    tip = pin.SE3(np.eye(3), np.array([0.1, 0.05, 0.2]))
    cm = _constraint(m, q0, C3, m.njoints - 1, tip)
    return m, q0, cm


@pytest.mark.parametrize("method, kw", [("dop853", dict(rtol=1e-10, atol=1e-10)), ("genalpha", dict(dt=1e-3))])
def test_continuous_joints_in_a_closed_loop(method, kw):
    """The constrained chain keeps its pin (projection after explicit steps; index-3 rows in
    generalized-α) with (cos θ, sin θ) unit, and conserves energy (no damping): dop853 to
    1e-8, generalized-α (dissipative, ρ∞ = 0.9, h = 1e-3) to 1e-3 of the energy's swing."""
    m, q0, cm = pinned_spatial_chain()
    pm = PinocchioModel(m, q0=q0, constraints=[cm])
    assert pm.n_constraints == 3 and len(pm.layout.circle_q) == 3
    # a velocity the pin allows: the null space of A
    A = pm.constraint_jacobian(q0)
    V0 = np.linalg.svd(A)[2][-1] * 2.0
    assert np.abs(A @ V0).max() < 1e-12
    r = simulate(pm, (0.0, 0.5), method=method, group="SO3xR3", q0=q0, V0=V0, **kw)
    assert r.success, r.message
    assert np.abs(pm.constraints(r.q[-1])).max() < 1e-9
    for c, s in pm.layout.circle_q:
        assert abs(np.hypot(r.q[-1, c], r.q[-1, s]) - 1.0) < 1e-14
    E = [pm.energy(q, V) for q, V in zip(r.q, r.V)]
    swing = max(abs(pm.energy(q0, V0)), 1.0)
    assert abs(E[-1] - E[0]) < (1e-8 if method == "dop853" else 1e-3) * swing
    assert np.abs(r.q[-1] - q0).max() > 0.05                     # it moved
