"""The local problem on compiled kernels (:mod:`lgt_bridge.kernels.stage`).

Same operations and results as :class:`~lgt_bridge.integrators.local.LocalProblem`
(tests: 1e-13), with every body of the model handled in one kernel call and the
stage buffers allocated once. The bodies' quaternions ("quats") are one (N, 4) array
instead of a list per body set.
"""
import numpy as np

from ..kernels import stage as _k
from ..kernels.rotations import PARAM_CODES
from .local import LocalProblem

_EMPTY = np.zeros((0, 0))


class CompiledProblem(LocalProblem):

    compiled = True

    def __init__(self, model, group="SE3", chart="exp"):
        super().__init__(model, group, chart)
        self.bt = _k.body_table(self.sets, PARAM_CODES)
        self.vt = np.stack([self.vq, self.vv, self.vx], axis=1).astype(np.int64).reshape(-1, 3)
        nb, nq = len(self.bt), self.layout.nq
        self._X = np.zeros(self.nX)
        self._W = np.zeros(self.nv)
        self._q = np.zeros(nq)
        self._V = np.zeros(self.nv)
        self._Xd = np.zeros(self.nX)
        self._p = np.zeros((nb, 4))
        self._one = np.ones(1)
        self._zW = np.zeros(self.nv)
        self._zK = np.zeros((1, self.nv))

    # --- per step ---------------------------------------------------------------
    def start(self, q_k, quats=None):
        self.q_k = np.ascontiguousarray(q_k, dtype=float)
        if quats is None:
            quats = np.empty((len(self.bt), 4))
            _k.bases(self.bt, self.q_k, quats)
        self.pk = quats

    @property
    def start_quats(self):
        return self.pk

    def snapshot(self):
        return self.q_k, self.pk

    def restore(self, snap):
        self.q_k, self.pk = snap

    def _at(self, X, W):
        """Kernel τ and velocities at (X, W): fills the internal buffers."""
        X = np.ascontiguousarray(X, dtype=float).reshape(1, -1)
        _k.stage_state(X, self._zK, self._one, 1, 1.0, W, self._X, self._W, self.bt, self.vt,
                       self.q_k, self.pk, self._q, self._V, self._Xd, self._p)

    def configuration(self, X):
        self._at(X, self._zW)
        return self._q.copy(), self._p.copy()

    def state_at(self, X, W):
        self._at(X, np.ascontiguousarray(W, dtype=float))
        return self._q.copy(), self._V.copy()

    def _convert(self, mode, src, W, quats):
        out = np.empty(len(src))
        _k.convert(mode, np.ascontiguousarray(src, dtype=float), np.ascontiguousarray(W, dtype=float),
                   quats, self.bt, out)
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
        self._at(X, np.ascontiguousarray(W, dtype=float))
        return self._Xd.copy()

    def rhs(self, X, W, t, at_start=False):
        W = np.ascontiguousarray(W, dtype=float)
        self._at(X, W)
        q, V, Xd, p = self._q.copy(), self._V.copy(), self._Xd.copy(), self._p.copy()
        Vd = np.asarray(self.model.f(q, V, t), dtype=float)
        self.n_f += 1
        return Xd, self.group_acceleration(Vd, W, p), q, V

    # --- the stage API ------------------------------------------------------------
    def stage(self, KX, KW, i, a, h, W0, t, ts, climit=np.inf):
        c = _k.stage_state(KX, KW, a, i, h, W0, self._X, self._W, self.bt, self.vt, self.q_k,
                           self.pk, self._q, self._V, KX[i], self._p)
        if c > climit:
            return c
        Vd = self.model.f(self._q, self._V, ts)
        self.n_f += 1
        if type(Vd) is not np.ndarray or Vd.dtype != np.float64:
            Vd = np.asarray(Vd, dtype=float)
        if not _k.stage_derivative(Vd, self._W, self._p, self.bt, KW, KX, i):
            self.stage_failed(KX[i], KW[i], t, ts, self._q, self._V)
        return 0.0

    def start_rates(self, KX, W0):
        _k.stage_state(KX, self._zK, self._one, 0, 0.0, W0, self._X, self._W, self.bt, self.vt,
                       self.q_k, self.pk, self._q, self._V, KX[0], self._p)

    def end(self, KX, KW, b, h, W0):
        _k.stage_state(KX, KW, b, len(b), h, W0, self._X, self._W, self.bt, self.vt, self.q_k,
                       self.pk, self._q, self._V, self._Xd, self._p)
        return self._X.copy(), self._W.copy(), self._q.copy(), self._V.copy(), self._p.copy()

    def max_cayley(self, X):
        if not len(self.cay_rows):
            return 0.0
        return float(np.sqrt((np.asarray(X)[self.cay_rows] ** 2).sum(axis=1)).max())
