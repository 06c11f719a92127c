"""The stepper behind a method name (:func:`make_stepper`), and finished steppers kept for the
next run of a model of the same kind.

A user's script often wraps its engine model afresh for every run (``simulate(PinocchioModel(
model), ...)`` in a loop, or an Exudyn system built anew): each run then built its local
problem, its stepper and the compiled step loop again, about 15 µs of a small robot's call.
An embedded pair's stepper on the compiled backend (dopri5, dop853 without projection) made
for a run of :func:`~lgt_bridge.simulate` is given back when that run ends (:func:`release`;
``simulate`` owns it, nothing of it is returned) and kept, by its layout object and options,
for the next :func:`make_stepper` of that kind. Taken again, it is first put back exactly as
it was made: every attribute of the stepper, its problem, step-size controller and step loop
restored from a copy taken when it was built, their arrays zeroed as new ones are (the loop
array copied from the one it was made with), and the new model's f bound to the problem.
Only the layout, the groups, charts, method and options (what the stepper was built from)
are shared; everything of the model itself (f, masses, torques) is bound afresh, so a changed
model never meets what an earlier one left.
"""
from .. import backend as _backend
from ..lgt import DEFAULT_GROUP
from . import registry as _registry
from .constraints import Projector
from .problem import make_problem

#: finished steppers by (layout id, method, groups, charts, options, engine bodies) -> (layout,
#: stepper); the oldest dropped first
_POOL = {}
POOL_MAX = 16


def make_stepper(model, method, group=DEFAULT_GROUP, chart="exp", *, dt=None, rtol=1e-6, atol=1e-8,
                 project=True, rho_inf=0.9, newton_tol=1e-10, span=None, fixed_steps=False):
    """The stepper behind a method name (the registry's builder), with its local problem
    and projector. Returns (stepper, dt): dt is the (macro) step to use (None: adaptive)."""
    spec = _registry.get(method)
    key = _key(model, spec, group, chart, dt, rtol, atol, project, fixed_steps)
    if key is not None:
        got = _POOL.pop(key, None)
        if got is not None and got[0] is model.layout:
            stepper = _restored(got[1], model)
            return stepper, stepper.step_size(dt, span)
    prob = make_problem(model, group, chart)
    projector = Projector(model) if (spec.projects and project and model.n_constraints) else None
    stepper = spec.build(prob, dt=dt, rtol=rtol, atol=atol, projector=projector, rho_inf=rho_inf,
                         newton_tol=newton_tol, fixed_steps=fixed_steps)
    if key is not None:
        _keep_fresh(stepper, key, model.layout)
    return stepper, stepper.step_size(dt, span)


def _key(model, spec, group, chart, dt, rtol, atol, project, fixed_steps):
    """The pool's key of a run (None: its stepper is not kept): an embedded pair on the compiled
    backend, not projected, of a model without post-step or mode-switch hooks."""
    if (spec.name not in ("dopri5", "dop853") or fixed_steps or (project and model.n_constraints)
            or getattr(model, "post_step", None) is not None or getattr(model, "switch_mode", None) is not None
            or not _backend.compiled(None)):
        return None
    eng = getattr(model, "engine_velocity", None)
    bodies = None if eng is None else tuple(int(b) for b in eng.bodies)
    try:
        key = (id(model.layout), spec.name, _hashable(group), _hashable(chart), dt, rtol, atol, bodies)
        hash(key)
    except TypeError:
        return None
    return key


def _hashable(option):
    return option if isinstance(option, str) else tuple(option)


def _keep_fresh(st, key, layout):
    """Give a just-built stepper its step loop and a copy of its state, for :func:`release`."""
    from .compiled import CompiledProblem
    from .compiled_loop import Loop
    from .rkmk import AdaptiveRK
    if type(st) is not AdaptiveRK or not isinstance(st.prob, CompiledProblem):
        return
    loop = st._compiled_loop = Loop(st)
    prob = st.prob
    pd = dict(prob.__dict__)
    pd["model"] = pd["_fs"] = None          # (bound again when taken: no model kept alive)
    st._fresh = (key, layout, dict(st.__dict__), pd, dict(st.control.__dict__), dict(loop.__dict__),
                 loop.L.copy())


def _restored(st, model):
    """A kept stepper as it was built, on ``model``."""
    fresh = st._fresh
    _, _, sd, pd, cd, ld, L0 = fresh
    prob, ctl, loop = sd["prob"], sd["control"], sd["_compiled_loop"]
    for obj, d in ((st, sd), (prob, pd), (ctl, cd), (loop, ld)):
        obj.__dict__.clear()
        obj.__dict__.update(d)
    st._fresh = fresh
    loop.L[:] = L0
    prob.work.fill(0.0)
    prob._Xd.fill(0.0)
    prob.bind(model)
    return st


def release(stepper):
    """A run's stepper is finished with (:func:`~lgt_bridge.simulate` owns it and returns
    nothing of it): keep it for the next :func:`make_stepper` of its kind."""
    fresh = getattr(stepper, "_fresh", None)
    if fresh is None:
        return
    prob = stepper.prob
    prob.model = prob._fs = None              # no model kept alive by the pool
    if len(_POOL) >= POOL_MAX:
        _POOL.pop(next(iter(_POOL)), None)
    _POOL[fresh[0]] = (fresh[1], stepper)
