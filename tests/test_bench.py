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
