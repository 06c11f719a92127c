"""Exudyn models whose constraints carry the user's settings and changes between steps,
written as Exudyn users write them (GitHub issue 21, Exudyn items 1, 5, 7, 8):

* ``index2_slider_crank``: a 3-D slider-crank of GenericJoints with free axes on EP
  nodes, started 0.25 off its position constraints, with
  ``generalizedAlpha.useIndex2Constraints = True`` (Exudyn enforces the constraints on
  velocities only: the offset stays);
* ``rolling_coin_sensor``: a rolling coin (ObjectJointRollingDisc, index 2) with a
  ``ForceLocal`` sensor on the joint (the Lagrange multipliers Exudyn stores);
* ``rotor_run_up``: a motor shaft driven at constant speed by a velocity-level
  ``CoordinateConstraint(velocityLevel=True, offset=ω)`` through an elastic coupling to a
  braked load;
* ``reeving_winch``: a load hanging from a rope whose length a ``CoordinateConstraint``'s
  ``offset`` sets, ramped by ``mbs.SetPreStepUserFunction`` every step (a crane's
  reeving system in small);
* ``switched_pendulum``: a pendulum on a revolute joint and a spherical joint to a second
  support; a pre-step function switches the second joint off with
  ``SetObjectParameter(joint, 'activeConnector', False)`` and later on again.

``Case.build()`` returns ``(mbs, simulationSettings)`` freshly assembled;
``exudyn_reference(case)`` is Exudyn's own generalized-α (the settings as the user wrote
them, index 2 where they say so) with the steps halved until two results agree.
"""
import functools
from dataclasses import dataclass, field
from typing import Callable

import exudyn as exu
import numpy as np
from exudyn.utilities import (CoordinateConstraint, CoordinateSpringDamper, GenericJoint, InertiaCuboid,
                              LoadCoordinate, LoadTorqueVector, MarkerBodyRigid, MarkerNodeCoordinate,
                              Node1D, NodePointGround, ObjectGround, ObjectJointRollingDisc,
                              ObjectRotationalMass1D, RigidBodyInertia, RotationMatrixY, RotationMatrixZ,
                              SensorObject)

EP = exu.NodeType.RotationEulerParameters
OVT = exu.OutputVariableType


from exudyn_special_models import _system  # noqa: E402  (the shared system)
from exudyn_special_models import settings as _settings  # noqa: E402


def settings(T, n, index2=False):
    """The shared settings, with index-2 constraints when asked (Exudyn requires Newmark then)."""
    s = _settings(T, n)
    s.timeIntegration.generalizedAlpha.useIndex2Constraints = index2
    s.timeIntegration.generalizedAlpha.useNewmark = index2
    return s


# ---------------------------------------------------------------------------- item 1
def index2_slider_crank(offset=0.25):
    """Crank (GenericJoint to ground, free about z), rod (GenericJoint to the crank pin,
    free about z), slider (GenericJoint to ground free along x); rod and slider joined by a
    GenericJoint holding x and y only. The slider is placed ``offset`` below the rod's end
    (a script error): the rod-slider joint starts violated by ``offset`` in y. EP nodes,
    crank torque, gravity along -y, useIndex2Constraints = True."""
    mbs = _system()
    ground = mbs.AddObject(ObjectGround())
    r, l, th = 0.3, 0.8, np.radians(45)
    A = r * np.array([np.cos(th), np.sin(th), 0.0])
    phi = np.arcsin(-r * np.sin(th) / l)
    B = A + l * np.array([np.cos(phi), np.sin(phi), 0.0])
    g = [0, -9.81, 0]
    crank = mbs.CreateRigidBody(inertia=InertiaCuboid(density=2000, sideLengths=[r, 0.04, 0.04]), nodeType=EP,
                                referencePosition=A / 2, referenceRotationMatrix=RotationMatrixZ(th), gravity=g)
    rod = mbs.CreateRigidBody(inertia=InertiaCuboid(density=2000, sideLengths=[l, 0.03, 0.03]), nodeType=EP,
                              referencePosition=(A + B) / 2, referenceRotationMatrix=RotationMatrixZ(phi), gravity=g)
    slider = mbs.CreateRigidBody(inertia=InertiaCuboid(density=2000, sideLengths=[0.1, 0.05, 0.05]), nodeType=EP,
                                 referencePosition=[B[0], -offset, 0], gravity=g)
    mG0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    mC0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=crank, localPosition=[-r / 2, 0, 0]))
    mC1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=crank, localPosition=[r / 2, 0, 0]))
    mR0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=rod, localPosition=[-l / 2, 0, 0]))
    mR1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=rod, localPosition=[l / 2, 0, 0]))
    mS = mbs.AddMarker(MarkerBodyRigid(bodyNumber=slider, localPosition=[0, 0, 0]))
    mGS = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[B[0], -offset, 0]))
    mbs.AddObject(GenericJoint(markerNumbers=[mG0, mC0], constrainedAxes=[1, 1, 1, 1, 1, 0]))
    mbs.AddObject(GenericJoint(markerNumbers=[mC1, mR0], constrainedAxes=[1, 1, 1, 1, 1, 0]))
    mbs.AddObject(GenericJoint(name="rodSlider", markerNumbers=[mR1, mS], constrainedAxes=[1, 1, 0, 0, 0, 0]))
    mbs.AddObject(GenericJoint(markerNumbers=[mGS, mS], constrainedAxes=[0, 1, 1, 1, 1, 1]))
    mbs.AddLoad(LoadTorqueVector(markerNumber=mC0, loadVector=[0, 0, 2.0]))
    mbs.Assemble()
    return mbs, settings(0.2, 100, index2=True)


def rolling_coin_sensor():
    """A coin (axis = local x) leaning 0.35 rad, spinning and yawing on the ground:
    ObjectJointRollingDisc with a ForceLocal sensor (stored internally), index 2 as in
    Exudyn's rolling-disc examples."""
    mbs = _system()
    ground = mbs.AddObject(ObjectGround())
    r, m = 0.1, 1.0
    inertia = RigidBodyInertia(mass=m, inertiaTensor=np.diag([0.5 * m * r**2, 0.25 * m * r**2, 0.25 * m * r**2]))
    R0 = RotationMatrixZ(0.2) @ RotationMatrixY(0.35)
    a = R0[:, 0]
    down = np.array([0.0, 0.0, -1.0]) - (-a[2]) * a
    down /= np.linalg.norm(down)
    p0 = -r * down
    w0 = 15.0 * a + np.array([0.0, 0.0, 2.0])
    v0 = np.cross(w0, p0)
    b = mbs.CreateRigidBody(inertia=inertia, nodeType=EP, referencePosition=p0, referenceRotationMatrix=R0,
                            initialVelocity=v0, initialAngularVelocity=w0, gravity=[0, 0, -9.81])
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))
    mC = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b))
    coin = mbs.AddObject(ObjectJointRollingDisc(name="coin", markerNumbers=[mG, mC], constrainedAxes=[1, 1, 1],
                                                discRadius=r))
    mbs.AddSensor(SensorObject(name="coinForce", objectNumber=coin, storeInternal=True, writeToFile=False,
                               outputVariableType=OVT.ForceLocal))
    mbs.Assemble()
    s = settings(0.25, 25, index2=True)
    s.solution.sensors.active = True
    return mbs, s


# ---------------------------------------------------------------------------- item 5
def rotor_run_up(speed=30.0):
    """A motor shaft (Node1D + ObjectRotationalMass1D) held at ``speed`` rad/s by a
    velocity-level CoordinateConstraint (offset = speed), started at that speed; an
    elastic coupling (CoordinateSpringDamper) to a load rotor, started at rest, with a
    braking torque."""
    mbs = _system()
    nG = mbs.AddNode(NodePointGround())
    mG = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nG, coordinate=0))
    nM = mbs.AddNode(Node1D(referenceCoordinates=[0.0], initialVelocities=[speed]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=nM, inertia=0.05))
    mM = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nM, coordinate=0))
    nL = mbs.AddNode(Node1D(referenceCoordinates=[0.0], initialVelocities=[0.0]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=nL, inertia=0.2))
    mL = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nL, coordinate=0))
    mbs.AddObject(CoordinateSpringDamper(markerNumbers=[mM, mL], stiffness=50.0, damping=0.5))
    mbs.AddObject(CoordinateConstraint(name="drive", markerNumbers=[mG, mM], velocityLevel=True, offset=speed))
    mbs.AddLoad(LoadCoordinate(markerNumber=mL, load=-1.0))
    mbs.Assemble()
    return mbs, settings(1.0, 100)


# ---------------------------------------------------------------------------- item 7
def reeving_winch(speed=2.88):
    """A load (Node1D, its height) hanging from a rope of stiffness k from a hook (Node1D)
    whose height a CoordinateConstraint's offset sets; the pre-step function reels the
    rope in: offset = speed·t at each step's end time."""
    mbs = _system()
    nG = mbs.AddNode(NodePointGround())
    mG = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nG, coordinate=0))
    nH = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=nH, inertia=5.0))
    mH = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nH, coordinate=0))
    nL = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=nL, inertia=2.0))
    mL = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nL, coordinate=0))
    mbs.AddObject(CoordinateSpringDamper(markerNumbers=[mH, mL], stiffness=800.0, damping=4.0, offset=-0.5))
    hook = mbs.AddObject(CoordinateConstraint(name="hook", markerNumbers=[mG, mH], offset=0.0))
    mbs.AddLoad(LoadCoordinate(markerNumber=mL, load=-2.0 * 9.81))

    def PreStepUserFunction(mbs, t):
        mbs.SetObjectParameter(hook, "offset", speed * t)
        return True

    mbs.SetPreStepUserFunction(PreStepUserFunction)
    mbs.Assemble()
    return mbs, settings(0.5, 100)


# ---------------------------------------------------------------------------- item 8
def switched_pendulum(t_off=0.1, t_on=None):
    """A rod hanging from ground by a GenericJoint free about z (a revolute joint at its
    top) and held horizontal at its other end by a second GenericJoint to ground (y); the
    pre-step function switches the lower joint off after ``t_off`` (and on again after
    ``t_on``, if given): the rod falls free to swing. EP node, gravity along -y."""
    mbs = _system()
    ground = mbs.AddObject(ObjectGround())
    L = 0.5
    rod = mbs.CreateRigidBody(inertia=InertiaCuboid(density=1000, sideLengths=[L, 0.03, 0.03]), nodeType=EP,
                              referencePosition=[L / 2, 0, 0], gravity=[0, -9.81, 0])
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    mTop = mbs.AddMarker(MarkerBodyRigid(bodyNumber=rod, localPosition=[-L / 2, 0, 0]))
    mbs.AddObject(GenericJoint(markerNumbers=[mG, mTop], constrainedAxes=[1, 1, 1, 1, 1, 0]))
    mG1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[L, 0, 0]))
    mEnd = mbs.AddMarker(MarkerBodyRigid(bodyNumber=rod, localPosition=[L / 2, 0, 0]))
    holder = mbs.AddObject(GenericJoint(name="holder", markerNumbers=[mG1, mEnd], constrainedAxes=[0, 1, 0, 0, 0, 0]))

    def PreStepUserFunction(mbs, t):
        on = t <= t_off + 1e-9 or (t_on is not None and t > t_on + 1e-9)
        mbs.SetObjectParameter(holder, "activeConnector", bool(on))
        return True

    mbs.SetPreStepUserFunction(PreStepUserFunction)
    mbs.Assemble()
    return mbs, settings(0.4, 200)


# ---------------------------------------------------------------------------- reference
@dataclass(frozen=True, eq=False)
class Case:
    name: str
    build: Callable
    ref_steps: int = 200
    max_steps: int = 25600
    rho: float = 0.8
    target: float = 1e-8
    order: int = 2              # Richardson extrapolation of successive runs (0: none)
    newton: dict = field(default_factory=lambda: dict(relativeTolerance=1e-10, absoluteTolerance=1e-12))

    def __repr__(self):
        return self.name


def node_state(mbs):
    """Position, RotationMatrix, Velocity, AngularVelocity of rigid nodes, Coordinates and
    Coordinates_t of 1-D nodes, at the system's current state (one vector)."""
    out = []
    for n in range(mbs.systemData.NumberOfNodes()):
        typ = mbs.GetNode(n)["nodeType"]
        if typ.startswith("RigidBody"):
            vs = [OVT.Position, OVT.RotationMatrix, OVT.Velocity, OVT.AngularVelocity]
        elif typ == "1D":
            vs = [OVT.Coordinates, OVT.Coordinates_t]
        else:
            vs = []
        out += [np.ravel(np.asarray(mbs.GetNodeOutput(n, v), float)) for v in vs]
    return np.concatenate(out)


def rel(x, ref):
    return float(np.abs(np.asarray(x) - ref).max() / max(1.0, float(np.abs(ref).max())))


def native_run(case, n, what=node_state):
    """Exudyn's own generalized-α on a fresh build at n steps (the user's settings
    otherwise: index 2 where they say so), tight Newton; returns what(mbs)."""
    mbs, s = case.build()
    ti = s.timeIntegration
    ti.numberOfSteps = n
    ti.generalizedAlpha.spectralRadius = case.rho
    for k, v in case.newton.items():
        setattr(ti.newton, k, v)
    s.solution.sensors.active = True
    exu.SolveDynamic(mbs, s, solverType=exu.DynamicSolverType.GeneralizedAlpha, showHints=False,
                     showCausingItems=False)
    return what(mbs)


@functools.lru_cache(maxsize=None)
def exudyn_reference(case):
    """(state, agreement, steps): Exudyn's generalized-α with the steps doubled from
    case.ref_steps, successive runs Richardson-extrapolated (case.order), until two
    successive extrapolations agree to case.target (relative to the state's size) or
    case.max_steps is reached; agreement is the last difference."""
    n, runs, ext, d = case.ref_steps, [native_run(case, case.ref_steps)], [], np.inf
    while True:
        n *= 2
        runs.append(native_run(case, n))
        f = 1.0 / (2 ** case.order - 1) if case.order else 0.0
        ext.append(runs[-1] + f * (runs[-1] - runs[-2]))
        if len(ext) >= 2:
            d = rel(ext[-1], ext[-2])
        if d <= case.target or n >= case.max_steps:
            return ext[-1], d, n


CASES = [
    Case("index2_slider_crank", index2_slider_crank, ref_steps=200),
    Case("rolling_coin_sensor", rolling_coin_sensor, ref_steps=100),
    Case("rotor_run_up", rotor_run_up, ref_steps=200),
    Case("reeving_winch", reeving_winch, ref_steps=200),
    Case("switched_pendulum", switched_pendulum, ref_steps=200, order=1),     # first order through the switch
]
CASE = {c.name: c for c in CASES}
