"""Scaling with the number of bodies: time per step and peak memory of the bridge on
N = 1 … 10⁴ free bodies (engine-free scene), rkmk4 at dt = 1e-3.

    python benchmarks/bench_scaling.py [--out benchmarks/results] [--max-n 10000]

Time per step is (wall(2k steps) - wall(k steps)) / k, median of 3 (the one-time set-up
cancels); peak memory is tracemalloc's peak during one
run (numpy arrays included) with only the last state recorded. The slope of log(time)
against log(N) is fitted over all N and over N ≥ 1000 (where the per-call overhead of
numpy no longer dominates). Writes scaling.{json,md}.
"""
import argparse
import json
import time
import tracemalloc
from pathlib import Path

import numpy as np

from lgt_bridge import scenes, simulate


def one(N, group, steps):
    """Seconds per step, without the one-time set-up: (wall(2k steps) - wall(k steps)) / k,
    median of 3; and tracemalloc's peak over a 2k-step run."""
    m = scenes.free_bodies(N)

    def wall(k):
        T = k * 1e-3
        t0 = time.perf_counter()
        simulate(m, (0, T), method="rkmk4", dt=1e-3, group=group, t_eval=[T])
        return time.perf_counter() - t0
    per_step = [(wall(2 * steps) - wall(steps)) / steps for _ in range(3)]
    tracemalloc.start()
    simulate(m, (0, 2 * steps * 1e-3), method="rkmk4", dt=1e-3, group=group, t_eval=[2 * steps * 1e-3])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return float(np.median(per_step)), peak


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--max-n", type=int, default=10_000)
    a = ap.parse_args(argv)
    Ns = [n for n in (1, 10, 100, 1000, 3000, 10_000) if n <= a.max_n]
    rows, fits = [], {}
    for group in ("SO3xR3", "SE3"):
        for N in Ns:
            steps = int(max(5, min(200, 20_000 // N)))
            t, mem = one(N, group, steps)
            rows.append(dict(group=group, N=N, steps=steps, s_per_step=t, us_per_body_step=1e6 * t / N,
                             peak_bytes=mem, bytes_per_body=mem / N))
            print(f"{group:7s} N={N:6d}: {1e3 * t:9.3f} ms/step  {1e6 * t / N:8.2f} µs/body/step  "
                  f"peak {mem / 1e6:8.2f} MB ({mem / N:9.0f} B/body)", flush=True)
        sub = [r for r in rows if r["group"] == group]
        lg = lambda k, rs: np.polyfit(np.log([r["N"] for r in rs]), np.log([r[k] for r in rs]), 1)[0]  # noqa: E731
        big = [r for r in sub if r["N"] >= 1000]
        fits[group] = dict(time_slope_all=float(lg("s_per_step", sub)),
                           time_slope_N_ge_1000=float(lg("s_per_step", big)) if len(big) > 1 else None,
                           memory_slope_N_ge_100=float(lg("peak_bytes", [r for r in sub if r["N"] >= 100])))
        print(group, fits[group])
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "scaling.json").write_text(json.dumps(dict(rows=rows, fits=fits), indent=1))
    lines = ["# Scaling with N free bodies (rkmk4, dt = 1e-3)", "",
             "| group | fitted slope of time/step, all N | N ≥ 1000 | memory slope, N ≥ 100 |", "|---|---:|---:|---:|"]
    lines += [f"| {g} | {f['time_slope_all']:.2f} | {f['time_slope_N_ge_1000'] or float('nan'):.2f} | "
              f"{f['memory_slope_N_ge_100']:.2f} |" for g, f in fits.items()]
    lines += ["", "| group | N | ms/step | µs/body/step | peak MB | B/body |", "|---|---:|---:|---:|---:|---:|"]
    lines += [f"| {r['group']} | {r['N']} | {1e3 * r['s_per_step']:.3f} | {r['us_per_body_step']:.2f} | "
              f"{r['peak_bytes'] / 1e6:.2f} | {r['bytes_per_body']:.0f} |" for r in rows]
    (out / "scaling.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
