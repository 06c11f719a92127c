"""The extremes suite (lgt_bridge.extremes): each case against an independent reference."""
import mpmath
import numpy as np
import pytest

from lgt_bridge import extremes, lgt, scenes
from lgt_bridge.analytic import torque_free_omega
from lgt_bridge.groups import se3, so3

EPS = np.finfo(float).eps


def _mp_reference(H_k, X, group):
    """α(q_k)·exp(X̂) with a 40-digit matrix exponential (mpmath; local precision, so the
    other mpmath tests keep theirs)."""
    with mpmath.workdps(40):
        if group == "SE3":
            E = mpmath.expm(mpmath.matrix(se3.hat6(X).tolist()))
            return H_k @ np.array(E.tolist(), dtype=float)
        E = np.array(mpmath.expm(mpmath.matrix(so3.hat(X[:3]).tolist())).tolist(),
                     dtype=float)
    H = H_k.copy()
    H[:3, :3] = H_k[:3, :3] @ E
    H[:3, 3] += X[3:]
    return H


def test_update_accuracy_from_1e_12_to_beyond_2pi_against_mpmath():
    rows = extremes.update_accuracy(_mp_reference)
    assert {r["step_angle"] for r in rows} >= {1e-12, np.pi - 1e-9, np.pi, np.pi + 1e-9, 2 * np.pi + 0.5}
    for r in rows:
        bound = 10 * EPS * max(1.0, r["step_angle"]) * r["conditioning"]
        assert r["rotation_error"] <= bound, r
        assert r["position_error"] <= 4 * bound, r


def test_cayley_near_a_half_turn_raises_fixed_and_shrinks_adaptive():
    rows = extremes.cayley_half_turn()
    fixed = {r["step_angle"]: r for r in rows if r["case"].startswith("rkmk4")}
    assert fixed[2.5]["outcome"] == "ChartDomainError" and "half-turn" in fixed[2.5]["message"]
    assert fixed[0.5]["outcome"] == "completed" and fixed[0.5]["rotation_error"] < 1e-3
    ad = rows[-1]
    assert ad["outcome"] == "completed" and ad["rejected"] > 0
    assert ad["max_step_angle"] < 2 * np.arctan(0.5) * 2 and ad["rotation_error"] < 1e-7


def test_tait_bryan_through_the_lock_and_rotation_vector_through_2pi_match_quaternions():
    tb, rv = extremes.singular_coordinates()
    assert tb["success"] and tb["lock_passes"] >= 1 and tb["closest_to_lock_rad"] < 5e-3
    assert tb["max_rotation_difference"] < 1e-10
    assert rv["success"] and rv["turns"] > 3 and rv["max_rotation_difference"] < 1e-10


def test_spin_1e3_and_inertia_ratio_1e6_against_the_analytic_solution():
    rows = {(r["case"][:5], r["method"]): r for r in extremes.spin_rows() + extremes.inertia_rows()}
    assert rows[("spin ", "dopri5")]["omega_rel_error"] < 1e-8
    assert rows[("spin ", "rkmk4")]["omega_rel_error"] < 1e-5 and rows[("spin ", "rkmk4")]["energy_drift"] < 1e-6
    assert rows[("inert", "dopri5")]["omega_rel_error"] < 1e-7
    assert rows[("inert", "dopri5")]["momentum_drift"] < 1e-10
    bad = rows[("inert", "rkmk4")]                       # ω·dt = 32 on the wobble: beyond RK4's limit
    assert not bad["success"] and "non-finite" in bad["message"]
    ga = rows[("inert", "genalpha")]
    assert ga["success"] and ga["energy_drift"] < 1e-6 and ga["momentum_drift"] < 1e-8


def test_stiff_springs_genalpha_stable_explicit_reported_unstable():
    rows = {r["method"]: r for r in extremes.spring_rows(T=0.01)}
    assert rows["genalpha"]["success"] and rows["genalpha"]["energy_ratio"] <= 1.0   # no growth
    for m in ("rkmk4", "euler"):                          # reported, never a silent 1e200
        assert not rows[m]["success"] and ("non-finite" in rows[m]["message"]
                                           or "stability limit" in rows[m]["message"]), rows[m]
    assert rows["dopri5"]["success"] and abs(rows["dopri5"]["energy_ratio"] - 1) < 1e-3


def test_spring_iteration_matrix_is_the_derivative_of_the_forces():
    """K_t of the scene's springs against central differences of -Q along τ (SO(3)xR³)."""
    rng = np.random.default_rng(3)
    J = np.diag([0.1, 0.2, 0.3])
    q0 = np.concatenate([rng.normal(size=3), [1, 0, 0, 0], rng.normal(size=3), [0.8, 0.6, 0, 0]])
    m = scenes.RigidBodySystem([1.0, 2.0], [J, 2 * J], q0, np.zeros(12), gravity=np.zeros(3),
                               springs=[(0, np.array([0.1, 0.2, 0]), -1, np.array([0.3, 0, 0.1]), 7.0, 0.0),
                                        (0, np.array([-0.1, 0.05, 0.2]), 1, np.array([0.2, -0.1, 0.3]), 5.0, 0.0)])
    L = lgt.LGT("quat", "SO3xR3", "exp")

    def Q(z):
        q = np.concatenate([L.tau(q0[None, :7], z[None, :6])[0], L.tau(q0[None, 7:], z[None, 6:])[0]])
        return m.forces(q, np.zeros(12), 0.0)
    e = 1e-6
    K = np.array([-(Q(e * u) - Q(-e * u)) / (2 * e) for u in np.eye(12)]).T
    np.testing.assert_allclose(m._spring_matrix(q0, 0.0, 1.0), K, atol=1e-8 * np.abs(K).max())


@pytest.mark.slow
def test_a_million_updates_keep_the_quaternion_unit_without_renormalization():
    """10⁶ steps of the update the integrators apply (τ from a prepared base, SO(3)xR³/exp,
    increments of the torque-free motion at dt = 1e-3): ‖Q‖ - 1 ≤ 1e-13."""
    L = lgt.LGT("quat", "SO3xR3", "exp")
    J, w0, dt, n = (1.0, 2.0, 3.0), (0.3, 2.0, 0.1), 1e-3, 1_000_000
    w = torque_free_omega(np.arange(1000) * dt, J, w0)          # a period's worth of increments
    X = np.zeros((len(w), 1, 6))
    X[:, 0, :3] = w * dt
    q = np.array([[0.0, 0, 0, 1, 0, 0, 0]])
    worst = 0.0
    for k in range(n):
        q = L.tau_at(L.base(q), X[k % 1000])
        if k % 50_000 == 0:
            worst = max(worst, abs(np.linalg.norm(q[0, 3:]) - 1))
    worst = max(worst, abs(np.linalg.norm(q[0, 3:]) - 1))
    assert worst <= 1e-13, worst


def test_integrator_long_run_norm_and_energy():
    rows = {r["method"]: r for r in extremes.long_run(20_000, methods=("euler", "rkmk4"))}
    for r in rows.values():
        assert r["steps"] == 20_000 and r["quat_norm_error"] <= 3e-14
    assert rows["rkmk4"]["energy_drift"] < 1e-12 < 1e-3 < rows["euler"]["energy_drift"]


def test_failed_steps_keep_every_earlier_step():
    nan, newton = extremes.failed_steps()
    assert not nan["success"] and nan["steps_kept"] == 49 and nan["t_last"] == pytest.approx(0.49)
    assert "non-finite" in nan["message"]
    assert not newton["success"] and newton["steps_kept"] == 6 and newton["t_last"] == pytest.approx(0.3)
    # the failing step was halved down to min_step before the run gave up
    assert "Newton" in newton["message"] and "halving the step" in newton["message"]


def _switched_top(t_switch):
    """The heavy top with a force switched on at t_switch (``np.heaviside(t - t_switch, 1)``)."""
    m = scenes.heavy_top(False)
    f0 = m.f

    def f(q, V, t):
        out = np.array(f0(q, V, t), float)
        if t >= t_switch:
            out[0] += 1e5
        return out
    m.f = f
    return m


@pytest.mark.parametrize("loop", [True, False])
@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_a_load_switched_at_the_end_time_ends_the_run_at_its_left_limit(method, loop, monkeypatch):
    """A force switched on exactly at the end time: each step landing on the end time has a
    stage there, so at a tight tolerance the steps collapse below min_step just before the
    end. The motion up to the end time does not depend on f at that instant: the run takes
    its last step to the double below the end time and ends there, at the state of the same
    top without the switch (an independent run at a tighter tolerance), reporting the jump.
    The compiled step loop and the Python one do the same. A run continued past the end time
    starts on the far side of the jump, as a fresh run from that state does."""
    from lgt_bridge import Simulation
    monkeypatch.setattr(Simulation, "_use_loop", loop)
    sim = Simulation(_switched_top(1.0), method=method, rtol=1e-10, atol=1e-10, min_step=1e-8)
    r = sim.run(1.0, t_eval=[0.5, 1.0])
    assert r.success, r.message
    assert r.t[-1] == 1.0 and r.stats["end_jump"] == pytest.approx(1e5)
    ref = Simulation(scenes.heavy_top(False), method="dop853", rtol=1e-12, atol=1e-12).run(1.0, t_eval=[1.0])
    assert np.abs(r.q[-1] - ref.q[-1]).max() < 1e-8
    assert np.abs(r.V[-1] - ref.V[-1]).max() < 1e-7
    on = sim.run(1.001, t_eval=[1.001])
    fresh = Simulation(_switched_top(1.0), method=method, rtol=1e-10, atol=1e-10, t0=1.0,
                       q0=r.q[-1], V0=r.V[-1]).run(1.001, t_eval=[1.001])
    assert on.success and np.abs(on.V[-1] - fresh.V[-1]).max() < 1e-6


def test_a_load_switched_inside_the_run_still_collapses_the_steps_where_it_is():
    """The same switch inside the run (t = 0.5003) collapses the steps at this tolerance where
    it is: the run stops there, and its message makes no claim about the end time."""
    from lgt_bridge import Simulation
    sim = Simulation(_switched_top(0.5003), method="dopri5", rtol=1e-10, atol=1e-10, min_step=1e-8)
    r = sim.run(1.0, t_eval=[1.0])
    assert not r.success and "below min_step" in r.message
    assert "end time" not in r.message and 0.5002 < sim.t < 0.5003
