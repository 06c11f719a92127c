"""Pinocchio adapter, issue 21: constraints as Pinocchio's users write them.

Each test compares with an independent reference: scipy's DOP853 at rtol = atol = 1e-12 on
Pinocchio's own (q, v) of models whose joints are all revolute (q̇ = v), with
pin.constraintDynamics (Baumgarte off, consistent initial state: the exact constrained motion)."""
import warnings

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from scipy.integrate import solve_ivp  # noqa: E402

from lgt_bridge.errors import InputError, ModelNote  # noqa: E402
from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_pinocchio import PinocchioModel  # noqa: E402
from lgt_pinocchio.constraints import REFUSED, init_dynamics, rows_of  # noqa: E402

from pinocchio_models import FOUR_BAR_EXAMPLE_Q0, four_bar, parallelogram_q  # noqa: E402

PIN4 = hasattr(pin, "PointAnchorConstraintModel")
needs_pin4 = pytest.mark.skipif(not PIN4, reason="Pinocchio 4's constraint classes")
C3, C6 = pin.ContactType.CONTACT_3D, pin.ContactType.CONTACT_6D
PL = pin.SE3(pin.exp3(np.array([0.3, -0.2, 0.5])), np.array([0.1, 0.02, -0.05]))


def reference(model, q0, v0, T, cms, tau=None, fext=None, prox=None):
    """(q, v) at T by scipy DOP853 (1e-12) on pin.constraintDynamics (q̇ = v: revolute joints);
    fext (joint frames) enters as Σ J_jᵀ f_j, J_j the LOCAL joint Jacobian."""
    assert model.nq == model.nv
    data = model.createData()
    vc, vd = pin.StdVec_RigidConstraintModel(), pin.StdVec_RigidConstraintData()
    for cm in cms:
        vc.append(cm)
        vd.append(cm.createData())
    init_dynamics(pin, model, data, vc, vd)
    prox = prox or pin.ProximalSettings(1e-14, 1e-12, 100)
    jd = model.createData()

    def rhs(t, y):
        q, v = y[:model.nq], y[model.nq:]
        u = np.zeros(model.nv) if tau is None else np.array(tau(t, q, v), float)
        if fext is not None:
            pin.computeJointJacobians(model, jd, q)
            for j, f in enumerate(fext(t, q, v)):
                if j:
                    u += pin.getJointJacobian(model, jd, j, pin.LOCAL).T @ np.asarray(f, float)
        return np.concatenate([v, pin.constraintDynamics(model, data, q, v, u, vc, vd, prox)])
    sol = solve_ivp(rhs, (0, T), np.concatenate([q0, v0]), method="DOP853", rtol=1e-12, atol=1e-12)
    assert sol.success
    return sol.y[:model.nq, -1], sol.y[model.nq:, -1]


def parallelogram_reference(m, theta0, omega0, T):
    """(q, v) at T of the four-bar on its parallelogram branch q = (θ, π - θ, θ), by scipy DOP853
    (1e-12) on θ alone: v = t θ̇ with t = (1, -1, 1) constant, and the constraint forces are
    orthogonal to t, so θ̈ = -tᵀ nle(q, v) / tᵀ M(q) t (Pinocchio's CRBA and nonLinearEffects).
    It holds through the singular configurations (θ = 0, π), where constraintDynamics' proximal
    solve on the full coordinates loses digits."""
    d = m.createData()
    t_ = np.array([1.0, -1.0, 1.0])

    def rhs(t, y):
        q, v = parallelogram_q(y[0]), t_ * y[1]
        M = pin.crba(m, d, q)
        M = np.triu(M) + np.triu(M, 1).T
        return [y[1], -t_ @ pin.nonLinearEffects(m, d, q, v) / (t_ @ M @ t_)]
    sol = solve_ivp(rhs, (0, T), [theta0, omega0], method="DOP853", rtol=1e-12, atol=1e-12)
    assert sol.success
    return parallelogram_q(sol.y[0, -1]), t_ * sol.y[1, -1]


def manipulator():
    m = pin.buildSampleModelManipulator()
    q0 = pin.integrate(m, pin.neutral(m), np.random.default_rng(1).normal(size=m.nv) * 0.6)
    return m, q0


def world_anchor(m, q0, j, pl, kind=C3):
    """The explicit RigidConstraintModel of a frame held where it is at q0."""
    d = m.createData()
    pin.forwardKinematics(m, d, q0)
    return pin.RigidConstraintModel(kind, m, j, pl, 0, d.oMi[j] * pl)


def run(pm, T, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelNote)
        r = simulate(pm, (0, T), t_eval=[T], **kw)
    assert r.success, r.message
    return r.q[-1], pm.v_from_twist(r.q[-1], r.V[-1])


# --- 1. Pinocchio 3 and 4 -----------------------------------------------------------------------
def test_the_installed_pinocchios_constraint_api():
    """rows_of/init_dynamics pick Pinocchio 3's size() and three-argument initConstraintDynamics,
    or 4's residualSize() and four arguments (the suite runs on both)."""
    m, q0 = manipulator()
    cm = pin.RigidConstraintModel(C6, m, 3, PL)
    assert rows_of(cm) == 6
    pm = PinocchioModel(m, q0=q0, constraints=[pin.RigidConstraintModel(C3, m, m.nv, PL)])
    assert pm.n_constraints == 3 and not pm.redundant_rows
    assert np.isfinite(pm.f(pm.q0, pm.V0, 0.0)).all()


def test_pinocchio_2_is_refused_with_the_version_needed(monkeypatch):
    m, q0 = manipulator()
    monkeypatch.setattr(pin, "__version__", "2.7.0")
    with pytest.raises(InputError, match=r"needs Pinocchio >= 3\.0; this is Pinocchio 2\.7\.0"):
        PinocchioModel(m, q0=q0)


# --- 2. Pinocchio 4's anchors, and the refused classes --------------------------------------------
@needs_pin4
@pytest.mark.parametrize("cls, kind", [("PointAnchorConstraintModel", C3), ("FrameAnchorConstraintModel", C6)])
@pytest.mark.parametrize("generic", [False, True])
def test_anchor_constraints_against_constraint_dynamics(cls, kind, generic):
    m, q0 = manipulator()
    j = m.getJointId("wrist1_joint") if kind == C6 else m.nv
    anchor = getattr(pin, cls)(m, j, PL)                   # to the world: held where it is at q0
    pm = PinocchioModel(m, q0=q0, constraints=[pin.ConstraintModel(anchor) if generic else anchor])
    # a weld of the fifth of six joints: 5 independent rows (the sixth is redundant)
    assert pm.n_constraints + len(pm.redundant_rows) == (3 if kind == C3 else 6)
    T = 0.5
    qr, vr = reference(m, q0, np.zeros(m.nv), T, [world_anchor(m, q0, j, PL, kind)])
    q, v = run(pm, T, method="dop853", rtol=1e-12, atol=1e-12)
    assert np.abs(q - q0).max() > 0.05
    assert np.abs(q - qr).max() < 1e-9 and np.abs(v - vr).max() < 1e-8


@needs_pin4
@pytest.mark.parametrize("make", [
    lambda m: pin.PointContactConstraintModel(m, 3),
    lambda m: pin.JointLimitConstraintModel(m, pin.StdVec_Index([1, 2])),
    lambda m: pin.JointFrictionConstraintModel(m, pin.StdVec_Index([1, 2])),
    lambda m: pin.ConstraintModel(pin.PointContactConstraintModel(m, 3)),
])
def test_unilateral_friction_and_limit_constraints_are_refused_naming_the_class(make):
    m, q0 = manipulator()
    c = make(m)
    name = type(c.extract() if isinstance(c, pin.ConstraintModel) else c).__name__
    with pytest.raises(InputError, match=f"constraints\\[0\\] is a .*{name}") as e:
        PinocchioModel(m, q0=q0, constraints=[c])
    assert REFUSED[name].split(" (")[0] in str(e.value)


@needs_pin4
def test_compliant_and_prescribed_anchors_are_refused():
    m, q0 = manipulator()
    a = pin.PointAnchorConstraintModel(m, 3, PL)
    a.desired_constraint_offset = np.array([0.0, 0.1, 0.0])
    with pytest.raises(InputError, match="desired_constraint_offset"):
        PinocchioModel(m, q0=q0, constraints=[a])
    a = pin.PointAnchorConstraintModel(m, 3, PL)
    a.setCompliance(np.full(3, 1e-3))
    with pytest.raises(InputError, match="compliance"):
        PinocchioModel(m, q0=q0, constraints=[a])
    with pytest.raises(InputError, match="RigidConstraintModel"):
        PinocchioModel(m, q0=q0, constraints=["contact"])
    with pytest.raises(InputError, match="a list"):
        PinocchioModel(m, q0=q0, constraints=3)


# --- 3. contacts and loops as Pinocchio's examples build them ---------------------------------------
def test_four_argument_contact_holds_the_frame_where_it_is():
    """RigidConstraintModel(type, model, joint1_id, placement) as in Pinocchio's contact example:
    Pinocchio constrains the frame's acceleration, so the frame stays where it is at q0."""
    m, q0 = manipulator()
    cm = pin.RigidConstraintModel(C3, m, m.nv, PL)
    pm = PinocchioModel(m, q0=q0, constraints=[cm])
    assert pm.cons.anchored == [0] and np.abs(pm.constraints(q0)).max() < 1e-14
    assert cm.joint2_placement.isIdentity()                   # the user's object is not changed
    T = 0.5
    qr, vr = reference(m, q0, np.zeros(m.nv), T, [cm])       # Pinocchio's own reading of it
    q, v = run(pm, T, method="dop853", rtol=1e-12, atol=1e-12)
    assert np.abs(q - qr).max() < 1e-9 and np.abs(v - vr).max() < 1e-8


def test_four_bar_from_its_examples_unclosed_start_is_projected_and_reported():
    m, cm = four_bar()
    with pytest.warns(ModelNote, match="redundant"):
        pm = PinocchioModel(m, q0=FOUR_BAR_EXAMPLE_Q0, constraints=[cm])
    assert np.abs(pm.cons.residual_all(FOUR_BAR_EXAMPLE_Q0)).max() > 0.9
    T = 0.8                  # its collinear configuration near t = 0.88: see the branch test
    with pytest.warns(ModelNote, match="violates the constraints"):
        r = simulate(pm, (0, T), method="dop853", rtol=1e-12, atol=1e-12)
    assert r.success
    rep = r.stats["initial_projection"]
    assert rep["position_residual"] > 0.9 and rep["position"] > 0.1 and rep["position_residual_after"] < 1e-12
    assert np.abs(pm.cons.residual_all(r.q[0])).max() < 1e-12
    q0 = r.q[0]                                              # closed on the parallelogram branch
    assert abs(q0[0] - q0[2]) < 1e-12 and abs(np.cos(q0[0] + q0[1]) + 1) < 1e-12
    qr, vr = parallelogram_reference(m, q0[0], r.V[0][0], T)
    assert np.abs(np.angle(np.exp(1j * (r.q[-1] - qr)))).max() < 1e-9 and np.abs(r.V[-1] - vr).max() < 1e-9
    assert np.abs(r.q[-1] - r.q[0]).max() > 0.1


def test_a_loop_that_cannot_close_is_refused_before_any_step():
    m, cm = four_bar()
    cm.joint2_placement = pin.SE3(np.eye(3), np.array([-5.0, 0.0, 0.0]))   # out of reach
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelNote)
        with pytest.raises(InputError, match="projection onto the constraints failed"):
            PinocchioModel(m, q0=pin.neutral(m), constraints=[cm])


# --- 4. the user's ProximalSettings ------------------------------------------------------------
def test_users_proximal_settings_are_used():
    m, q0 = manipulator()
    cm = world_anchor(m, q0, m.nv, PL)
    prox = pin.ProximalSettings(1e-13, 1e-12, 7)
    pm = PinocchioModel(m, q0=q0, constraints=cm, prox_settings=prox)      # one, not in a list
    assert pm.prox is prox
    pm.f(pm.q0, pm.V0, 0.0)
    assert prox.iter >= 1                                # Pinocchio wrote its iterations there
    T = 0.3
    qr, vr = reference(m, q0, np.zeros(m.nv), T, [cm], prox=pin.ProximalSettings(1e-13, 1e-12, 7))
    q, v = run(pm, T, method="dop853", rtol=1e-12, atol=1e-12)
    assert np.abs(q - qr).max() < 1e-9
    with pytest.raises(InputError, match="ProximalSettings"):
        PinocchioModel(m, q0=q0, constraints=[cm], prox_settings=(1e-12, 1e-12, 7))


# --- 5. a redundant loop on generalized-α ------------------------------------------------------------
def test_genalpha_runs_the_four_bar_closed_by_a_3d_loop():
    m, cm = four_bar()
    q0 = parallelogram_q(0.4)
    with pytest.warns(ModelNote, match=r"1 of its 3 constraint rows are redundant .*rows \[1\]"):
        pm = PinocchioModel(m, q0=q0, constraints=[cm])
    assert pm.n_constraints == 2 and pm.redundant_rows == [1]
    T = 1.0
    qr, vr = reference(m, q0, np.zeros(3), T, [cm])
    qp, vp = parallelogram_reference(m, 0.4, 0.0, T)
    assert np.abs(qr - qp).max() < 1e-10                                    # the references agree
    errs = []
    for dt in (2e-3, 1e-3):
        q, v = run(pm, T, method="genalpha", dt=dt)
        errs.append(np.abs(q - qr).max())
    assert errs[1] < errs[0] < 1e-3 and errs[0] / errs[1] > 3                 # second order
    q, v = run(pm, T, method="radau5", rtol=1e-10, atol=1e-10)
    assert np.abs(q - qr).max() < 1e-8 and np.abs(v - vr).max() < 1e-8


# --- 6. external forces with constraints; placements copied ----------------------------------------
@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_external_forces_with_constraints(backend):
    m, q0 = manipulator()
    cm = world_anchor(m, q0, m.nv, PL)

    def fext(t, q, v):
        return [np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0])] + [
            np.array([np.sin(t) + q[j - 1], 2.0, -v[j - 1], 0.3, 0.1 * j, -0.2]) for j in range(1, m.njoints)]
    pm = PinocchioModel(m, q0=q0, constraints=[cm], fext=fext, backend=backend)
    T = 0.4
    qr, vr = reference(m, q0, np.zeros(m.nv), T, [cm], fext=fext)
    qn, _ = reference(m, q0, np.zeros(m.nv), T, [cm])
    q, v = run(pm, T, method="dop853", rtol=1e-12, atol=1e-12)
    assert np.abs(qr - qn).max() > 1e-2                               # the forces matter
    assert np.abs(q - qr).max() < 1e-9 and np.abs(v - vr).max() < 1e-8
    errs = []                                                         # index 3: forces() with fext
    for dt in (4e-3, 2e-3):
        q, v = run(pm, T, method="genalpha", dt=dt)
        errs.append(np.abs(q - qr).max())
    assert errs[1] < errs[0] < 1e-2 and errs[0] / errs[1] > 3


def test_constraint_placements_are_copied_when_wrapped():
    m, q0 = manipulator()
    cm = world_anchor(m, q0, m.nv, PL)
    pm = PinocchioModel(m, q0=q0, constraints=[cm])
    cm.joint2_placement = pin.SE3(np.eye(3), np.ones(3))
    assert np.abs(pm.constraints(q0)).max() < 1e-14
    assert "copied when the model is wrapped" in " ".join(PinocchioModel.__doc__.split())   # the docstring says so


# --- 7. a branch switch at the four-bar's singular configuration ------------------------------------
def test_a_switch_of_assembly_branch_is_reported_with_its_time():
    """Started 0.05 rad above the horizontal, the parallelogram swings through its collinear
    (singular) configurations at t ≈ 0.80 and 0.95 s. radau5 at 1e-8 and rkmk4 at dt = 1e-3 pass
    them on the parallelogram branch (θ1 + θ2 = π; since the projection iterates to the
    rounding floor radau5 no longer leaves it) and say that they stayed on it; replaying the
    rkmk4 run's states with the velocity reversed inside the first passage (a jump onto the
    other branch's motion) is reported as a branch switch, naming its time."""
    m, cm = four_bar()
    q0 = parallelogram_q(-0.05)
    T = 1.2
    qr, _ = parallelogram_reference(m, -0.05, 0.0, T)

    def model():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ModelNote)
            return PinocchioModel(m, q0=q0, constraints=[cm])
    for method, kw in (("radau5", dict(rtol=1e-8, atol=1e-8)), ("rkmk4", dict(dt=1e-3))):
        pm = model()
        with warnings.catch_warnings(record=True) as notes:
            warnings.simplefilter("always", ModelNote)
            r = simulate(pm, (0, T), method=method, **kw)
        assert r.success and abs(r.q[-1, 0] + r.q[-1, 1] - np.pi) < 1e-10            # on its branch
        assert not pm.branch_switches and len(pm.singular_passages) >= 2
        assert any(0.79 < t0 < 0.81 for t0, _ in pm.singular_passages)
        assert all("stayed continuous" in str(w.message) for w in notes)
        if method == "rkmk4":
            assert np.abs(r.q[-1] - qr).max() < 1e-8
    # the detector on a motion that jumps: the rkmk4 states replayed with V reversed from the
    # middle of the passage at t ≈ 0.8 on (a velocity discontinuity there)
    t0, t1 = next(p for p in pm.singular_passages if 0.79 < p[0] < 0.81)
    replay = model()
    replay.project_initial(r.q[0], r.V[0], 0.0)                    # a fresh run's bookkeeping
    with pytest.warns(ModelNote, match=r"between t = 0\.8.* switched branch"):
        for t, q, V in zip(r.t, r.q, r.V):
            replay.write_back(q, -V if t > 0.5 * (t0 + t1) else V, t)
    assert 0.79 < replay.branch_switches[0][0] < 0.81      # (the replayed q then no longer fit -V: more follow)