"""Switches of a model's discrete mode, located in time and stepped over; and the steps of a
model with discontinuous states (:func:`attempt_discontinuous`, see its docstring).

Some models carry a discrete mode that their f reads and that the state decides between
steps: Exudyn's GeneralContact keeps the set of active contact pairs that its PostNewton
sets from the state (a pair becomes active when its gap closes with a compressive force,
inactive when its force would pull), and its forces come from that set. Such a model has

    ``switch_mode(q, V, t)``: make the mode the one the state (q, V, t) calls for, and
    return it (a value compared with ``==``).

:class:`SwitchLocator` then takes every step of the :class:`~.simulation.Simulation` so:

1. the mode is set from the step's start state (something between the steps, an engine's
   own step loop, may have set it from another state);
2. the step is taken with that mode frozen, so f is smooth within it;
3. after an accepted step of a method with dense output (dopri5, dop853, radau5), the mode
   is asked at the step's end and at equally spaced interior times (``SAMPLES``, or as many
   as the mode's ``test_points(h)`` asks for: Exudyn's spheres move less than half a radius
   between two), on the step's continuous extension; in the first interval where it differs from the step's
   mode, the switch is located by bisection to ``xtol`` (as events: 0.01·tol·h, not below
   4·eps·abs(t); a mode with ``partial = True`` is a tuple of per-item values whose call
   takes ``items=``: the bisection asks only the items that differ at the bracket's end), and the step is cut there: the stepper restarts (``restart_at``) at the
   bracket's upper end, with the state of the step's continuous extension there (the old
   mode's solution, a time ``xtol`` past the switch at most) and the new mode.

So no step straddles a switch and the error control sees smooth f only: the steps of an
error-controlled pair no longer collapse at a contact's damping jump, and the error falls
with the tolerance. A switch on and off again between two test points of one step is not
seen (cap the step with ``max_step``). Methods without dense output take the mode from
each step's start state only (Exudyn's own rule for its steps: the active set of the last
step's end).
"""
import numpy as np

_EPS = np.finfo(float).eps

#: what a model's ``post_step`` returns when its discontinuous states moved without
#: switching (an engine's friction direction, a penetration): redo the step with them
REDO = "redo"
#: states that never settle shorten the step down to this fraction of the run's step, where
#: they are kept when the model ignores max iterations (keeping them at the full step: a
#: rolling coin 5e-3 off Exudyn's result at any step; shortening to h_event: a car on two
#: penalty wheels advanced 1e-8 s per step); a model whose states cannot settle however
#: short the step (a dry friction whose direction flips at every redo of a sticking wheel)
#: sets its own ``unsettled_cut`` (1: kept at the step's length, as Exudyn keeps them)
UNSETTLED_CUT = 1.0 / 16


def attempt_discontinuous(sim, h, post):
    """A step of simulation ``sim`` whose model has discontinuous states (contact, friction:
    its ``post_step(q, V, t)`` updates them from the step's end state and says whether they
    switched: false, true, or ``REDO``). A step over which they switch is declined and
    retried at a quarter of its length, from its start and with the states of its start,
    until it is no longer than ``sim.h_event`` (nor ``sim.min_step``); that short step is
    then redone with the new states (as Exudyn's discontinuous iteration redoes its Newton
    step), up to ``max_discontinuous`` times (the model's attribute, else
    ``sim.MAX_DISCONTINUOUS``). ``REDO`` redoes the step at its length at once, as Exudyn
    iterates; states that still move after those redos shorten the step as a switch does
    (Exudyn's ``ignoreMaxIterations = False``), but when the model's
    ``ignore_max_discontinuous`` is true (Exudyn's default ``ignoreMaxIterations = True``: a
    friction direction flipping at every redo of a sticking wheel) only down to the model's
    ``unsettled_cut`` (else ``UNSETTLED_CUT``) of the run's step (``sim.dt``, else
    ``sim.max_step``), where they are kept and the step accepted. Exudyn's own loop keeps the
    states of its last solve, so a model emulating it counts its redos as Exudyn does (a
    friction direction flipping at every solve: the kept force depends on the parity of the
    count). Returns the stepper's (accepted, h_new)."""
    st, m, t = sim.stepper, sim.model, sim.t
    snap, d0 = st.snapshot(), m.discontinuous_state()
    # a step no longer than the floor up to rounding is at the floor (a step landing on the end
    # time may exceed it by an ulp: cut again, it lands on that same length, forever)
    floor = max(sim.h_event, sim.min_step) * (1.0 + 1e-9)
    n_max = int(getattr(m, "max_discontinuous", sim.MAX_DISCONTINUOUS))
    ignore = bool(getattr(m, "ignore_max_discontinuous", False))
    nominal = getattr(sim, "dt", None) or getattr(sim, "max_step", None) or h     # the run's step
    # (up to rounding: a step ending on a time grid point is longer than dt by an ulp)
    keep = max(floor, float(getattr(m, "unsettled_cut", UNSETTLED_CUT)) * nominal * (1.0 + 1e-9))
    accepted, h_new = st.attempt(t, h)
    for k in range(n_max + 1):
        changed = post(st.q, st.V, t + h) if accepted else False
        if not changed:
            break
        last = k == n_max
        if last and changed == REDO and ignore and h <= keep:
            break                                           # unsettled: kept, as Exudyn does
        if (changed != REDO or last) and h > floor:         # a switch within the step: locate it
            st.restore(snap)
            m.set_discontinuous_state(d0)
            return False, max(0.25 * h, max(sim.h_event, sim.min_step))
        if last:
            break
        st.restore(snap)
        sim.n_redone += 1
        accepted, h_new = st.attempt(t, h)
        if not accepted:
            # the redo with the new states was rejected by the error control: the retry, a
            # shorter step from the same start, begins with the start's states (left at the
            # end's, a spring switched on at a contact acted before the contact closed)
            m.set_discontinuous_state(d0)
    return accepted, h_new


class SwitchLocator:
    """The switches of one simulation's model (see the module docstring).

    Attributes
    ----------
    t_switches : list of float
        The located switch times (the restart times) of the simulation so far.
    """

    #: interior test points per step (besides the step's end), at least, and at most
    #: (a mode with ``test_points(h)`` asks for more: the step from the state of its
    #: last-but-one call to that of its last call)
    SAMPLES, MAX_SAMPLES = 3, 1000

    def __init__(self, sim, mode):
        self.sim, self.mode = sim, mode
        self.t_switches = []
        rtol = getattr(sim, "rtol", 1e-6)
        atol = getattr(sim, "atol", 1e-8)
        self.tol = min([x for x in (rtol, atol) if x > 0] or [1e-8])

    def attempt(self, t, h):
        """One step attempt from t of length h. Returns (accepted, h_new, t_cut): t_cut is
        the located switch time where the accepted step was cut (None: not cut)."""
        st = self.sim.stepper
        m0 = self.mode(st.q, st.V, t)
        accepted, h_new = st.attempt(t, h)
        if not accepted or not st.dense_capable:
            return accepted, h_new, None
        dense = st.dense
        if dense is None:
            return accepted, h_new, None
        t1 = t + h
        q1, V1 = st.q.copy(), st.V.copy()
        dense(t + 0.5 * h)      # made now, with the step's mode (DOP853's extra stages call f)
        proj = st.projector

        def state(s):
            if s >= t1:
                return q1, V1
            q, V = dense(s)
            if proj is not None:
                it = proj.iterations
                q = proj.positions(q, s)[0]
                V = proj.velocities(q, V, s)[0]
                proj.iterations = it        # the statistics count the steps' projections only
            return np.array(q, float), np.array(V, float)

        m1 = self.mode(q1, V1, t1)
        n = self.SAMPLES
        more = getattr(self.mode, "test_points", None)
        if more is not None:                # the model's own count (e.g. from how far it moved)
            n = min(max(n, int(more(h))), self.MAX_SAMPLES)
        lo, hi = t, None
        for k in range(1, n + 1):
            s = t + h * k / (n + 1)
            m = self.mode(*state(s), s)
            if m != m0:
                hi, m1 = s, m
                break
            lo = s
        if hi is None:
            if m1 == m0:
                self.mode(q1, V1, t1)       # the step's mode again, set from its end state
                return accepted, h_new, None
            hi = t1
        items = None                        # a partial mode: bisect on the items that differ at hi
        if getattr(self.mode, "partial", False):
            items = [i for i, (a, b) in enumerate(zip(m0, m1)) if a != b]
            ref = tuple(m0[i] for i in items)

        def switched(s):
            if items is None:
                return self.mode(*state(s), s) != m0
            return self.mode(*state(s), s, items=items) != ref

        xtol = max(0.01 * self.tol * h, 4 * _EPS * abs(t1))
        while hi - lo > xtol:
            mid = 0.5 * (lo + hi)
            if not lo < mid < hi:
                break
            if switched(mid):
                hi = mid
            else:
                lo = mid
        qe, Ve = state(hi)
        st.restart_at(qe, Ve, hi)
        if st.dense is None:                # outputs before the cut still read the step's extension
            st.dense = dense
        self.mode(st.q, st.V, hi)          # the new mode, from the state where it switched
        self.t_switches.append(hi)
        return accepted, h_new, hi


def locator(sim, model):
    """The :class:`SwitchLocator` of a model with ``switch_mode``, else None."""
    mode = getattr(model, "switch_mode", None)
    return None if mode is None else SwitchLocator(sim, mode)


__all__ = ["SwitchLocator", "locator"]
