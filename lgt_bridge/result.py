"""What a run returns: :class:`SimulationResult`."""
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
