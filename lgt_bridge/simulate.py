"""``simulate``: run a model on a bridge integrator and collect the result."""
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from .errors import ChartDomainError, InputError, StepError
from .integrators import METHODS
from .integrators.base import StepFailed
from .integrators.constraints import Projector
from .integrators.genalpha import GenAlpha
from .integrators.local import LocalProblem
from .integrators.rkmk import AdaptiveRK, FixedRK
from .integrators.tableaux import ADAPTIVE, FIXED
from .integrators.vector_space import ScipyStepper

_SCIPY = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")


@dataclass
class SimulationResult:
    """Output of :func:`simulate`: ``t`` (n,), ``q`` (n, nq) in the engine's own
    coordinates, ``V`` (n, nv) as (ω body, ṙ inertial) per body, ``success``,
    ``message`` and ``stats`` (n_steps, n_f, n_rejected, n_newton, wall_s, and
    the constraint residuals before/after projection where there are constraints)."""

    t: np.ndarray
    q: np.ndarray
    V: np.ndarray
    success: bool
    message: str
    stats: dict = field(default_factory=dict)
    method: str = ""
    group: object = ""
    chart: object = ""

    def raise_for_status(self):
        if not self.success:
            raise StepError(self.message)
        return self


def _check_inputs(model, t_span, method, dt, rtol, atol, q0, V0, t_eval, max_steps):
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError):
        raise InputError(f"t_span: expected (t0, t_end), got {t_span!r}.") from None
    if not (np.isfinite(t0) and np.isfinite(t1)):
        raise InputError(f"t_span: ({t0}, {t1}) must be finite.")
    if t1 <= t0:
        raise InputError(f"t_span: t_end = {t1} must be greater than t0 = {t0}; "
                         "lgt_bridge integrates forward in time.")
    if not (method in METHODS or (isinstance(method, str) and method.startswith("scipy:"))):
        raise InputError(f"unknown method {method!r}; use one of {list(METHODS)} or "
                         f"'scipy:<Name>' with Name in {list(_SCIPY)}.")
    if method.startswith("scipy:") and method[6:] not in _SCIPY:
        raise InputError(f"unknown scipy method {method[6:]!r}; use one of {list(_SCIPY)}.")
    if dt is not None and not (np.isfinite(dt) and dt > 0):
        raise InputError(f"dt = {dt} must be a positive finite step size.")
    if dt is None and (method in FIXED or method == "genalpha"):
        raise InputError(f"method {method!r} takes fixed steps: pass dt (e.g. dt=1e-3).")
    for name, v in (("rtol", rtol), ("atol", atol)):
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name} = {v} must be positive.")
    if not int(max_steps) > 0:
        raise InputError(f"max_steps = {max_steps} must be a positive integer.")
    lay = model.layout
    q0 = np.array(model.q0 if q0 is None else q0, float)
    V0 = np.array(model.V0 if V0 is None else V0, float)
    if q0.shape != (lay.nq,):
        raise InputError(f"q0: got shape {q0.shape}, the model has {lay.nq} coordinates.")
    if V0.shape != (lay.nv,):
        raise InputError(f"V0: got shape {V0.shape}, the model has {lay.nv} velocities.")
    for name, arr, kind in (("q0", q0, "q"), ("V0", V0, "V")):
        if not np.isfinite(arr).all():
            i = int(np.flatnonzero(~np.isfinite(arr))[0])
            raise InputError(f"{name}: entry {i} ({lay.owner(kind, i)}) is {arr[i]}; "
                             "give a finite initial state.")
    for k, b in enumerate(lay.bodies):
        b.param.validate(q0[[*b.pos, *b.rot]], f"q0 of body {k}" + (f" ({b.name})" if b.name else ""))
    if t_eval is not None:
        t_eval = np.asarray(t_eval, float).ravel()
        if not np.isfinite(t_eval).all() or np.any(np.diff(t_eval) <= 0):
            raise InputError("t_eval must be finite and strictly increasing.")
        if t_eval[0] < t0 or t_eval[-1] > t1:
            raise InputError(f"t_eval must lie within t_span [{t0}, {t1}].")
    return t0, t1, q0, V0, t_eval


class _Progress:
    def __init__(self, on, t0, t1):
        self.on, self.t0, self.t1 = on, t0, t1
        self.last = 0.0

    def __call__(self, t, n, final=False):
        if not self.on:
            return
        now = time.perf_counter()
        if final or now - self.last > 0.25:
            self.last = now
            frac = (t - self.t0) / (self.t1 - self.t0)
            bar = "#" * int(30 * frac)
            sys.stderr.write(f"\r[{bar:<30}] {100 * frac:5.1f}%  t = {t:.6g}  steps = {n}")
            if final:
                sys.stderr.write("\n")
            sys.stderr.flush()


def simulate(model, t_span, *, method="rkmk4", group="SE3", chart="exp", dt=None, rtol=1e-6,
             atol=1e-8, q0=None, V0=None, t_eval=None, progress=False, max_steps=1_000_000,
             project=True, rho_inf=0.9, newton_tol=1e-10):
    """Integrate ``model`` over ``t_span`` with a Lie group method through τ.

    method: "euler", "rkmk2", "rkmk4" (fixed dt), "dopri5" (adaptive: rtol/atol,
    dt = first step), "scipy:<Name>" (scipy solver inside macro steps of length dt),
    "genalpha" (fixed dt, index-3 constraints, numerical damping ``rho_inf``).
    group: "SE3" or "SO3xR3"; chart: "exp" or "cay" (one value or one per body).
    Constrained models with explicit methods are projected onto g = 0 and A V = 0
    after every step (``project=False`` turns this off).
    t_eval: output times (steps land on them); default: every step.
    """
    t0, t1, q0, V0, t_eval = _check_inputs(model, t_span, method, dt, rtol, atol, q0, V0, t_eval,
                                           max_steps)
    prob = LocalProblem(model, group, chart)
    explicit = method != "genalpha"
    projector = Projector(model) if (explicit and project and model.n_constraints) else None
    if method in FIXED:
        stepper = FixedRK(prob, FIXED[method], projector)
    elif method in ADAPTIVE:
        stepper = AdaptiveRK(prob, ADAPTIVE[method], rtol, atol, projector, first_step=dt)
    elif method == "genalpha":
        stepper = GenAlpha(prob, rho_inf=rho_inf, newton_tol=newton_tol)
    else:
        stepper = ScipyStepper(prob, method[6:], rtol, atol, projector)
        if dt is None:
            wmax = max([np.abs(V0[list(b.twist[:3])]).max() for b in model.layout.bodies] + [1e-12])
            dt = min((t1 - t0) / 10, 0.5 / wmax)
    stepper.set_state(q0, V0)
    wall0 = time.perf_counter()
    h = dt if dt is not None else stepper.initial_step(t0)
    targets = list(t_eval) if t_eval is not None else [t1]
    if targets[-1] < t1:
        targets.append(t1)
    record_all = t_eval is None
    ts, qs, Vs = [], [], []
    if record_all or (t_eval is not None and t_eval[0] == t0):
        ts.append(t0), qs.append(q0.copy()), Vs.append(V0.copy())
    if t_eval is not None and t_eval[0] == t0:
        targets = targets[1:]
    t, n_steps, success, message = t0, 0, True, "reached the end of t_span"
    bar = _Progress(progress, t0, t1)
    ti = 0
    while ti < len(targets):
        target = targets[ti]
        h_try = min(h, target - t)
        hit = target - (t + h_try) <= 1e-12 * max(1.0, abs(target))
        if hit:
            h_try = target - t
        try:
            accepted, h_new = stepper.attempt(t, h_try)
        except StepFailed as exc:
            if exc.error is ChartDomainError:
                err = ChartDomainError(str(exc))
                err.result = _result(ts, qs, Vs, False, str(exc), stepper, prob, projector, n_steps,
                                     wall0, method, group, chart, model)
                raise err from None
            success, message = False, str(exc)
            break
        if accepted:
            n_steps += 1
            t = target if hit else t + h_try
            model.write_back(stepper.q, stepper.V, t)
            if hit:
                ti += 1
            if record_all or hit:
                if record_all or t_eval is None or ti <= len(t_eval):
                    ts.append(t), qs.append(stepper.q.copy()), Vs.append(stepper.V.copy())
            if stepper.adaptive:
                h = max(h_new, h) if hit and h_new < h else h_new
            elif h_new is not None:
                h = h_new
            else:
                h = dt
            bar(t, n_steps)
        else:
            h = h_new
            if h < 1e-14 * max(1.0, abs(t)):
                success, message = False, f"step size underflow at t = {t:.9g} (h = {h:.3g})"
                break
        if n_steps >= max_steps and ti < len(targets):
            success, message = False, f"max_steps = {max_steps} reached at t = {t:.9g}"
            break
    if t_eval is not None and len(ts) > len(t_eval):
        ts, qs, Vs = ts[:len(t_eval)], qs[:len(t_eval)], Vs[:len(t_eval)]
    bar(t, n_steps, final=True)
    if not success:
        model.write_back(stepper.q, stepper.V, t)
    return _result(ts, qs, Vs, success, message, stepper, prob, projector, n_steps, wall0,
                   method, group, chart, model)


def _result(ts, qs, Vs, success, message, stepper, prob, projector, n_steps, wall0, method, group,
            chart, model):
    stats = dict(n_steps=n_steps, n_f=prob.n_f, n_rejected=stepper.n_rejected,
                 n_newton=stepper.n_newton, wall_s=time.perf_counter() - wall0)
    if projector is not None:
        stats.update(constraint_before_projection=projector.max_before,
                     constraint_after_projection=projector.max_after,
                     velocity_constraint_after_projection=projector.max_vel_after,
                     projection_iterations=projector.iterations)
    elif model.n_constraints and qs:
        stats["constraint_residual"] = float(max(np.abs(model.constraints(q)).max() for q in qs))
    if hasattr(stepper, "n_jacobians"):
        stats["n_jacobians"] = stepper.n_jacobians
    nq, nv = model.layout.nq, model.layout.nv
    return SimulationResult(np.array(ts), np.array(qs).reshape(-1, nq), np.array(Vs).reshape(-1, nv),
                            success, message, stats, method, group, chart)
