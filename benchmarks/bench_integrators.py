"""Per-step cost of each bridge method and the bridge overhead ratio.

    python benchmarks/bench_integrators.py [--out benchmarks/results] [--T 1.0]

Scenes: one torque-free body (N = 1) and 100 free bodies (N = 100). For every
method x (group, chart) the script reports the wall time per step, the time
spent inside the model's own functions (f, forces, mass matrix, constraints;
timed by wrapping them), and the overhead ratio = wall time / time in the model.
Ratios come from one run each, so they compare like with like on a noisy machine.
Writes integrator_cost.json and integrator_cost.md.
"""
import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

from lgt_bridge import scenes
from lgt_bridge.simulate import simulate

MODEL_FUNCS = ("f", "forces", "mass_matrix", "constraints", "constraint_jacobian", "constraint_gamma",
               "solve_mass")

METHODS = [("euler", dict(dt=1e-3)), ("rkmk2", dict(dt=1e-3)), ("rkmk4", dict(dt=1e-2)),
           ("dopri5", dict(rtol=1e-8, atol=1e-8)), ("genalpha", dict(dt=1e-2)),
           ("scipy:DOP853", dict(rtol=1e-8, atol=1e-8))]
COMBOS = [("SE3", "exp"), ("SE3", "cay"), ("SO3xR3", "exp"), ("SO3xR3", "cay")]


class Timed:
    """Wraps a model's protocol functions to accumulate the time spent inside them."""

    def __init__(self, model):
        self.inside = 0.0
        self.depth = 0
        for name in MODEL_FUNCS:
            fn = getattr(model, name)

            def wrapped(*a, _fn=fn):
                if self.depth:
                    return _fn(*a)
                self.depth += 1
                t0 = time.perf_counter()
                try:
                    return _fn(*a)
                finally:
                    self.inside += time.perf_counter() - t0
                    self.depth -= 1
            setattr(model, name, wrapped)


def measure(make, method, kw, group, chart, T):
    model = make()
    timer = Timed(model)
    t0 = time.perf_counter()
    r = simulate(model, (0, T), method=method, group=group, chart=chart, t_eval=[0, T], **kw)
    wall = time.perf_counter() - t0
    st = r.stats
    return dict(method=method, group=group, chart=chart, success=r.success, n_steps=st["n_steps"],
                n_f=st["n_f"], wall_s=wall, model_s=timer.inside,
                us_per_step=1e6 * wall / st["n_steps"], us_in_model_per_step=1e6 * timer.inside / st["n_steps"],
                overhead_ratio=wall / timer.inside)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--T", type=float, default=1.0)
    a = ap.parse_args(argv)
    scenes_ = {"free body (N=1)": lambda: scenes.free_body((1.0, 2.0, 3.0), (0.4, 1.0, -0.3)),
               "100 free bodies (N=100)": lambda: scenes.free_bodies(100)}
    rows = []
    for sname, make in scenes_.items():
        for method, kw in METHODS:
            for group, chart in COMBOS:
                row = measure(make, method, kw, group, chart, a.T)
                row["scene"] = sname
                rows.append(row)
                print(f"{sname:24s} {method:13s} {group:7s} {chart:4s} {row['us_per_step']:9.1f} µs/step "
                      f"({row['us_in_model_per_step']:8.1f} in model)  ratio {row['overhead_ratio']:5.2f}")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    meta = dict(python=platform.python_version(), numpy=np.__version__, T=a.T)
    (out / "integrator_cost.json").write_text(json.dumps(dict(meta=meta, rows=rows), indent=1))
    lines = ["# Bridge cost per step and overhead ratio", "",
             f"t = 0 … {a.T} s; numpy {meta['numpy']}. Overhead ratio = wall time / time inside the "
             "model's functions (1.0 = no overhead).", "",
             "| scene | method | group | chart | steps | f evals | µs/step | µs in model/step | overhead ratio |",
             "|---|---|---|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['method']} | {r['group']} | {r['chart']} | {r['n_steps']} | "
                     f"{r['n_f']} | {r['us_per_step']:.1f} | {r['us_in_model_per_step']:.1f} | "
                     f"{r['overhead_ratio']:.2f} |")
    for sname in scenes_:
        sub = [r for r in rows if r["scene"] == sname]
        lines.append(f"\n{sname}: overhead ratio {min(r['overhead_ratio'] for r in sub):.2f} … "
                     f"{max(r['overhead_ratio'] for r in sub):.2f}")
    (out / "integrator_cost.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines[-2:]))


if __name__ == "__main__":
    main()
