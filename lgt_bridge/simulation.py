"""The simulation object: set up once, then advance.

:class:`Simulation` checks a model and a method's options, resolves ``"auto"`` groups and
charts, builds the method's stepper from the registry (:mod:`.integrators.registry`) with
its local problem and projector, makes the initial state consistent, and then advances:

- :meth:`Simulation.advance_to` — to one time, returning (q, V) there (interpolated by the
  method's continuous extension when it has one); the engine drop-ins call this;
- :meth:`Simulation.run` — to ``t_end`` collecting outputs (every step, or ``t_eval``) into
  a :class:`~.result.SimulationResult`; called again, it continues from where the last call
  ended (consecutive short horizons, model-predictive control), without repeating set-up.

Hooks: ``on_step(t, q, V)`` after every accepted step; the model's ``write_back`` after
every step (engine sensors), ``post_step``/discontinuous states (contact switches located
by shortening the step), and ``min_step`` (a controller shrinking the step below it fails,
saying why). :func:`~lgt_bridge.simulate` is one ``Simulation(...).run(...)``.
"""
import math
import time
from bisect import bisect_left, bisect_right
from functools import partial

import numpy as np

from . import auto as _auto
from . import diagnosis as _diagnosis
from . import events as _events
from . import switches as _switches
from .end_jump import collapsed
from .errors import ChartDomainError, InputError, ModelError
from .integrators.base import StepFailed
from .integrators.constraints import note_initial_projection, project_initial
from .integrators.steppers import make_stepper
from .lgt import DEFAULT_GROUP
from .progress import simulation_bar
from .result import SimulationResult, collect
from .validation import check_options, check_state, check_t_eval


class Simulation:
    """A model on a method, set up once and advanced again and again (see the module docstring).

    Set-up (the checks, ``auto``, the method's stepper, a consistent initial state) happens
    here; :meth:`run` and :meth:`advance_to` then carry the state from call to call, so
    consecutive short horizons (model-predictive control, rollouts) pay for it once.

    Parameters
    ----------
    model : lgt_bridge.model.Model
        As :func:`~lgt_bridge.simulate`.
    method, group, chart, dt, rtol, atol, max_steps, project, rho_inf, newton_tol, max_step
        As :func:`~lgt_bridge.simulate`.
    q0, V0 : ndarray, optional
        The initial state (default: the model's).
    t0 : float, default 0.0
        The initial time.
    t_end : float, optional
        The end of the run, when known (adaptive methods with dense output then step freely
        up to it); each :meth:`run` sets it again.
    fixed_steps : bool, default False
        An adaptive pair runs fixed steps of ``dt`` with its own tableau.
    min_step : float, default 0.0
        (> 0) an error-controlled step shrinking below it ends the run, with
        ``min_step_why`` as the advice.
    checked : bool, default False
        The options and the initial state were checked by the caller already
        (:func:`~lgt_bridge.simulate` checks them first).

    Attributes
    ----------
    t, q, V
        The current time and state (the model's own coordinates).
    n_steps, n_redone : int
        Accepted steps so far, steps redone for discontinuous states.
    initial_projection : float or None
        How far the initial state was moved onto the constraints (None: it was consistent).

    Examples
    --------
    >>> from lgt_bridge import Simulation, scenes
    >>> sim = Simulation(scenes.heavy_top(True), method="dop853", rtol=1e-8, atol=1e-8)
    >>> for k in range(1, 4):
    ...     r = sim.run(0.02 * k)          # from where the last call ended
    >>> round(sim.t, 12)
    0.06
    """

    #: redos of one short step when the model's discontinuous states keep changing
    MAX_DISCONTINUOUS = 5
    #: the embedded pairs on compiled kernels step in the compiled step loop (False: the
    #: Python loop, the reference the tests hold it equal to)
    _use_loop = True

    def __init__(self, model, *, method="rkmk4", group=DEFAULT_GROUP, chart="exp", dt=None, rtol=1e-6,
                 atol=1e-8, t0=0.0, t_end=None, q0=None, V0=None, max_steps=1_000_000, project=True,
                 rho_inf=0.9, newton_tol=1e-10, fixed_steps=False, min_step=0.0, max_step=None,
                 checked=False):
        if max_step is not None and not (float(max_step) > 0.0):
            raise InputError(f"max_step = {max_step} must be positive (None: no cap).")
        if not checked:
            check_options(method, dt, rtol, atol, max_steps)
            q0, V0 = check_state(model, q0, V0)
            if t_end is not None and not float(t_end) > float(t0):
                raise InputError(f"t_end = {t_end} must be greater than t0 = {t0}.")
        q0 = model.q0 if q0 is None else q0
        V0 = model.V0 if V0 is None else V0
        self.method, self.choice = method, None
        self.rtol, self.atol = rtol, atol          # (events: their time tolerance)
        if _auto.wants_auto(group, chart):
            self.choice = _auto.choose(model, group, chart, method=method, project=project)
            group, chart = self.choice.groups, self.choice.charts
        self.group, self.chart = group, chart
        span = (float(t0), float(t_end)) if t_end is not None else None
        stepper, dt = make_stepper(model, method, group, chart, dt=dt, rtol=rtol, atol=atol,
                                   project=project, rho_inf=rho_inf, newton_tol=newton_tol, span=span,
                                   fixed_steps=fixed_steps)
        self._options = dict(dt=dt, rtol=rtol, atol=atol, project=project, rho_inf=rho_inf,
                             newton_tol=newton_tol, span=span, fixed_steps=fixed_steps)
        self._setup(model, stepper, dt, t0, q0, V0, max_steps, t_end, project)
        self.set_max_step(max_step)
        if min_step > 0:
            stepper.min_step = min_step
        self.min_step = min_step if stepper.adaptive else 0.0
        self.min_step_name, self.min_step_why = "min_step", ""

    @classmethod
    def from_stepper(cls, model, stepper, dt, t0, q0, V0, max_steps=1_000_000, t_end=None,
                     consistent=True):
        """A simulation driving a stepper built by hand (tests, custom tableaux)."""
        sim = cls.__new__(cls)
        sim.method, sim.choice, sim.group, sim.chart = type(stepper).__name__, None, "", ""
        sim.min_step, sim.min_step_name, sim.min_step_why = 0.0, "min_step", ""
        sim._setup(model, stepper, dt, t0, q0, V0, max_steps, t_end, consistent)
        return sim

    def set_max_step(self, max_step):
        """The largest step an adaptive method may take (None: no cap). The step controller
        never proposes more; output times still come from dense output."""
        self.max_step = float(max_step) if (max_step is not None and self.stepper.adaptive) else np.inf
        self.h = min(self.h, self.max_step)
        self.first_step = self.h

    def _setup(self, model, stepper, dt, t0, q0, V0, max_steps, t_end, consistent):
        self.model, self.stepper = model, stepper
        self.max_step = np.inf
        self._post = getattr(model, "post_step", None)
        self._switches = _switches.locator(self, model)     # a model's mode switches (contact)
        self.dt, self.t, self.max_steps = dt, float(t0), max_steps
        self._t_start = float(t0)
        self._q_start = np.array(q0, float)
        self.t_end = t_end
        self.dense = stepper.dense_capable and t_end is not None
        self.n_steps = 0
        self.n_redone = 0
        # the budget check (diagnosis.budget_tick); the run's end when t_end is None, and the
        # steps the caller's own engine takes for the run, (n, t0, t1, name) (drop-ins)
        self._budget_unit, self._budget_clock = self.BUDGET_UNITS[0], (0, time.perf_counter())
        self.run_end = self.reference_steps = None
        span = (t_end - self.t) if t_end is not None else (dt or 1.0) * 1e2
        # switches of discontinuous states are located to h_event (finer at tighter tolerances)
        self.h_event = min(1e-7, getattr(self, "rtol", 0.0) or 1e-7) * max(span, 1e-300)
        self.initial_projection = self.end_jump = None
        if consistent and model.n_constraints:
            own = getattr(model, "project_initial", None)     # an engine's own rule, if it has one
            q0, V0, self.initial_projection = (own or partial(project_initial, model))(q0, V0, self.t)
            if self.initial_projection is not None:
                model.write_back(q0, V0, self.t)
                note_initial_projection(self.initial_projection, self.t)
        stepper.set_state(q0, V0)
        self.h = dt if dt is not None else stepper.initial_step(self.t)
        self.first_step = self.h
        self.wall_s = 0.0

    # --- state ------------------------------------------------------------------------
    @property
    def q(self):
        return self.stepper.q

    @property
    def V(self):
        return self.stepper.V

    def restart(self):
        """Forget what the stepper carries from step to step (FSAL stages, Newton state):
        the model changed between steps (an engine's pre-step user function)."""
        st = self.stepper
        st.set_state(st.q, st.V)

    def rebuild(self):
        """Build the stepper again at the current state, for the model's constraint rows as
        they are now (an engine's pre-step user function switched a connector on or off:
        the rows a stepper was built on are gone or new). The state is made consistent with
        the new rows as at the start (a connector switched on may be violated); counters
        carry on. Returns the projection's report (None: the state was consistent)."""
        old = self.stepper
        if getattr(self, "_options", None) is None:
            raise InputError("Simulation.rebuild needs a Simulation built from a method name.")
        st, _ = make_stepper(self.model, self.method, self.group, self.chart, **self._options)
        q, V, rep = old.q.copy(), old.V.copy(), None
        if self.model.n_constraints:
            own = getattr(self.model, "project_initial", None)
            q, V, rep = (own or partial(project_initial, self.model))(q, V, self.t)
        st.set_state(q, V)
        st.prob.n_f += old.prob.n_f
        st.n_rejected += old.n_rejected
        st.n_newton += old.n_newton
        st.n_jacobians += old.n_jacobians
        st.min_step = old.min_step
        if st.projector is not None and old.projector is not None:
            for k in ("max_before", "max_after", "max_vel_after", "iterations"):
                setattr(st.projector, k, max(getattr(st.projector, k), getattr(old.projector, k)))
        self.stepper = st
        self.dense = st.dense_capable and self.t_end is not None
        return rep

    def stats(self):
        """Counters of the run so far."""
        st = self.stepper
        out = dict(n_steps=self.n_steps, n_f=st.prob.n_f, n_rejected=st.n_rejected,
                   n_newton=st.n_newton, wall_s=self.wall_s)
        if st.projector is not None:
            p = st.projector
            out.update(constraint_before_projection=p.max_before, constraint_after_projection=p.max_after,
                       velocity_constraint_after_projection=p.max_vel_after,
                       projection_iterations=p.iterations)
        if st.n_jacobians:
            out["n_jacobians"] = st.n_jacobians
        stiff = getattr(st, "stiff", None)
        if stiff is not None:       # an explicit method's steps at its stability limit (Hairer's test)
            out["stiff"] = dict(t=float(stiff[0]), h_stable=float(stiff[1]), rho=float(stiff[2]))
        if self.initial_projection is not None:
            out["initial_projection"] = self.initial_projection
        if self.end_jump is not None:
            out["end_jump"] = self.end_jump
        if getattr(self, "_switches", None) is not None:
            out["n_switches"] = len(self._switches.t_switches)
        if self.choice is not None:
            out["auto"] = self.choice.as_dicts()
        return out

    # --- stepping ---------------------------------------------------------------------
    def _step(self, target, on_step):
        st = self.stepper
        if self.n_steps >= self.max_steps:
            raise StepFailed(_diagnosis.max_steps_message(self))
        h_before = self.h
        rem = target - self.t
        if st.adaptive and self.h < rem <= st.landing_steps * self.h:     # no sliver of a step
            h_try = rem / math.ceil(rem / self.h - 1e-9)
        else:
            h_try = min(self.h, rem)
        hit = target - (self.t + h_try) <= 1e-12 * max(1.0, abs(target))
        if hit:
            h_try = target - self.t
        post, cut = self._post, None
        try:
            if post is None and self._switches is not None:
                accepted, h_new, cut = self._switches.attempt(self.t, h_try)
            elif post is None:
                accepted, h_new = st.attempt(self.t, h_try)
            else:
                accepted, h_new = _switches.attempt_discontinuous(self, h_try, post)
        except ModelError as exc:           # the engine raised: end the run, keep the steps
            raise StepFailed(str(exc), error=ModelError) from exc
        if accepted:
            self.n_steps += 1
            self.t = cut if cut is not None else (target if hit else self.t + h_try)
            self.model.write_back(st.q, st.V, self.t)
            if st.adaptive:
                # a step shortened to land: the carried proposal, shrunk if its error asks (and
                # its own proposal if longer); neither past the stability limit the stepper measured
                if h_try < self.h:
                    carried = self.h * min(1.0, h_new / h_try)
                    h_new = max(h_new, carried) if st.landing_grows else carried
                self.h = min(h_new, max(h_try, st.h_stable), self.max_step)
            else:
                self.h = min(h_new, self.dt) if h_new is not None else self.dt
            if on_step is not None:
                on_step(self.t, st.q, st.V)
            if st.adaptive and self.n_steps % self._budget_unit == 0:
                _diagnosis.budget_tick(self)
            elif not st.adaptive:
                _diagnosis.slow_tick(self)
        else:
            self.h = h_new
            if self.h < 1e-14 * max(1.0, abs(self.t)):
                raise self._too_small(underflow=True)
        if (self.h < self.min_step and self.h < h_before
                and self.t < target - 1e-12 * max(1.0, abs(target))):
            collapsed(self, on_step)

    def _too_small(self, underflow=False):
        return _diagnosis.step_too_small(self, underflow)

    #: a singular value of the constraint Jacobian below this fraction of the largest (and
    #: not already at the start) marks a singular configuration
    SINGULAR_RATIO = 1e-3
    #: the step budget is checked every BUDGET_WINDOW accepted steps, or every BUDGET_UNITS
    #: steps (divisors of it, multiples of the progress bar's stride) that take up to
    #: BUDGET_WALL s at the pace so far, when fewer (an expensive f: a verdict within seconds)
    BUDGET_WINDOW, BUDGET_UNITS, BUDGET_WALL = 1000, (50, 100, 200, 500, 1000), 2.0

    def _steps_until(self, stop, on_step):
        """Steps toward t_end until t reaches ``stop`` (to 1e-12 relative): the embedded
        pairs on compiled kernels in the compiled step loop (:mod:`.integrators.compiled_loop`,
        the same steps), else :meth:`_step` by :meth:`_step`."""
        loop = None
        if self._use_loop and getattr(self.stepper.prob, "compiled", False):
            from .integrators.compiled_loop import of       # (numba: not on the numpy backend)
            loop = of(self)
        if loop is not None:
            return loop.run(self, stop, on_step)
        tol = 1e-12 * max(1.0, abs(stop))
        while self.t < stop - tol:
            self._step(self.t_end, on_step)


    def advance_to(self, target, on_step=None):
        """Step until ``target`` is reached, without collecting states.

        Parameters
        ----------
        target : float
            The time to reach (≥ the current time).
        on_step : callable, optional
            ``on_step(t, q, V)`` after every accepted step.

        Returns
        -------
        q, V : ndarray
            The state at ``target`` (interpolated within the last step when the method has
            dense output).

        Raises
        ------
        lgt_bridge.StepError
            A failed step (:class:`~.errors.ModelError` when the engine raised,
            :class:`~.errors.ChartDomainError` for a fixed step beyond its chart's domain);
            the simulation stays at the last good step (``q``, ``V``, ``t``).
        """
        try:
            return self._advance_to(target, on_step)
        except StepFailed as exc:
            raise exc.error(str(exc)) from None

    def _advance_to(self, target, on_step=None):
        st = self.stepper
        if not self.dense:
            while self.t < target:
                self._step(target, on_step)
            return st.q, st.V
        tol = 1e-12 * max(1.0, abs(target))
        self._steps_until(target, on_step)
        if abs(self.t - target) <= tol or st.dense is None:
            return st.q, st.V
        return st.dense(target)

    def advance_to_many(self, targets, on_step=None):
        """Step until ``targets[0]`` is reached; the states at every target the last step
        covers, from its dense output in one call (failures as :meth:`advance_to`).

        Parameters
        ----------
        targets : array_like
            Increasing times (the first ≥ the current time).
        on_step : callable, optional
            As :meth:`advance_to`.

        Returns
        -------
        n : int
            How many of the targets the last step covers (≥ 1; 1 without dense output).
        Q, V : ndarray
            Rows of q and V at ``targets[:n]`` (on the step's end: the step's own state).
        """
        try:
            return self._advance_to_many(np.asarray(targets, float), on_step)
        except StepFailed as exc:
            raise exc.error(str(exc)) from None

    def _advance_to_many(self, targets, on_step=None):
        if not self.dense:
            return (1, *(np.array(x, ndmin=2) for x in self._advance_to(targets[0], on_step)))
        st, first = self.stepper, targets[0]
        self._steps_until(first, on_step)
        t, tol = self.t, 1e-12 * max(1.0, abs(self.t))
        # (bisect: numpy's searchsorted costs more on the few targets a step covers)
        n = max(1, bisect_right(targets, t + tol))
        k = min(n, bisect_left(targets, t - tol))
        dense = st.dense if k else None         # (made only for targets within the step)
        if k and dense is None:
            n, k = 1, 0
        Q, V = dense.many(targets[:k]) if k else (None, None)
        if k < n:                       # the step's own state for targets on its end
            if k == n - 1:
                Qe, Ve = np.array(st.q, float, ndmin=2), np.array(st.V, float, ndmin=2)
            else:
                Qe, Ve = np.empty((n - k, len(st.q))), np.empty((n - k, len(st.V)))
                Qe[:], Ve[:] = st.q, st.V
            Q, V = (Qe, Ve) if not k else (np.concatenate([Q, Qe]), np.concatenate([V, Ve]))
        return n, Q, V

    def run(self, t_end, t_eval=None, progress=None, events=None):
        """Advance from the current time to ``t_end``, collecting the states.

        Parameters
        ----------
        t_end : float
            The end of this stretch (> the current time).
        t_eval : array_like, optional
            Output times within the stretch (default: every step, the start included; empty:
            none, the state still advanced to ``t_end``).
        progress : bool, optional
            As :func:`~lgt_bridge.simulate`.
        events : callable or list of callable, optional
            Functions g(t, q, V) whose zero crossings are located and returned as
            ``t_events``/``q_events``/``V_events``; a terminal one ends the run there
            (:mod:`lgt_bridge.events`).

        Returns
        -------
        SimulationResult
            This stretch. A failed step ends it with ``success=False`` (every step before it
            kept, the model at the last good state).

        Raises
        ------
        lgt_bridge.ChartDomainError
            A fixed-step chart overrun, with the result so far as ``.result``.
        """
        t0, t1 = self.t, float(t_end)
        if not t1 > t0:
            raise InputError(f"t_end = {t1} must be greater than the simulation's time t = {t0}.")
        t_eval = check_t_eval(t_eval, t0, t1)
        st = self.stepper
        tracker = None if events is None else _events.Tracker(self, events)   # checks g before a step
        self.t_end = t1
        self.dense = st.dense_capable
        wall0 = time.perf_counter()
        n_steps0 = self.n_steps
        ts, qs, Vs = [], [], []
        record_all = t_eval is None
        targets = [t1] if record_all else t_eval[t_eval > t0]
        if record_all or (len(t_eval) and t_eval[0] == t0):
            ts.append(t0), qs.append(st.q.copy()), Vs.append(st.V.copy())
        bar = simulation_bar(progress, t0, t1, self, st)

        def on_step(t, q, V):
            if record_all:
                ts.append(t), qs.append(q.copy()), Vs.append(V.copy())
            bar.step()

        success, message = True, "reached the end of t_span"
        if tracker is not None:
            hook = tracker.hook(on_step)
        else:               # (None: nothing to do after a step, which lets the steps run on)
            hook = on_step if record_all else (None if bar.mode is None else bar.hook)
        try:
            if not record_all:          # the outputs within a step in one dense call
                i = 0
                while i < len(targets):
                    n, Q, V = self._advance_to_many(targets[i:], hook)
                    ts.extend(targets[i:i + n].tolist()), qs.extend(Q), Vs.extend(V)
                    i += n
            if self.t < t1:
                self._advance_to(t1, hook)
        except _events.Terminal as stop:      # the run ends at the event (the state moved there)
            last = ts[-1] if ts else -np.inf
            for t in ([stop.t] if record_all else [t for t in targets if last < t <= stop.t]):
                q_out, V_out = stop.state(t)
                ts.append(t), qs.append(np.array(q_out)), Vs.append(np.array(V_out))
            message = stop.message
        except StepFailed as exc:
            self.model.write_back(st.q, st.V, self.t)
            bar.close()
            if exc.error is ChartDomainError:
                err = ChartDomainError(str(exc))
                err.result = collect(self, ts, qs, Vs, False, str(exc), wall0, n_steps0, tracker)
                raise err from None
            success, message = False, str(exc)
        bar.close()
        return collect(self, ts, qs, Vs, success, message, wall0, n_steps0, tracker)


__all__ = ["Simulation", "SimulationResult", "make_stepper"]
