"""Hypothesis strategies and small helpers shared by the tests."""
import numpy as np
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp


def vec3(max_norm=3.0, min_norm=0.0):
    """3-vectors with norm in [min_norm, max_norm] (uniform direction, log-spread norms too)."""
    direction = hnp.arrays(np.float64, 3, elements=st.floats(-1, 1)).filter(lambda v: np.linalg.norm(v) > 1e-3)
    size = st.one_of(st.floats(min_norm, max_norm),
                     st.floats(-12, 0).map(lambda e: min(max(10.0 ** e, min_norm), max_norm)))
    return st.tuples(direction, size).map(lambda t: t[0] / np.linalg.norm(t[0]) * t[1])


def twist(max_rot=3.0, max_lin=5.0):
    lin = hnp.arrays(np.float64, 3, elements=st.floats(-max_lin, max_lin))
    return st.tuples(vec3(max_rot), lin).map(lambda t: np.concatenate(t))


def unit_quat():
    return hnp.arrays(np.float64, 4, elements=st.floats(-1, 1)).filter(
        lambda v: np.linalg.norm(v) > 1e-2).map(lambda v: v / np.linalg.norm(v))


def rel(a, b):
    return np.linalg.norm(np.asarray(a) - np.asarray(b)) / max(np.linalg.norm(b), 1e-300)
