"""
Exudyn heavy top, as written today
==================================

A heavy top as Exudyn users write it today: Euler-parameter node, spherical joint,
sensors, and Exudyn's own generalized-α solver::

    python examples/exudyn_heavy_top_legacy.py
    lgt-bridge run examples/exudyn_heavy_top_legacy.py --method dopri5   # same script, bridged
"""
import exudyn as exu
import numpy as np
from exudyn.utilities import ObjectGround, RigidBodyInertia, SensorNode

SC = exu.SystemContainer()
mbs = SC.AddSystem()

m = 15.0
inertia = RigidBodyInertia(mass=m, inertiaTensor=np.diag([0.234375, 0.46875, 0.234375]))
com = np.array([0.0, 1.0, 0.0])                  # centre of mass, 1 m from the pivot
omega0 = np.array([0.0, 150.0, -4.61538])        # body-fixed initial angular velocity

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

mbs.SolveDynamic(simulationSettings)

omega = mbs.GetSensorStoredData(sOmega)
print(f"t = {omega[-1, 0]:.3f} s: global angular velocity {omega[-1, 1:]}")
