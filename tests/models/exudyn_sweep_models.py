"""Models of the classes found by running Exudyn's own test models and examples through
``lgt-bridge run`` (issue 21: no raw numpy, scipy or Exudyn exception reaches a user),
written as Exudyn's users write them, each returning ``(mbs, simulationSettings)`` freshly
assembled.

- a spring-damper whose user function has the signature of an older Exudyn (no
  ``itemIndex`` argument): Exudyn raises when it calls it, before the first step
  (Exudyn's connectorRigidBodySpringDamperTest.py of an older version);
- a pre-step user function that raises in the middle of the run;
- a coordinate constraint driven by an offset user function (Exudyn's MiniExample
  ObjectConnectorCoordinate.py): one of an older signature raises while the bridge reads the
  constraint Jacobian, before the first step;
- a rigid body written as an ObjectGenericODE2 with Euler-parameter coordinates and mass and
  force user functions, its Euler-parameter norm a user-written CoordinateVectorConstraint
  (Exudyn's rigidBodyAsUserFunctionTest.py), next to the same body as an ObjectRigidBody;
- a double pendulum of two mass points in one ObjectGenericODE2 whose two length constraints
  are a CoordinateVectorConstraint's user functions, the constraint function ignoring its
  ``velocityLevel`` argument (Exudyn's coordinateVectorConstraintGenericODE2.py);
- an ALE cable (ObjectALEANCFCable2D elements sharing one ALE coordinate) whose ALE coordinate
  a CoordinateConstraint holds (Exudyn's ANCFmovingRigidBodyTest.py): its mass matrix is
  singular, positive definite only on the motions the constraints allow;
- a wheel of a mecanum car on its own (Exudyn's mecanumWheelRollingDiscTest.py): an
  ObjectConnectorRollingDiscPenalty with a 45° friction angle, rolling and slipping
  sideways, whose friction reads the slip velocity its PostNewton stored at the last step's
  end: the states move at every step without switching;
- a hanger sliding along an ANCF cable through an ObjectJointSliding2D (Exudyn's
  ANCFslidingJoint2D.py): its third algebraic coordinate is the sliding coordinate;
- a board on two wheels on RollingDiscPenalty contacts whose friction direction never
  settles in Exudyn's discontinuous iteration (Exudyn's createRollingDiscPenaltyTest.py);
- a spring-damper replicated by a LoadCoordinate that a PreNewtonResidualUserFunction sets
  from the state (Exudyn's mainSystemUserFunctionsTest.py);
- a ball on a floor triangle through an ObjectContactSphereTriangle with an impact model
  (Exudyn's sphereTriangleTest.py);
- a mass pulled across a rough floor whose stick/slip state a pre-step user function keeps in
  a data coordinate (Exudyn's lugreFrictionTest.py);
- a mass bouncing on a contact spring that a PostNewtonUserFunction switches through a data
  coordinate, reading Exudyn's step size from ``mbs.sys['dynamicSolver']`` (Exudyn's
  postNewtonStepContactTest.py).
"""
import numpy as np

import exudyn as exu
from exudyn.rigidBodyUtilities import (AngularVelocity2EulerParameters_t, EulerParameters2GLocal,
                                       Inertia6D2InertiaTensor, Skew, eulerParameters0)
from exudyn.utilities import (CoordinateConstraint, CoordinateSpringDamper, CoordinateVectorConstraint,
                              Gravity, MarkerBodyMass, MarkerNodeCoordinate, MarkerNodeCoordinates,
                              MarkerNodePosition, MarkerObjectODE2Coordinates, MassPoint, NodePoint,
                              NodePoint2D, NodePointGround, NodeRigidBodyEP, ObjectGenericODE2,
                              ObjectRigidBody, SensorNode, Force)

from exudyn_special_models import _system, settings  # the shared system and settings

from exudyn.utilities import (AddRigidBody, InertiaCylinder, MarkerBodyRigid, NodeGenericData,  # noqa: E402
                              ObjectConnectorRollingDiscPenalty, ObjectGround)


def _oscillator(mbs, **spring):
    """A mass point on a coordinate spring-damper to ground (x coordinate); its node."""
    ground = mbs.AddNode(NodePointGround())
    node = mbs.AddNode(NodePoint(referenceCoordinates=[1.0, 0, 0], initialVelocities=[0.1, 0, 0]))
    mbs.AddObject(MassPoint(mass=1.0, nodeNumber=node))
    m0 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    m1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
    mbs.AddObject(CoordinateSpringDamper(markerNumbers=[m0, m1], stiffness=100.0, damping=1.0, **spring))
    return node


def spring_with_old_user_function(t_end=0.1, n=10, acceleration_sensor=False):
    """The spring's force as a user function written for an older Exudyn, without
    ``itemIndex``: every call raises Exudyn's ModelError (a TypeError inside).
    ``acceleration_sensor``: the mass's acceleration recorded by a sensor (Exudyn then
    computes the initial accelerations itself, before the first step)."""
    mbs = _system()

    def force(mbs, t, u, v, k, d, offset):          # Exudyn < 1.2's signature
        return k * u + d * v

    node = _oscillator(mbs, springForceUserFunction=force)
    if acceleration_sensor:
        mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                 outputVariableType=exu.OutputVariableType.Acceleration))
    mbs.Assemble()
    return mbs, settings(t_end, n)


def prestep_raising_at(t_fail=0.05, t_end=0.1, n=10):
    """A pre-step user function (a controller as users write them) that raises ValueError
    once Exudyn's step time reaches ``t_fail``."""
    mbs = _system()
    _oscillator(mbs)

    def prestep(mbs, t):
        if t >= t_fail:
            raise ValueError(f"controller input missing at t = {t}")
        return True

    mbs.SetPreStepUserFunction(prestep)
    mbs.Assemble()
    return mbs, settings(t_end, n)


def driven_coordinate(old_signature=False, t_end=1.0, n=100):
    """A mass point whose x coordinate follows x_ref + offset(t), offset(t) =
    0.05 (1 - cos(π t / 2)), prescribed by a CoordinateConstraint's offset user function;
    ``old_signature``: the function as written for an older Exudyn (no ``itemNumber``), so
    every call raises. Returns (mbs, settings, node)."""
    mbs = _system()
    ground = mbs.AddNode(NodePointGround())
    node = mbs.AddNode(NodePoint(referenceCoordinates=[2.0, 0, 0]))
    mbs.AddObject(MassPoint(mass=5.0, nodeNumber=node))
    m0 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    m1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))

    def offset_old(mbs, t, lOffset):                 # the MiniExample's, no itemNumber
        return 0.5 * (1 - np.cos(2 * np.pi * 0.25 * t)) * lOffset

    def offset(mbs, t, itemNumber, lOffset):
        return offset_old(mbs, t, lOffset)

    mbs.AddObject(CoordinateConstraint(markerNumbers=[m0, m1], offset=0.1,
                                       offsetUserFunction=offset_old if old_signature else offset))
    mbs.Assemble()
    return mbs, settings(t_end, n), node


def rigid_body_as_user_function(t_end=0.05, n=50):
    """A spinning rigid body under gravity twice: as an ObjectRigidBody (Euler parameters)
    and as an ObjectGenericODE2 on a NodeRigidBodyEP without its own Euler-parameter
    constraint, the equations of motion in user functions (M = diag(m, m, m, Gᵀ J G),
    f = m g - Gᵀ ω̃ J ω) and the norm q·q = 1 as a CoordinateVectorConstraint with a
    quadratic term, as Exudyn's rigidBodyAsUserFunctionTest.py writes it. Returns (mbs,
    settings, node of the ObjectRigidBody, node of the user-function body)."""
    mbs = _system()
    mass, inertia6D, g = 2.0, [6, 1, 6, 0, 1, 0], 9.81
    omega0, v0 = [0, 50.0, 20], [0.2, 0.0, 0.0]
    ep_t0 = list(AngularVelocity2EulerParameters_t(omega0, eulerParameters0))
    n_rb = mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[0.5, 0, 0] + eulerParameters0,
                                       initialVelocities=v0 + ep_t0))
    o_rb = mbs.AddObject(ObjectRigidBody(mass=mass, inertia=inertia6D, nodeNumber=n_rb))
    mbs.AddLoad(Gravity(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=o_rb)), loadVector=[0, -g, 0]))

    q_ref = np.array([0.0, 0, 0] + eulerParameters0)
    n_uf = mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=q_ref, initialVelocities=v0 + ep_t0,
                                       addConstraintEquation=False))
    J = Inertia6D2InertiaTensor(inertia6D)
    f_g = np.array([0, -g * mass, 0] + [0] * 4)

    def force(mbs, t, itemIndex, q, q_t):
        G = EulerParameters2GLocal((np.array(q) + q_ref)[3:7])
        omega = G @ np.array(q_t)[3:7]
        f = f_g.copy()
        f[3:7] -= G.T @ Skew(omega) @ J @ omega
        return f

    def mass_matrix(mbs, t, itemIndex, q, q_t):
        G = EulerParameters2GLocal((np.array(q) + q_ref)[3:7])
        M = np.zeros((7, 7))
        M[0:3, 0:3] = mass * np.eye(3)
        M[3:7, 3:7] = G.T @ J @ G
        return M

    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[n_uf], forceUserFunction=force,
                                    massMatrixUserFunction=mass_matrix))
    ground = mbs.AddNode(NodePointGround())
    mbs.AddObject(CoordinateVectorConstraint(
        markerNumbers=[mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=ground)),
                       mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=n_uf))],
        scalingMarker0=[], scalingMarker1=[], quadraticTermMarker0=[],
        quadraticTermMarker1=np.array([[0, 0, 0, 1, 1, 1, 1]]), offset=[1]))
    mbs.Assemble()
    return mbs, settings(t_end, n), n_rb, n_uf


def pendulum_by_constraint_user_function(velocity_aware=False, velocity_row=False, t_end=0.5, n=500):
    """A double pendulum (links L = 0.8, masses 2.5 under gravity) of two NodePoint2D in one
    ObjectGenericODE2, its constraints |p0| = L and |p1 - p0| = L as a
    CoordinateVectorConstraint's constraint and Jacobian user functions. As Exudyn's test
    model writes it, the constraint function returns g whatever ``velocityLevel`` asks;
    ``velocity_aware``: it returns C_q q_t when velocityLevel is True. ``velocity_row``: the
    model also has a velocity-level CoordinateConstraint (a node held at rest in z, no
    effect on the motion). Returns (mbs, settings, node of the tip)."""
    mbs = _system()
    L, mass, g = 0.8, 2.5, 9.81
    n0 = mbs.AddNode(NodePoint2D(referenceCoordinates=[L, 0]))
    n1 = mbs.AddNode(NodePoint2D(referenceCoordinates=[2 * L, 0]))
    body = mbs.AddObject(ObjectGenericODE2(nodeNumbers=[n0, n1], massMatrix=mass * np.eye(4)))
    for node in (n0, n1):
        mbs.AddLoad(Force(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=node)),
                          loadVector=[0, -mass * g, 0]))

    def jacobian(mbs, t, itemNumber, q, q_t, velocityLevel):
        J = np.zeros((2, 4))
        J[0, 0:2] = np.array(q[0:2]) / np.linalg.norm(q[0:2])
        d = np.array(q[2:4]) - np.array(q[0:2])
        J[1, 0:2], J[1, 2:4] = -d / np.linalg.norm(d), d / np.linalg.norm(d)
        return J

    def constraint(mbs, t, itemNumber, q, q_t, velocityLevel):
        if velocityLevel and velocity_aware:
            return list(jacobian(mbs, t, itemNumber, q, q_t, True) @ np.array(q_t))
        return [np.sqrt(q[0] ** 2 + q[1] ** 2) - L, np.sqrt((q[2] - q[0]) ** 2 + (q[3] - q[1]) ** 2) - L]

    ground = mbs.AddNode(NodePointGround())
    mbs.AddObject(CoordinateVectorConstraint(
        markerNumbers=[mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=ground)),
                       mbs.AddMarker(MarkerObjectODE2Coordinates(objectNumber=body))],
        scalingMarker0=np.zeros((2, 4)), constraintUserFunction=constraint, jacobianUserFunction=jacobian))
    if velocity_row:
        n2 = mbs.AddNode(NodePoint(referenceCoordinates=[0, 0, 0]))
        mbs.AddObject(MassPoint(mass=1.0, nodeNumber=n2))
        mbs.AddObject(CoordinateConstraint(
            markerNumbers=[mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0)),
                           mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n2, coordinate=2))],
            velocityLevel=True))
    mbs.Assemble()
    return mbs, settings(t_end, n), n1


def ale_cable_held(n_elements=4, t_end=0.05, n=50):
    """A straight ALE cable under gravity, 10 m, ends pinned with fixed slopes
    (GenerateStraightLineANCFCable2D with an ALECable2D template on one NodeGenericODE2 ALE
    coordinate), the ALE coordinate held by a CoordinateConstraint to ground. Returns (mbs,
    settings, ALE node)."""
    from exudyn.beams import GenerateStraightLineANCFCable2D
    from exudyn.utilities import ALECable2D, NodeGenericODE2
    mbs = _system()
    ale = mbs.AddNode(NodeGenericODE2(numberOfODE2Coordinates=1, referenceCoordinates=[0],
                                      initialCoordinates=[0], initialCoordinates_t=[0]))
    cable = ALECable2D(physicsMassPerLength=6.96, physicsBendingStiffness=595.6, physicsAxialStiffness=9.67e6)
    cable.nodeNumbers[2] = ale
    GenerateStraightLineANCFCable2D(mbs, positionOfNode0=[0, 0, 0], positionOfNode1=[10, 0, 0],
                                    numberOfElements=n_elements, cableTemplate=cable,
                                    massProportionalLoad=[0, -9.81, 0],
                                    fixedConstraintsNode0=[1, 1, 0, 1], fixedConstraintsNode1=[1, 1, 0, 1])
    ground = mbs.AddNode(NodePointGround())
    mbs.AddObject(CoordinateConstraint(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ale, coordinate=0))]))
    mbs.Assemble()
    return mbs, settings(t_end, n), ale


def penalty_wheel(t_end=0.2, n=100):
    """(mbs, settings, node): a 0.3 m disc (EP node) rolling at 2 m/s and slipping sideways at
    0.5 m/s on the ground through a RollingDiscPenalty (k = 1e5, friction angle 45°), with
    the settings of Exudyn's mecanum-wheel test (discontinuous.iterationTolerance 0.1,
    ignoreMaxIterations False, spectral radius 0.5)."""
    mbs, r = _system(), 0.3
    inertia = InertiaCylinder(density=1000, length=0.1, outerRadius=r, axis=0)
    node, body = AddRigidBody(mainSys=mbs, inertia=inertia, nodeType=exu.NodeType.RotationEulerParameters,
                              position=[0, 0, r], velocity=[0.5, -2, 0], angularVelocity=[2 / r, 0, 0],
                              gravity=[0, 0, -9.81])
    ground = mbs.AddObject(ObjectGround())
    mg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    mw = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=[0, 0, 0]))
    nd = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0, 0], numberOfDataCoordinates=3))
    mbs.AddObject(ObjectConnectorRollingDiscPenalty(markerNumbers=[mg, mw], nodeNumber=nd, discRadius=r,
                                                    dryFriction=[1.0, 0.0], dryFrictionAngle=0.25 * np.pi,
                                                    dryFrictionProportionalZone=0.1, contactStiffness=1e5,
                                                    contactDamping=1e3))
    mbs.Assemble()
    s = settings(t_end, n)
    s.timeIntegration.generalizedAlpha.spectralRadius = 0.5
    s.timeIntegration.discontinuous.iterationTolerance = 0.1
    s.timeIntegration.discontinuous.ignoreMaxIterations = False
    return mbs, s, node


def slider_on_cable(t_end=0.05, n=100):
    """(mbs, settings, rigid node): a 2 m steel wire of three Cable2D elements, clamped at its
    left end, and a 0.12 kg hanger (RigidBody2D) riding on it through an ObjectJointSliding2D
    (MarkerBodyCable2DCoordinates per element, a NodeGenericData [element, sliding coordinate]),
    pushed along by a tenth of its weight (Exudyn's ANCFslidingJoint2D.py)."""
    from exudyn.utilities import (Cable2D, MarkerBodyCable2DCoordinates, MarkerBodyPosition, Point2DS1,
                                  Rigid2D, RigidBody2D, ObjectJointSliding2D)
    mbs, L, n_el, g = _system(), 2.0, 3, 9.81
    E, A, I, rho = 2.07e11, 1e-6, 1e-12 / 12, 7800
    le = L / n_el
    ground = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    nodes = [mbs.AddNode(Point2DS1(referenceCoordinates=[i * le, 0, 1, 0])) for i in range(n_el + 1)]
    cables = []
    for i in range(n_el):
        c = mbs.AddObject(Cable2D(physicsLength=le, physicsMassPerLength=rho * A, physicsBendingStiffness=E * I,
                                  physicsAxialStiffness=E * A, nodeNumbers=[nodes[i], nodes[i + 1]]))
        mbs.AddLoad(Gravity(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=c)), loadVector=[0, -g, 0]))
        cables.append(c)
    for c in (0, 1, 3):
        mbs.AddObject(CoordinateConstraint(markerNumbers=[
            mg, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))]))
    a, m = 0.1, 0.12
    s0 = 1.5 * le
    node = mbs.AddNode(Rigid2D(referenceCoordinates=[s0, -a, 0]))
    body = mbs.AddObject(RigidBody2D(physicsMass=m, physicsInertia=m / 12 * (2 * a) ** 2, nodeNumber=node))
    top = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[0, a, 0]))
    mbs.AddLoad(Force(markerNumber=mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[0, 0, 0])),
                      loadVector=[0.1 * m * g, -m * g, 0]))
    markers = [mbs.AddMarker(MarkerBodyCable2DCoordinates(bodyNumber=c)) for c in cables]
    data = mbs.AddNode(NodeGenericData(initialCoordinates=[1, s0], numberOfDataCoordinates=2))
    mbs.AddObject(ObjectJointSliding2D(markerNumbers=[top, markers[1]], slidingMarkerNumbers=markers,
                                       slidingMarkerOffsets=[i * le for i in range(n_el)], nodeNumber=data))
    mbs.Assemble()
    return mbs, settings(t_end, n), node


def penalty_two_wheeler(t_end=0.1, n=50):
    """(mbs, settings, wheel body): Exudyn's createRollingDiscPenaltyTest.py as written: a
    board on two wheels (CreateRigidBody, CreateRevoluteJoint) rolling at 4 rev/s on the
    ground through two CreateRollingDiscPenalty contacts (k = 1e5, d = 1e3, dry friction 0.4,
    no proportional zone), Exudyn's default discontinuous settings (maxIterations 5,
    ignoreMaxIterations True): the friction direction of a sticking wheel flips at every
    discontinuous iteration and never settles."""
    from exudyn.utilities import InertiaCuboid, ObjectGround, RigidBodyInertia
    mbs = _system()
    g, m, r, L = [0, 0, -9.81], 0.5, 0.1, 0.8
    omega0 = [0, 4 * 2 * np.pi, 0]
    v0 = Skew(omega0) @ [0, 0, r]
    ring = RigidBodyInertia(mass=1, inertiaTensor=np.diag([0.25 * m * r**2, 0.5 * m * r**2, 0.25 * m * r**2]))
    wheels = [mbs.CreateRigidBody(referencePosition=[x, 0, r], initialVelocity=v0, initialAngularVelocity=omega0,
                                  inertia=ring, gravity=g) for x in (-0.5 * L, 0.5 * L)]
    board = mbs.CreateRigidBody(referencePosition=[0, 0, 1.2 * r], initialVelocity=v0,
                                inertia=InertiaCuboid(2800, sideLengths=[L, 0.5 * r, 0.5 * r]), gravity=g)
    ground = mbs.AddObject(ObjectGround())
    for w in wheels:
        mbs.CreateRevoluteJoint(bodyNumbers=[w, board], position=[0, 0, 0], axis=[0, 1, 0], useGlobalFrame=False)
        mbs.CreateRollingDiscPenalty(bodyNumbers=[ground, w], axisPosition=[0, 0, 0], axisVector=[0, 1, 0],
                                     discRadius=r, contactStiffness=1e5, contactDamping=1e3, dryFriction=[0.4, 0.4])
    mbs.Assemble()
    s = settings(t_end, n)
    s.timeIntegration.newton.useModifiedNewton = True
    return mbs, s, wheels[0]


def residual_spring(t_end=0.5, n=500, raising=False):
    """(mbs, settings, node): Exudyn's mainSystemUserFunctionsTest.py, case
    ReplicateSpringDamper: a 4 kg Mass1D started 0.2 m out on a spring-damper (k = 12000,
    d = 20) that is no object but a LoadCoordinate whose load a PreNewtonResidualUserFunction
    sets from the node's displacement and velocity, with the SystemJacobianUserFunction of
    that force; ``raising``: the residual function fails (a typo) after t = 0.1."""
    from exudyn.utilities import LoadCoordinate, Mass1D, Node1D
    mbs, k, d = _system(), 12000.0, 20.0
    node = mbs.AddNode(Node1D(referenceCoordinates=[0], initialCoordinates=[0.2]))
    mbs.AddObject(Mass1D(nodeNumber=node, mass=4.0, referencePosition=[0, 1.2, 0]))
    marker = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
    load = mbs.AddLoad(LoadCoordinate(markerNumber=marker, load=0))
    mbs.Assemble()

    def residual(mbs, t, newtonIt, discontinuousIt):
        if raising and t > 0.1:
            return mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinate)    # the user's typo
        u = mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates)
        v = mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates_t)
        mbs.SetLoadParameter(load, "load", (-k * u - d * v))
    mbs.SetPreNewtonResidualUserFunction(residual)
    row = mbs.GetNodeODE2Index(node)

    def jacobian(mbs, t, factorODE2, factorODE2_t, factorODE1):
        mc = exu.MatrixContainer()
        mc.SetWithSparseMatrix([[row, row, -factorODE2 * k - factorODE2_t * d]], 1, 1)
        return mc
    mbs.SetSystemJacobianUserFunction(jacobian)
    mbs.Assemble()
    s = settings(t_end, n)
    s.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
    return mbs, s, node


def post_newton_contact(t_end=0.5, n=100):
    """(mbs, settings, node): Exudyn's postNewtonStepContactTest.py: a 0.25 kg mass point
    dropped at 1 m/s from 0.01 m above a contact spring (k = 20000) that a CoordinateSpringDamper's
    force user function switches on while a data coordinate is 1; a PostNewtonUserFunction sets
    it from the penetration and returns [error, recommended step] computed from the solver's
    current step size (``mbs.sys['dynamicSolver'].it.currentStepSize``); the script's settings
    (discontinuous maxIterations 1, ignoreMaxIterations False, minimumStepSize 1e-10, ...)."""
    from exudyn.utilities import LoadCoordinate, Point
    mbs, L, r, g, m, k = _system(), 0.5, 0.05, 9.81, 0.25, 20000.0
    mbs.AddNode(NodeGenericData(initialCoordinates=[0], numberOfDataCoordinates=1))
    node = mbs.AddNode(Point(referenceCoordinates=[0, L, 0], initialCoordinates=[0, r - L + 0.01, 0],
                             initialVelocities=[0, -1, 0]))

    def spring_force(mbs, t, itemIndex, u, v, k, d, offset, *args):
        return k * (L + u - r) if mbs.systemData.GetDataCoordinates()[0] == 1 else 0

    def post_newton(mbs, t):
        Pos, SOS = exu.OutputVariableType.Position, exu.ConfigurationType.StartOfStep
        p0 = mbs.GetNodeOutput(node, Pos, configuration=SOS)[1] - r
        p = mbs.GetNodeOutput(node, Pos)[1] - r
        h = mbs.sys["dynamicSolver"].it.currentStepSize
        d = mbs.systemData.GetDataCoordinates()
        d0 = mbs.systemData.GetDataCoordinates(configuration=SOS)
        error, step = 0, -1
        if (p < 0) == (d0[0] == 0):             # the contact closed or opened in this step
            error = abs(p)
            step = h * abs(p0) / (abs(p0) + abs(p)) if p0 > 0 else 0.25 * h
            d[0] = 1 if p < 0 else 0
        mbs.systemData.SetDataCoordinates(d)
        return [error, step]
    mbs.SetPostNewtonUserFunction(post_newton)
    mbs.AddObject(MassPoint(physicsMass=m, nodeNumber=node))
    ground = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    mn = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=1))
    mbs.AddObject(CoordinateSpringDamper(markerNumbers=[mg, mn], stiffness=k, springForceUserFunction=spring_force))
    mbs.AddLoad(LoadCoordinate(markerNumber=mn, load=-m * g))
    mbs.Assemble()
    s = settings(t_end, n)
    s.timeIntegration.discontinuous.iterationTolerance = 1e-8
    s.timeIntegration.discontinuous.maxIterations = 1
    s.timeIntegration.discontinuous.ignoreMaxIterations = False
    s.timeIntegration.minimumStepSize = 1e-10
    s.timeIntegration.adaptiveStepRecoverySteps = 0
    s.timeIntegration.adaptiveStepIncrease = 10
    s.timeIntegration.generalizedAlpha.spectralRadius = 1
    return mbs, s, node


def sphere_on_triangle(impact_model=2):
    """(mbs, settings): Exudyn's sphereTriangleTest.py with one ball: a 0.1 m sphere
    (CreateRigidBody) 1 cm above a floor triangle, ObjectContactSphereTriangle with
    ``impact_model`` (restitution 0.5, friction 0.2, k = 1e5)."""
    from exudyn.utilities import InertiaSphere, MarkerBodyRigid, ObjectContactSphereTriangle
    mbs, r, a = _system(), 0.1, 0.25
    ground = mbs.CreateGround()
    ball = mbs.CreateRigidBody(referencePosition=[0.2, 0.2, 1.1 * r], initialVelocity=[1.2, 0, 0],
                               inertia=InertiaSphere(mass=1.6, radius=r), gravity=[0, 0, -10])
    data = mbs.AddNode(NodeGenericData(initialCoordinates=[0.1, 0, 0, 0], numberOfDataCoordinates=4))
    mbs.AddObject(ObjectContactSphereTriangle(
        markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=ball)), mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))],
        nodeNumber=data, trianglePoints=exu.Vector3DList([[-a, -a, 0], [2 * a, -a, 0], [-a, 2 * a, 0]]),
        sphereRadius=r, contactStiffness=1e5, dynamicFriction=0.2, impactModel=impact_model,
        restitutionCoefficient=0.5))
    mbs.Assemble()
    return mbs, settings(0.1, 500)


def prestep_stick_slip(t_end=1.5, n=3000, speed=1.0):
    """(mbs, settings, node): Exudyn's lugreFrictionTest.py (its useLugrePos case), pulled
    ``speed`` times faster: a 1 kg Mass1D on a rough floor, pulled by a spring (K = 2) whose
    end moves at 0.1·speed m/s; the friction is a CoordinateSpringDamper force user function
    reading a data coordinate [stick, sticking position]: a stiff bristle spring (1e5) while
    sticking, a Stribeck force while slipping. A pre-step user function decides stick or slip
    from the state and writes the data coordinates."""
    from exudyn.utilities import Mass1D, Node1D
    mbs, M, K, s0, s2, Fc, Fs, Vs = _system(), 1.0, 2.0, 1e5, 0.4, 1.0, 1.5, 1e-3
    s1 = np.sqrt(s0)
    node = mbs.AddNode(Node1D(referenceCoordinates=[0], initialCoordinates=[0.], initialVelocities=[0.]))
    mbs.AddObject(Mass1D(nodeNumber=node, physicsMass=M))
    data = mbs.AddNode(NodeGenericData(initialCoordinates=[1, 0], numberOfDataCoordinates=2))
    mn = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
    floor = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))

    def friction(mbs, t, itemNumber, u, v, k, d, offset, *args):
        d0 = mbs.GetNodeOutput(data, variableType=exu.OutputVariableType.Coordinates)
        if d0[0] == 1:
            F = s0 * (u - d0[1]) + s1 * v
        else:
            F = np.sign(v) * (Fc + (Fs - Fc) * np.exp(-(v / Vs) ** 2))
        return d * v + F
    rough = mbs.AddObject(CoordinateSpringDamper(markerNumbers=[floor, mn], stiffness=s0, damping=s2,
                                                 springForceUserFunction=friction))
    pull_node = mbs.AddNode(NodePointGround())
    pull = mbs.AddObject(CoordinateSpringDamper(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=pull_node, coordinate=0)), mn], stiffness=K, damping=0))

    def prestep(mbs, t):
        U = 0.1 * speed * t
        mbs.SetNodeParameter(pull_node, "referenceCoordinates", [U, 0., 0.])
        mbs.SetObjectParameter(pull, "offset", U)
        u = mbs.GetObjectOutput(rough, variableType=exu.OutputVariableType.Displacement)
        v = mbs.GetObjectOutput(rough, variableType=exu.OutputVariableType.Velocity)
        F = Fc + (Fs - Fc) * np.exp(-(v / Vs) ** 2)
        d0 = mbs.systemData.GetDataCoordinates()
        if d0[0] == 1 and abs(s0 * (u - d0[1]) + s1 * v) > F:
            d0[0] = 0
        elif d0[0] == 0 and (np.sign(v) != np.sign(F) or abs(s0 * (u - d0[1]) + s1 * v) < F):
            d0[0] = 1
        if d0[0] == 0:
            d0[1] = u
        mbs.systemData.SetDataCoordinates(d0)
        return True
    mbs.SetPreStepUserFunction(prestep)
    mbs.Assemble()
    s = settings(t_end, n)
    s.timeIntegration.absoluteTolerance = s.timeIntegration.relativeTolerance = 1e-6
    return mbs, s, node
