"""Generalized-α's modified Newton iteration (:class:`.genalpha.GenAlpha`'s updates within a
step), its matrix kept or refreshed as :func:`.newton_control.verdict` says.

Two loops over the same updates:
* :func:`_fused`: the residual in forces with a constant M̄, position-level constraints (or
  none) and a solver with compiled parts (sparse or dense LU factors, or J⁻¹ by blocks): per
  update one model call for (Q, g), one for A unless constant, and one kernel for the
  residual, the solve, the update and the state at the new Ẇ (``ga_force_newton``,
  ``_dense``, ``_csr``); what stays the same through the step (the state's affine parts, the
  model's ``forces_and_constraints_function`` and ``constraint_jacobian_function``, A when
  constant) is looked up once. On the 104-coordinate ANCF cable, whose updates cost ~20 µs
  (9 µs of them Exudyn's own force evaluation), each lookup saved counts.
* :func:`_general`: every other residual form, through ``GenAlpha._residual`` and the
  stored solver.
The step converges on the velocity change h·ΔẆ (RMS): Ẇ itself carries rounding noise of
size eps/(h²β) from the scaled constraint rows.
"""
import math

import numpy as np

from .newton_control import AT_FLOOR, CONVERGED, REFRESH, verdict


def iterate(ga, Wd1, lam, t1, h, tol, floor):
    """Newton's updates from (Ẇ, λ) on ``ga``'s stored matrix: the converged (Ẇ_{k+1}, λ),
    or None (the reason in ``ga._why``)."""
    if ga._Mcsr is not None and ga._vel_rows is None and not ga._sparse_A:
        return _fused(ga, Wd1, lam, t1, h, tol, floor)
    return _general(ga, Wd1, lam, t1, h, tol, floor)


def _fused(ga, Wd1, lam, t1, h, tol, floor):
    kernels = _KERNELS or _kernels()
    prob, m, n = ga.prob, ga.prob.model, len(Wd1)
    z = np.concatenate([Wd1, lam])
    r = np.empty(len(z))
    Wd1, lam = z[:n], z[n:]
    cg = 1.0 / (h * h * ga.beta)
    A = ga._A_fixed
    if A is None and (ga._A_const or not ga.nc):
        A = ga._A_fixed = np.asarray(ga._A(ga.q), dtype=float)
    c = ga._affine(h)
    state, at = prob.ga_state, (c.s_v, c.sp, c.W0, c.dX0, ga._to_local)
    moved, q1, V1 = prob.ga_state_args(*at)          # the kernel leaves the state at its new Ẇ
    fc = getattr(m, "forces_and_constraints_function", None)
    forces_and_constraints, head = (fc() if fc else m.forces_and_constraints), (*ga._Mcsr, A)
    jf = getattr(m, "constraint_jacobian_function", None)
    jacobian = jf() if jf is not None and A is None else ga._A      # (right after forces_and_constraints)
    sizes, since = [], []         # the step's update sizes; those since the last refresh
    factors, kernel = _factors(ga._solve, kernels)
    tail = None if factors is None else (cg, *factors, z, r, *moved)
    state(Wd1, *at)
    z_before = np.empty_like(z)
    for _ in range(ga.nmax):
        z_before[:] = z
        if factors is not None:
            prob.n_f += 1
            Q, g = forces_and_constraints(q1, V1, t1)
            if A is None:
                head = (*ga._Mcsr, np.asarray(jacobian(q1), dtype=float))
            d2 = kernel(*head, Q, g, *tail)
            if d2 < 0.0:
                ga._why = "diverged (non-finite residual)"
                return None
            size = h * math.sqrt(d2 / n)
        else:                     # a solver without compiled factors (dense or block-wise)
            r = ga._residual(Wd1, lam, t1, h)
            if not ga._finite:
                ga._why = "diverged (non-finite residual)"
                return None
            dz = ga._solve(r)
            z -= dz
            size = h * math.sqrt(dz[:n].dot(dz[:n]) / n)
        ga.n_newton += 1
        sizes.append(size)
        since.append(size)
        v = CONVERGED if size <= tol else verdict(since, tol, floor, ga.BUDGET)
        if v is CONVERGED or v is AT_FLOOR:
            ga.n_floor += v is AT_FLOOR
            return Wd1.copy(), lam.copy()
        if v is REFRESH:
            if _grew(since):
                z[:] = z_before
            ga._jacobian(Wd1, lam, t1, h)
            since = []
            factors, kernel = _factors(ga._solve, kernels)
            tail = None if factors is None else (cg, *factors, z, r, *moved)
            state(Wd1, *at)               # (the matrix may have used the work array)
    return _not_converged(ga, sizes, tol, floor)


_KERNELS = []


def _kernels():
    """The fused update kernels (sparse LU, dense LU, CSR J⁻¹), imported on the first use
    (numba stays unloaded on the numpy backend) and kept: an import statement costs ~0.7 µs a
    step."""
    from ..kernels.genalpha import ga_force_newton, ga_force_newton_csr, ga_force_newton_dense
    _KERNELS.extend((ga_force_newton, ga_force_newton_dense, ga_force_newton_csr))
    return _KERNELS


def _factors(solve, kernels):
    """(what a fused kernel solves with, that kernel): sparse LU factors, dense LU factors or
    J⁻¹ as CSR (per-block inverses); (None, None) for a solver with none of them."""
    for k, name in enumerate(("factors", "dense_factors", "csr")):
        factors = getattr(solve, name, None)
        if factors is not None:
            return factors, kernels[k]
    return None, None


def _general(ga, Wd1, lam, t1, h, tol, floor):
    n = len(Wd1)
    sizes, since = [], []
    for _ in range(ga.nmax):
        before = (Wd1, lam)
        r = ga._residual(Wd1, lam, t1, h)
        if not ga._finite:
            ga._why = "diverged (non-finite residual)"
            return None
        dz = ga._solve(r)
        dW = dz[:n] if ga.nc else dz
        Wd1 = Wd1 - dW
        if ga.nc:
            lam = lam - dz[n:]
        ga.n_newton += 1
        size = h * math.sqrt(dW.dot(dW) / n)
        sizes.append(size)
        since.append(size)
        v = verdict(since, tol, floor, ga.BUDGET)
        if v is CONVERGED or v is AT_FLOOR:
            ga.n_floor += v is AT_FLOOR
            return Wd1, lam
        if v is REFRESH:
            if _grew(since):
                Wd1, lam = before
            ga._jacobian(Wd1, lam, t1, h)
            since = []
    return _not_converged(ga, sizes, tol, floor)


def _grew(since):
    """True when the last update on the matrix being refreshed was larger than the one
    before it: the stale matrix sent the iterate away, so the update is undone and the
    matrix taken where the iterate was (on a stiff chain swinging at Exudyn's step, updates
    on a kept matrix grew from 8 to 7e5 before the refresh, which then started there)."""
    return len(since) >= 2 and since[-1] > since[-2]


def _not_converged(ga, sizes, tol, floor):
    last = ", ".join(f"{x:.2g}" for x in sizes[-3:])
    ga._why = (f"did not converge in {ga.nmax} iterations (last updates h·|ΔẆ| = {last} m/s or "
               f"rad/s RMS, against the tolerance {tol:.2g} and the rounding floor {floor:.2g})")
    return None


def predict(x, x_prev, compiled=False):
    """Newton's starting value of a step's unknowns from the last two steps' values: their
    linear extrapolation, but 0 (Arnold and Brüls' start, and Exudyn's) where the last two
    alternate in sign, as the accelerations of a mode too fast for the step do under the
    numerical damping (a stiff spring at Exudyn's step), and extrapolating doubles the swing.
    A start that far off led Newton to another root of the step's equations: a stiff damped
    chain hung at h = 0.2 s turned through its anchor, ending 2 cm above the equilibrium
    (Exudyn's own start stays on the right root). ``compiled``: in one kernel call
    (``kernels.genalpha.predict``; nine numpy operations, twice a step, cost 5 % of the ANCF
    cable pendulum's run), else the reference here."""
    if compiled and len(x):
        out = np.empty(len(x))
        try:
            (_PREDICT[0] if _PREDICT else _predict_kernel())(x, x_prev, ALTERNATING, out)
            return out
        except TypeError:          # (not C-contiguous float64 vectors: the reference)
            pass
    out = 2.0 * x - x_prev
    if len(x):
        # alternating: opposite signs, neither near zero against the vector's size (a value
        # crossing zero smoothly between two steps is extrapolated as any other)
        big = ALTERNATING * math.sqrt(x.dot(x) / len(x))
        out[(x * x_prev < 0.0) & (np.abs(x) > big) & (np.abs(x_prev) > big)] = 0.0
    return out


#: the size, against the RMS of a step's unknowns, above which two of their values of
#: opposite signs count as alternating (:func:`predict`)
ALTERNATING = 0.1
_PREDICT = []


def _predict_kernel():
    from ..kernels.genalpha import predict as kernel
    _PREDICT.append(kernel)
    return kernel
