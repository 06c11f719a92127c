"""Exudyn joint models for the bridge, written as Exudyn users write them, and Exudyn's
own converged solution of each as the reference.

Three classes of models that a plain KKT solve on Exudyn's C_q does not handle:

* ``inactive``: joints with zeros in ``constrainedAxes`` (spherical joint free along x,
  generic joints with free rotation axes, an ``exudyn.robotics`` serial robot). Exudyn
  keeps such an equation and writes it as λᵢ = 0: a zero row of C_q.
* ``redundant``: closed loops of 3-D joints (four-bar, slider-crank), whose C_q has
  dependent rows (``mbs.ComputeSystemDegreeOfFreedom()['redundantConstraints'] > 0``).
* ``inconsistent``: initial states that violate the velocity (four-bar) or position
  (slider-crank) constraints; Exudyn's index-3 generalized-α corrects them in its
  first step, and its refined solution is the motion from the state projected onto
  the constraints.

``Case.build()`` returns ``(mbs, simulationSettings)`` freshly assembled on every
call, as the user's script sets them up. ``exudyn_reference(case)`` runs Exudyn's own
generalized-α with step doubling and Richardson extrapolation and returns the final
state (``state_at_end``) with the agreement reached. Verified facts behind the choices:

* Exudyn's limit h → 0 from violated velocities is the motion from the kinetic-energy-
  orthogonal projection of the velocities (2nd-order convergence, the same for EP and
  RotVecLG nodes). From violated positions it converges at 1st order only, to the motion
  from ``project_like_exudyn``: a closest point in the metric of each node's own
  coordinates, which differs between EP and RotVecLG nodes (3.7e-4 here). The reference
  of such a case integrates from that projected state (2nd order).
* Redundant loops need ``linearSolver.solverType = EigenDense`` with
  ``ignoreSingularJacobian = True`` (as Exudyn's fourBarMechanism3D.py); EXUdense warns
  "using zero initial accelerations" and then stops on the singular Jacobian.
"""
import functools
import time
from dataclasses import dataclass
from typing import Callable

import exudyn as exu
import numpy as np
from exudyn.utilities import (GenericJoint, InertiaCuboid, LoadTorqueVector, MarkerBodyRigid, ObjectGround,
                              ObjectJointPrismaticX, ObjectJointRevoluteZ, RotationMatrixZ)

EP = exu.NodeType.RotationEulerParameters
ROTVEC = exu.NodeType.RotationRotationVector
OVT = exu.OutputVariableType


def user_settings(endTime, numberOfSteps):
    """Simulation settings as an Exudyn script writes them (no files, no console output)."""
    s = exu.SimulationSettings()
    s.timeIntegration.endTime = endTime
    s.timeIntegration.numberOfSteps = numberOfSteps
    s.timeIntegration.verboseMode = 0
    s.solution.file.write = False
    s.solution.sensors.active = False
    s.show.computationTime = False
    return s


def redundant_settings(endTime, numberOfSteps):
    """As Exudyn's fourBarMechanism3D.py: the default EXUdense solver stops on the singular
    Jacobian of redundant joints (even with ignoreSingularJacobian); EigenDense with
    ignoreSingularJacobian (full-pivot LU, least squares) runs."""
    s = user_settings(endTime, numberOfSteps)
    s.linearSolver.ignoreSingularJacobian = True
    s.linearSolver.solverType = exu.LinearSolverType.EigenDense
    return s


# ---------------------------------------------------------------------------- class 1: inactive rows
def slider_pendulum(node=EP):
    """A rod hanging from a spherical joint whose x axis is free (constrainedAxes=[0,1,1]):
    the pivot slides along x while the rod swings in 3-D. 1 body, 2 active + 1 inactive rows."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    w0 = np.array([2.0, 0.0, 3.0])
    rod = mbs.CreateRigidBody(inertia=InertiaCuboid(density=500, sideLengths=[0.1, 1.0, 0.1]), nodeType=node,
                              referencePosition=[0, 0.5, 0],
                              initialAngularVelocity=w0, initialVelocity=[1.0, 0.0, 1.0],   # pivot: [2.5, 0, 0]
                              gravity=[0, 0, -9.81])
    mbs.CreateSphericalJoint(itemNumbers=[ground, rod], position=[0, 0, 0], constrainedAxes=[0, 1, 1])
    mbs.Assemble()
    return mbs, user_settings(0.5, 100)


def generic_double_pendulum(node=EP):
    """Two rods: ground—rod1 by CreateGenericJoint with constrainedAxes=[1,1,1,1,1,0]
    (revolute about z), rod1—rod2 by a low-level GenericJoint with constrainedAxes=
    [1,1,1,0,0,0] (ball joint); gravity along -y. 4 inactive rows of 12."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    inertia = InertiaCuboid(density=1000, sideLengths=[1.0, 0.06, 0.06])
    g = [0, -9.81, 0]
    w1, w2 = np.array([0, 0, 2.0]), np.array([1.0, 0.5, 2.0])
    v1 = np.cross(w1, [0.5, 0, 0])
    v2 = np.cross(w1, [1.0, 0, 0]) - np.cross(w2, [-0.5, 0, 0])    # joint point moves with both rods
    b1 = mbs.CreateRigidBody(inertia=inertia, nodeType=node, referencePosition=[0.5, 0, 0],
                             initialAngularVelocity=w1, initialVelocity=v1, gravity=g)
    b2 = mbs.CreateRigidBody(inertia=inertia, nodeType=node, referencePosition=[1.5, 0, 0],
                             initialAngularVelocity=w2, initialVelocity=v2, gravity=g)
    mbs.CreateGenericJoint(itemNumbers=[ground, b1], position=[0, 0, 0], constrainedAxes=[1, 1, 1, 1, 1, 0])
    m1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b1, localPosition=[0.5, 0, 0]))
    m2 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b2, localPosition=[-0.5, 0, 0]))
    mbs.AddObject(GenericJoint(markerNumbers=[m1, m2], constrainedAxes=[1, 1, 1, 0, 0, 0]))
    mbs.Assemble()
    return mbs, user_settings(0.5, 100)


def robot_3r(node=EP):
    """exudyn.robotics: the 3R manipulator of ``models.Manipulator3RSimple`` without PD
    control, falling under gravity from a bent pose (GenericJoints with one free axis each)."""
    from exudyn.robotics import Robot, RobotBase, RobotLink, RobotTool, StdDH2HT
    from exudyn.robotics.models import Manipulator3RSimple
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    d = Manipulator3RSimple()
    robot = Robot(gravity=d["gravity"], base=RobotBase(HT=d["base"]["HT"]), tool=RobotTool(HT=d["tool"]["HT"]),
                  referenceConfiguration=[0.2, 0.4, -0.7])
    for link in d["links"]:
        robot.AddLink(RobotLink(mass=link["mass"], COM=link["COM"], inertia=link["inertia"],
                                localHT=StdDH2HT(link["stdDH"])))
    ground = mbs.AddObject(ObjectGround())
    base = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    robot.CreateRedundantCoordinateMBS(mbs, baseMarker=base, rigidBodyNodeType=node)
    mbs.Assemble()
    return mbs, user_settings(0.5, 100)


# ---------------------------------------------------------------------------- class 2: redundant loops
FOURBAR = dict(a=0.3, b=0.8, c=0.6, d=0.7, theta=np.radians(60))   # crank, coupler, rocker, ground


def fourbar_geometry(a, b, c, d, theta):
    """Planar four-bar in the x-y plane: pivots A=0, D=(d,0); crank A-B, coupler B-C, rocker D-C."""
    A, D = np.zeros(3), np.array([d, 0, 0])
    B = a * np.array([np.cos(theta), np.sin(theta), 0])
    e = D - B
    L = np.linalg.norm(e)
    x = (b ** 2 - c ** 2 + L ** 2) / (2 * L)
    h = np.sqrt(b ** 2 - x ** 2)
    C = B + x * e / L + h * np.array([-e[1], e[0], 0]) / L                 # upper branch
    return A, B, C, D


def fourbar(node=EP, joint="revolute", crank_speed=5.0, consistent=True, closing=None):
    """Four-bar linkage from three rods and four 3-D revolute joints about z
    (``joint``: "revolute" CreateRevoluteJoint = RevoluteJointZ, "generic" CreateGenericJoint
    with constrainedAxes=[1,1,1,1,1,0]): 18 coordinates, 20 joint equations, 1 DOF, so 3
    equations are redundant. ``consistent=False``: the crank spins but coupler and
    rocker start at rest (the joint at B violates the velocity constraints by
    a·crank_speed = 1.5 m/s). ``closing``: constrainedAxes of the closing joint at D, e.g.
    [1,1,0,0,0,0] as in Exudyn's fourBarMechanism3D.py: the same motion without redundancy."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    A, B, C, D = fourbar_geometry(**FOURBAR)
    z = np.array([0, 0, 1.0])
    w2 = crank_speed
    vB = np.cross(w2 * z, B - A)
    # vB + w3 z×(C-B) = w4 z×(C-D): two equations for the coupler and rocker rates
    K = np.column_stack([np.cross(z, C - B)[:2], -np.cross(z, C - D)[:2]])
    w3, w4 = np.linalg.solve(K, -vB[:2])
    if not consistent:
        w3 = w4 = 0.0
    g = [0, -9.81, 0]
    bodies = []
    for P0, P1, w, v0 in ((A, B, w2, np.zeros(3)), (B, C, w3, vB if consistent else np.zeros(3)), (D, C, w4, np.zeros(3))):
        e = P1 - P0
        L = np.linalg.norm(e)
        com = 0.5 * (P0 + P1)
        vel = v0 + np.cross(w * z, com - P0)                               # P0: pivot end, moving with v0
        bodies.append(mbs.CreateRigidBody(inertia=InertiaCuboid(density=2000, sideLengths=[L, 0.04, 0.02]),
                                          nodeType=node, referencePosition=com,
                                          referenceRotationMatrix=RotationMatrixZ(np.arctan2(e[1], e[0])),
                                          initialAngularVelocity=w * z, initialVelocity=vel, gravity=g))
    crank, coupler, rocker = bodies
    for items, P in (([ground, crank], A), ([crank, coupler], B), ([coupler, rocker], C), ([ground, rocker], D)):
        if closing is not None and P is D:
            mbs.CreateGenericJoint(itemNumbers=items, position=P, constrainedAxes=list(closing))
        elif joint == "revolute":
            mbs.CreateRevoluteJoint(itemNumbers=items, position=P, axis=[0, 0, 1])
        else:
            mbs.CreateGenericJoint(itemNumbers=items, position=P, constrainedAxes=[1, 1, 1, 1, 1, 0])
    mbs.Assemble()
    return mbs, redundant_settings(0.2, 100)


SLIDER_CRANK = dict(r=0.3, l=0.8, theta=np.radians(45))


def slider_crank(node=EP, violate=False, crank_speed=4.0, torque=2.0, closing=None):
    """3-D slider-crank with low-level markers: crank (revolute z to ground at the origin),
    connecting rod (RevoluteJointZ at both ends), slider block on a PrismaticJointX along
    the global x axis; a constant torque drives the crank, gravity along -y. 18
    coordinates, 20 joint equations, 1 DOF: 3 redundant. ``violate=True`` is the classic
    script error: the rod is placed horizontally at the crank pin and the slider at its
    end, so the rod-slider joint is off by r·sinθ = 0.21 in y; everything starts at rest.
    ``closing``: constrainedAxes of a GenericJoint replacing the rod-slider revolute joint,
    e.g. [1,1,0,0,0,0]: the same motion without redundancy."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    r, l, th = SLIDER_CRANK["r"], SLIDER_CRANK["l"], SLIDER_CRANK["theta"]
    A = r * np.array([np.cos(th), np.sin(th), 0])
    if violate:
        phi, w, crank_speed = 0.0, 0.0, 0.0
    else:
        phi = np.arcsin(-r * np.sin(th) / l)                              # rod angle
        w = -r * np.cos(th) * crank_speed / (l * np.cos(phi))              # rod angular rate
    eR = np.array([np.cos(phi), np.sin(phi), 0])
    B = A + l * eR
    if not violate:
        assert abs(B[1]) < 1e-14
    z = np.array([0, 0, 1.0])
    vA = np.cross(crank_speed * z, A)
    vB = vA + np.cross(w * z, B - A)
    g = [0, -9.81, 0]
    crank = mbs.CreateRigidBody(inertia=InertiaCuboid(density=2000, sideLengths=[r, 0.04, 0.04]), nodeType=node,
                                referencePosition=A / 2, referenceRotationMatrix=RotationMatrixZ(th),
                                initialAngularVelocity=crank_speed * z, initialVelocity=vA / 2, gravity=g)
    rod = mbs.CreateRigidBody(inertia=InertiaCuboid(density=2000, sideLengths=[l, 0.03, 0.03]), nodeType=node,
                              referencePosition=(A + B) / 2, referenceRotationMatrix=RotationMatrixZ(phi),
                              initialAngularVelocity=w * z, initialVelocity=(vA + vB) / 2, gravity=g)
    slider = mbs.CreateRigidBody(inertia=InertiaCuboid(density=2000, sideLengths=[0.1, 0.05, 0.05]), nodeType=node,
                                 referencePosition=[B[0], 0, 0], initialVelocity=[vB[0], 0, 0], gravity=g)
    mG0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    mC0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=crank, localPosition=[-r / 2, 0, 0]))
    mC1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=crank, localPosition=[r / 2, 0, 0]))
    mR0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=rod, localPosition=[-l / 2, 0, 0]))
    mR1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=rod, localPosition=[l / 2, 0, 0]))
    mS = mbs.AddMarker(MarkerBodyRigid(bodyNumber=slider, localPosition=[0, 0, 0]))
    mGS = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[B[0], 0, 0]))
    mbs.AddObject(ObjectJointRevoluteZ(markerNumbers=[mG0, mC0]))
    mbs.AddObject(ObjectJointRevoluteZ(markerNumbers=[mC1, mR0]))
    if closing is None:
        mbs.AddObject(ObjectJointRevoluteZ(markerNumbers=[mR1, mS]))
    else:
        mbs.AddObject(GenericJoint(markerNumbers=[mR1, mS], constrainedAxes=list(closing)))
    mbs.AddObject(ObjectJointPrismaticX(markerNumbers=[mGS, mS]))
    mbs.AddLoad(LoadTorqueVector(markerNumber=mC0, loadVector=[0, 0, torque]))
    mbs.Assemble()
    return mbs, redundant_settings(0.2, 100)


#: the orthogonal Bricard 6R linkage: Denavit-Hartenberg d = 0, a = BRICARD_A, twists
#: alternating +90° and -90°
BRICARD_A = 0.3


def _dh(theta, a, alpha):
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st],
                     [0, sa, ca, 0.0], [0, 0, 0, 1.0]])


def bricard_frames(theta):
    """Frames F_0 = I, F_i = F_{i-1} Rz(θ_i) Tx(a) Rx(α_i) of the six links (F_6 = F_0 when the
    loop closes): joint i turns about the z axis of F_{i-1} through its origin."""
    F = [np.eye(4)]
    for k, th in enumerate(theta):
        F.append(F[-1] @ _dh(th, BRICARD_A, np.pi / 2 if k % 2 == 0 else -np.pi / 2))
    return F


@functools.lru_cache(maxsize=None)
def bricard_symmetric_angles():
    """(θ_odd, θ_even) of the loop's threefold-symmetric closed configuration (joint angles
    alternating; ≈ (0.7467, 2.0079) rad), solved from F_6 = I by Gauss-Newton."""
    from scipy.optimize import least_squares

    def gap(x):
        return (bricard_frames(np.array([x[0], x[1]] * 3))[6] - np.eye(4))[:3].ravel()
    return tuple(least_squares(gap, [0.75, 2.0], xtol=1e-15, ftol=1e-15, gtol=1e-15).x)


def bricard(node=EP, speed=3.0, closing=None):
    """The orthogonal Bricard linkage: six rods joined in a closed loop by six revolute
    joints (CreateRevoluteJoint), link 0 the ground. By Grübler's count (5 bodies × 6 - 6 × 5
    equations) it is rigid, yet it moves with one degree of freedom: the loop's equations are
    dependent everywhere on its motion (1 redundant), not only in a plane as a four-bar's.
    It starts in the threefold-symmetric configuration, moving along its one mode at
    ``speed`` rad/s (the largest joint rate), under gravity. ``closing``: constrainedAxes of
    a GenericJoint (axes: the joint's axis as local z) replacing the closing joint 6, e.g.
    [1,1,1,1,0,0]: the same motion without the redundant equation."""
    theta = np.array(list(bricard_symmetric_angles()) * 3)
    F = bricard_frames(theta)
    assert np.abs(F[6] - np.eye(4)).max() < 1e-12                     # the loop closes
    o = [f[:3, 3] for f in F]
    z = [f[:3, 2] for f in F]
    # joint rates of the one mode: Σ θ̇_k ξ_k = 0 with ξ_k = (z_{k-1}, o_{k-1} × z_{k-1})
    Xi = np.array([np.concatenate([z[k], np.cross(o[k], z[k])]) for k in range(6)]).T
    rates = np.linalg.svd(Xi)[2][-1]
    rates *= speed / np.abs(rates).max()
    assert np.abs(Xi @ rates).max() < 1e-12
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    links = [ground]
    for i in range(1, 6):                                  # link i: from joint i (o_{i-1}) to joint i+1 (o_i)
        com = 0.5 * (o[i - 1] + o[i])
        w = sum(rates[k] * z[k] for k in range(i))
        v = sum(rates[k] * np.cross(z[k], com - o[k]) for k in range(i))
        links.append(mbs.CreateRigidBody(inertia=InertiaCuboid(density=2000, sideLengths=[BRICARD_A, 0.03, 0.02]),
                                         nodeType=node, referencePosition=com, referenceRotationMatrix=F[i][:3, :3],
                                         initialAngularVelocity=w, initialVelocity=v, gravity=[0, 0, -9.81]))
    links.append(ground)
    for i in range(1, 7):                                  # joint i between links i-1 and i
        if i == 6 and closing is not None:
            mbs.CreateGenericJoint(itemNumbers=[links[5], links[6]], position=o[5], rotationMatrixAxes=F[5][:3, :3],
                                   constrainedAxes=list(closing))
        else:
            mbs.CreateRevoluteJoint(itemNumbers=[links[i - 1], links[i]], position=o[i - 1], axis=z[i - 1])
    mbs.Assemble()
    return mbs, redundant_settings(0.2, 100)


# ---------------------------------------------------------------------------- comparison state
def state_at_end(mbs, nodes):
    """Parameterization-independent state of the listed nodes in the system's current
    configuration: per node Position, RotationMatrix (row-major, rigid nodes only),
    Velocity, AngularVelocity (global frame, rigid nodes only)."""
    out = []
    for n in nodes:
        rigid = mbs.GetNode(n)["nodeType"].startswith("RigidBody")
        out.append(mbs.GetNodeOutput(n, OVT.Position))
        if rigid:
            out.append(np.ravel(mbs.GetNodeOutput(n, OVT.RotationMatrix)))
        out.append(mbs.GetNodeOutput(n, OVT.Velocity))
        if rigid:
            out.append(mbs.GetNodeOutput(n, OVT.AngularVelocity))
    return np.concatenate([np.ravel(np.asarray(v, float)) for v in out])


def rel_error(x, ref):
    """max |x - ref| relative to the size of the reference state (at least 1)."""
    return float(np.abs(np.asarray(x) - ref).max() / max(1.0, float(np.abs(ref).max())))


# ---------------------------------------------------------------------------- Exudyn evaluation
class Evaluator:
    """Exudyn's M, g, C_q and C_q q̇ at given total coordinates, on its own solver object
    (as in the notes; writes the Current configuration of ``mbs``)."""

    def __init__(self, mbs):
        s = exu.SimulationSettings()
        s.solution.file.write = False
        s.solution.sensors.active = False
        s.show.computationTime = False
        s.linearSolver.ignoreSingularJacobian = True           # initial accelerations of redundant loops
        s.linearSolver.solverType = exu.LinearSolverType.EigenDense
        self.mbs, self.sd = mbs, mbs.systemData
        sd = self.sd
        keep = (np.array(sd.GetODE2Coordinates()), np.array(sd.GetODE2Coordinates_t()),
                np.array(sd.GetODE2Coordinates_tt()), sd.GetTime())
        self.S = exu.MainSolverImplicitSecondOrder()
        self.S.InitializeSolver(mbs, s)                   # resets the Current state to Initial:
        sd.SetODE2Coordinates(keep[0])                    # put the state back
        sd.SetODE2Coordinates_t(keep[1])
        sd.SetODE2Coordinates_tt(keep[2])
        sd.SetTime(keep[3])
        self.n2, self.nae = self.S.GetODE2size(), self.S.GetAEsize()
        self.ref = np.array(self.sd.GetODE2Coordinates(exu.ConfigurationType.Reference))

    def total(self, configuration=exu.ConfigurationType.Current):
        return np.array(self.sd.GetODE2Coordinates(configuration)) + self.ref

    def set(self, q, qd=None):
        self.sd.SetODE2Coordinates(np.asarray(q) - self.ref)
        if qd is not None:
            self.sd.SetODE2Coordinates_t(qd)

    def mass(self):
        self.S.ComputeMassMatrix(self.mbs)
        return np.array(self.S.GetSystemMassMatrix())

    def g(self, velocity=False):
        self.S.ComputeAlgebraicEquations(self.mbs, velocity)
        return np.array(self.S.GetSystemResidual())[self.n2:]

    def Cq(self):
        ns = self.n2 + self.nae
        self.S.SetSystemJacobian(np.zeros((ns, ns)))
        self.S.ComputeJacobianAE(self.mbs, 1.0, 0.0, 0.0, False)
        return np.array(self.S.GetSystemJacobian())[self.n2:, :self.n2]


def constraint_residuals(mbs):
    """(max |g(q)|, max |C_q q̇|) of Exudyn's joint equations at the system's current
    state; inactive rows (λᵢ = 0 rows, read with λ = 0) count as 0."""
    ev = Evaluator(mbs)
    active = np.abs(ev.Cq()).max(axis=1, initial=0.0) > 0
    g, gv = ev.g()[active], ev.g(velocity=True)[active]
    return float(np.abs(g).max(initial=0.0)), float(np.abs(gv).max(initial=0.0))


def active_rows(mbs):
    """Joint equations that constrain: all equations of a joint, minus the zeros in its
    ``constrainedAxes``. Euler-parameter normalization equations are not counted."""
    sd = mbs.systemData
    node_rows = set()                                  # Euler-parameter norms belong to the nodes
    for i in range(sd.NumberOfNodes()):
        node_rows |= set(sd.GetNodeLTGAE(i))
    n = 0
    for i in range(sd.NumberOfObjects()):
        ae = set(sd.GetObjectLTGAE(i)) - node_rows
        if not ae:
            continue
        axes = mbs.GetObject(i).get("constrainedAxes")
        n += int(np.sum(axes)) if axes is not None else len(ae)
    return n


@functools.lru_cache(maxsize=None)
def _dof(name):
    mbs = CASE[name].build()[0]
    return {k: int(v) for k, v in mbs.ComputeSystemDegreeOfFreedom().items()}


def build_dof(case):
    """``mbs.ComputeSystemDegreeOfFreedom()`` of a fresh build (cached): degreeOfFreedom,
    redundantConstraints, nODE2, nAE, nPureAE (= the λᵢ = 0 rows of constrainedAxes zeros)."""
    CASE.setdefault(case.name, case)
    return _dof(case.name)


def project_like_exudyn(mbs):
    """Exudyn's first step from an initial state that violates position constraints, in
    the limit h → 0: the configuration q₁ on the constraints with M(q₁) Δ = C_q(q₁)ᵀ μ,
    where Δ is the step in the node's own coordinates (Euler parameters, positions: the
    plain difference q₁ - q₀; RotVecLG: the body-frame increment, R₁ = R₀ exp(Δθ)), so
    the metric depends on the node type. Velocities are projected at q₁ with the same
    metric (M-orthogonally onto C_q(q₁) q̇ = 0; only verified for models starting at
    rest, as ours do). Writes the result as the Initial state and returns (max |Δq|,
    max |Δq̇|). Verified against Exudyn's refined runs in test_exudyn_joints.py
    (test_exudyn_limit_is_the_projected_motion): agreement 4e-6 (EP), 8e-7 (RotVecLG),
    within the 1st-order extrapolation's own uncertainty."""
    from scipy.optimize import least_squares
    from scipy.spatial.transform import Rotation
    ev = Evaluator(mbs)
    sd = mbs.systemData
    q0 = ev.total(exu.ConfigurationType.Initial)
    v0 = np.array(sd.GetODE2Coordinates_t(exu.ConfigurationType.Initial))
    rotvec = []
    for i in range(sd.NumberOfNodes()):
        if mbs.GetNode(i)["nodeType"] == "RigidBodyRotVecLG":
            rotvec.append(list(sd.GetNodeLTGODE2(i))[3:])

    def q_of(d):
        q = q0 + d
        for r in rotvec:
            q[r] = (Rotation.from_rotvec(q0[r]) * Rotation.from_rotvec(d[r])).as_rotvec()
        return q

    n2, nae = ev.n2, ev.nae

    def residual(x):
        d, mu = x[:n2], x[n2:]
        ev.set(q_of(d))
        return np.concatenate([ev.mass() @ d - ev.Cq().T @ mu, ev.g()])

    sol = least_squares(residual, np.zeros(n2 + nae), xtol=1e-15, ftol=1e-15, gtol=1e-15)
    if np.abs(residual(sol.x)).max() > 1e-12:
        raise RuntimeError(f"project_like_exudyn: no projection found ({np.abs(residual(sol.x)).max():.2e})")
    q1 = q_of(sol.x[:n2])
    ev.set(q1)
    M, C = ev.mass(), ev.Cq()
    K = np.block([[M, C.T], [C, np.zeros((nae, nae))]])
    v1 = np.linalg.lstsq(K, np.concatenate([M @ v0, np.zeros(nae)]), rcond=None)[0][:n2]
    sd.SetODE2Coordinates(q1 - ev.ref, exu.ConfigurationType.Initial)
    sd.SetODE2Coordinates_t(v1, exu.ConfigurationType.Initial)
    sd.SetODE2Coordinates(q1 - ev.ref)
    sd.SetODE2Coordinates_t(v1)
    return float(np.abs(sol.x[:n2]).max()), float(np.abs(v1 - v0).max())


def project_velocities(mbs):
    """The kinetic-energy-orthogonal projection of the initial velocities onto C_q q̇ = 0
    (positions unchanged): Exudyn's h → 0 limit for violated velocity constraints (the
    same for every node type). Writes them as Initial velocities; returns max |Δq̇|."""
    ev = Evaluator(mbs)
    sd = mbs.systemData
    q0 = ev.total(exu.ConfigurationType.Initial)
    v0 = np.array(sd.GetODE2Coordinates_t(exu.ConfigurationType.Initial))
    ev.set(q0)
    M, C = ev.mass(), ev.Cq()
    K = np.block([[M, C.T], [C, np.zeros((ev.nae, ev.nae))]])
    v1 = np.linalg.lstsq(K, np.concatenate([M @ v0, np.zeros(ev.nae)]), rcond=None)[0][:ev.n2]
    sd.SetODE2Coordinates_t(v1, exu.ConfigurationType.Initial)
    sd.SetODE2Coordinates_t(v1)
    return float(np.abs(v1 - v0).max())


# ---------------------------------------------------------------------------- cases and reference
@dataclass(frozen=True)
class Case:
    """One model. ``build()`` -> (mbs, simulationSettings), assembled afresh. ``kind``:
    "inactive", "redundant" or "inconsistent". ``start``: "as-built", or "projected" when
    the reference starts from :func:`project_like_exudyn` of the built state (violated
    position constraints: Exudyn's own run converges only at first order to that motion,
    so the reference integrates from the projected state instead). ``ref_steps``: first
    and largest numberOfSteps of the reference's step doubling. ``genalpha_steps``:
    numberOfSteps for the bridge's fixed-step generalized-α. ``reference_build``: the same
    motion for Exudyn's reference where Exudyn's solver cannot run ``build`` (the Bricard
    linkage: its closing joint without the redundant equation)."""
    name: str
    build: Callable
    compare_nodes: tuple
    kind: str
    description: str = ""
    start: str = "as-built"
    genalpha_steps: int = 200
    ref_steps: tuple = (None, 16000)
    rho: float = 0.5
    #: Exudyn's count of redundant equations (redundant cases)
    redundant: int = 3
    #: what Exudyn's own reference runs, when it cannot run ``build`` itself (None: ``build``)
    reference_build: Callable = None

    def __post_init__(self):
        if self.ref_steps[0] is None:                       # the reference starts at the bridge's step
            object.__setattr__(self, "ref_steps", (self.genalpha_steps, self.ref_steps[1]))

    def __repr__(self):
        return f"Case({self.name})"


REF_TARGET = 1e-9          # stop doubling once successive extrapolated results agree this well
REF_BUDGET_S = None         # optional wall-time cut (None: the step budget alone, deterministic)
REF_NEWTON = dict(relativeTolerance=1e-11, absoluteTolerance=1e-13, useModifiedNewton=True)


def reference_settings(s, n, rho, rotvec, newton=None):
    """Turn the user's settings into a reference run with n fixed steps."""
    ti = s.timeIntegration
    ti.numberOfSteps = n
    ti.adaptiveStep = False                     # a reduced step would spoil the extrapolation
    ti.generalizedAlpha.spectralRadius = rho
    if rotvec:                                  # see notes: RotVecLG + joints needs it
        ti.generalizedAlpha.lieGroupSimplifiedKinematicRelations = True
    for k, v in dict(REF_NEWTON, **(newton or {})).items():
        setattr(ti.newton, k, v)
    ti.verboseMode = 0
    s.solution.file.write = False
    s.solution.sensors.active = False
    return s


@functools.lru_cache(maxsize=None)
def _projected_initial_state(name, start):
    mbs = CASE[name].build()[0]
    (project_like_exudyn if start == "projected" else project_velocities)(mbs)
    sd = mbs.systemData
    return (np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Initial)),
            np.array(sd.GetODE2Coordinates_t(exu.ConfigurationType.Initial)))


def exudyn_run(case, n, start=None, solverType=exu.DynamicSolverType.GeneralizedAlpha, newton=None):
    """One run of Exudyn's own solver on a fresh build with n steps: (state_at_end, mbs).
    ``start``: as ``Case.start``, or "velocity-projected" (:func:`project_velocities`).
    ``newton``: NewtonSettings overriding REF_NEWTON (Exudyn's first step from a violated
    position needs looser ones: relativeTolerance=1e-10, absoluteTolerance=1e-12)."""
    CASE.setdefault(case.name, case)
    mbs, s = (case.reference_build or case.build)()
    start = case.start if start is None else start
    if start in ("projected", "velocity-projected"):
        q, v = _projected_initial_state(case.name, start)
        mbs.systemData.SetODE2Coordinates(q, exu.ConfigurationType.Initial)
        mbs.systemData.SetODE2Coordinates_t(v, exu.ConfigurationType.Initial)
    rotvec = any(mbs.GetNode(i)["nodeType"] == "RigidBodyRotVecLG" for i in range(mbs.systemData.NumberOfNodes()))
    reference_settings(s, n, case.rho, rotvec, newton)
    exu.SolveDynamic(mbs, s, solverType=solverType, showHints=False, showCausingItems=False)
    it = mbs.sys["dynamicSolver"].it
    if it.currentStepIndex != n + 1 or abs(it.currentTime - s.timeIntegration.endTime) > 1e-12:
        raise RuntimeError(f"{case.name}: Exudyn took {it.currentStepIndex - 1} steps instead of {n}")
    return state_at_end(mbs, case.compare_nodes), mbs


def extrapolated_sequence(case, steps, start=None, order=2, budget=REF_BUDGET_S, target=REF_TARGET, newton=None):
    """Exudyn runs at steps[0], 2·steps[0], ... (at most steps[1]; with a ``budget`` in
    seconds, also while the runs fit in it), each pair Richardson-extrapolated for the given order:
    (last extrapolation, tolerance, wall time of the finest run, list of (n, raw result)).
    The tolerance is the larger of the last two differences between successive
    extrapolations, relative to the state size; doubling stops once it is ≤ target."""
    CASE.setdefault(case.name, case)
    start = case.start if start is None else start
    if start != "as-built":
        _projected_initial_state(case.name, start)          # once (cached), outside the timing
    n, runs, Rs, tol, wall = steps[0], [], [], np.inf, 0.0
    t_all = time.perf_counter()
    while n <= steps[1]:
        t0 = time.perf_counter()
        x = exudyn_run(case, n, start, newton=newton)[0]
        wall = time.perf_counter() - t0
        runs.append((n, x))
        if len(runs) >= 2:
            Rs.append((2 ** order * x - runs[-2][1]) / (2 ** order - 1))
        if len(Rs) >= 3:
            # the worse of the last two agreements: a single one can be small by chance
            tol = max(rel_error(Rs[-1], Rs[-2]), rel_error(Rs[-2], Rs[-3]))
            if tol <= target:
                break
        if budget is not None and time.perf_counter() - t_all + 2.2 * wall > budget:
            break
        n *= 2
    if len(Rs) == 2:
        tol = rel_error(Rs[-1], Rs[-2])
    return (Rs[-1] if Rs else runs[-1][1]), tol, wall, runs


@functools.lru_cache(maxsize=None)
def _reference(name):
    case = CASE[name]
    return extrapolated_sequence(case, case.ref_steps)


def exudyn_reference(case):
    """Exudyn's own converged solution of ``case`` at endTime (cached per case name):
    (state vector, converged tolerance relative to the state size, wall time of the
    finest run). Generalized-α (index 3, spectral radius ``case.rho``), Newton tolerances
    tight, fixed steps doubled from ``case.ref_steps[0]``, each pair Richardson-
    extrapolated (2nd order); the tolerance is the larger of the last two differences
    of successive extrapolations (see :func:`extrapolated_sequence`)."""
    CASE.setdefault(case.name, case)
    return _reference(case.name)[:3]


def exudyn_genalpha_error(case):
    """Error of Exudyn's own generalized-α at ``case.genalpha_steps`` steps (the first run
    of the reference sequence, same start and spectral radius), relative to the state size."""
    CASE.setdefault(case.name, case)
    R, tol, wall, runs = _reference(case.name)
    n, x = runs[0]
    assert n == case.genalpha_steps, (n, case.genalpha_steps)
    return rel_error(x, R)


def _case(name, build, nodes, kind, description, **kw):
    return Case(name, build, tuple(nodes), kind, description, **kw)


CASES = [
    _case("inactive-spherical-slider-EP", lambda: slider_pendulum(EP), [0], "inactive",
          "rod on a spherical joint free along x (constrainedAxes=[0,1,1]), EP node", genalpha_steps=250),
    _case("inactive-spherical-slider-RotVecLG", lambda: slider_pendulum(ROTVEC), [0], "inactive",
          "rod on a spherical joint free along x (constrainedAxes=[0,1,1]), RotVecLG node", genalpha_steps=250),
    _case("inactive-generic-double-pendulum-EP", lambda: generic_double_pendulum(EP), [0, 1], "inactive",
          "double pendulum: GenericJoint [1,1,1,1,1,0] to ground, GenericJoint [1,1,1,0,0,0] between, EP",
          genalpha_steps=250),
    _case("inactive-generic-double-pendulum-RotVecLG", lambda: generic_double_pendulum(ROTVEC), [0, 1], "inactive",
          "double pendulum: GenericJoint [1,1,1,1,1,0] to ground, GenericJoint [1,1,1,0,0,0] between, RotVecLG",
          genalpha_steps=250),
    _case("inactive-robot-3R-EP", lambda: robot_3r(EP), [0, 1, 2], "inactive",
          "exudyn.robotics Manipulator3RSimple without control, falling (3 GenericJoints, one free axis each)",
          genalpha_steps=250),
    _case("redundant-fourbar-revolute-EP", lambda: fourbar(EP), [0, 1, 2], "redundant",
          "four-bar of CreateRevoluteJoint (RevoluteJointZ): 20 equations, rank 17, EP"),
    _case("redundant-fourbar-generic-RotVecLG", lambda: fourbar(ROTVEC, joint="generic"), [0, 1, 2], "redundant",
          "four-bar of GenericJoint [1,1,1,1,1,0]: redundant and inactive rows, RotVecLG"),
    _case("redundant-slider-crank-EP", lambda: slider_crank(EP), [0, 1, 2], "redundant",
          "3-D slider-crank, RevoluteJointZ x3 + PrismaticJointX, crank torque, EP"),
    _case("redundant-bricard-EP", lambda: bricard(EP), [0, 1, 2, 3, 4], "redundant",
          "orthogonal Bricard 6R loop of CreateRevoluteJoint: 35 equations, 1 redundant everywhere on its motion, "
          "1 DOF, EP; Exudyn's GA stops on it (Newton fails at the first step), so its reference runs the closing "
          "joint as GenericJoint [1,1,1,1,0,0]", redundant=1,
          reference_build=lambda: bricard(EP, closing=[1, 1, 1, 1, 0, 0])),
    _case("inconsistent-velocity-fourbar-EP", lambda: fourbar(EP, consistent=False), [0, 1, 2], "inconsistent",
          "four-bar (redundant) whose coupler and rocker start at rest while the crank spins: 1.5 m/s violation"),
    _case("inconsistent-position-slider-crank-EP", lambda: slider_crank(EP, violate=True), [0, 1, 2], "inconsistent",
          "slider-crank (redundant) built with the rod horizontal: rod-slider joint off by 0.21, at rest, EP",
          start="projected"),
    _case("inconsistent-position-slider-crank-RotVecLG", lambda: slider_crank(ROTVEC, violate=True), [0, 1, 2],
          "inconsistent", "as above with RotVecLG nodes (Exudyn's limit differs from EP's, see project_like_exudyn)",
          start="projected"),
]
CASE = {c.name: c for c in CASES}
