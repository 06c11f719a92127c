"""Shared by the backend-agreement tests: relative closeness and a clean interpreter."""
import os
import subprocess
import sys

import numpy as np


def close(a, b, tol=1e-13, floor=1e-300):
    """|a - b| ≤ tol relative to the magnitude of b (at least ``floor``); same shapes."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape, (a.shape, b.shape)
    return a.size == 0 or np.abs(a - b).max() <= tol * max(np.abs(b).max(), floor)


def run_python(code, **env):
    """stdout of ``python -c code`` in a fresh interpreter with ``env`` added."""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env=dict(os.environ, **env), timeout=300)
    assert r.returncode == 0, r.stderr
    return r.stdout
