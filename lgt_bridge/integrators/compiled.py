"""The local problem on compiled kernels (:mod:`lgt_bridge.kernels.stage`).

Same operations and results as :class:`~lgt_bridge.integrators.local.LocalProblem`
(tests: 1e-13), with every body of the model handled in one kernel call and the stage
state in one preallocated work array. A stage is one kernel call (the previous stage's
derivative from the model's V̇, fused with this stage's state) and the model's f, which
receives views of the work array. The bodies' quaternions ("quats") are one (N, 4) array
instead of a list per body set.
"""
import numpy as np

from ..kernels import entry_point
from ..kernels import genalpha as _ga
from ..kernels import stage as _k
from ..kernels import steps as _steps
from ..kernels.rotations import PARAM_CODES
from .base import NULL_CONTEXT
from .local import LocalProblem

_NONE = np.zeros(0)
_F64 = np.dtype(np.float64)
_NDARRAY = np.ndarray
#: the stage and step-end kernels without type dispatch, for the steppers' own buffers
#: (float64, C-contiguous) and a V̇ checked float64 and 1-D
_STAGE, _STEP_END = entry_point(_k.stage), entry_point(_k.step_end)


class CompiledProblem(LocalProblem):

    compiled = True

    def __init__(self, model, group="SE3", chart="exp"):
        super().__init__(model, group, chart)
        self.work = w = np.zeros(self.work_size)
        # the work array's views (as kernels.stage.views), sliced here: a call's set-up is
        # part of every call
        self._X, self._W, self._q, self._V, self._W0, self._qk, self._xd = [w[i:j] for i, j in self._slices]
        self._pk, self._p = [w[i:j].reshape(-1, 4) for i, j in self._quat_slices]
        self.bind(model)
        self._Xd = np.zeros(self.nX)
        self._W0_src = None            # the array last copied into the W0 slot
        self._vd = _NONE               # the model's V̇ of the last stage, not yet converted
        self._pending = None           # (i, t, ts) of that stage

    def bind(self, model):
        """The stages' f and its velocity argument: f(q, V) or the engine's f(q, v) (v written
        by the stage kernel, V̇ read in the engine's form: model.engine_velocity). A problem
        kept for reuse (:mod:`.steppers`) is bound to the next model of its layout here."""
        self.model = model
        self._fs, self._vs = model.f, self._V
        eng = getattr(model, "engine_velocity", None)
        if eng is not None and len(eng.bodies):
            bodies = eng.bodies
            got = self._engine_I.get(bodies) if type(bodies) is tuple else None    # (made before)
            self._I = got if got is not None else self._engine_tables(tuple(int(b) for b in bodies))
            w = self.work
            self._fs, self._vs = eng.f, w[self._ve_slice[0]:self._ve_slice[1]]

    @staticmethod
    def analyze(model, group, chart):
        """The reference problem's analysis and the kernels' tables: the body table, the
        vector/circle table ``vt``, the work array's layout, and the constant inputs of the
        kernels (read only, shared by the problems of the model)."""
        a = LocalProblem.analyze(model, group, chart)
        a["bt"] = _k.body_table(a["sets"], PARAM_CODES)
        # rows (iq, iv, ix, iq_sin): iq_sin = -1 for a vector coordinate, else the sin entry
        # of a circle coordinate whose cos entry is iq
        vec = np.stack([a["vq"], a["vv"], a["vx"], np.full(len(a["vq"]), -1)], axis=1)
        circ = np.stack([a["cq"][:, 0], a["cv"], a["cx"], a["cq"][:, 1]], axis=1)
        a["vt"] = np.ascontiguousarray(np.concatenate([vec.reshape(-1, 4), circ.reshape(-1, 4)]), np.int64)
        nX, nv, nq, nb = a["nX"], a["nv"], model.layout.nq, len(a["bt"])
        a["off"], a["work_size"] = _k.work_layout(nX, nv, nq, nb)
        off = [int(o) for o in a["off"]]
        a["_slices"] = [(off[k], off[k] + n) for k, n in ((_k.OX, nX), (_k.OW, nv), (_k.OQ, nq), (_k.OV, nv),
                                                          (_k.OW0, nv), (_k.OQK, nq), (_k.OXD, nX))]
        a["_quat_slices"] = [(off[k], off[k] + 4 * nb) for k in (_k.OPK, _k.OP)]
        a["_I"] = _k.pack_tables(a["bt"], a["vt"], a["off"])
        a["_ve_slice"] = (off[_k.OVE], off[_k.OVE] + nv)
        a["_engine_I"] = {}                       # packed tables by the model's engine bodies
        a["_n_end"] = off[_k.OW0]                 # X, W, q, V: the work array's first entries
        a["_one"] = np.ones(1)
        a["_zK"] = np.zeros((2, max(nX, nv)))
        a["_zv"], a["_zx"] = np.zeros(nv), np.zeros(nX)     # (rates: no affine part)
        return a

    def _engine_tables(self, bodies):
        """The packed tables with the bodies ``bodies`` (layout indices) in the engine's
        velocity form (kept in the analysis, by bodies)."""
        got = self._engine_I.get(bodies)
        if got is None:
            row = {}
            for s in self.sets:
                for b in s.ids:
                    row[int(b)] = len(row)
            bad = [b for b in bodies if b not in row or self.layout.bodies[b].rotation_only]
            if bad:
                from ..errors import InputError
                raise InputError(f"engine_velocity: bodies {bad} are not rigid bodies with a position "
                                 f"in the model's layout ({self.layout.nbodies} bodies); list only indices "
                                 "of layout.bodies whose twist has six entries (rotation-only bodies take V as is)")
            bt, off = _k.with_engine(self.bt, self.off, [row[b] for b in bodies])
            got = self._engine_I[bodies] = _k.pack_tables(bt, self.vt, off)
        return got

    # --- per step ---------------------------------------------------------------
    def start(self, q_k, quats=None):
        self.q_k = q_k
        self._qk[:] = q_k
        if quats is None:
            _k.bases(self.bt, self._qk, self._pk)
        else:
            self._pk[:] = quats
        self._vd = _NONE

    @property
    def start_quats(self):
        return self._pk.copy()

    def snapshot(self):
        return self.q_k, self._pk.copy()

    def restore(self, snap):
        self.start(*snap)

    def _w0(self, W0):
        if W0 is not self._W0_src:
            self._W0[:] = W0
            self._W0_src = W0

    def _at(self, X, W):
        """τ and velocities at (X, W) into the work array (q, V, p; Xd into _Xd)."""
        K = np.ascontiguousarray(X, dtype=float).reshape(1, -1)
        self._W0[:] = W
        self._W0_src = None
        _k.stage_state(K, self._zK, self._one, 1, 1.0, self._W0, self._X, self._W, self.bt, self.vt,
                       self._qk, self._pk, self._q, self._V, self._Xd, self._p)

    def configuration(self, X):
        self._at(X, 0.0)
        return self._q.copy(), self._p.copy()

    def state_at(self, X, W):
        self._at(X, W)
        return self._q.copy(), self._V.copy()

    def dense_states(self, w, FX, FW, W0, base):
        """As the reference, in one kernel call on the base's q_k and quaternions."""
        q_k, pk = base
        Q, V = np.empty((len(w), len(self._qk))), np.empty((len(w), self.nv))
        c = np.ascontiguousarray               # (one signature: C-contiguous float64)
        _k.dense_states(c(w, dtype=float), c(FX, dtype=float), c(FW, dtype=float), c(W0, dtype=float), self.bt,
                        self.vt, c(q_k, dtype=float), pk, Q, V)
        return Q, V

    def _convert(self, mode, src, W, quats):
        out = np.empty(len(src))
        _k.convert(mode, np.ascontiguousarray(src, dtype=float), np.ascontiguousarray(W, dtype=float),
                   np.ascontiguousarray(quats, dtype=float), self.bt, out)
        return out

    def model_velocity(self, W, quats):
        return self._convert(0, W, W, quats)

    def group_velocity(self, V, quats):
        return self._convert(1, V, V, quats)

    def group_acceleration(self, Vdot, W, quats):
        return self._convert(2, Vdot, W, quats)

    def model_acceleration(self, Wdot, W, quats):
        return self._convert(3, Wdot, W, quats)

    def kinematics(self, X, W):
        self._at(X, W)
        return self._Xd.copy()

    def rhs(self, X, W, t, at_start=False):
        self._at(X, W)
        q, V, Xd, p = self._q.copy(), self._V.copy(), self._Xd.copy(), self._p.copy()
        Vd = np.asarray(self.model.f(q, V, t), dtype=float)
        self.n_f += 1
        return Xd, self.group_acceleration(Vd, self._W, p), q, V

    def rates(self, X, W, t):
        """[Ẋ, Ẇ] of the local ODE at (X, W) as one vector: the state kernel, the model's f
        (on views of the work array) and the conversion kernel."""
        _ga.ga_state(self._zv, 0.0, self._zx, W, X, self.local_index, self.work, self.bt, self.vt, self.off, True)
        Vd = self.model.f(self._q, self._V, t)
        self.n_f += 1
        if type(Vd) is not np.ndarray or Vd.dtype is not _F64:
            Vd = np.ascontiguousarray(Vd, dtype=float)
        out = np.empty(self.nX + self.nv)
        out[:self.nX] = self._xd
        _k.convert(2, Vd, self._W, self._p, self.bt, out[self.nX:])
        return out

    def initial_step(self, fX, fW, W, t, rtol, atol, order):
        """:func:`.control.initial_step` from f0 = (fX, fW) at X = 0 (the first stage's), its
        arithmetic in two kernel calls around the one f it needs."""
        nX = self.nX
        Y = np.empty(nX + len(fW))
        h0, d1 = _steps.h0_start(fX, fW, W, float(rtol), float(atol), Y)
        f1 = self.rates(Y[:nX], Y[nX:], t + h0)
        return _steps.h0_end(f1, fX, fW, W, float(rtol), float(atol), h0, d1, float(order))

    # --- generalized-α ---------------------------------------------------------------
    def ga_state(self, Wd, sv, sp, Wa, dXa, to_local):
        """(q, V, quats, W) at W = Wa + sv Ẇ, X = dXa + sp Ẇ[to_local]: one kernel call;
        views of the work array, valid until the next evaluation."""
        _ga.ga_state(Wd, sv, sp, Wa, dXa, to_local, self.work, self.bt, self.vt, self.off, False)
        return self._q, self._V, self._p, self._W

    def ga_state_args(self, sv, sp, Wa, dXa, to_local):
        """(ga_state's kernel arguments after Ẇ, q, V): for a kernel that ends with the state
        at its new Ẇ (genalpha's fused Newton update), and the views of q and V it writes."""
        return (sv, sp, Wa, dXa, to_local, self.work, self.bt, self.vt, self.off, False), self._q, self._V

    def ga_affine(self, W, Wd, a, af, am, h, g, b, k, to_local):
        """One kernel call instead of ~10 numpy operations."""
        n, nX = len(W), len(to_local)
        a0, Wa, dXa, sp = np.empty(n), np.empty(n), np.empty(nX), np.empty(nX)
        _ga.ga_affine(W, Wd, a, af, am, h, g, b, k, self.chart_scale, to_local, a0, Wa, dXa, sp)
        return a0, Wa, dXa, sp

    error_sums = staticmethod(_k.error_sums)

    def quiet(self):
        """The kernels never warn: nothing to silence."""
        return NULL_CONTEXT

    def ga_residual(self, Vd, Wd, r, W, quats):
        """r = Ẇ - Ẇ(V̇) at the last ga_state (W, quats are its own); returns Σ r²."""
        if type(Vd) is not np.ndarray or Vd.dtype is not _F64:
            Vd = np.ascontiguousarray(Vd, dtype=float)
        return _ga.ga_residual(Vd, Wd, r, self.work, self.bt, self.off)

    # --- the stage API ------------------------------------------------------------
    def stage(self, KX, KW, i, a, h, W0, t, ts, climit=np.inf):
        if W0 is not self._W0_src:                 # (_w0, inlined: this runs once per stage)
            self._W0[:] = W0
            self._W0_src = W0
        c = _k.stage(_NONE if i == 0 else self._vd, KX, KW, a, i, h, self.work, self._I)
        if c < 0.0:
            self._failed(KX, KW)
        self._vd = _NONE                          # consumed (a failing f leaves nothing pending)
        if c > climit:
            return c
        Vd = self._fs(self._q, self._vs, ts)
        self.n_f += 1
        if type(Vd) is not np.ndarray or Vd.dtype is not _F64 or Vd.ndim != 1:
            Vd = np.ascontiguousarray(Vd, dtype=float).reshape(-1)
        self._vd = Vd
        self._pending = (i, t, ts)
        self._h = h
        return 0.0

    def _failed(self, KX, KW):
        i, t, ts = self._pending
        self._vd = _NONE
        self.stage_failed(KX, KW, i, t, ts, self._q, self._V, self._h, self._W0, self._W)

    def flush(self, KX, KW):
        """Convert the last stage's V̇ (the fused kernel defers it to the next call)."""
        if len(self._vd):
            i = self._pending[0]
            if _k.stage(self._vd, KX, KW, _NONE, i + 1, 0.0, self.work, self._I) < 0.0:
                self._failed(KX, KW)
            self._vd = _NONE

    def start_rates(self, KX, W0):
        self._w0(W0)
        self._vd = _NONE
        _k.stage(_NONE, KX, self._zK, self._one, 0, 0.0, self.work, self._I)

    def end(self, KX, KW, b, h, W0):
        if W0 is not self._W0_src:
            self._W0[:] = W0
            self._W0_src = W0
        i = self._pending[0] + 1 if len(self._vd) else len(b)
        c = _k.stage(self._vd, KX, KW, b, i, h, self.work, self._I)
        if c < 0.0:
            self._failed(KX, KW)
        self._vd = _NONE
        return self._X.copy(), self._W.copy(), self._q.copy(), self._V.copy(), self._p.copy()

    def run_stages(self, KX, KW, A, c, i0, h, t, W0, climit=np.inf):
        """Stages i0, ..., len(c) - 1 of the step from t (the explicit steppers' loop, as
        ``stage`` for each): one kernel call and the model's f per stage, the names bound
        once. Returns 0.0, or the chart usage of the first stage beyond ``climit`` (its f
        not called); the last stage's V̇ is converted by :meth:`end_step` or :meth:`end`.
        KX, KW: the stepper's stage buffers (float64, C-contiguous: the kernel is called
        without type checks), A's rows float64 vectors."""
        if W0 is not self._W0_src:
            self._W0[:] = W0
            self._W0_src = W0
        kern, f, w, I, q, V = _STAGE, self._fs, self.work, self._I, self._q, self._vs
        vd, n = self._vd, 0
        try:
            for i in range(i0, len(c)):
                cm = kern(vd, KX, KW, A[i], i, h, w, I)
                if cm < 0.0 or cm > climit:
                    self._vd = _NONE
                    if cm < 0.0:
                        self._pending = (i - 1, t, t + c[i - 1] * h)
                        self._h = h
                        self._failed(KX, KW)
                    return cm
                vd = f(q, V, t + c[i] * h)
                n += 1
                if vd.__class__ is not _NDARRAY or vd.dtype is not _F64 or vd.ndim != 1:
                    vd = np.ascontiguousarray(vd, dtype=float).reshape(-1)
        finally:
            self.n_f += n
        self._vd = vd
        self._pending = (len(c) - 1, t, t + c[-1] * h)
        self._h = h
        return 0.0

    def end_step(self, KX, KW, T, h, W0, rtol, atol):
        """The end of an embedded pair's step in one kernel call (:func:`kernels.stage.step_end`):
        (X1, W1, q1, V1, quats, s5, s3, num, den, sq) as :meth:`LocalProblem.end_step`; the
        four states are views of one new array."""
        if W0 is not self._W0_src:
            self._W0[:] = W0
            self._W0_src = W0
        vd = self._vd
        i = self._pending[0] + 1 if len(vd) else T.shape[1]
        st, s5, s3, num, den, sq = _STEP_END(vd, KX, KW, T, i, h, self.work, self._I, rtol, atol)
        if st < 0.0:
            self._failed(KX, KW)
        self._vd = _NONE
        y = self.work[:self._n_end].copy()
        a, b, c = self.nX, self.nX + self.nv, self.nX + self.nv + len(self._qk)
        return y[:a], y[a:b], y[b:c], y[c:], self._p.copy(), s5, s3, num, den, sq

    def chart_overrun(self, X=None):
        return super().chart_overrun(self._X if X is None else X)
