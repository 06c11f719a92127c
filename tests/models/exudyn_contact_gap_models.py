"""Penalty contacts whose force acts while the gap their PostNewton stored is closed (Exudyn's
active set strategy), written as Exudyn's users write them, each returning ``(mbs,
simulationSettings, node)`` freshly assembled:

- a mass point dropped onto a floor through an ObjectContactCoordinate (Exudyn's
  contactCoordinateTest.py);
- a barrel-shaped roll dropped onto the floor, tilted, through an ObjectContactConvexRoll
  (Exudyn's ConvexContactTest.py, without its spin and friction).
"""
import numpy as np

import exudyn as exu
from exudyn.utilities import (InertiaCylinder, MarkerBodyRigid, MarkerNodeCoordinate, MarkerNodeRigid,
                              MassPoint, LoadCoordinate, NodeGenericData, NodePoint, NodePointGround,
                              ObjectContactConvexRoll, ObjectContactCoordinate, ObjectGround, RotationMatrixY)


def _settings(t_end, n):
    s = exu.SimulationSettings()
    s.timeIntegration.numberOfSteps = n
    s.timeIntegration.endTime = t_end
    s.timeIntegration.verboseMode = 0
    s.solution.file.write = False
    return s


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
