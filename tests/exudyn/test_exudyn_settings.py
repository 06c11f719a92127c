"""Issue 11, items 8 and 10: ``lgt_exudyn.SolveDynamic`` honours Exudyn's simulation
settings as Exudyn's own SolveDynamic does, and ``lgt-bridge run`` runs a script as
``python script.py`` would (skipped only when exudyn is not installed)."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from exudyn.utilities import (LoadForceVector, MarkerBodyPosition, MarkerNodePosition, MassPoint,  # noqa: E402
                              NodePoint, ObjectConnectorSpringDamper, ObjectGround, SensorNode)

from lgt_bridge import InputError, StepError, cli  # noqa: E402
from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_exudyn import ExudynModel, SolveDynamic  # noqa: E402
from lgt_exudyn import solve as solve_module  # noqa: E402

import exudyn_models as em  # noqa: E402

def point_mass():
    """A point mass on a spring to ground, with gravity and a time-dependent force: a model
    Exudyn's own explicit solvers (DOPRI5) accept."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    n = mbs.AddNode(NodePoint(referenceCoordinates=[1.0, 0, 0], initialVelocities=[0, 2.0, 0.5]))
    mbs.AddObject(MassPoint(mass=2.0, nodeNumber=n))
    mG = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
    mP = mbs.AddMarker(MarkerNodePosition(nodeNumber=n))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mG, mP], stiffness=400, damping=1,
                                              referenceLength=0.8))
    mbs.AddLoad(LoadForceVector(markerNumber=mP, loadVector=[0, 0, 0],
                                loadVectorUserFunction=lambda mbs, t, load: [5 * np.sin(10 * t), 0, -9.81 * 2]))
    mbs.Assemble()
    return SC, mbs


def fixed_settings(T, n):
    s = em.settings(T, n)
    s.timeIntegration.automaticStepSize = False
    return s


def reference(make, t0, t1):
    """Final total coordinates by the bridge's dop853 at rtol = atol = 1e-12."""
    SC, mbs = make()[:2]
    r = simulate(ExudynModel(mbs), (t0, t1), method="dop853", rtol=1e-12, atol=1e-12, t_eval=[t1])
    assert r.success
    return r.q[-1]


# --- item 8: automaticStepSize = False --------------------------------------------------------

def test_automatic_step_size_off_gives_fixed_dopri5_steps_as_exudyns_dopri5():
    """automaticStepSize=False: dopri5 takes numberOfSteps fixed steps with its own tableau
    (6 f evaluations each, the FSAL end stage dropped), the same steps as Exudyn's DOPRI5
    with its error check switched off (adaptiveStep=False, huge tolerances): equal to
    round-off. 5th order: halving the step divides the error by about 32."""
    T = 0.5
    ref = reference(point_mass, 0, T)
    errs = []
    for n in (25, 50):
        SC, mbs = point_mass()
        s = fixed_settings(T, n)
        s.timeIntegration.solverType = exu.DynamicSolverType.DOPRI5
        s.timeIntegration.adaptiveStep = False
        s.timeIntegration.relativeTolerance = s.timeIntegration.absoluteTolerance = 1e3
        mbs.SolveDynamic(s)
        q_native = em.total_q(mbs)
        SC, mbs = point_mass()
        assert SolveDynamic(mbs, fixed_settings(T, n), method="dopri5")
        st = mbs.sys["lgtBridgeStats"]
        assert st["n_steps"] == n and st["n_f"] == 6 * n and st["n_rejected"] == 0
        assert st["dt"] == pytest.approx(T / n) and st["rtol"] is None
        q = em.total_q(mbs)
        assert np.abs(q - q_native).max() < 1e-13
        errs.append(np.abs(q - ref).max())
    assert 20 < errs[0] / errs[1] < 45, errs
    assert "fixed step 0.01 s (automaticStepSize=False" in solve_module.describe(st)


def test_automatic_step_size_off_gives_fixed_dop853_steps():
    """dop853 at fixed steps: 12 f evaluations per step, 8th order (ratio ~256 per halving)."""
    T = 0.5
    ref = reference(point_mass, 0, T)
    errs = []
    for n in (10, 20):
        SC, mbs = point_mass()
        SolveDynamic(mbs, fixed_settings(T, n), method="dop853")
        st = mbs.sys["lgtBridgeStats"]
        assert st["n_steps"] == n and st["n_f"] == 12 * n and st["success"]
        errs.append(np.abs(em.total_q(mbs) - ref).max())
    assert 120 < errs[0] / errs[1] < 500, errs


def test_tolerances_passed_explicitly_keep_error_control():
    """rtol/atol given to SolveDynamic (lgt-bridge run --rtol/--atol) select error control
    even when the script switched automaticStepSize off."""
    SC, mbs = point_mass()
    SolveDynamic(mbs, fixed_settings(0.5, 50), method="dopri5", rtol=1e-9, atol=1e-9)
    st = mbs.sys["lgtBridgeStats"]
    assert st["rtol"] == 1e-9 and st["dt"] is None and st["tolerance_source"] == dict(rtol="given", atol="given")


def test_fixed_dopri5_on_a_constrained_rigid_body_model():
    """EP heavy top with its spherical joint (Exudyn's explicit solvers refuse it): fixed
    dopri5 steps stay on the constraint (projection) and close to the adaptive result."""
    T, n = 0.05, 100
    SC, mbs, _ = em.heavy_top(em.EP)
    SolveDynamic(mbs, fixed_settings(T, n), method="dopri5")
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and st["n_steps"] == n and st["constraint_after_projection"] < 1e-10
    SC2, mbs2, _ = em.heavy_top(em.EP)
    SolveDynamic(mbs2, em.settings(T, n), method="dopri5", rtol=1e-10, atol=1e-10)
    assert np.abs(em.total_q(mbs) - em.total_q(mbs2)).max() < 1e-6


# --- item 8: tolerances ------------------------------------------------------------------------

def test_relative_tolerance_zero_is_pure_absolute_tolerance():
    """relativeTolerance = 0 (allowed by Exudyn) is accepted by SolveDynamic and by the core;
    atol must stay positive."""
    T = 0.5
    ref = reference(em.spring_body_with_load, 0, T)
    SC, mbs = em.spring_body_with_load()
    s = em.settings(T, 50)
    s.timeIntegration.relativeTolerance = 0.0
    s.timeIntegration.absoluteTolerance = 1e-9
    SolveDynamic(mbs, s, method="dopri5")
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and st["rtol"] == 0.0 and st["atol"] == 1e-9
    assert "rtol=0, atol=1e-09 (from simulationSettings.timeIntegration" in solve_module.describe(st)
    assert np.abs(em.total_q(mbs) - ref).max() < 1e-6
    model = ExudynModel(em.spring_body_with_load()[1])
    r = simulate(model, (0, T), method="dop853", rtol=0, atol=1e-9, t_eval=[T])
    assert r.success and np.abs(r.q[-1] - ref).max() < 1e-6
    with pytest.raises(InputError, match="atol = 0"):
        simulate(model, (0, T), method="dopri5", rtol=0, atol=0)
    with pytest.raises(InputError, match="rtol = -1"):
        simulate(model, (0, T), method="dopri5", rtol=-1, atol=1e-9)
    SC, mbs = em.spring_body_with_load()
    s.timeIntegration.absoluteTolerance = 0.0
    with pytest.raises(InputError, match="atol = 0"):
        SolveDynamic(mbs, s, method="dopri5")


# --- item 8: minimumStepSize, initialStepSize ---------------------------------------------------

def _jump_model():
    """The spring body with a force that jumps at t = 0.1 s (as a user writes a switched load)."""
    SC, mbs = em.spring_body_with_load()
    mbs.SetLoadParameter(0, "loadVectorUserFunction", lambda mbs, t, load: [0, 0, 100.0] if t > 0.1 else [0, 0, 0])
    return SC, mbs


def test_minimum_step_size_stops_error_control_with_a_step_error():
    """Resolving the jump needs steps far below 1e-3 s: with minimumStepSize = 1e-3 the run
    fails with a StepError naming the setting, the system left at the last good state before
    the jump; with Exudyn's default (1e-8) it succeeds."""
    SC, mbs = _jump_model()
    s = em.settings(0.3, 30)
    assert s.timeIntegration.minimumStepSize == 1e-8
    SolveDynamic(mbs, s, method="dopri5")
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and st["minimum_step"] == 1e-8 and st["n_rejected"] > 0
    SC, mbs = _jump_model()
    s.timeIntegration.minimumStepSize = 1e-3
    with pytest.raises(StepError, match=r"below simulationSettings\.timeIntegration\.minimumStepSize = 0\.001"):
        SolveDynamic(mbs, s, method="dopri5")
    st = mbs.sys["lgtBridgeStats"]
    t = mbs.systemData.GetTime()
    assert not st["success"] and 0.05 < t <= 0.1 + 1e-3
    assert np.isfinite(em.total_q(mbs)).all()


def test_initial_step_size_is_the_first_trial_step():
    """initialStepSize > 0 is the first trial step; 0 (Exudyn's default) leaves it to the
    bridge's starting-step estimate. Either way the run reaches the same state."""
    T = 0.2
    out = {}
    for h0 in (0.0, 1e-5):
        SC, mbs = em.spring_body_with_load()
        s = em.settings(T, 20)
        s.timeIntegration.initialStepSize = h0
        SolveDynamic(mbs, s, method="dopri5", rtol=1e-10, atol=1e-10)
        out[h0] = mbs.sys["lgtBridgeStats"], em.total_q(mbs)
    assert out[1e-5][0]["first_step"] == 1e-5
    assert out[0.0][0]["first_step"] > 1e-4                  # the estimate, not Exudyn's 0
    assert out[1e-5][0]["n_steps"] > out[0.0][0]["n_steps"]  # grows from the tiny first step
    assert np.abs(out[1e-5][1] - out[0.0][1]).max() < 1e-8


# --- item 8: startTime, output periods, output steps -------------------------------------------

def _times_in_file(path):
    rows = [ln for ln in Path(path).read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    return np.array([float(r.split(",")[0]) for r in rows])


def _with_outputs(tmp_path, tag, solve):
    """The spring body from startTime = 0.1 with a sensor file, an internally stored sensor
    and the solution file, written at periods that are no multiple of the step."""
    SC, mbs = em.spring_body_with_load()
    node = 0
    mbs.AddSensor(SensorNode(nodeNumber=node, fileName=str(tmp_path / f"{tag}_sensor.txt"),
                             outputVariableType=exu.OutputVariableType.Position))
    si = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                  outputVariableType=exu.OutputVariableType.Velocity))
    mbs.Assemble()
    s = em.settings(0.4, 150, write=True, sensors=True)
    s.timeIntegration.startTime = 0.1
    s.solution.file.name = str(tmp_path / f"{tag}_sol.txt")
    s.solution.file.writePeriod = 0.007
    s.solution.sensors.writePeriod = 0.005
    solve(mbs, s)
    return (_times_in_file(tmp_path / f"{tag}_sol.txt"), _times_in_file(tmp_path / f"{tag}_sensor.txt"),
            mbs.GetSensorStoredData(si), mbs)


@pytest.mark.parametrize("method,fixed", [("dopri5", False), ("dop853", True), ("rkmk4", False)],
                         ids=["dopri5", "dop853-fixed", "rkmk4"])
def test_start_time_and_write_periods_as_exudyn_writes_them(tmp_path, method, fixed):
    """startTime, solution.file.writePeriod and solution.sensors.writePeriod: Exudyn keeps
    its loop, so the solution file, the sensor file and the stored sensor data hold the same
    times as Exudyn's own solver writes; the values agree with it (generalized-α: 2nd order)."""
    def bridge(mbs, s):
        s.timeIntegration.automaticStepSize = not fixed
        SolveDynamic(mbs, s, method=method, rtol=1e-9 if not fixed else None, atol=1e-9 if not fixed else None)

    sol_n, sens_n, data_n, _ = _with_outputs(tmp_path, "native", lambda mbs, s: mbs.SolveDynamic(s))
    sol_b, sens_b, data_b, mbs = _with_outputs(tmp_path, "bridge", bridge)
    assert sens_n[0] == pytest.approx(0.1) and sens_n[-1] == pytest.approx(0.4)
    assert len(sol_n) > 10 and len(sens_n) > 10
    np.testing.assert_array_equal(sol_b, sol_n)
    np.testing.assert_array_equal(sens_b, sens_n)
    np.testing.assert_array_equal(data_b[:, 0], data_n[:, 0])
    assert np.abs(data_b[:, 1:] - data_n[:, 1:]).max() < 1e-2 * np.abs(data_n[:, 1:]).max()
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and (st["dt"] is not None) == (fixed or method == "rkmk4")
    assert mbs.systemData.GetTime() == pytest.approx(0.4)


def test_start_time_integrates_from_start_time():
    """startTime = 0.2: the time-dependent load is evaluated from t = 0.2 on (the same run as
    simulate over (0.2, 0.5))."""
    SC, mbs = em.spring_body_with_load()
    s = em.settings(0.5, 30)
    s.timeIntegration.startTime = 0.2
    SolveDynamic(mbs, s, method="dopri5", rtol=1e-10, atol=1e-10)
    assert np.abs(em.total_q(mbs) - reference(em.spring_body_with_load, 0.2, 0.5)).max() < 1e-7
    assert np.abs(em.total_q(mbs) - reference(em.spring_body_with_load, 0.0, 0.3)).max() > 1e-4


@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_more_output_steps_do_not_add_bridge_steps(method):
    """With the cap lifted (max_step=None), adaptive methods are not capped at the output
    interval: ten times more Exudyn output
    steps come from dense output, not from more integration steps."""
    st, q = [], []
    for n in (40, 400):
        SC, mbs = em.spring_body_with_load()
        SolveDynamic(mbs, em.settings(0.5, n), method=method, rtol=1e-8, atol=1e-8, max_step=None)
        st.append(mbs.sys["lgtBridgeStats"])
        q.append(em.total_q(mbs))
    assert st[0]["success"] and st[1]["success"] and st[1]["exudyn_steps"] == 400
    assert st[1]["n_steps"] < 400 / 3                     # steps longer than the output interval
    assert st[1]["n_steps"] <= 1.03 * st[0]["n_steps"], (st[0]["n_steps"], st[1]["n_steps"])
    assert np.abs(q[0] - q[1]).max() < 1e-9


# --- item 8: verboseMode, realtime ------------------------------------------------------------

def test_verbose_mode_prints_the_description(capsys):
    SC, mbs = em.spring_body_with_load()
    s = em.settings(0.05, 10)
    SolveDynamic(mbs, s, method="dopri5")
    assert "lgt-bridge: SolveDynamic" not in capsys.readouterr().out      # verboseMode = 0
    s.timeIntegration.verboseMode = 1
    SC, mbs = em.spring_body_with_load()
    SolveDynamic(mbs, s, method="dopri5")
    out = capsys.readouterr().out
    line = [ln for ln in out.splitlines() if ln.startswith("lgt-bridge: SolveDynamic")]
    assert len(line) == 1 and "dopri5 on SO3xR3/exp, rtol=1e-08, atol=1e-08" in line[0] and "steps" in line[0]
    SC, mbs = em.spring_body_with_load()
    SolveDynamic(mbs, s, method="dopri5", verbose=False)
    assert "lgt-bridge: SolveDynamic" not in capsys.readouterr().out


def test_simulate_in_realtime_is_ignored_with_one_note(capsys, monkeypatch):
    monkeypatch.setattr(solve_module, "_noted", set())
    s = em.settings(0.5, 50)
    s.timeIntegration.realtime.active = True          # simulateInRealtime in older scripts
    for _ in range(2):
        SC, mbs = em.spring_body_with_load()
        assert SolveDynamic(mbs, s, method="dopri5")
        assert mbs.systemData.GetTime() == pytest.approx(0.5)
    err = capsys.readouterr().err
    assert err.count("realtime") == 1 and "ignored" in err and len(err.strip().splitlines()) == 1
    assert s.timeIntegration.realtime.active                  # the script's settings are unchanged


# --- item 10: lgt-bridge run runs a script as python would --------------------------------------

HELPER = '''"""Helper module of a two-file model: builds a pendulum."""
import exudyn as exu
import numpy as np
from exudyn.utilities import ObjectGround, RigidBodyInertia, SensorNode


def build():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    b = mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=1.0, inertiaTensor=np.diag([0.01, 0.1, 0.1])),
                            nodeType=exu.NodeType.RotationEulerParameters, referencePosition=[0.5, 0, 0],
                            gravity=[0, 0, -9.81])
    mbs.CreateRevoluteJoint(itemNumbers=[ground, b], position=[0, 0, 0], axis=[0, 1, 0])
    n = mbs.GetObject(b)["nodeNumber"]
    s = mbs.AddSensor(SensorNode(nodeNumber=n, storeInternal=True,
                                 outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    return SC, mbs, s
'''

SCRIPT = '''import json
import os
import sys

import exudyn as exu
import lgt_test_pendulum_parts as parts

SC, mbs, sensor = parts.build()
settings = exu.SimulationSettings()
settings.timeIntegration.endTime = 0.1
settings.timeIntegration.numberOfSteps = 50
settings.solution.file.write = False
exu.SolveDynamic(mbs, settings)
facts = dict(name=__name__, file=__file__, argv=sys.argv, cwd=os.getcwd(), path0=sys.path[0],
             helper=parts.__file__, main_file=sys.modules["__main__"].__file__,
             final=list(mbs.GetSensorStoredData(sensor)[-1, 1:]))
with open("facts.json", "w") as f:          # relative: lands in the working directory
    json.dump(facts, f)
if __name__ == "__main__":
    print("SCRIPT_MAIN_RAN")
'''


def _two_file_model(tmp_path):
    model = tmp_path / "model"
    model.mkdir()
    (model / "lgt_test_pendulum_parts.py").write_text(HELPER)
    (model / "pendulum.py").write_text(SCRIPT)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    return model, elsewhere


def test_run_in_process_sees_the_script_as_python_would(tmp_path, monkeypatch, capsys):
    """A multi-file model run from another working directory: the script's folder first on
    sys.path (its helper imports), __file__, __name__ == "__main__", sys.argv == [script],
    the working directory unchanged; sys.path, sys.argv and __main__ restored afterwards and
    the helper forgotten. --rtol 0 (pure absolute tolerance) is accepted."""
    model, elsewhere = _two_file_model(tmp_path)
    script = str(model / "pendulum.py")
    monkeypatch.chdir(elsewhere)
    path_before, argv_before, main_before = list(sys.path), list(sys.argv), sys.modules["__main__"]
    assert cli.main(["run", script, "--method", "dopri5", "--rtol", "0", "--atol", "1e-9"]) == 0
    out = capsys.readouterr().out
    assert "SCRIPT_MAIN_RAN" in out and "SolveDynamic #1 ran dopri5 on SO3xR3/exp, rtol=0, atol=1e-09" in out
    facts = json.loads((elsewhere / "facts.json").read_text())
    assert facts["name"] == "__main__" and facts["file"] == script == facts["main_file"]
    assert facts["argv"] == [script] and facts["cwd"] == str(elsewhere)
    assert facts["path0"] == os.path.realpath(model)
    assert facts["helper"] == os.path.join(os.path.realpath(model), "lgt_test_pendulum_parts.py")
    assert sys.path == path_before and sys.argv == argv_before and sys.modules["__main__"] is main_before
    assert "lgt_test_pendulum_parts" not in sys.modules and os.getcwd() == str(elsewhere)
    assert not (model / "facts.json").exists()


def test_run_matches_python_script_from_another_directory(tmp_path):
    """`lgt-bridge run ../model/pendulum.py` and `python ../model/pendulum.py`, both from
    another working directory, give the script the same __file__, sys.argv, sys.path[0] and
    working directory, and the same motion (within generalized-α's error)."""
    model, elsewhere = _two_file_model(tmp_path)
    rel = os.path.join("..", "model", "pendulum.py")
    native = subprocess.run([sys.executable, rel], cwd=elsewhere, capture_output=True, text=True)
    assert native.returncode == 0, native.stderr
    facts_native = json.loads((elsewhere / "facts.json").read_text())
    (elsewhere / "facts.json").unlink()
    routed = subprocess.run([sys.executable, "-m", "lgt_bridge.cli", "run", rel, "--method", "rkmk4"],
                            cwd=elsewhere, capture_output=True, text=True)
    assert routed.returncode == 0, routed.stderr
    assert "SCRIPT_MAIN_RAN" in routed.stdout and "SolveDynamic #1 ran rkmk4" in routed.stdout
    facts = json.loads((elsewhere / "facts.json").read_text())
    for key in ("name", "file", "argv", "cwd", "path0", "helper", "main_file"):
        assert facts[key] == facts_native[key], key
    assert facts["argv"] == [rel]
    assert np.abs(np.array(facts["final"]) - facts_native["final"]).max() < 1e-3


@pytest.mark.parametrize("rho", [0.5, 1.0])
def test_genalpha_takes_the_settings_spectral_radius(rho):
    """generalizedAlpha.spectralRadius is genalpha's rho_inf (Exudyn's generalized-α has the
    same coefficients): at Exudyn's 100 steps, Exudyn's own result to the Newton tolerances
    (measured 8.8e-10 at 0.5, 2.3e-10 at 1; with the bridge's 0.9 it was 6.1e-4 and 1.4e-5
    off). An explicit rho_inf still wins."""
    finals = []
    for run in ("exudyn", "bridge", "rho_inf"):
        SC, mbs = point_mass()
        s = em.settings(1.0, 100)
        s.timeIntegration.generalizedAlpha.spectralRadius = rho
        if run == "exudyn":
            mbs.SolveDynamic(s)
        else:
            SolveDynamic(mbs, s, method="genalpha", **({"rho_inf": 0.9} if run == "rho_inf" else {}))
        finals.append(np.array(mbs.systemData.GetODE2Coordinates()))
    assert np.abs(finals[1] - finals[0]).max() < 1e-8
    assert np.abs(finals[2] - finals[0]).max() > 1e-6


def test_genalpha_takes_the_settings_newmark_method():
    """generalizedAlpha.useNewmark (with newmarkBeta, newmarkGamma) is Newmark's method,
    generalized-α with α_m = α_f = 0 (``genalpha.Newmark``): at Exudyn's 100 steps, Exudyn's
    own Newmark result to the Newton tolerances, where the settings' spectral radius (the
    setting ignored) is far off; an unstable (β, γ) is refused."""
    from lgt_bridge.errors import InputError
    finals = []
    for run in ("exudyn", "bridge", "spectral radius"):
        SC, mbs = point_mass()
        s = em.settings(1.0, 100)
        ga = s.timeIntegration.generalizedAlpha
        ga.useNewmark = run != "spectral radius"
        ga.newmarkBeta, ga.newmarkGamma = 0.3, 0.6
        if run == "exudyn":
            mbs.SolveDynamic(s)
        else:
            SolveDynamic(mbs, s, method="genalpha")
        finals.append(np.array(mbs.systemData.GetODE2Coordinates()))
    assert np.abs(finals[1] - finals[0]).max() < 1e-8
    assert np.abs(finals[2] - finals[0]).max() > 1e-6
    SC, mbs = point_mass()
    s = em.settings(1.0, 100)
    s.timeIntegration.generalizedAlpha.useNewmark = True
    s.timeIntegration.generalizedAlpha.newmarkBeta = 0.1
    with pytest.raises(InputError, match="Newmark"):
        SolveDynamic(mbs, s, method="genalpha")


def test_the_stored_solver_counts_the_bridges_steps_as_exudyns_dopri5_counts_its_own():
    """mbs.sys['dynamicSolver'].it.currentStepIndex - 1 is the number of steps taken, as Exudyn's
    own DOPRI5 counts its adaptive steps there (Exudyn's explicitLieGroupIntegratorTest.py
    reads it; here Exudyn's own run takes more steps than numberOfSteps, so the counter is not
    numberOfSteps). The bridge's stored solver said numberOfSteps (2000 for 9014 steps taken)."""
    n = 20
    SC, mbs = point_mass()
    s = em.settings(1.0, n)
    s.timeIntegration.absoluteTolerance = s.timeIntegration.relativeTolerance = 1e-10
    mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.DOPRI5, showHints=False)
    own = mbs.sys["dynamicSolver"].it.currentStepIndex - 1
    assert own > n                                  # Exudyn's counter: its own adaptive steps
    SC, mbs = point_mass()
    SolveDynamic(mbs, s, method="dopri5")
    st = mbs.sys["lgtBridgeStats"]
    assert st["n_steps"] > n
    assert mbs.sys["dynamicSolver"].it.currentStepIndex - 1 == st["n_steps"]
    assert mbs.sys["dynamicSolver"].it.rejectedAutomaticStepSizeSteps == st["n_rejected"]
