"""A ball bearing as Exudyn's TestModels/ballBearingTest.py builds it (issue 21): a shaft on
an Rxyz node held at a constant spin by a velocity-level CoordinateConstraint, its inner ring
carrying balls through ObjectContactSphereTorus contacts with regularised friction
(``frictionProportionalZone``) to the ground's outer ring, the balls kept apart by a cage of
spring-dampers (exudyn.machines.CreateBallBearing). The shaft starts spinning the other way
round from the constraint's (the script's own signs), so the first step reverses it and the
balls' contacts slip hard: the case where generalized-α's Newton matrix, differenced with a
step sized for the positions, moved a ball's spin by 1e3 rad/s and Newton bounced."""
import numpy as np

import exudyn as exu
from exudyn.machines import CreateBallBearing, GetBallBearingData
from exudyn.utilities import InertiaCylinder, MarkerBodyRigid

from exudyn_special_models import _system, settings  # the shared system and settings


def ball_bearing(n_balls=5, t_end=0.002, n=20):
    """(mbs, settings, shaft body): ballBearingTest.py with ``n_balls`` balls (the script has
    14), its contact parameters, cage springs, tolerances and step 1e-4 s."""
    mbs = _system()
    axis, omega, gravity = [0, 0, 1], 4 * np.pi, [0, -9.81, 0]
    data = GetBallBearingData(axis, 0.080, 0.050, 0.016, n_balls, radiusBalls=0.00873 / 2, ballsAngleOffset=0,
                              radiusCage=0.0325, innerGrooveRadius=0.00873 / 2 * 1.25,
                              outerGrooveRadius=0.00873 / 2 * 1.25, innerEdgeChamfer=0.001,
                              outerEdgeChamfer=0.001, innerRingShoulderRadius=0.029875,
                              outerRingShoulderRadius=0.035125)
    ground = mbs.CreateGround()
    m_outer = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    shaft = mbs.CreateRigidBody(referencePosition=[0, 0, 0], nodeType=exu.NodeType.RotationRxyz,
                                inertia=InertiaCylinder(7800, 0.120, 0.025, axis=2),
                                initialAngularVelocity=[0, 0, omega], gravity=gravity)
    mbs.CreateCoordinateConstraint(itemNumbers=[shaft, None], coordinates=[5, None], velocityLevel=True,
                                   offset=omega, show=False)
    m_inner = mbs.AddMarker(MarkerBodyRigid(bodyNumber=shaft, localPosition=[0, 0, 0]))
    data['radiusBalls'] *= 1.01
    CreateBallBearing(mbs, data, m_inner, m_outer, 7800, 7800, cageInitialAngularVelocity=[0, 0, 0],
                      ballsInitialAngularVelocity=[0, 0, 0], gravity=gravity, springStiffnessCage=1e5,
                      springDampingCage=1e2,
                      contactParametersRingBalls={'contactStiffness': 5e6, 'contactDamping': 50,
                                                  'dynamicFriction': 0.2, 'contactStiffnessExponent': 1,
                                                  'frictionProportionalZone': 1e-2})
    mbs.Assemble()
    s = settings(t_end, n)
    s.timeIntegration.newton.absoluteTolerance = 1e-8
    s.timeIntegration.newton.relativeTolerance = 1e-6
    s.timeIntegration.newton.useModifiedNewton = True
    s.linearSolverType = exu.LinearSolverType.EigenSparse
    return mbs, s, shaft
