"""Pinocchio adapter, issue 12: constraint Jacobian and γ from Pinocchio's frame Jacobians
and accelerations, and generalized-α's iteration matrix from its RNEA derivatives.

References: central finite differences kept on the model (``_constraint_jacobian_fd``,
``_constraint_gamma_fd``) and of the model's own residual M̄ V̇ - Q̄ (+ Aᵀλ) built from
``mass_matrix`` and ``forces`` (CRBA and RNEA in twist coordinates), along the increments
of SO(3)xR³ (``_moved``)."""
import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from lgt_bridge.errors import InputError  # noqa: E402
from lgt_bridge.simulate import make_stepper, simulate  # noqa: E402
from lgt_pinocchio import PinocchioModel  # noqa: E402

from pinocchio_models import ball_chain  # noqa: E402

C3, C6 = pin.ContactType.CONTACT_3D, pin.ContactType.CONTACT_6D
PL = pin.SE3(pin.exp3(np.array([0.3, -0.2, 0.5])), np.array([0.1, 0.02, -0.05]))


def rel(X, Y):
    return np.abs(np.asarray(X) - Y).max() / max(np.abs(Y).max(), 1e-300)


def _constraint(model, q0, kind, j1, pl1, j2=0):
    """A constraint satisfied at q0: joint2's frame put where joint1's frame is."""
    d = model.createData()
    pin.forwardKinematics(model, d, q0)
    if j2 == 0:
        cm = pin.RigidConstraintModel(kind, model, j1, pl1, pin.LOCAL)
        cm.joint2_placement = d.oMi[j1] * pl1
        return cm
    return pin.RigidConstraintModel(kind, model, j1, pl1, j2, d.oMi[j2].inverse() * d.oMi[j1] * pl1, pin.LOCAL)


def random_state(model, seed, scale=1.0):
    """A configuration away from the neutral one, the same for the same seed."""
    dq = np.random.default_rng(seed).normal(size=model.nv) * scale
    return pin.integrate(model, pin.neutral(model), dq)


def sample_humanoid(seed=0):
    """pin.buildSampleModelHumanoidRandom with its random inertias and placements seeded."""
    pin.seed(seed)
    return pin.buildSampleModelHumanoidRandom()


def humanoid(kinds=("6D", "3D", "6D loop", "3D loop"), seed=0, **kw):
    """The sample humanoid at a random configuration: a foot on the ground (6-D), the other
    foot's point on it (3-D), the hands welded (6-D loop) or a hand point on the chest (3-D loop)."""
    m = sample_humanoid(seed)
    q0 = random_state(m, seed)
    j = m.getJointId
    spec = {"6D": (C6, j("lleg6_joint"), PL), "3D": (C3, j("rleg6_joint"), PL),
            "6D loop": (C6, j("larm6_joint"), PL, j("rarm6_joint")),
            "3D loop": (C3, j("rarm4_joint"), PL.inverse(), j("chest_joint"))}
    cms = [_constraint(m, q0, *spec[k]) for k in kinds]
    return PinocchioModel(m, q0=q0, constraints=cms, **kw)


def ball_chain_contact():
    """Free-flyer + spherical joint + hinge, the hinge link's point held in the world."""
    m = ball_chain()
    q0 = random_state(m, 2)
    return PinocchioModel(m, q0=q0, v0=np.zeros(m.nv),
                          constraints=[_constraint(m, q0, C3, m.getJointId("hinge"), PL)])


def pinned_body(kind):
    """A free body, a point of it pinned (3-D) or welded to the world (6-D)."""
    m = pin.Model()
    r = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    m.appendBodyToJoint(r, pin.Inertia(1.0, np.zeros(3), np.diag([1.0, 2.0, 3.0])), pin.SE3.Identity())
    q0 = random_state(m, 3)
    return PinocchioModel(m, q0=q0, constraints=[_constraint(m, q0, kind, r, PL)])


class FDConstraints(PinocchioModel):
    """The same model with A and γ by finite differences (the adapter's former A)."""

    def constraint_jacobian(self, q):
        return self._constraint_jacobian_fd(q)

    def constraint_gamma(self, q, V):
        return self._constraint_gamma_fd(q, V)


def consistent_velocity(pm, q, rng):
    A = pm.constraint_jacobian(q)
    V = rng.normal(size=pm.nv)
    for _ in range(2):
        V = V - np.linalg.pinv(A) @ (A @ V)
    return V


# --- 1. constraints without finite differences ---------------------------------------------
CONSTRAINED = {"humanoid_all_kinds": humanoid, "ball_chain_contact": ball_chain_contact,
               "pinned_body_3d": lambda: pinned_body(C3), "pinned_body_6d": lambda: pinned_body(C6)}


@pytest.mark.parametrize("case", list(CONSTRAINED))
def test_jacobian_and_gamma_against_finite_differences(case):
    """At q0 (g = 0) and at configurations off the constraints (g ≠ 0: the Jlog3 factor and
    its derivative in the 6-D rows matter there), with velocities that violate A V = 0."""
    pm = CONSTRAINED[case]()
    rng = np.random.default_rng(7)
    for scale in (0.0, 0.3, 0.8):
        q = pm._moved(pm.q0, rng.normal(size=pm.nv) * scale)
        V = rng.normal(size=pm.nv) * 2
        assert rel(pm.constraint_jacobian(q), pm._constraint_jacobian_fd(q)) < 1e-7
        assert rel(pm.constraint_gamma(q, V), pm._constraint_gamma_fd(q, V)) < 1e-7
        if scale:
            assert np.abs(pm.constraints(q)).max() > 1e-2


@pytest.mark.parametrize("case", [c for c in CONSTRAINED if c != "pinned_body_6d"])   # (it cannot move)
def test_gamma_is_pinocchios_constraint_acceleration(case):
    """Pinocchio's constraintDynamics (what f runs) imposes A V̇ + γ = 0 at consistent states."""
    pm = CONSTRAINED[case]()
    rng = np.random.default_rng(8)
    V = consistent_velocity(pm, pm.q0, rng) * 3
    gam = pm.constraint_gamma(pm.q0, V)
    assert np.abs(gam).max() > 1e-1
    assert np.abs(pm.constraint_jacobian(pm.q0) @ pm.f(pm.q0, V, 0.0) + gam).max() < 1e-10 * np.abs(gam).max()


@pytest.mark.filterwarnings("ignore:the initial state")     # V0 is consistent to 1e-9 with the FD A
def test_dopri5_holds_the_loop_and_agrees_with_the_finite_difference_model():
    """The humanoid standing on one foot (6-D contact) with its hands welded (6-D loop),
    under gravity; the projection after each step uses A (each model its own)."""
    kinds = ("6D", "6D loop")
    pm, pf = humanoid(kinds), humanoid(kinds)
    pf.__class__ = FDConstraints
    V0 = consistent_velocity(pm, pm.q0, np.random.default_rng(9))
    runs = [simulate(m, (0, 0.2), method="dopri5", rtol=1e-9, atol=1e-9, V0=V0) for m in (pm, pf)]
    assert all(r.success for r in runs)
    for m, r in zip((pm, pf), runs):                     # every step (projected), t_eval off
        assert max(np.abs(pm.constraints(q)).max() for q in r.q) < 1e-10
        assert max(np.abs(m.constraint_jacobian(q) @ V).max() for q, V in zip(r.q, r.V)) < 1e-12
    assert runs[0].t[-1] == runs[1].t[-1] == 0.2
    assert np.abs(runs[0].q[-1] - runs[1].q[-1]).max() < 1e-8
    assert np.abs(runs[0].q[-1] - runs[0].q[0]).max() > 1e-2             # it moved


# --- 2. the iteration matrix ----------------------------------------------------------------
def pd_humanoid(kp=1e3, fext=False, seed=1):
    """The sample humanoid under a PD controller toward the neutral pose (root unactuated),
    a time-dependent feed-forward term, and optionally state-dependent external forces."""
    m = sample_humanoid(seed)
    rng = np.random.default_rng(seed)
    qref = pin.neutral(m)
    kpv, kdv = kp * (1 + rng.random(m.nv)), 0.1 * kp * (1 + rng.random(m.nv))
    kpv[:6] = kdv[:6] = 0.0

    def tau(t, q, v):
        return kpv * pin.difference(m, q, qref) - kdv * v + np.sin(3 * t) * q[7:].sum()

    def forces(t, q, v):
        return [pin.Force(np.array([q[0], 0.3, v[2]]), np.array([0.1, v[1] * q[4], 0.3])) for _ in range(m.njoints)]
    return PinocchioModel(m, q0=random_state(m, seed), tau=tau, fext=forces if fext else None)


def residual_fd(pm, q, V, Vd, t, lam=None, eps=1e-6):
    """(C_t, K_t) by central differences of M̄(q) V̇ - Q̄(q, V, t) (+ A(q)ᵀλ)."""
    def res(q, V):
        r = pm.mass_matrix(q) @ Vd - pm.forces(q, V, t)
        return r if lam is None else r + pm.constraint_jacobian(q).T @ lam
    C, K = np.empty((pm.nv, pm.nv)), np.empty((pm.nv, pm.nv))
    for k in range(pm.nv):
        e = np.zeros(pm.nv)
        e[k] = eps
        K[:, k] = (res(pm._moved(q, e), V) - res(pm._moved(q, -e), V)) / (2 * eps)
        C[:, k] = (res(q, V + e) - res(q, V - e)) / (2 * eps)
    return C, K


ITERATION = {"pd_humanoid": pd_humanoid, "pd_humanoid_fext": lambda: pd_humanoid(fext=True),
             "ball_chain": lambda: PinocchioModel(ball_chain(), q0=pin.neutral(ball_chain()),
                                                  tau=lambda t, q, v: -3.0 * v + np.cos(q[:9]).sum())}


@pytest.mark.parametrize("case", list(ITERATION))
@pytest.mark.parametrize("at", ["solution", "any_acceleration"])
def test_iteration_matrix_against_finite_differences_of_the_residual(case, at):
    """M̄, C_t = ∂R/∂V and K_t = ∂R/∂z of R = M̄ V̇ - Q̄, at the acceleration the model
    computes itself (f's: R = 0) or at a given V̇ (then (∂Tᵀ/∂z) R enters as well)."""
    pm = ITERATION[case]()
    rng = np.random.default_rng(4)
    q = pm._moved(pm.q0, rng.normal(size=pm.nv) * 0.5)
    V, t = rng.normal(size=pm.nv) * 2, 0.3
    Vd = pm.f(q, V, t) if at == "solution" else rng.normal(size=pm.nv) * 3
    kw = {} if at == "solution" else {"Vdot": Vd}
    M = pm.iteration_matrix(q, V, t, 1.0, 0.0, 0.0, **kw)
    C = pm.iteration_matrix(q, V, t, 0.0, 1.0, 0.0, **kw)
    K = pm.iteration_matrix(q, V, t, 0.0, 0.0, 1.0, **kw)
    Cf, Kf = residual_fd(pm, q, V, Vd, t)
    assert rel(M, pm.mass_matrix(q)) < 1e-12
    assert rel(C, Cf) < 1e-6 and rel(K, Kf) < 1e-6
    assert rel(pm.iteration_matrix(q, V, t, 2.0, -3.0, 5.0, **kw), 2 * M - 3 * C + 5 * K) < 1e-14


def test_iteration_matrix_with_constraint_forces():
    """Given λ: V̇ = M̄⁻¹(Q̄ - Aᵀλ) and the geometric stiffness ∂(Aᵀλ)/∂z."""
    pm = humanoid(("6D", "3D loop"), tau=lambda t, q, v: -10.0 * v)
    rng = np.random.default_rng(5)
    q = pm._moved(pm.q0, rng.normal(size=pm.nv) * 0.3)
    V, lam, t = rng.normal(size=pm.nv), rng.normal(size=pm.n_constraints) * 10, 0.1
    Vd = np.linalg.solve(pm.mass_matrix(q), pm.forces(q, V, t) - pm.constraint_jacobian(q).T @ lam)
    Cf, Kf = residual_fd(pm, q, V, Vd, t, lam)
    assert rel(pm.iteration_matrix(q, V, t, 0.0, 1.0, 0.0, lam=lam), Cf) < 1e-6
    assert rel(pm.iteration_matrix(q, V, t, 0.0, 0.0, 1.0, lam=lam), Kf) < 1e-6


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_genalpha_takes_the_analytic_path_and_its_matrix_is_the_residuals_jacobian(group):
    """Generalized-α's whole Newton matrix, assembled from the model's M, C_t, K_t, against
    central differences of its own residual at the solution of a step."""
    pm = pd_humanoid()
    h = 1e-3
    ga, _ = make_stepper(pm, "genalpha", group, "exp", dt=h)
    assert ga.analytic
    ga.set_state(pm.q0, pm.V0)
    t = 0.0
    for _ in range(3):
        ga.attempt(t, h)
        t += h
    snap = (ga.q.copy(), ga.V.copy(), ga.W.copy(), ga.Wd.copy(), ga.a.copy(), ga.lam.copy(), ga._prev)
    ga.attempt(t, h)
    Wd1, lam = ga.Wd.copy(), ga.lam.copy()
    q, V, W, ga.Wd, ga.a, ga.lam, ga._prev = snap
    ga.set_state(q, V, W)
    J = ga.iteration_matrix(Wd1, lam, t + h, h)
    Jf = np.empty_like(J)
    for j in range(len(Wd1)):
        e = 1e-4 * max(1.0, abs(Wd1[j]))
        Wp, Wm = Wd1.copy(), Wd1.copy()
        Wp[j] += e
        Wm[j] -= e
        Jf[:, j] = (ga.residual(Wp, lam, t + h, h) - ga.residual(Wm, lam, t + h, h)) / (2 * e)
    assert rel(J, Jf) < 1e-6, rel(J, Jf)


def stiff_pd_quadruped(kp=1e4):
    """A free-flying trunk with four two-link legs of small inertia under stiff PD control
    (kd = 2√(kp M_ii)): closed-loop eigenvalues down to ≈ -1.8e4 1/s (rkmk4 needs dt < 1.5e-4)."""
    m = pin.Model()
    root = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    m.appendBodyToJoint(root, pin.Inertia(5.0, np.zeros(3), np.diag([0.05, 0.1, 0.12])), pin.SE3.Identity())
    for k, (x, y) in enumerate([(0.2, 0.1), (0.2, -0.1), (-0.2, 0.1), (-0.2, -0.1)]):
        hip = m.addJoint(root, pin.JointModelRY(), pin.SE3(np.eye(3), np.array([x, y, 0.0])), f"hip{k}")
        m.appendBodyToJoint(hip, pin.Inertia(0.2, np.array([0, 0, -0.1]), np.diag([1e-3, 1e-3, 1e-4])), pin.SE3.Identity())
        knee = m.addJoint(hip, pin.JointModelRY(), pin.SE3(np.eye(3), np.array([0, 0, -0.2])), f"knee{k}")
        m.appendBodyToJoint(knee, pin.Inertia(0.1, np.array([0, 0, -0.1]), np.diag([5e-4, 5e-4, 5e-5])), pin.SE3.Identity())
    qref = pin.neutral(m)
    d = m.createData()
    M = pin.crba(m, d, qref)
    kpv = np.full(m.nv, kp)
    kpv[:6] = 0.0
    kdv = 2.0 * np.sqrt(kpv * np.diag(M))

    def tau(t, q, v):
        return kpv * pin.difference(m, q, qref) - kdv * v
    rng = np.random.default_rng(0)
    dq = rng.normal(size=m.nv) * 0.2
    dq[:6] = 0.0
    return PinocchioModel(m, tau=tau, q0=pin.integrate(m, qref, dq), v0=rng.normal(size=m.nv) * 0.5), qref


@pytest.mark.filterwarnings("ignore::RuntimeWarning")       # rkmk4's overflow as it diverges
def test_genalpha_is_stable_on_stiff_pd_control_where_rkmk4_is_not():
    """At dt = 4e-3 (h λ ≈ -70 on the stiffest mode) rkmk4 diverges; generalized-α on the
    analytic matrix runs through and the joints settle on their targets (free fall: no
    internal loads). Fewer f evaluations than with the matrix by
    finite differences of the step, and the same solution."""
    pm, qref = stiff_pd_quadruped()
    T, dt = 0.5, 4e-3
    assert not simulate(pm, (0, T), method="rkmk4", dt=dt, t_eval=[T]).success
    r = simulate(pm, (0, T), method="genalpha", dt=dt, t_eval=[T])
    assert r.success and np.isfinite(r.q).all()
    assert np.abs(pin.difference(pm.model, r.q[-1], qref)[6:]).max() < 1e-3
    pf, _ = stiff_pd_quadruped()
    pf.iteration_matrix = None                                # generalized-α's finite differences
    rf = simulate(pf, (0, T), method="genalpha", dt=dt, t_eval=[T])
    assert rf.success and r.stats["n_f"] < rf.stats["n_f"]
    assert np.abs(r.q[-1] - rf.q[-1]).max() < 1e-6


def test_genalpha_on_a_constrained_humanoid_with_the_analytic_matrix():
    """Standing on one foot with welded hands: the analytic matrix (with the geometric
    stiffness from λ) keeps the index-3 constraints to rounding and agrees with dopri5."""
    pm = humanoid(("6D", "6D loop"), tau=lambda t, q, v: -20.0 * v)
    T = 0.1
    ref = simulate(pm, (0, T), method="dopri5", rtol=1e-10, atol=1e-10, t_eval=[T])
    errs = []
    for dt in (4e-3, 2e-3):
        r = simulate(pm, (0, T), method="genalpha", dt=dt, t_eval=[T])
        assert r.success and r.stats["constraint_residual"] < 1e-10
        errs.append(np.abs(pin.difference(pm.model, r.q[-1], ref.q[-1])).max())
    assert errs[1] < errs[0] < 1e-2 and errs[0] / errs[1] > 3          # second order


def _pd_with_derivatives(m, seed=2):
    """A joint-space PD controller on the sample humanoid with its Jacobians, and a counter
    of its calls."""
    from lgt_pinocchio.baselines import pd_torque
    rng = np.random.default_rng(seed)
    tau = pd_torque(m, random_state(m, seed + 1), 200.0 * (1 + rng.random(m.nv - 6)), 5.0 + rng.random(m.nv - 6))
    calls = [0]

    def counted(t, q, v):
        calls[0] += 1
        return tau(t, q, v)
    return counted, tau.derivatives, calls


def test_tau_derivatives_give_the_differenced_iteration_matrix():
    """The controller's own Jacobians replace its forward differences: the same M̄, C_t, K_t
    (to the differences' error), and generalized-α takes the same steps to the same answer
    with 2 nv fewer controller calls per matrix."""
    m = sample_humanoid(3)
    q0 = random_state(m, 3)
    tau, dtau, calls = _pd_with_derivatives(m)
    fd = PinocchioModel(m, q0=q0, tau=tau)
    an = PinocchioModel(m, q0=q0, tau=tau, tau_derivatives=dtau)
    V, t = np.random.default_rng(0).normal(size=fd.nv), 0.1
    for c in ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)):
        A, F = an.iteration_matrix(q0, V, t, *c), fd.iteration_matrix(q0, V, t, *c)
        assert rel(A, F) < 1e-6
    runs = []
    for pm in (fd, an):
        calls[0] = 0
        r = simulate(pm, (0.0, 0.1), method="genalpha", group="SO3xR3", dt=4e-3)
        assert r.success, r.message
        runs.append((r, calls[0]))
    (r_fd, n_fd), (r_an, n_an) = runs
    assert r_an.stats["n_steps"] == r_fd.stats["n_steps"]
    assert np.abs(r_an.q[-1] - r_fd.q[-1]).max() < 1e-8
    assert n_an <= n_fd - 2 * fd.nv * r_an.stats["n_jacobians"]


@pytest.mark.parametrize("bad, words", [
    (lambda t, q, v: np.zeros((3, 3)), "pair"),
    (lambda t, q, v: (np.zeros((3, 3)), np.zeros((3, 3))), "shapes"),
    (lambda t, q, v: (np.full((32, 32), np.nan), np.zeros((32, 32))), "finite"),
    (lambda t, q: None, "signature|tau_derivatives"),
])
def test_bad_tau_derivatives_are_refused_before_any_step(bad, words):
    m = sample_humanoid(3)
    tau, _, _ = _pd_with_derivatives(m)
    assert m.nv == 32
    with pytest.raises(InputError, match=words):
        PinocchioModel(m, q0=random_state(m, 3), tau=tau, tau_derivatives=bad)
    with pytest.raises(InputError, match="not a callable"):
        PinocchioModel(m, tau=np.zeros(m.nv), tau_derivatives=lambda t, q, v: None)


def test_radau5_on_stiff_pd_control_and_on_a_constrained_humanoid():
    """radau5 (implicit, order 5) on the stiff quadruped (|λ| up to ≈ 1.8e4 1/s) against dop853
    at 1e-12, at a fraction of dopri5's evaluations at the same tolerance (measured 1166 f and
    4.7e-9 against 6951 f and 1.0e-8); and on the constrained humanoid (its f solves for the
    contact forces, so its Jacobian is differenced; the projection keeps the constraints)
    against dopri5."""
    pm, _ = stiff_pd_quadruped()
    T = 0.2
    ref = simulate(pm, (0, T), method="dop853", rtol=1e-12, atol=1e-12, t_eval=[T])
    r = simulate(pm, (0, T), method="radau5", rtol=1e-6, atol=1e-6, t_eval=[T])
    e = simulate(pm, (0, T), method="dopri5", rtol=1e-6, atol=1e-6, t_eval=[T])
    assert r.success and r.stats["n_f"] < 0.25 * e.stats["n_f"], (r.stats, e.stats)
    assert np.abs(pin.difference(pm.model, r.q[-1], ref.q[-1])).max() < 5e-8
    hm = humanoid(("6D", "6D loop"), tau=lambda t, q, v: -20.0 * v)
    ref = simulate(hm, (0, 0.1), method="dopri5", rtol=1e-11, atol=1e-11, t_eval=[0.1])
    r = simulate(hm, (0, 0.1), method="radau5", rtol=1e-8, atol=1e-8, t_eval=[0.1])
    assert r.success and r.stats["constraint_after_projection"] < 1e-10
    assert np.abs(pin.difference(hm.model, r.q[-1], ref.q[-1])).max() < 1e-6
