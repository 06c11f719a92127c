"""Events (issue 24): how accurately crossings are located, and what events cost.

    python benchmarks/bench_events.py [--before REV] [--steps 10000] [--repeats 7]

1. Accuracy against exact references:
   - the period of a compound pendulum released at θ0 = 2.5 rad (``scenes.pendulum``) from its
     passes through the vertical, against 4 K(sin²(θ0/2)) √(l/g) (mpmath's ellipk), dop853 at
     rtol = atol = 1e-13 on SE(3) and SO(3)xR³;
   - the time a free body (spinning, SE(3)) falls 2 m, against √(2h/g): dop853 at 1e-12,
     scipy:DOP853 at 1e-12, rkmk4 with dt = 0.05 on SO(3)xR³ (the cubic Hermite is exact there);
   - the order of the located time with fixed-step rkmk4 (cubic Hermite within the step): the
     first pass of the pendulum through the vertical (exactly T/4) at dt = T/40 ... T/160,
     slope of log error against log dt.
2. Cost without events: a ``--steps``-step rkmk4 run of ``scenes.free_body()`` (dt = 1e-3,
   compiled backend, every step recorded), timed with this tree's ``Simulation.run`` and with
   ``lgt_bridge/simulation.py`` of git revision ``--before`` (default: the merge base with
   main) loaded into the same process; runs alternate (each case first in turn, garbage
   collected before each), best of ``--repeats``. Also the same run
   with one event that never crosses zero and with one that crosses at every other step
   region (for what events cost when used).
"""
import argparse
import gc
import importlib.util
import math
import subprocess
import sys
import time
from pathlib import Path

import mpmath
import numpy as np

from lgt_bridge import scenes, simulate
from lgt_bridge.groups.batch import rotate
from lgt_bridge.simulation import Simulation

ROOT = Path(__file__).resolve().parents[1]
G = 9.81


def pendulum_period(group):
    theta0 = 2.5
    m = scenes.pendulum(theta0)
    T = float(4 * mpmath.ellipk(math.sin(theta0 / 2) ** 2) * mpmath.sqrt(m.equivalent_length / G))
    c = np.array([[0.0, 0.0, -0.6]])
    r = simulate(m, (0.0, 3.3 * T), method="dop853", group=group, rtol=1e-13, atol=1e-13,
                 events=[lambda t, q, V: rotate(q[None, 3:7], c)[0, 0]])
    te = r.t_events[0]
    T_fit = 2 * np.polyfit(np.arange(len(te)), te, 1)[0]
    return abs(T_fit - T) / T, abs(te[0] - T / 4) / T, len(te)


def fall_time(method, **kw):
    h = 2.0
    m = scenes.RigidBodySystem([1.0], [np.diag([1.0, 2.0, 3.0])], np.array([0, 0, h, 1, 0, 0, 0.0]),
                               np.array([0.3, 0.2, 0.1, 0, 0, 0.0]))
    ground = lambda t, q, V: q[2]                   # noqa: E731
    ground.terminal = True
    r = simulate(m, (0.0, 2.0), method=method, events=[ground], **kw)
    return abs(r.t_events[0][0] - math.sqrt(2 * h / G))


def rkmk4_order():
    theta0 = 2.5
    m = scenes.pendulum(theta0)
    T = float(4 * mpmath.ellipk(math.sin(theta0 / 2) ** 2) * mpmath.sqrt(m.equivalent_length / G))
    c = np.array([[0.0, 0.0, -0.6]])
    dts = T / np.array([40, 56, 80, 113, 160])
    errs = []
    for dt in dts:
        r = simulate(m, (0.0, 0.3 * T), method="rkmk4", dt=dt,
                     events=[lambda t, q, V: rotate(q[None, 3:7], c)[0, 0]])
        errs.append(abs(r.t_events[0][0] - T / 4))
    return np.polyfit(np.log(dts), np.log(errs), 1)[0], dts, errs


def load_before(rev):
    """lgt_bridge/simulation.py of git revision ``rev`` as a module of the package (same process)."""
    src = subprocess.run(["git", "show", f"{rev}:lgt_bridge/simulation.py"], cwd=ROOT, check=True,
                         capture_output=True, text=True).stdout
    spec = importlib.util.spec_from_loader("lgt_bridge._simulation_before", loader=None)
    mod = importlib.util.module_from_spec(spec)
    mod.__package__ = "lgt_bridge"
    exec(compile(src, f"{rev}:lgt_bridge/simulation.py", "exec"), mod.__dict__)
    return mod


def timed(cls, steps, events=None):
    m = scenes.free_body()
    sim = cls(m, method="rkmk4", dt=1e-3, t_end=steps * 1e-3)
    gc.collect()
    t0 = time.perf_counter()
    r = sim.run(steps * 1e-3, progress=False) if events is None else sim.run(steps * 1e-3, progress=False,
                                                                               events=events)
    wall = time.perf_counter() - t0
    assert r.success and r.stats["n_steps"] == steps
    return wall


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", default=None, help="git revision of the code without events (default: merge base with main)")
    ap.add_argument("--steps", type=int, default=10_000)
    ap.add_argument("--repeats", type=int, default=7)
    a = ap.parse_args(argv)
    print("1. accuracy")
    for group in ("SE3", "SO3xR3"):
        rel, first, n = pendulum_period(group)
        print(f"   pendulum period, dop853 1e-13, {group:6s}: relative error {rel:.1e} ({n} crossings; "
              f"first crossing vs T/4: {first:.1e} of T)")
    for method, kw in (("dop853", dict(rtol=1e-12, atol=1e-12)), ("scipy:DOP853", dict(dt=0.25, rtol=1e-12, atol=1e-12)),
                       ("rkmk4", dict(dt=0.05, group="SO3xR3"))):
        print(f"   fall time, {method} {kw}: |t - sqrt(2h/g)| = {fall_time(method, **kw):.1e} s")
    slope, dts, errs = rkmk4_order()
    print(f"   rkmk4 located-time order: slope {slope:.3f} (dt {dts[0]:.4f} .. {dts[-1]:.4f}: error "
          f"{errs[0]:.2e} .. {errs[-1]:.2e})")
    rev = a.before or subprocess.run(["git", "merge-base", "HEAD", "main"], cwd=ROOT, check=True,
                                     capture_output=True, text=True).stdout.strip()
    Before = load_before(rev).Simulation
    never = lambda t, q, V: 1.0                     # noqa: E731
    crossing = lambda t, q, V: math.sin(40 * t)    # noqa: E731  (a crossing every 78.5 steps)
    cases = {f"before ({rev[:7]})": (Before, None), "after, no events": (Simulation, None),
             f"before ({rev[:7]}), again (noise)": (Before, None),
             "after, one event never crossing": (Simulation, [never]),
             "after, one event crossing every 79 steps": (Simulation, [crossing])}
    for cls, ev in cases.values():                  # warm-up: numba compiles, caches fill
        timed(cls, 200, ev)
    best = {k: math.inf for k in cases}
    keys = list(cases)
    for i in range(a.repeats):
        for k in keys[i % len(keys):] + keys[:i % len(keys)]:        # each case first in turn
            cls, ev = cases[k]
            best[k] = min(best[k], timed(cls, a.steps, ev))
    print(f"2. cost: {a.steps}-step rkmk4 free body (dt = 1e-3, every step recorded), best of {a.repeats}, one process")
    base = best[next(iter(cases))]
    for k, w in best.items():
        print(f"   {k:42s} {w * 1e3:8.1f} ms  ({w / a.steps * 1e6:6.2f} us/step, {w / base:5.3f}x before)")


if __name__ == "__main__":
    sys.exit(main())
