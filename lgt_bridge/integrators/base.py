"""What every stepper shares: the local problem, the state, failure reporting."""
import math

import numpy as np

from ..errors import StepError


class StepFailed(Exception):
    """Internal: a step could not be completed; the driver turns it into a result."""

    def __init__(self, message, error=StepError):
        super().__init__(message)
        self.error = error


def first_nonfinite(layout, kind, arr):
    i = int(np.flatnonzero(~np.isfinite(arr))[0])
    return layout.owner(kind, i)


class Stepper:
    """Holds (q, W) between steps; ``attempt(t, h)`` advances or declines."""

    adaptive = False

    def __init__(self, problem, projector=None):
        self.prob = problem
        self.projector = projector
        self.n_rejected = 0
        self.n_newton = 0

    def set_state(self, q, V, W=None, quats=None, copy=True):
        """Start (or restart) from model coordinates (q, V); a step that ends at (q, V)
        passes its W and body quaternions along so they need not be recomputed
        (``copy=False``: q and V are fresh arrays the stepper may keep)."""
        self.q = np.array(q, float) if copy else q
        self.prob.start(self.q, quats)
        self.V = np.array(V, float) if copy else V
        self.W = self.prob.group_velocity(self.V, self.prob.start_quats) if W is None else W

    def check_finite(self, t, q, V):
        if math.isfinite(q.dot(q) + V.dot(V)):       # one reduction; inf/NaN propagate
            return
        for kind, arr in (("q", q), ("V", V)):
            if not np.isfinite(arr).all():
                raise StepFailed(f"non-finite {kind} at t = {t:.9g} in "
                                 f"{first_nonfinite(self.prob.layout, kind, arr)}; the model "
                                 "returned NaN/inf or the step diverged (try a smaller dt).")

    def finish(self, t1, q1, V1, W1=None, quats=None):
        """Accept (q1, V1) at t1, after projection onto the constraints if the model has them."""
        self.check_finite(t1, q1, V1)
        if self.projector is not None:
            q1, V1 = self.projector(q1, V1)
            W1 = quats = None
        self.set_state(q1, V1, W1, quats, copy=False)
