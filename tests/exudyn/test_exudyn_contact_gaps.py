"""Penalty contacts that switch their force on and off through the gap their PostNewton
stores in a data coordinate (ObjectContactCoordinate, ObjectContactConvexRoll: the force acts
while the stored gap is closed). Such a gap closing or opening inside a step is a switch
located in time, as for ObjectContactSphereSphere (``hooks.GAP_OBJECTS``).

Before, only the sphere contact's gap was one: the others switched at the end of the step
they fell in, up to Exudyn's step late, at any tolerance (Exudyn's contactCoordinateTest.py
ran 0.44 % off Exudyn's converged result, its ConvexContactTest.py 0.4 %)."""
import contextlib
import io
import warnings

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.errors import ModelNote  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

from exudyn_contact_gap_models import (coin_dropped, convex_roll_dropped, disc_on_curve,  # noqa: E402
                                       mass_on_coordinate_contact, pin_in_polygon_bowl)


def _position(mbs, node):
    """The node's position (for the 2-D disc: its coordinates x, y, φ)."""
    kind = exu.OutputVariableType.Coordinates if "2D" in str(mbs.GetNode(node)["nodeType"]) else \
        exu.OutputVariableType.Position
    return np.array(mbs.GetNodeOutput(node, kind))


def _exudyn(build, n):
    mbs, s, node = build(n=n)
    with contextlib.redirect_stdout(io.StringIO()):     # Exudyn prints each switch it meets
        mbs.SolveDynamic(s, showHints=False)
    return _position(mbs, node)


def _dopri5(build, tol):
    mbs, s, node = build()
    s.timeIntegration.relativeTolerance = s.timeIntegration.absoluteTolerance = tol
    with contextlib.redirect_stdout(io.StringIO()):
        SolveDynamic(mbs, s, method="dopri5")
    assert mbs.sys["lgtBridgeStats"]["success"]
    return _position(mbs, node)


@pytest.mark.parametrize("tol", [1e-8, 1e-10])
def test_coordinate_contact_closes_where_the_gap_does(tol):
    """A mass bouncing on an ObjectContactCoordinate, at 0.2 s: dopri5 within 2e-6 m of Exudyn's
    own generalized-α at 1e6 steps (measured 2.8e-7 and 2e-7; Exudyn's own at 3e5 steps differs
    from 1e6 by 1.6e-6). Before, 1.3e-4 at 1e-8 and 3.6e-4 at 1e-10."""
    ref = _exudyn(mass_on_coordinate_contact, 10**6)
    assert np.abs(_dopri5(mass_on_coordinate_contact, tol) - ref).max() < 2e-6


@pytest.mark.parametrize("tol", [1e-8, 1e-10])
def test_convex_roll_touches_down_where_the_gap_closes(tol):
    """A roll dropped on the floor through an ObjectContactConvexRoll, at 0.1 s: dopri5 within
    1e-6 m of Exudyn's own at 2e5 steps (measured 3e-8 at both tolerances; Exudyn at 2e4 steps
    differs from 2e5 by 2.7e-7). Before, 5.1e-6 at 1e-8, and at 1e-10 the step size fell below
    minimumStepSize at the first touch-down."""
    ref = _exudyn(convex_roll_dropped, 2 * 10**5)
    assert np.abs(_dopri5(convex_roll_dropped, tol) - ref).max() < 1e-6


@pytest.mark.parametrize("tol", [1e-8, 1e-10])
def test_a_circle_touches_down_on_a_curve_where_its_gap_closes(tol):
    """A disc bouncing on a floor of segments through an ObjectContactCurveCircles, at 0.3 s:
    dopri5 within 1e-6 m of Exudyn's own at 3e5 steps (measured 6e-8 at both tolerances;
    Exudyn at 3e4 steps differs from 3e5 by 2.6e-7). Before, touch-down and lift-off were
    taken at the end of the step they fell in: 1.8e-4 off at 1e-8, 1.8e-5 at 1e-10."""
    ref = _exudyn(disc_on_curve, 3 * 10**5)
    assert np.abs(_dopri5(disc_on_curve, tol) - ref).max() < 1e-6


@pytest.mark.parametrize("tol", [1e-8, 1e-10])
def test_a_circle_sliding_onto_the_next_segment_is_a_switch(tol):
    """A pin sliding down a bowl of 32 segments through an ObjectContactCurveCircles, in
    contact all along, at 0.3 s: dopri5 within 1e-6 m of Exudyn's own at 3e5 steps (measured
    7e-8 at both tolerances; Exudyn at 3e4 steps differs from 3e5 by 2.5e-7). Before, the
    segment the pin left kept pushing and the next one stayed idle until the step's end
    (only touch-down and lift-off were located): 4.6e-5 off at 1e-8, 1.2e-5 at 1e-10."""
    ref = _exudyn(pin_in_polygon_bowl, 3 * 10**5)
    assert np.abs(_dopri5(pin_in_polygon_bowl, tol) - ref).max() < 1e-6


def test_genalpha_takes_a_circles_touch_down_at_exudyns_steps():
    """genalpha keeps Exudyn's 300 steps (touch-down taken at the step's end, as Exudyn
    does) and Exudyn's own result at those steps (measured equal to 1e-15)."""
    ref = _exudyn(disc_on_curve, 300)
    mbs, s, node = disc_on_curve()
    with contextlib.redirect_stdout(io.StringIO()):
        SolveDynamic(mbs, s, method="genalpha")
    assert mbs.sys["lgtBridgeStats"]["n_steps"] == 300
    assert np.abs(_position(mbs, node) - ref).max() < 1e-9


def _contact_point(mbs, contact):
    return np.array(mbs.GetObjectOutput(contact, exu.OutputVariableType.Position))


def test_genalpha_takes_a_coins_touch_down_at_exudyns_steps():
    """Exudyn's rollingCoinPenaltyTest.py (a rolling coin dropped 1 cm onto the ground through
    a RollingDiscPenalty with regularized dry friction) at its 5000 steps: genalpha redoes the
    step in which the coin touches down, as Exudyn's discontinuous iteration does. Located
    instead (to 5e-8 s), the steps after the touch-down met the contact damping (1e4 Ns/m at
    0.44 m/s) on the located step's tiny remainder, their friction left its proportional zone
    and flipped at every redo, and the contact point ended 7e-4 m off Exudyn refined. Now
    within 5e-5 m of Exudyn's own solver refined 10× (measured 2.8e-5; Exudyn's own at the
    script's steps 3e-6), in at most 1.5× the steps (measured 5005)."""
    mbs, s, contact = coin_dropped(n=50000)
    with contextlib.redirect_stdout(io.StringIO()):
        mbs.SolveDynamic(s, showHints=False)
    ref = _contact_point(mbs, contact)
    mbs, s, contact = coin_dropped()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelNote)
        SolveDynamic(mbs, s, method="genalpha")
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and st["n_steps"] <= 1.5 * 5000
    assert np.abs(_contact_point(mbs, contact) - ref).max() < 5e-5
