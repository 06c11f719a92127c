"""A rope over a roll, written as Exudyn's users write it (Exudyn's reevingSystemOpen.py in
small): an open rope of ANCFCable2D elements laid over a roll along a reeving curve
(exudyn.beams.CreateReevingCurve, PointsAndSlopes2ANCFCable2D), a mass point hanging at each
end, in contact with the roll through a GeneralContact (a sphere marker and the cables, zero
half height). The rope starts lying on the roll at zero gap, so the contact active sets
switch back and forth at once (they chatter)."""
import numpy as np
import exudyn as exu
from exudyn.utilities import (Cable2D, Force, MarkerBodyPosition, MarkerBodyRigid, ObjectGround,
                              ObjectMassPoint2D)
from exudyn.beams import CreateReevingCurve, PointsAndSlopes2ANCFCable2D


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
    s = exu.SimulationSettings()
    s.timeIntegration.endTime = t_end
    s.timeIntegration.numberOfSteps = steps
    s.solutionSettings.writeSolutionToFile = False
    s.timeIntegration.verboseMode = 0
    return mbs, s
