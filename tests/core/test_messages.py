"""Messages that point the right way (issue 13): singular mass matrices rejected before the
first step, diverging explicit steps reported as divergence without numpy warnings, and
the Pinocchio / Exudyn adapters' input messages."""
import warnings

import numpy as np
import pytest

from lgt_bridge import scenes, simulate
from lgt_bridge.errors import InputError
from lgt_bridge.validation import mass_defects, mass_message

I3 = np.diag([1.0, 2.0, 3.0])


def _two_bodies(inertia2, **kw):
    fb = scenes.free_body()
    q0 = np.concatenate([fb.q0, fb.q0 + np.r_[1.0, 0, 0, 0, 0, 0, 0]])
    V0 = np.concatenate([fb.V0, fb.V0])
    return scenes.RigidBodySystem([1.0, 1.0], [I3, inertia2], q0, V0, names=["hull", "flap"], **kw)


# --- singular / indefinite mass matrix -----------------------------------------------------
@pytest.mark.parametrize("inertia2, kind", [(np.diag([1e-30, 1.0, 1.0]), "singular"),
                                            (np.diag([-1.0, 2.0, 2.0]), "indefinite")])
def test_zero_inertia_body_is_rejected_before_the_first_step(inertia2, kind):
    model = _two_bodies(inertia2)
    with pytest.raises(InputError, match=rf"mass matrix at q0 is {kind}.*body 1 \(flap\)") as exc:
        simulate(model, (0, 1), method="dopri5")
    assert "positive principal inertias" in str(exc.value)


def test_a_rounding_level_negative_eigenvalue_is_no_inertia_not_negative_inertia():
    """A rank-deficient M whose zero eigenvalue comes out at -1e-15 (Exudyn's ObjectANCFBeam):
    singular, "no inertia"; a clearly negative one stays indefinite."""
    for lam, kind in [(-1e-15, "singular"), (-1e-3, "indefinite")]:
        M = np.eye(3)
        M[0, 0] = lam
        msg = mass_message(mass_defects(M), ["coordinate 0 of node 0"] * 3)
        assert msg.startswith(f"mass matrix at q0 is {kind}")
        assert ("negative inertia" in msg) == (kind == "indefinite")


def test_valid_scenes_pass_the_mass_check():
    for model in (scenes.free_body(), scenes.heavy_top(), scenes.heavy_top(constrained=True),
                  scenes.chain(4), scenes.free_bodies(20), _two_bodies(I3)):
        simulate(model, (0, 1e-3), method="rkmk4", dt=1e-3).raise_for_status()


def test_mass_defects_blocks_and_constraints():
    M = np.diag([2.0, 1e-3, 5.0, 0.0])
    assert [i for i, _ in mass_defects(M)] == [3]
    # a rank-deficient coupled block: the eigenvector names an index inside it
    M = np.eye(4)
    M[1:3, 1:3] = [[1.0, 1.0], [1.0, 1.0]]
    (i, lam), = mass_defects(M)
    assert i in (1, 2) and abs(lam) < 1e-12
    # the same singular direction held by a constraint is fine (index-1 solve is regular)
    A = np.array([[0.0, 1.0, -1.0, 0.0]])
    assert mass_defects(M, A) == []
    # units do not matter: a light but regular body passes
    assert mass_defects(np.diag([1e-9, 1e-9, 1e-9, 100.0, 100.0, 100.0])) == []


# --- diverging explicit steps -----------------------------------------------------------------
def _stiff_spring():
    fb = scenes.free_body()
    s = np.array([0.1, 0.0, 0.0])
    return scenes.RigidBodySystem([1.0], [I3], fb.q0, fb.V0, gravity=np.zeros(3),
                                  springs=[(0, s, -1, s, 1e8, 0.0)])


@pytest.mark.parametrize("backend", ["numba", "numpy"])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_diverging_explicit_step_says_diverged_without_warnings(monkeypatch, backend, group):
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", backend)
    model = _stiff_spring()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        res = simulate(model, (0, 1), method="rkmk4", dt=1e-3, group=group)
    assert not res.success
    msg = res.message
    assert "diverged" in msg and "reduce dt" in msg and "genalpha" in msg
    assert "body 0" in msg
    assert "the model returned NaN/inf" not in msg
    assert len(res.t) > 1                      # the steps before it are kept


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_model_nan_at_a_calm_state_still_blames_the_model(monkeypatch, backend):
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", backend)
    model = scenes.free_body()
    f = model.f

    def bad_f(q, V, t):
        out = np.array(f(q, V, t))
        if t > 0.0105:
            out[0] = np.nan
        return out
    model.f = bad_f
    res = simulate(model, (0, 1), method="rkmk4", dt=1e-2)
    assert not res.success
    assert "the model returned NaN/inf" in res.message and "diverged" not in res.message


def test_adaptive_method_survives_the_stiff_spring():
    res = simulate(_stiff_spring(), (0, 1e-3), method="dopri5", rtol=1e-6, atol=1e-8)
    assert res.success, res.message


# --- Pinocchio --------------------------------------------------------------------------------
pin = pytest.importorskip("pinocchio")


def _pin_model(**kw):
    from lgt_pinocchio import PinocchioModel
    return PinocchioModel(pin.buildSampleModelHumanoid(), **kw)


def test_pinocchio_tau_with_the_wrong_signature():
    with pytest.raises(InputError, match=r"tau: expected a callable tau\(t, q, v\)"):
        _pin_model(tau=lambda t: np.zeros(3))
    with pytest.raises(InputError, match=r"fext: expected a callable fext\(t, q, v\)"):
        _pin_model(fext=lambda t, q: None)
    _pin_model(tau=lambda t, q, v, *rest: np.zeros(len(v)))       # extra optional args are fine


def test_pinocchio_data_instead_of_model():
    from lgt_pinocchio import PinocchioModel
    m = pin.buildSampleModelHumanoid()
    with pytest.raises(InputError, match=r"got a pinocchio.Data; pass the pinocchio.Model"):
        PinocchioModel(m.createData())
    with pytest.raises(InputError, match=r"expected a pinocchio.Model, got a str"):
        PinocchioModel("talos")


def test_pinocchio_nan_in_q0_names_the_joint():
    m = pin.buildSampleModelHumanoid()
    q0 = pin.neutral(m)
    q0[10] = np.nan
    j = next(j for j in range(1, m.njoints) if m.joints[j].idx_q <= 10 < m.joints[j].idx_q + m.joints[j].nq)
    with pytest.raises(InputError, match=rf"q0: entry 10 \(joint '{m.names[j]}' \(Pinocchio joint {j}\)\)"):
        _pin_model(q0=q0)


def test_pinocchio_zero_inertia_link_is_rejected_and_armature_fixes_it():
    from lgt_pinocchio import PinocchioModel
    m = pin.buildSampleModelHumanoid()
    j = m.njoints - 1                                  # a leaf joint: give its link no inertia
    m.inertias[j] = pin.Inertia.Zero()
    model = PinocchioModel(m)
    with pytest.raises(InputError, match=rf"mass matrix \(crba\) at q0 is singular.*joint '{m.names[j]}'"):
        simulate(model, (0, 1), method="dopri5")
    m.armature[:] = 1e-3
    simulate(PinocchioModel(m), (0, 1e-3), method="rkmk4", dt=1e-3).raise_for_status()


def _erd(name):
    erd = pytest.importorskip("example_robot_data")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return erd.load(name)


@pytest.mark.parametrize("name, joint", [("icub", "neck_yaw"), ("romeo", "LFinger")])
def test_example_robot_data_zero_inertia_robots_are_rejected(name, joint):
    from lgt_pinocchio import PinocchioModel
    r = _erd(name)
    with pytest.raises(InputError, match=rf"singular: the motion of joint '{joint}"):
        simulate(PinocchioModel(r.model, q0=r.q0), (0, 1), method="dopri5")


@pytest.mark.parametrize("name", ["solo12", "go2", "talos"])
def test_example_robot_data_valid_robots_pass(name):
    from lgt_pinocchio import PinocchioModel
    r = _erd(name)
    PinocchioModel(r.model, q0=r.q0).check_mass_matrix(r.q0)


def test_pinocchio_sample_models_pass():
    from lgt_pinocchio import PinocchioModel
    for m in (pin.buildSampleModelHumanoid(), pin.buildSampleModelHumanoidRandom(),
              pin.buildSampleModelManipulator()):
        PinocchioModel(m).check_mass_matrix(pin.neutral(m))


# --- Exudyn -----------------------------------------------------------------------------------
def _exu_top():
    exu = pytest.importorskip("exudyn")
    from lgt_exudyn.scenes import EP, heavy_top
    SC, mbs, _ = heavy_top(EP)
    return exu, SC, mbs


def test_exudyn_end_before_start_in_exudyn_setting_names():
    exu, SC, mbs = _exu_top()
    from lgt_exudyn import SolveDynamic
    s = exu.SimulationSettings()
    s.timeIntegration.startTime = 1.0
    s.timeIntegration.endTime = 0.5
    with pytest.raises(InputError, match=r"simulationSettings.timeIntegration.endTime = 0.5 must be greater "
                                         r"than simulationSettings.timeIntegration.startTime = 1.0"):
        SolveDynamic(mbs, s)


def test_exudyn_non_unit_euler_parameters_say_reference_plus_initial():
    exu = pytest.importorskip("exudyn")
    from exudyn.utilities import NodeRigidBodyEP, ObjectRigidBody
    from lgt_exudyn import ExudynModel
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    n = mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[0, 0, 0, 1, 0, 0, 0],
                                    initialCoordinates=[0, 0, 0, 0.1, 0, 0, 0], name="top"))
    mbs.AddObject(ObjectRigidBody(mass=1.0, inertia=[1, 2, 3, 0, 0, 0], nodeNumber=n))
    mbs.Assemble()
    with pytest.raises(InputError, match=r"node 'top': its Euler parameters reference \+ initial coordinates = "
                                         r"\[1, 0, 0, 0\] \+ \[0.1, 0, 0, 0\] = \[1.1, 0, 0, 0\] have norm 1.1"):
        ExudynModel(mbs)


def test_exudyn_models_pass_the_mass_check():
    exu, SC, mbs = _exu_top()
    from lgt_exudyn import ExudynModel
    from lgt_exudyn.scenes import chain
    for m in (mbs, chain(3)[1]):
        simulate(ExudynModel(m), (0, 1e-3), method="rkmk4", dt=1e-3).raise_for_status()


def test_exudyn_massless_node_is_named():
    exu = pytest.importorskip("exudyn")
    from exudyn.utilities import MassPoint, NodePoint
    from lgt_exudyn import ExudynModel
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    n = mbs.AddNode(NodePoint(referenceCoordinates=[0, 0, 0]))
    mbs.AddObject(MassPoint(mass=1.0, nodeNumber=n))
    n2 = mbs.AddNode(NodePoint(referenceCoordinates=[1, 0, 0]))
    mbs.AddObject(MassPoint(mass=0.0, nodeNumber=n2))
    mbs.Assemble()
    with pytest.raises(InputError, match=r"mass matrix at q0 is singular: the motion of coordinate 0 of node 1 "
                                         r"\(NodePoint\) of ObjectMassPoint 1 \(velocity index 3\)"):
        simulate(ExudynModel(mbs), (0, 1), method="dopri5")


def test_singular_inertia_is_an_input_error_naming_the_body():
    """numpy's LinAlgError from inverting the inertias used to reach the user."""
    q0 = np.array([0, 0, 0, 1.0, 0, 0, 0] * 2)
    with pytest.raises(InputError, match=r"body 1: its inertia matrix .* is singular"):
        scenes.RigidBodySystem([1.0, 1.0], [np.eye(3), np.zeros((3, 3))], q0, np.zeros(12))


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_pinocchio_f_with_a_wrong_size_twist_is_an_input_error(backend):
    pin = pytest.importorskip("pinocchio")
    from lgt_pinocchio import PinocchioModel
    for model in (pin.buildSampleModelHumanoidRandom(), pin.buildSampleModelManipulator()):  # root / fixed base
        pm = PinocchioModel(model, backend=backend)
        with pytest.raises(InputError, match="V of shape"):
            pm.f(pm.q0, np.zeros(3), 0.0)
