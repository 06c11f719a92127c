"""Exudyn's TestModels/ballBearingTest.py through generalized-α (issue 21): a shaft on an Rxyz
node in a ball bearing of sphere–torus contacts with regularised friction.

A model with an Rxyz node gets generalized-α's Newton matrix by finite differences of the
step's residual (Exudyn's Jacobian misses the adapter's Ḣ V term there). The difference step
was sized to move the positions by √eps, which moved the velocities by √eps·γ/(hβ)·|Ẇ|: at
h = 1e-4 a ball's spin by ~1e3 rad/s, far beyond the friction's proportional zone (1e-2 m/s)
and the contacts' 50 µm penetration. Newton then bounced between two states (updates 59, 59,
59) and halved the step to 1e-8 before stopping ("Newton did not converge", at t = 1.03e-4
in the script; at 20 steps of this 5-ball copy too). The force rows are now differenced with
a step that moves the velocities by √eps relative to their change over the step."""
import warnings

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.errors import ModelNote  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

from exudyn_bearing_models import ball_bearing  # noqa: E402

T_END, N = 0.002, 20          # the script's step, 1e-4 s


@pytest.fixture(scope="module")
def exudyn_refined():
    """Exudyn's own generalized-α at 100x the script's steps (1e-6 s): within 3e-5 of its
    solution at 1000x (measured 2.7e-5), its error falling tenfold per tenfold step count."""
    mbs, s, _ = ball_bearing(t_end=T_END, n=100 * N)
    mbs.SolveDynamic(s, showHints=False)
    return np.array(mbs.systemData.GetODE2Coordinates())


def _bridge(n):
    mbs, s, _ = ball_bearing(t_end=T_END, n=n)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelNote)   # the shaft's initial spin is reversed
        SolveDynamic(mbs, s, method="genalpha")
    return np.array(mbs.systemData.GetODE2Coordinates()), mbs.sys["lgtBridgeStats"]


@pytest.mark.parametrize("factor, bound", [(1, 3e-3), (10, 4e-4)])
def test_ball_bearing_genalpha_runs_and_converges_to_exudyns_refined_solution(exudyn_refined, factor, bound):
    """At the script's step and at a tenth of it, genalpha finishes (cutting steps where the
    contacts slip hardest, as Exudyn's own generalized-α does) and stands from Exudyn's
    refined solution where Exudyn's own solver at the same step stands (measured: bridge
    2.10e-3 and 2.74e-4, Exudyn 2.10e-3 and 2.75e-4, in the coordinates' largest entry)."""
    q, st = _bridge(factor * N)
    assert st["success"]
    assert np.abs(q - exudyn_refined).max() < bound
