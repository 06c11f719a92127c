"""Every Exudyn model class the drop-in runs (the test models of tests/models/exudyn_joint_models.py
and tests/models/exudyn_special_models.py) against Exudyn's own converged solution:

    python benchmarks/bench_exudyn_classes.py [--out benchmarks/results]

Per case: the reference (Exudyn's own solver, steps doubled and Richardson-extrapolated until
converged: its agreement and the wall time of its finest run), and the bridge's
lgt_exudyn.SolveDynamic with dopri5 and dop853 at rtol = atol = 1e-10 and genalpha at the
case's step: relative error against the reference and wall time (lgtBridgeStats["wall_s"],
best of 2). Writes exudyn_classes.{json,md}.
"""
import argparse
import json
import sys
import warnings
from pathlib import Path

_TESTS = Path(__file__).resolve().parents[1] / "tests"
sys.path[:0] = [str(_TESTS / "models"), str(_TESTS / "exudyn")]     # the test models and their cases

import exudyn_joint_models as jm  # noqa: E402
import exudyn_special_models as sm  # noqa: E402
import test_exudyn_joints as tj  # noqa: E402
import test_exudyn_special as ts  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

METHODS = ("dopri5", "dop853", "genalpha")


def joint_run(case, method, R):
    mbs, s = case.build()
    if method == "genalpha":
        s.timeIntegration.numberOfSteps = case.genalpha_steps
        s.timeIntegration.generalizedAlpha.spectralRadius = case.rho
        kw = dict(rho_inf=case.rho)
    else:
        kw = tj.ADAPTIVE[method]
    SolveDynamic(mbs, s, method=method, **kw)
    return jm.rel_error(jm.state_at_end(mbs, case.compare_nodes), R), mbs.sys["lgtBridgeStats"]["wall_s"]


def special_run(case, method, ref):
    mbs = ts.run_bridge(case, method)
    err = sm.discrepancy(sm.state_blocks(mbs, case.compare_nodes), ref.blocks)[0]
    return err, mbs.sys["lgtBridgeStats"]["wall_s"]


def best_of(fn, k=2):
    runs = [fn() for _ in range(k)]
    return min(runs, key=lambda r: r[1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    a = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    rows = []
    for c in jm.CASES:
        R, tol, wall = jm.exudyn_reference(c)
        row = dict(case=c.name, kind=c.kind, ref_agreement=tol, ref_wall_s=wall)
        for m in METHODS:
            row[m] = best_of(lambda: joint_run(c, m, R))
        rows.append(row)
        print(row, flush=True)
    for c in sm.CASES:
        ref = sm.exudyn_reference(c)
        row = dict(case=c.name, kind=f"class {c.cls}", ref_agreement=ref.agreement, ref_wall_s=ref.wall_s)
        for m in METHODS:
            row[m] = best_of(lambda: special_run(c, m, ref))
        rows.append(row)
        print(row, flush=True)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "exudyn_classes.json").write_text(json.dumps(rows, indent=1))
    lines = ["# Exudyn model classes: the bridge against Exudyn's converged solution", "",
             "| case | class | reference agreement, finest run | dopri5 1e-10: error / wall | "
             "dop853 1e-10 | genalpha |", "|---|---|---|---|---|---|"]
    for r in rows:
        cells = [f"{r[m][0]:.1e} / {r[m][1]:.3f} s" for m in METHODS]
        lines.append(f"| {r['case']} | {r['kind']} | {r['ref_agreement']:.1e}, {r['ref_wall_s']:.2f} s | "
                     + " | ".join(cells) + " |")
    (out / "exudyn_classes.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
