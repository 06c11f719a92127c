"""Issue 12, robots as bench scenes: ``lgt-bridge bench pinocchio_robot:NAME --scenario free|pd``.

The registry and every option check run without the robot loaders (hidden or faked here);
only the runs on a real robot need ``example-robot-data-loaders`` (the ``robots`` extra, which
the README's test command installs)."""
import json
import sys
import types

import numpy as np
import pytest

from lgt_bridge import InputError, bench, cli, scenes
from lgt_bridge.bench import BenchScene, SceneFamily

pin = pytest.importorskip("pinocchio", reason="the Pinocchio adapter's scenes need pinocchio (pip install 'lgt-bridge[pinocchio]')")

from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_pinocchio import PinocchioModel  # noqa: E402
from lgt_pinocchio import baselines as bl  # noqa: E402
from lgt_pinocchio import bench as pb  # noqa: E402

NEEDS_LOADERS = "needs the robot loaders: pip install 'lgt-bridge[robots]' (example-robot-data-loaders)"


def _one_error_line(err):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("lgt-bridge: error: "), err
    return lines[0]


@pytest.fixture
def no_loaders(monkeypatch):
    """As in CI: example_robot_data cannot be imported."""
    for mod in ("example_robot_data", "example_robot_data.robots_loader"):
        monkeypatch.setitem(sys.modules, mod, None)


@pytest.fixture
def fake_loaders(monkeypatch):
    """Loaders that know two robots, one with a free-flyer root and one without."""
    robots = {"quad": type("QuadLoader", (), {"free_flyer": True}),
              "arm": type("ArmLoader", (), {"free_flyer": False})}
    monkeypatch.setattr(pb, "_loaders", lambda: types.SimpleNamespace(ROBOTS=robots))


@pytest.fixture
def no_run(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("a run started before the options were checked")
    monkeypatch.setattr(bench.runner, "simulate", boom)
    monkeypatch.setattr(bench.runner, "load_scene", boom)


# --- registry and option checks: no loaders needed ----------------------------------------------
def test_the_robot_family_is_registered_with_its_scenarios(capsys):
    fam = bench.all_scenes()["pinocchio_robot"]
    assert isinstance(fam, SceneFamily) and list(fam.scenarios) == ["free", "pd"]
    assert "kp = 1000" in fam.scenarios["pd"] and "critical damping" in fam.scenarios["pd"]
    with pytest.raises(SystemExit):
        cli.main(["bench", "--help"])
    out = capsys.readouterr().out
    for word in ("pinocchio_robot:NAME", "--scenario", "--scenario free (default)", "--scenario pd",
                 "kp = 1000 N·m/rad", "pinocchio_robot_solo12_pd", "lgt-bridge[robots]"):
        assert word in out, word


def test_missing_loaders_say_what_to_install(no_loaders, no_run, capsys):
    with pytest.raises(InputError, match=r"pip install 'lgt-bridge\[robots\]'"):
        bench.get_scene("pinocchio_robot:solo12")
    assert cli.main(["bench", "pinocchio_robot:solo12", "--scenario", "pd"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "example-robot-data-loaders" in line and "lgt-bridge[robots]" in line


def test_unknown_scenario_is_rejected_before_the_robot_is_looked_up(no_loaders, no_run, capsys):
    assert cli.main(["bench", "pinocchio_robot:solo12", "--scenario", "tumble"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "unknown scenario 'tumble'" in line and "free, pd" in line


@pytest.mark.parametrize("scene", ["heavy_top", "pinocchio_humanoid", "extremes"])
def test_scenario_on_a_scene_without_scenarios(no_run, capsys, scene):
    assert cli.main(["bench", scene, "--scenario", "pd"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert f"scene '{scene}' has no scenarios" in line and "leave out --scenario" in line


def test_unknown_and_fixed_base_robots(fake_loaders, no_run, capsys):
    assert cli.main(["bench", "pinocchio_robot:qaud"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "unknown robot 'qaud'" in line and "free-flyer robots: quad." in line
    assert cli.main(["bench", "pinocchio_robot:arm", "--scenario", "pd"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "robot 'arm' has a fixed base" in line and "quad" in line
    # the family's name alone, and a known robot resolves without loading anything
    assert cli.main(["bench", "pinocchio_robot"]) == 2
    assert "name one as pinocchio_robot:NAME" in _one_error_line(capsys.readouterr().err)
    assert bench.scenarios_of("pinocchio_robot:quad") == ("free", "pd")
    bench.check_options("pinocchio_robot:quad", ["rkmk4"], ["SE3"], ["exp"], [], [1e-3], scenario="pd")
    assert bench.report_name("pinocchio_robot:quad", "pd") == "pinocchio_robot_quad_pd"


def test_a_scene_declares_scenarios_the_sweep_runs_and_names_its_files(monkeypatch, tmp_path):
    """Generic: a BenchScene with scenarios (no engine): the default is the first, the
    chosen one reaches the runs, and the files carry its name."""
    slow = BenchScene(lambda: scenes.free_body((1.0, 2.0, 3.0), (0.01, 0.5, 0.01)), 0.5, about="slow spin")
    fast = BenchScene(lambda: scenes.free_body((1.0, 2.0, 3.0), (0.01, 4.0, 0.01)), 0.5, about="fast spin")
    toy = BenchScene(slow.make, slow.t_end, about="toy", scenarios={"slow": slow, "fast": fast})
    monkeypatch.setitem(bench.SCENES, "toy", toy)
    assert bench.get_scene("toy") is slow and bench.get_scene("toy", "fast") is fast
    kw = dict(workers=1, progress=False, auto=False, repeat=1)
    runs = {}
    for sc in ("slow", "fast"):
        ref, rows = bench.sweep("toy", ["rkmk4"], ["SO3xR3"], ["exp"], [], [0.05], scenario=sc, **kw)
        assert ref["scenario"] == sc and rows[0]["success"]
        runs[sc] = rows[0]["pose_error"]
        text = bench.write_report(tmp_path, "toy", ref, rows, plots=False).read_text()
        assert f"# Work-precision: toy, scenario {sc}" in text
        assert json.loads((tmp_path / f"bench_toy_{sc}.json").read_text())["scenario"] == sc
    assert runs["fast"] > 10 * runs["slow"]                # the fast spin is the harder one
    ref, _ = bench.sweep("toy", ["rkmk4"], ["SO3xR3"], ["exp"], [], [0.05], **kw)
    assert ref["scenario"] == "slow"                        # the default


def test_user_loops_take_the_same_pd_torque_as_the_bridge():
    """The baselines' tau plumbing, on the sample humanoid (no loaders): PD toward q_ref,
    renormalized DOP853 on (q, v) against the bridge on one PinocchioModel."""
    m, q0, v0 = bl.humanoid()
    q_ref = pin.neutral(m)
    tau = bl.pd_torque(m, q_ref, 50.0, 2.0)
    t_probe = tau(0.0, q0, v0)
    assert np.all(t_probe[:6] == 0) and np.allclose(t_probe[6:], 50 * (q_ref[7:] - q0[7:]) - 2 * v0[6:])
    T = 0.2
    q_dop, n = bl.dop853_renorm(m, q0, v0, T, 1e-11, tau=tau)
    pm = PinocchioModel(m, q0=q0, v0=v0, tau=tau)
    r = simulate(pm, (0, T), method="dop853", rtol=1e-11, atol=1e-11, t_eval=[T])
    assert n > 0 and bench.pose_error(pm, r.q[-1], q_dop) < 1e-8
    q_free, _ = bl.dop853_renorm(m, q0, v0, T, 1e-11)
    assert bench.pose_error(pm, q_free, q_dop) > 1e-3      # the torque acts
    q_rk4, n4 = bl.rk4_renorm(m, q0, v0, T, 1e-3, tau=tau)
    q_sie, ne = bl.semi_implicit_euler(m, q0, v0, T, 1e-4, tau=tau)
    assert n4 == 800 and ne == 2000
    assert bench.pose_error(pm, q_rk4, q_dop) < 1e-7 and bench.pose_error(pm, q_sie, q_dop) < 1e-2


# --- on a real robot (skipped without the loaders) -----------------------------------------------
def test_robot_scene_loads_the_loaders_q0_and_pd_holds_it():
    pytest.importorskip("example_robot_data", reason=NEEDS_LOADERS)
    m, q0 = pb.load_robot("solo12")
    assert pb.load_robot("solo12")[0] is m                 # loaded once per process
    assert m.joints[1].shortname() == "JointModelFreeFlyer" and m.nv == 18
    free, pd = (bench.get_scene("pinocchio_robot:solo12", s) for s in ("free", "pd"))
    pm = free.make()
    assert isinstance(pm, PinocchioModel) and np.array_equal(pm.q0, q0) and pm._tau is None
    _, q_, v_ = pb.robot_state("solo12")
    assert np.array_equal(v_[:6], pb.BASE_TWIST)
    tau = pd.make()._tau
    assert np.abs(tau(0.0, q0, np.zeros(m.nv))).max() == 0.0       # at rest on the target: no torque
    kp, kd = pb.pd_gains(m, q0)
    assert np.all(kp == pb.KP) and np.all(kd > 0)


def test_a_fixed_base_robot_floated_as_its_loader_allows():
    """tiago's loader fixes its base: refused unless floated, then built by the loader itself
    with a free-flyer root (its other joints as loaded) and tumbling like any free robot:
    the bridge's dop853 matches scipy DOP853 on Pinocchio's (q, v) (both at 1e-10)."""
    pytest.importorskip("example_robot_data", reason=NEEDS_LOADERS)
    with pytest.raises(InputError, match="fixed base"):
        pb.robot_state("tiago")
    assert pb.floated("tiago") and not pb.floated("solo12")
    fixed = pb._loaders().ROBOTS["tiago"]().robot.model
    m, q0, v0 = pb.robot_state("tiago", floating=True)
    assert m.joints[1].shortname() == "JointModelFreeFlyer" and m.nv == fixed.nv + 6
    assert [j.shortname() for j in m.joints][2:] == [j.shortname() for j in fixed.joints][1:]
    pm = PinocchioModel(m, q0=q0, v0=v0)
    r = simulate(pm, (0, 0.3), method="dop853", rtol=1e-10, atol=1e-10, t_eval=[0.3])
    q_ref, _ = bl.dop853_renorm(m, q0, v0, 0.3, 1e-10)
    assert r.success and bench.pose_error(pm, r.q[-1], q_ref) < 1e-7


def test_tiny_bench_run_on_a_real_robot(tmp_path):
    pytest.importorskip("example_robot_data", reason=NEEDS_LOADERS)
    # free fall through the command line, the user loops included
    assert cli.main(["bench", "pinocchio_robot:solo12", "--methods", "dopri5", "--groups", "SO3xR3",
                     "--charts", "exp", "--tols", "1e-8", "--no-auto", "--workers", "1", "--repeat", "1",
                     "--no-plots", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "bench_pinocchio_robot_solo12_free.json").read_text())
    assert data["scenario"] == "free" and data["reference"]["scenario"] == "free"
    by = {(r["method"], r["value"]): r for r in data["runs"]}
    assert by[("dopri5", 1e-8)]["success"] and by[("dopri5", 1e-8)]["pose_error"] < 1e-6
    assert by[("DOP853 + renormalization", 1e-10)]["pose_error"] < 1e-8
    e = [by[("semi-implicit Euler + pin.integrate", dt)]["pose_error"] for dt in (1e-3, 4e-4, 1e-4)]
    assert e[2] < e[1] < e[0]                               # first order
    # PD: stiff joints; generalized-α takes 4 ms steps where RKMK4 diverges
    ref, rows = bench.sweep("pinocchio_robot:solo12", ["genalpha", "rkmk4"], ["SO3xR3"], ["exp"], [], [4e-3],
                            scenario="pd", workers=1, progress=False, auto=False, natives=False, repeat=1)
    by = {r["method"]: r for r in rows}
    assert ref["scenario"] == "pd"
    assert by["genalpha"]["success"] and by["genalpha"]["pose_error"] < 1e-2
    assert not by["rkmk4"]["success"] or not by["rkmk4"]["pose_error"] < 1e-2


def test_radau5_on_a_pd_robot_against_the_users_dop853():
    """solo12 under PD (kp = 1000): radau5 against scipy DOP853 on Pinocchio's own (q, v) at
    1e-12 (an independent reference), with the model's analytic Jacobian, and at a fraction of
    dopri5's evaluations (7205 at 1e-8, held there by stability; radau5: 1312 SO3xR3, 1770 SE3)."""
    pytest.importorskip("example_robot_data", reason=NEEDS_LOADERS)
    model, T = bench.load_scene("pinocchio_robot:solo12", scenario="pd")
    m, q0, v0 = pb.robot_state("solo12")
    q_ref, _ = bl.dop853_renorm(m, q0, v0, T, 1e-12, tau=pb.pd_controller("solo12"))
    for group in ("SO3xR3", "SE3"):
        r = simulate(model, (0, T), method="radau5", group=group, rtol=1e-8, atol=1e-8)
        assert r.success
        assert bench.pose_error(model, r.q[-1], q_ref) < 1e-8
        assert r.stats["n_f"] < 2500 and r.stats["n_jacobians"] < 20, r.stats
