"""The compiled backend's f of :class:`lgt_exudyn.ExudynModel`: the kernels
(:mod:`.kernel_maps`, :mod:`.kernel_solve`) on a model's packed tables
(:mod:`.kernel_tables`) wired to Exudyn's calls, with one state write per evaluation (three
with the γ differences). Imported only when used (it imports numba).

* :func:`f_compiled` (model, P, q, V, t): ExudynModel.f of any model;
* :func:`plain_f` (model, P): the same for a model with a constant M̄, unconstrained or with
  closed-form joint rows, as a closure with everything looked up once (unconstrained: forces
  and solve fused in ``free_rhs``);
* :func:`solve_fallback` (P, nc, Vd): finishes a ``solve`` that returned 1 (redundant
  constraints) by ``lgt_bridge.model.solve_schur`` from the buffers it left (:func:`buffers`);
* :func:`pack` (model): the tables of :mod:`.kernel_tables` and, for a constrained model
  with a constant M̄, the sparse rows (``P.sp``, :class:`SparseRows`): A in CSR and the
  sparse index-1 solve of :mod:`.kernel_sparse` — A and γ in closed form when every row is
  a joint's :mod:`.sparse` knows (spherical, generic, revolute-z, prismatic-x; checked
  against Exudyn's Jacobian and γ's differences at the analysis), else A from Exudyn's
  dense Jacobian gathered into the pattern — once, when it is the same at every analysis
  state and nothing moves in time (coordinate constraints: γ = 0).

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
from .kernel_sparse import joint_rows, sparse_correction, sparse_solve
from .kernel_tables import OMIQ, OS, OR, OY
from .kernel_tables import pack as pack_tables
from . import sparse

__all__ = ["pack", "write", "forces", "constraint_matrix", "gamma_fd", "solve", "free_rhs", "buffers",
           "solve_fallback", "plain_f", "f_compiled", "joint_rows", "sparse_solve", "sparse_fallback", "SparseRows", "constraint_schur"]

#: the closed-form rows are taken when they equal Exudyn's Jacobian to this (relative) and γ's
#: differences to GAMMA_CHECK at the analysis
JACOBIAN_CHECK, GAMMA_CHECK = 1e-10, 1e-5


class SparseRows:
    """A model's constraint rows in CSR (``aptr``, ``acol``; values ``aval``, rows in the
    model's order) and the structure of :func:`.kernel_sparse.sparse_solve` (``I``, ``io``,
    ``F``, ``fo``: :func:`.sparse.structure`). ``joints``: (J, Jf) of
    :func:`.kernel_sparse.joint_rows` when the rows are computed in closed form, else None
    (A from Exudyn's dense Jacobian: ``flat``, the pattern's positions in a dense nc x nv A)."""

    def __init__(self, P, aptr, acol, joints, nonzero=None):
        self.aptr, self.acol, self.I, self.io, self.F, self.fo = sparse.structure(P, aptr, acol, nonzero)
        #: closed-form rows fill the pattern they were given: kept only when widening it to
        #: whole slots (:func:`.sparse.structure`) left it as it was
        same = len(self.acol) == len(acol) and np.array_equal(self.acol, acol)
        self.joints = joints if same else None
        self.rows = np.repeat(np.arange(len(self.aptr) - 1), np.diff(self.aptr))
        self.flat = self.rows * P.nv + self.acol
        self.aval = np.zeros(len(self.acol))
        #: the last sparse_solve left λ (unique: no redundant rows) in F's LAM section
        self.lam_ok = False
        #: A is the same everywhere (``aval`` set once, γ = 0)
        self.constant = False

    def dense(self, nc, nv):
        """A as a dense nc x nv array (from ``aval``; kept for constant rows)."""
        if self.constant and getattr(self, "_dense", None) is not None:
            return self._dense.copy()
        # (the pattern's entries summed where two fall on one place, in their order, as
        # np.add.at sums them: one call of ~1 µs instead of ~3 µs a Newton update)
        A = np.bincount(self.flat, weights=self.aval, minlength=nc * nv).reshape(nc, nv)
        if self.constant:
            self._dense = A.copy()
        return A


def pack(model, nc_max=None, views=True):
    """:func:`.kernel_tables.pack`, and ``P.sp``: the model's :class:`SparseRows`, or None
    (no constraints, no constant M̄ packed, rows of unknown owners, or ``nc_max`` other than
    the model's rows)."""
    P = pack_tables(model, nc_max, views)
    P.sp = None
    cons = getattr(model, "cons", None)
    if (cons is None or not model.n_constraints or not P.constant_mass or P.nc_max != model.n_constraints
            or not views):
        return P
    joints = sparse.joint_rows(model, P)
    if joints is not None and not _joints_agree(model, P, *joints):
        joints = None
    pattern = joints[2:] if joints is not None else sparse.ltg_pattern(model)
    if pattern is None:
        return P
    sp = SparseRows(P, *pattern[:2], joints=None if joints is None else joints[:2],
                    nonzero=pattern[2] if joints is not None else None)
    if sp.joints is None:
        held = _pattern_holds(model, P, sp)
        if held is None:
            return P
        if held is not False:                  # the same A at every analysis state
            sp.aval[:] = held
            sp.constant = True
    P.sp = sp
    P.gam0c = np.zeros(model.n_constraints)
    return P


def _states(model):
    """(q, V) at which the analysis compares: the initial state and a moved one."""
    rng = np.random.default_rng(3)
    q0, V0 = model.q0[:model.n2], model.V0[:model.nv]
    V1 = rng.normal(size=model.nv)
    return [(q0, V0), (model.nodes.moved(q0, V1, 0.3), V1)]


def _dense_A(model, q):
    model.sd.SetODE2Coordinates(q - model.ref)
    return model.cons.Cq() @ model.nodes.H(q)


def _joints_agree(model, P, J, Jf, aptr, acol, nonzero):
    """True when the closed-form rows equal Exudyn's Jacobian (C_q H) and γ its differences
    at the analysis states (and are zero where ``nonzero`` says they stay zero); leaves the system's state as it found it."""
    sd = model.sd
    keep = (np.array(sd.GetODE2Coordinates()), np.array(sd.GetODE2Coordinates_t()), sd.GetTime())
    nc, nv = model.n_constraints, model.nv
    rows = np.repeat(np.arange(nc), np.diff(aptr))
    try:
        for q, V in _states(model):
            aval, gam = np.zeros(len(acol)), np.zeros(nc)
            joint_rows(P.T, np.ascontiguousarray(q, float), np.ascontiguousarray(V, float), J, Jf, aval, gam)
            if np.any(aval[~nonzero]):
                return False
            A = np.zeros((nc, nv))
            np.add.at(A, (rows, acol), aval)
            Ad = _dense_A(model, q)
            if np.abs(A - Ad).max() > JACOBIAN_CHECK * max(1.0, np.abs(Ad).max()):
                return False
            gd = model.cons.gamma(q, V, model.t0)
            if np.abs(gam - gd).max() > GAMMA_CHECK * max(1.0, np.abs(gd).max()):
                return False
        return True
    finally:
        sd.SetODE2Coordinates(keep[0])
        sd.SetODE2Coordinates_t(keep[1])
        sd.SetTime(keep[2])


def _pattern_holds(model, P, sp):
    """None when Exudyn's Jacobian at the analysis states is nonzero outside sp's pattern;
    else A's values in the pattern when they are the same at every analysis state (constant
    rows: coordinate constraints between vector-space coordinates, not moving in time, so
    γ = d/dt(A V) = 0), else False."""
    sd, cons = model.sd, model.cons
    keep = np.array(sd.GetODE2Coordinates())
    vals = []
    try:
        for q, _ in _states(model) + [(model.nodes.moved(model.q0[:model.n2], np.ones(model.nv), 0.1), None)]:
            A = _dense_A(model, q)
            vals.append(A.ravel()[sp.flat].copy())
            A.ravel()[sp.flat] = 0.0
            if np.abs(A).max() > 0.0:
                return None
    finally:
        sd.SetODE2Coordinates(keep)
    if cons.time_dependent or cons.nonholonomic or cons.velocity_rows or any(np.any(v != vals[0]) for v in vals):
        return False
    return vals[0]


def sparse_values(model, P, q):
    """A's values at q into P.sp.aval (closed form, or gathered from Exudyn's dense Jacobian;
    the system's coordinates are then q's)."""
    sp = P.sp
    if sp.joints is not None:
        joint_rows(P.T, q, np.zeros(P.nv), sp.joints[0], sp.joints[1], sp.aval, P.gam)
    elif not sp.constant:
        model.sd.SetODE2Coordinates(q - model.ref)
        E = model.engine
        constraint_matrix(P.T, P.off, P.w, q, E.ae_jacobian_full(1.0, 1.0 if model.cons.nonholonomic else 0.0),
                          P.rows, P.A)
        np.take(P.A.ravel(), sp.flat, out=sp.aval)
    return sp.aval


#: constraint_schur returns A dense up to this many entries nc x nv, as scipy CSR above
DENSE_SCHUR_A = 2500


def constraint_schur(model, P, q):
    """(A, correct) of ``Model.constraint_schur`` from the sparse rows: A as a scipy CSR
    matrix (dense up to DENSE_SCHUR_A entries), correct(r) = M̄⁻¹Aᵀ(A M̄⁻¹ Aᵀ)⁻¹ r by :func:`.kernel_sparse.sparse_correction` (the
    dense minimum-norm solve when rows are redundant)."""
    sp, nv, nc = P.sp, P.nv, model.n_constraints
    aval = sparse_values(model, P, np.ascontiguousarray(q, float)).copy()
    if nc * nv <= DENSE_SCHUR_A:          # small: a dense A (a CSR matrix costs ~15 µs to build)
        # the pattern's positions are distinct (CSR): set, not np.add.at (~2 µs a call);
        # + 0.0 as the sum onto zeros had it (-0.0 becomes 0.0)
        A = np.zeros(nc * nv)
        A[sp.flat] = aval + 0.0
        A = A.reshape(nc, nv)
    else:
        from scipy.sparse import csr_matrix
        A = csr_matrix((aval, sp.acol, sp.aptr), shape=(nc, nv))

    def correct(r):
        out = np.empty(nv)
        r = np.ascontiguousarray(r, float)
        if sparse_correction(P.T, P.off, P.w, sp.I, sp.io, sp.F, sp.fo, aval, r, out) == 0:
            return out
        Ad = A.toarray() if hasattr(A, "toarray") else A
        MiAt = model._solve_mass2(q, Ad.T)
        return MiAt @ solve_schur(Ad @ MiAt, r)
    return A, correct


def sparse_fallback(model, P, q, gam, Vd):
    """After sparse_solve returned 1 (redundant constraints): V̇ by lgt_bridge.model.solve_schur
    (minimum-norm λ) on dense matrices from the sparse rows, M̄⁻¹Q̄ from the work array."""
    sp, nv = P.sp, P.nv
    A = sp.dense(len(gam), nv)
    Miv = P.w[P.off[OMIQ]:P.off[OMIQ] + nv].copy()
    MiAt = model._solve_mass2(q, A.T)
    lam = solve_schur(A @ MiAt, A @ Miv + gam)
    np.subtract(Miv, MiAt @ lam, out=Vd)
    return Vd


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
    """f of a model with a constant M̄ packed, unconstrained (free bodies, trees of vector
    coordinates) or with joints whose rows and γ are in closed form (``P.sp.joints``):
    :func:`f_compiled`'s calls for that case with everything looked up once, as a closure
    (q, V float64 C-contiguous); unconstrained, forces and solve in one kernel call
    (``free_rhs``). None for any other model."""
    if not P.constant_mass or not P.nv:
        return None
    S, mbs, sd = model.solver, model.mbs, model.sd
    compute, residual, set_time = S.ComputeODE2RHS, S.GetSystemResidual, sd.SetTime
    T, off, w, qpos, qvel, Qbar, nv = P.T, P.off, P.w, P.qpos, P.qvel, P.Qbar, P.nv
    if model.n_constraints:
        sp = P.sp
        if sp is None or sp.joints is None:
            return None
        ja, jb, aval, gam, empty = sp.joints[0], sp.joints[1], sp.aval, P.gam, P.empty
        I, io, F, fo = sp.I, sp.io, sp.F, sp.fo

        def joint_f(q, V, t):
            joint_rows(T, q, V, ja, jb, aval, gam)
            write(T, off, w, q, V, 0.0, qpos, qvel)
            set_time(t)
            compute(mbs)
            forces(T, off, w, q, V, residual(), empty, Qbar, empty)
            model.n_eval += 1
            Vd = np.empty(nv)
            sp.lam_ok = sparse_solve(T, off, w, I, io, F, fo, aval, Qbar, gam, Vd) == 0
            if not sp.lam_ok:
                sparse_fallback(model, P, q, gam, Vd)
            return Vd
        return joint_f

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
    sp = P.sp
    if nc and sp is not None and sp.joints is not None:
        gam = P.gam
        joint_rows(T, q, V, sp.joints[0], sp.joints[1], sp.aval, gam)
    elif nc and sp is not None and sp.constant:
        gam = P.gam0c
    elif nc:
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
    Vd = np.empty(P.nv)
    if sp is not None:
        if sp.joints is None and not sp.constant:
            constraint_matrix(T, off, w, q, E.ae_jacobian_full(1.0, 1.0 if cons.nonholonomic else 0.0), P.rows, P.A)
            np.take(P.A.ravel(), sp.flat, out=sp.aval)
        sp.lam_ok = sparse_solve(T, off, w, sp.I, sp.io, sp.F, sp.fo, sp.aval, P.Qbar, gam, Vd) == 0
        if not sp.lam_ok:
            sparse_fallback(model, P, q, gam, Vd)
        return Vd
    if nc:
        A = P.A
        constraint_matrix(T, off, w, q, E.ae_jacobian_full(1.0, 1.0 if cons.nonholonomic else 0.0), P.rows, A)
    else:
        A, gam = P.A0, P.gam0
    flag = solve(T, off, w, Mbar, A, P.Qbar, gam, Vd)
    if flag == 1:
        solve_fallback(P, len(gam), Vd)
    elif flag == 2:
        raise ModelError(f"Exudyn model: the twist mass matrix is not positive definite at t = {t:.9g}; "
                         "give every moving body a positive mass and positive principal inertias.")
    return Vd
