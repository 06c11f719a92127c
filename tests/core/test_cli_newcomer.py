"""Issue 23: a newcomer's friction points (fresh clone, README only), each through the
public interface: the command line in a subprocess, or the Python API the README shows."""
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lgt_bridge import InputError, scenes
from lgt_bridge.simulate import simulate

ROOT = Path(__file__).resolve().parents[2]
PENDULUM = ROOT / "tests" / "models" / "legacy" / "exudyn_pendulum.py"


def _cli(*args, cwd=ROOT):
    env = dict(os.environ)
    # this checkout's sources first, whatever the venv has installed
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), str(ROOT / "adapters"), env.get("PYTHONPATH", "")])
    return subprocess.run([sys.executable, "-m", "lgt_bridge.cli", *args], capture_output=True, text=True,
                          env=env, cwd=cwd)


def _error_line(p):
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2 and len(lines) == 1 and lines[0].startswith("lgt-bridge: error: "), p.stderr
    return lines[0]


def _pendulum(tmp_path, extra=""):
    """The legacy pendulum with lines inserted before its SolveDynamic call."""
    text = PENDULUM.read_text().replace("exu.SolveDynamic(mbs, settings)", f"{extra}\nexu.SolveDynamic(mbs, settings)")
    script = tmp_path / "pendulum.py"
    script.write_text(text)
    return script


# 1. a scene built differently on each call is refused -----------------------------------

@pytest.mark.parametrize("body", [
    "from lgt_bridge import scenes\nimport numpy as np\n\ndef make():\n"
    "    return scenes.free_body(tuple(1 + np.random.rand(3)), (0.01, 2.0, 0.01)), 0.5\n",
    "import pinocchio as pin\nfrom lgt_pinocchio import PinocchioModel\n\ndef make():\n"
    "    return PinocchioModel(pin.buildSampleModelHumanoidRandom()), 0.1\n"])
def test_bench_refuses_a_scene_that_is_not_deterministic(tmp_path, body):
    if "pinocchio" in body:
        pytest.importorskip("pinocchio")
    f = tmp_path / "random_scene.py"
    f.write_text(body)
    line = _error_line(_cli("bench", f"{f}:make", "--methods", "rkmk4", "--dts", "1e-2", "--out", str(tmp_path)))
    assert "make() must be deterministic" in line and "seed" in line
    assert not list(tmp_path.glob("bench_*"))


# 2, 3. tolerances: what the README and --help say is what a run uses, and each one's source --

def test_run_fixed_steps_without_automatic_step_size_and_no_tolerances(tmp_path):
    pytest.importorskip("exudyn")
    script = _pendulum(tmp_path, "settings.timeIntegration.automaticStepSize = False")
    p = _cli("run", str(script))
    assert p.returncode == 0, p.stderr
    assert "fixed step 0.001 s (automaticStepSize=False" in p.stdout and "rtol=" not in p.stdout.split("\n")[0]
    p = _cli("run", str(script), "--method", "scipy:RK45")          # as --help says: the settings' tolerances
    assert "rtol=1e-08, atol=1e-08 (from simulationSettings.timeIntegration" in p.stdout, p.stderr
    page = " ".join((ROOT / "docs" / "tutorials" / "exudyn.rst").read_text().split())   # where the README sends users
    assert "else 1e-6/1e-8" not in page and "fixed steps of the script's output step" in page


@pytest.mark.parametrize("args, words", [
    (["--rtol", "1e-6"], "rtol=1e-06 (given), atol=1e-08 (from simulationSettings.timeIntegration.absoluteTolerance)"),
    (["--atol", "1e-7"], "rtol=1e-08 (from simulationSettings.timeIntegration.relativeTolerance), atol=1e-07 (given)"),
    (["--rtol", "1e-6", "--atol", "1e-7"], "rtol=1e-06, atol=1e-07 (given)"),
    ([], "rtol=1e-08, atol=1e-08 (from simulationSettings.timeIntegration.relative/absoluteTolerance)"),
])
def test_run_says_where_each_tolerance_came_from(args, words):
    pytest.importorskip("exudyn")
    p = _cli("run", str(PENDULUM), *args)
    assert p.returncode == 0 and words in p.stdout, p.stdout + p.stderr


def test_run_bridge_default_tolerance_is_labelled(tmp_path):
    pytest.importorskip("exudyn")
    script = _pendulum(tmp_path, "settings.timeIntegration.automaticStepSize = False")
    p = _cli("run", str(script), "--rtol", "1e-7")
    assert "rtol=1e-07 (given), atol=1e-08 (bridge default)" in p.stdout, p.stdout + p.stderr


# 4. negative numbers reach the option's own check ---------------------------------------

@pytest.mark.parametrize("args, words", [
    (["run", str(PENDULUM), "--rtol", "-1e-6"], "--rtol = -1e-06: must be zero or a positive number"),
    (["run", str(PENDULUM), "--atol", "-1e-8"], "--atol = -1e-08: must be a positive number"),
    (["bench", "heavy_top", "--tols", "-1e-6"], "--tols: -1e-06 must be a positive finite number"),
    (["bench", "heavy_top", "--methods", "rkmk4", "--dts", "-.5"], "--dts: -0.5 must be a positive finite number"),
])
def test_negative_values_get_the_options_message(args, words):
    if args[0] == "run":
        pytest.importorskip("exudyn")
    assert words in _error_line(_cli(*args))


# 5. an error in the script shows what `python script.py` shows ---------------------------

@pytest.mark.parametrize("source", ["x = (1,\n", "print('start')\nundefined_name + 1\n",
                                    "def f():\n    raise ValueError('from the script')\n\nf()\n"])
def test_script_errors_show_the_scripts_own_traceback(tmp_path, source):
    pytest.importorskip("exudyn")
    script = tmp_path / "bug.py"
    script.write_text(source)
    ours = _cli("run", str(script))
    python = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, cwd=ROOT)
    assert ours.returncode == python.returncode == 1
    assert ours.stderr == python.stderr
    assert "lgt_bridge" not in ours.stderr and "cli" not in ours.stderr


# 6. a missing scene file is named ------------------------------------------------------

def test_bench_names_a_missing_scene_file(tmp_path):
    line = _error_line(_cli("bench", "nofile.py:make"))
    assert "no file 'nofile.py'" in line and "unknown scene" not in line
    assert "no file" in _error_line(_cli("bench", f"{tmp_path}/sub/scene.py:make"))


# 7. the script's own arguments --------------------------------------------------------

def test_run_passes_arguments_after_double_dash(tmp_path):
    pytest.importorskip("exudyn")
    script = tmp_path / "args.py"
    script.write_text("import sys\nprint('ARGV', sys.argv)\n")
    p = _cli("run", str(script), "--method", "rkmk4", "--", "--steps", "10", "-v")
    assert p.returncode == 0, p.stderr
    assert f"ARGV {[str(script), '--steps', '10', '-v']}" in p.stdout
    p = _cli("demo", "--", "x")
    assert p.returncode == 2 and "after --" in p.stderr


# 8. the demo's table times warm runs and says so ---------------------------------------

def test_demo_times_warm_runs_and_says_so():
    p = _cli("demo", "--T", "0.004")
    assert p.returncode == 0, p.stderr
    table, _, note = p.stdout.partition("\n\nwall ms:")
    assert "untimed warm-up run of the same method, group and chart" in note and "Demo total" in note
    assert "warm demo" in " ".join((ROOT / "docs" / "getting_started.rst").read_text().split())
    assert "docs/getting_started.rst" in (ROOT / "README.md").read_text()


# 9. bench: files named, pose error defined, readable axes -------------------------------

def test_bench_prints_where_its_files_went_and_defines_pose_error(tmp_path):
    p = _cli("bench", "heavy_top_pivot", "--methods", "rkmk4", "--groups", "SO3xR3", "--charts", "exp",
             "--dts", "1e-3,5e-4", "--out", str(tmp_path / "res"), "--workers", "1", "--no-auto", "--repeat", "1")
    assert p.returncode == 0, p.stderr
    said = re.search(r"lgt-bridge bench: wrote (.*)", p.stderr).group(1).split(", ")
    assert said[0].endswith("bench_heavy_top_pivot.md") and said[1].endswith("bench_heavy_top_pivot.json")
    assert all(Path(x).is_file() for x in said)
    assert "Pose error: at the end time, the largest rotation angle error" in p.stdout
    assert "Pose error:" in _cli("bench", "--help").stdout


@pytest.mark.parametrize("walls", [(0.004, 0.006, 0.011, 0.03), (0.0101, 0.0102), (1e-4, 0.5, 30.0)])
def test_work_precision_axes_have_readable_labels(tmp_path, monkeypatch, walls):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from lgt_bridge import plots
    seen = []
    save = Figure.savefig

    def check(fig, *a, **k):
        fig.canvas.draw()
        ax = fig.axes[0]
        r = fig.canvas.get_renderer()
        labels = [t for t in ax.get_xticklabels() if t.get_visible() and t.get_text()
                  and ax.get_xlim()[0] <= t.get_position()[0] <= ax.get_xlim()[1]]
        boxes = sorted((t.get_window_extent(r) for t in labels), key=lambda b: b.x0)
        seen.append((ax.get_ylabel(), len(boxes), all(a.x1 < b.x0 for a, b in zip(boxes, boxes[1:]))))
        return save(fig, *a, **k)

    monkeypatch.setattr(Figure, "savefig", check)
    rows = [dict(method="rkmk4", group="SE3", chart="exp", success=True, wall_s=w, n_f=int(1000 * w / walls[0]),
                 pose_error=1e-3 * walls[0] / w, wall_repeats=3) for w in walls]
    assert len(plots.work_precision_plots(tmp_path, "s", rows)) == 2
    for ylabel, n, apart in seen:
        assert "rotation error [rad] + largest position error [m]" in ylabel
        assert n >= 2 and apart


# 10. the paper is cited, its corrections are in the project -------------------------------

def test_readme_links_resolve_inside_the_project():
    readme = (ROOT / "README.md").read_text()
    assert "../shared" not in readme and "ERRATA" not in readme
    for link in re.findall(r"\]\(([^)#]+)\)", readme) + re.findall(r"`(docs/[^`*…]+\.md)`", readme):
        if not link.startswith("http"):
            assert (ROOT / link).exists(), link          # a file or a folder (the gallery's sources)
    assert "docs/paper_corrections.md" in readme
    corrections = (ROOT / "docs" / "paper_corrections.md").read_text()
    assert "Müller" in corrections and "SO3exp2" in corrections and "dCayInvSE3" in corrections


# 11. the valid groups include auto -----------------------------------------------------------

def test_unknown_group_or_chart_lists_auto():
    top = scenes.heavy_top(True)
    with pytest.raises(InputError, match=r"unknown group 'SE33'; use one of \['SE3', 'SO3xR3', 'auto'\]"):
        simulate(top, (0, 0.01), group="SE33", dt=1e-3)
    with pytest.raises(InputError, match=r"unknown chart 'cayy'.*'auto'"):
        simulate(top, (0, 0.01), chart="cayy", dt=1e-3)


# 12. one default group everywhere, the one the README recommends ----------------------------

def test_default_group_is_the_recommended_one(tmp_path):
    r = simulate(scenes.heavy_top(True), (0, 0.01), dt=1e-3)
    assert r.group == "SO3xR3"
    assert "(default SO3xR3)" in " ".join(_cli("run", "--help").stdout.split())
    readme = (ROOT / "README.md").read_text()
    assert 'group="SE3"' not in readme.partition("## Pinocchio")[2].partition("\n## ")[0]
    for page in ("getting_started.rst", "tutorials/pinocchio.rst", "tutorials/exudyn.rst"):   # runs shown to newcomers
        runs = [ln for ln in (ROOT / "docs" / page).read_text().splitlines() if "simulate(" in ln or "SolveDynamic(" in ln]
        assert runs and not [ln for ln in runs if 'group="SE3"' in ln], page
    if _has("exudyn"):
        assert "ran dopri5 on SO3xR3/exp" in _cli("run", str(PENDULUM)).stdout


def _has(module):
    import importlib.util
    return importlib.util.find_spec(module) is not None


# 13. pin_state: a clear error on an empty state; the README's snippet --------------------------

def test_pin_state_after_a_failed_run_and_the_readme_snippet():
    pin = pytest.importorskip("pinocchio")
    from lgt_pinocchio import PinocchioModel
    pin.seed(0)
    model = pin.buildSampleModelHumanoidRandom()
    m = PinocchioModel(model)
    with pytest.raises(InputError, match=r"r\.success"):             # r.q, r.V of a run without states
        m.pin_state(np.zeros((0, model.nq)), np.zeros((0, m.layout.nv)))
    with pytest.raises(InputError, match="expected one state"):
        m.pin_state(np.zeros((2, model.nq)), np.zeros((2, model.nv)))
    r = simulate(m, (0.0, 0.01), method="rkmk4", dt=1e-3)
    assert r.success
    q, v = m.pin_state(r.q[-1], r.V[-1])
    assert q.shape == (model.nq,) and v.shape == (model.nv,)
    np.testing.assert_allclose(v[3:6], r.V[-1][:3], atol=1e-14)     # Pinocchio's v: linear first, then ω
    assert "r.success" in (ROOT / "README.md").read_text()
    assert "if not r.success:" in (ROOT / "docs" / "tutorials" / "pinocchio.rst").read_text()


# 14. demo validates before printing -------------------------------------------------------

def test_demo_rejects_a_negative_end_time_before_printing():
    p = _cli("demo", "--T", "-1")
    assert "--T" in _error_line(p) and p.stdout == ""
