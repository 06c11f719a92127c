"""Time τ and dψ⁻¹ per (parameterization, group, chart) for N = 1, 100, 10 000 bodies.

    python benchmarks/bench_lgt.py [--out benchmarks/results] [--repeat 7]

Writes lgt_timings.json and lgt_timings.md: µs per call and per body, for the
internal batched path the integrators use (LGT.tau / LGT.rates on validated
arrays) and for the checked public function lgt.tau (validation included).
Median of --repeat runs, each timing enough calls to last >= 20 ms.
"""
import argparse
import itertools
import json
import platform
import time
from pathlib import Path

import numpy as np

from lgt_bridge import lgt, params

PARAMS = [params.QUAT_WXYZ, params.QUAT_XYZW, params.ROTVEC, params.RXYZ]


def per_call(fn, repeat):
    fn()
    n, t = 1, 0.0
    while t < 0.02:
        n *= 2
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        t = time.perf_counter() - t0
    runs = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        runs.append((time.perf_counter() - t0) / n)
    return float(np.median(runs)) * 1e6


def states(param, N, rng):
    r = rng.normal(size=(N, 3))
    if param.nrot == 4:
        p = rng.normal(size=(N, 4))
        rot = p / np.linalg.norm(p, axis=1, keepdims=True)
    else:
        rot = rng.uniform(-1.2, 1.2, size=(N, 3))
    return np.concatenate([r, rot], axis=1), rng.normal(size=(N, 6)) * 0.05, rng.normal(size=(N, 6))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--sizes", default="1,100,10000")
    a = ap.parse_args(argv)
    rng = np.random.default_rng(0)
    rows = []
    for N in map(int, a.sizes.split(",")):
        for param, group, chart in itertools.product(PARAMS, lgt.GROUPS, lgt.CHARTS):
            L = lgt.LGT(param, group, chart)
            q, X, V = states(param, N, rng)
            t_tau = per_call(lambda: L.tau(q, X), a.repeat)
            base = L.base(q)
            t_stage = per_call(lambda: L.tau_at(base, X), a.repeat)
            t_rates = per_call(lambda: L.rates(X, V), a.repeat)
            t_pub = per_call(lambda: lgt.tau(q, X, param, group, chart), a.repeat)
            rows.append(dict(N=N, param=param.name, group=group, chart=chart,
                             tau_us=t_tau, tau_us_per_body=t_tau / N,
                             stage_tau_us=t_stage, stage_tau_us_per_body=t_stage / N,
                             rates_us=t_rates, rates_us_per_body=t_rates / N,
                             public_tau_us=t_pub))
            print(f"N={N:6d} {param.name:10s} {group:7s} {chart:4s} τ {t_tau:9.1f} µs "
                  f"({t_tau / N:7.3f}/body)  stage τ {t_stage / N:7.3f}/body  dψ⁻¹ {t_rates:8.1f} µs ({t_rates / N:7.3f}/body)")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    meta = dict(python=platform.python_version(), numpy=np.__version__, machine=platform.machine(),
                processor=platform.processor(), repeat=a.repeat)
    (out / "lgt_timings.json").write_text(json.dumps(dict(meta=meta, rows=rows), indent=1))
    lines = ["# τ and dψ⁻¹ timings (median, µs)", "",
             f"numpy {meta['numpy']}, Python {meta['python']}. Internal path = LGT.tau/LGT.rates on "
             "validated arrays; stage τ = LGT.tau_at with α(q_k) prepared once per step (what "
             "the integrators call in every stage); public = lgt.tau with input checks.", "",
             "| N | param | group | chart | τ µs/call | τ µs/body | stage τ µs/body | dψ⁻¹ µs/call "
             "| dψ⁻¹ µs/body | public τ µs/call |",
             "|---:|---|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['N']} | {r['param']} | {r['group']} | {r['chart']} | {r['tau_us']:.1f} | "
                     f"{r['tau_us_per_body']:.4f} | {r['stage_tau_us_per_body']:.4f} | {r['rates_us']:.1f} | {r['rates_us_per_body']:.4f} | "
                     f"{r['public_tau_us']:.1f} |")
    big = [r for r in rows if r["N"] == max(x["N"] for x in rows)]
    worst = {k: max(big, key=lambda r: r[k]) for k in ("tau_us_per_body", "stage_tau_us_per_body",
                                                       "rates_us_per_body")}
    lines += [""] + [f"Worst {k.replace('_us_per_body', '')} at N = {r['N']}: {r[k]:.3f} µs/body "
                     f"({r['param']}, {r['group']}, {r['chart']}); target <= 0.5 µs/body."
                     for k, r in worst.items()]
    (out / "lgt_timings.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines[-3:]))
    print(f"wrote {out}/lgt_timings.md and lgt_timings.json")


if __name__ == "__main__":
    main()
