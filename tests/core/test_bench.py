"""lgt-bridge bench: a small sweep, its report, and user scene files."""
import json

import pytest

from lgt_bridge import InputError, bench, cli


def test_bench_sweep_writes_a_report_whose_errors_follow_the_settings(tmp_path, capsys):
    assert cli.main(["bench", "heavy_top_pivot", "--methods", "rkmk4,dopri5", "--groups", "SE3,SO3xR3",
                     "--charts", "exp", "--tols", "1e-5,1e-8", "--dts", "1e-3,5e-4", "--out", str(tmp_path),
                     "--workers", "2", "--no-auto"]) == 0
    data = json.loads((tmp_path / "bench_heavy_top_pivot.json").read_text())
    assert data["reference"]["rtol"] == 1e-12 and len(data["runs"]) == 8
    assert (tmp_path / "bench_heavy_top_pivot.md").read_text().count("\n| ") == 9   # header + 8 runs
    by = {(r["method"], r["group"], r["value"]): r for r in data["runs"]}
    for g in ("SE3", "SO3xR3"):
        assert by[("dopri5", g, 1e-8)]["pose_error"] < by[("dopri5", g, 1e-5)]["pose_error"]
        coarse, fine = by[("rkmk4", g, 1e-3)], by[("rkmk4", g, 5e-4)]
        assert 12 < coarse["pose_error"] / fine["pose_error"] < 20                  # 4th order: 2⁴
        assert fine["n_f"] == 2 * coarse["n_f"] and fine["energy_drift"] < coarse["energy_drift"]
    assert "Reference: dopri5 on SE3/exp" in capsys.readouterr().out


def test_bench_user_scene_file(tmp_path):
    f = tmp_path / "myscene.py"
    f.write_text("from lgt_bridge import scenes\n\ndef make():\n    return scenes.free_body(), 0.5\n")
    ref, rows = bench.sweep(f"{f}:make", ["rkmk4"], ["SE3"], ["exp", "cay"], [], [1e-2], workers=1, auto=False,
                            progress=False)
    assert ref["t_end"] == 0.5 and len(rows) == 2 and all(r["success"] and r["pose_error"] < 1e-6 for r in rows)
    path = bench.write_report(tmp_path, f"{f}:make", ref, rows)
    assert path.name == "bench_myscene.md"


def test_bench_unknown_scene():
    with pytest.raises(InputError, match="unknown scene 'nope'"):
        bench.load_scene("nope")


def test_bench_auto_runs_plots_and_energy_traces(tmp_path):
    pytest.importorskip("matplotlib")
    ref, rows = bench.sweep("heavy_top", ["rkmk4"], ["SE3"], ["exp"], [], [1e-3, 5e-4], workers=1,
                            progress=False)
    auto = [r for r in rows if r["group"] == "auto"]
    assert len(rows) == 4 and len(auto) == 2 and [tuple(x) for x in auto[0]["auto"]] == [("SO3xR3", "exp")]
    # auto (SO(3)xR³ with the joint projected) beats SE(3) at equal steps: on the front
    gaps = bench.front_gaps(rows)
    assert len(gaps) == 2 and all(g["n_f_ratio_same_method"] in (None, 1.0) for g in gaps)
    se3 = {r["value"]: r for r in rows if r["group"] == "SE3"}
    assert all(a["pose_error"] < se3[a["value"]]["pose_error"] for a in auto)
    for r in rows:                      # energy drift over time, from t = 0 to the end
        assert r["energy_t"][0] == 0.0 and r["energy_t"][-1] == pytest.approx(ref["t_end"])
        assert r["energy_drift_t"][0] == 0.0 and r["energy_drift_t"][-1] == r["energy_drift"] > 0
    path = bench.write_report(tmp_path, "heavy_top", ref, rows)
    text = path.read_text()
    assert "## auto against the front" in text
    for name in ("error_vs_wall", "error_vs_nf", "energy_drift"):
        png = tmp_path / f"heavy_top_{name}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
        assert png.name in text


def test_bench_on_a_dask_local_cluster(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        ref, rows = bench.sweep("free_body", ["rkmk4", "dopri5"], ["SO3xR3"], ["exp"], [1e-6], [1e-2],
                                progress=False, scheduler=client, auto=False)
        assert len(client.scheduler_info()["workers"]) == 2
    local_ref, local = bench.sweep("free_body", ["rkmk4", "dopri5"], ["SO3xR3"], ["exp"], [1e-6], [1e-2],
                                   workers=1, progress=False, auto=False)
    assert [r["pose_error"] for r in rows] == [r["pose_error"] for r in local]   # same numbers
    assert all(r["success"] and r["pose_error"] < 1e-4 for r in rows)


def test_bench_extremes_report(tmp_path, monkeypatch):
    from lgt_bridge import extremes
    monkeypatch.setattr(extremes, "CASES", dict(update_accuracy=extremes.update_accuracy,
                                                long_run=extremes.long_run))
    assert cli.main(["bench", "extremes", "--out", str(tmp_path), "--long-steps", "200"]) == 0
    data = json.loads((tmp_path / "extremes.json").read_text())
    assert [r["steps"] for r in data["long_run"]] == [200] * 4
    assert "## update accuracy" in (tmp_path / "extremes.md").read_text()


def test_bench_wall_times_are_the_best_of_lone_runs_and_the_report_says_so(tmp_path):
    # two identical settings in one parallel sweep: both timed alone, best of `repeat`
    ref, rows = bench.sweep("free_body", ["rkmk4"], ["SO3xR3"], ["exp"], [], [1e-2, 1e-2], workers=2,
                            progress=False, auto=False, repeat=2)
    assert len(rows) == 2 and rows[0]["pose_error"] == rows[1]["pose_error"]
    assert ref["timing"]["method"] == "serial-best-of" and ref["timing"]["repeat"] == 2
    for r in rows:
        assert r["wall_repeats"] == 2 and len(r["wall_samples_s"]) == 2
        assert r["wall_s"] == min(r["wall_samples_s"]) and r["wall_pass_s"] > 0
    text = bench.write_report(tmp_path, "free_body", ref, rows, plots=False).read_text()
    assert "Wall times: serial, best of 2" in text and "one at a time" in text and "2 parallel worker" in text
    assert text.count(" | 2 |\n") == 2                  # the "timed runs" column
    # a serial sweep counts its own pass as the first lone run
    ref, rows = bench.sweep("free_body", ["rkmk4"], ["SO3xR3"], ["exp"], [], [1e-2], workers=1,
                            progress=False, auto=False, repeat=3)
    (r,) = rows
    assert r["wall_repeats"] == 3 and r["wall_samples_s"][0] == r["wall_pass_s"]
    assert "(the pass itself was the first of them)" in ref["timing"]["text"]


def test_bench_repeat_zero_keeps_the_pass_times_and_says_they_are_distorted(tmp_path):
    ref, rows = bench.sweep("free_body", ["rkmk4"], ["SO3xR3"], ["exp"], [], [1e-2, 5e-3], workers=2,
                            progress=False, auto=False, repeat=0)
    assert all(r["wall_repeats"] == 0 and r["wall_s"] == r["wall_pass_s"] for r in rows)
    text = bench.write_report(tmp_path, "free_body", ref, rows, plots=False).read_text()
    assert "first pass only (repeat = 0)" in text and "distorted" in text


@pytest.mark.parametrize("repeat", [-1, 1.5, "3"])
def test_bench_bad_repeat_is_rejected_before_the_reference_run(monkeypatch, repeat):
    monkeypatch.setattr(bench.runner, "simulate", lambda *a, **k: pytest.fail("the reference run started"))
    with pytest.raises(InputError, match="repeat"):
        bench.sweep("free_body", ["rkmk4"], ["SO3xR3"], ["exp"], [], [1e-2], workers=1, repeat=repeat)


def _row(method, group, chart, value, err, wall, n_f):
    return dict(method=method, group=group, chart=chart, setting="dt", value=value, success=True, message="",
                wall_s=wall, n_f=n_f, n_steps=n_f // 4, n_rejected=0, pose_error=err, velocity_error=err,
                constraint_residual=0.0, wall_repeats=3)


_REF = dict(bench.REFERENCE, n_steps=10, wall_s=1.0, t_end=0.1,
            timing=dict(method="serial-best-of", repeat=3, text="serial, best of 3 (test)"))


def test_bench_report_marks_interpolated_figures(tmp_path):
    bracketed = [_row("rkmk4", "SE3", "exp", 1e-3, 1e-5, 0.1, 400), _row("rkmk4", "SE3", "exp", 5e-4, 1e-7, 0.2, 800)]
    text = bench.write_report(tmp_path, "heavy_top", _REF, bracketed, plots=False).read_text()
    assert "- bridge: rkmk4 SE3 exp, ≈ " in text and "*interpolated*" in text
    data = json.loads((tmp_path / "bench_heavy_top.json").read_text())
    assert data["best_at_target"]["bridge"]["interpolated"] is True
    below = [_row("rkmk4", "SE3", "exp", 5e-4, 1e-7, 0.2, 800)]       # nothing to interpolate between
    text = bench.write_report(tmp_path, "heavy_top", _REF, below, plots=False).read_text()
    assert "≤ 0.200 s, measured" in text and "- bridge:" in text
    assert "*interpolated*" not in text.split("## Cheapest")[1]


def test_series_styles_are_a_pure_injective_function_of_the_sweeps_series():
    from lgt_bridge.plots import series_styles
    keys = [(m, g, c) for m in ("rkmk4", "dopri5", "genalpha") for g in ("SE3", "SO3xR3") for c in ("exp", "cay")]
    keys += [(m, "auto", "auto") for m in ("rkmk4", "dopri5", "genalpha")]
    keys += [("exudyn_ga_EP", "native", "engine"), ("exudyn_ga_RotVecLG", "native", "engine")]
    styles = series_styles(keys)
    assert set(styles) == set(keys) and len(set(styles.values())) == len(keys)            # injective
    assert series_styles(list(reversed(keys)) + keys[:3]) == styles                      # pure: order, repeats
    assert styles[("rkmk4", "SE3", "exp")][0] == styles[("rkmk4", "auto", "auto")][0]   # colour by method
    # more methods than colours, unknown groups: still one style per series
    many = [(f"m{i}", g, c) for i in range(30) for g, c in (("SE3", "exp"), ("G", "x"))]
    assert len(set(series_styles(many).values())) == len(many)


def test_every_plot_of_a_sweep_uses_the_same_style_per_series_and_legends_sit_outside(tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    from lgt_bridge import plots
    ref, rows = bench.sweep("heavy_top", ["rkmk4", "dopri5"], ["SE3", "SO3xR3"], ["exp"], [1e-6], [1e-3, 5e-4],
                            workers=1, progress=False, repeat=1)
    seen, save = [], plots._save

    def record(plt, fig, ax, *a):
        lines = {ln.get_gid(): (ln.get_color(), ln.get_marker(), ln.get_linestyle()) for ln in ax.get_lines()}
        out = save(plt, fig, ax, *a)          # draws the legend
        fig.canvas.draw()
        seen.append((lines, ax.get_legend().get_window_extent().x0 >= ax.get_window_extent().x1))
        return out

    monkeypatch.setattr(plots, "_save", record)
    assert len(plots.work_precision_plots(tmp_path, "heavy_top", rows)) == 3
    styles = {"|".join(k): v for k, v in plots.series_styles({plots.series_key(r) for r in rows}).items()}
    assert len(seen) == 3 and len(styles) == 6                       # 2 methods x (SE3, SO3xR3, auto)
    for lines, outside in seen:
        assert lines == styles and outside                            # same style in every plot


def test_a_worker_process_that_dies_costs_only_its_own_run(tmp_path):
    """A run whose worker process dies (here: os._exit inside the model's f, at a stage time
    only the dt = 5e-4 run reaches, and only in worker processes) is a failed row saying the
    worker died; every other run of the sweep, including those the broken pool could not
    finish, has its result, and the report is written."""
    f = tmp_path / "dying.py"
    f.write_text(
        "import multiprocessing, os\n"
        "from lgt_bridge import scenes\n\n"
        "def make():\n"
        "    m = scenes.free_body()\n"
        "    f0 = m.f\n\n"
        "    def f(q, V, t):\n"
        "        if multiprocessing.parent_process() is not None and abs(t - 2.5e-4) < 1e-12:\n"
        "            os._exit(3)\n"
        "        return f0(q, V, t)\n"
        "    m.f = f\n"
        "    return m, 0.01\n")
    ref, rows = bench.sweep(f"{f}:make", ["rkmk4", "dopri5"], ["SE3"], ["exp"], [1e-6, 1e-8], [1e-3, 5e-4],
                            workers=2, auto=False, progress=False, repeat=1)
    by = {(r["method"], r["value"]): r for r in rows}
    assert len(rows) == 4
    dead = by[("rkmk4", 5e-4)]
    assert not dead["success"] and "WorkerDied" in dead["message"] and "process" in dead["message"]
    for key in [("rkmk4", 1e-3), ("dopri5", 1e-6), ("dopri5", 1e-8)]:
        assert by[key]["success"] and by[key]["pose_error"] < 1e-5 and by[key]["wall_repeats"] == 1
    text = bench.write_report(tmp_path, f"{f}:make", ref, rows, plots=False).read_text()
    assert "WorkerDied" in text


def _blas_threads():
    from threadpoolctl import threadpool_info
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_sweep_workers_run_one_blas_thread():
    """A pool already fills the cores: its workers' BLAS pools are limited to one thread each,
    while this process keeps its own (compared in the same run)."""
    from threadpoolctl import threadpool_limits
    from lgt_bridge.bench import runner
    if not _blas_threads():
        pytest.skip("numpy reports no BLAS library to limit")
    with threadpool_limits(2):                      # the parent's pool as a user's machine sets it
        parent = _blas_threads()
        submit, _, close = runner._executor(2, None)
        try:
            workers = [submit(_blas_threads).result() for _ in range(4)]
        finally:
            close()
    assert all(w == [1] * len(parent) for w in workers), (parent, workers)
