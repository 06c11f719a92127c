"""Modified Newton's verdict after each update of a fixed-step implicit method: converged,
go on, or refresh the stored iteration matrix (Hairer & Wanner, Solving Ordinary
Differential Equations II, IV.8).

The sizes of successive updates contract by θ ≈ ‖Δ_k‖/‖Δ_{k-1}‖, so the error left after
update k is about θ/(1 − θ)·‖Δ_k‖ (the sum of the updates still to come). The iteration
has converged when that estimate is within the tolerance: usually one update before the
update itself is (a plain ‖Δ_k‖ ≤ tol test needs one more update of size θ·tol).

A matrix kept from earlier steps contracts worse the older it is. It is kept as long as the
updates still to come, (log(tol (1 − θ)/(θ ‖Δ_k‖)) / log θ), bring the step's count within
``budget``: a refresh costs a Jacobian and a factorization, worth many residuals on large
models, while a slowly contracting but converging iteration costs a few residuals. θ is the
larger of the last two ratios: a stale matrix's ratios alternate (a pair of complex
eigenvalues of I − J_old⁻¹J), and the larger one bounds both the estimate and the count.
The first ratio never counts: the first update removes the predictor's error, which any
recent matrix resolves well (ratios of 1e-5 on a kept matrix that then contracts by 0.3 were
seen on a spinning top: trusting them left errors 100x the tolerance).

On the ANCF cable pendulum (104 coordinates, 1000 steps) a budget of 10 took 57 Jacobians and
6429 updates where refreshing at a contraction of 0.1 took 121 and 6118; 8: 79 and 5772.
"""
import math

import numpy as np

CONVERGED, AT_FLOOR, CONTINUE, REFRESH = "converged", "at the floor", "continue", "refresh"

#: contraction at or above which a kept matrix is refreshed whatever the count
THETA_MAX = 0.5
#: the rounding floor of the Newton updates, in units of its estimate (:func:`tolerances`)
FLOOR = 100.0
_EPS = float(np.finfo(float).eps)


def tolerances(W, q, newton_tol, h, beta, constrained):
    """(tol, floor) of generalized-α's Newton updates' RMS size h·|ΔẆ|/√n (a velocity).

    tol = newton_tol·(1 + |W|_RMS): relative to the size of the velocities W, per
    unknown (the Euclidean norm over a 40-body chain's 240 unknowns was 15x a 1-body
    model's: the same accuracy failed on the larger model).
    floor: the level the residual's rounding sets. The position rows g/(h²β) of a
    ``constrained`` model carry rounding eps·|q|, which moves Ẇ by eps·|q|/(h²β) and h·Ẇ by
    eps·|q|/(hβ); the force rows move it by eps·(1 + |W|). It grows as h falls, so halving
    the step cannot get below it: an update that stops falling below FLOOR times this is
    converged."""
    w_rms = math.sqrt(W.dot(W) / max(len(W), 1))
    tol = newton_tol * (1.0 + w_rms)
    qmax = float(np.abs(q).max()) if len(q) and constrained else 0.0
    floor = FLOOR * _EPS * ((1.0 + w_rms) + (qmax / (h * beta) if constrained else 0.0))
    return tol, max(tol, floor)


def contraction(sizes):
    """θ from the update sizes since the matrix was last refreshed: the larger of the last
    two ratios, never the first ratio (the first update removes the predictor's error, which
    the matrix resolves well, and the error left contracts at the matrix's own rate, up to
    1000x slower on a kept matrix); None before three updates."""
    k = len(sizes)
    if k < 3:
        return None
    theta = sizes[-1] / sizes[-2]
    return theta if k == 3 else max(theta, sizes[-2] / sizes[-3])


def verdict(sizes, tol, floor, budget):
    """What to do after the last of ``sizes`` (the update sizes since the matrix was last
    refreshed, all finite): CONVERGED (the update, or from the third update on its estimated
    error, within ``tol``), AT_FLOOR (the updates stopped falling at the rounding floor
    ``floor``: converged as far as the residual can tell), REFRESH (a contraction θ ≥
    THETA_MAX, the first ratio included, or more than ``budget`` updates in all
    predicted) or CONTINUE."""
    size = sizes[-1]
    if size <= tol:
        return CONVERGED
    if len(sizes) < 2:
        return CONTINUE
    if size <= floor and size >= 0.5 * sizes[-2]:
        return AT_FLOOR
    if size >= THETA_MAX * sizes[-2]:
        return REFRESH
    theta = contraction(sizes)
    if theta is None:
        return CONTINUE
    if theta * size <= tol * (1.0 - theta):
        return CONVERGED
    if theta >= THETA_MAX:
        return REFRESH
    left = math.log(tol * (1.0 - theta) / (theta * size)) / math.log(theta)
    return REFRESH if len(sizes) + left > budget else CONTINUE
