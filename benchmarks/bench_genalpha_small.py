"""Generalized-α on small Exudyn models, as Exudyn users run them: ``lgt_exudyn.SolveDynamic(mbs,
settings, method="genalpha")`` against Exudyn's own ``mbs.SolveDynamic(settings)`` (its
generalized-α, its default dense solver) at the same numberOfSteps:

    python benchmarks/bench_genalpha_small.py [--out benchmarks/results]

Models (tests/models/exudyn_solver_models.py): a pendulum (one EP rigid body on a revolute
joint) at 100 and 1000 steps over 2 s, a chain of 10 rigid links on spherical joints (500
steps over 0.5 s), a stiff chain of 5 mass points on 1e7 N/m springs (100 steps over 1 s).
Per model: each side's wall (the model built anew per run and not timed, set-up and outputs
timed), interleaved, best of 3; the ratio bridge / Exudyn; the largest difference of the final
coordinates; the Newton updates and matrices of both. No target: the bridge's Newton update is
Python around Exudyn's calls (about 12 µs on the pendulum against Exudyn's 2 µs), so small
models stay several times Exudyn's own; the drop-in's default, dopri5, is the fast choice for
them unless they are stiff. Writes genalpha_small.{json,md}.
"""
import argparse
import contextlib
import io
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "models"))

import exudyn as exu  # noqa: E402
import exudyn_solver_models as sm  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

CASES = {
    "pendulum (EP node, revolute joint), 100 steps": (sm.pendulum, 100),
    "pendulum (EP node, revolute joint), 1000 steps": (sm.pendulum, 1000),
    "10 rigid links on spherical joints, 500 steps": (lambda: sm.rigid_chain(n=10, t_end=0.5, steps=500), None),
    "5 mass points on 1e7 N/m springs, 100 steps": (lambda: sm.stiff_spring_chain(damping=1e5), None),
}


def _run(build, steps, bridge):
    mbs, s = build()
    if steps is not None:
        s.timeIntegration.numberOfSteps = steps
    with contextlib.redirect_stdout(io.StringIO()):
        if bridge:
            t = time.perf_counter()
            SolveDynamic(mbs, s, method="genalpha")
            wall = time.perf_counter() - t
            st = mbs.sys["lgtBridgeStats"]
            counts = (st["n_newton"], st.get("n_jacobians", 0))
        else:
            solver = exu.MainSolverImplicitSecondOrder()
            t = time.perf_counter()
            solver.SolveSystem(mbs, s)
            wall = time.perf_counter() - t
            counts = (solver.it.newtonStepsCount, solver.it.newtonJacobiCount)
    return wall, np.array(mbs.systemData.GetODE2Coordinates()), counts


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results"))
    a = ap.parse_args(argv)
    warnings.filterwarnings("ignore")
    rows = []
    for name, (build, steps) in CASES.items():
        best = {True: np.inf, False: np.inf}
        for _ in range(3):
            for bridge in (False, True):
                w, q, counts = _run(build, steps, bridge)
                best[bridge] = min(best[bridge], w)
                if bridge:
                    qb, cb = q, counts
                else:
                    qn, cn = q, counts
        rows.append(dict(case=name, bridge_s=best[True], exudyn_s=best[False], ratio=best[True] / best[False],
                         max_difference=float(np.abs(qb - qn).max()), bridge_newton=cb, exudyn_newton=cn))
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "genalpha_small.json").write_text(json.dumps(rows, indent=1, default=float))
    lines = ["# Generalized-α on small Exudyn models: the drop-in vs Exudyn's own", "",
             "| model | bridge (s) | Exudyn (s) | bridge / Exudyn | final difference | Newton updates / matrices "
             "(bridge; Exudyn) |", "|---|---:|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['bridge_s']:.4f} | {r['exudyn_s']:.4f} | {r['ratio']:.1f} | "
                     f"{r['max_difference']:.1e} | {r['bridge_newton'][0]} / {r['bridge_newton'][1]}; "
                     f"{r['exudyn_newton'][0]} / {r['exudyn_newton'][1]} |")
    (out / "genalpha_small.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
