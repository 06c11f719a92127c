"""Step-size control shared by the adaptive methods: the one starting-step rule, the
scaled RMS norm, and the PI controller of the explicit pairs (radau5 keeps Hairer's
predictive controller of RADAU5 in its own module)."""
import math

import numpy as np


def rms(y):
    """Root mean square of a scaled vector (any shape; 0 for an empty one)."""
    v = y if y.ndim == 1 else y.ravel()
    return math.sqrt(float(v.dot(v)) / v.size) if v.size else 0.0


def initial_step(rates, nX, W, t, rtol, atol, order, f0=None):
    """Hairer–Nørsett–Wanner's starting step (Solving ODEs I, II.4) on y = (X, W) from
    X = 0, for a method whose error estimate is of order ``order - 1`` (the step is
    ``(0.01 / max(d1, d2))^(1/order)``). ``rates(X, W, t)`` is the local ODE's [Ẋ, Ẇ] (None
    when not finite); ``f0`` its value at the start, when known."""
    # (each numpy call on these short vectors costs about as much as its arithmetic: as few
    # as the rule allows, every value as the rule writes it)
    y0 = np.zeros(nX + len(W))
    y0[nX:] = W
    f0 = rates(np.zeros(nX), W, t) if f0 is None else f0
    sc = atol + rtol * np.abs(y0)
    d0, d1 = rms(y0 / sc), rms(f0 / sc)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    hf = h0 * f0
    f1 = rates(hf[:nX], W + hf[nX:], t + h0)
    if f1 is None:
        return h0
    f1 -= f0
    f1 /= sc
    d2 = rms(f1) / h0
    h1 = max(1e-6, h0 * 1e-3) if max(d1, d2) <= 1e-15 else (0.01 / max(d1, d2)) ** (1.0 / order)
    return min(100 * h0, h1)


class PIController:
    """h_new = h · clip(safety · err^-α · err_prev^β, facmin, facmax) after an accepted step
    (Hairer–Wanner's PI control; β = 0: the classical controller), and
    h · max(facmin, safety · err^(-1/order)) after a rejected one, with no growth on the
    step after a rejection."""

    SAFETY = 0.9

    def __init__(self, alpha, beta, facmin, facmax, order):
        self.alpha, self.beta, self.facmin, self.facmax, self.order = alpha, beta, facmin, facmax, order
        self._cap = facmax
        self._err_prev = 1e-4

    def accepted(self, err):
        """The factor for the next step after an accepted step with error norm ``err`` ≤ 1."""
        fac = self.SAFETY * err ** -self.alpha * self._err_prev ** self.beta if err > 0 else self._cap
        fac = min(self._cap, max(self.facmin, fac))
        self._err_prev = max(err, 1e-4)
        self._cap = self.facmax
        return fac

    def rejected(self, err=None):
        """The factor for the retry after a rejected step (``err`` None: the step failed
        outright, e.g. blew up or left its chart; the caller picks its own retry)."""
        self._cap = 1.0
        if err is None:
            return None
        return max(self.facmin, self.SAFETY * err ** (-1.0 / self.order))
