"""lgt_bridge.switches: a model's discrete mode kept through each step and its switches
located on the step's dense output, against the closed-form motion of a point dropped on a
penalty floor whose contact is active while its gap is closed and its force compressive
(tests/models/contact_reference.py; the rule of Exudyn's GeneralContact active sets)."""
import numpy as np
import pytest

from lgt_bridge import Simulation, simulate, switches
from lgt_bridge.model import Layout, Model

import contact_reference as cr

R, M, G, K, D = 0.1, 0.1, 9.81, 5e3, 20.0


class _Drop(Model):
    """A mass point over the floor y = 0 (vector-space y), its contact force from the mode
    (``active``) set by switch_mode only, as Exudyn's active sets are."""

    def __init__(self, y0=0.55, with_switches=True):
        self.layout = Layout.stacked([], n_vector=1)
        self.q0, self.V0 = np.array([y0]), np.array([-1.0])
        self.active = False
        if with_switches:
            self.switch_mode = self._mode

    def _mode(self, q, V, t):
        gap = q[0] - R
        self.active = bool(gap < 0 and K * gap + D * V[0] < 0)
        return self.active

    def f(self, q, V, t):
        F = -(K * (q[0] - R) + D * V[0]) if self.active else 0.0
        return np.array([-G + F / M])


@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_switches_located_and_error_falls_with_tolerance(method):
    (y, v), sw = cr.drop(0.55, -1.0, 0.5)
    errs = []
    for tol in (1e-10, 1e-12):
        sim = Simulation(_Drop(), method=method, rtol=tol, atol=tol, t_end=0.5)
        r = sim.run(0.5)
        assert r.success and r.stats["n_switches"] == len(sw)
        # located to the step's continuous extension's accuracy (xtol = 0.01 tol h)
        assert np.abs(np.array(sim._switches.t_switches) - sw).max() < 100 * tol
        errs.append(max(abs(r.q[-1, 0] - y), abs(r.V[-1, 0] - v)))
    assert errs[0] < 2e-9 and errs[1] < 2e-11 and errs[1] < errs[0] / 10, errs


def test_outputs_across_cut_steps_follow_the_exact_motion():
    """t_eval outputs come from the dense output of steps that were cut at a switch: only
    the part before the cut is used."""
    ts = np.linspace(0.0, 0.5, 201)[1:]
    r = simulate(_Drop(), (0.0, 0.5), method="dop853", rtol=1e-11, atol=1e-11, t_eval=ts)
    ref = np.array([cr.drop(0.55, -1.0, t)[0][0] for t in ts])
    assert r.success and np.abs(r.q[:, 0] - ref).max() < 1e-9


def test_without_dense_output_the_mode_comes_from_each_steps_start():
    """rkmk4 (no dense output) takes the mode at each step's start, as Exudyn's own steps do:
    the point bounces (it would fall through with the mode never set) and the error is
    first order in the step (one step's worth of the damping jump per switch)."""
    (y, v), _ = cr.drop(0.55, -1.0, 0.5)
    errs = []
    for dt in (1e-4, 2.5e-5):
        r = simulate(_Drop(), (0.0, 0.5), method="rkmk4", dt=dt)
        assert r.success and r.q[:, 0].min() > 0.09
        errs.append(abs(r.V[-1, 0] - v))
    assert errs[1] < errs[0] / 2.5, errs


def test_a_model_without_switch_mode_is_untouched():
    r = simulate(_Drop(with_switches=False), (0.0, 0.5), method="dopri5", rtol=1e-8, atol=1e-8)
    assert "n_switches" not in r.stats
    assert abs(r.q[-1, 0] - (0.55 - 0.5 - 0.5 * G * 0.25)) < 1e-9       # free fall: no mode ever set


# --- discontinuous states (post_step): a switch located, a move redone (REDO) ---------------------
class _Lagged(Model):
    """ẍ = -x + d: d a discontinuous state that post_step sets to x/2 at each step's end (a
    force reading a value stored at the last step's end, as Exudyn's RollingDiscPenalty reads
    its slip velocity). ``kind``: what post_step says when d moved by more than 1e-9 (REDO,
    True: a switch, or REDO always: states that never settle)."""

    def __init__(self, kind):
        self.layout = Layout.stacked([], n_vector=1)
        self.q0, self.V0 = np.array([1.0]), np.array([0.0])
        self.d, self.kind, self.calls = 0.0, kind, 0

    def f(self, q, V, t):
        return np.array([-q[0] + self.d])

    def discontinuous_state(self):
        return self.d

    def set_discontinuous_state(self, d):
        self.d = d

    def post_step(self, q, V, t):
        self.calls += 1
        new, old = 0.5 * q[0], self.d
        self.d = new
        if self.kind == "never":
            return switches.REDO
        return (switches.REDO if self.kind == "redo" else True) if abs(new - old) > 1e-9 else False


def test_states_that_move_redo_the_step_at_its_length():
    """REDO: each step is redone with the moved states (a fixed point d = x(t + h)/2, as
    Exudyn's discontinuous iteration) and kept at its length: rkmk4 takes its 50 steps; the
    motion approaches ẍ = -x/2 (d = x/2 at the step's end, an O(h) lag): x(1) within 2e-3 of
    cos(1/√2). The same moves reported as switches shorten every step."""
    redo, switch = _Lagged("redo"), _Lagged("switch")
    r = Simulation(redo, method="rkmk4", dt=0.02).run(1.0, t_eval=[1.0])
    assert r.success and r.stats["n_steps"] == 50
    assert abs(r.q[-1][0] - np.cos(1.0 / np.sqrt(2.0))) < 2e-3          # (measured 4e-4; d kept at 0: 0.22)
    s = Simulation(switch, method="rkmk4", dt=0.02)
    s.h_event = 1e-3
    assert s.run(1.0, t_eval=[1.0]).stats["n_steps"] > 200


def test_states_that_never_settle_shorten_the_step():
    """REDO after MAX_DISCONTINUOUS redos still moving: the step is shortened, as Exudyn does
    with ignoreMaxIterations = False, down to h_event, where it is kept."""
    m = _Lagged("never")
    s = Simulation(m, method="rkmk4", dt=0.02)
    s.h_event = 0.02 / 16
    r = s.run(0.1, t_eval=[0.1])
    assert r.success and r.stats["n_steps"] >= 0.1 / s.h_event - 1


def test_states_that_never_settle_are_kept_when_the_model_ignores_max_iterations():
    """A model with ``ignore_max_discontinuous`` (Exudyn's default ignoreMaxIterations = True)
    shortens an unsettled step only down to UNSETTLED_CUT of the run's step and keeps it there:
    rkmk4 at dt = 0.02 takes steps of 0.02/16 (80 over 0.1, a few more to land on the end:
    measured 92), where the same model without the flag goes on to h_event (0.02/64: 320
    steps; the last one, an ulp above h_event, was cut again forever)."""
    steps = []
    for ignore in (True, False):
        m = _Lagged("never")
        m.max_discontinuous, m.ignore_max_discontinuous = 3, ignore
        s = Simulation(m, method="rkmk4", dt=0.02)
        s.h_event = 0.02 / 64
        r = s.run(0.1, t_eval=[0.1])
        assert r.success
        steps.append(r.stats["n_steps"])
    n_cut = round(0.1 / (0.02 * switches.UNSETTLED_CUT))
    assert n_cut <= steps[0] <= 1.2 * n_cut and steps[1] >= 0.1 / (0.02 / 64) - 1, steps


def test_states_that_cannot_settle_are_kept_at_the_runs_step():
    """A model whose own ``unsettled_cut`` is 1 (Exudyn's RollingDiscPenalty with Coulomb
    friction: a sticking wheel's friction direction flips at every redo, however short the
    step) keeps unsettled states at the run's step, as Exudyn does: rkmk4 takes its 5 steps of
    0.02 over 0.1, after max_discontinuous redos each (a step landing on a time of the grid
    is longer than dt by an ulp: it counts as at it, not as a step to cut)."""
    m = _Lagged("never")
    m.max_discontinuous, m.ignore_max_discontinuous, m.unsettled_cut = 3, True, 1.0
    s = Simulation(m, method="rkmk4", dt=0.02)
    s.h_event = 0.02 / 64
    r = s.run(0.1, t_eval=[0.1])
    assert r.success and r.stats["n_steps"] == 5
    assert m.calls == 5 * (3 + 1)
