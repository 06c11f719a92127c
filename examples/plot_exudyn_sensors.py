"""
Exudyn: the same sensors from Exudyn's solver and from the bridge
=================================================================

The heavy top of :doc:`exudyn_heavy_top_legacy` built once per solver: Exudyn's own
generalized-α (``mbs.SolveDynamic``) and the bridge's ``dop853`` through the drop-in
:func:`lgt_exudyn.SolveDynamic`. The model and its sensor are the same code; the sensors
record the same output times, so their series can be compared point by point. A run of the
bridge at a tight tolerance is the reference.
"""
import exudyn as exu
import matplotlib.pyplot as plt
import numpy as np
from exudyn.utilities import ObjectGround, RigidBodyInertia, SensorNode

from lgt_exudyn import SolveDynamic


def heavy_top():
    """The Exudyn heavy top (Euler-parameter node, spherical joint) with an angular velocity
    sensor; returns (SC, mbs, settings, sensor)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    inertia = RigidBodyInertia(mass=15.0, inertiaTensor=np.diag([0.234375, 0.46875, 0.234375]))
    com, omega0 = np.array([0.0, 1.0, 0.0]), np.array([0.0, 150.0, -4.61538])
    ground = mbs.AddObject(ObjectGround())
    top = mbs.CreateRigidBody(inertia=inertia, nodeType=exu.NodeType.RotationEulerParameters,
                              referencePosition=com, initialAngularVelocity=omega0,
                              initialVelocity=np.cross(omega0, com), gravity=[0.0, 0.0, -9.81])
    mbs.CreateSphericalJoint(itemNumbers=[ground, top], position=[0.0, 0.0, 0.0])
    node = mbs.GetObject(top)["nodeNumber"]
    sensor = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                      outputVariableType=exu.OutputVariableType.AngularVelocity))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.timeIntegration.endTime = 0.5
    settings.timeIntegration.numberOfSteps = 2000
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = 0.005
    settings.timeIntegration.verboseMode = 0
    return SC, mbs, settings, sensor


SC, mbs, settings, sensor = heavy_top()
mbs.SolveDynamic(settings)                                  # Exudyn's generalized-α, 2000 steps
exudyn_omega = mbs.GetSensorStoredData(sensor).copy()

SC, mbs, settings, sensor = heavy_top()
SolveDynamic(mbs, settings, method="dop853", group="SO3xR3", chart="exp", rtol=1e-7, atol=1e-7,
             verbose=True)
bridge_omega = mbs.GetSensorStoredData(sensor).copy()
stats = mbs.sys["lgtBridgeStats"]

SC, mbs, settings, sensor = heavy_top()
SolveDynamic(mbs, settings, method="dop853", group="SO3xR3", chart="exp", rtol=1e-12, atol=1e-12)
ref_omega = mbs.GetSensorStoredData(sensor).copy()

t = ref_omega[:, 0]
err_exudyn = np.abs(exudyn_omega[:, 1:] - ref_omega[:, 1:]).max(axis=1)
err_bridge = np.abs(bridge_omega[:, 1:] - ref_omega[:, 1:]).max(axis=1)
print(f"Exudyn generalized-α, 2000 steps: largest angular velocity error {err_exudyn.max():.1e} rad/s")
print(f"bridge dop853 rtol = 1e-7, {stats['n_steps']} steps: largest error {err_bridge.max():.1e} rad/s")

fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(6.4, 6.0), sharex=True)
for k, name in enumerate("xyz"):
    ax1.plot(t, ref_omega[:, 1 + k], label=f"ω{name}")
ax1.set_ylabel("angular velocity (rad/s)")
ax1.set_title("Exudyn heavy top: the sensor's series")
ax1.legend(ncol=3)
ax2.semilogy(t[1:], err_exudyn[1:], label="Exudyn generalized-α, 2000 steps")
ax2.semilogy(t[1:], err_bridge[1:], label=f"bridge dop853, rtol 1e-7 ({stats['n_steps']} steps)")
ax2.set_xlabel("t (s)")
ax2.set_ylabel("error (rad/s)")
ax2.legend()
fig.tight_layout()
plt.show()
