"""Issue 21, class 10: an explicit method through the drop-in, on a model whose stability
limit needs far more steps than the run can afford, says so within a bounded number of steps
— even when the run would fit in max_steps — while Exudyn's own step (genalpha) runs it.

"Far more": the rest of the run at the stability limit needs more than STIFF_RATIO times the
steps Exudyn's own solver takes for it (numberOfSteps) and more than STIFF_WALL seconds at
the pace so far (lgt_bridge.diagnosis)."""
import re

import numpy as np
import pytest
exu = pytest.importorskip("exudyn")
from lgt_bridge import StepError  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402
import exudyn_solver_models as sm  # noqa: E402

#: DOPRI5's stability function R(z) = Σ_{k≤5} z^k/k! + z⁶/600: its edge on the negative real
#: axis, the real root of R(x) = ±1 nearest 0 but 0 itself (Hairer-Wanner: ≈ 3.3)
_R = [1 / 600, 1 / 120, 1 / 24, 1 / 6, 1 / 2, 1.0, 1.0]
DOPRI5_REAL = float(min(-r.real for sign in (1.0, -1.0) for r in np.roots(np.subtract(_R, [0] * 6 + [sign]))
                        if abs(r.imag) < 1e-9 and r.real < -1e-9))


def chain_fastest_rate(n, k, c):
    """|λ| max of the chain's axial motion, linearized: M ẍ + c L ẋ + k L x = 0 with L the
    Laplacian of a chain of n unit masses hung from ground (the first spring to ground)."""
    L = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    L[-1, -1] = 1.0
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-k * L, -c * L]])
    return float(np.abs(np.linalg.eigvals(A)).max())


def test_dopri5_on_a_stiff_damped_chain_within_max_steps_stops_with_the_stability_limit():
    """Five 1 kg masses hanging on 1e7 N/m springs with 1e5 N s/m damping, over 20 s with
    numberOfSteps = 100: the fastest mode is real (|λ| ≈ 3.7e5 1/s), DOPRI5 allows h ≈ 9e-6 s
    there, so the run needs about 2.2e6 steps — within 4 × max_steps, which the old check waited
    for, so it ground on for minutes — 2e4 times Exudyn's 100. It stops within 2000 steps with
    the stability limit (within 5 % of the analytic one), the ratio to Exudyn's steps and the
    advice, the system left at the last step; the same model through radau5 runs, and ends
    where Exudyn's own solver does (the static equilibrium)."""
    k, c = 1e7, 1e5
    mbs, s = sm.stiff_spring_chain(damping=c, t_end=20.0, steps=100, hanging=True)
    with pytest.raises(StepError) as exc:
        SolveDynamic(mbs, s, method="dopri5")
    st = mbs.sys["lgtBridgeStats"]
    msg = str(exc.value)
    assert not st["success"] and st["n_steps"] <= 2000, st
    assert "times the" in msg and "numberOfSteps = 100" in msg
    assert "method='radau5' or method='genalpha'" in msg
    h = float(re.search(r"stability limit, h ≈ ([0-9.e+-]+) s", msg).group(1))
    assert h == pytest.approx(DOPRI5_REAL / chain_fastest_rate(5, k, c), rel=0.05)
    assert 0.0 < mbs.systemData.GetTime() < 0.1
    assert np.abs(_end_state("radau5") - _end_state(None)).max() < 1e-9


def _end_state(method, t_end=20.0, steps=100):
    """The hanging damped chain's coordinates at t_end through the drop-in (None: Exudyn's own
    solver)."""
    mbs, s = sm.stiff_spring_chain(damping=1e5, t_end=t_end, steps=steps, hanging=True)
    if method is None:
        mbs.SolveDynamic(s)
    else:
        SolveDynamic(mbs, s, method=method)
        assert mbs.sys["lgtBridgeStats"]["success"]
    return mbs.systemData.GetODE2Coordinates()


def test_genalpha_on_the_stiff_damped_chain_at_exudyns_step():
    """The same chain through genalpha at Exudyn's step h = 0.2 s ends where Exudyn's own
    generalized-α does (the static equilibrium, 1.5e-5 m below the reference). The stiff
    modes' accelerations alternate in sign from step to step there; Newton's start had
    extrapolated them (doubling the swing) and found another root of the step's equations:
    the chain turned through its anchor and ended 2 cm above the equilibrium."""
    assert np.abs(_end_state("genalpha") - _end_state(None)).max() < 1e-9


def test_genalpha_on_the_swinging_stiff_chain_follows_exudyns_converged_motion():
    """The chain laid out horizontally (k = 1e7 N/m, lightly damped) swings down for 1 s at
    Exudyn's 100, 200 and 400 steps: genalpha takes Exudyn's steps (none halved) and ends
    where Exudyn's own generalized-α does, to 1e-5 at 100 steps (measured 2.1e-6) and 1e-8 at
    200 and 400 (1.2e-9, 5.2e-9), both 2.5e-5 or less from Exudyn refined 100x. Before: with
    Newton's extrapolated start the chain ended at +0.054 (another root of the steps'
    equations); with that fixed, 52 of its 152 steps at 100 were halved (Newton diverged on a
    kept matrix and went on from the iterate it had sent away), 1.4e-4 from the reference."""
    mbs, s = sm.stiff_spring_chain(damping=10.0, t_end=1.0, steps=10000)
    mbs.SolveDynamic(s)
    ref = np.array(mbs.systemData.GetODE2Coordinates())[1]
    ends = {}
    for steps in (100, 200, 400):
        mbs, s = sm.stiff_spring_chain(damping=10.0, t_end=1.0, steps=steps)
        mbs.SolveDynamic(s)
        own = np.array(mbs.systemData.GetODE2Coordinates())
        mbs, s = sm.stiff_spring_chain(damping=10.0, t_end=1.0, steps=steps)
        SolveDynamic(mbs, s, method="genalpha")
        st = mbs.sys["lgtBridgeStats"]
        assert st["success"]
        ends[steps] = (np.array(mbs.systemData.GetODE2Coordinates()), own, st["n_steps"])
    for steps, tol in ((100, 1e-5), (200, 1e-8), (400, 1e-8)):
        q, own, n = ends[steps]
        assert n == steps and np.abs(q - own).max() < tol
        assert abs(q[1] - ref) < 3e-5


def test_dopri5_on_a_stiff_ancf_cable_within_max_steps_stops_early():
    """The damped ANCF cable (8 elements) over 2 s with numberOfSteps = 200: about 1.1e6 steps
    at dopri5's stability limit (within 4 × max_steps), 5e3 times Exudyn's. It stops within
    2000 steps saying so; genalpha at Exudyn's step runs it."""
    mbs, s, tip = sm.ancf_cable_damped(elements=8)
    s.timeIntegration.endTime, s.timeIntegration.numberOfSteps = 2.0, 200
    with pytest.raises(StepError, match=r"stability limit, h ≈ .*method='radau5' or method='genalpha'"):
        SolveDynamic(mbs, s, method="dopri5")
    assert mbs.sys["lgtBridgeStats"]["n_steps"] <= 2000
    mbs, s, tip = sm.ancf_cable_damped(elements=8)
    s.timeIntegration.endTime, s.timeIntegration.numberOfSteps = 2.0, 200
    SolveDynamic(mbs, s, method="genalpha")
    assert mbs.sys["lgtBridgeStats"]["success"]


def test_a_stiff_run_the_caller_affords_runs_through():
    """The same chain over 0.05 s with numberOfSteps = 10: 5600 steps at the stability limit,
    560 times Exudyn's, but a second or so: it runs to the end, the statistics saying where
    the steps sat."""
    mbs, s = sm.stiff_spring_chain(damping=1e5, t_end=0.05, steps=10)
    SolveDynamic(mbs, s, method="dopri5")
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and st["stiff"]["h_stable"] * 3e5 < 3.3


def test_a_stiff_run_a_few_times_the_engines_steps_goes_on_with_a_note(monkeypatch):
    """The stiff chain over 0.05 s with numberOfSteps = 1100: about 5500 steps at dopri5's
    stability limit, 5 times Exudyn's (below STIFF_RATIO): it runs to the end, and once the
    rest would take over STIFF_WALL s (lowered here to 0) it says once that the steps sit at
    the stability limit and which methods would not be held there (Exudyn's hydraulic
    actuator script ran 38 s, 4x Exudyn's steps, without a word). Unlowered: no note."""
    import warnings
    from lgt_bridge import diagnosis
    from lgt_bridge.errors import ModelNote
    for wall, noted in ((0.0, True), (diagnosis.STIFF_WALL, False)):
        monkeypatch.setattr(diagnosis, "STIFF_WALL", wall)
        mbs, s = sm.stiff_spring_chain(damping=1e5, t_end=0.05, steps=1100)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            SolveDynamic(mbs, s, method="dopri5")
        st = mbs.sys["lgtBridgeStats"]
        notes = [str(w.message) for w in caught if issubclass(w.category, ModelNote) and "stability limit" in str(w.message)]
        assert st["success"] and 2 * 1100 < st["n_steps"] < 20 * 1100, st
        assert len(notes) == (1 if noted else 0), notes
        if noted:
            assert "it goes on" in notes[0] and "method='radau5' or method='genalpha'" in notes[0]
            h = float(re.search(r"stability limit, h ≈ ([0-9.e+-]+) s", notes[0]).group(1))
            assert abs(h - st["stiff"]["h_stable"]) < 0.1 * h


def test_radau5_does_not_grow_the_step_right_after_a_rejection():
    """The swinging stiff chain through radau5 over 0.3 s: steps that grow right after a
    rejected one fail Newton again, so RADAU5 (and scipy's Radau) keep the step after a
    rejection from growing. Without that rule 952 rejections for 562 steps; with it 480 for
    566: fewer rejections than steps."""
    mbs, s = sm.stiff_spring_chain(damping=1e5, t_end=0.3, steps=30)
    SolveDynamic(mbs, s, method="radau5")
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and st["n_rejected"] < st["n_steps"], st


def test_an_accuracy_held_explicit_run_goes_on_and_says_how_long(monkeypatch):
    """A lightly damped chain (k = 1e5 N/m, ω up to about 600 rad/s) over 2 s with
    numberOfSteps = 2, dopri5 at rtol = atol = 1e-10: its steps are held by the accuracy
    (h|λ| well inside the stability region), not by the stability limit, so the run goes on to
    the end; past STIFF_RATIO times Exudyn's steps (and, here, any wall time) it warns once
    with the steps the rest needs and what to use instead. Without the wall floor lowered the
    same run says nothing (a second or less: nothing to warn about)."""
    import warnings
    from lgt_bridge import diagnosis
    from lgt_bridge.errors import ModelNote
    for wall, warned in ((0.0, True), (diagnosis.STIFF_WALL, False)):
        monkeypatch.setattr(diagnosis, "STIFF_WALL", wall)
        mbs, s = sm.stiff_spring_chain(k=1e5, damping=0.1, t_end=2.0, steps=2, hanging=True)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            SolveDynamic(mbs, s, method="dopri5", rtol=1e-10, atol=1e-10)
        st = mbs.sys["lgtBridgeStats"]
        notes = [str(w.message) for w in caught if issubclass(w.category, ModelNote) and "held by its accuracy" in str(w.message)]
        assert st["success"] and st["n_steps"] > 20 * 2, st
        assert len(notes) == (1 if warned else 0), notes
        if warned:
            assert "times the" in notes[0] and "method='genalpha'" in notes[0]


def test_a_slow_genalpha_run_says_where_its_steps_go_and_goes_on(monkeypatch):
    """genalpha through the drop-in on the stiff swinging chain, whose Newton matrix is made
    anew several times a step (its springs turn within a step), with the slow-run thresholds
    scaled down so that this short run crosses them: one ModelNote with its Newton matrices a
    step, naming Exudyn's own solver, and the run ends where it would have."""
    from lgt_bridge import diagnosis
    from lgt_bridge.errors import ModelNote
    monkeypatch.setattr(diagnosis, "SLOW_AFTER", 0.005)
    monkeypatch.setattr(diagnosis, "SLOW_EVERY", 0.001)
    monkeypatch.setattr(diagnosis, "SLOW_WALL", 1e-6)
    mbs, s = sm.stiff_spring_chain(damping=1e5)
    with pytest.warns(ModelNote) as got:
        SolveDynamic(mbs, s, method="genalpha")
    slow = [str(w.message) for w in got if "the rest of the run" in str(w.message)]
    assert len(slow) == 1, [str(w.message) for w in got]
    jac = float(re.search(r"and ([0-9.]+) Newton matrices a step", slow[0]).group(1))
    assert jac >= 1.0 and "Exudyn's own solver may keep its matrix across steps" in slow[0]
    assert mbs.sys["lgtBridgeStats"]["success"] and mbs.systemData.GetTime() == pytest.approx(1.0)
