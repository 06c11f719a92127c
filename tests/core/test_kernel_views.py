"""lgt_bridge.kernels.views: the kernels' matrix views of a flat array are numpy's reshape of
the same entries, share their memory, leak nothing, and fall back to reshape with the JIT off."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from lgt_bridge.kernels.views import block, matrix

from backend_checks import run_python


@njit(cache=False)
def _views(a, o2, n, m, o3, k, i, j):
    M = matrix(a[o2:], n, m)
    B = block(a[o3:], k, i, j)
    return M, B


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 6), m=st.integers(1, 7), k=st.integers(1, 3), i=st.integers(1, 4),
       j=st.integers(1, 5), o2=st.integers(0, 9), o3=st.integers(0, 9), extra=st.integers(0, 5))
def test_views_are_numpys_reshape_of_the_same_memory(n, m, k, i, j, o2, o3, extra):
    size = max(o2 + n * m, o3 + k * i * j) + extra
    a = np.random.default_rng(size).standard_normal(size)
    M, B = _views(a, o2, n, m, o3, k, i, j)
    np.testing.assert_array_equal(M, a[o2:o2 + n * m].reshape(n, m))
    np.testing.assert_array_equal(B, a[o3:o3 + k * i * j].reshape(k, i, j))
    assert M.flags.c_contiguous and B.flags.c_contiguous
    M[n - 1, m - 1] = 7.5                      # views: writes reach the flat array
    assert a[o2 + n * m - 1] == 7.5
    B[k - 1, i - 1, j - 1] = -3.25
    assert a[o3 + k * i * j - 1] == -3.25


def test_views_keep_their_array_alive_and_leak_nothing():
    out = run_python(
        "import gc, numpy as np\n"
        "from numba import njit\n"
        "from numba.core.runtime import rtsys\n"
        "from lgt_bridge.kernels.views import matrix\n"
        "@njit\n"
        "def f(n):\n"
        "    a = np.arange(12.0)\n"               # allocated in the kernel: only the view holds it
        "    return matrix(a[2:], n, 5)\n"
        "@njit\n"
        "def scribble(n):\n"                     # fresh allocations that would reuse a freed a
        "    s = 0.0\n"
        "    for k in range(n):\n"
        "        s += np.full(12, -1.0).sum()\n"
        "    return s\n"
        "M = f(2)\n"
        "gc.collect()\n"
        "junk = [np.full(12, -1.0) for _ in range(50)], scribble(50)\n"
        "ok = (M == np.arange(2.0, 12.0).reshape(2, 5)).all()\n"
        "s0 = rtsys.get_allocation_stats()\n"
        "for _ in range(500):\n"
        "    f(2)\n"
        "s1 = rtsys.get_allocation_stats()\n"
        "print(ok, (s1.alloc - s0.alloc) - (s1.free - s0.free), (s1.mi_alloc - s0.mi_alloc) - (s1.mi_free - s0.mi_free))",
        NUMBA_NRT_STATS="1")
    assert out.split() == ["True", "0", "0"]


def test_views_run_interpreted():
    out = run_python(
        "import numpy as np\n"
        "from lgt_bridge.kernels.views import block, matrix\n"
        "a = np.arange(30.0)\n"
        "print((matrix(a[3:], 4, 5) == a[3:23].reshape(4, 5)).all(), (block(a[1:], 2, 3, 4) == a[1:25].reshape(2, 3, 4)).all())",
        NUMBA_DISABLE_JIT="1")
    assert out.split() == ["True", "True"]
