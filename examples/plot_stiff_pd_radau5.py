"""
Stiff models: a PD-controlled quadruped with radau5
===================================================

The quadruped solo12 of example-robot-data under joint-space PD control toward its reference
configuration (kp = 1000 N·m/rad on every joint, critically damped; the ``pd`` scenario of
``lgt-bridge bench pinocchio_robot:solo12``), its base tumbling. The gains make the model
stiff: an explicit method's step is capped by stability, not by its tolerance, so ``dop853``
takes about the same number of steps at every tolerance. ``radau5`` (implicit, L-stable,
order 5) takes its Newton matrix from Pinocchio's analytic derivatives and the PD law's own
Jacobians (``pd_torque(...).derivatives``), and steps as the accuracy allows.

Needs the ``robots`` extra (``pip install -e ".[robots]"``: example-robot-data).
"""
import time

import matplotlib.pyplot as plt
import numpy as np

from lgt_bridge import simulate
from lgt_pinocchio import PinocchioModel
from lgt_pinocchio.bench import pd_controller, robot_state

model, q0, v0 = robot_state("solo12")
tau = pd_controller("solo12")
T = 0.5

fig, ax = plt.subplots(figsize=(6.4, 4.0))
for method in ("dop853", "radau5"):
    for tol in (1e-5, 1e-8):
        m = PinocchioModel(model, q0=q0, v0=v0, tau=tau, tau_derivatives=tau.derivatives)
        start = time.perf_counter()
        r = simulate(m, (0.0, T), method=method, group="SO3xR3", chart="exp", rtol=tol, atol=tol)
        wall = time.perf_counter() - start
        print(f"{method}, rtol = atol = {tol:g}: {r.stats['n_steps']:5d} steps, "
              f"{r.stats['n_f']:6d} f evaluations, {wall:.3f} s")
        ax.semilogy(r.t[1:], np.diff(r.t), ".-" if method == "radau5" else "-", ms=3,
                    label=f"{method}, tol {tol:g}: {r.stats['n_steps']} steps, {r.stats['n_f']} f")
ax.set_xlabel("t (s)")
ax.set_ylabel("step size (s)")
ax.set_title("solo12 under PD control")
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()
