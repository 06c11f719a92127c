"""f(q, V, t) of a :class:`lgt_pinocchio.PinocchioModel` on either backend: one Pinocchio ABA
(constraintDynamics with constraints) between the V -> v and a -> V̇ conversions.

* :func:`f_numpy`: the readable reference, on :class:`lgt_pinocchio.joints.Joints`;
* :func:`build_f`: the compiled backend's f, a closure over the model's constants (no attribute
  look-ups per call) around two kernel calls (:mod:`lgt_pinocchio.kernels`) over the model's
  preallocated work array, and, on a model whose only converted joints are free-flyers, the
  same f in Pinocchio's own velocities (the model's ``engine_velocity``: the compiled stages
  convert in their kernel and call Pinocchio directly).
"""
from collections import namedtuple

from functools import partial

import numpy as np

from lgt_bridge.errors import InputError

_F64 = np.dtype(np.float64)
_Sizes = namedtuple("_Sizes", "nq nv")


def check_sizes(m, q, V):
    """InputError unless q and V have the model's sizes."""
    if np.shape(q) != (m.nq,) or np.shape(V) != (m.nv,):
        raise InputError(f"PinocchioModel.f: q has shape {np.shape(q)} and V {np.shape(V)}; this model needs "
                         f"q of shape ({m.nq},) and V of shape ({m.nv},) (the twist layout of "
                         "model.layout).")


def f_numpy(m, q, V, t):
    """f on the numpy backend (a new array)."""
    check_sizes(m, q, V)
    pin = m.pin
    v = m.joints.v_from_twist(q, V)
    tau = m.loads.torques(t, q, v)
    if m.cons.n_all:
        if m.loads.fext is not None:           # constraintDynamics takes no fext: Jᵀf as torques
            tau = tau + m.loads.joint_torques(t, q, v)
        a = m.cons.dynamics(q, v, tau)
    elif m.loads.fext is None:
        a = pin.aba(m.model, m.data, q, v, tau)
    else:
        a = pin.aba(m.model, m.data, q, v, tau, m.loads.forces(t, q, v))
    return m.joints.vdot_from_a(q, v, a)


def compiled_f(m):
    """(f, f_engine) of model ``m`` on the compiled backend (:func:`build_f`), after its set-up:
    the kernels (imported on first use: they import numba) as ``m._kernels``, the joint table
    ``m._jt`` (the joints' constant: made once per pinocchio.Model, kept in its memo) and the
    kernels' work array ``m._kW`` with v's view ``m._kv``."""
    global _KERNELS
    if _KERNELS is None:
        from . import kernels as _KERNELS
    kernels = m._kernels = _KERNELS
    jt = m._memo.get("joint_table")
    if jt is None:
        jt = m._memo["joint_table"] = kernels.joint_table(m.joints.roots, m.joints.planars, m.joints.zyx)
    m._jt = jt
    m._kW, m._kv = kernels.work_array(jt, m.nv)
    return build_f(m, kernels)


_KERNELS = None


def build_f(m, kernels):
    """(f, f_engine) of model ``m`` on the compiled backend. f: V -> v by one kernel call into
    the work array, Pinocchio, then a -> V̇ in place by a second (ABA's a is a new array, so
    it is returned as V̇). f_engine(q, v, t): Pinocchio's a at its own (q, v), None unless
    the model has free-flyers and no planar or spherical-ZYX joint (whose conversions the
    stage kernels do not make)."""
    v_from_twist, vdot_from_a = kernels.v_from_twist, kernels.vdot_from_a_unchecked
    pin, model, data = m.pin, m.model, m.data
    # the closure holds no reference to m (it becomes m.f: a cycle would keep m and its
    # Pinocchio Data alive until the garbage collector runs, models built per call piling up)
    sizes = _Sizes(m.nq, m.nv)
    jt, W = m._jt, m._kW
    v_buf = W[m._kv]
    has_roots = m.joints.convert
    tau_c = np.zeros(m.nv) if m.loads.tau is None else m.loads.tau
    tau_call = callable(tau_c)
    nv_shape = (m.nv,)
    checked_tau, forces = m.loads.checked_tau, m.loads.forces
    ndarray, F64, contiguous = np.ndarray, _F64, np.ascontiguousarray
    if m.cons.n_all:
        cms, cds, prox = m.cons.cms, m.cons.cds, m.cons.prox
        dynamics = pin.constraintDynamics
        if m.loads.fext is None:
            def engine(q, v, tau, t):
                return dynamics(model, data, q, v, tau, cms, cds, prox)
        else:
            joint_torques = m.loads.joint_torques

            def engine(q, v, tau, t):              # constraintDynamics takes no fext: Jᵀf as torques
                return dynamics(model, data, q, v, tau + joint_torques(t, q, v), cms, cds, prox)
    elif m.loads.fext is not None:
        aba = pin.aba

        def engine(q, v, tau, t):
            return aba(model, data, q, v, tau, forces(t, q, v))
    else:
        engine = None
        aba = pin.aba

    if engine is None and not tau_call:
        def f_engine(q, v, t):                 # (free motion, constant torques: the stage loop's f)
            return aba(model, data, q, v, tau_c)
        # the same without a Python frame: aba(model, data)(q, v, tau_c), for the compiled step loop
        f_engine.time_free_call = (partial(aba, model, data), tau_c)
    else:
        def f_engine(q, v, t):
            tau = tau_c
            if tau_call:
                tau = tau(t, q, v)
                if type(tau) is not ndarray or tau.dtype is not F64 or tau.shape != nv_shape:
                    tau = checked_tau(tau)
            return aba(model, data, q, v, tau) if engine is None else engine(q, v, tau, t)
    # Pinocchio's a: a float64 vector of nv entries (the compiled step loop need not check it)
    f_engine.returns_float64_vector = True

    def f(q, V, t):
        if has_roots:
            try:
                v_from_twist(q, V, jt, W)
            except (TypeError, ValueError):        # not float64 C-contiguous, or the wrong size
                q, V = contiguous(q, dtype=F64), contiguous(V, dtype=F64)
                check_sizes(sizes, q, V)
                v_from_twist(q, V, jt, W)
            v = v_buf
        else:
            if type(q) is not ndarray or q.dtype is not F64:
                q = contiguous(q, dtype=F64)
            if type(V) is not ndarray or V.dtype is not F64:
                V = contiguous(V, dtype=F64)
            if V.shape != nv_shape:
                check_sizes(sizes, q, V)
            v = V                                  # the same in both coordinates
        tau = tau_c
        if tau_call:
            tau = tau(t, q, v)
            if type(tau) is not ndarray or tau.dtype is not F64 or tau.shape != nv_shape:
                tau = checked_tau(tau)
        a = aba(model, data, q, v, tau) if engine is None else engine(q, v, tau, t)
        if has_roots:
            vdot_from_a(jt, W, a)                  # in place (jt, W and a: int64 / float64 arrays)
        return a

    free_flyers_only = m.joints.roots and not (m.joints.planars or m.joints.zyx)
    return f, (f_engine if free_flyers_only else None)
