"""
Exudyn heavy top, through the bridge
====================================

The same heavy top through the bridge: the model is untouched; only the solve call
changes (compare with exudyn_heavy_top_legacy.py):

.. code-block:: diff

    -mbs.SolveDynamic(simulationSettings)
    +from lgt_exudyn import SolveDynamic
    +SolveDynamic(mbs, simulationSettings, method="dopri5", group="SO3xR3", chart="exp")

Euler parameters stay unit without the normalization constraint, sensors and the
solution file work as before, and adaptive error control is available.
"""
import exudyn as exu
import numpy as np
from exudyn.utilities import ObjectGround, RigidBodyInertia, SensorNode

from lgt_exudyn import SolveDynamic

SC = exu.SystemContainer()
mbs = SC.AddSystem()

m = 15.0
inertia = RigidBodyInertia(mass=m, inertiaTensor=np.diag([0.234375, 0.46875, 0.234375]))
com = np.array([0.0, 1.0, 0.0])
omega0 = np.array([0.0, 150.0, -4.61538])

ground = mbs.AddObject(ObjectGround())
top = mbs.CreateRigidBody(inertia=inertia, nodeType=exu.NodeType.RotationEulerParameters,
                          referencePosition=com, initialAngularVelocity=omega0,
                          initialVelocity=np.cross(omega0, com), gravity=[0.0, 0.0, -9.81])
mbs.CreateSphericalJoint(itemNumbers=[ground, top], position=[0.0, 0.0, 0.0])
node = mbs.GetObject(top)["nodeNumber"]
sOmega = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                  outputVariableType=exu.OutputVariableType.AngularVelocity))
mbs.Assemble()

simulationSettings = exu.SimulationSettings()
simulationSettings.timeIntegration.endTime = 0.5
simulationSettings.timeIntegration.numberOfSteps = 2000
simulationSettings.solution.file.write = False
simulationSettings.solution.sensors.writePeriod = 0.01
simulationSettings.timeIntegration.verboseMode = 0

SolveDynamic(mbs, simulationSettings, method="dopri5", group="SO3xR3", chart="exp",
             rtol=1e-8, atol=1e-8, verbose=True)

omega = mbs.GetSensorStoredData(sOmega)
p = mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates)[3:]
print(f"t = {omega[-1, 0]:.3f} s: global angular velocity {omega[-1, 1:]}")
print(f"Euler parameters (reference + current) stay unit: |p| - 1 = {np.linalg.norm(p + [1, 0, 0, 0]) - 1:.1e}")
