"""An explicit method on a model whose stability limit needs far more steps than the run can
afford stops early, naming the step that limit allows (checked against the stability region
of DOPRI5's own stability polynomial along the stiff mode's analytic eigenvalue), and keeps
every step it took; runs it can afford run through.

The model: a free asymmetric body whose centre of mass hangs on a zero-length spring-damper
to the origin (stiffness k, damping c, mass 1; no gravity): its translation is
x'' + c x' + k x = 0 per axis, with eigenvalues the roots of λ² + cλ + k."""
import math
import re

import numpy as np
import pytest

from lgt_bridge import Simulation, scenes, simulate
from lgt_bridge.integrators.stability import ray_bound
from lgt_bridge.integrators.tableaux import DOPRI5

R0, V0 = np.array([0.01, -0.02, 0.005]), np.array([0.1, 0.0, 0.0])
J, W0 = (1.0, 2.0, 3.0), (0.01, 2.0, 0.01)

#: DOPRI5's stability function (Hairer-Wanner I, II.4 and IV.2): R(z) = Σ_{k≤5} z^k/k! + z⁶/600
DOPRI5_R = [1.0, 1.0, 1 / 2, 1 / 6, 1 / 24, 1 / 120, 1 / 600]


def body(k, c):
    fb = scenes.free_body(J, W0, r0=R0, v0=V0)
    z = np.zeros(3)
    return scenes.RigidBodySystem([1.0], [np.diag(J)], fb.q0, fb.V0, gravity=z, springs=[(0, z, -1, z, k, c)])


def stiff_eigenvalue(k, c):
    """The eigenvalue of largest modulus of x'' + c x' + k x = 0 (upper half plane)."""
    lam = np.roots([1.0, c, k])
    lam = lam[np.argmax(np.abs(lam))]
    return complex(lam.real, abs(lam.imag))


def dopri5_limit(lam):
    """The step DOPRI5 allows for the eigenvalue λ: the smallest r > 0 with |R(r d)| = 1,
    d = λ/|λ|, as the smallest positive root of the polynomial |R(r d)|² - 1 in r."""
    d = lam / abs(lam)
    p = np.array([a * d ** k for k, a in enumerate(DOPRI5_R)])[::-1]      # R(r d), highest first
    sq = np.polymul(p, np.conj(p)).real
    sq[-1] -= 1.0
    r = np.roots(sq)
    r = r[(abs(r.imag) < 1e-9) & (r.real > 1e-6)].real
    return float(r.min()) / abs(lam)


def reported_h(message):
    return float(re.search(r"stability limit, h ≈ ([0-9.e+-]+) s", message).group(1))


def test_dopri5s_stability_polynomial_and_ray_bound():
    """The stability polynomial taken from the tableau is DOPRI5's, and the boundary along a
    ray is the root of |R|² = 1 (3.3066 on the negative real axis, 0.9972 on the imaginary)."""
    from lgt_bridge.integrators.stability import stability_polynomial
    c = stability_polynomial(DOPRI5)
    assert np.allclose(c[:7], DOPRI5_R, rtol=1e-12, atol=1e-15) and np.allclose(c[7:], 0.0, atol=1e-15)
    for lam in (-1.0 + 0j, -1.0 + 3.0j, -0.02 + 1.0j, 1j):
        assert ray_bound(DOPRI5, lam) == pytest.approx(dopri5_limit(lam) * abs(lam), rel=1e-6)
    assert dopri5_limit(-1.0 + 0j) == pytest.approx(3.3066, abs=1e-4)


def test_dopri5_on_an_overdamped_stiff_spring_stops_with_the_stability_limit():
    """k = 1e6, c = 1e5: λ ≈ -1e5 1/s, DOPRI5's limit 3.31e-5 s; over 1000 s the run needs
    about 3e7 steps against max_steps = 1e6. It stops after at most 2000 steps, naming the
    limit (within 2 % of the analytic one), the steps needed and the advice, with every step
    taken in the result."""
    k, c = 1e6, 1e5
    r = simulate(body(k, c), (0, 1000.0), method="dopri5", group="SO3xR3", rtol=1e-6, atol=1e-8)
    assert not r.success and r.stats["n_steps"] <= 2000
    assert len(r.t) == r.stats["n_steps"] + 1 and np.isfinite(r.q[-1]).all()
    assert "stability limit" in r.message and "method='radau5' or method='genalpha'" in r.message
    assert "would need about" in r.message and "max_steps = 1000000" in r.message
    lam = stiff_eigenvalue(k, c)
    assert reported_h(r.message) == pytest.approx(dopri5_limit(lam), rel=0.02)


def test_dopri5_on_a_lightly_damped_stiff_spring_is_told_by_the_jacobian():
    """k = 1e8, c = 400: λ = -200 ± 9998i, an oscillation with damping ratio 0.02, where
    DOPRI5's stability region is narrow (|hλ| ≤ 2.07 along that ray; Hairer's real-axis test,
    h·ρ > 3.25, misjudges it). Once the mode has decayed (0.2 s) the steps sit there; run on
    to 1000 s (5e6 steps at that limit), the run stops at the next checks with the limit
    from the model's Jacobian, within 3 % of the analytic one, and the oscillation's
    frequency."""
    k, c = 1e8, 400.0
    sim = Simulation(body(k, c), method="dopri5", group="SO3xR3", rtol=1e-6, atol=1e-8)
    assert sim.run(0.2, t_eval=[0.2]).success
    n0 = sim.n_steps
    r = sim.run(1000.0, t_eval=[1000.0])
    assert not r.success and sim.n_steps - n0 <= 2000
    lam = stiff_eigenvalue(k, c)
    assert reported_h(r.message) == pytest.approx(dopri5_limit(lam), rel=0.03)
    hz = float(re.search(r"an oscillation of ([0-9.e+-]+) Hz", r.message).group(1))
    assert hz == pytest.approx(lam.imag / (2 * math.pi), rel=0.01)


def test_the_same_budget_leaves_a_run_it_affords_alone():
    """The same body on a soft spring-damper (k = 100, c = 1: not stiff) over the same 1000 s
    with the same max_steps runs to the end; so does the stiff overdamped one over 0.5 s
    (about 1.5e4 steps at its stability limit, well within max_steps)."""
    r = simulate(body(100.0, 1.0), (0, 1000.0), method="dopri5", group="SO3xR3", rtol=1e-6, atol=1e-8,
                 t_eval=[1000.0])
    assert r.success and r.t[-1] == 1000.0
    r = simulate(body(1e6, 1e5), (0, 0.5), method="dopri5", group="SO3xR3", rtol=1e-6, atol=1e-8,
                 t_eval=[0.5])
    assert r.success and r.stats["n_steps"] > 10000


def test_dominant_eigenvalues_of_a_state_of_mixed_scales():
    """A pressure of 1e7 Pa beside an angle: the differences move each entry by 1e-6 of its
    own size (one step for all, 1e-6 of the state's norm, moved the angle by 10 rad and gave
    eigenvalues of ±1e8 1/s on Exudyn's hydraulic actuator). A pendulum (ω² = 400) driven by a
    pressure that relaxes at 1200 1/s: the Jacobian's eigenvalues at the state, to 1e-4."""
    from lgt_bridge.integrators.stability import dominant_eigenvalues
    p0, w2, lam = 1e7, 400.0, 1200.0

    class Problem:
        nX = 1

        def rates(self, X, W, t):
            return np.array([W[0], -w2 * np.sin(X[0]) + 1e-7 * (W[1] - p0), -lam * (W[1] - p0) - 1e5 * W[0]])
    W = np.array([0.3, p0 + 50.0])
    J = np.array([[0.0, 1.0, 0.0], [-w2, 0.0, 1e-7], [0.0, -1e5, -lam]])       # at X = 0
    ev = dominant_eigenvalues(Problem(), W, 0.0)
    for r in np.linalg.eigvals(J):
        assert np.min(np.abs(ev - r)) < 1e-4 * abs(r), (r, ev)
