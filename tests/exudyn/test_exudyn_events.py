"""Events on an Exudyn model: the period of a pendulum on a revolute joint from its crossings
of the vertical, against the complete elliptic integral (the model's own q: Exudyn's total
coordinates)."""
import math

import mpmath
import numpy as np
import pytest

import lgt_bridge
from lgt_bridge import simulate

exu = pytest.importorskip("exudyn")
G = 9.81


def Ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def period(theta0, L):
    """4 K(sin²(θ0/2)) √(L/g), K the complete elliptic integral of the first kind (parameter m)."""
    return float(4 * mpmath.ellipk(math.sin(theta0 / 2) ** 2) * mpmath.sqrt(L / G))


def test_exudyn_revolute_pendulum_period():
    from exudyn.utilities import InertiaCuboid, ObjectGround

    theta0, rho, sides = 2.2, 500.0, [0.1, 0.1, 1.2]
    d = sides[2] / 2
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    inertia = InertiaCuboid(density=rho, sideLengths=sides)
    R0 = Ry(theta0)
    body = mbs.CreateRigidBody(inertia=inertia, referencePosition=R0 @ [0, 0, -d], referenceRotationMatrix=R0,
                               gravity=[0, 0, -G])
    mbs.CreateRevoluteJoint(itemNumbers=[ground, body], position=[0, 0, 0], axis=[0, 1, 0])
    mbs.Assemble()
    m = lgt_bridge.wrap(mbs)
    mass = rho * np.prod(sides)
    I_pivot = mass * (sides[0] ** 2 + sides[2] ** 2) / 12 + mass * d * d
    T = period(theta0, I_pivot / (mass * d))
    r = simulate(m, (0.0, 1.3 * T), method="dop853", rtol=1e-12, atol=1e-12,
                 events=[lambda t, q, V: q[0]])          # x of the body's centre (Exudyn's own q)
    te = r.t_events[0]
    assert len(te) == 3
    assert abs(te[0] - T / 4) / T < 1e-9 and abs(te[2] - te[0] - T) / T < 1e-9
