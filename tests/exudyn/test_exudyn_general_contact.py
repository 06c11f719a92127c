"""Exudyn's GeneralContact (issue 21, item 4): its forces come from the active sets that
Exudyn's PostNewton sets from the state; the bridge takes them at each step's start, locates
where they switch inside a step of a method with dense output and restarts there
(lgt_bridge.switches, lgt_exudyn.contact). References independent of the bridge: the closed
form of a point dropped on the floor through that contact (tests/models/contact_reference.py),
scipy's DOP853 at 1e-13 on a column of spheres with every switch as an event, and Exudyn's own
generalized-α refined."""
import warnings

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

import lgt_bridge  # noqa: E402
from lgt_bridge import StepError  # noqa: E402
from lgt_bridge.errors import ModelNote  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402
from lgt_exudyn.hooks import general_contacts  # noqa: E402
from lgt_exudyn.model import ExudynModel  # noqa: E402

import contact_reference as cr  # noqa: E402
import exudyn_solver_models as sm  # noqa: E402

T_FLOOR = 0.5


def _floor_exact():
    """(y0, y1, ẏ0, ẏ1) at 0.5 s of the two spheres of sm.general_contact_spheres (they never
    meet: each is a point dropped on the floor) and their switch count. Stiffness in series
    (1e4 with 1e4: 5e3), dampings added (10 + 10)."""
    (a, va), sa = cr.drop(0.25, -1.0, T_FLOOR)
    (b, vb), sb = cr.drop(0.55, -1.0, T_FLOOR)
    return np.array([a, b, va, vb]), len(sa) + len(sb)


def _state(q, V):
    return np.r_[q[[1, 4]], V[[1, 4]]]


def _solve_dynamic(method, tol):
    mbs, s = sm.general_contact_spheres()
    SolveDynamic(mbs, s, method=method, rtol=tol, atol=tol)
    sd = mbs.systemData
    q = np.array(sd.GetODE2Coordinates()) + np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))
    return _state(q, np.array(sd.GetODE2Coordinates_t())), mbs.sys["lgtBridgeStats"]


@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_contact_switches_located_error_falls_with_tolerance(method):
    """dopri5/dop853 at rtol = atol = 1e-10 collapsed at the first touch (the damping force
    jumps there). Now each switch is located and the step restarted there: simulate() and
    SolveDynamic both run through, finding the 9 switches of the exact motion, and the error
    against it falls with the tolerance (measured from 1e-10 to 1e-12, simulate /
    SolveDynamic: dopri5 9.5e-10 → 1.2e-11 / 9.3e-10 → 1.2e-11, dop853 4.0e-10 → 4.5e-12 /
    4.4e-12 → 3.9e-13, its steps capped at Exudyn's 1e-3). Before, simulate() never saw a contact force
    (the spheres fell through the floor): nothing had set Exudyn's active sets."""
    exact, n_switches = _floor_exact()
    errs = []
    for tol in (1e-10, 1e-12):
        mbs, s = sm.general_contact_spheres()
        r = lgt_bridge.simulate(ExudynModel(mbs, s), (0, T_FLOOR), method=method, rtol=tol, atol=tol)
        assert r.success and r.stats["n_switches"] == n_switches
        errs.append(np.abs(_state(r.q[-1], r.V[-1]) - exact).max())
        x, st = _solve_dynamic(method, tol)
        assert st["success"]
        errs.append(np.abs(x - exact).max())
    assert max(errs[:2]) < 2e-9 and max(errs[2:]) < 3e-11, errs
    assert errs[2] < errs[0] / 10 and errs[3] < errs[1] / 5, errs


@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_sphere_column_error_falls_with_tolerance(method):
    """Three spheres in a column bouncing on the floor and on each other (sphere-sphere and
    sphere-triangle contacts, 17 switches), against scipy's DOP853 at 1e-13 with every switch
    located as an event (measured: dopri5 4.6e-10 → 5.3e-12, dop853 3.1e-11 → 3.6e-12)."""
    C = sm.COLUMN
    (ys, vs), sw = cr.column([C["y0"] + C["dy"] * i for i in range(3)], -1.0, 0.4)
    errs = []
    for tol in (1e-10, 1e-12):
        mbs, s = sm.general_contact_column()
        r = lgt_bridge.simulate(ExudynModel(mbs, s), (0, 0.4), method=method, rtol=tol, atol=tol)
        assert r.success and r.stats["n_switches"] == len(sw)
        errs.append(np.abs(np.r_[r.q[-1][1::3] - ys, r.V[-1][1::3] - vs]).max())
    assert errs[0] < 2e-9 and errs[1] < 2e-11 and errs[1] < errs[0] / 5, errs


def test_exudyns_own_generalized_alpha_refined_tends_to_the_same_motion():
    """Exudyn's generalized-α takes the active sets of each step's start (its PostNewton after
    the step), so each switch costs it an O(h) error: refined from 1e-3 to 1.5625e-5 its
    error against the exact motion falls from 0.42 to 9.4e-3 (velocities; positions hold
    about 3 digits at the finest step), towards the motion the bridge's located switches
    give to 1e-9 at 1e-10; on the sphere column likewise."""
    exact, _ = _floor_exact()
    errs = []
    for k in (0, 3, 6):
        mbs, s = sm.general_contact_spheres()
        s.timeIntegration.numberOfSteps = 500 * 2 ** k
        mbs.SolveDynamic(s)
        sd = mbs.systemData
        q = np.array(sd.GetODE2Coordinates()) + np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))
        errs.append(np.abs(_state(q, np.array(sd.GetODE2Coordinates_t())) - exact).max())
    assert errs[2] < errs[1] < errs[0] and errs[2] < 0.05 * errs[0], errs
    x, _ = _solve_dynamic("dop853", 1e-10)
    assert np.abs(x - exact).max() < 1e-6 * errs[2]
    # the sphere column: 6.8e-3, 4.2e-4, 4.9e-5 (positions 8.7e-6 → 2.1e-7) at 1e-3, 1.25e-4,
    # 1.5625e-5, against the bridge's 3.1e-11 (dop853 at 1e-10)
    C = sm.COLUMN
    (ys, vs), _ = cr.column([C["y0"] + C["dy"] * i for i in range(3)], -1.0, 0.4)
    errs = []
    for k in (0, 3, 6):
        mbs, s = sm.general_contact_column(steps=400 * 2 ** k)
        mbs.SolveDynamic(s)
        sd = mbs.systemData
        q = np.array(sd.GetODE2Coordinates()) + np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))
        errs.append(np.abs(np.r_[q[1::3] - ys, np.array(sd.GetODE2Coordinates_t())[1::3] - vs]).max())
    assert errs[2] < errs[1] < errs[0] and errs[2] < 0.05 * errs[0], errs
    mbs, s = sm.general_contact_column()
    SolveDynamic(mbs, s, method="dop853", rtol=1e-10, atol=1e-10)
    sd = mbs.systemData
    q = np.array(sd.GetODE2Coordinates()) + np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))
    assert np.abs(np.r_[q[1::3] - ys, np.array(sd.GetODE2Coordinates_t())[1::3] - vs]).max() < 1e-5 * errs[2]


def test_general_contact_failure_names_it_in_one_line_and_keeps_the_steps():
    """A run that still fails (here: minimumStepSize 5e-4 above what the contact phase needs
    at 1e-10) says so in one line naming the GeneralContact, its parts and that the switches
    were located; the steps before are kept: it stops at the first switch, t = 0.10047899
    (sphere 0 touching, y = 0.1), sphere 1 in free fall y = 0.55 - t - g t²/2 (to 1e-9).
    Without dense output the message says the switches are not located. genalpha at Exudyn's
    steps gives Exudyn's own generalized-α result (both take the active sets at each step's
    start)."""
    mbs, s = sm.general_contact_spheres()
    s.timeIntegration.minimumStepSize = 5e-4
    with pytest.raises(StepError) as exc:
        SolveDynamic(mbs, s, method="dopri5", rtol=1e-10, atol=1e-10)
    msg = str(exc.value)
    assert "\n" not in msg and "GeneralContact 0 (2 spheres, 2 triangles)" in msg
    assert "located these switches" in msg and "radau5" in msg
    (_, _), sw = cr.drop(0.25, -1.0, 0.2)
    t = mbs.systemData.GetTime()
    assert abs(t - sw[0]) < 1e-9
    y = np.array(mbs.systemData.GetODE2Coordinates())[[1, 4]] + np.array([0.25, 0.55])
    assert np.abs(y - [0.1, 0.55 - t - 0.5 * 9.81 * t ** 2]).max() < 1e-9
    assert "does not locate these switches" in general_contacts(mbs, located=False)
    mbs, s = sm.general_contact_spheres()
    mbs.SolveDynamic(s)
    exu_q = np.array(mbs.systemData.GetODE2Coordinates())
    mbs, s = sm.general_contact_spheres()
    SolveDynamic(mbs, s, method="genalpha")
    assert np.abs(np.array(mbs.systemData.GetODE2Coordinates()) - exu_q).max() < 1e-6


def test_an_explicit_solver_type_on_damped_general_contact_is_announced():
    """Exudyn's explicit solvers keep no active sets: a damped pair pulls as it separates, so
    Exudyn's own RK44 at 5e4 steps has the second sphere at rest on the floor at 0.5 s
    (|ẏ| ≈ 1e-6 m/s), where the law of its implicit solvers, which the bridge follows, has it
    bouncing (exact: ẏ = -0.228 m/s). A script asking for solverType=RK44 gets a ModelNote
    saying so (Exudyn's generalContactCylinderTest.py, ExplicitEuler: 0.5 % apart at 2 s),
    and the bridge's motion is still the exact one of its law; solverType=GeneralizedAlpha
    gets no note."""
    exact, _ = _floor_exact()
    mbs, s = sm.general_contact_spheres()
    s.timeIntegration.numberOfSteps = 50000
    mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.RK44)
    sd = mbs.systemData
    assert abs(sd.GetODE2Coordinates_t()[4] - exact[3]) > 0.2            # Exudyn's explicit law
    mbs, s = sm.general_contact_spheres()
    with pytest.warns(ModelNote, match="solverType = RK44"):
        SolveDynamic(mbs, s, solverType=exu.DynamicSolverType.RK44, method="dopri5", rtol=1e-10, atol=1e-10)
    sd = mbs.systemData
    q = np.array(sd.GetODE2Coordinates()) + np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))
    assert np.abs(_state(q, np.array(sd.GetODE2Coordinates_t())) - exact).max() < 1e-8
    mbs, s = sm.general_contact_spheres()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        SolveDynamic(mbs, s, solverType=exu.DynamicSolverType.GeneralizedAlpha, method="dopri5")
    assert not [w for w in caught if "GeneralContact" in str(w.message)]


def test_chattering_active_sets_stop_dopri5_naming_genalpha_which_runs():
    """A rope lying on a roll at zero gap (Exudyn's reevingSystemOpen.py in small,
    exudyn_rope_models): its cables' active sets switch back at once after every located
    switch, so each dopri5 step is cut at the next one (steps of 1e-17 s). The stop says the
    mode chatters and names genalpha (it blamed sign(v) friction and advised radau5, which
    stops the same way). genalpha runs at Exudyn's 100 steps and lies as far from Exudyn's own
    generalized-α refined 100x as Exudyn's own steps do (measured 4.6e-3; Exudyn at 100
    steps 4.7e-3, at 1000 5.5e-4, refined 100x 6.5e-5 from 1000x)."""
    from exudyn_rope_models import rope_over_roll
    mbs, s = rope_over_roll()
    with pytest.raises(StepError) as exc:
        SolveDynamic(mbs, s, method="dopri5")
    msg = str(exc.value)
    assert "the mode chatters" in msg and "method='genalpha'" in msg, msg
    assert "radau5'" not in msg.split("chatters", 1)[1], msg         # no advice to use radau5
    assert "sign(v)" not in msg, msg
    mbs, s = rope_over_roll(steps=100 * 100)
    mbs.SolveDynamic(s)
    ref = np.array(mbs.systemData.GetODE2Coordinates())
    mbs, s = rope_over_roll()
    SolveDynamic(mbs, s, method="genalpha")
    assert mbs.sys["lgtBridgeStats"]["success"] and mbs.sys["lgtBridgeStats"]["n_steps"] == 100
    assert np.abs(np.array(mbs.systemData.GetODE2Coordinates()) - ref).max() < 1e-2
