"""Exudyn's CoordinateSpringDamperExt with limit stops and with bristle friction, written as
Exudyn's own test model ``coordinateSpringDamperExt`` writes them (a mass point on a ground
coordinate, the states in a NodeGenericData of 3 data coordinates).

Its limit-stop state and its friction mode live in the data coordinates, updated by Exudyn's
PostNewton after each step. The bridge used to take three things wrong here (dopri5 at 1e-8
ended at -0.60 where the motion ends at -0.752): a stop left after a shallow penetration was
not a switch (PostNewton's force error counts the last step's penetration), so a long step
kept pulling the mass back; PostNewton read the slip force a friction sticks again with from
the data's StartOfStep configuration, which the bridge never set; and in ``SolveDynamic``
Exudyn's own loop ran PostNewton on its output state, behind the bridge's last step, undoing
a contact the bridge had entered (dop853 at 1e-12 then stopped at the first stop).

References: the limit stops' motion is piecewise linear (free flight, a damped spring in a
stop), integrated here with scipy's DOP853 at 1e-13 with each stop located as an event; the
bristle friction against Exudyn's own generalized-α refined until converged."""
import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from exudyn.utilities import (CoordinateSpringDamperExt, MarkerNodeCoordinate, MassPoint,  # noqa: E402
                              NodeGenericData, NodePoint, NodePointGround)
from scipy.integrate import solve_ivp  # noqa: E402

from lgt_bridge import simulate  # noqa: E402
from lgt_exudyn import ExudynModel, SolveDynamic  # noqa: E402

from exudyn_special_models import _system, settings  # noqa: E402

M, V0, T = 0.5, 10.0, 2.0
K_STOP, D_STOP, UPPER, LOWER = 1e4, 10.0, 0.9, -0.9


def mass_on_coordinate(kind, n_steps=1000):
    """A mass point (0.5 kg, 10 m/s) on a ground coordinate with a CoordinateSpringDamperExt:
    ``kind`` "limits" (stops at ±0.9, k = 1e4, d = 10) or "bristle" (spring 100 N/m, damping
    2.8, dry friction through the bristle model with sticking stiffness 1e4)."""
    mbs = _system()
    ng = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0))
    nm = mbs.AddNode(NodePoint(referenceCoordinates=[0, 0, 0], initialVelocities=[V0, 0, 0]))
    mbs.AddObject(MassPoint(mass=M, nodeNumber=nm))
    mm = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nm, coordinate=0))
    if kind == "limits":
        nd = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0, 0], numberOfDataCoordinates=3))
        mbs.AddObject(CoordinateSpringDamperExt(markerNumbers=[mg, mm], nodeNumber=nd, limitStopsUpper=UPPER,
                                                limitStopsLower=LOWER, limitStopsStiffness=K_STOP,
                                                limitStopsDamping=D_STOP, useLimitStops=True))
    else:
        fd = 0.3 * M * 9.81
        nd = mbs.AddNode(NodeGenericData(initialCoordinates=[1, 0, 0], numberOfDataCoordinates=3))
        mbs.AddObject(CoordinateSpringDamperExt(markerNumbers=[mg, mm], nodeNumber=nd, stiffness=100, damping=2.8,
                                                dynamicFrictionForce=fd, staticFrictionOffsetForce=0.5 * fd,
                                                stickingStiffness=1e4, stickingDamping=100,
                                                frictionProportionalZone=0, exponentialDecayStatic=0.2))
    mbs.Assemble()
    return mbs, settings(T, n_steps)


def limit_stops_reference():
    """(x, v) at T of the mass between the stops: free flight, and in a stop
    m ẍ = -(k (x - stop) + d ẋ) until it leaves it (scipy DOP853 at 1e-13, stops as events)."""
    t, y, mode = 0.0, np.array([0.0, V0]), 0
    while t < T:
        if mode == 0:
            def up(t, y):
                return y[0] - UPPER

            def down(t, y):
                return y[0] - LOWER
            up.terminal = down.terminal = True
            up.direction, down.direction = 1, -1
            events, rhs = [up, down], (lambda t, y: [y[1], 0.0])
        else:
            stop = UPPER if mode > 0 else LOWER

            def leave(t, y, stop=stop):
                return y[0] - stop
            leave.terminal, leave.direction = True, -mode
            events = [leave]

            def rhs(t, y, stop=stop):
                return [y[1], -(K_STOP * (y[0] - stop) + D_STOP * y[1]) / M]
        r = solve_ivp(rhs, (t, T), y, method="DOP853", rtol=1e-13, atol=1e-13, events=events)
        t, y = r.t[-1], r.y[:, -1]
        if r.status == 1:
            mode = (1 if r.t_events[0].size else -1) if mode == 0 else 0
    return y


@pytest.fixture(scope="module")
def exact():
    return limit_stops_reference()


def _error(r, exact):
    return max(abs(r.q[-1][0] - exact[0]), abs(r.V[-1][0] - exact[1]) * 0.1)


def test_limit_stops_converge_to_the_exact_motion(exact):
    """simulate(ExudynModel(...)): every stop reached and left is located; the error falls as
    the tolerance falls (measured 1.0e-6, 1.2e-8; dop853 at 1e-12: 1.5e-10)."""
    errs = {}
    for method, tol in (("dopri5", 1e-8), ("dopri5", 1e-10), ("dop853", 1e-12)):
        mbs, s = mass_on_coordinate("limits")
        r = simulate(ExudynModel(mbs, s), (0, T), method=method, rtol=tol, atol=tol, t_eval=[T])
        assert r.success, r.message
        errs[method, tol] = _error(r, exact)
    assert errs["dopri5", 1e-8] < 5e-6
    assert errs["dopri5", 1e-10] < 5e-8 and errs["dopri5", 1e-10] < 0.1 * errs["dopri5", 1e-8]
    assert errs["dop853", 1e-12] < 2e-9


def test_limit_stops_through_the_drop_in(exact):
    """SolveDynamic at the script's settings: Exudyn's own loop no longer undoes the bridge's
    contact states (dop853 at 1e-12 stopped at the first stop; dopri5 at 1e-8 ended 0.15
    off). The drop-in locates switches to 4 × minimumStepSize (4e-8 s), which bounds its
    error: the stop's damping force d·v ≈ 100 N acts up to 4e-8 s early or late, 8e-6 m/s per
    switch, ten switches (measured: dop853 at 1e-12 1.7e-7, dopri5 at 1e-8 4.5e-6, at 1e-10
    3.9e-6). Exudyn's own generalized-α at 1000 steps is 0.12 off, at 256000 steps 9e-5."""
    for method, tol in (("dop853", 1e-12), ("dopri5", 1e-8)):
        mbs, s = mass_on_coordinate("limits")
        SolveDynamic(mbs, s, method=method, rtol=tol, atol=tol)
        assert mbs.sys["lgtBridgeStats"]["success"]
        x = mbs.systemData.GetODE2Coordinates()[0]
        assert abs(x - exact[0]) < 2e-5


def test_bristle_friction_agrees_with_exudyn_refined():
    """Sliding, sticking and sliding again with the bristle model: the end position against
    Exudyn's generalized-α at 64000 steps (which 256000 steps change by 7e-9). Before
    StartOfStep was set, the stick positions were off by the initial slip force's 1e-4 m and
    the end by 5.5e-5; with it, but stick <-> slip not a switch, by 3.6e-7; now 6e-8."""
    mbs, s = mass_on_coordinate("bristle", 64000)
    mbs.SolveDynamic(s, showHints=False)
    ref = mbs.systemData.GetODE2Coordinates()[0]
    mbs, s = mass_on_coordinate("bristle")
    r = simulate(ExudynModel(mbs, s), (0, T), method="dopri5", rtol=1e-10, atol=1e-10, t_eval=[T])
    assert r.success, r.message
    assert abs(r.q[-1][0] - ref) < 2e-7
