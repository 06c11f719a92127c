"""Compiled kernels (numba ``@njit(cache=True)``) of the hot paths, one module per family.

They are plain Python loops over float64 arrays, so with ``NUMBA_DISABLE_JIT=1`` the same
source runs interpreted (debugging, coverage). Every kernel is tested equal (1e-13) to the
numpy reference functions it replaces; ``LGT_BRIDGE_BACKEND=numpy`` runs without them.
They import nothing above :mod:`lgt_bridge.groups`. Importing this package imports numba.
"""
