"""The compiled step loop (:mod:`lgt_bridge.integrators.compiled_loop`) takes the same steps
as the Python loop it replaces (``Simulation._use_loop = False``: ``Simulation._step``,
``AdaptiveRK._attempt``), on the same compiled stage kernels: equal states, times and counts
— through rejected steps, Hairer's stiffness cap, landings on output times, consecutive
horizons, steps handed back to Python (chart limits), hooks after every step, and failures
(the step budget, min_step, an engine error), each of which ends with the same message and
keeps the same steps. And the loop is really used where it applies (``Loop.runs``)."""
import numpy as np
import pytest

from lgt_bridge import Simulation, scenes
from lgt_bridge.errors import ModelError
from lgt_bridge.integrators import compiled_loop

from test_backends import Mixed
from test_engine_velocity import EngineMixed
from test_stiff_steps import damped_body


@pytest.fixture(autouse=True)
def compiled(monkeypatch):
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", "numba")


def _pair(make, run, **opts):
    """``run(sim)`` on two simulations of ``make()``: the compiled loop's and the Python loop's
    (results, simulations)."""
    out = []
    for use in (True, False):
        sim = Simulation(make(), **opts)
        sim._use_loop = use
        out.append((run(sim), sim))
    return out


def _loop_runs(sim):
    loop = getattr(sim.stepper, "_compiled_loop", None)
    return 0 if loop is None else loop.runs


def _same(a, b, counts=("n_steps", "n_f", "n_rejected")):
    assert a.success == b.success and a.message == b.message
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_allclose(a.q, b.q, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(a.V, b.V, rtol=1e-12, atol=1e-14)
    for k in counts:
        assert a.stats[k] == b.stats[k], k


MODELS = {
    "free body": lambda: scenes.free_body(omega0=(0.3, 8.0, 0.2)),
    "heavy top": lambda: scenes.heavy_top(False),
    "free bodies": lambda: scenes.free_bodies(5),
    "mixed": lambda: Mixed(np.random.default_rng(3)),
    "engine velocity": lambda: EngineMixed(np.random.default_rng(3)),
}


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("model", sorted(MODELS))
def test_the_loop_takes_the_python_loops_steps(method, group, model):
    T = 1.5
    for t_eval in ([T], np.linspace(0.0, T, 11)):
        (a, sa), (b, sb) = _pair(MODELS[model], lambda sim: sim.run(T, t_eval=t_eval),
                                 method=method, group=group, rtol=1e-10, atol=1e-10)
        _same(a, b)
        assert _loop_runs(sa) >= 1 and _loop_runs(sb) == 0
        assert a.stats["n_steps"] > 5


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_stiff_steps_and_horizons_are_the_python_loops(method):
    """The damped body (test_stiff_steps): the stiffness cap holds the steps at the stability
    limit and steps are rejected; as 25 consecutive 20 ms horizons carrying the state."""
    def horizons(sim):
        rs = [sim.run(0.02 * k, t_eval=[0.02 * k]) for k in range(1, 26)]
        st = sim.stepper
        return rs, (sim.t, sim.h, sim.n_steps, st.n_rejected, st.prob.n_f, st.h_stable, st._rho, st.stiff)
    (ra, ka), (rb, kb) = [r for r, _ in _pair(damped_body, horizons, method=method, group="SO3xR3",
                                               rtol=1e-6, atol=1e-6)]
    for a, b in zip(ra, rb):
        _same(a, b)
    assert ka == kb
    assert ka[3] > 0 and np.isfinite(ka[5])        # rejected steps, and the cap measured


def test_bounded_chart_steps_handed_back_to_python():
    """Cayley's chart bounds a stage's rotation: a fast spin at a loose tolerance runs into
    the bound; those attempts are handed back to the Python stepper (which retries them
    shorter), so the steps equal the Python loop's (the handed-back attempts' f are
    evaluated twice: n_f is not compared)."""
    make = lambda: scenes.free_body(omega0=(0.5, 40.0, 0.3))        # noqa: E731
    (a, sa), (b, sb) = _pair(make, lambda sim: sim.run(1.0, t_eval=[0.5, 1.0]), method="dopri5",
                             group="SO3xR3", chart="cay", rtol=1e-3, atol=1e-3)
    _same(a, b, counts=("n_steps", "n_rejected"))
    assert np.isfinite(sa.stepper._hcay) and _loop_runs(sa) >= 1
    assert a.stats["n_f"] > b.stats["n_f"]


def test_every_step_recorded_and_events_as_the_python_loop():
    """With outputs at every step (t_eval None) and with an event, the loop hands back after
    every accepted step."""
    def g(t, q, V):
        return V[0] - 0.5                      # the top's ω_x passing 0.5
    (a, sa), (b, _) = _pair(lambda: scenes.heavy_top(False), lambda sim: sim.run(0.8, events=g),
                            method="dop853", rtol=1e-8, atol=1e-8)
    _same(a, b)
    assert len(a.t) == a.stats["n_steps"] + 1 and _loop_runs(sa) >= 1
    assert len(a.t_events[0]) and np.array_equal(a.t_events[0], b.t_events[0])


@pytest.mark.parametrize("case", ["max_steps", "min_step", "engine error"])
def test_failures_end_as_in_the_python_loop(case):
    opts = dict(method="dop853", rtol=1e-9, atol=1e-9)
    make = MODELS["heavy top"]
    if case == "max_steps":
        opts["max_steps"] = 7
    elif case == "min_step":
        opts["min_step"] = 0.05                 # the error control wants smaller steps
    else:
        def make():
            m = scenes.heavy_top(False)
            f = m.f

            def failing(q, V, t):
                if t > 0.3:
                    raise ModelError("the engine stopped at t > 0.3")
                return f(q, V, t)
            m.f = failing
            return m
    (a, sa), (b, sb) = _pair(make, lambda sim: sim.run(0.7, t_eval=np.linspace(0, 0.7, 8)), **opts)
    assert not a.success
    _same(a, b)
    assert sa.t == sb.t and np.array_equal(sa.q, sb.q)
    assert _loop_runs(sa) >= 1


def test_only_where_it_applies():
    """Not for fixed steps, projected constraints or the numpy backend (their own loops)."""
    assert compiled_loop.of(Simulation(scenes.heavy_top(False), method="rkmk4", dt=0.01)) is None
    assert compiled_loop.of(Simulation(scenes.heavy_top(True), method="dop853")) is None
    assert compiled_loop.of(Simulation(scenes.heavy_top(False), method="dop853")) is not None


def test_switching_loops_between_horizons_keeps_the_steps():
    """Horizons run alternately by the Python loop and the compiled one (the loop made after
    Python steps takes over the stepper's stage buffers, FSAL stage and dense output) equal
    a run by the Python loop alone."""
    def horizons(sim, switch):
        out = []
        for k in range(1, 9):
            if switch:
                sim._use_loop = k % 2 == 0
            out.append(sim.run(0.1 * k, t_eval=[0.1 * k - 0.05, 0.1 * k]))
        return out
    ref = Simulation(MODELS["heavy top"](), method="dop853", rtol=1e-9, atol=1e-9)
    ref._use_loop = False
    mixed = Simulation(MODELS["heavy top"](), method="dop853", rtol=1e-9, atol=1e-9)
    for a, b in zip(horizons(mixed, True), horizons(ref, False)):
        _same(a, b)
    assert _loop_runs(mixed) >= 4


def test_a_progress_bar_lets_the_loop_run_on_and_shows_the_run(capsys):
    """With a progress bar (its hook may wait STRIDE steps) the loop hands back every STRIDE
    steps, not after each (the other hooks: every step), and the run equals the Python loop's;
    the bar is drawn."""
    from lgt_bridge import progress
    (a, sa), (b, _) = _pair(MODELS["heavy top"], lambda sim: sim.run(2.0, t_eval=[2.0], progress=True),
                            method="dopri5", rtol=1e-10, atol=1e-10)
    _same(a, b)
    n = a.stats["n_steps"]
    assert n > 3 * progress.STRIDE
    calls = []
    sim = Simulation(MODELS["heavy top"](), method="dopri5", rtol=1e-10, atol=1e-10, t_end=2.0)
    bar = progress.simulation_bar(True, 0.0, 2.0, sim, sim.stepper)
    calls_hook = bar.hook

    def counting(t, q, V):
        calls.append(t)
        calls_hook(t, q, V)
    counting.stride = progress.STRIDE
    sim.advance_to(2.0, counting)
    bar.close()
    assert sim.n_steps == n and len(calls) <= n // progress.STRIDE + 1
    assert "simulate" in capsys.readouterr().err
