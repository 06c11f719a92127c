"""
Events: a quadruped's first touchdown
=====================================

Events on a Pinocchio model: Solo-12 (example-robot-data) dropped from 0.3 m, its base
rolled by 0.05 rad and pitched by 0.2 rad and its knees folded 0.4 rad beyond the standing
pose, under joint-space PD control towards that pose, stopping when a foot first touches
the ground.

One event function per foot, g(t, q, V) = the height of the foot frame, computed by Pinocchio
itself (g may call the engine: q is Pinocchio's own configuration; v would come from
``m.pin_state(q, V)``).
Each is terminal and fires going down (``direction = -1``): the run ends at the first
touchdown, located on the step's continuous extension through τ to the run's tolerances,
with the model written back there; ``result.message`` names the foot::

    python examples/events_quadruped_drop.py
"""
import example_robot_data
import numpy as np
import pinocchio as pin

from lgt_bridge import simulate
from lgt_pinocchio import PinocchioModel
from lgt_pinocchio.baselines import pd_torque

robot = example_robot_data.load("solo12")
model = robot.model
data = model.createData()
q_stand = robot.q0.copy()
q0 = q_stand.copy()
q0[2] += 0.3                                         # the base 0.3 m above its standing height,
q0[3:7] = pin.Quaternion(pin.utils.rpyToMatrix(0.05, 0.2, 0.0)).coeffs()    # rolled, pitched (x y z w),
q0[9::3] += np.sign(q_stand[9::3]) * 0.4             # knees folded further: the PD unfolds them
feet = ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]
frames = [model.getFrameId(f) for f in feet]
m = PinocchioModel(model, q0=q0, v0=np.zeros(model.nv), tau=pd_torque(model, q_stand, kp=5.0, kd=0.1))


def foot_height(frame, name):
    def g(t, q, V):
        pin.forwardKinematics(model, data, q)          # the bridge's q is Pinocchio's own q
        return pin.updateFramePlacement(model, data, frame).translation[2]
    g.__name__ = f"{name} touches the ground"
    g.terminal, g.direction = True, -1
    return g


events = [foot_height(f, n) for f, n in zip(frames, feet)]
r = simulate(m, (0.0, 2.0), method="dop853", rtol=1e-9, atol=1e-9, events=events)
t_hit = min(te[0] for te in r.t_events if len(te))
print(r.message)
print(f"touchdown at t = {t_hit:.9f} s after {r.stats['n_steps']} steps, {r.stats['n_f']} ABA calls")
q_hit, v_hit = m.pin_state(r.q[-1], r.V[-1])
print("feet heights there (m):", ", ".join(f"{n} {g(t_hit, r.q[-1], r.V[-1]):+.2e}" for n, g in zip(feet, events)))
print(f"base height {q_hit[2]:.6f} m, vertical base velocity {v_hit[2]:+.6f} m/s (Pinocchio's own q, v)")
