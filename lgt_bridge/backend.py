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


def name(backend=None):
    """The backend to use: ``backend`` if given, else $LGT_BRIDGE_BACKEND, else 'numba'."""
    if not backend:
        backend = os.environ.get(ENV)
        if not backend:
            return "numba"
    b = backend.strip().lower()
    if b not in BACKENDS:
        raise InputError(f"{ENV}={b!r} is not a backend; use one of {list(BACKENDS)}.")
    return b


def compiled(backend=None):
    """True when the compiled kernels run the hot paths."""
    return name(backend) == "numba"
