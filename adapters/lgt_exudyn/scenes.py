"""Exudyn example scenes, built as Exudyn users build them (bench scenes and tests)."""
import exudyn as exu
import numpy as np
from exudyn.utilities import ObjectGround, RigidBodyInertia

from lgt_bridge.groups.batch import to_matrix
from lgt_bridge.scenes import principal_inertia

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
    """n links along x from a ground joint, spinning about the vertical (as scenes.chain);
    ``joint``: "spherical" (CreateSphericalJoint), "revolute" (CreateRevoluteJoint, about y:
    JointRevoluteZ) or "generic" (CreateGenericJoint, revolute about y)."""
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
        elif joint == "generic":            # revolute about y as a generic joint
            mbs.CreateGenericJoint(itemNumbers=[prev, b], position=[float(k), 0, 0], constrainedAxes=[1, 1, 1, 1, 0, 1])
        else:
            mbs.CreateRevoluteJoint(itemNumbers=[prev, b], position=[float(k), 0, 0], axis=[0, 1, 0])
        prev = b
    mbs.Assemble()
    return SC, mbs


def settings(T, n, write=False, sensors=False):
    s = exu.SimulationSettings()
    s.timeIntegration.endTime = T
    s.timeIntegration.numberOfSteps = n
    s.timeIntegration.verboseMode = 0
    s.solution.file.write = write
    s.solution.sensors.active = sensors
    if hasattr(s, "show"):                           # newer Exudyn; displayComputationTime is deprecated
        s.show.computationTime = False
    else:
        s.displayComputationTime = False
    return s


def total_q(mbs):
    sd = mbs.systemData
    return np.array(sd.GetODE2Coordinates()) + np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))


def free_bodies(n=8, node=ROTVEC, seed=0):
    """n torque-free bodies (no gravity) with random inertias, attitudes and spins, as
    lgt_bridge.scenes.free_bodies: the case Exudyn's explicit Lie group solvers handle."""
    rng = np.random.default_rng(seed)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    for _ in range(n):
        J = principal_inertia(rng)
        p = rng.normal(size=4)
        p /= np.linalg.norm(p)
        R = to_matrix(p[None])[0]
        mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=1.0, inertiaTensor=J), nodeType=node,
                            referencePosition=rng.normal(size=3), referenceRotationMatrix=R,
                            initialAngularVelocity=rng.normal(size=3) * 2.0, initialVelocity=rng.normal(size=3),
                            gravity=[0.0, 0.0, 0.0])
    mbs.Assemble()
    return SC, mbs



def ancf_pendulum(n=25, L=2.0, EI=1.0, rhoA=1.0):
    """A flexible pendulum as Exudyn's examples build it: n ObjectANCFCable2D elements
    (reduced integration, axial stiffness 1e4 EI) along x from a pinned end
    (``GenerateStraightLineANCFCable2D`` with fixedConstraintsNode0=[1, 1, 0, 0]: two
    CoordinateConstraints), falling under gravity along -y; 4 (n + 1) coordinates."""
    from exudyn.beams import GenerateStraightLineANCFCable2D
    from exudyn.utilities import ObjectANCFCable2D
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    mbs.AddObject(ObjectGround())
    cable = ObjectANCFCable2D(physicsMassPerLength=rhoA, physicsBendingStiffness=EI,
                              physicsAxialStiffness=EI * 1e4, useReducedOrderIntegration=True)
    GenerateStraightLineANCFCable2D(mbs, positionOfNode0=[0, 0, 0], positionOfNode1=[L, 0, 0], numberOfElements=n,
                                    cableTemplate=cable, massProportionalLoad=[0, -9.81, 0],
                                    fixedConstraintsNode0=[1, 1, 0, 0], fixedConstraintsNode1=[0, 0, 0, 0])
    mbs.Assemble()
    return SC, mbs
