"""Models of issue 21's solver classes (Exudyn items 2, 3, 6, 9, 10), written as Exudyn's
users write them (Exudyn's own test models and examples are the pattern), each returning
``(mbs, simulationSettings)`` freshly assembled.

  2  ANCF cable and ANCF beam with damping (Exudyn's ANCFCableBeamDampingTest pattern)
  4  GeneralContact: spheres on a triangle floor
  3  the IFToMM double four-bar (Exudyn's fourBarMechanismIftomm.py pattern), a crank-rocker
     four-bar away from singular configurations, a pendulum copied by pickling, a slider
     and bar whose torque a user function switches on at endTime (pickleCopyMbs.py's)
  6  a load pulse much shorter than the run (automaticStepSize's maximum step)
  9  a long chain of rigid bodies on spherical joints (genalpha's Newton test)
  10 stiff models for an explicit method: a 1e7 N/m spring chain; Newton's cradle; Coulomb
     friction as sign(v) in a spring's user function
"""
import exudyn as exu
import numpy as np
from exudyn.beams import GenerateStraightLineANCFCable2D
from exudyn.utilities import (Cable2D, CoordinateSpringDamper, InertiaRodX, LoadForceVector, LoadMassProportional, MarkerBodyMass,
                              MarkerBodyPosition, MarkerNodeCoordinate, MarkerBodyRigid, MarkerNodePosition, MarkerNodeRigid,
                              MassPoint,
                              NodePoint, NodePointGround,
                              NodePointSlope23, NodeRigidBody2D, ObjectANCFBeam, ObjectConnectorSpringDamper,
                              ObjectGround, RevoluteJoint2D, RigidBody2D)

G2 = [0.0, -9.81, 0.0]


from exudyn_special_models import _system, settings  # noqa: E402  (the shared system and settings)


# ---------------------------------------------------------------------------- item 2
_CABLE = dict(l=0.5, massPerLength=2.0, d=0.02, E=1e8, beta=0.02, betaAxial=0.0005)


def _section():
    c = _CABLE
    r = c["d"] / 2
    A, I = np.pi * r ** 2, np.pi * r ** 4 / 4
    rho = c["massPerLength"] / A
    return rho * A, rho * I, c["E"] * A, c["E"] * I


def ancf_cable_damped(elements=4, load=(0.0, -5.0, 0.0)):
    """The ANCF cable half of Exudyn's ANCFCableBeamDampingTest: a Cable2D template with
    bending and axial (Rayleigh) damping meshed by GenerateStraightLineANCFCable2D, clamped
    at node 0 (fixedConstraintsNode0=[1]*4), a tip load. Returns (mbs, settings, tip node)."""
    mbs = _system()
    rhoA, rhoI, EA, EI = _section()
    c = _CABLE
    mbs.CreateGround(referencePosition=[0, 0, 0])
    template = Cable2D(physicsMassPerLength=rhoA, physicsBendingStiffness=EI, physicsAxialStiffness=EA,
                       physicsBendingDamping=c["beta"] * EI, physicsAxialDamping=c["betaAxial"] * EA,
                       useReducedOrderIntegration=0)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        nodes = GenerateStraightLineANCFCable2D(mbs, positionOfNode0=[0, 0, 0], positionOfNode1=[c["l"], 0, 0],
                                                fixedConstraintsNode0=[1] * 4, numberOfElements=elements,
                                                cableTemplate=template)[0]
    tip = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1]))
    mbs.AddLoad(LoadForceVector(markerNumber=tip, loadVector=list(load)))
    mbs.Assemble()
    return mbs, settings(0.1, 25), nodes[-1]


def ancf_beam_zero_torsion_inertia(elements=4, torsion_inertia=0.0):
    """The ANCF beam half of the same test: ObjectANCFBeam on NodePointSlope23 with
    sectionData.inertia = diag(torsion_inertia, ρI, ρI) (by default no torsional inertia) and
    a damping matrix, clamped by a generic joint: its mass matrix is singular (three
    directions of each node's slopes carry no mass, with any torsion_inertia)."""
    mbs = _system()
    rhoA, rhoI, EA, EI = _section()
    c = _CABLE
    ground = mbs.CreateGround(referencePosition=[0, 0, 0])
    sec = exu.BeamSection()
    sec.stiffnessMatrix = np.diag([EA, EA, EA, EA, EI, EI])
    sec.inertia = np.diag([torsion_inertia, rhoI, rhoI])
    sec.massPerLength = rhoA
    sec.dampingMatrix = np.diag([EA * c["betaAxial"], 0, 0, 0, EI * c["beta"], EI * c["beta"]])
    le = c["l"] / elements
    rot = [0, 1, 0, 0, 0, 1]
    n0 = mbs.AddNode(NodePointSlope23(referenceCoordinates=[0, 0, 1] + rot))
    markers = [mbs.AddMarker(MarkerNodeRigid(nodeNumber=n0))]
    for k in range(elements):
        n1 = mbs.AddNode(NodePointSlope23(referenceCoordinates=[le * (k + 1), 0, 1] + rot))
        markers.append(mbs.AddMarker(MarkerNodeRigid(nodeNumber=n1)))
        mbs.AddObject(ObjectANCFBeam(nodeNumbers=[n0, n1], physicsLength=le, sectionData=sec,
                                     crossSectionPenaltyFactor=[1] * 3))
        n0 = n1
    mbs.CreateGenericJoint(itemNumbers=[ground, markers[0]])
    mbs.AddLoad(LoadForceVector(markerNumber=markers[-1], loadVector=[0, -5, 0]))
    mbs.Assemble()
    return mbs, settings(0.1, 25)


# ---------------------------------------------------------------------------- item 3
def iftomm_double_fourbar(t_end=1.0, n=100):
    """Exudyn's fourBarMechanismIftomm.py: five NodeRigidBody2D bars (m = 1, L = 1,
    InertiaRodX) on seven RevoluteJoint2D, a double parallelogram (redundant constraints,
    a singular position when the bars lie flat), gravity by LoadMassProportional, started
    with v0 = 1."""
    mbs = _system()
    L, v0, mass = 1.0, 1.0, 1.0
    inertia = InertiaRodX(mass, L)
    ref = [[0, 0.5 * L, 0.5 * np.pi], [0.5 * L, L, 0], [L, 0.5 * L, 0.5 * np.pi], [1.5 * L, L, 0],
           [2 * L, 0.5 * L, 0.5 * np.pi]]
    vel = [[0.5 * v0, 0, -v0 / L], [v0, 0, 0], [0.5 * v0, 0, -v0 / L], [v0, 0, 0], [0.5 * v0, 0, -v0 / L]]
    m0, m1 = [], []
    for r, v in zip(ref, vel):
        nd = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=r, initialVelocities=v))
        ob = mbs.AddObject(RigidBody2D(nodeNumber=nd, physicsMass=inertia.mass,
                                       physicsInertia=inertia.inertiaTensor[2, 2]))
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=ob)), loadVector=G2))
        m0.append(mbs.AddMarker(MarkerBodyPosition(bodyNumber=ob, localPosition=[-0.5 * L, 0, 0])))
        m1.append(mbs.AddMarker(MarkerBodyPosition(bodyNumber=ob, localPosition=[0.5 * L, 0, 0])))
    ground = mbs.AddObject(ObjectGround())
    g = [mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[x, 0, 0])) for x in (0, L, 2 * L)]
    for a, b in ((g[0], m0[0]), (g[1], m0[2]), (g[2], m0[4]), (m1[0], m0[1]), (m1[1], m0[3]), (m1[2], m0[3]),
                 (m1[3], m1[4])):
        mbs.AddObject(RevoluteJoint2D(markerNumbers=[a, b]))
    mbs.Assemble()
    return mbs, settings(t_end, n)


def crank_rocker_fourbar(t_end=1.0, n=100, theta0=np.pi / 3, omega0=4.0):
    """A single-loop four-bar away from any singular configuration: a Grashof crank-rocker
    (crank a = 0.2, coupler b = 0.6, rocker c = 0.5, ground d = 0.5; s + l = 0.8 < p + q = 1.0,
    so its four links are never in line) of three NodeRigidBody2D bars (InertiaRodX, 1 kg/m)
    on four RevoluteJoint2D, under gravity, the crank started at theta0 with omega0 and the
    other bars with the velocities the loop allows (a consistent start)."""
    mbs = _system()
    a, b, c, d = 0.2, 0.6, 0.5, 0.5
    A, D = np.array([0.0, 0.0]), np.array([d, 0.0])
    B = a * np.array([np.cos(theta0), np.sin(theta0)])
    e = D - B                                   # C on both circles |C - B| = b, |C - D| = c (upper)
    L = np.linalg.norm(e)
    x = (b ** 2 - c ** 2 + L ** 2) / (2 * L)
    C = B + x * e / L + np.sqrt(b ** 2 - x ** 2) * np.array([-e[1], e[0]]) / L
    vB = omega0 * np.array([-B[1], B[0]])       # w2 x (C - B) - w3 x (C - D) = -vB
    perp = lambda r: np.array([-r[1], r[0]])  # noqa: E731
    w2, w3 = np.linalg.solve(np.column_stack([perp(C - B), -perp(C - D)]), -vB)
    bars = [(A, B, omega0, np.zeros(2)), (B, C, w2, vB), (D, C, w3, np.zeros(2))]
    ends = []
    for p0, p1, w, v0 in bars:
        r = p1 - p0
        length = np.linalg.norm(r)
        inertia = InertiaRodX(length, length)                  # 1 kg/m
        mid = 0.5 * (p0 + p1)
        vmid = v0 + w * perp(mid - p0)
        nd = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[mid[0], mid[1], np.arctan2(r[1], r[0])],
                                         initialVelocities=[vmid[0], vmid[1], w]))
        ob = mbs.AddObject(RigidBody2D(nodeNumber=nd, physicsMass=inertia.mass,
                                       physicsInertia=inertia.inertiaTensor[2, 2]))
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=ob)), loadVector=G2))
        ends.append([mbs.AddMarker(MarkerBodyPosition(bodyNumber=ob, localPosition=[s * 0.5 * length, 0, 0]))
                     for s in (-1, 1)])
    ground = mbs.AddObject(ObjectGround())
    gA, gD = [mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[p[0], p[1], 0])) for p in (A, D)]
    for m0, m1 in ((gA, ends[0][0]), (ends[0][1], ends[1][0]), (ends[1][1], ends[2][1]), (gD, ends[2][0])):
        mbs.AddObject(RevoluteJoint2D(markerNumbers=[m0, m1]))
    mbs.Assemble()
    return mbs, settings(t_end, n)


# ---------------------------------------------------------------------------- item 4
def general_contact_spheres(k=1e4, d=10.0):
    """Two mass points (0.1 kg) as spheres (r = 0.1) of an Exudyn GeneralContact with a ground
    floor of two triangles (AddSphereWithMarker, AddTrianglesRigidBodyBased, as
    generalContactSpheresTest and the triangle-mesh tests write it), falling at 1 m/s under
    gravity from 0.25 and 0.55 m: the first touches the floor at t ≈ 0.1 s and settles, the
    second bounces. Returns (mbs, settings)."""
    mbs = _spheres_on_floor([[0.3 * i, 0.25 + 0.3 * i, 0] for i in range(2)], k, d)
    return mbs, settings(0.5, 500)


# ---------------------------------------------------------------------------- item 6
PULSE = dict(t_on=10.01, length=0.05, force=40.0, mass=1.0, t_end=50.0, n=1000)


def load_pulse():
    """A free mass point and a load user function that acts for 0.05 s in a 50 s run
    (1000 Exudyn steps of 0.05 s): the velocity after the pulse is exactly F·0.05/m = 2,
    the end position 2·(t_end − t_on − 0.025). Returns (mbs, settings, node)."""
    p = PULSE
    mbs = _system()
    nd = mbs.AddNode(NodePoint(referenceCoordinates=[0, 0, 0]))
    mbs.AddObject(MassPoint(mass=p["mass"], nodeNumber=nd))
    mk = mbs.AddMarker(MarkerNodePosition(nodeNumber=nd))

    def load(mbs, t, load):
        return [p["force"] if p["t_on"] <= t < p["t_on"] + p["length"] else 0.0, 0, 0]

    mbs.AddLoad(LoadForceVector(markerNumber=mk, loadVector=[0, 0, 0], loadVectorUserFunction=load))
    mbs.Assemble()
    return mbs, settings(p["t_end"], p["n"]), nd


def load_pulse_exact():
    p = PULSE
    v = p["force"] * p["length"] / p["mass"]
    return v, v * (p["t_end"] - p["t_on"] - 0.5 * p["length"])


# ---------------------------------------------------------------------------- item 10
def stiff_spring_chain(n=5, k=1e7, t_end=1.0, steps=100, damping=10.0, hanging=False):
    """A chain of n mass points (1 kg) on ObjectConnectorSpringDamper springs of stiffness k
    (1e7 N/m: a period of 2 ms), the first hung from ground, under gravity: laid out along x
    (it swings down), or ``hanging`` along -y (it only stretches)."""
    mbs = _system()
    ground = mbs.AddObject(ObjectGround())
    prev = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
    for i in range(n):
        at = [0, -0.1 * (i + 1), 0] if hanging else [0.1 * (i + 1), 0, 0]
        nd = mbs.AddNode(NodePoint(referenceCoordinates=at))
        mbs.AddObject(MassPoint(mass=1.0, nodeNumber=nd))
        mk = mbs.AddMarker(MarkerNodePosition(nodeNumber=nd))
        mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[prev, mk], stiffness=k, damping=damping,
                                                  referenceLength=0.1))
        mbs.AddLoad(LoadForceVector(markerNumber=mk, loadVector=[0, -9.81, 0]))
        prev = mk
    mbs.Assemble()
    return mbs, settings(t_end, steps)


FRICTION = dict(m=1.0, k=100.0, F=1.5, x0=0.1)


def coulomb_friction_oscillator(t_end=2.0, steps=200, v_eps=None):
    """A mass point on a spring with Coulomb (dry) friction, written as Exudyn users write it:
    a CoordinateSpringDamper on the x coordinate whose springForceUserFunction returns
    k·u + F·sign(v) (a force that jumps at v = 0). Released from x0 = 0.1 at rest: the
    amplitude falls by 2F/k = 0.03 each half period π/ω (ω = 10 rad/s), 0.1 → −0.07 → 0.04
    → −0.01, where |k x| = 1 N < F: it sticks at x = −0.01 from t = 3π/10 on (exact).
    ``v_eps``: regularized instead, F·tanh(v/v_eps) (smooth, and stiff for small v_eps).
    Returns (mbs, settings, node)."""
    p = FRICTION
    mbs = _system()
    nd = mbs.AddNode(NodePoint(referenceCoordinates=[0, 0, 0], initialCoordinates=[p["x0"], 0, 0]))
    mbs.AddObject(MassPoint(mass=p["m"], nodeNumber=nd))
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    mx = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nd, coordinate=0))

    def force(mbs, t, itemNumber, u, v, k, d, offset):
        return k * (u - offset) + d * v + p["F"] * (np.sign(v) if v_eps is None else np.tanh(v / v_eps))

    mbs.AddObject(CoordinateSpringDamper(markerNumbers=[mg, mx], stiffness=p["k"], damping=0.0,
                                         springForceUserFunction=force))
    mbs.Assemble()
    return mbs, settings(t_end, steps), nd


def coulomb_friction_exact(t):
    """x(t) of :func:`coulomb_friction_oscillator` (the piecewise cosine, then sticking)."""
    p = FRICTION
    w = np.sqrt(p["k"] / p["m"])
    d = p["F"] / p["k"]
    x, t0 = p["x0"], 0.0
    while abs(x) * p["k"] > p["F"]:
        c = np.sign(x) * d                       # the centre of this half period (friction against v)
        if t < t0 + np.pi / w:
            return c + (x - c) * np.cos(w * (t - t0))
        x, t0 = 2 * c - x, t0 + np.pi / w
    return x


def pendulum():
    """A rigid bar (EP node, InertiaCuboid) on a revolute joint to ground, swinging under
    gravity, built with CreateRigidBody/CreateRevoluteJoint."""
    from exudyn.utilities import InertiaCuboid
    mbs = _system()
    ground = mbs.CreateGround()
    bar = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [1, 0.1, 0.1]), referencePosition=[0.5, 0, 0],
                              gravity=G2, initialAngularVelocity=[0, 0, 2.0], initialVelocity=[0, 1.0, 0])
    mbs.CreateRevoluteJoint(bodyNumbers=[ground, bar], position=[0, 0, 0], axis=[0, 0, 1])
    mbs.Assemble()
    return mbs, settings(2.0, 100)


def pickled_pendulum():
    """The pendulum copied by pickling, as users copy a system (parameter studies): the copy
    is appended to a new SystemContainer and assembled again."""
    import pickle
    mbs0, s = pendulum()
    mbs = pickle.loads(pickle.dumps(mbs0))
    SC = exu.SystemContainer()
    SC.AppendSystem(mbs)
    mbs.sys["_SC"] = SC
    mbs.Assemble()
    return mbs, s


def slider_torque_at_end(t_end=1.0, steps=1000, switched=True):
    """Exudyn's pickleCopyMbs.py model: a block on a prismatic joint to ground carrying a bar
    on a revolute joint (CreateRigidBody, CreatePrismaticJoint, CreateRevoluteJoint), both
    moving at 1 m/s, the bar spinning at 4π rad/s; a torque user function on the bar,
    ``np.heaviside(t - 1, 1)``, switches on at t = 1, the script's endTime (with
    ``switched=False`` the same model without it)."""
    from exudyn.utilities import InertiaCuboid
    mbs = _system()
    L, w = 0.5, 0.05
    ground = mbs.CreateGround()
    p0, s0 = np.array([0.5, 1, 0]), [0.5 * L, L, 0.2 * L]
    b0 = mbs.CreateRigidBody(referencePosition=p0, initialVelocity=[0, 1, 0], inertia=InertiaCuboid(500, s0))
    p1 = p0 + [0, 0.5 * L, 0.5 * s0[2] + w]
    b1 = mbs.CreateRigidBody(referencePosition=p1, initialVelocity=[0, 1, 0], initialAngularVelocity=[0, 0, 4 * np.pi],
                             inertia=InertiaCuboid(1000, [w, L, w]))
    mbs.CreateRevoluteJoint(bodyNumbers=[b0, b1], position=p1 - [0, 0.5 * L, 0.5 * w], axis=[0, 0, 1])
    mbs.CreatePrismaticJoint(bodyNumbers=[ground, b0], position=p0, axis=[0, 1, 0])

    def torque(mbs, t, load):
        return [0, 0, -np.heaviside(t - 1, 1) * 2 * np.cos(2 * np.pi * t) if switched else 0.0]
    mbs.CreateTorque(bodyNumber=b1, loadVector=[0, 0, 0], loadVectorUserFunction=torque)
    mbs.Assemble()
    return mbs, settings(t_end, steps)


# ---------------------------------------------------------------------------- item 9
def rigid_chain(n=40, node=exu.NodeType.RotationEulerParameters, t_end=0.5, steps=100, L=0.1, origin=0.0):
    """A chain of n rigid links (length L, steel bars, InertiaCuboid) on spherical joints, hung from
    ground at one end, started horizontal and falling under gravity (CreateRigidBody,
    CreateSphericalJoint, as Exudyn's chain examples build it)."""
    from exudyn.utilities import InertiaCuboid
    mbs = _system()
    ground = mbs.CreateGround()
    prev = ground
    for i in range(n):
        body = mbs.CreateRigidBody(inertia=InertiaCuboid(7800, [L, 0.02, 0.05]),
                                   nodeType=node, referencePosition=[origin + (i + 0.5) * L, 0, 0], gravity=G2)
        mbs.CreateSphericalJoint(bodyNumbers=[prev, body], position=[origin + i * L, 0, 0])
        prev = body
    mbs.Assemble()
    return mbs, settings(t_end, steps)


def newtons_cradle(n=3, impact_model=2, restitution=0.9, t_end=0.2, steps=200, gap=0.0):
    """Newton's cradle: n balls (r = 0.05 m, 1 kg mass points, CreateMassPoint) hanging as
    pendulums (CreateDistanceConstraint to ground, 1 m) in a row along x, touching; the
    first is released from 0.2 m to the side with 1 m/s towards the others. Neighbours meet
    by CreateSphereSphereContact with an impact model (impactModel 2: Gonthier / Carvalho-
    Martins, restitution coefficient) and contact stiffness 1e6 N/m."""
    mbs = _system()
    r, length = 0.05, 1.0
    ground = mbs.CreateGround()
    balls = []
    for i in range(n):
        x = 2 * r * i + (i > 0) * gap
        start = [x - (0.2 if i == 0 else 0.0), -length, 0]
        ball = mbs.CreateMassPoint(referencePosition=start, initialVelocity=[1.0 if i == 0 else 0.0, 0, 0],
                                   physicsMass=1.0, gravity=G2)
        mbs.CreateDistanceConstraint(bodyNumbers=[ground, ball], localPosition0=[x, 0, 0],
                                     distance=None)
        balls.append(ball)
    for a, b in zip(balls, balls[1:]):
        mbs.CreateSphereSphereContact(itemNumbers=[a, b], spheresRadii=[r, r], contactStiffness=1e6,
                                      contactDamping=0.0, impactModel=impact_model,
                                      restitutionCoefficient=restitution)
    mbs.Assemble()
    return mbs, settings(t_end, steps), balls


def general_contact_column(n=3, k=1e4, d=10.0, t_end=0.4, steps=400):
    """A column of n mass points (0.1 kg) as GeneralContact spheres (r = 0.1) over a triangle
    floor, as Exudyn's generalContactSpheresTest writes its spheres (AddSphereWithMarker on
    MarkerNodePosition, sphere-sphere contact on): dropped at 1 m/s, 0.25 m apart, away from
    the floor's diagonal edge; the lowest bounces on the floor and knocks the others up.
    Returns (mbs, settings); heights in ``COLUMN`` (x = 0.5, z = 0.2 for all)."""
    mbs = _spheres_on_floor([[0.5, COLUMN["y0"] + COLUMN["dy"] * i, 0.2] for i in range(n)], k, d)
    return mbs, settings(t_end, steps)


COLUMN = dict(y0=0.15, dy=0.25)


def _spheres_on_floor(positions, k, d):
    """The assembled system: mass points (0.1 kg) at ``positions`` falling at 1 m/s under
    gravity, as spheres (r = 0.1) of one GeneralContact with a floor of two triangles
    (contact stiffness k, damping d, no friction)."""
    mbs = _system()
    gc = mbs.AddGeneralContact()
    gc.verboseMode = 0
    for p in positions:
        nd = mbs.AddNode(NodePoint(referenceCoordinates=list(p), initialVelocities=[0, -1, 0]))
        mbs.AddObject(MassPoint(mass=0.1, nodeNumber=nd))
        mk = mbs.AddMarker(MarkerNodePosition(nodeNumber=nd))
        mbs.AddLoad(LoadForceVector(markerNumber=mk, loadVector=[0, -0.981, 0]))
        gc.AddSphereWithMarker(mk, radius=0.1, contactStiffness=k, contactDamping=d, frictionMaterialIndex=0)
    ground = mbs.AddObject(ObjectGround())
    mg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))
    gc.AddTrianglesRigidBodyBased(rigidBodyMarkerIndex=mg, contactStiffness=k, contactDamping=d,
                                  frictionMaterialIndex=0, pointList=[[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]],
                                  triangleList=[[0, 2, 1], [0, 3, 2]])
    gc.SetFrictionPairings(0.0 * np.eye(1))
    gc.SetSearchTreeCellSize(numberOfCells=[4, 4, 4])
    mbs.Assemble()
    return mbs
