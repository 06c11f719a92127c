"""The step loop of an embedded RKMK pair (dopri5, dop853) in one compiled kernel.

The stepper of :mod:`lgt_bridge.integrators.rkmk` driven from Python
(:meth:`lgt_bridge.Simulation._step` and ``AdaptiveRK._attempt``) spends about 1 µs of
Python per stage and 20 µs per step around the stage kernels, as much as the model's f on a
small robot. :func:`drive` runs the same loop between two evaluations of f: it takes the
model's V̇ of the pending stage and does everything up to the next stage's state — the
stage derivative, the next stage, or the step's end, its error norm, Hairer's stiffness
test, the PI controller, the landing of the last stretch on the target, acceptance or
rejection, the FSAL stage — and returns the next f's time (the state in the work array,
as :func:`.stage.stage` leaves it). So a run is one kernel call and one f per stage
(:mod:`lgt_bridge.integrators.compiled_loop`). :func:`drive` itself handles the common call
(a stage that is not a step's last) and :func:`_advance` the rest.

It returns NaN to hand back to Python, with a code in ``C[CODE]``: ``ACCEPTED`` after an
accepted step that reaches the stop time, after every accepted step when asked (on-step
hooks, engines' write-back), and every ``C[BUDGET]`` accepted steps (the budget window, or a
progress bar's stride); ``PY_STEP`` when the next attempt is one the Python stepper must do
itself (the step budget is spent, a stage left its chart or is not finite, a non-finite end
state): the attempt is abandoned, its start unchanged; ``UNDERFLOW`` and ``MIN_STEP`` when
the step size fell below what the run allows. The arithmetic is the Python stepper's,
operation for operation (tests: equal runs).

``C`` holds the loop's state and settings at the slots named below.
"""
import math

import numpy as np
from numba import njit

from . import guard_cache
from .stage import OP, OQK, OPK, OW0, NB_, NQ_, NV_, NX_, stage, step_end
from .views import block, matrix

guard_cache(__file__, extra=(__file__.replace("steps.py", "stage.py"),))

# slots of the state array C
(T, H, HT, HIT, TARGET, STOP, CODE, STAGE, HBEFORE, NSTEPS, MAXSTEPS, NREJ, NF, CUR, FSAL, HCAY, HSTABLE,
 RHO, NSTIFF, NNONSTIFF, STIFF_T, STIFF_H, STIFF_RHO, ERRPREV, CAP, ALPHA, BETA, FACMIN, FACMAX, ORDER,
 SAFETY, RTOL, ATOL, CLIMIT, MAXSTEP, MINSTEP, LANDING, GROWS, BOUND, RHODECAY, STIFFSTEPS, HASPAIR,
 HASE3, TABFSAL, NSTAGES, NY, EACH, BUDGET, ROLL, ACC, TPREV, HPREV,
 # the loop array's layout: offsets of S, TA, BX, BW, the rows of TA and of a buffer set
 OS, OTA, OBX, OBW, NTA, NBUF) = range(58)
NC = 58


def layout(ns, n_rows, nbuf, nX, nv, n_save):
    """The loop array of a stepper: C (NC entries), the save area S (n_save), TA (n_rows × ns),
    the two sets of stage buffers BX (2 × nbuf × nX), BW (2 × nbuf × nv); returns (C's layout
    entries OS..NBUF, the array's size)."""
    o_s = NC
    o_ta = o_s + n_save
    o_bx = o_ta + n_rows * ns
    o_bw = o_bx + 2 * nbuf * nX
    return (o_s, o_ta, o_bx, o_bw, n_rows, nbuf), o_bw + 2 * nbuf * nv


@njit(cache=True, error_model="numpy", inline="always")
def parts(L, nX, nv, nq, nb):
    """(C, S, TA, BX, BW) as views of the loop array (:func:`layout`)."""
    C = L[:NC]
    ns = int(C[NSTAGES])
    o_s, o_ta, o_bx, o_bw, nta, nbuf = int(C[OS]), int(C[OTA]), int(C[OBX]), int(C[OBW]), int(C[NTA]), int(C[NBUF])
    S = L[o_s:o_ta]
    TA = matrix(L[o_ta:], nta, ns)
    BX = block(L[o_bx:], 2, nbuf, nX)
    BW = block(L[o_bw:], 2, nbuf, nv)
    return C, S, TA, BX, BW

ACCEPTED, PY_STEP, UNDERFLOW, MIN_STEP = 1, 2, 3, 4


@njit(cache=True, error_model="numpy", inline="always")
def _exit(C, code):
    """Back to Python with ``code`` (in C[CODE]): NaN, where the next f's time goes."""
    C[CODE] = code
    return np.nan


@njit(cache=True, error_model="numpy", inline="always")
def _roll(w, off, nend, S):
    """The accepted step's end as the next step's start: W0 = W1, q_k = q1, p_k = p1 (from
    the save area S = [X1, W1, q1, V1, p1])."""
    nX, nv, nq, nb = off[NX_], off[NV_], off[NQ_], off[NB_]
    for j in range(nv):
        w[off[OW0] + j] = S[nX + j]
    for j in range(nq):
        w[off[OQK] + j] = S[nX + nv + j]
    for j in range(4 * nb):
        w[off[OPK] + j] = S[nend + j]


@njit("float64(float64[:], float64[::1], int64[::1], float64[::1])", cache=True, error_model="numpy")
def _advance(Vd, w, I, L):
    """Advance the step loop to the next f (see the module's docstring). ``Vd``: the model's
    V̇ at the pending stage (empty: none pending); w, I: the problem's work array and tables;
    L: the loop array (:func:`layout`, one argument instead of five: a numba call costs
    ~0.1 µs per argument), with the loop's state C, the last accepted step's end S = [X1,
    W1, q1, V1, p1] (written at each acceptance), the tableau TA (A's ns rows, c, then the
    pair's rows b, e5, e3 and the stiffness test's two) and the stepper's two sets of stage
    buffers BX, BW."""
    off = I[:15]
    nX, nv, nq, nb = off[NX_], off[NV_], off[NQ_], off[NB_]
    C, S, TA, BX, BW = parts(L, nX, nv, nq, nb)
    nend = off[OW0]                      # X, W, q, V: the work array's first entries
    ns = int(C[NSTAGES])
    Tp = TA[ns + 1:]
    cur = int(C[CUR])
    KX, KW = BX[cur], BW[cur]
    t, h_try, target = C[T], C[HT], C[TARGET]
    climit = C[CLIMIT]
    empty = Vd[:0]
    if Vd.shape[0] > 0:
        C[NF] += 1.0
        i = int(C[STAGE])
        if i < ns - 1:                                   # the next stage
            cm = stage(Vd, KX, KW, TA[i + 1], i + 1, h_try, w, I)
            if cm < 0.0 or cm > climit:
                C[STAGE] = -1.0
                return _exit(C, PY_STEP)
            C[STAGE] = i + 1.0
            return t + TA[ns, i + 1] * h_try
        # the step's end (AdaptiveRK._attempt)
        C[STAGE] = -1.0
        st, s5, s3, num, den, sq = step_end(Vd, KX, KW, Tp, ns, h_try, w, I, C[RTOL], C[ATOL])
        if st < 0.0:
            return _exit(C, PY_STEP)
        if C[HASE3] == 0.0:
            en = abs(h_try) * math.sqrt(s5 / C[NY])
        elif s5 == 0.0 and s3 == 0.0:
            en = 0.0
        else:
            en = abs(h_try) * s5 / math.sqrt((s5 + 0.01 * s3) * C[NY])
        h = C[H]
        if not math.isfinite(en):
            C[NREJ] += 1.0
            accepted, h_new = False, 0.25 * h_try
        elif en > 1.0:
            C[NREJ] += 1.0
            C[CAP] = 1.0
            accepted, h_new = False, h_try * max(C[FACMIN], C[SAFETY] * en ** (-1.0 / C[ORDER]))
        else:
            if not sq - sq == 0.0:                       # q1 or V1 not finite: the stepper's finish
                return _exit(C, PY_STEP)
            accepted = True
            if C[HASPAIR] != 0.0:                        # Hairer's stiffness test (_detect_stiffness)
                dd = den * (h_try * h_try)
                mem = C[RHO] * C[RHODECAY]
                capped = h_try >= 0.95 * C[HSTABLE]
                if not dd > 0.0 or not math.isfinite(num):
                    C[RHO] = mem
                    C[HSTABLE] = C[BOUND] / mem if mem > 0.0 else np.inf
                else:
                    rho = math.sqrt(num / dd)
                    mem = max(rho, mem)
                    C[RHO] = mem
                    C[HSTABLE] = C[BOUND] / mem if mem > 0.0 else np.inf
                    if h_try * rho > C[BOUND] or capped:
                        C[NSTIFF] += 1.0
                        C[NNONSTIFF] = 0.0
                        if C[NSTIFF] >= C[STIFFSTEPS]:
                            C[STIFF_T], C[STIFF_H], C[STIFF_RHO] = t + h_try, C[HSTABLE], mem
                    else:
                        C[NNONSTIFF] += 1.0
                        if C[NNONSTIFF] >= 6.0:
                            C[NSTIFF] = 0.0
                            C[STIFF_T] = np.nan
            # the PI controller (control.PIController.accepted)
            cap = C[CAP]
            if en > 0:
                fac = C[SAFETY] * en ** -C[ALPHA] * C[ERRPREV] ** C[BETA]
            else:
                fac = cap
            fac = min(cap, max(C[FACMIN], fac))
            C[ERRPREV] = max(en, 1e-4)
            C[CAP] = C[FACMAX]
            # the end state saved, the buffers swapped (the accepted step's stay for its dense output)
            for j in range(nend):
                S[j] = w[j]
            for j in range(4 * nb):
                S[nend + j] = w[off[OP] + j]
            other = 1 - cur
            if C[TABFSAL] != 0.0:
                nst = int(C[NSTAGES])
                for j in range(nv):
                    BW[other, 0, j] = KW[nst - 1, j]
                C[FSAL] = 1.0
            else:
                C[FSAL] = 0.0
            C[CUR] = other
            h_new = min(h_try * fac, C[HCAY], max(h_try, C[HSTABLE]))
            C[HCAY] *= 1.2
        # the driver's part (Simulation._step)
        if accepted:
            C[NSTEPS] += 1.0
            C[TPREV], C[HPREV] = t, h_try
            t = target if C[HIT] != 0.0 else t + h_try
            C[T] = t
            if h_try < h:
                carried = h * min(1.0, h_new / h_try)
                h_new = max(h_new, carried) if C[GROWS] != 0.0 else carried
            C[H] = h = min(h_new, max(h_try, C[HSTABLE]), C[MAXSTEP])
            C[ROLL] = C[ACC] = 1.0
            stop = C[STOP]
            if (C[EACH] != 0.0 or t >= stop - 1e-12 * max(1.0, abs(stop))
                    or C[NSTEPS] % C[BUDGET] == 0.0):
                return _exit(C, ACCEPTED)
        else:
            C[H] = h = h_new
            if h < 1e-14 * max(1.0, abs(t)):
                return _exit(C, UNDERFLOW)
        if h < C[MINSTEP] and h < C[HBEFORE] and t < target - 1e-12 * max(1.0, abs(target)):
            return _exit(C, MIN_STEP)
    # a new attempt (Simulation._step's start, AdaptiveRK.run_stages)
    if C[NSTEPS] >= C[MAXSTEPS]:
        return _exit(C, PY_STEP)
    h = C[H]
    C[HBEFORE] = h
    rem = target - t
    if h < rem <= C[LANDING] * h:
        h_try = rem / math.ceil(rem / h - 1e-9)
    else:
        h_try = min(h, rem)
    hit = target - (t + h_try) <= 1e-12 * max(1.0, abs(target))
    if hit:
        h_try = target - t
    C[HIT] = 1.0 if hit else 0.0
    C[HT] = h_try
    if C[ROLL] != 0.0:
        _roll(w, off, nend, S)
        C[ROLL] = 0.0
    cur = int(C[CUR])
    KX, KW = BX[cur], BW[cur]
    i0 = 0
    if C[FSAL] != 0.0:
        stage(empty, KX, KW, TA[0], 0, 0.0, w, I)        # the start's rates (start_rates)
        i0 = 1
    cm = stage(empty, KX, KW, TA[i0], i0, h_try, w, I)
    if cm > climit:
        return _exit(C, PY_STEP)
    C[STAGE] = float(i0)
    return t + TA[ns, i0] * h_try


@njit("float64(float64[:], float64[::1], int64[::1], float64[::1])", cache=True, error_model="numpy")
def drive(Vd, w, I, L):
    """Advance the step loop to the next f (see the module's docstring and :func:`_advance`,
    which does all of it but the common case here: the model's V̇ of a stage that is not a
    step's last, whose derivative and the next stage's state are one call of the compiled
    stage kernel — in a small function, since this is every call but one a step)."""
    C = L[:NC]
    i = int(C[STAGE])
    ns = int(C[NSTAGES])
    if Vd.shape[0] > 0 and i < ns - 1:
        nX, nv = I[NX_], I[NV_]
        cur, nbuf = int(C[CUR]), int(C[NBUF])
        o_bx = int(C[OBX]) + cur * nbuf * nX
        o_bw = int(C[OBW]) + cur * nbuf * nv
        KX = matrix(L[o_bx:], nbuf, nX)
        KW = matrix(L[o_bw:], nbuf, nv)
        o_ta = int(C[OTA])
        h_try = C[HT]
        C[NF] += 1.0
        cm = stage(Vd, KX, KW, L[o_ta + (i + 1) * ns:o_ta + (i + 2) * ns], i + 1, h_try, w, I)
        if cm < 0.0 or cm > C[CLIMIT]:
            C[STAGE] = -1.0
            return _exit(C, PY_STEP)
        C[STAGE] = i + 1.0
        return C[T] + L[o_ta + ns * ns + i + 1] * h_try
    return _advance(Vd, w, I, L)


# --- the starting step ---------------------------------------------------------------------
# Hairer–Nørsett–Wanner's rule as :func:`lgt_bridge.integrators.control.initial_step` writes it
# (the reference), on y = (X, W) from X = 0 with f0 = (fX, fW): its arithmetic in two calls
# around the one f it needs (about twenty numpy operations on short vectors otherwise, as much
# as a small robot's whole set-up). sc = atol + rtol |y0| is atol on X (y0's X is 0).
@njit("UniTuple(float64, 2)(float64[::1], float64[::1], float64[::1], float64, float64, float64[::1])",
      cache=True, error_model="numpy")
def h0_start(fX, fW, W, rtol, atol, Y):
    """(h0, d1): the trial step h0 = 0.01 d0/d1 (1e-6 when either is below 1e-5) and d1 = |f0|
    (scaled RMS, :func:`h0_end` takes it), and Y = y0 + h0 f0."""
    nX, nv = len(fX), len(fW)
    n = nX + nv
    s0 = s1 = 0.0
    for i in range(nX):
        x = fX[i] / atol
        s1 += x * x
    for i in range(nv):
        sc = atol + rtol * abs(W[i])
        x = W[i] / sc
        s0 += x * x
        x = fW[i] / sc
        s1 += x * x
    d0 = math.sqrt(s0 / n) if n else 0.0
    d1 = math.sqrt(s1 / n) if n else 0.0
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    for i in range(nX):
        Y[i] = h0 * fX[i]
    for i in range(nv):
        Y[nX + i] = W[i] + h0 * fW[i]
    return h0, d1


@njit("float64(float64[::1], float64[::1], float64[::1], float64[::1], float64, float64, float64, float64, float64)",
      cache=True, error_model="numpy")
def h0_end(f1, fX, fW, W, rtol, atol, h0, d1, order):
    """The starting step from f1 = f(y0 + h0 f0) and :func:`h0_start`'s (h0, d1): d2 = |f1 - f0| / h0
    and min(100 h0, (0.01 / max(d1, d2))^(1/order)) (max(1e-6, 1e-3 h0) when both vanish)."""
    nX, nv = len(fX), len(fW)
    n = nX + nv
    s2 = 0.0
    for i in range(nX):
        x = (f1[i] - fX[i]) / atol
        s2 += x * x
    for i in range(nv):
        x = (f1[nX + i] - fW[i]) / (atol + rtol * abs(W[i]))
        s2 += x * x
    d2 = (math.sqrt(s2 / n) if n else 0.0) / h0
    m = d2 if d2 > d1 else d1                   # Python's max(d1, d2), NaN included
    if m <= 1e-15:
        x = h0 * 1e-3
        h1 = x if x > 1e-6 else 1e-6
    else:
        h1 = (0.01 / m) ** (1.0 / order)
    x = 100 * h0
    return h1 if h1 < x else x
