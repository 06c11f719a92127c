"""A fixed-step run (rkmk4, genalpha) whose rest would take long at its pace says so once, in
a ModelNote, with where a step's time goes, and goes on (``diagnosis.slow_tick``); a run
that will end soon says nothing. The thresholds (5 s run, 60 s to go, a look every second) are
scaled down here so that an ordinary run crosses them."""
import warnings

import numpy as np
import pytest

from lgt_bridge import diagnosis, scenes, simulate
from lgt_bridge.errors import ModelNote


@pytest.fixture
def quick(monkeypatch):
    monkeypatch.setattr(diagnosis, "SLOW_AFTER", 0.005)
    monkeypatch.setattr(diagnosis, "SLOW_EVERY", 0.001)


def _notes(run):
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        r = run()
    return r, [str(w.message) for w in got if issubclass(w.category, ModelNote)]


@pytest.mark.parametrize("method,words", [("rkmk4", ["4 evaluations of the model a step"]),
                                          ("genalpha", ["Newton updates", "Newton matrices a step"])])
def test_a_fixed_step_run_whose_rest_is_long_says_so_once_and_goes_on(method, words, quick, monkeypatch):
    monkeypatch.setattr(diagnosis, "SLOW_WALL", 0.05)
    model = scenes.heavy_top(constrained=True)
    ref, _ = _notes(lambda: simulate(model, (0, 1.0), method=method, dt=5e-4))
    monkeypatch.setattr(diagnosis, "SLOW_WALL", 1e-6)
    r, notes = _notes(lambda: simulate(scenes.heavy_top(constrained=True), (0, 1.0), method=method, dt=5e-4))
    assert r.success and r.t[-1] == 1.0
    slow = [n for n in notes if "the rest of the run" in n]
    assert len(slow) == 1, notes
    assert slow[0].startswith(f"{method} at t = ") and "It goes on." in slow[0]
    assert all(w in slow[0] for w in words), slow[0]
    t_note = float(slow[0].split("t = ")[1].split(":")[0])
    assert 0.0 < t_note < 1.0
    assert np.array_equal(r.q[-1], ref.q[-1])          # the note changed nothing of the run


def test_a_run_about_to_end_says_nothing(quick, monkeypatch):
    """The rest at the pace so far below SLOW_WALL: no note, however long the run has gone."""
    monkeypatch.setattr(diagnosis, "SLOW_WALL", 1e6)
    _, notes = _notes(lambda: simulate(scenes.heavy_top(constrained=True), (0, 1.0), method="rkmk4", dt=5e-4))
    assert not [n for n in notes if "the rest of the run" in n]


def test_the_pace_is_the_last_stretchs_not_the_whole_runs(quick, monkeypatch):
    """Steps that turn slow halfway (a contact closing: here f sleeps 0.5 ms from t = 0.5 on):
    the rest is judged at the pace of the last SLOW_AFTER s, which says so within a few
    looks, where the pace of the whole run so far (its fast half included) would not."""
    import time
    monkeypatch.setattr(diagnosis, "SLOW_AFTER", 0.05)
    monkeypatch.setattr(diagnosis, "SLOW_EVERY", 0.01)
    monkeypatch.setattr(diagnosis, "SLOW_WALL", 0.3)
    model = scenes.heavy_top(constrained=True)
    fast_f = model.f

    def f(q, V, t):
        if t > 0.5:
            time.sleep(5e-4)
        return fast_f(q, V, t)
    model.f = f
    _, notes = _notes(lambda: simulate(model, (0, 1.0), method="rkmk4", dt=1e-3))
    slow = [n for n in notes if "the rest of the run" in n]
    assert len(slow) == 1, notes
    assert 0.5 < float(slow[0].split("t = ")[1].split(":")[0]) < 0.7
