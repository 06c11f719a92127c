"""What the adapter keeps of one ``pinocchio.Model`` object while it is unchanged, for
models wrapped afresh for every run (a user's loop of ``PinocchioModel(model)`` and
``simulate``): its :class:`~.joints.Joints`, the configurations whose mass check passed,
the checked initial states and a few spare ``pinocchio.Data``."""
import numpy as np

from lgt_bridge.errors import InputError

from .joints import Joints

#: what is known of a pinocchio.Model object, id -> dict (``model_memo``), the newest last
_MEMO = {}
_MEMO_MAX = 16
#: spare Data kept per model, and checked initial states
_DATA_MAX = 4
_STATES_MAX = 16


def model_memo(pin, model):
    """What the adapter has computed of one ``pinocchio.Model`` object while it is unchanged: a
    dict with ``joints`` (its :class:`Joints`, made here), ``mass_ok`` (the configurations
    whose mass check passed), ``states`` (:func:`initial_state`) and ``data`` (spare Data,
    :func:`lend_data`). Unchanged means equal to a copy taken when the entry was made
    (Pinocchio's own ``Model ==``, a few µs: joints, names, inertias, placements, armature,
    limits); a model changed since gets a new entry, so everything is computed and checked
    again."""
    got = _MEMO.get(id(model))
    if got is not None and got["model"] is model and model == got["copy"]:
        return got
    joints = Joints(model)               # InputError for a joint it cannot step: nothing kept
    got = {"model": model, "copy": pin.Model(model), "joints": joints, "mass_ok": set(), "states": {},
           "data": []}
    _MEMO.pop(id(model), None)
    if len(_MEMO) >= _MEMO_MAX:
        _MEMO.pop(next(iter(_MEMO)))
    _MEMO[id(model)] = got
    return got


def lend_data(pin, memo, owner, constraints=None):
    """A ``pinocchio.Data`` of the memo's model for ``owner`` alone: a spare one given back
    by an owner since collected, else a new one (``pin.Data(model)``: the same Data as
    ``createData()`` in about half the time). Data is scratch every algorithm overwrites
    before reading; an owner with constraints keeps its own (constraintDynamics carries
    state in it) and gives nothing back. Two live owners never share one. The owner gives
    its Data back by calling :func:`give_back` when it is freed (its ``__del__``: a
    ``weakref.finalize`` per owner costs 4-6 µs of a call's set-up)."""
    pool = memo["data"]
    data = pool.pop() if pool else pin.Data(memo["model"])
    if constraints is None or (isinstance(constraints, (list, tuple)) and not constraints):
        owner._lent = (pool, data)
    return data


def give_back(owner):
    """``owner``'s lent Data back to its pool (once; nothing for an owner that has none)."""
    lent = owner.__dict__.pop("_lent", None)
    if lent is not None:
        pool, data = lent
        if len(pool) < _DATA_MAX and not any(d is data for d in pool):
            pool.append(data)


def _checked_state(joints, pin, model, q0, v0):
    """(q0, v0) as finite float vectors of sizes (nq, nv), valid coordinates (default: neutral, 0)."""
    q0 = pin.neutral(model) if q0 is None else np.asarray(q0, float)
    v0 = np.zeros(model.nv) if v0 is None else np.asarray(v0, float)
    if q0.shape != (model.nq,) or v0.shape != (model.nv,):
        raise InputError(f"q0/v0: expected sizes nq = {model.nq}, nv = {model.nv}; got "
                         f"{q0.shape}, {v0.shape}.")
    for name, arr in (("q0", q0), ("v0", v0)):
        if not np.isfinite(arr).all():
            i = int(np.flatnonzero(~np.isfinite(arr))[0])
            kind = "q" if name == "q0" else "v"
            raise InputError(f"{name}: entry {i} ({joints.joint_of(kind, i)}) is {arr[i]}; give a "
                             "finite initial state.")
    joints.validate(q0)
    return q0, v0


def initial_state(memo, pin, model, q0, v0):
    """(q0, v0, V0): the initial state checked (finite, valid coordinates; default neutral,
    0) and its twist V0, as new arrays. A state met before with the memo's model is taken
    from the memo (keyed by its bytes: the checks and the twist depend on the values only)."""
    joints = memo["joints"]
    key = None
    if isinstance(q0, np.ndarray) and isinstance(v0, np.ndarray) and q0.dtype == v0.dtype == np.float64:
        key = (q0.shape, v0.shape, q0.tobytes(), v0.tobytes())
        got = memo["states"].get(key)
        if got is not None:
            return got[0].copy(), got[1].copy(), got[2].copy()
    q0, v0 = _checked_state(joints, pin, model, q0, v0)
    q0, v0 = np.array(q0), np.array(v0)
    V0 = joints.twist_from_v(q0, v0)
    if key is not None and len(memo["states"]) < _STATES_MAX:
        memo["states"][key] = (q0.copy(), v0.copy(), V0.copy())
    return q0, v0, V0
