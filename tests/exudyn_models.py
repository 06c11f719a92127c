"""Exudyn models for the adapter tests, written as Exudyn users write them."""
import exudyn as exu
import numpy as np
from exudyn.utilities import (MarkerNodePosition, MassPoint, NodePoint, ObjectConnectorCartesianSpringDamper,
                              ObjectGround, RigidBodyInertia, MarkerBodyRigid, LoadForceVector,
                              MarkerBodyPosition)

EP = exu.NodeType.RotationEulerParameters
ROTVEC = exu.NodeType.RotationRotationVector
RXYZ = exu.NodeType.RotationRxyz
G = [0.0, 0.0, -9.81]


def heavy_top(node=EP, joint=True, R0=None, assemble=True):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    inertia = RigidBodyInertia(mass=15.0, inertiaTensor=np.diag([0.234375, 0.46875, 0.234375]))
    R0 = np.eye(3) if R0 is None else R0
    com, w0 = R0 @ np.array([0.0, 1.0, 0.0]), np.array([0.0, 150.0, -4.61538])
    ground = mbs.AddObject(ObjectGround())
    body = mbs.CreateRigidBody(inertia=inertia, nodeType=node, referencePosition=com, referenceRotationMatrix=R0,
                               initialAngularVelocity=w0, initialVelocity=R0 @ np.cross(w0, [0, 1, 0]), gravity=G)
    if joint:
        mbs.CreateSphericalJoint(itemNumbers=[ground, body], position=[0.0, 0.0, 0.0])
    if assemble:
        mbs.Assemble()
    return SC, mbs, mbs.GetObject(body)["nodeNumber"]


def chain(n=5, node=EP, joint="spherical"):
    """n links along x from a ground joint, spinning about the vertical (as scenes.chain)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    prev, spin = ground, 2.0
    inertia = RigidBodyInertia(mass=1.0, inertiaTensor=np.diag([1e-3, 1 / 12, 1 / 12]))
    for k in range(n):
        x = k + 0.5
        b = mbs.CreateRigidBody(inertia=inertia, nodeType=node, referencePosition=[x, 0, 0],
                                initialAngularVelocity=[0, 0, spin], initialVelocity=[0, spin * x, 0], gravity=G)
        if joint == "spherical":
            mbs.CreateSphericalJoint(itemNumbers=[prev, b], position=[float(k), 0, 0])
        else:
            mbs.CreateRevoluteJoint(itemNumbers=[prev, b], position=[float(k), 0, 0], axis=[0, 1, 0])
        prev = b
    mbs.Assemble()
    return SC, mbs


def spring_body_with_load(node=EP):
    """A rigid body on a Cartesian spring-damper to ground with a time-dependent force."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    inertia = RigidBodyInertia(mass=2.0, inertiaTensor=np.diag([0.1, 0.2, 0.3]))
    b = mbs.CreateRigidBody(inertia=inertia, nodeType=node, referencePosition=[0, 0, 0],
                            initialAngularVelocity=[1.0, -2.0, 3.0], gravity=G)
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0.5, 0, 0]))
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b, localPosition=[0.2, 0.1, 0]))
    mbs.AddObject(ObjectConnectorCartesianSpringDamper(markerNumbers=[mG, mB], stiffness=[400, 300, 500],
                                                       damping=[1, 1, 1]))
    mF = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=[0, 0.3, 0]))
    mbs.AddLoad(LoadForceVector(markerNumber=mF, loadVector=[0, 0, 0],
                                loadVectorUserFunction=lambda mbs, t, load: [5 * np.sin(10 * t), 0, 2 * t]))
    mbs.Assemble()
    return SC, mbs


def mixed_with_point_mass(node=EP):
    """The heavy top plus a point mass hanging from its tip on a spring (vector-space block)."""
    SC, mbs, n = heavy_top(node, assemble=False)
    body = [i for i in range(mbs.systemData.NumberOfObjects()) if mbs.GetObject(i)["objectType"] == "RigidBody"][0]
    nP = mbs.AddNode(NodePoint(referenceCoordinates=[0, 1.5, -0.5], initialVelocities=[0.0, 0.0, 0.0]))
    mbs.AddObject(MassPoint(mass=0.5, nodeNumber=nP))
    mP = mbs.AddMarker(MarkerNodePosition(nodeNumber=nP))
    mT = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=[0, 0.5, 0]))
    mbs.AddObject(ObjectConnectorCartesianSpringDamper(markerNumbers=[mT, mP], stiffness=[200, 200, 200],
                                                       damping=[0.5, 0.5, 0.5]))
    mbs.AddLoad(LoadForceVector(markerNumber=mP, loadVector=[0, 0, -0.5 * 9.81]))
    mbs.Assemble()
    return SC, mbs


def settings(T, n, write=False, sensors=False):
    s = exu.SimulationSettings()
    s.timeIntegration.endTime = T
    s.timeIntegration.numberOfSteps = n
    s.timeIntegration.verboseMode = 0
    s.solution.file.write = write
    s.solution.sensors.active = sensors
    s.displayComputationTime = False
    return s


def total_q(mbs):
    sd = mbs.systemData
    return np.array(sd.GetODE2Coordinates()) + np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))
