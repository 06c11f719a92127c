"""The local problem of one step: the model seen through τ from X = 0.

For a step from (q_k, W_k) the state is (X, W): X the local coordinates of every
rigid body (6 each, in its group's chart) followed by the increments of the
vector-space coordinates and the angle increments of the circle (SO(2)) coordinates;
W the velocities in the integrator's representation: per rigid body (ω, Rᵀṙ) on SE(3),
(ω, ṙ) on SO(3)xR³; vector and circle rates unchanged.

    q(X)  = τ(q_k, X)                                   per body, batched per (α, G, ψ)
            (c, s) = (c_k, s_k) · exp(i X)              circles (SO(2), abelian)
    Ẋ     = dψ⁻¹_{-X}(W)  (bodies),   v (vector and circle coordinates)
    Ẇ     = f(q, V, t)  with  V = (ω, R u) on SE(3)  and  d/dt(Rᵀṙ) = Rᵀr̈ - ω × Rᵀṙ
"""
from contextlib import contextmanager

import numpy as np

from .. import charts as _charts
from .. import lgt as _lgt
from ..lgt import circle_tau
from ..errors import InputError
from ..groups import quaternion as _q
from ..groups._vec import cross
from .base import StepFailed, diverged_message, first_nonfinite, norm


class BodySet:
    """Bodies that share (parameterization, group, chart): one batched τ call.
    Rotation-only bodies (spherical joints) form sets of their own (3 local coordinates)."""

    def __init__(self, param, group, chart, body_ids, layout, xoff):
        bodies = [layout.bodies[i] for i in body_ids]
        self.rot_only = bodies[0].rotation_only
        self.lgt = _lgt.RotationLGT(param, chart) if self.rot_only else _lgt.LGT(param, group, chart)
        self.se3 = group == "SE3" and not self.rot_only
        self.chart = _charts.get(chart)
        self.ids = np.array(body_ids)
        self.qidx = np.array([[*b.pos, *b.rot] for b in bodies])
        self.vidx = np.array([b.twist for b in bodies])
        self.wang, self.wlin = self.vidx[:, :3], self.vidx[:, 3:]
        n = 3 if self.rot_only else 6
        self.xidx = xoff[self.ids][:, None] + np.arange(n)

    def base(self, q_k, quats=None):
        rows = q_k[self.qidx]
        if self.rot_only:
            return self.lgt.base(rows) if quats is None else (None, rows, quats)
        return self.lgt.base(rows) if quats is None else (rows[:, :3], rows[:, 3:], quats)


def analysis(model, group, chart, analyze):
    """``analyze(model, group, chart)``, computed once per layout and (group, chart): kept
    on the layout object (repeated runs of one model skip it, and so do models wrapped
    afresh that share their engine model's layout, as a new PinocchioModel per run of one
    robot; a model given a new layout is analyzed again; on the model with its layout when
    the layout takes no attributes), and shared by models of equal layouts. ``analyze``
    must read nothing of the model but its layout."""
    key = (analyze.__qualname__, _key(group), _key(chart))
    lay = model.layout
    # kept on the layout object (models wrapped afresh share their engine model's layout), or
    # on the model with its layout when the layout takes no attributes
    memo = getattr(lay, "__dict__", None)
    on_layout = memo is not None
    if not on_layout:
        memo = getattr(model, "__dict__", None)
    if memo is not None:
        got = memo.get("_lgt_analysis", _EMPTY).get(key)
        if got is not None and (on_layout or got[0] is lay):
            return got if on_layout else got[1]
    shared = key + (_layout_key(lay),)
    a = _SHARED.get(shared)
    if a is None:
        a = analyze(model, group, chart)
        if len(_SHARED) >= _SHARED_MAX:
            _SHARED.pop(next(iter(_SHARED)))
        _SHARED[shared] = a
    if memo is not None:             # (the layout keeps no reference to itself: no cycle)
        memo.setdefault("_lgt_analysis", {})[key] = a if on_layout else (lay, a)
    return a


_EMPTY = {}
#: analyses by layout content, shared by models of equal layouts (oldest dropped first)
_SHARED = {}
_SHARED_MAX = 32


def _layout_key(lay):
    """What an analysis depends on: the layout's bodies (parameterization and indices),
    vector and circle coordinates."""
    return (lay.nq, lay.nv, tuple((b.param.name, b.pos, b.rot, b.twist) for b in lay.bodies),
            lay.vector_q, lay.vector_v, lay.circle_q, lay.circle_v)


def _key(option):
    return option if isinstance(option, str) else tuple(option)


def per_body(option, n, name, check):
    """A group/chart option given once or per body -> list of n values."""
    if isinstance(option, str):
        return [check(option)] * n
    vals = list(option)
    if len(vals) != n:
        raise InputError(f"{name}: got {len(vals)} values for {n} rigid bodies; give one value "
                         "or one per body.")
    return [check(v) for v in vals]


class LocalProblem:
    """Evaluates the local ODE of a model for the step that starts at q_k (numpy
    reference backend; :class:`~lgt_bridge.integrators.compiled.CompiledProblem` runs
    the same operations in compiled kernels)."""

    compiled = False

    def __init__(self, model, group="SE3", chart="exp"):
        self.model = model
        self.layout = model.layout
        self.__dict__.update(analysis(model, group, chart, type(self).analyze))
        self.n_f = 0

    @staticmethod
    def analyze(model, group, chart):
        """What the problem needs from the model's layout, groups and charts alone (the
        model's one-time analysis, shared by every problem of that combination): the body
        sets, index arrays, chart rows and scales."""
        lay = model.layout
        nb = lay.nbodies
        a = {}
        a["groups"] = per_body(group, nb, "group", _lgt.check_group)
        a["charts"] = per_body(chart, nb, "chart", _lgt.check_chart)
        sizes = np.array([3 if b.rotation_only else 6 for b in lay.bodies], int)
        xoff = np.concatenate([[0], np.cumsum(sizes)])
        keys = {}
        for i, b in enumerate(lay.bodies):
            keys.setdefault((b.param.name, a["groups"][i], a["charts"][i], b.rotation_only), []).append(i)
        sets = a["sets"] = [BodySet(lay.bodies[ids[0]].param, g, c, ids, lay, xoff)
                            for (_, g, c, _), ids in keys.items()]
        a["vq"], a["vv"] = np.array(lay.vector_q, int), np.array(lay.vector_v, int)
        a["vx"] = int(xoff[-1]) + np.arange(len(a["vq"]))
        a["cq"], a["cv"] = np.array(lay.circle_q, int).reshape(-1, 2), np.array(lay.circle_v, int)
        a["cx"] = int(xoff[-1]) + len(a["vq"]) + np.arange(len(a["cv"]))
        nX = a["nX"] = int(xoff[-1]) + len(a["vq"]) + len(a["cv"])
        a["nv"] = lay.nv
        # the rotation rows of the bodies whose chart has a domain limit, with 1/limit each
        bounded = [s for s in sets if s.chart.bounded]
        a["chart_rows"] = np.concatenate([s.xidx[:, :3] for s in bounded] or [np.zeros((0, 3), int)])
        a["chart_inv_limit"] = np.concatenate([np.full(len(s.ids), 1.0 / s.chart.limit) for s in bounded]
                                              or [np.zeros(0)])
        a["chart_of_row"] = [s.chart for s in bounded for _ in s.ids]
        a["bounded"] = bool(len(a["chart_rows"]))
        # dψ⁻¹_0 = scale·I: an exp-coordinate increment ΔX is the chart's scale·ΔX to second
        # order (Cayley charts: cay(ΔX/2) = exp(ΔX) + O(|ΔX|³)); rotation rows, on SE(3) also
        # the translation rows (the R³ factor of SO(3)xR³ is additive)
        scale = a["chart_scale"] = np.ones(nX)
        for s in sets:
            scale[s.xidx if s.se3 else s.xidx[:, :3]] = s.chart.scale
        # X's entries in V's layout (``local_index``)
        idx = a["_local_index"] = np.empty(nX, np.int64)
        for s in sets:
            idx[s.xidx] = s.vidx
        idx[a["vx"]], idx[a["cx"]] = a["vv"], a["cv"]
        return a

    # --- per step ---------------------------------------------------------------
    def start(self, q_k, quats=None):
        """Prepare the step from q_k (``quats``: the bodies' quaternions, when known)."""
        self.q_k = q_k
        quats = quats if quats is not None else [None] * len(self.sets)
        self.bases = [s.base(q_k, p) for s, p in zip(self.sets, quats)]

    @property
    def start_quats(self):
        return [b[2] for b in self.bases]

    def snapshot(self):
        """The current step's base (restore with :meth:`restore`)."""
        return self.q_k, self.bases

    def restore(self, snap):
        self.q_k, self.bases = snap

    @contextmanager
    def based_at(self, base):
        """Evaluate within a past step (dense output): its base restored for the ``with``
        block, the current one put back afterwards."""
        snap = self.snapshot()
        self.restore(base)
        try:
            yield self
        finally:
            self.restore(snap)

    def configuration(self, X):
        """q = τ(q_k, X) and the quaternion of every body set."""
        q = self.q_k.copy()
        quats = []
        for s, base in zip(self.sets, self.bases):
            rows, p = s.lgt.tau_pose(base, X[s.xidx])
            q[s.qidx] = rows
            quats.append(p)
        if len(self.vq):
            q[self.vq] = self.q_k[self.vq] + X[self.vx]
        if len(self.cv):
            q[self.cq] = circle_tau(self.q_k[self.cq], X[self.cx])
        return q, quats

    def model_velocity(self, W, quats):
        """V = W with the linear velocity of SE(3) bodies rotated to the inertial frame."""
        V = W.copy()
        for s, p in zip(self.sets, quats):
            if s.se3:
                V[s.wlin] = _q._rotate(p, W[s.wlin])
        return V

    def group_velocity(self, V, quats):
        W = V.copy()
        for s, p in zip(self.sets, quats):
            if s.se3:
                W[s.wlin] = _q._rotate(_q._conj(p), V[s.wlin])
        return W

    def group_acceleration(self, Vdot, W, quats):
        """Ẇ from V̇: on SE(3) d/dt(Rᵀṙ) = Rᵀr̈ - ω × Rᵀṙ."""
        Wd = Vdot.copy()
        for s, p in zip(self.sets, quats):
            if s.se3:
                Wd[s.wlin] = _q._rotate(_q._conj(p), Vdot[s.wlin]) - cross(W[s.wang], W[s.wlin])
        return Wd

    def model_acceleration(self, Wdot, W, quats):
        """V̇ from Ẇ (the inverse of group_acceleration)."""
        Vd = Wdot.copy()
        for s, p in zip(self.sets, quats):
            if s.se3:
                Vd[s.wlin] = _q._rotate(p, Wdot[s.wlin] + cross(W[s.wang], W[s.wlin]))
        return Vd

    def kinematics(self, X, W):
        """Ẋ = dψ⁻¹_{-X}(W) per body; v for vector coordinates."""
        Xd = np.empty(self.nX)
        for s in self.sets:
            Xd[s.xidx] = s.lgt.rates(X[s.xidx], W[s.vidx])
        if len(self.vq):
            Xd[self.vx] = W[self.vv]
        if len(self.cv):
            Xd[self.cx] = W[self.cv]
        return Xd

    def rhs(self, X, W, t, at_start=False):
        """(Ẋ, Ẇ) of the local ODE, and the q, V it was evaluated at.
        ``at_start``: X = 0, where q = q_k and Ẋ = dψ⁻¹_0(W) = chart_scale · W."""
        if at_start:
            q, quats = self.q_k, self.start_quats
            Xd = self.chart_scale * self.to_local(W)
        else:
            q, quats = self.configuration(X)
            Xd = self.kinematics(X, W)
        V = self.model_velocity(W, quats)
        Vd = self.model.f(q, V, t)
        self.n_f += 1
        return Xd, self.group_acceleration(Vd, W, quats), q, V

    # --- the stage API of the explicit steppers (same on both backends) ---------
    def stage(self, KX, KW, i, a, h, W0, t, ts, climit=np.inf):
        """Stage i of a step from t: X = h Σ_{j<i} a_j KX_j, W = W0 + h Σ a_j KW_j,
        KX[i] = dψ⁻¹_{-X}(W), KW[i] = Ẇ from f at time ts. Returns 0.0, or the largest
        chart usage |x|/limit (f not called) when it exceeds ``climit``; StepFailed on NaN/inf.
        KW[i] is complete after the next ``stage``, ``end`` or ``flush`` call (the compiled
        backend converts it in the same kernel call as the next stage's state)."""
        if i == 0:
            X, W = np.zeros(self.nX), W0
        else:
            X = h * (a[:i] @ KX[:i])
            W = W0 + h * (a[:i] @ KW[:i])
            c = self.chart_usage(X)
            if c > climit:
                self._stage_X = X
                return c
        KX[i], KW[i], q, V = self.rhs(X, W, ts, at_start=i == 0)
        if not (np.isfinite(KW[i]).all() and np.isfinite(KX[i]).all()):
            self.stage_failed(KX, KW, i, t, ts, q, V, h, W0, W)
        return 0.0

    def flush(self, KX, KW):
        """Complete the last stage's KW (the compiled backend defers it; here a no-op)."""

    def start_rates(self, KX, W0):
        """KX[0] = dψ⁻¹_0(W0) (the first stage's kinematics, no f)."""
        KX[0] = self.chart_scale * self.to_local(W0)

    def end(self, KX, KW, b, h, W0):
        """(X1, W1, q1, V1, quats) at the end of a step with weights b (fresh arrays)."""
        X1 = h * (b @ KX[:len(b)])
        W1 = W0 + h * (b @ KW[:len(b)])
        q1, quats = self.configuration(X1)
        return X1, W1, q1, self.model_velocity(W1, quats), quats

    def run_stages(self, KX, KW, A, c, i0, h, t, W0, climit=np.inf):
        """Stages i0, ..., len(c) - 1 of the step from t (weights A[i], times t + c[i] h), as
        :meth:`stage` for each. Returns 0.0, or the chart usage of the first stage beyond
        ``climit`` (its f not called)."""
        for i in range(i0, len(c)):
            cm = self.stage(KX, KW, i, A[i], h, W0, t, t + c[i] * h, climit)
            if cm:
                return cm
        return 0.0

    def end_step(self, KX, KW, T, h, W0, rtol, atol):
        """The end of an embedded pair's step: (X1, W1, q1, V1, quats) with the weights b = T[0]
        (as :meth:`end`), the error sums (s5, s3) of e5 = T[1], e3 = T[2] (:meth:`error_sums`),
        the stiffness test's (num, den) = the error sums of T[3], T[4] with unit scale (0, 0
        when T has 3 rows), and sq = |q1|² + |V1|² (not finite when q1 or V1 is not)."""
        X1, W1, q1, V1, quats = self.end(KX, KW, T[0], h, W0)
        s5, s3 = self.error_sums(KX, KW, T[1], T[2], X1, W1, W0, rtol, atol)
        num = den = 0.0
        if len(T) > 3:
            num, den = self.error_sums(KX, KW, T[3], T[4], KX[0], KW[0], KW[0], 0.0, 1.0)
        return X1, W1, q1, V1, quats, s5, s3, num, den, float(q1.dot(q1) + V1.dot(V1))

    def state_at(self, X, W):
        """(q, V) at local state (X, W) of the current step."""
        q, quats = self.configuration(X)
        return q, self.model_velocity(W, quats)

    def dense_states(self, w, FX, FW, W0, base):
        """Rows of (Q, V): (q, V) at the local states X = w[r] @ FX, W = W0 + w[r] @ FW (a
        dense output's polynomials with the weights ``w`` of each time) of the step whose
        base is ``base`` (:meth:`snapshot`). The reference evaluates them one by one with
        :meth:`state_at`; the compiled backend in one kernel call."""
        X, W = w @ FX, W0 + w @ FW
        Q, V = np.empty((len(X), self.layout.nq)), np.empty((len(X), self.nv))
        with self.based_at(base):
            for r in range(len(X)):
                Q[r], V[r] = self.state_at(X[r], W[r])
        return Q, V

    #: a stage whose velocity moved this many times farther from the step's start than
    #: the start's own acceleration predicts (h |Ẇ_0|) is an explicit step blowing up
    BLOWUP = 10.0

    def stage_failed(self, KX, KW, i, t, ts, q, V, h, W0, W):
        """Raise StepFailed for stage i whose state (q, V) or derivative (KX[i], KW[i]) is not
        finite. A non-finite stage state, or a model that returned NaN/inf at a stage whose
        velocity had already run away from the step's start (by more than BLOWUP times what
        the start's acceleration predicts), is a diverging step; only a model that returned
        NaN/inf at a state near the step's start is reported as the model's failure."""
        for kind, arr in (("q", q), ("V", V)):
            if not np.isfinite(arr).all():
                raise StepFailed(diverged_message(
                    t, f"the stage at t = {ts:.9g} has non-finite {kind} in "
                       f"{first_nonfinite(self.layout, kind, arr)}", h), diverged=True)
        bad = ~(np.isfinite(KW[i]).all() and np.isfinite(KX[i]).all())
        where = first_nonfinite(self.layout, "V", KW[i]) if not np.isfinite(KW[i]).all() else "the kinematics"
        if bad and i > 0:
            dW, pred = norm(W - W0), h * norm(KW[0])
            if dW > self.BLOWUP * pred:
                raise StepFailed(diverged_message(
                    t, f"within the step the velocity ran away from |V| = {norm(W0):.3g} by {dW:.3g} "
                       f"(the start's acceleration predicts {pred:.3g}), and at stage time {ts:.9g} "
                       f"the acceleration of {where} overflowed to NaN/inf", h), diverged=True)
        raise StepFailed(f"non-finite acceleration of {where} in the step from t = {t:.9g} "
                         f"(stage time {ts:.9g}): the model returned NaN/inf for a finite state "
                         f"near the step's start (|V| = {norm(V):.3g}); check the model's f there "
                         "(e.g. a division by zero, a singular configuration). The result keeps "
                         "every step before it.")

    def rates(self, X, W, t):
        """[Ẋ, Ẇ] of the local ODE at (X, W) as one vector (the implicit methods' F)."""
        Xd, Wd, _, _ = self.rhs(X, W, t)
        return np.concatenate([Xd, Wd])

    # --- generalized-α (the compiled backend fuses these into one kernel call each) -----
    def ga_state(self, Wd, sv, sp, Wa, dXa, to_local):
        """(q, V, quats, W) at W = Wa + sv Ẇ, X = dXa + sp Ẇ[to_local] (generalized-α's state,
        affine in its unknowns Ẇ)."""
        W = Wa + sv * Wd
        q, quats = self.configuration(dXa + sp * Wd[to_local])
        return q, self.model_velocity(W, quats), quats, W

    def ga_affine(self, W, Wd, a, af, am, h, g, b, k, to_local):
        """Generalized-α's step constants (a0, Wa, dXa, sp): a0 = (α_f Ẇ - α_m a)/(1 - α_m),
        Wa = W + h(1 - γ) a + hγ a0, dXa = S (hW + h²(½ - β) a + h²β a0)[to_local],
        sp = h²βk S (S: the chart scale)."""
        a0 = (af * Wd - am * a) / (1 - am)
        d0 = h * W + h * h * (0.5 - b) * a + h * h * b * a0
        scale = self.chart_scale
        return a0, W + h * (1 - g) * a + h * g * a0, scale * d0[to_local], h * h * b * k * scale

    def error_sums(self, KX, KW, e5, e3, X1, W1, W0, rtol, atol):
        """Σ (Σ_i e5_i K_i / sc)² and the same with e3 over y = (X, W), sc = atol +
        rtol·max(|y_k|, |y_{k+1}|) (X_k = 0): the embedded pairs' error sums."""
        ns = len(e5)
        sc = np.concatenate([atol + rtol * np.abs(X1), atol + rtol * np.maximum(np.abs(W0), np.abs(W1))])
        err5 = np.concatenate([e5 @ KX[:ns], e5 @ KW[:ns]]) / sc
        err3 = np.concatenate([e3 @ KX[:ns], e3 @ KW[:ns]]) / sc
        return float(err5 @ err5), float(err3 @ err3)

    def quiet(self):
        """A context in which the library's own arithmetic on a diverging step does not warn
        (non-finite values are reported as StepError naming the body instead)."""
        return np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore")

    def ga_residual(self, Vd, Wd, r, W, quats):
        """r = Ẇ - Ẇ(V̇) (in place); returns Σ r² (not finite when r is not)."""
        r[:] = Wd - self.group_acceleration(np.asarray(Vd, dtype=float), W, quats)
        if not np.isfinite(r).all():
            return np.inf
        with np.errstate(over="ignore"):
            return float(r.dot(r))

    def to_local(self, d):
        """A vector in V's layout as X's layout (bodies: the same 6 numbers; vector part: rates)."""
        X = np.empty(self.nX)
        for s in self.sets:
            X[s.xidx] = d[s.vidx]
        if len(self.vq):
            X[self.vx] = d[self.vv]
        if len(self.cv):
            X[self.cx] = d[self.cv]
        return X

    @property
    def local_index(self):
        """X's entries in V's layout as int64 indices: X = d[local_index] is to_local(d)."""
        idx = getattr(self, "_local_index", None)
        if idx is None:
            idx = self._local_index = np.rint(self.to_local(np.arange(self.nv, dtype=float))).astype(np.int64)
        return idx

    def chart_usage(self, X):
        """Largest |x|/limit among bounded-chart bodies (> 1: out of the chart's domain)."""
        if not self.bounded:
            return 0.0
        return float((np.sqrt((X[self.chart_rows] ** 2).sum(axis=1)) * self.chart_inv_limit).max())

    def chart_overrun(self, X=None):
        """(chart, angle, limit angle) in degrees of the body that goes farthest beyond its
        chart's domain at X (default: the last stage that did)."""
        X = self._stage_X if X is None else X
        n = np.sqrt((np.asarray(X)[self.chart_rows] ** 2).sum(axis=1))
        k = int(np.argmax(n * self.chart_inv_limit))
        ch = self.chart_of_row[k]
        return ch, float(np.degrees(ch.angle(n[k]))), float(np.degrees(ch.max_angle))
