"""Runge-Kutta-Munthe-Kaas: an explicit tableau on the local ODE (X, W) from X = 0,
q_{k+1} = τ(q_k, X_{k+1}). Fixed step (euler, rkmk2, rkmk4) and embedded pairs
(Dormand-Prince 5(4), Hairer's DOP853 with its 5th/3rd-order estimate) with error
control on (X, W), step-size control and dense output: the continuous extension of
the pair on (X, W) within the step, mapped through τ of the step's own base.

The stages of a step are ``problem.run_stages(...)``: on the compiled backend one kernel
call and the model's f per stage over preallocated buffers, and an embedded pair's end
(end state, error sums, stiffness sums) is one more call, ``problem.end_step``
(:mod:`lgt_bridge.integrators.compiled`)."""
import math

import numpy as np

from ..errors import ChartDomainError
from . import tableaux
from .base import NULL_CONTEXT, ChartLimit, StepFailed, Stepper
from .control import PIController, initial_step


def build(method, problem, o):
    """The stepper of an RKMK method of the registry (fixed tableaux; embedded pairs, or
    their fixed form with ``o["fixed_steps"]``)."""
    if method.fixed:
        return FixedRK(problem, tableaux.FIXED[method.name], o["projector"])
    tab = tableaux.ADAPTIVE[method.name]()
    if o["fixed_steps"]:
        return FixedRK(problem, tableaux.fixed_form(tab), o["projector"])
    return AdaptiveRK(problem, tab, o["rtol"], o["atol"], o["projector"], first_step=o["dt"])


_COEFFICIENTS = {}


def _stage_coefficients(tableau):
    """(rows of A as contiguous arrays, b, c as Python floats) of a tableau, made once per
    tableau (a run's set-up is part of every call)."""
    key = id(tableau)
    got = _COEFFICIENTS.get(key)
    if got is None or got[0] is not tableau:
        if len(_COEFFICIENTS) > 64:          # tableaux made per call (fixed forms): keep it small
            _COEFFICIENTS.clear()
        c = [float(x) for x in tableau.c]
        ends = [i for i in range(tableau.stages) if c[i] == 1.0]
        got = _COEFFICIENTS[key] = (tableau, [np.ascontiguousarray(row, dtype=float) for row in tableau.A],
                                    np.ascontiguousarray(tableau.b, dtype=float), c, ends[-1] if ends else 0)
    return got[1:]


def _pair_constants(tableau):
    """(T, stiff_pair) of an embedded pair, made once per tableau: T's rows the weights
    b, e5, e3 over the stages and, for Hairer's stiffness test when the last two stages (i, j
    = stiff_pair, else None) are both at c = 1 (the stiffest rate seen by the step: ρ ≈
    |K_j - K_i| / |y_j - y_i|), the weights of K_j - K_i and of (y_j - y_i)/h."""
    key = ("pair", id(tableau))
    got = _COEFFICIENTS.get(key)
    if got is None or got[0] is not tableau:
        if len(_COEFFICIENTS) > 64:
            _COEFFICIENTS.clear()
        e5 = tableau.e5 if tableau.e5 is not None else tableau.b - tableau.b_err
        e5 = np.ascontiguousarray(e5, dtype=float)
        e3 = np.ascontiguousarray(tableau.e3 if tableau.e3 is not None else np.zeros_like(e5), dtype=float)
        ns = tableau.stages
        c = np.asarray(tableau.c, float)
        pair, d, a = ((ns - 2, ns - 1) if ns >= 2 and c[ns - 2] == 1.0 == c[ns - 1] else None), None, None
        if pair is not None:
            i, j = pair
            d, a = np.zeros(ns), np.zeros(ns)
            d[j], d[i] = 1.0, -1.0
            a[:j] = np.asarray(tableau.A[j], float)[:j] - np.asarray(tableau.A[i], float)[:j]
        rows = [tableau.b, e5, e3] + ([d, a] if pair is not None else [])
        got = _COEFFICIENTS[key] = (tableau, np.ascontiguousarray(np.array(rows, float)), pair)
    return got[1:]


class ExplicitRK(Stepper):

    def __init__(self, problem, tableau, projector=None):
        super().__init__(problem, projector)
        self.tab = tableau
        ns = tableau.stages + (len(tableau.extra[1]) if tableau.extra is not None else 0)
        # two sets of stage buffers: the last accepted step's stages stay valid for its
        # dense output while the next step is attempted in the other set; views of one
        # array per kind (the compiled step loop takes both sets in one argument each)
        self._BX, self._BW = np.zeros((2, ns, problem.nX)), np.zeros((2, ns, problem.nv))
        self._bufs = [(self._BX[k], self._BW[k]) for k in range(2)]
        self.KX, self.KW = self._bufs[0]
        # (_i_end: the stage nearest the step's end)
        self._A, self._b, self._c, self._i_end = _stage_coefficients(tableau)
        self._fsal = False                     # KW[0] holds the first stage of the next step
        self.climit = 1.0 if problem.bounded else np.inf     # stage chart usage |x|/limit
        self._last_KW = None                   # the stages' Ẇ of the last accepted step

    def set_state(self, q, V, W=None, quats=None, copy=True):
        super().set_state(q, V, W, quats, copy)
        self._fsal = False

    def step_rates(self):
        """(Ẇ at the start, Ẇ at the end) of the last accepted step from its stages, no f:
        the first stage, and the last stage at c = 1 (the end point itself for the FSAL
        pairs; RK4's and Heun's last stage, within O(h³) and O(h²) of it; Euler: the first
        stage again). None before the first step."""
        KW = self._last_KW
        return None if KW is None else (KW[0].copy(), KW[self._i_end].copy())

    def attempt(self, t, h):
        """One step attempt (see the subclasses' ``_attempt``). On the numpy backend the
        library's own arithmetic on a diverging step (overflow, inf - inf) would warn before
        the step is reported; those floating-point warnings are silenced inside the step,
        and non-finite values are reported as StepError naming the body (the compiled
        kernels never warn: their problem's context is a null one, not entered)."""
        quiet = self.prob.quiet()
        if quiet is NULL_CONTEXT:
            return self._attempt(t, h)
        with quiet:
            return self._attempt(t, h)

    def run_stages(self, t, h):
        """All stages of one step (ChartLimit when one leaves its chart's domain); the last
        stage's Ẇ is completed by the problem's ``end`` or ``end_step``."""
        prob = self.prob
        i0 = 0
        if self._fsal:
            prob.start_rates(self.KX, self.W)
            i0 = 1
        cm = prob.run_stages(self.KX, self.KW, self._A, self._c, i0, h, t, self.W, self.climit)
        if cm:
            raise ChartLimit.at(prob, cm)

    def stages(self, t, h):
        """All stages of one step; returns (X1, W1, q1, V1, quats) or raises ChartLimit."""
        self.run_stages(t, h)
        return self.prob.end(self.KX, self.KW, self._b, h, self.W)


class FixedRK(ExplicitRK):
    """Fixed steps. A step beyond the stability limit of the stiffest mode shows as a
    velocity change that grows geometrically from step to step (by |R(hλ)| > 1);
    GROWTH-fold growth over RUN consecutive steps is reported as instability (a
    resolved physical growth at rate λ grows by e^{λh} ≈ 1 + λh per step)."""

    GROWTH, RUN = 2.0, 5
    _dW, _grow = None, 0

    def _check_growth(self, t, h, W1):
        d = W1 - self.W
        dW = math.sqrt(d.dot(d))
        if self._dW is not None and dW > self.GROWTH * self._dW and dW > 1e-300:
            self._grow += 1
        else:
            self._grow = 0
        self._dW = dW
        if self._grow >= self.RUN:
            raise StepFailed(f"unstable at t = {t + h:.9g}: the velocity change per step grew more than "
                             f"{self.GROWTH:g}-fold in each of {self.RUN} consecutive steps (last |ΔV| = "
                             f"{dW:.3g}); dt = {h:.3g} is beyond this method's stability limit for the "
                             "stiffest mode. Reduce dt, or use genalpha or an adaptive method.")

    def _attempt(self, t, h):
        try:
            X1, W1, q1, V1, quats = self.stages(t, h)
        except ChartLimit as lim:
            raise StepFailed(lim.message(t, h), ChartDomainError) from None
        # every stage was checked finite; q1, V1 (built from X1, W1) are checked before the growth
        self.check_finite(t + h, q1, V1)
        self._check_growth(t, h, W1)
        self.finish(t + h, q1, V1, W1, quats, checked=True)
        self._last_KW = self.KW
        return True, None      # fixed step: the driver goes back to dt after a shortened landing step


class AdaptiveRK(ExplicitRK):
    """Embedded pair with step-size control (Hairer-Wanner: PI control for DOPRI5,
    err^(-1/8) with factors in [1/3, 6] for DOP853) and dense output.

    On a mildly stiff model (PD-controlled robots) the error control alone grows the step
    past the stability limit of the stiffest mode whenever that mode is quiet, and the step
    is rejected when it wakes (about one rejected step per 20 ms horizon on a PD-controlled
    talos). So a step grows no further than ``h_stable`` = bound/ρ, ρ the stiffest rate
    the accepted steps measured (Hairer's stiffness estimate, fading by RHO_DECAY per step);
    a step already beyond it is kept, not shrunk (the error control shrinks it if needed)."""

    adaptive = True
    # the last stretch to a target in up to four equal steps, the proposal free to grow after
    # them (to h_stable): no sliver of a step, and no proposal ratcheting down on them
    landing_steps, landing_grows = 4, True

    def __init__(self, problem, tableau, rtol, atol, projector=None, first_step=None):
        super().__init__(problem, tableau, projector)
        self.rtol, self.atol = rtol, atol
        self.h_next = first_step
        self.control = PIController(*tableau.control, order=tableau.err_order)
        self._T, self._stiff_pair = _pair_constants(tableau)
        self._n = problem.nX + problem.nv
        self._dense = None                     # DenseStep of the last accepted step (``dense``)
        self._dense_args = None                # what makes it, kept at each accepted step
        self._hcay = np.inf                    # steps below this keep bounded charts' stages in their domain
        self.dense_capable = tableau.dense
        self.stability_bound = self.STABILITY_BOUND.get(tableau.stages, 3.25)
        self._n_stiff = self._n_nonstiff = 0
        self.stiff = None          # (t, h_stable, rho) once the accepted steps sit at the stability limit
        self.h_stable = math.inf   # bound/ρ: a step may not grow past it (see the class docstring)
        self._rho = 0.0            # the stiffest rate measured, fading by RHO_DECAY per step

    @property
    def dense(self):
        """The :class:`DenseStep` of the last accepted step (None before the first), made on
        first use: most steps are never interpolated."""
        d = self._dense
        if d is None and self._dense_args is not None:
            d = self._dense = DenseStep(self.tab, self.prob, *self._dense_args)
        return d

    @dense.setter
    def dense(self, d):
        self._dense, self._dense_args = d, None

    #: h·ρ at the edge of the stability region on the negative real axis, by number of
    #: stages (Hairer's values: DOPRI5 3.25, DOP853 6.1)
    STABILITY_BOUND = {7: 3.25, 13: 6.1}
    #: accepted steps in a row at the stability limit before the model is called stiff (Hairer: 15)
    STIFF_STEPS = 15
    #: the stiffest rate measured so far fades by this factor per accepted step, unless a step
    #: measures a higher one: a step whose stages barely excite the stiff mode (after short
    #: steps damped it, at a horizon's end) measures a slow rate, yet the mode is still there
    RHO_DECAY = 0.95

    def stiffness_rate(self, h, num, den):
        """ρ ≈ |f(y_j) − f(y_i)| / |y_j − y_i| from the step's last two stages (both at
        t + h): the rate of the stiffest mode the step sees; None when not measurable.
        ``num``, ``den``: |K_j - K_i|² and |Σ a_k K_k|² (y_j - y_i = h Σ a_k K_k), the error
        sums of the weights e_j - e_i and a with unit scale (the problem's ``end_step``)."""
        if self._stiff_pair is None:
            return None
        den *= h * h
        if not den > 0.0 or not math.isfinite(num):
            return None
        return math.sqrt(num / den)

    def _detect_stiffness(self, t, h, rho):
        """Hairer's test on each accepted step (``rho``: :meth:`stiffness_rate`, None when not
        measurable): h·ρ above the stability bound, or the step held at ``h_stable``, in
        STIFF_STEPS accepted steps (six neither in a row reset the count) means the step is
        held at the stability limit by a mode it does not need to resolve: ``stiff`` is then
        (t, h_stable, ρ) (ρ the stiffest rate measured), for the driver to judge whether the run can afford it. Sets ``h_stable`` from the stiffest
        rate measured (inf: none yet), the cap on the next step's growth."""
        mem = self._rho * self.RHO_DECAY
        capped = h >= 0.95 * self.h_stable         # the step sat at the cap: held by stability
        if rho is None:
            self._rho = mem
            self.h_stable = self.stability_bound / mem if mem > 0.0 else math.inf
            return
        self._rho = mem = max(rho, mem)
        self.h_stable = self.stability_bound / mem if mem > 0.0 else math.inf
        if h * rho > self.stability_bound or capped:
            self._n_stiff += 1
            self._n_nonstiff = 0
            if self._n_stiff >= self.STIFF_STEPS:
                self.stiff = (t + h, self.h_stable, mem)
        else:
            self._n_nonstiff += 1
            if self._n_nonstiff >= 6:
                self._n_stiff = 0
                self.stiff = None

    def initial_step(self, t):
        """The starting step (:func:`.control.initial_step`). Its f at the start is the
        first step's first stage, computed as that stage (as scipy reuses its f0): the
        first step then starts from it, one f fewer."""
        prob, KX, KW = self.prob, self.KX, self.KW
        try:
            prob.stage(KX, KW, 0, self._A[0], 0.0, self.W, t, t)
            prob.flush(KX, KW)
        except StepFailed:            # not finite at the start: the first step reports it
            f0 = None
        else:
            self._fsal = True
            if prob.compiled:         # the rule's arithmetic in kernels
                return prob.initial_step(KX[0], KW[0], self.W, t, self.rtol, self.atol, self.tab.err_order)
            f0 = np.concatenate([KX[0], KW[0]])
        return initial_step(prob.rates, prob.nX, self.W, t, self.rtol, self.atol, self.tab.err_order, f0=f0)

    def error_norm(self, h, s5, s3):
        """The scaled error norm of the step from its error sums (the problem's ``end_step``)."""
        if self.tab.e3 is None:
            return abs(h) * math.sqrt(s5 / self._n)
        if s5 == 0.0 and s3 == 0.0:
            return 0.0
        return abs(h) * s5 / math.sqrt((s5 + 0.01 * s3) * self._n)

    def _attempt(self, t, h):
        prob, KX, KW = self.prob, self.KX, self.KW
        try:
            self.run_stages(t, h)
            X1, W1, q1, V1, quats, s5, s3, num, den, sq = prob.end_step(
                KX, KW, self._T, h, self.W, self.rtol, self.atol)
        except ChartLimit as lim:
            self.n_rejected += 1
            self.control.rejected()
            # retry at 80 % of the step that reaches the limit, and keep later steps below it
            # (regrowing 20 % per step)
            self._hcay = lim.shrink(h)
            return False, min(self._hcay, 0.5 * h)
        except StepFailed as exc:
            if not exc.diverged:
                raise
            self.n_rejected += 1              # a trial step that blew up: retry smaller
            self.control.rejected()
            return False, 0.25 * h
        # the error norm (error_norm, inlined: this runs once per step)
        if self.tab.e3 is None:
            en = abs(h) * math.sqrt(s5 / self._n)
        elif s5 == 0.0 and s3 == 0.0:
            en = 0.0
        else:
            en = abs(h) * s5 / math.sqrt((s5 + 0.01 * s3) * self._n)
        if not math.isfinite(en):
            self.n_rejected += 1
            return False, 0.25 * h
        if en > 1.0:
            self.n_rejected += 1
            return False, h * self.control.rejected(en)
        if self._stiff_pair is not None:
            self._detect_stiffness(t, h, self.stiffness_rate(h, num, den))
        fac = self.control.accepted(en)
        if self.dense_capable:                # the DenseStep itself is made on first use
            self._dense = None
            self._dense_args = (t, h, X1, W1, KX, KW, self.W, prob.snapshot())
        if self.projector is None and sq - sq == 0.0:
            # finish(t + h, q1, V1, W1, quats, checked=True) without projection, inlined:
            # q1, V1, W1 are fresh arrays (views of end_step's one new array) the stepper keeps
            self.q, self.V, self.W = q1, V1, W1
            prob.start(q1, quats)
            self._fsal = False
        else:
            self.finish(t + h, q1, V1, W1, quats, checked=math.isfinite(sq))
        # the stage buffers alternate: the dense output keeps the accepted step's stages
        bufs = self._bufs
        other = bufs[1] if KX is bufs[0][0] else bufs[0]
        self._last_KW = KW
        if self.tab.fsal and self.projector is None:
            other[1][0] = KW[self.tab.stages - 1]
            self._fsal = True
        self.KX, self.KW = other
        # the step grows no further than the stiffest mode's stability limit (a step already
        # beyond it is kept, not shrunk: the error control shrinks it when that mode grows)
        h_new = min(h * fac, self._hcay, max(h, self.h_stable))
        self._hcay *= 1.2
        return True, h_new


class DenseStep:
    """Continuous extension of one accepted step on (X, W), evaluated through τ of the
    step's own base (so it stays valid after the stepper has moved on). DOP853's three
    extra stages are computed on the first evaluation."""

    def __init__(self, tab, prob, t, h, X1, W1, KX, KW, W0, base):
        # the stepper's tableau and problem, not the stepper (which holds this step as its
        # ``dense``: no reference cycle keeping a finished run alive until the collector runs);
        # KX, KW: the step's stage buffers, W0 its start, base the problem's snapshot there
        self.tab, self.prob, self.t0, self.h = tab, prob, t, h
        self.t1 = t + h
        self.KX, self.KW = KX, KW
        self.W0, self.X1, self.W1 = W0, X1, W1
        self.base = base
        self.q1, self.V1 = None, None
        self._F = None

    def _coefficients(self):
        tab, prob = self.tab, self.prob
        h, KX, KW = self.h, self.KX, self.KW
        if tab.P is not None:
            P = tab.P
            return ("P", h * (P.T @ KX[:len(P)]), h * (P.T @ KW[:len(P)]))
        rows, cs, B, cdy = _dense_tables(tab)
        with prob.based_at(self.base):          # the extra stages (no chart limit passed)
            prob.run_stages(KX, KW, rows, cs, tab.stages, h, self.t0, self.W0)
            prob.flush(KX, KW)
        # Hairer's contd8 rows: F0 = Δy, F1 = hK_0 - Δy, F2 = 2Δy - h(K_{s-1} + K_0), F3.. = h D K
        n = B.shape[1]
        return ("D", np.outer(cdy, self.X1) + h * (B @ KX[:n]),
                np.outer(cdy, self.W1 - self.W0) + h * (B @ KW[:n]))

    def __call__(self, t):
        """(q, V) at t in [t0, t1] (τ of the step's base)."""
        if self._F is None:
            self._F = self._coefficients()
        th = (t - self.t0) / self.h
        kind, FX, FW = self._F
        if kind == "P":
            pw = np.cumprod(np.full(FX.shape[0], th))
            X, W = pw @ FX, self.W0 + pw @ FW
        else:
            X, W = _dop853_eval(FX, th), self.W0 + _dop853_eval(FW, th)
        prob = self.prob
        with prob.based_at(self.base):
            return prob.state_at(X, W)

    def many(self, ts):
        """Rows of (Q, V) at the times ``ts`` in [t0, t1]: the polynomials and τ of the
        step's base at every time in one call (:meth:`LocalProblem.dense_states`); equal
        to calling the step at each time, to rounding."""
        if self._F is None:
            self._F = self._coefficients()
        th = (np.asarray(ts, float) - self.t0) / self.h
        kind, FX, FW = self._F
        # the polynomials' weights: θ^(k+1) (dopri5), Hairer's contd8 products (dop853)
        f = np.empty((len(th), FX.shape[0]))
        f[:] = th[:, None]
        if kind == "D":
            f[:, 1::2] = 1.0 - f[:, 1::2]
        w = np.cumprod(f, axis=1)
        return self.prob.dense_states(w, FX, FW, self.W0, self.base)


_DENSE = {}


def _dense_tables(tab):
    """DOP853's dense output, made once per tableau: the extra stages' A rows (contiguous)
    and c, indexed by stage as ``run_stages`` reads them (the first ``stages`` entries
    unused), and (B, cdy) with contd8's rows F = cdy ⊗ Δy + h B K."""
    got = _DENSE.get(id(tab))
    if got is None or got[0] is not tab:
        A, c = tab.extra
        ns = tab.stages
        n = ns + len(c)
        B = np.zeros((7, n))
        B[1, 0] = 1.0
        B[2, 0] = B[2, ns - 1] = -1.0
        B[3:] = tab.D
        rows = [None] * ns + [np.ascontiguousarray(A[k][:ns + k], float) for k in range(len(c))]
        got = _DENSE[id(tab)] = (tab, rows, [0.0] * ns + [float(x) for x in c], B,
                                 np.array([1.0, -1.0, 2.0, 0.0, 0.0, 0.0, 0.0]))
    return got[1:]


def _dop853_eval(F, x):
    """Hairer's contd8 polynomial: y - y_0 at θ = x, i.e. θ (F0 + (1-θ)(F1 + θ(F2 + (1-θ)(F3
    + θ(F4 + (1-θ)(F5 + θ F6)))))) as one product with the weights of the rows."""
    u = 1.0 - x
    w1 = x * u
    w2 = w1 * x
    w3 = w2 * u
    w4 = w3 * x
    w5 = w4 * u
    return np.array([x, w1, w2, w3, w4, w5, w5 * x]) @ F
