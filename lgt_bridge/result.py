"""What a run returns: :class:`SimulationResult`."""
from dataclasses import dataclass, field

import numpy as np

from .errors import StepError


@dataclass
class SimulationResult:
    """Output of :func:`~lgt_bridge.simulate` and :meth:`~lgt_bridge.Simulation.run`: ``t``
    (n,), ``q`` (n, nq) in the engine's own coordinates, ``V`` (n, nv) as (ω body,
    ṙ inertial) per body, ``success``, ``message`` and ``stats`` (n_steps, n_f, n_rejected,
    n_newton, wall_s, and the constraint residuals before/after projection where there are
    constraints). With ``events``: ``t_events`` (one array of times per event function, as
    scipy's ``sol.t_events``), ``q_events`` and ``V_events`` (per event function an array
    (n, nq) / (n, nv) of the states there, as scipy's ``sol.y_events``); None without."""

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
        if not self.success:
            raise StepError(self.message)
        return self
