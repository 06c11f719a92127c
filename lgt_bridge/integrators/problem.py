"""The local problem of a model on the selected backend: the numpy reference
(:class:`.local.LocalProblem`) or the compiled kernels (:class:`.compiled.CompiledProblem`)."""
from .. import backend as _backend
from .local import LocalProblem


def make_problem(model, group="SE3", chart="exp", backend=None):
    """The local problem on the selected backend (:mod:`lgt_bridge.backend`)."""
    global _COMPILED
    if _backend.compiled(backend):
        if _COMPILED is None:              # (imported on first use: it imports numba)
            from .compiled import CompiledProblem
            _COMPILED = CompiledProblem
        return _COMPILED(model, group, chart)
    return LocalProblem(model, group, chart)


_COMPILED = None
