"""Penalty contacts whose force acts while the gap their PostNewton stored is closed (Exudyn's
active set strategy), written as Exudyn's users write them, each returning ``(mbs,
simulationSettings, node)`` freshly assembled:

- a mass point dropped onto a floor through an ObjectContactCoordinate (Exudyn's
  contactCoordinateTest.py);
- a barrel-shaped roll dropped onto the floor, tilted, through an ObjectContactConvexRoll
  (Exudyn's ConvexContactTest.py, without its spin and friction);
- a disc (2-D rigid body) dropped onto a floor of eight segments through an
  ObjectContactCurveCircles, rolling over the segments' ends (Exudyn's chainDriveExample.py
  and contactCurveExample.py: rollers on a sprocket's polygon);
- a pin sliding down a bowl of segments through an ObjectContactCurveCircles, in contact all
  along (Exudyn's contactCurvePolynomial.py);
- a coin dropped rolling onto the ground through an ObjectConnectorRollingDiscPenalty with
  regularized dry friction (Exudyn's rollingCoinPenaltyTest.py).
"""
import numpy as np

import exudyn as exu
from exudyn.utilities import (InertiaCylinder, MarkerBodyRigid, MarkerNodeCoordinate, MarkerNodeRigid,
                              MassPoint, LoadCoordinate, NodeGenericData, NodePoint, NodePointGround,
                              ObjectContactConvexRoll, ObjectContactCoordinate, ObjectContactCurveCircles,
                              ObjectGround, RotationMatrixY)


from exudyn_special_models import settings as _settings  # noqa: E402  (the shared settings)


def mass_on_coordinate_contact(t_end=0.2, n=100):
    """A 0.25 kg mass point 5 cm above a contact spring (1e5 N/m, 20 Ns/m) on its y
    coordinate, falling under its weight; it bounces about three times."""
    mbs = exu.SystemContainer().AddSystem()
    data = mbs.AddNode(NodeGenericData(initialCoordinates=[1], numberOfDataCoordinates=1))
    node = mbs.AddNode(NodePoint(referenceCoordinates=[0, 0, 0], initialCoordinates=[0, 0.1, 0]))
    mbs.AddObject(MassPoint(mass=0.25, nodeNumber=node))
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    m_ground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    m_y = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=1))
    mbs.AddObject(ObjectContactCoordinate(markerNumbers=[m_ground, m_y], nodeNumber=data,
                                          contactStiffness=1e5, contactDamping=20, offset=0.05))
    mbs.AddLoad(LoadCoordinate(markerNumber=m_y, load=-0.25 * 9.81))
    mbs.Assemble()
    return mbs, _settings(t_end, n), node


def convex_roll_dropped(t_end=0.1, n=200):
    """A steel roll 10 cm long with a parabolic hull (radius 16.5 mm at its middle), tilted by
    π/16 and released 2 cm above the floor (Euler-parameter node); no friction."""
    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddObject(ObjectGround())
    m_ground = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))
    roll = mbs.CreateRigidBody(inertia=InertiaCylinder(density=7800, length=0.1, outerRadius=3e-3, axis=0),
                               referencePosition=[0, 0, 0.02], referenceRotationMatrix=RotationMatrixY(np.pi / 16),
                               gravity=[0, 0, -9.81], nodeType=exu.NodeType.RotationEulerParameters)
    node = mbs.GetObject(roll)["nodeNumber"]
    data = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0, 0], numberOfDataCoordinates=3))
    m_roll = mbs.AddMarker(MarkerNodeRigid(nodeNumber=node))
    mbs.AddObject(ObjectContactConvexRoll(markerNumbers=[m_ground, m_roll], nodeNumber=data,
                                          contactStiffness=1e3, contactDamping=1, dynamicFriction=0,
                                          rollLength=0.1, coefficientsHull=[-3.6, 0, 1.65e-2]))
    mbs.Assemble()
    return mbs, _settings(t_end, n), node


def disc_on_curve(t_end=0.3, n=300):
    """A disc of radius 5 cm (2-D rigid body) released 5 cm above a floor of eight segments
    with 0.3 m/s sideways; it bounces on the contact spring (1e4 N/m, 2 Ns/m) and rolls over
    from one segment to the next (no friction)."""
    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.CreateGround()
    m_ground = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))
    r = 0.05
    disc = mbs.CreateRigidBody(referencePosition=[0.013, 0.1, 0], initialVelocity=[0.3, 0, 0],
                               inertia=InertiaCylinder(density=1000, length=0.02, outerRadius=r, axis=2),
                               gravity=[0, -9.81, 0], create2D=True)
    m_disc = mbs.AddMarker(MarkerBodyRigid(bodyNumber=disc))
    xs = np.linspace(0.5, -0.5, 9)          # right to left: the exterior (above) is on the right
    segments = np.array([[xs[i], 0.0, xs[i + 1], 0.0] for i in range(len(xs) - 1)])
    data = mbs.AddNode(NodeGenericData(initialCoordinates=[-1, 0, 0] * len(segments),
                                       numberOfDataCoordinates=3 * len(segments)))
    mbs.AddObject(ObjectContactCurveCircles(markerNumbers=[m_ground, m_disc], nodeNumber=data, circlesRadii=[r],
                                            segmentsData=exu.MatrixContainer(segments),
                                            contactStiffness=1e4, contactDamping=2))
    mbs.Assemble()
    return mbs, _settings(t_end, n), mbs.GetObject(disc)["nodeNumber"]


def pin_in_polygon_bowl(t_end=0.3, n=300, segments=32):
    """A pin of radius 2 cm (2-D rigid body, 1 kg) released against the wall of a bowl of
    radius 0.5 m drawn as ``segments`` segments (Exudyn's contactCurvePolynomial.py: a pin on a
    circular arc); it slides down and up the other side in continuous contact (1e6 N/m,
    1e3 Ns/m, no friction), from one segment to the next."""
    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.CreateGround()
    m_ground = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))
    R, r = 0.5, 0.02
    pin = mbs.CreateRigidBody(referencePosition=[(R - r) * np.sin(1.2), -(R - r) * np.cos(1.2) + 0.002, 0],
                              inertia=InertiaCylinder(density=4e4, length=0.02, outerRadius=r, axis=2),
                              gravity=[0, -9.81, 0], create2D=True)
    m_pin = mbs.AddMarker(MarkerBodyRigid(bodyNumber=pin))
    phi = np.linspace(-0.5 * np.pi, 0.5 * np.pi, segments + 1)
    pts = np.array([R * np.sin(phi), -R * np.cos(phi)]).T
    seg = np.hstack([pts[1:], pts[:-1]])    # each from its right end to its left: the inside is the exterior
    data = mbs.AddNode(NodeGenericData(initialCoordinates=[-1, 0, 0] * segments, numberOfDataCoordinates=3 * segments))
    mbs.AddObject(ObjectContactCurveCircles(markerNumbers=[m_ground, m_pin], nodeNumber=data, circlesRadii=[r],
                                            segmentsData=exu.MatrixContainer(seg),
                                            contactStiffness=1e6, contactDamping=1e3))
    mbs.Assemble()
    return mbs, _settings(t_end, n), mbs.GetObject(pin)["nodeNumber"]


def coin_dropped(t_end=0.5, n=5000):
    """(mbs, settings, contact object): Exudyn's rollingCoinPenaltyTest.py as written: a 1 kg
    coin of radius 1 cm (EP node), nicked 5°, rolling at 40 rad/s, released 1 cm above the
    ground; an ObjectConnectorRollingDiscPenalty (k = 1e5, d = 1e4, dry friction 0.8 with a
    proportional zone of 1e-2 m/s, viscous rolling friction) on a NodeGenericData holds its
    slip velocity and gap; Newmark, index-2 constraints, spectral radius 0.5. It touches
    down at 0.045 s; the output is the contact point (``OutputVariableType.Position``)."""
    from exudyn.utilities import AddRigidBody, ObjectConnectorRollingDiscPenalty, RigidBodyInertia, Skew
    mbs = exu.SystemContainer().AddSystem()
    phi0, m, r = 5.0 / 180.0 * np.pi, 1.0, 0.01
    p0 = [r * np.sin(phi0), 0, r * np.cos(phi0) + 0.01]
    rotation = RotationMatrixY(phi0)
    omega0 = [40, 0, 0]
    v0 = Skew(omega0) @ rotation @ [0, 0, r]
    inertia = RigidBodyInertia(mass=m, inertiaTensor=np.diag([0.5 * m * r**2, 0.25 * m * r**2, 0.25 * m * r**2]))
    _, body = AddRigidBody(mainSys=mbs, inertia=inertia, nodeType=str(exu.NodeType.RotationEulerParameters),
                           position=p0, rotationMatrix=rotation, angularVelocity=omega0, velocity=v0,
                           gravity=[0, 0, -9.81])
    ground = mbs.AddObject(ObjectGround())
    mg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    mc = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=[0, 0, 0]))
    data = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0, 0], numberOfDataCoordinates=3))
    contact = mbs.AddObject(ObjectConnectorRollingDiscPenalty(
        markerNumbers=[mg, mc], nodeNumber=data, discRadius=r, dryFriction=[0.8, 0.8],
        dryFrictionProportionalZone=1e-2, rollingFrictionViscous=0.2, contactStiffness=1e5, contactDamping=1e4))
    mbs.Assemble()
    s = _settings(t_end, n)
    ga = s.timeIntegration.generalizedAlpha
    ga.useIndex2Constraints = ga.useNewmark = True
    ga.spectralRadius = 0.5
    ga.computeInitialAccelerations = True
    return mbs, s, contact
