"""The Pinocchio adapter (skipped only when pin is not installed)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

pin = pytest.importorskip("pinocchio")

from lgt_bridge import InputError, lgt, wrap  # noqa: E402
from lgt_bridge.analytic import torque_free_omega  # noqa: E402
from lgt_bridge.scenes import RigidBodySystem  # noqa: E402
from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_pinocchio import PinocchioModel  # noqa: E402
from lgt_pinocchio.constraints import init_dynamics  # noqa: E402

import references as ref  # noqa: E402
from pinocchio_models import ball_chain  # noqa: E402

J = np.array([1.0, 2.0, 3.0])
W0 = np.array([0.01, 2.0, 0.01])                   # near the middle axis: the Dzhanibekov flip


def free_body_model(gravity=False):
    m = pin.Model()
    jid = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    m.appendBodyToJoint(jid, pin.Inertia(1.0, np.zeros(3), np.diag(J)), pin.SE3.Identity())
    if not gravity:
        m.gravity.linear[:] = 0.0
    return m


def R_xyzw(q):
    return ref.qmat(np.array([q[6], q[3], q[4], q[5]]))


def test_wrap_finds_the_pinocchio_adapter():
    assert isinstance(wrap(free_body_model()), PinocchioModel)


def test_f_equals_engine_free_body(rng):
    pm = PinocchioModel(free_body_model(gravity=True))
    s = RigidBodySystem([1.0], [np.diag(J)], np.zeros(7) + [0, 0, 0, 0, 0, 0, 1], np.zeros(6), param="quat_xyzw")
    for _ in range(10):
        q = lgt.tau(s.q0, rng.normal(size=6) * 2, "quat_xyzw", "SO3xR3", "exp")
        V = rng.normal(size=6) * 3
        assert np.abs(pm.f(q, V, 0.0) - s.f(q, V, 0.0)).max() < 1e-13
        q_pin, v_pin = pm.pin_state(q, V)
        assert np.abs(pm.twist_from_v(q_pin, v_pin) - V).max() < 1e-14


def test_free_body_against_analytic_solution_and_conservation():
    pm = PinocchioModel(free_body_model(), v0=np.concatenate([np.zeros(3), W0]))
    ts = np.linspace(0, 10, 11)
    r = simulate(pm, (0, 10), method="dopri5", rtol=1e-10, atol=1e-12, t_eval=ts)
    assert r.success
    assert np.abs(r.V[:, :3] - torque_free_omega(ts, J, W0)).max() < 2e-7
    E = np.array([pm.energy(q, V) for q, V in zip(r.q, r.V)])
    h = np.array([pm.spatial_momentum(q, V) for q, V in zip(r.q, r.V)])
    assert np.ptp(E) / E[0] < 1e-9
    assert np.abs(h - h[0]).max() / np.linalg.norm(h[0]) < 1e-8


def _semi_implicit_euler(model, q, v, dt, n):
    data = model.createData()
    for _ in range(n):
        v = v + dt * pin.aba(model, data, q, v, np.zeros(model.nv))
        q = pin.integrate(model, q, v * dt)
    return q


def _rk4_renormalized(model, q, v, dt, n):
    """What users write with a plain ODE solver: q̇ from v, RK4, renormalize the quaternion."""
    data = model.createData()

    def rhs(y):
        q, v = y[:7], y[7:]
        p = np.array([q[6], q[3], q[4], q[5]])
        R = ref.qmat(p / np.linalg.norm(p))
        pd = 0.5 * ref.qmul(p, np.concatenate([[0.0], v[3:]]))
        return np.concatenate([R @ v[:3], pd[1:], [pd[0]], pin.aba(model, data, q, v, np.zeros(6))])

    y = np.concatenate([q, v])
    for _ in range(n):
        k1 = rhs(y)
        k2 = rhs(y + dt / 2 * k1)
        k3 = rhs(y + dt / 2 * k2)
        k4 = rhs(y + dt * k3)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        y[3:7] /= np.linalg.norm(y[3:7])
    return y[:7]


def test_bridge_beats_the_user_baselines_at_equal_cost():
    """10 s of the free asymmetric body (Dzhanibekov flip), same number of ABA calls:
    semi-implicit Euler + pin.integrate at dt = 1e-3 vs the bridge's rkmk2 at 2e-3;
    RK4 + renormalization at 1e-2 vs rkmk4 at 1e-2."""
    model = free_body_model()
    T = 10.0
    v0 = np.concatenate([np.zeros(3), W0])
    q0 = pin.neutral(model)
    Rref, _ = ref.rigid_rotation(np.diag(J), W0, T)
    pm = PinocchioModel(model, v0=v0)
    base_sie = ref.angle(R_xyzw(_semi_implicit_euler(model, q0, v0, 1e-3, 10000)), Rref)
    bridge_euler = simulate(pm, (0, T), method="rkmk2", dt=2e-3, t_eval=[T])
    base_rk4 = ref.angle(R_xyzw(_rk4_renormalized(model, q0, v0, 1e-2, 1000)), Rref)
    bridge_rk4 = simulate(pm, (0, T), method="rkmk4", dt=1e-2, t_eval=[T])
    e_euler = ref.angle(R_xyzw(bridge_euler.q[-1]), Rref)
    e_rk4 = ref.angle(R_xyzw(bridge_rk4.q[-1]), Rref)
    assert bridge_euler.stats["n_f"] == 10000 and bridge_rk4.stats["n_f"] == 4000
    assert base_sie > 1e-3                                   # first order: 9e-3 here
    assert e_euler < base_sie / 100
    assert e_rk4 < base_rk4 and e_rk4 < 1e-7


def test_humanoid_zero_gravity_momentum_and_reference():
    model = pin.buildSampleModelHumanoidRandom()
    model.gravity.linear[:] = 0.0
    rng = np.random.default_rng(3)
    q0 = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    v0 = rng.normal(size=model.nv) * 0.5
    pm = PinocchioModel(model, q0=q0, v0=v0)
    T = 1.0
    ts = np.linspace(0, T, 5)
    r = simulate(pm, (0, T), method="dopri5", rtol=1e-9, atol=1e-9, t_eval=ts)
    tight = simulate(pm, (0, T), method="dopri5", rtol=1e-12, atol=1e-12, t_eval=ts)
    assert r.success and tight.success
    h = np.array([pm.spatial_momentum(q, V) for q, V in zip(r.q, r.V)])
    assert np.abs(h - h[0]).max() <= 1e-7 * np.abs(h[0]).max()
    assert np.abs(r.q[-1] - tight.q[-1]).max() < 1e-6
    E = [pm.energy(q, V) for q, V in zip(r.q, r.V)]
    assert np.ptp(E) / E[0] < 1e-7


def test_bad_input():
    model = free_body_model()
    q = pin.neutral(model)
    bad = q.copy()
    bad[6] = 1.00001
    with pytest.raises(InputError, match=r"off by 1e-05"):
        PinocchioModel(model, q0=bad)
    with pytest.raises(InputError, match="sizes nq = 7, nv = 6"):
        PinocchioModel(model, q0=q, v0=np.zeros(7))
    with pytest.raises(InputError, match=r"entry 2 \(joint 'root' \(Pinocchio joint 1\)\) is nan"):
        PinocchioModel(model, v0=np.array([0, 0, np.nan, 0, 0, 0]))
    with pytest.raises(InputError, match="one per joint, model.njoints = 2"):
        PinocchioModel(model, fext=lambda t, q, v: [pin.Force.Zero()])
    with pytest.raises(InputError, match="tau"):
        PinocchioModel(model, tau=np.zeros(5))
    h = pin.Model()
    comp = pin.JointModelComposite()
    comp.addJoint(pin.JointModelSpherical())
    h.addJoint(0, comp, pin.SE3.Identity(), "composite")
    with pytest.raises(InputError, match="JointModelSpherical component"):
        PinocchioModel(h)


def test_external_force_and_torque_inputs():
    """A constant body-frame force on the free body: ṙ grows as R(t) f / m in the world frame."""
    model = free_body_model()
    f = np.array([0.0, 0.0, 1.0])
    pm = PinocchioModel(model, fext=lambda t, q, v: [pin.Force.Zero(), pin.Force(f, np.zeros(3))])
    r = simulate(pm, (0, 0.5), method="rkmk4", dt=1e-3)
    # no rotation (v0 = 0): the force stays along world z, r = ½ f t² / m
    assert np.allclose(r.q[-1][:3], [0, 0, 0.125], atol=1e-12)


def _pinned(p=np.array([0.5, 0.2, 0.0]), w=np.array([0.3, 2.0, -0.5])):
    model = free_body_model()
    jid = model.getJointId("root")
    cm = pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, jid, pin.SE3(np.eye(3), p), pin.LOCAL)
    cm.joint2_placement = pin.SE3(np.eye(3), p.copy())        # the world point where the body point is at q0
    v0 = np.concatenate([-np.cross(w, p), w])                  # consistent: the pinned point is at rest
    return PinocchioModel(model, v0=v0, constraints=[cm])


def test_pinned_point_drift_se3_vs_so3xr3_and_projection():
    """A body point pinned by a 3-D constraint, rkmk4 at dt = 1e-2 for 10 s. Without
    projection the SE(3) step keeps the pivot (the velocity constraint is linear with
    constant coefficients in the body twist, and exp of such a twist is a rotation about
    the pivot); SO(3)xR³ lets it drift at the method's order. Projection holds both."""
    pm = _pinned()
    drift = {}
    for group in ("SE3", "SO3xR3"):
        r = simulate(pm, (0, 10), method="rkmk4", group=group, dt=1e-2, project=False)
        drift[group] = max(np.abs(pm.constraints(q)).max() for q in r.q)
        rp = simulate(pm, (0, 10), method="rkmk4", group=group, dt=1e-2)
        assert rp.stats["constraint_after_projection"] <= 1e-10
        assert max(np.abs(pm.constraints(q)).max() for q in rp.q) <= 1e-10
    assert drift["SE3"] < 1e-11
    assert drift["SO3xR3"] > 1e-9 and drift["SO3xR3"] > 1e3 * drift["SE3"]


def test_constraint_jacobian_matches_pinocchio_where_satisfied(rng):
    model = pin.buildSampleModelHumanoidRandom()
    j = model.njoints - 1
    d = model.createData()
    q0 = pin.neutral(model)
    pin.forwardKinematics(model, d, q0)
    pl = pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.05]))
    cm = pin.RigidConstraintModel(pin.ContactType.CONTACT_6D, model, j, pl, pin.LOCAL)
    cm.joint2_placement = d.oMi[j] * pl
    pm = PinocchioModel(model, constraints=[cm])
    V = rng.normal(size=pm.nv)
    v = pm.v_from_twist(q0, V)
    cms = pin.StdVec_RigidConstraintModel()
    cms.append(cm)
    cds = pin.StdVec_RigidConstraintData()
    cds.append(cm.createData())
    dd = model.createData()
    init_dynamics(pin, model, dd, cms, cds)                    # pin 3: three arguments, pin 4: four
    pin.constraintDynamics(model, dd, q0, v, np.zeros(model.nv), cms, cds, pin.ProximalSettings(1e-12, 1e-12, 20))
    Jc = pin.getConstraintsJacobian(model, dd, cms, cds)      # LOCAL frame of the contact
    Rc = (dd.oMi[j] * pl).rotation
    AV = pm.constraint_jacobian(q0) @ V
    assert np.abs(AV[:3] - Rc @ (Jc[:3] @ v)).max() < 1e-8 * max(1, np.abs(AV).max())
    assert np.abs(AV[3:] - Jc[3:] @ v).max() < 1e-8 * max(1, np.abs(AV).max())


def test_constraint_to_the_default_world_anchor_holds_its_frame_at_q0():
    """Pinocchio constrains the frame's acceleration: a constraint left at the default anchor
    (joint 2 the world at the identity) keeps the frame where it is at q0 (issue 21; it was
    refused as not satisfied at q0)."""
    model = free_body_model()
    cm = pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, 1, pin.SE3(np.eye(3), np.array([0.5, 0, 0])),
                                  pin.LOCAL)
    pm = PinocchioModel(model, constraints=[cm])
    assert pm.cons.anchored == [0] and np.abs(pm.constraints(pm.q0)).max() < 1e-15


def test_mass_matrix_and_forces_reproduce_aba(rng):
    """M̄⁻¹ Q̄ (CRBA/RNEA in twist coordinates) must equal the ABA-based f."""
    model = free_body_model(gravity=True)
    pm = PinocchioModel(model, fext=lambda t, q, v: [pin.Force.Zero(),
                                                     pin.Force(np.array([0.1, 0.2, 0.3]), np.array([0.01, -0.02, 0.05]))])
    h = pin.buildSampleModelHumanoidRandom()
    ph = PinocchioModel(h, q0=pin.randomConfiguration(h, -np.ones(h.nq), np.ones(h.nq)), v0=rng.normal(size=h.nv))
    for m in (pm, ph):
        for _ in range(3):
            q = m._moved(m.q0, rng.normal(size=m.nv) * 0.5)
            V = rng.normal(size=m.nv)
            assert np.abs(np.linalg.solve(m.mass_matrix(q), m.forces(q, V, 0.3)) - m.f(q, V, 0.3)).max() < 1e-11


def test_genalpha_on_the_pinned_body():
    pm = _pinned()
    T = 1.0
    ref_run = simulate(pm, (0, T), method="dopri5", rtol=1e-11, atol=1e-11, t_eval=[T])
    errs = []
    for dt in (2e-3, 1e-3):
        r = simulate(pm, (0, T), method="genalpha", dt=dt, t_eval=[T])
        assert r.success and r.stats["constraint_residual"] < 1e-12
        errs.append(np.abs(r.q[-1] - ref_run.q[-1]).max())
    assert 3.3 < errs[0] / errs[1] < 4.8                           # second order


def test_fixed_base_and_several_free_flyers():
    m = pin.buildSampleModelManipulator()                     # no free-flyer: all vector-space joints
    pm = PinocchioModel(m, v0=np.full(m.nv, 0.3))
    r = simulate(pm, (0, 0.5), method="dopri5", rtol=1e-9, atol=1e-9)
    E = [pm.energy(q, V) for q, V in zip(r.q, r.V)]
    assert r.success and not pm.layout.bodies and np.ptp(E) / abs(E[0]) < 1e-8
    m2 = pin.Model()
    for k in range(2):
        j = m2.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), f"ff{k}")
        m2.appendBodyToJoint(j, pin.Inertia(1.0 + k, np.zeros(3), np.diag([1.0, 2 + k, 3 + k])), pin.SE3.Identity())
    m2.gravity.linear[:] = 0.0
    pm2 = PinocchioModel(m2, v0=np.array([0.1, 0, 0, 0.3, 1, 0.2, 0, 0.2, 0, -0.5, 0.1, 1.5]))
    r2 = simulate(pm2, (0, 2), method="dopri5", rtol=1e-10, atol=1e-10)
    h = np.array([pm2.spatial_momentum(q, V) for q, V in zip(r2.q, r2.V)])
    assert r2.success and len(pm2.layout.bodies) == 2 and np.abs(h - h[0]).max() < 1e-8


def _plain_reference(model, q0, v0, T):
    """Renormalized DOP853 on Pinocchio's (q, v): q̇ = (R v_lin, ½ p⊗(0, ω)) for the root,
    ½ p⊗(0, ω) for the ball (x y z w order), v for the hinge; no lgt_bridge code."""
    data = model.createData()

    def qd_quat(p_xyzw, w):
        p = np.array([p_xyzw[3], *p_xyzw[:3]])
        d = 0.5 * ref.qmul(p, np.concatenate([[0.0], w]))
        return np.array([d[1], d[2], d[3], d[0]])

    def rhs(t, y):
        q, v = y[:model.nq].copy(), y[model.nq:]
        q[3:7] /= np.linalg.norm(q[3:7])
        q[7:11] /= np.linalg.norm(q[7:11])
        R = R_xyzw(q)
        qd = np.concatenate([R @ v[:3], qd_quat(q[3:7], v[3:6]), qd_quat(q[7:11], v[6:9]), v[9:]])
        return np.concatenate([qd, pin.aba(model, data, q, v, np.zeros(model.nv))])

    s = solve_ivp(rhs, (0, T), np.concatenate([q0, v0]), method="DOP853", rtol=1e-12, atol=1e-12)
    q = s.y[:model.nq, -1].copy()
    q[3:7] /= np.linalg.norm(q[3:7])
    q[7:11] /= np.linalg.norm(q[7:11])
    return q


@pytest.mark.parametrize("group,chart", [("SE3", "exp"), ("SO3xR3", "cay"), ("SE3", "cay2"), ("SO3xR3", "cay2")])
def test_spherical_joint_as_rotation_only_body(group, chart):
    model = ball_chain()
    rng = np.random.default_rng(1)
    q0 = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    v0 = rng.normal(size=model.nv)
    pm = PinocchioModel(model, q0=q0, v0=v0)
    assert [b.rotation_only for b in pm.layout.bodies] == [False, True]
    T = 1.0
    r = simulate(pm, (0, T), method="dopri5", group=group, chart=chart, rtol=1e-11, atol=1e-11, t_eval=[0, T])
    qref = _plain_reference(model, q0, v0, T)
    assert ref.angle(R_xyzw(r.q[-1]), R_xyzw(qref)) < 1e-8                     # root rotation
    assert np.abs(r.q[-1][:3] - qref[:3]).max() < 1e-8                         # root position
    assert ref.angle(R_xyzw(np.r_[0, 0, 0, r.q[-1][7:11]]), R_xyzw(np.r_[0, 0, 0, qref[7:11]])) < 1e-8
    assert abs(r.q[-1][11] - qref[11]) < 1e-8                                   # hinge
    assert abs(np.linalg.norm(r.q[-1][7:11]) - 1) < 1e-14


def test_bench_scene_with_the_user_loops_as_natives():
    from lgt_bridge import bench
    _, rows = bench.sweep("pinocchio_humanoid", ["dopri5"], ["SO3xR3"], ["exp"], [1e-8], [], workers=1,
                          progress=False, auto=False, repeat=1)
    nat = {(r["method"], r["value"]): r for r in rows if r["group"] == "native"}
    assert len(nat) == 9 and all(r["success"] for r in nat.values())
    e = [nat[("semi-implicit Euler + pin.integrate", dt)]["pose_error"] for dt in (1e-3, 4e-4, 1e-4)]
    assert e[2] < e[1] < e[0] and 5 < e[0] / e[2] < 20                        # first order: 10
    assert nat[("DOP853 + renormalization", 1e-10)]["pose_error"] < 1e-7
    assert [r for r in rows if r["group"] == "SO3xR3"][0]["pose_error"] < 1e-6


def test_a_model_changed_after_wrapping_is_analyzed_and_checked_again():
    """A pinocchio.Model wrapped again and again reuses its analysis (joints, passed mass
    check) only while it is unchanged: an inertia zeroed in place is refused by the next
    wrap's mass check, restored it passes again, and a joint added gets its new layout."""
    m = pin.Model()
    j = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    m.appendBodyToJoint(j, pin.Inertia(1.0, np.zeros(3), np.diag([1.0, 2.0, 3.0])), pin.SE3.Identity())
    good = pin.Inertia(m.inertias[1])
    for _ in range(2):                          # the second wrap finds the first's analysis
        r = simulate(PinocchioModel(m), (0, 0.01), method="dop853", t_eval=[0.01])
        assert r.success
    m.inertias[1] = pin.Inertia(1.0, np.zeros(3), np.diag([0.0, 2.0, 3.0]))    # no inertia about x
    with pytest.raises(InputError, match="mass matrix"):
        simulate(PinocchioModel(m), (0, 0.01), method="dop853")
    m.inertias[1] = good
    assert simulate(PinocchioModel(m), (0, 0.01), method="dop853").success
    k = m.addJoint(j, pin.JointModelRX(), pin.SE3.Identity(), "arm")
    m.appendBodyToJoint(k, pin.Inertia(0.5, np.array([0.1, 0.0, 0.0]), np.diag([0.1, 0.1, 0.1])), pin.SE3.Identity())
    pm = PinocchioModel(m)
    assert (pm.layout.nq, pm.layout.nv, pm.layout.vector_v) == (8, 7, (6,))
    assert simulate(pm, (0, 0.01), method="dop853").success


def test_models_wrapped_afresh_share_no_data_and_reuse_their_checks():
    """Models wrapped afresh from one pinocchio.Model: two live ones never share a Data, a
    collected one's Data serves the next, every wrap owns its initial state, and the run of
    a wrap on a reused Data equals the run of the first wrap (Data is scratch)."""
    import gc
    m = pin.buildSampleModelManipulator()
    q0, v0 = pin.neutral(m), np.linspace(0.1, 0.6, m.nv)
    a, b = PinocchioModel(m, q0=q0, v0=v0), PinocchioModel(m, q0=q0, v0=v0)
    assert a.data is not b.data
    assert not np.shares_memory(a.q0, b.q0) and not np.shares_memory(a.V0, b.V0)
    np.testing.assert_array_equal(a.V0, b.V0)
    np.testing.assert_array_equal(a.q0, q0)
    r0 = simulate(a, (0, 0.2), method="dop853", rtol=1e-9, atol=1e-9, t_eval=[0.2])
    used = [a.data, b.data]
    del a, b
    gc.collect()
    c = PinocchioModel(m, q0=q0, v0=v0)
    assert any(c.data is x for x in used)       # given back when a and b were collected
    d = PinocchioModel(m, q0=q0, v0=v0)
    assert d.data is not c.data
    r1 = simulate(c, (0, 0.2), method="dop853", rtol=1e-9, atol=1e-9, t_eval=[0.2])
    np.testing.assert_array_equal(r1.q, r0.q)
    np.testing.assert_array_equal(r1.V, r0.V)
    c.q0[:] = np.nan                            # a wrap's q0 is its own: the next one is checked as given
    np.testing.assert_array_equal(PinocchioModel(m, q0=q0, v0=v0).q0, q0)
    bad = q0.copy()
    bad[0] = np.inf
    with pytest.raises(InputError, match="q0"):
        PinocchioModel(m, q0=bad, v0=v0)
