"""
Events: a pendulum's period
===========================

Events on an engine-free model: the period of a large-amplitude compound pendulum from its
successive passes through the vertical, against the exact 4 K(sin²(θ0/2)) √(l/g).

g(t, q, V) = x of the centre of mass (zero at the vertical), with ``direction = +1``: one
crossing per period. Every crossing is located on the step's continuous extension through
τ — dop853's dense output; rkmk4's cubic Hermite interpolant of (X, W) within the step::

    python examples/events_pendulum_period.py
"""
import numpy as np
from scipy.special import ellipk

from lgt_bridge import scenes, simulate
from lgt_bridge.groups.batch import rotate

theta0 = 2.5                                         # 143° from the vertical, released from rest
m = scenes.pendulum(theta0)
T = 4 * ellipk(np.sin(theta0 / 2) ** 2) * np.sqrt(m.equivalent_length / 9.81)
c = np.array([[0.0, 0.0, -0.6]])                     # the centre of mass in the body frame


def passes_vertical(t, q, V):
    return rotate(q[None, 3:7], c)[0, 0]        # its x; q = (pivot, quaternion w x y z)


passes_vertical.direction = 1
print(f"exact period {T:.12f} s (small-angle formula: {2 * np.pi * np.sqrt(m.equivalent_length / 9.81):.6f} s)")
runs = (("dop853", "rtol = atol = 1e-13", dict(rtol=1e-13, atol=1e-13)),
        ("rkmk4", "dt = T/100", dict(dt=T / 100)), ("rkmk4", "dt = T/400", dict(dt=T / 400)))
for method, label, kw in runs:
    r = simulate(m, (0.0, 10.3 * T), method=method, events=[passes_vertical], **kw)
    te = r.t_events[0]
    periods = np.diff(te)
    print(f"{method:6s} {label:20s} {len(te)} passes, period {periods.mean():.12f} s, relative error "
          f"{abs(periods.mean() - T) / T:.1e} (largest of one period {np.abs(periods - T).max() / T:.1e})")
