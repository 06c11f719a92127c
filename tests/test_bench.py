"""lgt-bridge bench: a small sweep, its report, and user scene files."""
import json

import pytest

from lgt_bridge import InputError, bench, cli


def test_bench_sweep_writes_a_report_whose_errors_follow_the_settings(tmp_path, capsys):
    assert cli.main(["bench", "heavy_top_pivot", "--methods", "rkmk4,dopri5", "--groups", "SE3,SO3xR3",
                     "--charts", "exp", "--tols", "1e-5,1e-8", "--dts", "1e-3,5e-4", "--out", str(tmp_path),
                     "--workers", "2"]) == 0
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
    ref, rows = bench.sweep(f"{f}:make", ["rkmk4"], ["SE3"], ["exp", "cay"], [], [1e-2], workers=1,
                            progress=False)
    assert ref["t_end"] == 0.5 and len(rows) == 2 and all(r["success"] and r["pose_error"] < 1e-6 for r in rows)
    path = bench.write_report(tmp_path, f"{f}:make", ref, rows)
    assert path.name == "bench_myscene.md"


def test_bench_unknown_scene():
    with pytest.raises(InputError, match="unknown scene 'nope'"):
        bench.load_scene("nope")
