"""Modified Newton's verdict (lgt_bridge.integrators.newton_control) on update sizes of known
contraction: its converged test against the defining identity of the estimate (the error left
is the sum of the updates still to come), its refresh rule against the count of updates a
geometric sequence still needs, and the first ratio (the predictor's error) never trusted."""
import math

import pytest

from lgt_bridge.integrators import newton_control as nc

TOL, NO_FLOOR = 1e-10, 0.0


def tail(s0, theta, k):
    """Σ_{j>k} s0 θ^j: the error left after update k of a geometric sequence."""
    return s0 * theta ** (k + 1) / (1.0 - theta)


@pytest.mark.parametrize("theta", [0.01, 0.1, 0.3, 0.45])
def test_converged_when_the_updates_still_to_come_are_within_the_tolerance(theta):
    """Updates s0 θ^k (the first one 1e3 larger: the predictor's error): from the third update
    on, CONVERGED exactly when the tail of the sequence is within tol, i.e. one update before
    the update itself is."""
    s0 = 1e-3
    sizes = [1.0]
    for k in range(1, 60):
        sizes.append(s0 * theta ** k)
        v = nc.verdict(sizes, TOL, NO_FLOOR, budget=1000)
        if v is nc.CONVERGED:
            break
        assert v is nc.CONTINUE, (k, v)
    assert k >= 2
    # converged at k: the tail after k is within tol, the tail after k - 1 is not
    assert tail(s0, theta, k) <= TOL * (1 + 1e-12) and sizes[-1] > TOL
    assert tail(s0, theta, k - 1) > TOL


def test_the_first_ratio_is_not_trusted():
    """A kept matrix resolves the predictor's error and then contracts slowly: after updates
    1 and 1e-7 (ratio 1e-7) the step is not converged at tol 1e-10 and not refreshed."""
    assert nc.verdict([1.0, 1e-7], TOL, NO_FLOOR, budget=8) is nc.CONTINUE
    assert nc.contraction([1.0, 1e-7]) is None
    assert nc.contraction([1.0, 1e-7, 3e-8]) == pytest.approx(0.3)
    # the larger of the last two ratios (a stale matrix's ratios alternate)
    assert nc.contraction([1.0, 1e-3, 1e-4, 4e-5]) == pytest.approx(0.4)


@pytest.mark.parametrize("theta", [0.05, 0.2, 0.4])
@pytest.mark.parametrize("budget", [6, 8, 12])
def test_refresh_when_the_updates_needed_exceed_the_budget(theta, budget):
    """At the third update of s0 θ^k the verdict refreshes exactly when the geometric sequence
    would first be converged (tail within tol) after more than ``budget`` updates."""
    s0 = 1e-2
    sizes = [1.0, s0 * theta, s0 * theta ** 2]
    needed = next(k for k in range(1, 500) if tail(s0, theta, k) <= TOL) + 1   # updates 0..k
    v = nc.verdict(sizes, TOL, NO_FLOOR, budget)
    if needed <= 3:
        assert v is nc.CONVERGED
    else:
        assert v is (nc.REFRESH if needed > budget else nc.CONTINUE), (needed, v)


def test_poor_contraction_refreshes_and_the_floor_converges():
    assert nc.verdict([1.0, 0.6], TOL, NO_FLOOR, budget=100) is nc.REFRESH        # first ratio 0.6
    assert nc.verdict([1.0, 0.1, 0.06], TOL, NO_FLOOR, budget=100) is nc.REFRESH  # θ = 0.6
    # updates that stop falling below the rounding floor: converged as far as it can tell
    assert nc.verdict([1.0, 3e-9, 2e-9], TOL, 5e-9, budget=100) is nc.AT_FLOOR
    assert nc.verdict([1.0, 3e-9], TOL, 1e-9, budget=100) is not nc.AT_FLOOR


def test_tolerances_scale_with_the_velocities_and_the_step():
    import numpy as np
    W, q = np.full(4, 3.0), np.array([0.0, 2.0, -5.0])
    tol, floor = nc.tolerances(W, q, 1e-10, 1e-3, 0.3, constrained=True)
    assert tol == pytest.approx(1e-10 * 4.0)
    eps = np.finfo(float).eps
    assert floor == pytest.approx(max(tol, nc.FLOOR * eps * (4.0 + 5.0 / (1e-3 * 0.3))))
    assert nc.tolerances(W, q, 1e-10, 1e-3, 0.3, constrained=False)[1] == tol
    assert math.isfinite(nc.tolerances(np.zeros(0), np.zeros(0), 1e-10, 1e-3, 0.3, False)[0])
