"""Models of the classes found by running Exudyn's own test models and examples through
``lgt-bridge run`` (issue 21: no raw numpy, scipy or Exudyn exception reaches a user),
written as Exudyn's users write them, each returning ``(mbs, simulationSettings)`` freshly
assembled.

- a spring-damper whose user function has the signature of an older Exudyn (no
  ``itemIndex`` argument): Exudyn raises when it calls it, before the first step
  (Exudyn's connectorRigidBodySpringDamperTest.py of an older version);
- a pre-step user function that raises in the middle of the run.
"""
import exudyn as exu
from exudyn.utilities import (CoordinateSpringDamper, MarkerNodeCoordinate, MassPoint, NodePoint,
                              NodePointGround, SensorNode)

from exudyn_special_models import _system, settings  # the shared system and settings


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
