"""Exudyn models for the adapter tests, written as Exudyn users write them (the scenes
shared with the bench live in lgt_exudyn.scenes)."""
import exudyn as exu
import numpy as np
from exudyn.utilities import (MarkerNodePosition, MassPoint, NodePoint, ObjectConnectorCartesianSpringDamper,
                              ObjectGround, RigidBodyInertia, MarkerBodyRigid, LoadForceVector,
                              MarkerBodyPosition)
from lgt_exudyn.scenes import EP, G, ROTVEC, RXYZ, chain, heavy_top, settings, total_q  # noqa: F401


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


