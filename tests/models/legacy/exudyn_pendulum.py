"""A short legacy Exudyn script (rigid pendulum on a revolute joint), run unchanged by
`lgt-bridge run` in the tests. Prints the final angle so the test can read it."""
import exudyn as exu
import numpy as np
from exudyn.utilities import ObjectGround, RigidBodyInertia, SensorNode

SC = exu.SystemContainer()
mbs = SC.AddSystem()
ground = mbs.AddObject(ObjectGround())
b = mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=1.0, inertiaTensor=np.diag([0.01, 0.1, 0.1])),
                        nodeType=exu.NodeType.RotationEulerParameters, referencePosition=[0.5, 0, 0],
                        gravity=[0, 0, -9.81])
mbs.CreateRevoluteJoint(itemNumbers=[ground, b], position=[0, 0, 0], axis=[0, 1, 0])
n = mbs.GetObject(b)["nodeNumber"]
s = mbs.AddSensor(SensorNode(nodeNumber=n, storeInternal=True, outputVariableType=exu.OutputVariableType.Position))
mbs.Assemble()
settings = exu.SimulationSettings()
settings.timeIntegration.endTime = 0.3
settings.timeIntegration.numberOfSteps = 300
settings.timeIntegration.verboseMode = 0
settings.solution.file.write = False
exu.SolveDynamic(mbs, settings)
print("FINAL_POSITION", *mbs.GetSensorStoredData(s)[-1, 1:])
