"""What a run returns: :class:`SimulationResult`."""
import time
from dataclasses import dataclass, field

import numpy as np

from .errors import StepError


@dataclass
class SimulationResult:
    """What :func:`~lgt_bridge.simulate` and :meth:`~lgt_bridge.Simulation.run` return.

    Attributes
    ----------
    t : ndarray, shape (n,)
        The output times (every step, or ``t_eval``).
    q : ndarray, shape (n, nq)
        The states in the engine's own coordinates (Exudyn's, Pinocchio's q).
    V : ndarray, shape (n, nv)
        The velocities as (ω body, ṙ inertial) per body, angular first.
    success : bool
        False when the run stopped early (the message says why; the states computed before
        are kept).
    message : str
        What happened: the end reached, a terminal event, or why the run stopped.
    stats : dict
        n_steps, n_f, n_rejected, n_newton, wall_s, and the constraint residuals
        before/after projection where there are constraints.
    method, group, chart
        The method and the resolved per-body groups and charts (after "auto").
    t_events : list of ndarray or None
        With ``events``: one array of times per event function, as scipy's
        ``sol.t_events``; None without events.
    q_events, V_events : list of ndarray or None
        Per event function, the states there, (n, nq) and (n, nv), as scipy's
        ``sol.y_events``.
    """

    t: np.ndarray
    q: np.ndarray
    V: np.ndarray
    success: bool
    message: str
    stats: dict = field(default_factory=dict)
    method: str = ""
    group: object = ""
    chart: object = ""
    t_events: list = None
    q_events: list = None
    V_events: list = None

    def raise_for_status(self):
        """The result itself when the run succeeded; else raise :class:`~lgt_bridge.StepError`
        with its message (for scripts that should stop on a failed run)."""
        if not self.success:
            raise StepError(self.message)
        return self


def collect(sim, ts, qs, Vs, success, message, wall0, n_steps0, tracker=None):
    """The :class:`SimulationResult` of one :meth:`Simulation.run <lgt_bridge.Simulation.run>`
    of ``sim`` from its outputs (``wall0``, ``n_steps0``: the wall clock and step count at
    its start; ``tracker``: its events, if any): the run's statistics, the largest constraint
    residual at the outputs of a run without projection."""
    wall = time.perf_counter() - wall0
    sim.wall_s += wall
    stats = sim.stats()
    stats.update(n_steps=sim.n_steps - n_steps0, wall_s=wall)
    model = sim.model
    if sim.stepper.projector is None and model.n_constraints and qs:
        rows = model.position_rows
        stats["constraint_residual"] = float(max(
            (np.abs(model.constraints_at(q, t)[rows]).max() if len(rows) else 0.0)
            for t, q in zip(ts, qs)))
    nq, nv = model.layout.nq, model.layout.nv
    res = SimulationResult(np.array(ts), np.array(qs).reshape(-1, nq), np.array(Vs).reshape(-1, nv),
                           success, message, stats, sim.method, sim.group, sim.chart)
    if tracker is not None:
        res.t_events, res.q_events, res.V_events = tracker.close()
    return res
