"""The compiled backend's f of :class:`lgt_exudyn.ExudynModel`: the kernels
(:mod:`.kernel_maps`, :mod:`.kernel_solve`) on a model's packed tables
(:mod:`.kernel_tables`) wired to Exudyn's calls, with one state write per evaluation (three
with the γ differences). Imported only when used (it imports numba).

* :func:`f_compiled` (model, P, q, V, t): ExudynModel.f of any model;
* :func:`plain_f` (model, P): the same for an unconstrained model with a constant M̄, as a
  closure with everything looked up once (forces and solve fused in ``free_rhs``);
* :func:`solve_fallback` (P, nc, Vd): finishes a ``solve`` that returned 1 (redundant
  constraints) by ``lgt_bridge.model.solve_schur`` from the buffers it left (:func:`buffers`).

The numpy reference is ExudynModel's own f (:mod:`.layout`'s maps, :mod:`.constraints`' γ
and ``lgt_bridge.model.solve_kkt``); tests/test_exudyn_kernels.py holds them equal (1e-13;
1e-9 with γ's differences).
"""
import numpy as np

from lgt_bridge.errors import ModelError
from lgt_bridge.model import solve_schur

from .constraints import EPS_GAMMA
from .kernel_maps import constraint_matrix, forces, gamma_fd, write
from .kernel_solve import free_rhs, solve
from .kernel_tables import OMIQ, OS, OR, OY, pack

__all__ = ["pack", "write", "forces", "constraint_matrix", "gamma_fd", "solve", "free_rhs", "buffers",
           "solve_fallback", "plain_f", "f_compiled"]


def buffers(P, nc):
    """(S, r, Miv, Y) a solve left in w for nc constraint rows: A M̄⁻¹ Aᵀ, A M̄⁻¹ Q̄ + γ,
    M̄⁻¹ Q̄ and M̄⁻¹ Aᵀ transposed (nc x nv)."""
    off, w, nv = P.off, P.w, P.nv
    return (w[off[OS]:off[OS] + nc * nc].reshape(nc, nc), w[off[OR]:off[OR] + nc],
            w[off[OMIQ]:off[OMIQ] + nv], w[off[OY]:off[OY] + nc * nv].reshape(nc, nv))


def solve_fallback(P, nc, Vd):
    """After a solve returned 1: λ by lgt_bridge.model.solve_schur (minimum norm for
    redundant constraints) from the buffers the kernel left; V̇ = M̄⁻¹Q̄ - M̄⁻¹Aᵀλ into Vd."""
    S, r, Miv, Y = buffers(P, nc)
    lam = solve_schur(S, r)
    np.subtract(Miv, Y.T @ lam, out=Vd)
    return Vd


def plain_f(model, P):
    """f of an unconstrained model with a constant M̄ packed (free bodies, trees of vector
    coordinates): :func:`f_compiled`'s calls for that case with everything looked up once,
    as a closure (q, V float64 C-contiguous), forces and solve in one kernel call
    (``free_rhs``). None for any other model."""
    if model.n_constraints or not P.constant_mass or not P.nv:
        return None
    S, mbs, sd = model.solver, model.mbs, model.sd
    compute, residual, set_time = S.ComputeODE2RHS, S.GetSystemResidual, sd.SetTime
    T, off, w, qpos, qvel, Qbar, nv = P.T, P.off, P.w, P.qpos, P.qvel, P.Qbar, P.nv

    def f(q, V, t):
        write(T, off, w, q, V, 0.0, qpos, qvel)
        set_time(t)
        compute(mbs)
        Vd = np.empty(nv)
        free_rhs(T, off, w, q, V, residual(), Qbar, Vd)
        model.n_eval += 1
        return Vd
    return f


def f_compiled(model, P, q, V, t):
    """ExudynModel.f from the kernels and Exudyn's calls (the compiled backend's f).

    P = pack(model) (nc_max = model.n_constraints, Exudyn's views); q, V float64
    C-contiguous. The two γ evaluations come first and the state itself last, so that the
    system ends at (q, V, t) after three writes instead of four."""
    E, cons = model.engine, model.cons
    S, mbs, sd = E.solver, E.mbs, E.sd
    T, off, w, qpos, qvel = P.T, P.off, P.w, P.qpos, P.qvel
    nc = model.n_constraints
    if nc:
        td = cons.time_dependent
        if (td and not cons.exudyn_gt) or not cons.velocity_level:
            gam = cons.gamma(q, V, t)                        # numpy path (second differences)
        else:
            eps = write(T, off, w, q, V, EPS_GAMMA, qpos, qvel)   # moved by +h, h = 1e-5 / max(1, |V|∞)
            sd.SetTime(t + eps if td else t)
            S.ComputeAlgebraicEquations(mbs, True)
            rp = S.GetSystemResidual()
            write(T, off, w, q, V, -EPS_GAMMA, qpos, qvel)
            sd.SetTime(t - eps if td else t)
            S.ComputeAlgebraicEquations(mbs, True)
            gam = P.gam
            gamma_fd(rp, S.GetSystemResidual(), P.rows, eps, gam)
    write(T, off, w, q, V, 0.0, qpos, qvel)
    sd.SetTime(t)
    S.ComputeODE2RHS(mbs)
    Q = S.GetSystemResidual()
    if P.constant_mass:
        M = Mbar = P.empty
    else:
        S.ComputeMassMatrix(mbs)
        M, Mbar = S.GetSystemMassMatrix(), P.Mbar
    forces(T, off, w, q, V, Q, M, P.Qbar, Mbar)
    model.n_eval += 1
    if nc:
        A = P.A
        constraint_matrix(T, off, w, q, E.ae_jacobian_full(1.0, 1.0 if cons.nonholonomic else 0.0), P.rows, A)
    else:
        A, gam = P.A0, P.gam0
    Vd = np.empty(P.nv)
    flag = solve(T, off, w, Mbar, A, P.Qbar, gam, Vd)
    if flag == 1:
        solve_fallback(P, len(gam), Vd)
    elif flag == 2:
        raise ModelError(f"Exudyn model: the twist mass matrix is not positive definite at t = {t:.9g}; "
                         "give every moving body a positive mass and positive principal inertias.")
    return Vd
