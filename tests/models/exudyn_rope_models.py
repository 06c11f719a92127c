"""A rope over a roll, written as Exudyn's users write it (Exudyn's reevingSystemOpen.py in
small): an open rope of ANCFCable2D elements laid over a roll along a reeving curve
(exudyn.beams.CreateReevingCurve, PointsAndSlopes2ANCFCable2D), a mass point hanging at each
end, in contact with the roll through a GeneralContact (a sphere marker and the cables, zero
half height). The rope starts lying on the roll at zero gap, so the contact active sets
switch back and forth at once (they chatter).

And a pipe conveying fluid, written as Exudyn's ALEANCF_pipe.py writes it: ALECable2D elements
sharing one ALE coordinate whose velocity a velocity-level CoordinateConstraint holds at the
fluid speed, the pipe clamped at its left end, hanging under gravity."""
import numpy as np
import exudyn as exu
from exudyn.utilities import (ALECable2D, Cable2D, CoordinateConstraint, Force, Gravity, MarkerBodyMass,
                              MarkerBodyPosition, MarkerBodyRigid, MarkerNodeCoordinate, NodeGenericODE2,
                              NodePoint2DSlope1, NodePointGround, ObjectGround, ObjectMassPoint2D)
from exudyn.beams import CreateReevingCurve, PointsAndSlopes2ANCFCable2D

from exudyn_special_models import settings  # (the shared settings)


def rope_over_roll(n_nodes=12, t_end=0.05, steps=100):
    """(mbs, simulationSettings): the rope of n_nodes ANCF nodes over a roll of radius 0.45 m
    (the reeving curve runs around three circles; the middle one is the roll), 2 kg at each
    end, contact stiffness 1e5 N/m, damping 200 N·s/m, no friction; Exudyn's generalized-α at
    ``steps`` steps to ``t_end``."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    R = 0.45
    circles = [[[0, -1.5], R, 'L'], [[0, 0], R, 'L'], [[1, -1.5], R, 'L']]
    reeving = CreateReevingCurve(circles, removeLastLine=False, numberOfANCFnodes=n_nodes, graphicsNodeSize=0.01)
    E, rho, b = 1e9, 1000, 0.002
    A, I = b * b, b**4 / 12
    cable = Cable2D(physicsMassPerLength=rho * A, physicsBendingStiffness=E * I, physicsAxialStiffness=E * A,
                    physicsBendingDamping=1e-3 * E * I, physicsAxialDamping=1e-2 * E * A)
    g = np.array([0, -9.81, 0])
    ancf = PointsAndSlopes2ANCFCable2D(mbs, reeving['ancfPointsSlopes'], reeving['elementLengths'], cable,
                                       massProportionalLoad=g, firstNodeIsLastNode=False)
    for node in (ancf[0][0], ancf[0][-1]):
        m = mbs.AddObject(ObjectMassPoint2D(physicsMass=2, nodeNumber=node))
        mbs.AddLoad(Force(markerNumber=mbs.AddMarker(MarkerBodyPosition(bodyNumber=m)), loadVector=2 * g))
    gc = mbs.AddGeneralContact()
    gc.SetSearchTreeCellSize(numberOfCells=[8, 8, 1])
    ground = mbs.AddObject(ObjectGround())
    roll = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    gc.AddSphereWithMarker(roll, radius=R, contactStiffness=1e5, contactDamping=200, frictionMaterialIndex=0)
    for o in ancf[1]:
        gc.AddANCFCable(objectIndex=o, halfHeight=0, contactStiffness=1e5, contactDamping=200, frictionMaterialIndex=0)
    gc.SetFrictionPairings(np.zeros((1, 1)))
    mbs.Assemble()
    return mbs, settings(t_end, steps)


def ale_pipe(moving_mass_factor=1.0, n_elements=4, t_end=0.1, steps=100):
    """(mbs, simulationSettings, ALE node): Exudyn's ALEANCF_pipe.py with fewer elements: a 1 m
    pipe (EI 10, EA 1e6, 10 kg/m, physicsMovingMassFactor ``moving_mass_factor``) of
    ALECable2D elements, fluid speed 10 m/s held by a velocity-level CoordinateConstraint on the
    ALE coordinate, clamped at x = 0 (position and slope), gravity 0.981 m/s²; Exudyn's
    generalized-α at ``steps`` steps to ``t_end``. With the factor 1 all of the pipe's mass moves
    with the fluid and the mass matrix is singular (an ALE motion and an axial motion of the
    straight pipe carry the same kinetic energy); the constraints hold that direction."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    L, v_ale = 1.0, 10.0
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    m_ground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    ale = mbs.AddNode(NodeGenericODE2(numberOfODE2Coordinates=1, referenceCoordinates=[0], initialCoordinates=[0],
                                      initialCoordinates_t=[v_ale]))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[m_ground, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ale, coordinate=0))],
                                       offset=v_ale, velocityLevel=True))
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[L * i / n_elements, 0, 1, 0]))
             for i in range(n_elements + 1)]
    for i in range(n_elements):
        e = mbs.AddObject(ALECable2D(physicsLength=L / n_elements, physicsMassPerLength=10, physicsBendingStiffness=10,
                                     physicsAxialStiffness=1e6, physicsMovingMassFactor=moving_mass_factor,
                                     nodeNumbers=[nodes[i], nodes[i + 1], ale]))
        mbs.AddLoad(Gravity(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=e)), loadVector=[0, -0.981, 0]))
    for c in (0, 1, 3):
        mbs.AddObject(CoordinateConstraint(markerNumbers=[m_ground, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0],
                                                                                                      coordinate=c))]))
    mbs.Assemble()
    return mbs, settings(t_end, steps), ale
