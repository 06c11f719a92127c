"""
Work-precision: choosing a method on the heavy top
==================================================

The engine-free heavy top (m = 15 kg spinning at 150 rad/s, held by a spherical joint) run
with the fixed-step ``rkmk4`` and the adaptive pairs ``dopri5`` and ``dop853`` at several
steps and tolerances, on SO(3)×R³ with the exponential chart. Each run's end pose is
compared with a ``dop853`` run at rtol = atol = 1e-12; the plot is error against the
number of f evaluations (the engine's cost, independent of the machine).

``lgt-bridge bench heavy_top ...`` makes the same study with wall times and every group and
chart (see :doc:`/tutorials/choosing`).
"""
import matplotlib.pyplot as plt
import numpy as np

from lgt_bridge import scenes, simulate

T = 0.5
top = scenes.heavy_top(constrained=True, param="quat")
ref = simulate(top, (0.0, T), method="dop853", group="SO3xR3", rtol=1e-12, atol=1e-12,
               t_eval=[T])


def pose_error(r):
    """Largest difference of the end position and of the (sign-aligned) quaternion."""
    q, q_ref = r.q[-1], ref.q[-1]
    p, p_ref = q[3:7], q_ref[3:7]
    return max(np.abs(q[:3] - q_ref[:3]).max(), np.abs(p * np.sign(p @ p_ref) - p_ref).max())


runs = {"rkmk4 (dt)": [dict(method="rkmk4", dt=dt) for dt in (2e-3, 1e-3, 5e-4, 2.5e-4)],
        "dopri5 (rtol)": [dict(method="dopri5", rtol=tol, atol=tol) for tol in (1e-5, 1e-7, 1e-9)],
        "dop853 (rtol)": [dict(method="dop853", rtol=tol, atol=tol) for tol in (1e-5, 1e-7, 1e-9)]}

fig, ax = plt.subplots(figsize=(6.4, 4.2))
for label, options in runs.items():
    nf, err = [], []
    for opt in options:
        r = simulate(top, (0.0, T), group="SO3xR3", chart="exp", t_eval=[T], **opt)
        nf.append(r.stats["n_f"])
        err.append(pose_error(r))
        print(f"{label:14s} {opt}: {r.stats['n_f']:6d} f, pose error {err[-1]:.1e}")
    ax.loglog(nf, err, "o-", label=label)
ax.set_xlabel("f evaluations")
ax.set_ylabel("pose error at t = 0.5 s")
ax.set_title("heavy top, SO(3)×R³ / exp")
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
plt.show()
