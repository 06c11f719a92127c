"""Smoke test of benchmarks/bench_integrators.py (--tiny): it runs and writes the expected
report. No timing is asserted, only that the numbers exist and are positive."""
import importlib.util
import json
import math
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_integrators.py"


@pytest.fixture(scope="module")
def bench_integrators():
    spec = importlib.util.spec_from_file_location("bench_integrators", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _positive(x):
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


def test_bench_integrators_tiny_writes_json_and_markdown(bench_integrators, tmp_path, monkeypatch):
    monkeypatch.delenv("LGT_BRIDGE_BACKEND", raising=False)
    bench_integrators.main(["--tiny", "--out", str(tmp_path)])
    data = json.loads((tmp_path / "integrator_cost.json").read_text())
    md = (tmp_path / "integrator_cost.md").read_text()
    assert {"meta", "settings", "notes", "glue", "fits", "exudyn", "verdicts", "work_precision",
            "total_wall_s"} <= set(data)
    assert {"python", "numpy", "numba", "exudyn"} <= set(data["meta"])
    assert "LGT_BRIDGE_BACKEND" not in __import__("os").environ          # restored after the run

    Ns, groups = data["settings"]["Ns"], data["settings"]["groups"]
    methods = data["settings"]["methods"]
    assert len(data["glue"]) == len(Ns) * len(groups) * len(data["settings"]["charts"]) * len(methods)
    for r in data["glue"]:
        assert r["success"], r
        assert r["n_f"] >= r["n_steps"] >= 1
        for k in ("us_per_step", "f_us_per_eval", "glue_us_per_eval", "peak_bytes", "bytes_per_body", "T"):
            assert _positive(r[k]), (k, r)
    assert len(data["fits"]) == len(groups) * len(methods)
    for f in data["fits"]:
        assert f["k_time_per_step"] is not None and f["memory_slope"] is not None
    assert [v["target"][:6] for v in data["verdicts"][:4]] == ["glue ≤", "glue ≤", "time p", "memory"]
    # section 5: generalized-α on free bodies, the engine-free scene (and Exudyn's twin if installed)
    ga = data["genalpha"]
    assert [v["target"][:8] for v in data["verdicts"][4:]] == ["genalpha"] * len(ga)
    assert len(ga) == 1 + (importlib.util.find_spec("exudyn") is not None)
    for g in ga:
        assert g["steps"] >= 1 and _positive(g["us_per_step"]) and _positive(g["f_us"])
        assert g["ratio"] == g["us_per_step"] / g["f_us"] and g["f_per_step"] >= 1

    if importlib.util.find_spec("exudyn") is not None:
        rows = data["exudyn"]["rows"]
        assert [r["N"] for r in rows] == Ns
        for r in rows:
            assert _positive(r["us_per_eval"]) and _positive(r["build_s"]) and r["view_write_matches_set"]
            assert r["rhs_vs_scene_forces"] < 1e-10              # Exudyn evaluates the same bodies
        assert all(_positive(r["glue_over_exudyn"]) for r in data["glue"])
    else:
        assert "skipped" in data["exudyn"]

    wp = data["work_precision"]
    assert wp["reference"]["success"] and wp["rows"]
    for r in wp["rows"]:
        assert r["success"] and _positive(r["pose_error"]) and _positive(r["wall_s"]) and r["n_f"] > 0
    assert {(x["method"], x["pose_error"]) for x in wp["at_error"]} >= {("dopri5", 1e-6), ("dopri5", 1e-8)}
    assert "## 1. Glue per stage" in md and "## 4. Heavy top work-precision" in md


@pytest.mark.parametrize("script", sorted(p.name for p in SCRIPT.parent.glob("*.py")))
def test_every_benchmark_script_starts(script):
    """Each script under benchmarks/ imports what it needs (the engines, the test models it
    shares) and parses its options: ``--help`` exits 0."""
    import subprocess
    import sys
    pytest.importorskip("exudyn")
    pytest.importorskip("pinocchio")
    r = subprocess.run([sys.executable, str(SCRIPT.parent / script), "--help"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "usage" in r.stdout.lower()
