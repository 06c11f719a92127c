"""Explicit adaptive pairs on a mildly stiff model (a PD-controlled robot's situation), run
in one go and as consecutive short horizons (model-predictive control): the steps do not
grow past the stiffest mode's stability limit, the horizons cost about what one run costs,
and both reach the analytic solution. And an adaptive run's last stretch to a target in
equal steps.

The model: a free asymmetric body whose centre of mass hangs on a zero-length
spring-damper to the origin (k = 1e4, c = 1e3, m = 1; no gravity). Its translation is
x'' + c x' + k x = 0 per axis, overdamped: rates λ = -989.9 (stiff) and -10.1 1/s; its
rotation is torque-free (the spring acts at the centre of mass): both analytic."""
import math

import numpy as np
import pytest

from lgt_bridge import Simulation, scenes, simulate
from lgt_bridge.analytic import torque_free_omega

K, C = 1e4, 1e3
R0, V0 = np.array([0.01, -0.02, 0.005]), np.array([0.1, 0.0, 0.0])
J, W0 = (1.0, 2.0, 3.0), (0.01, 2.0, 0.01)
L_FAST, L_SLOW = (-C - math.sqrt(C * C - 4 * K)) / 2, (-C + math.sqrt(C * C - 4 * K)) / 2
T, H = 0.5, 0.02


def damped_body():
    fb = scenes.free_body(J, W0, r0=R0, v0=V0)
    z = np.zeros(3)
    return scenes.RigidBodySystem([1.0], [np.diag(J)], fb.q0, fb.V0, gravity=z, springs=[(0, z, -1, z, K, C)])


def exact(t):
    """(centre of mass, ω) at t: the overdamped oscillator per axis, Euler's torque-free body."""
    a = (V0 - L_SLOW * R0) / (L_FAST - L_SLOW)
    x = a * math.exp(L_FAST * t) + (R0 - a) * math.exp(L_SLOW * t)
    return x, torque_free_omega(np.array([t]), J, W0)[0]


def _errors(q, V):
    x, w = exact(T)
    return np.abs(q[:3] - x).max(), np.abs(V[:3] - w).max()


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_consecutive_horizons_at_the_stability_limit_cost_about_one_run(method):
    """25 horizons of 20 ms carrying the state: the steps sit at the explicit method's
    stability limit (h|λ| ≈ 6.1 for dop853, 3.3 for dopri5: 3 to 6 steps a horizon) and
    the step carried into a horizon is not one the stiff mode rejects (before the cap, a
    step grown on a horizon's short landing steps: 23 and 27 rejected steps here, about
    one a horizon); the f count within 15 % of one run's, and the same accuracy as one
    run against the analytic solution."""
    tol = 1e-6
    one = simulate(damped_body(), (0, T), method=method, group="SO3xR3", rtol=tol, atol=tol, t_eval=[T])
    sim = Simulation(damped_body(), method=method, group="SO3xR3", rtol=tol, atol=tol)
    for k in range(1, 26):
        r = sim.run(H * k, t_eval=[H * k])
        assert r.success and r.t[-1] == pytest.approx(H * k)
    assert sim.stepper.n_rejected <= 5
    assert sim.stepper.prob.n_f <= 1.15 * one.stats["n_f"]
    for q, V in ((sim.q, sim.V), (one.q[-1], one.V[-1])):
        ex, ew = _errors(q, V)
        assert ex < 1e-2 * tol and ew < 1e-10


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_steps_do_not_grow_past_the_measured_stability_limit(method):
    """After every accepted step the next proposal is at most the longer of that step and
    the stepper's stability limit (bound/ρ, ρ the stiffest rate its steps measured), and
    the steps of the second half sit at the analytic limit bound/|λ_fast| (the cap neither
    holds them below it nor lets them run past it)."""
    sim = Simulation(damped_body(), method=method, group="SO3xR3", rtol=1e-6, atol=1e-6)
    st, steps, last = sim.stepper, [], [0.0]

    def hook(t, q, V):
        h = t - last[0]
        last[0] = t
        steps.append((t, h))
        assert sim.h <= max(h, st.h_stable) * (1 + 1e-12)
    sim.advance_to(T, on_step=hook)
    assert math.isfinite(st.h_stable)
    t, h = np.array(steps).T
    hl = h[(t > T / 2) & (t < T - 4 * h.max())] * -L_FAST / st.stability_bound
    assert 0.9 < np.median(hl) < 1.3 and hl.max() < 2.0
    assert st.n_rejected <= 0.1 * len(h)


@pytest.mark.parametrize("n", [2.5, 3.5])
def test_the_last_stretch_to_a_target_takes_equal_steps(n):
    """Up to ``landing_steps`` (4 for the explicit pairs) steps of the proposal before a
    target: that many equal steps, no sliver (before: full steps, then the last two shared
    what was left). The model above, its steps steady at the stability limit by then."""
    sim = Simulation(damped_body(), method="dop853", group="SO3xR3", rtol=1e-6, atol=1e-6)
    sim.run(T / 2)
    h = sim.h
    d = np.diff(sim.run(sim.t + n * h).t)
    assert len(d) == math.ceil(n) and np.ptp(d) < 1e-9 * h
