"""The embedded pairs' step loop in one compiled kernel (:func:`lgt_bridge.kernels.steps.drive`).

On the compiled backend a dop853 step of a small robot is 12 evaluations of f, 12 stage
kernel calls and, driven from Python (``Simulation._step``, ``AdaptiveRK._attempt`` and
``CompiledProblem.run_stages``), about 30 µs of Python: half a step's f on solo12. Here a
run is a bare loop of one kernel call and one f per stage; the kernel does the rest of the
step loop between two f, with the Python stepper's arithmetic (same steps, same results:
tests/core/test_compiled_loop.py). It hands back to Python

- after an accepted step that reaches the stop time, or after every accepted step when
  something must run then (an ``on_step`` hook, the model's ``write_back``), and every
  ``Simulation._budget_unit`` steps (the step-budget check), or every ``stride`` steps of
  a hook that may wait that long (a progress bar's);
- an attempt the Python stepper does itself (the step budget spent, a stage beyond its
  chart's domain or not finite): :meth:`Simulation._step` then takes that step, with its
  failure reports and retries, and the loop goes on (that attempt's f are evaluated twice);
- a step size below what the run allows (the same StepFailed as the Python loop).

Three attributes of an f let the loop call it more cheaply: ``loop_f``, a form of f for the
loop's own arguments (float64 C-contiguous q, v and a float t: Exudyn's f without its
conversions), which the loop calls instead; ``returns_float64_vector`` (its adapter vouches
for the result: Pinocchio's ABA, Exudyn's kernels), which spares the check of what it returns;
``time_free_call = (g, arg)`` with f(q, v, t) = g(q, v, arg) for every t (Pinocchio's free
motion under constant torques: ``aba(model, data)``), which spares f's own Python frame.

Used for a :class:`~.rkmk.AdaptiveRK` stepper on a
:class:`~.compiled.CompiledProblem`, without projection, post-step hooks or mode switches
(those stay in the Python loop).
"""
import numpy as np

from .. import diagnosis as _diagnosis
from ..end_jump import collapsed
from ..errors import ModelError
from ..kernels import entry_point
from ..kernels import steps as _s
from .base import StepFailed
from .compiled import CompiledProblem
from .rkmk import AdaptiveRK

_DRIVE = entry_point(_s.drive)
_NONE = np.zeros(0)
_F64 = np.dtype(np.float64)
_NDARRAY = np.ndarray


def of(sim):
    """The loop of a :class:`~lgt_bridge.Simulation` (made once per stepper), or None when
    its stepper or model needs the Python loop."""
    st = sim.stepper
    loop = getattr(st, "_compiled_loop", None)
    if loop is None:
        if not (type(st) is AdaptiveRK and isinstance(st.prob, CompiledProblem)):
            return None
        loop = st._compiled_loop = Loop(st)
    if st.projector is not None or sim._post is not None or sim._switches is not None:
        return None
    return loop


_PROTOTYPES = {}


def _prototype(st):
    """(the loop array with C's fixed entries and the tableau filled in, its layout), made
    once per tableau, sizes and tolerances (a run's set-up is part of every call)."""
    prob, tab = st.prob, st.tab
    key = (id(tab), st._BX.shape, st._BW.shape, prob._n_end, len(prob.bt), st.rtol, st.atol, st.climit)
    got = _PROTOTYPES.get(key)
    if got is None or got[0] is not tab:
        ns = tab.stages
        A = np.zeros((ns, ns))
        for i, row in enumerate(st._A):
            A[i, :len(row)] = row
        TA = np.vstack([A, np.asarray(st._c, float)[None], st._T])
        lay, size = _s.layout(ns, len(TA), st._BX.shape[1], prob.nX, prob.nv, prob._n_end + 4 * len(prob.bt))
        L = np.zeros(size)
        C, ctl = L[:_s.NC], st.control
        C[_s.OS:_s.NBUF + 1] = lay
        C[_s.ALPHA], C[_s.BETA], C[_s.FACMIN], C[_s.FACMAX] = ctl.alpha, ctl.beta, ctl.facmin, ctl.facmax
        C[_s.ORDER], C[_s.SAFETY] = ctl.order, ctl.SAFETY
        C[_s.LANDING], C[_s.GROWS] = st.landing_steps, 1.0 if st.landing_grows else 0.0
        C[_s.BOUND], C[_s.RHODECAY], C[_s.STIFFSTEPS] = st.stability_bound, st.RHO_DECAY, st.STIFF_STEPS
        C[_s.HASPAIR] = st._stiff_pair is not None
        C[_s.HASE3] = tab.e3 is not None
        C[_s.TABFSAL] = bool(tab.fsal)
        C[_s.NSTAGES] = ns
        C[_s.RTOL], C[_s.ATOL], C[_s.CLIMIT], C[_s.NY] = st.rtol, st.atol, st.climit, st._n
        L[lay[1]:lay[2]] = TA.ravel()
        if len(_PROTOTYPES) > 32:
            _PROTOTYPES.clear()
        got = _PROTOTYPES[key] = (tab, L, lay)
    return got[1:]


class Loop:
    """The kernel's loop array for one stepper (:func:`.kernels.steps.layout`): the state C
    (its constants set here), the save area of the last accepted step's end, the tableau, and
    the stepper's stage buffers, which become views of it."""

    def __init__(self, st):
        L0, lay = _prototype(st)
        self.n_end = st.prob._n_end
        self.L = L = L0.copy()
        self.C = L[:_s.NC]
        o_s, o_ta, o_bx, o_bw = lay[:4]
        self.S = L[o_s:o_ta]
        # the stepper's buffers as views of L (their contents and which set is current kept)
        BX, BW = L[o_bx:o_bw].reshape(st._BX.shape), L[o_bw:].reshape(st._BW.shape)
        BX[:], BW[:] = st._BX, st._BW
        bufs = st._bufs
        cur = 0 if st.KX is bufs[0][0] else 1
        last = 0 if st._last_KW is bufs[0][1] else 1 if st._last_KW is bufs[1][1] else None
        st._BX, st._BW = BX, BW
        st._bufs = bufs = [(BX[0], BW[0]), (BX[1], BW[1])]
        st.KX, st.KW = bufs[cur]
        if last is not None:
            st._last_KW = bufs[last][1]
        self.runs = 0                          # calls of run (tests: the loop was used)

    def _load(self, sim, stop, each):
        """The simulation's and stepper's state into C."""
        st, C = sim.stepper, self.C
        ctl = st.control
        C[_s.T], C[_s.H], C[_s.TARGET], C[_s.STOP] = sim.t, sim.h, sim.t_end, stop
        C[_s.STAGE], C[_s.NSTEPS], C[_s.MAXSTEPS], C[_s.NREJ], C[_s.NF] = -1.0, sim.n_steps, sim.max_steps, 0.0, 0.0
        C[_s.CUR] = 0.0 if st.KX is st._bufs[0][0] else 1.0
        C[_s.FSAL], C[_s.HCAY], C[_s.HSTABLE], C[_s.RHO] = st._fsal, st._hcay, st.h_stable, st._rho
        C[_s.NSTIFF], C[_s.NNONSTIFF] = st._n_stiff, st._n_nonstiff
        C[_s.STIFF_T], C[_s.STIFF_H], C[_s.STIFF_RHO] = st.stiff if st.stiff is not None else (np.nan,) * 3
        C[_s.ERRPREV], C[_s.CAP] = ctl._err_prev, ctl._cap
        C[_s.MAXSTEP], C[_s.MINSTEP] = sim.max_step, sim.min_step
        C[_s.EACH], C[_s.BUDGET] = each, sim._budget_unit
        C[_s.ROLL] = C[_s.ACC] = 0.0
        prob = st.prob
        prob._W0[:] = st.W                 # the step's start: W0 here, q_k and p_k the problem's base
        prob._W0_src = None
        prob._vd = _NONE

    def _unload(self, sim):
        """C into the simulation and stepper (the last accepted step's end as their state,
        its dense output when the work array still holds its start)."""
        st, C = sim.stepper, self.C
        c = C.tolist()                     # (Python floats: one conversion, not one per slot)
        prob, ctl = st.prob, st.control
        sim.t, sim.h, sim.n_steps = c[_s.T], c[_s.H], int(c[_s.NSTEPS])
        st.n_rejected += int(c[_s.NREJ])
        prob.n_f += int(c[_s.NF])
        C[_s.NREJ] = C[_s.NF] = 0.0
        st._fsal = bool(c[_s.FSAL])
        cur = int(c[_s.CUR])
        st.KX, st.KW = st._bufs[cur]
        st._hcay, st.h_stable, st._rho = c[_s.HCAY], c[_s.HSTABLE], c[_s.RHO]
        st._n_stiff, st._n_nonstiff = int(c[_s.NSTIFF]), int(c[_s.NNONSTIFF])
        st.stiff = None if c[_s.STIFF_T] != c[_s.STIFF_T] else (c[_s.STIFF_T], c[_s.STIFF_H], c[_s.STIFF_RHO])
        ctl._err_prev, ctl._cap = c[_s.ERRPREV], c[_s.CAP]
        prob._vd = _NONE
        prob._W0_src = None
        if not c[_s.ACC]:
            return
        C[_s.ACC] = 0.0
        nX, nv, n_end = prob.nX, prob.nv, self.n_end
        y = self.S.copy()
        X1, W1, q1, V1 = y[:nX], y[nX:nX + nv], y[nX + nv:n_end - nv], y[n_end - nv:n_end]
        quats = y[n_end:].reshape(-1, 4)
        st._last_KW = st._bufs[1 - cur][1]
        st._dense = None
        if c[_s.ROLL]:              # the accepted step's start is still the problem's base
            base = (prob._qk.copy(), prob._pk.copy())
            st._dense_args = (c[_s.TPREV], c[_s.HPREV], X1, W1, *st._bufs[1 - cur], prob._W0.copy(), base)
        else:
            st._dense_args = None
        st.q, st.V, st.W = q1, V1, W1
        prob.start(q1, quats)

    def run(self, sim, stop, on_step):
        """Steps until t reaches ``stop`` (:meth:`Simulation._steps_until`)."""
        st = sim.stepper
        prob = st.prob
        tol = 1e-12 * max(1.0, abs(stop))
        if not sim.t < stop - tol:
            return
        self.runs += 1
        # after every step, unless the hook may wait (a progress bar's: every ``stride`` steps)
        stride = getattr(on_step, "stride", None)
        each = (on_step is not None and stride is None) or sim.model.step_write_back
        kern, f, q, v = _DRIVE, prob._fs, prob._q, prob._vs
        f = getattr(f, "loop_f", f)            # an f's form for float64 C-contiguous q, v and a float t
        w, I, L, C = prob.work, prob._I, self.L, self.C
        ndarray, F64 = _NDARRAY, _F64
        # an f whose result needs no check (its adapter says it returns a float64 vector)
        trusted = getattr(f, "returns_float64_vector", False) is True
        fast = getattr(f, "time_free_call", None) if trusted else None
        g, arg = fast if fast is not None else (None, None)
        while True:
            self._load(sim, stop, each)
            if stride is not None:
                C[_s.BUDGET] = stride
            vd = _NONE
            try:
                # one kernel call and one f per stage, nothing else (NaN: back to Python, C[CODE]
                # says why)
                if fast is not None:   # f(q, v, t) = g(q, v, arg) for every t, with no Python frame
                    ts = kern(vd, w, I, L)
                    while ts == ts:
                        ts = kern(g(q, v, arg), w, I, L)
                elif trusted:
                    ts = kern(vd, w, I, L)
                    while ts == ts:
                        ts = kern(f(q, v, ts), w, I, L)
                else:
                    ts = kern(vd, w, I, L)
                    while ts == ts:
                        vd = f(q, v, ts)
                        if vd.__class__ is not ndarray or vd.dtype is not F64 or vd.ndim != 1:
                            vd = np.ascontiguousarray(vd, dtype=float).reshape(-1)
                        ts = kern(vd, w, I, L)
            except ModelError as exc:          # the engine raised: end the run, keep the steps
                raise StepFailed(str(exc), error=ModelError) from exc
            finally:
                self._unload(sim)
            code = C[_s.CODE]
            if code == _s.ACCEPTED:            # Simulation._step's part after an accepted step
                sim.model.write_back(st.q, st.V, sim.t)
                if on_step is not None:
                    on_step(sim.t, st.q, st.V)
                if sim.n_steps % sim._budget_unit == 0:
                    _diagnosis.budget_tick(sim)
                target = sim.t_end
                if (sim.h < sim.min_step and sim.h < C[_s.HBEFORE]
                        and sim.t < target - 1e-12 * max(1.0, abs(target))):
                    collapsed(sim, on_step)
            elif code == _s.PY_STEP:
                sim._step(sim.t_end, on_step)
            elif code == _s.MIN_STEP:
                collapsed(sim, on_step)
            else:
                raise sim._too_small(underflow=code == _s.UNDERFLOW)
            if not sim.t < stop - tol:
                return
