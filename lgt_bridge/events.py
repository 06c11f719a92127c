"""Events: the moments a function of the state crosses zero, located on the step's continuous
extension through τ (``simulate(..., events=[g, ...])``, :meth:`Simulation.run`).

An event function is ``g(t, q, V) -> float`` in the model's own coordinates (q as the
engine stores it, V = (ω body, ṙ inertial) per body), with scipy's attributes:

- ``g.terminal``: False/0 (default), True (= 1) or a count n: the run ends at the n-th
  occurrence of this event, at the located time, with the model written back there (a later
  ``Simulation.run`` continues from there and does not find that crossing again; the
  stepper restarts there, generalized-α with Ẇ from f at the event's state and its
  auxiliary a = Ẇ + (a - Ẇ of the step's end), so the continued run keeps second order);
- ``g.direction``: 0 (default, both), > 0 (only g going from negative to positive), < 0;
- ``g.interp_points`` (ours, default 0): g is also tested at this many equally spaced
  interior times of every step (on its continuous extension), for g that wiggle faster than
  the rule below sees.

Detection: after every accepted step, g at the step's end against its value at the step's
start. A crossing is a change between strict signs (an exact zero at a step's end is decided
by the next value: it is reported there when g goes on to the other side). So g = 0 at the
initial time is not an event: the first occurrence is the first time g returns to zero.
(scipy 1.17's ``solve_ivp`` does report a zero at t0; MATLAB's ``odezero`` and Julia's
callbacks do not.)

Two crossings within one step (g leaves zero's side and comes back: no sign change between
the step's ends, which scipy's rule misses) are found too: g's slope G'(t) at the step's end
is a one-sided difference of g along the state's tangent there, (q, V)(t - δ) = τ(q_{k+1},
-δ Ẋ) with Ẋ = dψ⁻¹_0(W), W - δ Ẇ, δ = 2⁻¹⁶ h, Ẇ from what the step computed anyway (the
stages of the Runge-Kutta methods, generalized-α's unknowns; along the dense output for
radau5 and ``scipy:<Name>``), and the end's slope is the next step's start slope. The cubic Hermite
of G through both ends' values and slopes is then searched for interior extrema that turn
towards zero (on the other side of zero, or nearer to it than both ends); g is evaluated
there on the step's continuous extension, and where the cubic was so far off that the sign
of g at its extremum is in doubt (``abs(g) < 4 abs(cubic - g)`` there), g's extremum itself is searched
for (bounded Brent minimization to 1e-3 h, stopping at the first sign change). Each sign
change among the tested points is then located as below. Cost per step: one g call and one
τ evaluation (no f); the continuous extension (an f for the fixed-step methods, DOP853's
three extra stages) only in steps with a crossing or such an extremum. The search is as
good as the cubic: a pair of crossings closer together than the cubic can resolve, in a step
where g has more than two extrema, can still be missed (set ``interp_points`` or ``max_step``).

Location: Brent's method (:func:`scipy.optimize.brentq`) on G(t) = g(t, q(t), V(t)), with
(q, V)(t) = τ(q_k, X(t)) and X(t), W(t) the step's continuous extension in the local
coordinates of the step's own base q_k:

- dopri5, dop853, radau5: the method's dense output (:class:`.integrators.rkmk.DenseStep`,
  :class:`.integrators.radau.RadauDense`), of the method's own order;
- scipy:<Name>: scipy's dense output of the macro step
  (:class:`.integrators.vector_space.ScipyDense`, computed only in runs with events);
- euler, rkmk2, rkmk4, genalpha (and adaptive pairs run with fixed steps): a cubic Hermite
  interpolant (:class:`.hermite.HermiteStep`) of (X, W) through the step's start (X = 0, W_k) and end
  (X_{k+1} = τ⁻¹(q_k, q_{k+1}), W_{k+1}) with their rates Ẋ = dψ⁻¹_{-X}(W) and Ẇ (at the
  start from the step's first stage, at the end from one f, only in steps that are
  searched): the located time is accurate to O(h⁴), or to the method's order if lower.

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
from .hermite import HermiteStep, local_coordinates
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
        if type(out) is float and math.isfinite(out):       # the common case, checked first
            return out
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
    return int(x > 0.0) - int(x < 0.0)


class _Crossed(Exception):
    """Internal: the search for g's extremum reached the other side of zero."""


def _extrema(ga, gb, ma, mb):
    """The interior extrema (s, p(s)), 0 < s < 1, of the cubic Hermite p of g through (ga,
    ma = h g'(ta)) at s = 0 and (gb, mb = h g'(tb)) at s = 1 that turn towards zero: p there
    on the other side of zero than an end, or nearer to zero than both ends."""
    d = gb - ga
    c2, c3 = 3.0 * d - 2.0 * ma - mb, ma + mb - 2.0 * d
    # p'(s) = ma + 2 c2 s + 3 c3 s²
    A, B, C = 3.0 * c3, 2.0 * c2, ma
    if A == 0.0:
        if B == 0.0:
            return []
        roots = [-C / B]
    else:
        disc = B * B - 4.0 * A * C
        if disc < 0.0:
            return []
        qq = -0.5 * (B + math.copysign(math.sqrt(disc), B))
        roots = [qq / A] + ([C / qq] if qq != 0.0 else [])
    near, sa, sb = min(abs(ga), abs(gb)), _sign(ga), _sign(gb)
    out = []
    for x in sorted(roots):
        if 0.0 < x < 1.0:
            px = ga + x * (ma + x * (c2 + x * c3))
            sp = _sign(px)
            if sp != sa or sp != sb or abs(px) < near:
                out.append((x, px))
    return out


def _test_extrema(G, ta, h, ga, gb, extrema):
    """The times at which g is tested at the cubic's extrema (:func:`_extrema`), g evaluated
    there (``G(t)``, on the step's continuous extension). Where the cubic is so far off g
    there that the sign of g at its extremum is in doubt (``abs(g) < 4 abs(p - g)``), the extremum of g
    itself is searched for (:func:`scipy.optimize.minimize_scalar`, bounded, to 1e-3 h),
    stopping once g changes sign."""
    out = []
    for k, (sx, px) in enumerate(extrema):
        tt = ta + sx * h
        out.append(tt)
        val = G(tt)
        side = _sign(val)
        if not (side and side == _sign(ga) == _sign(gb) and abs(val) < 4.0 * abs(px - val)):
            continue
        from scipy.optimize import minimize_scalar
        lo = extrema[k - 1][0] if k > 0 else 0.0
        hi = extrema[k + 1][0] if k + 1 < len(extrema) else 1.0

        def toward_zero(u):
            x = side * G(ta + u * h)
            if x < 0.0:
                raise _Crossed(u)
            return x
        try:
            res = minimize_scalar(toward_zero, bounds=(lo, hi), method="bounded",
                                  options=dict(xatol=1e-3, maxiter=30))
            out.append(ta + float(res.x) * h)
        except _Crossed as c:
            out.append(ta + c.args[0] * h)
    return out


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
        self.Sa = None            # g's slopes at the next step's start (carried from its end)
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
    #: the step of the one-sided difference that gives g's slope at a step's end, as a
    #: fraction of the step (along the state's tangent there, or along the dense output)
    SLOPE_STEP = 2.0 ** -16

    def _tangent(self, base, W, Wd, d):
        """(q, V) at a distance d in time along the tangent (Ẋ = dψ⁻¹_0(W), Ẇ) at X = 0 of
        ``base`` (None: the current step's base, i.e. the last step's end)."""
        p = self.sim.stepper.prob
        if base is None:
            return p.state_at(d * p.chart_scale * W[p.local_index], W + d * Wd)
        with p.based_at(base):
            return p.state_at(d * p.chart_scale * W[p.local_index], W + d * Wd)

    def _slopes(self, t, gb):
        """dG/dt per event at the step's end, and at its start when not carried over from the
        previous step: a one-sided difference of g along the state's tangent, with Ẇ from the
        step's own stages (no f); along the dense output where the method has no such rates
        (radau5, scipy:*); else from one f at each end."""
        st, ta = self.sim.stepper, self.ta
        d = self.SLOPE_STEP * (t - ta)
        rates = st.step_rates()
        first = self.Sa is None
        if rates is None and st.dense is not None and abs(st.dense.t0 - ta) <= 1e-9 * (t - ta):
            dense = st.dense
            b0, b1 = dense(t - d), dense(t)
            Sb = [(s.value(t, *b1) - s.value(t - d, *b0)) / d for s in self.specs]
            if first:
                a0, a1 = dense(ta), dense(ta + d)
                self.Sa = [(s.value(ta + d, *a1) - s.value(ta, *a0)) / d for s in self.specs]
            return Sb
        if rates is None:                    # a stepper without either: f at the ends
            prob = st.prob
            Wd_b = prob.rhs(np.zeros(prob.nX), st.W, t, at_start=True)[1]
            Wd_a = self.Wda
            if Wd_a is None and first:
                with prob.based_at(self.base) as p:
                    Wd_a = p.rhs(np.zeros(p.nX), self.Wa, ta, at_start=True)[1]
            rates = (Wd_a, Wd_b)
        else:
            self.Wda = rates[0]              # exact f at the start: the Hermite step's Ẇ_0
        qm, Vm = self._tangent(None, st.W, rates[1], -d)
        Sb = [(gb[i] - s.value(t - d, qm, Vm)) / d for i, s in enumerate(self.specs)]
        if first:
            qp, Vp = self._tangent(self.base, self.Wa, rates[0], d)
            self.Sa = [(s.value(ta + d, qp, Vp) - self.g[i]) / d for i, s in enumerate(self.specs)]
        return Sb

    def check(self, t):
        """After the step to t: record the crossings in it; a terminal one moves the
        simulation to its time and raises :class:`Terminal`."""
        st = self.sim.stepper
        q, V = st.q, st.V
        gb = [s.value(t, q, V) for s in self.specs]
        self._Wd_end = None
        ta, h = self.ta, t - self.ta
        ext, cache = [], {}

        def state(tt):
            if tt == t:
                return q, V
            if tt == ta:
                return self.qa, self.Va
            if tt not in cache:
                if not ext:
                    ext.append(self._extension(t))
                cache[tt] = ext[0](tt)
            return cache[tt]

        Sb = self._slopes(t, gb)
        xtol = max(0.01 * self.tol * h, 4 * _EPS * abs(t))
        found = []
        for i, s in enumerate(self.specs):
            ga, sigma, sb = self.g[i], self.sigma[i], _sign(gb[i])
            extrema = _extrema(ga, gb[i], h * self.Sa[i], h * Sb[i])
            if not (extrema or s.interp_points or (sb and sigma and sb != sigma)):
                if sb:                       # no crossing and nothing to test inside
                    self.sigma[i] = sb
                continue
            # the test points of this event in the step, with g's values there: the ends, the
            # interior extrema of g that turn towards zero, and interp_points equally spaced
            vals = {ta: ga, t: gb[i]}

            def G(tt, s=s, vals=vals):
                if tt not in vals:
                    vals[tt] = s.value(tt, *state(tt))
                return vals[tt]

            _test_extrema(G, ta, h, ga, gb[i], extrema)
            for k in range(1, s.interp_points + 1):
                G(ta + h * k / (s.interp_points + 1))
            for tt in sorted(vals)[1:]:
                sk = _sign(vals[tt])
                if not sk:
                    continue
                if sigma and sk != sigma and (s.direction == 0 or s.direction == sk):
                    prev = max(x for x in vals if x < tt)
                    found.append((self._locate(s, state, prev, tt, vals[prev], vals[tt], xtol), i, sk))
                sigma = sk
            self.sigma[i] = sigma
        self.g, self.Sa = gb, Sb
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
        st.restart_at(qe, Ve, te)
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
