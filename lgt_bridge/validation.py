"""Checks made before any step: the run's options, the initial state, the mass matrix.

Public for the adapters and for users who build their own loops: ``check_inputs``
(t_span, method, tolerances, initial state), ``check_mass`` / ``mass_defects`` /
``mass_message`` (a singular or indefinite mass matrix named by its body; ``more_directions``
its note of further defects, for adapters' own texts),
``validate_bodies`` (every body's coordinates, batched per parameterization), and
``QUAT_NORM_TOL`` (how far a unit quaternion's norm may be from 1).
"""
import math

import numpy as np

from ._checks import QUAT_NORM_TOL  # noqa: F401  (public here)
from .errors import InputError
from .integrators import registry as _methods


def check_inputs(model, t_span, method, dt, rtol, atol, q0, V0, t_eval, max_steps):
    """Every input of a run, before any step: (t0, t_end, q0, V0, t_eval) checked and
    converted, or InputError saying what, where and what to do."""
    t0, t1 = check_span(t_span)
    check_options(method, dt, rtol, atol, max_steps)
    q0, V0 = check_state(model, q0, V0)
    return t0, t1, q0, V0, check_t_eval(t_eval, t0, t1)


def _finite(x):
    """np.isfinite(x) of a scalar, without numpy's per-call cost for Python numbers."""
    return math.isfinite(x) if type(x) in (float, int) else np.isfinite(x)


def check_span(t_span):
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError):
        raise InputError(f"t_span: expected (t0, t_end), got {t_span!r}.") from None
    if not (math.isfinite(t0) and math.isfinite(t1)):
        raise InputError(f"t_span: ({t0}, {t1}) must be finite.")
    if t1 <= t0:
        raise InputError(f"t_span: t_end = {t1} must be greater than t0 = {t0}; "
                         "lgt_bridge integrates forward in time.")
    return t0, t1


def check_options(method, dt, rtol, atol, max_steps):
    """The method (from the registry), its step or tolerances, max_steps; returns the
    registry's :class:`~.integrators.registry.Method`."""
    spec = _methods.get(method)
    if dt is not None and not (_finite(dt) and dt > 0):
        raise InputError(f"dt = {dt} must be a positive finite step size.")
    if dt is None and spec.fixed:
        raise InputError(f"method {method!r} takes fixed steps: pass dt (e.g. dt=1e-3).")
    if not (_finite(rtol) and rtol >= 0):       # rtol = 0: pure absolute tolerance
        raise InputError(f"rtol = {rtol} must be zero or positive.")
    if not (_finite(atol) and atol > 0):
        raise InputError(f"atol = {atol} must be positive.")
    if not int(max_steps) > 0:
        raise InputError(f"max_steps = {max_steps} must be a positive integer.")
    return spec


def check_state(model, q0=None, V0=None):
    """The initial state (default: the model's): shapes, finiteness, every body's
    coordinates, the mass matrix; returns float copies (q0, V0)."""
    lay = model.layout
    q0 = np.array(model.q0 if q0 is None else q0, float)
    V0 = np.array(model.V0 if V0 is None else V0, float)
    if q0.shape != (lay.nq,):
        raise InputError(f"q0: got shape {q0.shape}, the model has {lay.nq} coordinates.")
    if V0.shape != (lay.nv,):
        raise InputError(f"V0: got shape {V0.shape}, the model has {lay.nv} velocities.")
    if not math.isfinite(q0.dot(q0) + V0.dot(V0)):          # (one reduction; inf/NaN propagate)
        for name, arr, kind in (("q0", q0, "q"), ("V0", V0, "V")):
            if not np.isfinite(arr).all():
                i = int(np.flatnonzero(~np.isfinite(arr))[0])
                raise InputError(f"{name}: entry {i} ({lay.owner(kind, i)}) is {arr[i]}; "
                                 "give a finite initial state.")
    # the bodies' coordinates and the mass matrix at q0: checked once per model and q0 (a
    # model's structure does not change; repeated runs from one state skip the checks), the
    # coordinates once per layout object and q0 (models wrapped afresh per run of one engine
    # model share their layout)
    memo = getattr(model, "__dict__", {})
    key = q0.tobytes()
    if memo.get("_lgt_checked_q0") != key:
        lay_memo = getattr(lay, "__dict__", {})
        if lay_memo.get("_lgt_valid_q0") != key:
            validate_bodies(lay, q0)
            lay_memo["_lgt_valid_q0"] = key
        check_mass(model, q0)
        memo["_lgt_checked_q0"] = key
    return q0, V0


def check_t_eval(t_eval, t0, t1):
    """t_eval as a float array (None: every step; empty: no output, the run still advances),
    finite, strictly increasing and within [t0, t1]."""
    if t_eval is not None:
        t_eval = np.asarray(t_eval, float).ravel()
        if not t_eval.size:
            return t_eval
        first, last = float(t_eval[0]), float(t_eval[-1])
        # strictly increasing with finite ends: finite throughout (a NaN makes the min NaN)
        rising = t_eval.size == 1 or float((t_eval[1:] - t_eval[:-1]).min()) > 0.0
        if not (rising and math.isfinite(first) and math.isfinite(last)):
            raise InputError("t_eval must be finite and strictly increasing.")
        if first < t0 or last > t1:
            raise InputError(f"t_eval must lie within t_span [{t0}, {t1}].")
    return t_eval


def validate_bodies(lay, q0):
    """Every body's coordinates, batched per parameterization; on failure the body-by-body
    pass names the first bad body."""
    lay.validate_circles(q0, "q0")
    groups = {}
    for b in lay.bodies:
        groups.setdefault((b.param.name, b.rotation_only), []).append(b)
    for bodies in groups.values():
        rows = q0[np.array([[*b.pos, *b.rot] for b in bodies])]
        try:
            if bodies[0].rotation_only:
                bodies[0].param._rot(rows, "q0")
            else:
                bodies[0].param.validate(rows, "q0")
        except InputError:
            for b in bodies:
                k = lay.bodies.index(b)
                b.validate(q0, f"q0 of body {k}" + (f" ({b.name})" if b.name else ""))
            raise


_EPS = float(np.finfo(float).eps)

#: dense mass-matrix checks above this many velocities are skipped (memory: 8 nv² bytes)
MASS_CHECK_MAX_NV = 2000


def mass_defects(M, A=None, rtol=None):
    """Directions in which the mass matrix M cannot be inverted: a list of
    (velocity index, scaled eigenvalue), empty when M is positive definite (on the null
    space of the constraint Jacobian A, if given: what the index-1 solve needs).

    The test is scale-free: M is scaled symmetrically by its diagonal (so kilograms and
    kg m² compare), a zero or negative diagonal entry is a defect of its own index, and an
    eigenvalue of the scaled matrix below ``rtol`` (default max(1e-12, 100 n eps)) is a
    defect named by the largest entry of its eigenvector. The test is a Cholesky factorization
    of the scaled matrix less rtol·I (cheap); the eigen-decomposition runs only to name the
    defects when it fails. Independent diagonal blocks (the block-diagonal M of free bodies)
    are checked block by block."""
    M = np.asarray(M, float)
    n = len(M)
    if n == 0:
        return []
    if not np.isfinite(M).all():
        i = int(np.flatnonzero(~np.isfinite(M).all(axis=1))[0])
        return [(i, float("nan"))]
    M = 0.5 * (M + M.T)
    rtol = max(1e-12, 100 * n * _EPS) if rtol is None else rtol
    d = np.diag(M).copy()
    dmax = float(np.abs(d).max())
    if dmax == 0.0:
        return [(i, 0.0) for i in range(n)]
    bad = np.flatnonzero(d <= rtol * dmax)
    if len(bad):
        return [(int(i), float(d[i] / dmax)) for i in bad]
    s = 1.0 / np.sqrt(d)
    S = M * s[:, None] * s[None, :]
    if A is not None and len(A):
        # M restricted to the motions the constraints allow: Zᵀ S Z, Z an orthonormal basis
        # of the null space of A D^(-1/2) (redundant constraints are fine)
        As = np.asarray(A, float) * s[None, :]
        _, sv, Vt = np.linalg.svd(As)
        rank = int((sv > 1e-10 * max(float(sv.max(initial=0.0)), 1e-300)).sum())
        Z = Vt[rank:].T
        if Z.shape[1] == 0:
            return []
        w, U = np.linalg.eigh(Z.T @ S @ Z)
        U = Z @ U
        return [(int(np.argmax(np.abs(U[:, k]))), float(w[k])) for k in np.flatnonzero(w <= rtol)]
    blocks = _diagonal_blocks(S)
    if len(blocks) == 1:                           # one block (robots: the floating base couples all)
        try:
            np.linalg.cholesky(S - rtol * np.eye(n))
            return []
        except np.linalg.LinAlgError:
            w, U = np.linalg.eigh(S)
            return sorted((int(np.argmax(np.abs(U[:, k]))), float(w[k])) for k in np.flatnonzero(w <= rtol))
    out = []
    by_size = {}
    for idx in blocks:
        by_size.setdefault(len(idx), []).append(idx)
    for group in by_size.values():                 # same-size blocks in one batched call
        I = np.array(group)
        B = S[I[:, :, None], I[:, None, :]]
        try:                                       # every eigenvalue > rtol: Cholesky of B - rtol I
            np.linalg.cholesky(B - rtol * np.eye(B.shape[1]))
            continue
        except np.linalg.LinAlgError:              # name the defect: the eigen-decomposition
            pass
        w, U = np.linalg.eigh(B)
        for b, k in zip(*np.nonzero(w <= rtol)):
            out.append((int(I[b][np.argmax(np.abs(U[b][:, k]))]), float(w[b, k])))
    return sorted(out)


def _diagonal_blocks(S):
    """Index sets of the independent diagonal blocks of the symmetric S (its connected
    components); one block when S is mostly nonzero."""
    n = len(S)
    nz = S != 0.0
    if n <= 12 or nz.sum() > 0.25 * n * n:
        return [np.arange(n)]
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components
    k, labels = connected_components(csr_matrix(nz), directed=False)
    order = np.argsort(labels, kind="stable")
    return np.split(order, np.cumsum(np.bincount(labels, minlength=k))[:-1])


def check_mass(model, q0):
    """Reject, before any step, a model whose mass matrix at q0 is singular or indefinite
    (e.g. links with zero inertia): an explicit adaptive method would otherwise grind to
    max_steps. A model may provide ``check_mass_matrix(q)`` (raising InputError itself and
    naming its own joints); otherwise a model with ``mass_matrix`` is checked densely (up to
    MASS_CHECK_MAX_NV velocities; block by block when M is block-diagonal), on the null
    space of the constraint Jacobian when it has constraints (a singular M is then fine
    when the constraints hold the singular direction)."""
    own = getattr(model, "check_mass_matrix", None)
    if own is not None:
        own(q0)
        return
    if not model.has_mass_matrix or model.layout.nv > MASS_CHECK_MAX_NV:
        return
    M = model.mass_matrix(q0)
    A = model.constraint_jacobian(q0) if model.n_constraints else None
    defects = mass_defects(M, A)
    if defects:
        raise InputError(mass_message(defects, [model.layout.owner("V", i) for i, _ in defects]))


#: a scaled eigenvalue of M below minus this is negative inertia; above it (to rtol) it is
#: zero up to rounding (ObjectANCFBeam: -1.1e-15)
NEGATIVE_INERTIA = 1e-9


def more_directions(defects, owners):
    """"; n such directions, in <owners>" for a mass message naming more than one defect
    (the first six owners), "" for one."""
    if len(defects) <= 1:
        return ""
    names = list(dict.fromkeys(owners))
    return f"; {len(defects)} such directions, in {', '.join(names[:6])}" + (", ..." if len(names) > 6 else "")


def mass_message(defects, owners):
    """InputError text for ``mass_defects`` output; ``owners`` names each defect's index."""
    i, lam = defects[0]
    # an eigenvalue of the scaled M at rounding level is zero, whatever its sign
    negative = lam < -NEGATIVE_INERTIA
    kind = "indefinite" if negative else "singular"
    more = more_directions(defects, owners)
    return (f"mass matrix at q0 is {kind}: the motion of {owners[0]} (velocity index {i}) has "
            f"{'negative' if negative else 'no'} inertia (scaled eigenvalue {lam:.2g}){more}. "
            "Its acceleration is undefined and an integrator would fail or crawl to max_steps. "
            "Give every moving body a positive mass and positive principal inertias (a "
            "zero-inertia link: merge it into its parent, or add a small rotor inertia/armature).")
