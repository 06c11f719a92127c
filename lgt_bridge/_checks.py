"""Input validation shared by the public functions (internal).

Public functions accept a single element (shape ``(k,)``) or a batch
(``(N, k)``); internally everything is a float64 batch. Each check names the
argument and the first offending body so the user can find it.
"""
import numpy as np

from .errors import InputError

QUAT_NORM_TOL = 1e-6


def batch(a, shape, name):
    """Return ``(array of shape (N, *shape), single)`` or raise InputError.

    ``single`` is True when the input was one element without a batch axis.
    """
    try:
        arr = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: cannot convert to a float array ({exc}); pass numbers "
                         f"of shape {shape} or (N, {', '.join(map(str, shape))}).") from None
    shape = tuple(shape)
    if arr.shape == shape:
        arr, single = arr[None], True
    elif arr.ndim == len(shape) + 1 and arr.shape[1:] == shape:
        single = False
    else:
        want = " or ".join([str(shape), "(N, " + ", ".join(map(str, shape)) + ")"])
        raise InputError(f"{name}: got shape {arr.shape}, expected {want}.")
    finite(arr, name)
    return arr, single


def finite(arr, name):
    """Raise InputError naming the first body with a NaN/inf entry."""
    ok = np.isfinite(arr)
    if not ok.all():
        bad = ok.reshape(len(arr), -1).all(axis=1)
        i = int(np.flatnonzero(~bad)[0])
        raise InputError(f"{name}: body {i} has a non-finite entry ({arr[i].tolist()}); "
                         "check the initial state or the model output that produced it.")


def unit_quaternion(p, name, tol=QUAT_NORM_TOL):
    """Raise InputError when a quaternion's norm is off by more than ``tol``."""
    norm = np.sqrt(np.einsum("ij,ij->i", p, p))
    err = np.abs(norm - 1.0)
    if np.any(err > tol):
        i = int(np.argmax(err > tol))
        raise InputError(f"{name}: body {i} quaternion {p[i].tolist()} has norm {norm[i]:.12g} "
                         f"(off by {err[i]:.3g} > {tol:g}); normalize it before passing it in.")


def unbatch(arr, single):
    return arr[0] if single else arr


def rotation_matrix(R, name, tol=1e-6):
    """Raise InputError when a (N, 3, 3) batch is not orthonormal with det +1."""
    err = np.abs(np.einsum("nki,nkj->nij", R, R) - np.eye(3)).max(axis=(1, 2))
    det = np.linalg.det(R)
    bad = (err > tol) | (det < 0)
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"{name}: body {i} is not a rotation matrix (|RᵀR - I| = {err[i]:.3g}, "
                         f"det = {det[i]:.6g}); pass an orthonormal matrix with det +1.")


def public(*specs):
    """Decorate an internal batched function as a public one.

    ``specs`` gives ``(name, shape)`` per positional argument; names ``R``,
    ``C*`` are checked as rotations / rigid transformations, ``p``, ``q`` as
    unit quaternions. Inputs are
    validated (shape, finiteness), batched to a common N (a single element is
    broadcast), and the output is returned without the batch axis when every
    input came without one.
    """
    def wrap(fn):
        def api(*args):
            if len(args) != len(specs):
                raise InputError(f"{fn.__name__}: takes {len(specs)} argument(s) "
                                 f"({', '.join(s[0] for s in specs)}), got {len(args)}.")
            arrs, singles = [], []
            for a, (name, shape) in zip(args, specs):
                arr, single = batch(a, shape, name)
                if name == "R":
                    rotation_matrix(arr, name)
                elif name.startswith("C"):
                    rotation_matrix(arr[:, :3, :3], name)
                elif name in ("p", "q"):
                    unit_quaternion(arr, name)
                arrs.append(arr)
                singles.append(single)
            n = {len(a) for a in arrs} - {1}
            if len(n) > 1:
                raise InputError(f"{fn.__name__}: batch sizes differ "
                                 f"({', '.join(f'{s[0]}: {len(a)}' for s, a in zip(specs, arrs))}); "
                                 "pass arrays with the same number of bodies.")
            if n:
                N = n.pop()
                arrs = [np.broadcast_to(a, (N,) + a.shape[1:]) if len(a) == 1 else a for a in arrs]
            res = fn(*arrs)
            if all(singles):
                return tuple(r[0] for r in res) if isinstance(res, tuple) else res[0]
            return res
        api.__name__ = fn.__name__.lstrip("_")
        api.__qualname__ = api.__name__
        api.__module__ = fn.__module__       # documented (and pickled) as the group module's own
        api.__doc__ = fn.__doc__
        api.__wrapped__ = fn
        return api
    return wrap


GROUP6_API = {name: (("X", (6,)),) for name in ("exp", "cay", "dexp", "dexp_inv", "dcay", "dcay_inv")}
GROUP6_API.update({name: (("X", (6,)), ("V", (6,))) for name in
                   ("dexp_apply", "dexp_inv_apply", "dcay_apply", "dcay_inv_apply")})
GROUP6_API.update(log=(("C", (4, 4)),), cay_inv=(("C", (4, 4)),), inv=(("C", (4, 4)),),
                  adjoint=(("C", (4, 4)),), mul=(("C1", (4, 4)), ("C2", (4, 4))))


def export_group6(namespace):
    """Define the public, checked functions of a 6-dimensional group module from its
    internal ``_name`` functions (SE(3) and SO(3)xR³ share the API)."""
    for name, specs in GROUP6_API.items():
        namespace[name] = public(*specs)(namespace["_" + name])
