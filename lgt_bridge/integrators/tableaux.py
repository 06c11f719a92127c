"""Explicit Butcher tableaux, as data. ``b_err`` is the embedded lower-order
weight vector (for error control); ``fsal``: the last stage is the end point.

Adaptive pairs also carry their error weights ``e5`` (and ``e3`` for DOP853's
5th/3rd-order estimate), err = h Σ e_i K_i, their step-size controller constants and
their continuous extension (dense output): ``P`` (Dormand-Prince 5(4): y(θ) = y_0 +
h Σ_i K_i Σ_k P_ik θ^(k+1)) or ``extra`` = (A rows, c) of the extra stages and ``D``
(DOP853, Hairer's contd8). DOP853's coefficients are scipy's (``scipy.integrate._ivp.
dop853_coefficients``, Hairer's dop853.f): about 200 published numbers we do not
retype; tests/core/test_dop853.py checks them against the order conditions.
"""
from dataclasses import dataclass
from functools import lru_cache

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
    e5: np.ndarray = None       # error weights (default b - b_err)
    e3: np.ndarray = None       # DOP853: the 3rd-order estimate's weights
    P: np.ndarray = None        # Dormand-Prince dense output
    extra: tuple = None         # DOP853 dense output: (A rows, c) of the extra stages
    D: np.ndarray = None        # DOP853 dense output coefficients
    err_order: int = None       # order of the controller's exponent 1/err_order
    control: tuple = (0.17, 0.04, 0.2, 10.0)    # (α, β, facmin, facmax): PI control h·err^-α·err_prev^β

    @property
    def stages(self):
        return len(self.b)

    @property
    def dense(self):
        return self.P is not None or self.D is not None


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
    fsal=True,
    # Hairer-Wanner's continuous extension of DOPRI5 (4th order; scipy RK45.P)
    P=np.array([
        [1, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
        [0, 0, 0, 0],
        [0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
        [0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
        [0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
        [0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
        [0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423]]),
    err_order=5)


@lru_cache(maxsize=1)
def dop853():
    """Hairer's DOP853 as a 13-stage tableau: the 12 stages of the step and the end point
    (FSAL), with the 5th- and 3rd-order error weights over those 13, and the 3 extra
    stages and coefficients of its 7th-order continuous extension."""
    from scipy.integrate._ivp import dop853_coefficients as co
    n = co.N_STAGES                                      # 12
    A = np.zeros((n + 1, n + 1))
    A[:n, :n] = co.A[:n, :n]
    A[n, :n] = co.B
    return Tableau("dop853", A, np.append(co.B, 0.0), np.append(co.C[:n], 1.0), 8,
                   fsal=True, e5=np.array(co.E5, float), e3=np.array(co.E3, float),
                   extra=(np.array(co.A[n + 1:], float), np.array(co.C[n + 1:], float)),
                   D=np.array(co.D, float), err_order=8, control=(0.125, 0.0, 1 / 3, 6.0))


FIXED = {t.name: t for t in (EULER, RK2, RK4)}
ADAPTIVE = {DOPRI5.name: lambda: DOPRI5, "dop853": dop853}


def fixed_form(tab):
    """The tableau of an embedded pair for fixed steps: its propagating weights b, without
    the FSAL end-point stage (b is 0 there; a fixed step would evaluate it for nothing)."""
    k = tab.stages - 1 if tab.fsal and tab.b[-1] == 0.0 else tab.stages
    return Tableau(tab.name, tab.A[:k, :k], tab.b[:k], tab.c[:k], tab.order)
