"""Multi-dimensional views of a 1-D array's leading entries, for the kernels' packed arrays.

The stage and step kernels keep their tables and buffers in one flat array each (a numba
call costs per argument) and view parts of them as matrices at every call. numba's
``reshape`` does that through a helper call that checks the strides, ≈ 13 ns each, and a
dop853 stage made eight of them: a fifth of the stage kernel's own arithmetic on a small
robot. :func:`matrix` and :func:`block` build the same C-contiguous views directly: the
caller guarantees that the 1-D array is C-contiguous (the only layout they accept) and holds
at least the view's entries.

Where numba's array internals used here are missing (another numba), both fall back to
``reshape``; with the JIT off they are numpy's reshape.
"""
from numba import config, njit, types

try:
    from numba.core import cgutils
    from numba.core.extending import intrinsic
    from numba.core.imputils import impl_ret_borrowed
    from numba.np.arrayobj import make_array, populate_array
except ImportError:                                   # pragma: no cover - other numba versions
    intrinsic = None
if config.DISABLE_JIT:                                # the kernels run as Python: numpy's reshape
    intrinsic = None


def _view_intrinsic(ndim):
    """An intrinsic (a, *shape) -> the C-contiguous ``ndim``-D view of a's first entries."""

    def typer(typingctx, a, *dims):
        if not (isinstance(a, types.Array) and a.ndim == 1 and a.layout == "C" and len(dims) == ndim
                and all(isinstance(d, types.Integer) for d in dims)):
            return None
        out_ty = types.Array(a.dtype, ndim, "C")

        def codegen(context, builder, sig, args):
            src = make_array(sig.args[0])(context, builder, value=args[0])
            out = make_array(out_ty)(context, builder)
            dims_ = [context.cast(builder, v, t, types.intp) for v, t in zip(args[1:], sig.args[1:])]
            stride = context.get_constant(types.intp, context.get_abi_sizeof(context.get_data_type(a.dtype)))
            strides = [stride]
            for d in reversed(dims_[1:]):
                strides.insert(0, builder.mul(strides[0], d))
            populate_array(out, data=src.data, shape=cgutils.pack_array(builder, dims_),
                           strides=cgutils.pack_array(builder, strides), itemsize=src.itemsize,
                           meminfo=src.meminfo, parent=src.parent)
            return impl_ret_borrowed(context, builder, out_ty, out._getvalue())
        return out_ty(a, *dims), codegen

    # numba's intrinsic reads the typer's parameters: spell them out per ndim
    if ndim == 2:
        def typer2(typingctx, a, n, m):
            return typer(typingctx, a, n, m)
        return intrinsic(typer2)

    def typer3(typingctx, a, n, m, k):
        return typer(typingctx, a, n, m, k)
    return intrinsic(typer3)


if intrinsic is not None:
    #: a[:n*m] as an (n, m) C-contiguous view (a: 1-D, C-contiguous)
    matrix = _view_intrinsic(2)
    #: a[:n*m*k] as an (n, m, k) C-contiguous view (a: 1-D, C-contiguous)
    block = _view_intrinsic(3)
else:                                                 # pragma: no cover
    @njit(cache=True, inline="always")
    def matrix(a, n, m):
        return a[:n * m].reshape((n, m))

    @njit(cache=True, inline="always")
    def block(a, n, m, k):
        return a[:n * m * k].reshape((n, m, k))
