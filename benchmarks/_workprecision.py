"""Shared by the work-precision benchmarks."""
import numpy as np


def wall_at_error(rows, target):
    """(wall time at `target` error, exact?) along one family's runs: log-log interpolation
    where the runs bracket the target, otherwise the cheapest run at or below it (an upper
    bound, exact = False); (None, False) when no run reaches it."""
    pts = sorted((r["error"], r["wall_s"]) for r in rows if r["error"] > 0 and np.isfinite(r["error"]))
    for (e1, w1), (e2, w2) in zip(pts, pts[1:]):
        if e1 <= target <= e2:
            f = (np.log(target) - np.log(e1)) / (np.log(e2) - np.log(e1))
            return float(np.exp(np.log(w1) + f * (np.log(w2) - np.log(w1)))), True
    below = [w for e, w in pts if e <= target]
    return (min(below), False) if below else (None, False)
