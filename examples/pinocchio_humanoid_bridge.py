"""
Pinocchio humanoid, through the bridge
======================================

The same floating humanoid through the bridge. The model is untouched; the loop::

    for _ in range(n):
        v = v + dt * pin.aba(model, data, q, v, tau)
        q = pin.integrate(model, q, v * dt)

becomes::

    from lgt_bridge import simulate
    from lgt_pinocchio import PinocchioModel
    r = simulate(PinocchioModel(model, q0=q, v0=v, tau=tau), (0, T), method="rkmk4", dt=dt)
    q, v = r.q[-1], PinocchioModel(...).pin_state(r.q[-1], r.V[-1])[1]

and results come back in Pinocchio's own q (and v through pin_state).
"""
import numpy as np
import pinocchio as pin

from lgt_bridge import simulate
from lgt_pinocchio import PinocchioModel

model = pin.buildSampleModelHumanoidRandom()
model.gravity.linear[:] = 0.0
data = model.createData()
rng = np.random.default_rng(3)
q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
v = rng.normal(size=model.nv) * 0.5


def momentum(q, v):
    pin.computeCentroidalMomentum(model, data, q, v)
    return np.concatenate([data.hg.linear, data.hg.angular])


h0 = momentum(q, v)
T, dt = 1.0, 4e-3                                  # 250 steps x 4 ABA calls = 1000, as the legacy loop
m = PinocchioModel(model, q0=q, v0=v, tau=np.zeros(model.nv))
r = simulate(m, (0, T), method="rkmk4", group="SO3xR3", chart="exp", dt=dt, t_eval=[0, T])
if not r.success:                                  # r.q is empty when the run stopped before T
    raise SystemExit(f"the run failed: {r.message}")
q1, v1 = m.pin_state(r.q[-1], r.V[-1])            # r.q: Pinocchio's q; r.V: the bridge's (ω, v)
h1 = momentum(q1, v1)
print(f"bridge rkmk4, dt = {dt}: {r.stats['n_f']} ABA calls, linear momentum drift "
      f"{np.abs(h1[:3] - h0[:3]).max():.2e}")
print(f"free-flyer quaternion norm - 1: {np.linalg.norm(q1[3:7]) - 1:.1e}")
