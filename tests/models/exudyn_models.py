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




def _bar(mbs, a, b, node, spin=0.0, inertia_scale=1.0):
    """A rigid bar from point a to point b (its node at the middle, its x axis along it)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    x = (b - a) / np.linalg.norm(b - a)
    y = np.cross([0.3, 0.5, 0.8], x)
    y /= np.linalg.norm(y)
    R = np.column_stack([x, y, np.cross(x, y)])
    L = np.linalg.norm(b - a)
    inertia = RigidBodyInertia(mass=inertia_scale, inertiaTensor=np.diag([1e-3, L * L / 12, L * L / 12]) * inertia_scale)
    return mbs.CreateRigidBody(inertia=inertia, nodeType=node, referencePosition=0.5 * (a + b),
                               referenceRotationMatrix=R, initialAngularVelocity=[spin, 0, 0], gravity=G), L


def _spherical(mbs, bodyA, bodyB, point, ground=None):
    """A spherical joint as users write it with markers: MarkerBodyPosition on each side."""
    from exudyn.utilities import ObjectJointSpherical
    def marker(body):
        if body is None:
            return mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground[0], localPosition=list(point)))
        o = mbs.GetObject(body)
        n = mbs.GetNode(o["nodeNumber"])
        ref = np.asarray(n["referenceCoordinates"], float)
        R = np.array(mbs.GetNodeOutput(o["nodeNumber"], exu.OutputVariableType.RotationMatrix,
                                       exu.ConfigurationType.Reference)).reshape(3, 3)
        return mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=list(R.T @ (np.asarray(point) - ref[:3]))))
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[marker(bodyA), marker(bodyB)]))


def spherical_tree(node=EP, length=2):
    """A tree of bars on spherical joints: a trunk hanging from the ground, three branches of
    ``length`` bars from its lower end (bars along varied directions, varied spins)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    trunk, _ = _bar(mbs, [0, 0, 0], [0.2, 0.1, -1.0], node, spin=1.0)
    mbs.CreateSphericalJoint(itemNumbers=[ground, trunk], position=[0, 0, 0])
    tip = np.array([0.2, 0.1, -1.0])
    for k, d in enumerate(([1.0, 0.0, -0.3], [-0.5, 0.8, -0.2], [-0.4, -0.9, 0.1])):
        d = np.asarray(d) / np.linalg.norm(d)
        prev, a = trunk, tip
        for j in range(length):
            b = a + (0.7 if j == 0 else 0.5) * d + [0, 0, -0.3 * (j > 0)]
            bar, _ = _bar(mbs, a, b, node, spin=0.5 * k - 0.7 * j)
            mbs.CreateSphericalJoint(itemNumbers=[prev, bar], position=list(a))
            prev, a = bar, b
    mbs.Assemble()
    return SC, mbs


def spherical_loop(node=EP):
    """A closed loop: three bars ground - b1 - b2 - b3 - ground on four spherical joints
    (markers added by hand, as in Exudyn's own examples), not in one plane."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    P = [np.array(p, float) for p in ([0, 0, 0], [0, 1, 0], [1, 1.1, 0.5], [1.2, 0, 0])]
    bars = [_bar(mbs, P[k], P[k + 1], node, spin=0.3 * k)[0] for k in range(3)]
    _spherical(mbs, None, bars[0], P[0], (ground,))
    _spherical(mbs, bars[0], bars[1], P[1])
    _spherical(mbs, bars[1], bars[2], P[2])
    _spherical(mbs, bars[2], None, P[3], (ground,))
    mbs.Assemble()
    return SC, mbs


#: constrainedAxes of the generic joints of :func:`generic_chain`: revolute about z and about
#: x, universal, free translations in the joint frame (with 3, 2 and 1 rotations locked), a ball
GENERIC_AXES = ([1, 1, 1, 1, 1, 0], [1, 1, 1, 0, 1, 1], [1, 1, 1, 1, 0, 0], [0, 1, 1, 1, 1, 1],
                [1, 0, 1, 1, 0, 1], [1, 1, 0, 0, 1, 0], [1, 1, 1, 0, 0, 0])


def generic_chain(node=EP, axes=GENERIC_AXES, extra=True):
    """An open chain of bars on generic joints (CreateGenericJoint, one ``axes`` pattern each,
    their frames tilted by rotationMatrixAxes), hung from a ground object placed and turned
    away from the origin with the ground as the joint's second item; ``extra``: a revolute
    (CreateRevoluteJoint: JointRevoluteZ) and a prismatic joint (CreatePrismaticJoint:
    JointPrismaticX) further down. Not at rest, not consistent with its joints (A and γ are
    defined everywhere)."""
    from exudyn.utilities import RotationMatrixX, RotationMatrixZ
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround(referencePosition=[0.3, -0.2, 0.1],
                                        referenceRotation=RotationMatrixZ(0.4) @ RotationMatrixX(0.3)))
    a = np.zeros(3)
    d = np.array([0.8, 0.3, -0.4])
    prev = ground
    for k, ax in enumerate(list(axes) + ([None, None] if extra else [])):
        b = a + d
        bar, _ = _bar(mbs, a, b, node, spin=0.4 * k - 1.0)
        if ax is None and k == len(axes):
            mbs.CreateRevoluteJoint(itemNumbers=[prev, bar], position=list(a), axis=[0.2, 0.3, 1.0])
        elif ax is None:
            mbs.CreatePrismaticJoint(itemNumbers=[prev, bar], position=list(a), axis=list(d))
        else:
            items = [bar, prev] if prev == ground else [prev, bar]
            mbs.CreateGenericJoint(itemNumbers=items, position=list(a), constrainedAxes=ax,
                                   rotationMatrixAxes=RotationMatrixX(0.3 * k) @ RotationMatrixZ(0.2))
        prev, a = bar, b
        d = np.array([d[1], -d[2], d[0]]) * 0.9
    mbs.Assemble()
    return SC, mbs


def point_mass_on_joint(node=EP):
    """A bar on a spherical joint to the ground with a point mass (NodePoint, MassPoint) held
    at its tip by a spherical joint on a node marker: rows on vector-space coordinates."""
    from exudyn.utilities import ObjectJointSpherical
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    bar, _ = _bar(mbs, [0, 0, 0], [1.0, 0.2, -0.3], node, spin=1.0)
    mbs.CreateSphericalJoint(itemNumbers=[ground, bar], position=[0, 0, 0])
    nP = mbs.AddNode(NodePoint(referenceCoordinates=[1.0, 0.2, -0.3], initialVelocities=[0.0, 0.5, 0.0]))
    mbs.AddObject(MassPoint(mass=0.5, nodeNumber=nP))
    mP = mbs.AddMarker(MarkerNodePosition(nodeNumber=nP))
    mT = mbs.AddMarker(MarkerBodyPosition(bodyNumber=bar, localPosition=[0.5 * np.linalg.norm([1.0, 0.2, -0.3]), 0, 0]))
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[mT, mP]))
    mbs.AddLoad(LoadForceVector(markerNumber=mP, loadVector=[0, 0, -0.5 * 9.81]))
    mbs.Assemble()
    return SC, mbs


def welded_pair(node=EP):
    """Two bars, the first on a spherical joint to the ground, the second welded to it by a
    generic joint with every axis locked and ``alternativeConstraints`` (rotation rows the
    kernels do not write in closed form)."""
    from exudyn.utilities import GenericJoint
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    b1, _ = _bar(mbs, [0, 0, 0], [1.0, 0.0, -0.2], node, spin=1.0)
    b2, _ = _bar(mbs, [1.0, 0.0, -0.2], [1.5, 0.6, -0.4], node, spin=1.0)
    mbs.CreateSphericalJoint(itemNumbers=[ground, b1], position=[0, 0, 0])
    m1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b1, localPosition=[0.5 * np.hypot(1.0, 0.2), 0, 0]))
    m2 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b2, localPosition=[-0.5 * np.linalg.norm([0.5, 0.6, -0.2]), 0, 0]))
    mbs.AddObject(GenericJoint(markerNumbers=[m1, m2], constrainedAxes=[1, 1, 1, 1, 1, 1], alternativeConstraints=True))
    mbs.Assemble()
    return SC, mbs


def random_states(m, rng, n=3):
    """Random states near q0 (Rxyz nodes kept away from gimbal lock)."""
    out = []
    while len(out) < n:
        q = m._moved(m.q0, rng.normal(size=m.nv) * 0.5, 1.0)
        if any(typ == "RigidBodyRxyz" and abs(np.cos(q[idx[4]])) < 0.3 for typ, idx, _ in m.kinds):
            continue
        out.append((q, rng.normal(size=m.nv) * 3.0, float(rng.uniform(0, 1))))
    return out


def tree_with_masses(n_masses=3):
    """Free mass points (the first held in y by a CoordinateConstraint) next to a two-link
    KinematicTree pendulum, whose mass matrix depends on its joint angles (Exudyn's
    serialRobotKinematicTreeDigging.py: a robot as a KinematicTree among particles): a
    configuration-dependent M̄ made of small diagonal blocks and one 2 x 2 block."""
    from exudyn.utilities import HTtranslate, InertiaRodX, TreeLink
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    masses = [mbs.CreateMassPoint(referencePosition=[1.0 + i, 0, 0], initialVelocity=[0, 0.1 * i, 0.2],
                                  physicsMass=0.5 + i, gravity=[0, -9.81, 0]) for i in range(n_masses)]
    mbs.CreateCoordinateConstraint(bodyNumbers=[None, masses[0]], coordinates=[None, 1])
    L = 0.5
    links = [TreeLink(linkInertia=InertiaRodX(1.0, L).Translated([L / 2, 0, 0]), jointType=exu.JointType.RevoluteZ,
                      jointHT=HTtranslate([L if k else 0.0, 0, 0]), parent=k - 1) for k in range(2)]
    mbs.CreateKinematicTree(listOfTreeLinks=links, gravity=[0, -9.81, 0], referenceCoordinates=[0.0, 0.0],
                            initialCoordinates=[0.3, -0.4], initialCoordinates_t=[1.0, -2.0])
    mbs.Assemble()
    return SC, mbs
