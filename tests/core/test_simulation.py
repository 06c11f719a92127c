"""The simulation object: set up once, advanced over consecutive horizons carrying its
state (model-predictive rollouts), the same motion as one run."""
import numpy as np
import pytest

from lgt_bridge import InputError, Simulation, scenes, simulate


def test_consecutive_horizons_equal_one_run_with_fixed_steps():
    m = scenes.heavy_top(True)
    one = simulate(m, (0, 0.1), method="rkmk4", dt=1e-3, t_eval=np.linspace(0.02, 0.1, 5))
    sim = Simulation(scenes.heavy_top(True), method="rkmk4", dt=1e-3)
    ends = [sim.run(0.02 * k) for k in range(1, 6)]
    assert all(r.success for r in ends)
    q = np.array([r.q[-1] for r in ends])
    assert np.abs(q - one.q).max() < 1e-12
    assert ends[0].t[0] == 0.0 and ends[1].t[0] == pytest.approx(0.02)     # each stretch starts where the last ended
    assert sim.t == pytest.approx(0.1) and sim.n_steps == 100


def test_consecutive_horizons_with_dense_output_track_a_tight_run():
    T, tight = 0.2, dict(rtol=1e-12, atol=1e-12)
    ref = simulate(scenes.heavy_top(False), (0, T), method="dop853", t_eval=[T], **tight)
    sim = Simulation(scenes.heavy_top(False), method="dop853", rtol=1e-10, atol=1e-10)
    for k in range(1, 11):
        r = sim.run(0.1 * T * k, t_eval=[0.1 * T * k])
        assert r.success and r.t[-1] == pytest.approx(0.1 * T * k)
    assert np.abs(sim.q - ref.q[-1]).max() < 1e-7
    assert np.abs(sim.V - ref.V[-1]).max() < 1e-7 * 150


def test_a_horizon_must_move_forward_and_options_are_checked_at_set_up():
    sim = Simulation(scenes.free_body(), method="rkmk4", dt=0.01)
    sim.run(0.05)
    with pytest.raises(InputError, match="greater than the simulation's time"):
        sim.run(0.05)
    with pytest.raises(InputError, match="unknown method"):
        Simulation(scenes.free_body(), method="rk45")
    with pytest.raises(InputError, match="takes fixed steps"):
        Simulation(scenes.free_body(), method="rkmk4")
    with pytest.raises(InputError, match="unknown chart"):
        Simulation(scenes.free_body(), method="rkmk4", dt=0.01, chart="cay3")
