"""Exudyn data coordinates that move at every step without switching: a RollingDiscPenalty's
friction reads the slip velocity its PostNewton stored at the last step's end (Exudyn's
mecanumWheelRollingDiscTest.py timed out through the bridge at 90 s; Exudyn takes 0.8 s).

Each such move used to count as a switch to locate, so every step was cut to a quarter down
to 1e-7 of the span (a single wheel: 4305 generalized-α steps for Exudyn's 100, 47 s). Now a
force error of PostNewton without a sign change of a gap or mode redoes the step with the
new states, as Exudyn's discontinuous iteration does (``lgt_bridge.switches.REDO``)."""
import warnings

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.errors import ModelNote  # noqa: E402
from lgt_exudyn import ExudynModel, SolveDynamic  # noqa: E402

from exudyn_sweep_models import penalty_two_wheeler, penalty_wheel  # noqa: E402


def _position(mbs, node):
    return np.array(mbs.GetNodeOutput(node, exu.OutputVariableType.Position))


def _exudyn_and_bridge(method):
    """(Exudyn's own position at the end, the bridge's, the bridge's statistics) of the wheel."""
    mbs, s, node = penalty_wheel()
    mbs.SolveDynamic(s, showHints=False)
    ref = _position(mbs, node)
    mbs, s, node = penalty_wheel()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelNote)
        SolveDynamic(mbs, s, method=method)
    return ref, _position(mbs, node), mbs.sys["lgtBridgeStats"]


def test_penalty_wheel_genalpha_takes_exudyns_steps_and_its_result():
    """genalpha at Exudyn's 100 steps: 100 steps (no cut) and Exudyn's own generalized-α's
    position at the same steps to 1e-6 (measured 3.6e-7; cutting every step, it was 3e-6)."""
    ref, x, st = _exudyn_and_bridge("genalpha")
    assert st["success"] and st["n_steps"] == 100
    assert np.abs(x - ref).max() < 1e-6


def test_penalty_wheel_adaptive_runs_at_its_own_steps():
    """dopri5 at the script's settings: a few hundred steps (3750 when every move was a switch),
    within the step dependence the note announces of Exudyn's result (measured 1.1e-5 m)."""
    ref, x, st = _exudyn_and_bridge("dopri5")
    assert st["success"] and st["n_steps"] < 500
    assert np.abs(x - ref).max() < 1e-4


def test_a_lagged_force_is_named_when_the_model_is_wrapped():
    mbs, s, _ = penalty_wheel()
    with pytest.warns(ModelNote, match=r"ConnectorRollingDiscPenalty.*slip velocity stored at the last step's end"):
        ExudynModel(mbs, s)


def _body_position(mbs, body):
    return np.array(mbs.GetObjectOutputBody(body, exu.OutputVariableType.Position, [0, 0, 0]))


def _two_wheeler_errors(t_end, n, refine):
    """(the bridge's genalpha statistics, its error, Exudyn's own error at the same steps): the
    board's wheel position against Exudyn's own solver refined ``refine`` times."""
    mbs, s, wheel = penalty_two_wheeler(t_end, n * refine)
    mbs.SolveDynamic(s, showHints=False)
    ref = _body_position(mbs, wheel)
    mbs, s, wheel = penalty_two_wheeler(t_end, n)
    mbs.SolveDynamic(s, showHints=False)
    own = np.abs(_body_position(mbs, wheel) - ref).max()
    mbs, s, wheel = penalty_two_wheeler(t_end, n)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelNote)
        SolveDynamic(mbs, s, method="genalpha")
    return mbs.sys["lgtBridgeStats"], np.abs(_body_position(mbs, wheel) - ref).max(), own


def test_states_that_never_settle_keep_the_step_as_exudyn_does():
    """Exudyn's createRollingDiscPenaltyTest.py: a sticking wheel's friction direction flips at
    every discontinuous iteration (dry friction without a proportional zone). Exudyn solves a
    step maxIterations = 5 times and keeps the states of its last solve (ignoreMaxIterations =
    True, its default), so the force a step keeps depends on the parity of that count. The
    bridge solved once more (maxIterations redos): the kept force was biased, 4e-4 m off here
    and 4.5e-3 m at the script's end, and cutting such steps to a sixteenth of Exudyn's step
    made up for it (960 steps here, 75 s for the script). With Exudyn's count and the steps
    kept, genalpha takes Exudyn's 50 steps, within 5e-5 m of Exudyn's own solver refined 200×
    and closer than Exudyn's own at the same steps (measured 2.3e-5 against 1.6e-4)."""
    st, err, own = _two_wheeler_errors(0.1, 50, 200)
    assert st["success"] and st["n_steps"] <= 1.5 * 50                  # (measured 50)
    assert err < 5e-5 and err < own


def test_the_two_wheeler_script_runs_at_its_steps_as_accurately_as_exudyn():
    """The script's whole run (1 s, 500 steps): genalpha at most 1.5× the script's steps
    (measured 500; 8000 when unsettled steps were cut to a sixteenth), and no farther from
    Exudyn refined 20× than Exudyn's own solver at the script's steps (measured 1.5e-4 m
    against 2.9e-4; one solve more than Exudyn per step: 4.5e-3)."""
    st, err, own = _two_wheeler_errors(1.0, 500, 20)
    assert st["success"] and st["n_steps"] <= 1.5 * 500
    assert err < own


def test_lagged_forces_of_one_kind_are_named_in_one_note():
    """Exudyn's createRollingDiscPenaltyTest.py (two RollingDiscPenalty wheels): one note naming
    both objects (Exudyn's mobileMecanumWheelRobotWithLidar.py printed the same paragraph once
    per wheel, four times)."""
    mbs, s, _ = penalty_two_wheeler()
    wheels = [k for k in range(mbs.systemData.NumberOfObjects())
              if "RollingDiscPenalty" in str(mbs.GetObject(k)["objectType"])]
    assert len(wheels) == 2
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        ExudynModel(mbs, s)
    notes = [str(w.message) for w in rec if issubclass(w.category, ModelNote) and "RollingDiscPenalty" in str(w.message)]
    assert len(notes) == 1, notes
    for k in wheels:
        assert f" {k} '" in notes[0], (k, notes[0])
    assert "slip velocity stored at the last step's end" in notes[0]
