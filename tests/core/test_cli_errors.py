"""Issue 13: the command line speaks in one line, and long runs are never silent.

Exit status 2 with ``lgt-bridge: error: <message>`` for errors raised on purpose (a
traceback only with --debug), complete --help texts, option checks before the bench's
reference run, failing runs as rows of a sweep, and progress bars shown when forced,
not shown when piped or in CI."""
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from lgt_bridge import bench, cli, progress, scenes
from lgt_bridge.errors import StepError
from lgt_bridge.simulate import simulate

HERE = Path(__file__).parent
PENDULUM = HERE.parent / "models" / "legacy" / "exudyn_pendulum.py"


def _cli(*args, env=None):
    e = dict(os.environ, **(env or {}))
    return subprocess.run([sys.executable, "-m", "lgt_bridge.cli", *args], capture_output=True, text=True,
                          env=e, cwd=HERE.parent)


def _one_error_line(err):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("lgt-bridge: error: "), err
    assert "Traceback" not in err
    return lines[0]


# --- one-line errors ------------------------------------------------------------------

def test_missing_script_is_one_line_and_status_2():
    p = _cli("run", "no_such_script.py")
    assert p.returncode == 2
    assert "no_such_script.py" in _one_error_line(p.stderr)


def test_unknown_scene_is_one_line_and_status_2():
    p = _cli("bench", "no_such_scene")
    assert p.returncode == 2
    line = _one_error_line(p.stderr)
    assert "no_such_scene" in line and "heavy_top" in line


@pytest.mark.parametrize("where", ["before", "after"])
def test_debug_shows_the_traceback(where):
    args = ["--debug", "run", "no_such_script.py"] if where == "before" else ["run", "no_such_script.py", "--debug"]
    p = _cli(*args)
    assert p.returncode != 0 and "Traceback" in p.stderr and "InputError" in p.stderr


def test_unexpected_exception_keeps_its_traceback(tmp_path):
    pytest.importorskip("exudyn")
    script = tmp_path / "bug.py"
    script.write_text("x = 1 / 0\n")
    p = _cli("run", str(script))
    assert p.returncode == 1 and "Traceback" in p.stderr and "ZeroDivisionError" in p.stderr
    assert "lgt-bridge: error:" not in p.stderr


def test_lgt_error_in_process_returns_2(capsys):
    assert cli.main(["run", "no_such_script.py"]) == 2
    assert _one_error_line(capsys.readouterr().err)


# --- help texts -------------------------------------------------------------------------

def _help(*args, capsys):
    with pytest.raises(SystemExit) as e:
        cli.main([*args, "--help"])
    assert e.value.code == 0
    return capsys.readouterr().out


def test_run_help_documents_every_option(capsys):
    out = _help("run", capsys=capsys)
    for word in ("euler", "rkmk2", "rkmk4", "genalpha", "dopri5", "dop853", "scipy:", "SE3", "SO3xR3",
                 "exp", "cay", "auto", "--rtol", "--atol", "relativeTolerance", "absoluteTolerance",
                 "automaticStepSize", "numberOfSteps", "--progress", "--debug", "--events"):
        assert word in out, word


def test_bench_help_lists_every_scene_and_the_files(capsys):
    out = _help("bench", capsys=capsys)
    for name in bench.all_scenes():                    # engine scenes included where installed
        assert name in out, name
    for word in ("extremes", "file.py:", ".json", ".md", ".png", "--progress"):
        assert word in out, word


def test_run_accepts_group_and_chart_auto():
    a = cli._parser().parse_args(["run", "x.py", "--group", "auto", "--chart", "auto"])
    assert (a.group, a.chart) == ("auto", "auto")


# --- bench: options checked before the reference run; failures become rows ------------

@pytest.fixture
def no_reference(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("simulate ran before the options were checked")
    monkeypatch.setattr(bench.runner, "simulate", boom)
    monkeypatch.setattr(bench.runner, "load_scene", boom)


@pytest.mark.parametrize("opts, word", [
    (["--methods", "rkmk4,rk99"], "rk99"),
    (["--groups", "SE3,SE4"], "SE4"),
    (["--charts", "exp,cayley"], "cayley"),
    (["--tols", "1e-6,-1"], "--tols"),
    (["--tols", "abc"], "abc"),
    (["--dts", "0"], "--dts"),
    (["--methods", "rkmk4", "--dts", ""], "--dts"),
    (["--workers", "0"], "--workers"),
])
def test_bench_checks_options_before_the_reference_run(no_reference, capsys, opts, word):
    assert cli.main(["bench", "free_body", *opts]) == 2
    assert word in _one_error_line(capsys.readouterr().err)


def test_bench_unknown_scene_before_the_reference_run(no_reference, capsys):
    assert cli.main(["bench", "free_bdy"]) == 2
    assert "free_bdy" in _one_error_line(capsys.readouterr().err)


def test_a_failing_run_becomes_a_row(monkeypatch, tmp_path, capsys):
    scene = tmp_path / "tiny.py"
    scene.write_text("from lgt_bridge import scenes\n\ndef make():\n    return scenes.free_body(), 0.02\n")
    real = bench.runner.simulate

    def flaky(model, span, **kw):
        if kw.get("method") == "rkmk2":
            raise StepError("boom: diverged")
        return real(model, span, **kw)
    monkeypatch.setattr(bench.runner, "simulate", flaky)
    out = tmp_path / "out"
    assert cli.main(["bench", f"{scene}:make", "--methods", "rkmk2,rkmk4", "--groups", "SE3", "--charts", "exp",
                     "--dts", "0.01", "--no-auto", "--no-plots", "--workers", "1", "--out", str(out)]) == 0
    runs = {r["method"]: r for r in json.loads((out / "bench_tiny.json").read_text())["runs"]}
    assert not runs["rkmk2"]["success"] and "StepError: boom: diverged" in runs["rkmk2"]["message"]
    assert runs["rkmk4"]["success"] and runs["rkmk4"]["pose_error"] < 1e-6
    md = (out / "bench_tiny.md").read_text()
    assert "failed: StepError: boom" in md and "| rkmk4 |" in md


# --- run: notes and what was used ---------------------------------------------------------

def test_run_without_routable_calls_ends_with_a_note(tmp_path):
    pytest.importorskip("exudyn")
    script = tmp_path / "loop.py"
    script.write_text("print('a hand-written loop')\n")
    p = _cli("run", str(script))
    assert p.returncode == 0 and "a hand-written loop" in p.stdout
    assert "no solver call" in p.stderr and "SolveDynamic" in p.stderr
    assert "PinocchioModel" in p.stderr and "simulate" in p.stderr


def test_run_says_method_group_chart_and_tolerances():
    pytest.importorskip("exudyn")
    p = _cli("run", str(PENDULUM), "--group", "auto", "--chart", "auto")
    assert p.returncode == 0, p.stderr
    line = [ln for ln in p.stdout.splitlines() if "SolveDynamic #1" in ln][0]
    assert "dopri5 on auto→" in line and "rtol=1e-08, atol=1e-08" in line
    assert "from simulationSettings.timeIntegration" in line
    assert "%|" not in p.stderr                              # piped: no bar by default


def test_solve_dynamic_describe():
    from lgt_exudyn.solve import describe
    st = dict(method="dop853", group="SE3", chart="cay", rtol=1e-7, atol=1e-9,
              tolerance_source=dict(rtol="given", atol="given"), dt=None)
    assert describe(st) == "dop853 on SE3/cay, rtol=1e-07, atol=1e-09 (given)"
    st["tolerance_source"] = dict(rtol="given", atol="default")
    assert describe(st) == "dop853 on SE3/cay, rtol=1e-07 (given), atol=1e-09 (bridge default)"
    st.update(rtol=None, atol=None, tolerance_source=None, dt=1e-3, method="rkmk4")
    assert describe(st) == "rkmk4 on SE3/cay, fixed step 0.001 s (from endTime/numberOfSteps)"


# --- progress ------------------------------------------------------------------------------

def test_progress_forced_shows_time_steps_f_evals_step_size(capsys):
    simulate(scenes.free_body(), (0, 0.05), method="rkmk4", dt=0.01, progress=True)
    err = capsys.readouterr().err
    assert "100%" in err and "steps=5" in err and "f evals=20" in err and "h=1.00e-02" in err
    assert "steps/s" in err and "t=0.05 s" in err


def test_progress_default_is_silent_when_piped_and_in_ci(capsys, monkeypatch):
    simulate(scenes.free_body(), (0, 0.05), method="rkmk4", dt=0.01)      # pytest's stderr: not a tty
    assert capsys.readouterr().err == ""
    assert progress.mode(None, io.StringIO()) is None

    class Tty(io.StringIO):
        def isatty(self):
            return True
    monkeypatch.delenv("CI", raising=False)
    assert progress.mode(None, Tty()) == "auto"
    monkeypatch.setenv("CI", "true")
    assert progress.mode(None, Tty()) is None
    assert progress.mode(True, io.StringIO()) == "on" and progress.mode(False, Tty()) is None


def test_progress_default_appears_only_after_the_delay(monkeypatch):
    class Tty(io.StringIO):
        def isatty(self):
            return True
    monkeypatch.delenv("CI", raising=False)
    quiet = Tty()
    p = progress.Progress(None, 10, lambda: (5, "x"), stream=quiet)
    for _ in range(10):
        p.step()
    p.close()
    assert not p.shown and quiet.getvalue() == ""               # short run: nothing drawn
    monkeypatch.setattr(progress, "DELAY", 0.0)
    loud = Tty()
    p = progress.Progress(None, 10, lambda: (10, "steps=10"), desc="sim", stream=loud)
    p.step()
    p.close()
    assert p.shown and "steps=10" in loud.getvalue() and "100%" in loud.getvalue()


def test_progress_checks_the_clock_rarely(monkeypatch):
    class Tty(io.StringIO):
        def isatty(self):
            return True
    monkeypatch.delenv("CI", raising=False)
    p = progress.Progress(None, 1.0, lambda: (0.0, ""), stream=Tty())
    checks = []
    real = p._check
    monkeypatch.setattr(p, "_check", lambda *a, **k: (checks.append(1), real(*a, **k)))
    for _ in range(100_000):
        p.step()
    assert len(checks) < 1000
    off = progress.Progress(False, 1.0, lambda: (0.0, ""))
    assert off.step is progress._nothing                         # progress=False: a no-op per step


def test_run_progress_forced_shows_the_routed_solve():
    pytest.importorskip("exudyn")
    p = _cli("run", str(PENDULUM), "--method", "rkmk4", "--progress")
    assert p.returncode == 0, p.stderr
    assert "SolveDynamic: 100%" in p.stderr and "steps=300" in p.stderr


def test_bench_progress_forced_shows_the_reference_run(tmp_path):
    scene = tmp_path / "tiny.py"
    scene.write_text("from lgt_bridge import scenes\n\ndef make():\n    return scenes.free_body(), 0.02\n")
    p = _cli("bench", f"{scene}:make", "--methods", "rkmk4", "--groups", "SE3", "--charts", "exp", "--dts", "0.01",
             "--no-auto", "--no-plots", "--workers", "1", "--out", str(tmp_path / "o"), "--progress")
    assert p.returncode == 0, p.stderr
    assert "simulate: 100%" in p.stderr and "sweep: 100%" in p.stderr
    q = _cli("bench", f"{scene}:make", "--methods", "rkmk4", "--groups", "SE3", "--charts", "exp", "--dts", "0.01",
             "--no-auto", "--no-plots", "--workers", "1", "--out", str(tmp_path / "o"))
    assert q.returncode == 0 and "%|" not in q.stderr


def test_bench_repeat_option_reaches_the_report(tmp_path, capsys):
    """--repeat sets how many lone runs each wall time is the best of; a bad value is a
    one-line error before the reference run."""
    assert cli.main(["bench", "free_body", "--methods", "rkmk4", "--groups", "SO3xR3", "--charts", "exp",
                     "--dts", "1e-2", "--workers", "1", "--no-auto", "--no-plots", "--repeat", "1",
                     "--out", str(tmp_path)]) == 0
    rows = json.loads((tmp_path / "bench_free_body.json").read_text())["runs"]
    assert rows and all(r["wall_repeats"] == 1 for r in rows if r["group"] != "native")
    capsys.readouterr()
    assert cli.main(["bench", "free_body", "--repeat", "-1", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lgt-bridge: error:") and "repeat" in err
