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


def test_a_finished_run_is_freed_at_once():
    """No reference cycle outlives a run (stepper <-> dense output, the progress bar's state):
    what a call built is freed when its last reference goes, not at the next collection."""
    import gc
    import weakref
    gc.disable()
    try:
        for method, kw in (("dop853", {}), ("rkmk4", dict(dt=1e-3))):
            sim = Simulation(scenes.heavy_top(), method=method, t0=0.0, t_end=0.01, **kw)
            sim.run(0.01, t_eval=[0.005, 0.01])
            refs = [weakref.ref(o) for o in (sim, sim.stepper, sim.stepper.prob)]
            del sim
            assert all(r() is None for r in refs), method
    finally:
        gc.enable()


def test_the_first_step_reuses_the_starting_steps_f():
    """The starting step's f at the start is the first step's first stage (as scipy's f0):
    one accepted dop853 step costs 2 + 12 evaluations of f, and the same step as before."""
    m = scenes.free_body()
    r = simulate(m, (0, 1e-3), method="dop853", rtol=1e-6, atol=1e-8)
    assert r.stats["n_steps"] == 1 and r.stats["n_rejected"] == 0
    assert r.stats["n_f"] == 14
    sim = Simulation(m, method="dop853", rtol=1e-6, atol=1e-8, t0=0.0, t_end=1e-3)
    sim.restart()                  # the first stage computed again by the step itself
    r2 = sim.run(1e-3)
    assert r2.stats["n_f"] == 15 and np.array_equal(r2.q, r.q) and np.array_equal(r2.V, r.V)


@pytest.mark.parametrize("case", ["top", "top rtol=0", "free body at rest", "chain"])
@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_the_compiled_starting_step_is_the_reference_rule(case, method):
    """On compiled kernels the starting step's arithmetic runs in two kernel calls
    (kernels.steps.h0_start/h0_end); it is the reference rule (control.initial_step) on the
    same f0 and the same f, every branch: steps from d0/d1, a state at rest (d0 = 0: 1e-6),
    rtol = 0, and an f that vanishes (max(1e-6, 1e-3 h0))."""
    from lgt_bridge.integrators.control import initial_step
    rtol, atol, V0 = 1e-7, 1e-9, None
    model = {"top": scenes.heavy_top(), "top rtol=0": scenes.heavy_top(), "chain": scenes.chain(3),
             "free body at rest": scenes.free_body()}[case]
    if case == "top rtol=0":
        rtol = 0.0
    if case == "free body at rest":
        V0 = np.zeros(model.layout.nv)
    sim = Simulation(model, method=method, rtol=rtol, atol=atol, t_end=1.0, V0=V0)
    st = sim.stepper
    assert st.prob.compiled and st._fsal       # the first stage holds f0
    f0 = np.concatenate([st.KX[0], st.KW[0]])
    ref = initial_step(st.prob.rates, st.prob.nX, st.W, 0.0, rtol, atol, st.tab.err_order, f0=f0)
    assert sim.h == pytest.approx(ref, rel=1e-12, abs=0.0)
    if case == "free body at rest":
        assert not np.any(f0)                  # (the branch where both estimates vanish)


def test_models_of_equal_layouts_share_their_analysis_and_a_new_layout_gets_its_own():
    from lgt_bridge.integrators.problem import make_problem
    a, b = make_problem(scenes.free_body(), "SO3xR3"), make_problem(scenes.free_body(), "SO3xR3")
    assert a.sets is b.sets                          # one analysis for the two models
    m = scenes.free_body()
    make_problem(m, "SO3xR3")
    m.layout = scenes.chain(3).layout                # (a model given another layout)
    p = make_problem(m, "SO3xR3")
    assert p.nX == 18 and p.nv == m.layout.nv

@pytest.mark.parametrize("backend", ["numba", "numpy"])
@pytest.mark.parametrize("method", ["dopri5", "dop853", "radau5", "rkmk4"])
def test_outputs_within_a_step_in_one_call_equal_one_by_one(method, backend, monkeypatch):
    """run(t_eval) evaluates the output times a step covers in one dense-output call (one
    kernel call for τ); the states equal advance_to's, which evaluates the step's dense
    output at one time per call, to rounding — 1201 outputs, steps covering several."""
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", backend)
    T, t_eval = 0.3, np.linspace(0.0, 0.3, 1201)
    kw = dict(method=method, rtol=1e-6, atol=1e-6, t_end=T, dt=0.01 if method == "rkmk4" else None)
    r = Simulation(scenes.heavy_top(True), **kw).run(T, t_eval=t_eval)
    sim = Simulation(scenes.heavy_top(True), **kw)
    one = [(sim.q.copy(), sim.V.copy())] + [tuple(np.array(x) for x in sim.advance_to(t)) for t in t_eval[1:]]
    assert r.success and np.array_equal(r.t, t_eval)
    if method != "rkmk4":
        assert r.stats["n_steps"] < len(t_eval) // 3       # several outputs per step
    for k, (q, V) in enumerate(one):
        assert np.abs(r.q[k] - q).max() <= 1e-13 * max(1.0, np.abs(q).max()), k
        assert np.abs(r.V[k] - V).max() <= 1e-13 * max(1.0, np.abs(V).max()), k


def test_advance_to_many_returns_the_times_the_last_step_covers():
    """advance_to_many steps to the first target and returns the states at every target up to
    the step's end (a target on the step's end gets the step's own state), not beyond it."""
    sim = Simulation(scenes.heavy_top(True), method="dop853", rtol=1e-8, atol=1e-8, t_end=0.3)
    targets = np.linspace(0.001, 0.3, 300)
    n, Q, V = sim.advance_to_many(targets)
    assert 1 <= n < len(targets) and Q.shape == (n, len(sim.q)) and V.shape == (n, len(sim.V))
    assert targets[n - 1] <= sim.t < targets[n]
    d = sim.stepper.dense
    for k in range(n):
        q, v = d(targets[k])
        assert np.abs(Q[k] - q).max() <= 1e-13 and np.abs(V[k] - v).max() <= 1e-12
    n2, Q2, _ = sim.advance_to_many(np.r_[sim.t, targets[n:]])      # the step's end itself
    assert n2 == 1 and np.array_equal(Q2[0], sim.q)


def test_a_horizons_end_is_met_without_a_sliver_step_and_the_step_carries_on():
    # an adaptive run splits the last stretch to a horizon's end into equal steps
    # (no sliver of a step that throws the controller off) and the next horizon starts
    # from the controller's proposal, not from the shortened step
    sim = Simulation(scenes.heavy_top(False), method="dop853", rtol=1e-8, atol=1e-8)
    H, shortest, longest = 0.005, np.inf, 0.0
    for k in range(1, 41):
        r = sim.run(H * k)
        h = np.diff(r.t)
        if k > 1:
            shortest, longest = min(shortest, h.min()), max(longest, h.max())
    assert longest > 0 and shortest > 0.3 * longest


@pytest.mark.parametrize("t_eval,why", [
    ([0.0, np.nan, 0.1], "finite and strictly increasing"),
    ([0.0, np.inf], "finite and strictly increasing"),
    ([0.05, 0.05], "finite and strictly increasing"),
    ([0.06, 0.02], "finite and strictly increasing"),
    ([-0.01, 0.05], "within t_span"),
    ([0.05, 0.2], "within t_span"),
])
def test_bad_t_eval_is_refused_before_any_step(t_eval, why):
    with pytest.raises(InputError, match=why):
        simulate(scenes.free_body(), (0, 0.1), method="dopri5", t_eval=t_eval)


def test_empty_t_eval_advances_without_outputs():
    """t_eval=[]: no output rows (scipy's solve_ivp accepts it too), the run still reaches
    t_end: the next stretch continues from there, equal to one run to the end."""
    tight = dict(method="dop853", rtol=1e-10, atol=1e-10)
    ref = simulate(scenes.heavy_top(False), (0, 0.2), t_eval=[0.2], **tight)
    sim = Simulation(scenes.heavy_top(False), **tight)
    r = sim.run(0.1, t_eval=[])
    assert r.success and r.t.shape == (0,) and r.q.shape == (0, len(sim.q)) and sim.t == pytest.approx(0.1)
    r2 = sim.run(0.2, t_eval=np.array([0.2]))
    assert np.abs(r2.q[-1] - ref.q[-1]).max() < 1e-8
