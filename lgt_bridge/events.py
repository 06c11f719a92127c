"""Events: the moments a function of the state crosses zero, located on the step's continuous
extension through τ (``simulate(..., events=[g, ...])``, :meth:`Simulation.run`).

An event function is ``g(t, q, V) -> float`` in the model's own coordinates (q as the
engine stores it, V = (ω body, ṙ inertial) per body), with scipy's attributes:

- ``g.terminal``: False/0 (default), True (= 1) or a count n: the run ends at the n-th
  occurrence of this event, at the located time, with the model written back there (a later
  ``Simulation.run`` continues from there and does not find that crossing again);
- ``g.direction``: 0 (default, both), > 0 (only g going from negative to positive), < 0;
- ``g.interp_points`` (ours, default 0): besides the step ends, g is tested at this many equally
  spaced interior times of every step on its continuous extension, so that two crossings
  within one step (no sign change between its ends) are found too; 0 is scipy's rule (a
  sign change between step ends), which may miss such pairs.

Detection: after every accepted step, g at the step's end against its value at the step's
start. A crossing is a change between strict signs (an exact zero at a step's end is decided
by the next value: it is reported there when g goes on to the other side). So g = 0 at the
initial time is not an event: the first occurrence is the first time g returns to zero.
(scipy 1.17's ``solve_ivp`` does report a zero at t0; MATLAB's ``odezero`` and Julia's
callbacks do not.)

Location: Brent's method (:func:`scipy.optimize.brentq`) on G(t) = g(t, q(t), V(t)), with
(q, V)(t) = τ(q_k, X(t)) and X(t), W(t) the step's continuous extension in the local
coordinates of the step's own base q_k:

- dopri5, dop853, radau5: the method's dense output (:class:`.integrators.rkmk.DenseStep`,
  :class:`.integrators.radau.RadauDense`), of the method's own order;
- scipy:<Name>: scipy's dense output of the macro step
  (:class:`.integrators.vector_space.ScipyDense`, computed only in runs with events);
- euler, rkmk2, rkmk4, genalpha (and adaptive pairs run with fixed steps): a cubic Hermite
  interpolant (:class:`HermiteStep`) of (X, W) through the step's start (X = 0, W_k) and end
  (X_{k+1} = τ⁻¹(q_k, q_{k+1}), W_{k+1}) with their rates Ẋ = dψ⁻¹_{-X}(W) and Ẇ from the
  model's f (one f per step, only in steps that are searched): the located time is
  accurate to O(h⁴), or to the method's order if lower.

With constraints projected after each step, the interpolated states are projected too, so
g is evaluated, and events are located, on the projected trajectory.

Time tolerance: the root is bracketed to ``xtol = 0.01·tol·h`` (h: the step's length, tol:
the smaller of the run's positive rtol and atol), and never below 4·eps·abs(t) (brentq's own
floor). A time error tol·h changes the state by about tol·‖Δy‖ over the step, below the
error the tolerances already allow the step.
"""
import math

import numpy as np

from .errors import InputError, ModelError
from .groups import quaternion as _q
from .integrators.base import StepFailed

_EPS = np.finfo(float).eps


class EventSpec:
    """One event function with its attributes, checked."""

    def __init__(self, fn, index):
        self.fn, self.index = fn, index
        name = getattr(fn, "__name__", None) or type(fn).__name__
        self.name = f"event {index} ({name})"
        if not callable(fn):
            raise InputError(f"events[{index}] is a {type(fn).__name__}, not a function: pass "
                             "callables g(t, q, V) -> float (scipy's convention).")
        term = getattr(fn, "terminal", False)
        if isinstance(term, (bool, np.bool_)):
            self.max_count = 1 if term else math.inf
        elif isinstance(term, (int, np.integer)) and term >= 0:
            self.max_count = int(term) if term > 0 else math.inf
        else:
            raise InputError(f"{self.name}: terminal = {term!r}; use True/False or a positive count "
                             "(the run ends at that occurrence).")
        direction = getattr(fn, "direction", 0)
        if isinstance(direction, (bool, np.bool_)) or not isinstance(direction, (int, float, np.integer, np.floating)) \
                or not math.isfinite(direction):
            raise InputError(f"{self.name}: direction = {direction!r}; use -1 (downward), 0 (both) or +1 "
                             "(upward crossings).")
        self.direction = int(np.sign(direction))
        n = getattr(fn, "interp_points", 0)
        if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 0:
            raise InputError(f"{self.name}: interp_points = {n!r}; use a count >= 0 (interior test points "
                             "per step).")
        self.interp_points = int(n)

    def value(self, t, q, V, initial=False):
        """g(t, q, V) as a float; a bad return or an exception is InputError at the start,
        StepFailed (the run ends, keeping its steps) later."""
        try:
            out = self.fn(t, q, V)
        except Exception as exc:            # noqa: BLE001 - the user's function: report, name it
            msg = f"{self.name} raised {type(exc).__name__} at t = {t:.9g}: {exc}"
            if initial:
                raise InputError(msg + " (evaluated at the initial state, before the first step).") from exc
            raise StepFailed(msg + ". The run ends there; the result keeps every step before it.") from exc
        try:
            bad = isinstance(out, (bool, np.bool_, complex, np.complexfloating)) or np.size(out) != 1
            val = float(np.asarray(out).reshape(-1)[0]) if not bad else math.nan
        except (TypeError, ValueError):
            bad, val = True, math.nan
        if bad or not math.isfinite(val):
            msg = (f"{self.name} returned {out!r} at t = {t:.9g}; an event function returns one finite "
                   "real number g(t, q, V) whose zeros are the events")
            if initial:
                raise InputError(msg + ".")
            raise StepFailed(msg + ". The run ends there; the result keeps every step before it.")
        return val


def prepare(events):
    """The event functions as a list of :class:`EventSpec` (one callable or a sequence)."""
    if callable(events):
        events = [events]
    try:
        events = list(events)
    except TypeError:
        raise InputError(f"events = {events!r}: pass a function g(t, q, V) -> float or a list of them.") from None
    return [EventSpec(fn, i) for i, fn in enumerate(events)]


class Terminal(Exception):
    """Internal: a terminal event ended the run at ``t`` (the simulation already moved there)."""

    def __init__(self, message, t, state):
        super().__init__(message)
        self.message, self.t, self.state = message, t, state


def _sign(x):
    return (x > 0.0) - (x < 0.0)


# --- the local coordinates of a pose: X = τ⁻¹(q_k, q) -----------------------------------------
def local_coordinates(prob, q):
    """X with τ(q_k, X) = q in the current step's chart (q_k: ``prob.q_k``): per body
    ψ⁻¹(α(q_k)⁻¹ α(q)), vector coordinates q - q_k, circle angles of (c, s)·(c_k, s_k)⁻¹."""
    qk = prob.q_k
    X = np.zeros(prob.nX)
    for s in prob.sets:
        par = s.lgt.param
        rk, r1 = qk[s.qidx], q[s.qidx]
        pk = par._to_quat(rk[:, -par.nrot:])
        p1 = par._to_quat(r1[:, -par.nrot:])
        R = _q._to_matrix(_q._mul(_q._conj(pk), p1))
        if s.rot_only:
            X[s.xidx] = s.chart.on("SO3").psi_inv(R)
            continue
        d = r1[:, :3] - rk[:, :3]
        if s.se3:
            d = _q._rotate(_q._conj(pk), d)
        C = np.zeros((len(R), 4, 4))
        C[:, :3, :3], C[:, :3, 3], C[:, 3, 3] = R, d, 1.0
        X[s.xidx] = s.chart.on(s.lgt.group).psi_inv(C)
    if len(prob.vq):
        X[prob.vx] = q[prob.vq] - qk[prob.vq]
    if len(prob.cv):
        ck, c1 = qk[prob.cq], q[prob.cq]
        X[prob.cx] = np.arctan2(c1[:, 1] * ck[:, 0] - c1[:, 0] * ck[:, 1],
                                c1[:, 0] * ck[:, 0] + c1[:, 1] * ck[:, 1])
    return X


class HermiteStep:
    """The continuous extension of a fixed step: the cubic Hermite interpolant of (X, W) in
    the chart of the step's base, through (0, W0) at t0 and (X1, W1) at t1 with the rates
    (Ẋ, Ẇ) of the local ODE at both ends, mapped through τ of the base. ``Wd0``: Ẇ at the
    start when known (the previous step's end: W is the body-frame velocity, the same in
    every step's chart), else one f. The end's Ẇ is kept as ``Wd1`` for the next step."""

    def __init__(self, prob, base, t0, W0, t1, q1, W1, Wd0=None):
        self.prob, self.base, self.t0, self.t1, self.h = prob, base, t0, t1, t1 - t0
        with prob.based_at(base):
            X1 = local_coordinates(prob, q1)
            Xd0, Wd, _, _ = prob.rhs(np.zeros(prob.nX), W0, t0, at_start=True) if Wd0 is None else \
                (prob.chart_scale * prob.to_local(W0), Wd0, None, None)
            Xd1, Wd1, _, _ = prob.rhs(X1, W1, t1)
        self.Wd1 = Wd1
        h = self.h
        # y(s) = y0 + s (h ẏ0) + s² (3Δ - 2h ẏ0 - h ẏ1) + s³ (h ẏ0 + h ẏ1 - 2Δ)
        self.cX = self._coef(np.zeros(prob.nX), X1, h * Xd0, h * Xd1)
        self.cW = self._coef(W0, W1, h * Wd, h * Wd1)

    @staticmethod
    def _coef(y0, y1, d0, d1):
        dy = y1 - y0
        return (y0, d0, 3.0 * dy - 2.0 * d0 - d1, d0 + d1 - 2.0 * dy)

    @staticmethod
    def _eval(c, s):
        return c[0] + s * (c[1] + s * (c[2] + s * c[3]))

    def local(self, t):
        s = (t - self.t0) / self.h
        return self._eval(self.cX, s), self._eval(self.cW, s)

    def __call__(self, t):
        X, W = self.local(t)
        with self.prob.based_at(self.base) as prob:
            return prob.state_at(X, W)


class Tracker:
    """The events of one run: checks g at every step's end, locates crossings on the step's
    continuous extension, records them, and ends the run at a terminal one.

    ``sim``: the :class:`~lgt_bridge.simulation.Simulation`; every g is evaluated at its
    current state (InputError on bad input, before the first step)."""

    def __init__(self, sim, events):
        self.sim = sim
        self.specs = prepare(events)
        st = sim.stepper
        rtol = getattr(sim, "rtol", getattr(st, "rtol", 1e-6))
        atol = getattr(sim, "atol", getattr(st, "atol", 1e-8))
        self.tol = min([x for x in (rtol, atol) if x > 0] or [1e-8])
        self.t_events = [[] for _ in self.specs]
        self.q_events = [[] for _ in self.specs]
        self.V_events = [[] for _ in self.specs]
        self.count = [0] * len(self.specs)
        t, q, V = sim.t, st.q, st.V
        self.g = [s.value(t, q, V, initial=True) for s in self.specs]
        self.sigma = [_sign(x) for x in self.g]      # the sign of g's last nonzero value
        # a run that continues from a terminal event: that event's g is (about) zero here and
        # has crossed to the other side; it is not found again at the start
        te, fn, side = getattr(sim, "_event_resume", (None, None, 0))
        if te == t:
            for i, s in enumerate(self.specs):
                if s.fn is fn:
                    self.sigma[i] = side
        self.interp = max(s.interp_points for s in self.specs)
        self._keep = getattr(st, "keep_dense", None) is False   # dense output on request (scipy's)
        if self._keep:
            st.keep_dense = True
        self._start(t, q, V, None)

    def _start(self, t, q, V, Wd):
        """Remember the state at the start of the next step (for the Hermite interpolant)."""
        st = self.sim.stepper
        self.ta, self.qa, self.Va, self.Wa = t, q.copy(), V.copy(), st.W.copy()
        self.base = st.prob.snapshot()
        self.Wda = Wd

    def close(self):
        """The run is over: (t_events, q_events, V_events), per event an array of times, of
        q (n, nq) and of V (n, nv); a stepper's dense output kept for the events is off again."""
        if self._keep:
            self.sim.stepper.keep_dense = False
        lay = self.sim.model.layout
        return ([np.array(t, float) for t in self.t_events],
                [np.array(q, float).reshape(-1, lay.nq) for q in self.q_events],
                [np.array(V, float).reshape(-1, lay.nv) for V in self.V_events])

    def hook(self, on_step):
        """``on_step`` with the events checked first (a terminal event raises :class:`Terminal`
        before the step's end is recorded; an exception in g records the step, then ends the run)."""
        def hooked(t, q, V):
            try:
                self.check(t)
            except StepFailed:
                on_step(t, q, V)
                raise
            except ModelError as exc:         # the engine raised in f for the step's interpolant
                on_step(t, q, V)
                raise StepFailed(str(exc), error=ModelError) from exc
            on_step(t, q, V)
        return hooked

    # --- the step's continuous extension -----------------------------------------------------
    def _extension(self, t):
        st = self.sim.stepper
        d = st.dense
        h = t - self.ta
        if d is not None and abs(d.t0 - self.ta) <= 1e-9 * h and abs(d.t1 - t) <= 1e-9 * h:
            ext = d
        else:
            ext = HermiteStep(st.prob, self.base, self.ta, self.Wa, t, st.q, st.W, self.Wda)
            self._Wd_end = ext.Wd1
        proj = st.projector
        if proj is None:
            return ext

        def projected(tt):
            q, V = ext(tt)
            it = proj.iterations
            q, _, _ = proj.positions(q, tt)
            V, _ = proj.velocities(q, V, tt)
            proj.iterations = it             # the step statistics count the steps' projections only
            return q, V
        return projected

    # --- per step ------------------------------------------------------------------------------
    def check(self, t):
        """After the step to t: record the crossings in it; a terminal one moves the
        simulation to its time and raises :class:`Terminal`."""
        st = self.sim.stepper
        q, V = st.q, st.V
        gb = [s.value(t, q, V) for s in self.specs]
        self._Wd_end = None
        ta = self.ta
        flagged = [i for i, s in enumerate(self.specs)
                   if (sb := _sign(gb[i])) and self.sigma[i] and sb != self.sigma[i]]
        found = []
        if flagged or self.interp:
            ext = self._extension(t)
            cache = {}

            def state(tt):
                if tt == t:
                    return q, V
                if tt == ta:
                    return self.qa, self.Va
                if tt not in cache:
                    cache[tt] = ext(tt)
                return cache[tt]

            xtol = max(0.01 * self.tol * (t - ta), 4 * _EPS * abs(t))
            for i, s in enumerate(self.specs):
                # the test points of this event in the step, with g's values there
                n = s.interp_points
                times = [ta] + [ta + (t - ta) * k / (n + 1) for k in range(1, n + 1)] + [t]
                vals = [self.g[i]] + [s.value(tt, *state(tt)) for tt in times[1:-1]] + [gb[i]]
                sigma = self.sigma[i]
                for k in range(1, len(times)):
                    sk = _sign(vals[k])
                    if not sk:
                        continue
                    if sigma and sk != sigma:
                        if s.direction == 0 or s.direction == sk:
                            te = self._locate(s, state, times[k - 1], times[k], vals[k - 1], vals[k], xtol)
                            found.append((te, i, sk))
                    sigma = sk
                self.sigma[i] = sigma
        else:
            for i, x in enumerate(gb):
                if x != 0.0:
                    self.sigma[i] = _sign(x)
        self.g = gb
        stop = None
        for te, i, side in sorted(found):
            qe, Ve = state(te)
            self.t_events[i].append(te)
            self.q_events[i].append(np.array(qe, float))
            self.V_events[i].append(np.array(Ve, float))
            self.count[i] += 1
            if self.count[i] >= self.specs[i].max_count:
                stop = (te, i, qe, Ve, side)
                break
        if stop is None:
            self._start(t, q, V, self._Wd_end)
            return
        te, i, qe, Ve, side = stop
        qe, Ve = np.array(qe, float), np.array(Ve, float)
        sim = self.sim
        st.set_state(qe, Ve)
        sim.t = te
        sim._event_resume = (te, self.specs[i].fn, side)
        sim.model.write_back(qe, Ve, te)
        s = self.specs[i]
        nth = "" if s.max_count == 1 else f" (occurrence {self.count[i]})"
        raise Terminal(f"terminal {s.name} at t = {te:.12g}{nth}", te, state)

    def _locate(self, spec, state, a, b, ga, gb, xtol):
        """The zero of g in [a, b] (ga, gb of opposite signs or ga = 0) by Brent's method."""
        if ga == 0.0:
            return a
        from scipy.optimize import brentq

        def G(tt):
            if tt == a:
                return ga
            if tt == b:
                return gb
            return spec.value(tt, *state(tt))
        return float(brentq(G, a, b, xtol=xtol, rtol=4 * _EPS))


__all__ = ["EventSpec", "Tracker", "Terminal", "HermiteStep", "local_coordinates", "prepare"]
