"""Which implementation runs the hot paths: ``LGT_BRIDGE_BACKEND=numba`` (default:
compiled kernels in :mod:`lgt_bridge.kernels`) or ``numpy`` (the readable reference
functions of :mod:`lgt_bridge.groups`, :mod:`lgt_bridge.params` and :mod:`lgt_bridge.lgt`).

The variable is read when a stepper or a scene is built, so a test can switch backends
within one process. numba is imported only by the kernels, the first time one is used.
"""
import os

from .errors import InputError

BACKENDS = ("numba", "numpy")
ENV = "LGT_BRIDGE_BACKEND"


#: os.environ's own store and the variable's key in it (CPython's ``_Environ``): a lookup
#: there is a dict lookup, where ``os.environ.get`` of an unset variable raises and catches
#: a KeyError (5-8 µs in a call's set-up, which reads it several times)
_STORE = getattr(os.environ, "_data", None)
try:
    _KEY = os.environ.encodekey(ENV)
except AttributeError:
    _STORE = None


def _variable():
    """$LGT_BRIDGE_BACKEND (None when unset), read now."""
    if _STORE is None:
        return os.environ.get(ENV)
    raw = _STORE.get(_KEY)
    return None if raw is None else os.environ.decodevalue(raw)


def name(backend=None):
    """The backend to use: ``backend`` if given, else $LGT_BRIDGE_BACKEND, else 'numba'."""
    if not backend:
        backend = _variable()
        if not backend:
            return "numba"
    b = backend.strip().lower()
    if b not in BACKENDS:
        raise InputError(f"{ENV}={b!r} is not a backend; use one of {list(BACKENDS)}.")
    return b


def compiled(backend=None):
    """True when the compiled kernels run the hot paths."""
    return name(backend) == "numba"
