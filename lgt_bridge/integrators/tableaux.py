"""Explicit Butcher tableaux, as data. ``b_err`` is the embedded lower-order
weight vector (for error control); ``fsal``: the last stage is the end point."""
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Tableau:
    name: str
    A: np.ndarray
    b: np.ndarray
    c: np.ndarray
    order: int
    b_err: np.ndarray = None
    fsal: bool = False

    @property
    def stages(self):
        return len(self.b)


EULER = Tableau("euler", np.array([[0.0]]), np.array([1.0]), np.array([0.0]), 1)

# Heun (explicit trapezoidal rule)
RK2 = Tableau("rkmk2", np.array([[0.0, 0.0], [1.0, 0.0]]), np.array([0.5, 0.5]), np.array([0.0, 1.0]), 2)

RK4 = Tableau("rkmk4",
              np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0]], float),
              np.array([1 / 6, 1 / 3, 1 / 3, 1 / 6]), np.array([0, 0.5, 0.5, 1.0]), 4)

# Dormand-Prince 5(4) (Hairer, Nørsett, Wanner, Table II.5.2; scipy RK45)
DOPRI5 = Tableau(
    "dopri5",
    np.array([
        [0, 0, 0, 0, 0, 0, 0],
        [1 / 5, 0, 0, 0, 0, 0, 0],
        [3 / 40, 9 / 40, 0, 0, 0, 0, 0],
        [44 / 45, -56 / 15, 32 / 9, 0, 0, 0, 0],
        [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0, 0, 0],
        [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0, 0],
        [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0]]),
    np.array([35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0]),
    np.array([0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1, 1]),
    5,
    b_err=np.array([5179 / 57600, 0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40]),
    fsal=True)

FIXED = {t.name: t for t in (EULER, RK2, RK4)}
ADAPTIVE = {DOPRI5.name: DOPRI5}
