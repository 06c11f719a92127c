"""
Pinocchio humanoid, as written today
====================================

A floating humanoid simulated the way Pinocchio users do it today: semi-implicit
Euler with pin.integrate (zero gravity, zero torques, so the total momentum must stay
constant; its drift measures the integrator)::

    python examples/pinocchio_humanoid_legacy.py
"""
import numpy as np
import pinocchio as pin

model = pin.buildSampleModelHumanoidRandom()
model.gravity.linear[:] = 0.0
data = model.createData()
rng = np.random.default_rng(3)
q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
v = rng.normal(size=model.nv) * 0.5
tau = np.zeros(model.nv)


def momentum(q, v):
    pin.computeCentroidalMomentum(model, data, q, v)
    return np.concatenate([data.hg.linear, data.hg.angular]), data.com[0].copy()


h0, _ = momentum(q, v)
dt, T = 1e-3, 1.0
for _ in range(int(T / dt)):
    v = v + dt * pin.aba(model, data, q, v, tau)
    q = pin.integrate(model, q, v * dt)
h1, _ = momentum(q, v)
print(f"semi-implicit Euler, dt = {dt}: {int(T / dt)} ABA calls, linear momentum drift "
      f"{np.abs(h1[:3] - h0[:3]).max():.2e}")
