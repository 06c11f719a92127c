"""The demo scene of ``lgt-bridge demo``: the heavy top on several method x group x
chart choices, each run's final error against a tight-tolerance reference.

Each run is timed after an untimed warm-up run of the same method, group and chart, so
its wall time is the integration's and not the compilation (or cache loading) of its
kernels; the warm-up's total is printed under the table."""
import time

import numpy as np

from . import scenes
from .bench import pose_errors
from .errors import InputError
from .lgt import DEFAULT_GROUP
from .simulate import simulate

RUNS = [
    ("euler", "SO3xR3", "exp", dict(dt=5e-5)),
    ("rkmk2", "SO3xR3", "exp", dict(dt=2e-4)),
    ("rkmk4", "SE3", "exp", dict(dt=1e-3)),
    ("rkmk4", "SE3", "cay", dict(dt=1e-3)),
    ("rkmk4", "SO3xR3", "exp", dict(dt=1e-3)),
    ("rkmk4", "SO3xR3", "cay", dict(dt=1e-3)),
    ("rkmk4", "SO3xR3", "cay2", dict(dt=1e-3)),
    ("dopri5", "SO3xR3", "exp", dict(rtol=1e-6, atol=1e-6)),
    ("dopri5", "SE3", "exp", dict(rtol=1e-9, atol=1e-9)),
    ("dopri5", "SO3xR3", "exp", dict(rtol=1e-9, atol=1e-9)),
    ("dop853", "SO3xR3", "exp", dict(rtol=1e-6, atol=1e-6)),
    ("dop853", "SE3", "exp", dict(rtol=1e-9, atol=1e-9)),
    ("dop853", "SO3xR3", "exp", dict(rtol=1e-9, atol=1e-9)),
    ("scipy:DOP853", "SO3xR3", "exp", dict(rtol=1e-9, atol=1e-9)),
    ("radau5", "SO3xR3", "exp", dict(rtol=1e-6, atol=1e-6)),
    ("genalpha", "SE3", "exp", dict(dt=1e-4)),
    ("genalpha", "SO3xR3", "exp", dict(dt=1e-4)),
]


def _warm_up(model, T, method, group, chart, kw):
    """One short untimed run (a few steps) that compiles or loads the run's kernels."""
    span = 3 * kw["dt"] if "dt" in kw else T / 20
    simulate(model, (0, span), method=method, group=group, chart=chart, t_eval=[0, span], **kw)


def run(out, T=0.1, param="quat", constrained=True, runs=RUNS):
    if not (np.isfinite(T) and T > 0):
        raise InputError(f"demo: end time T = {T:g} must be a positive number of seconds (--T).")
    wall0 = time.perf_counter()
    model = scenes.heavy_top(constrained, param=param)
    form = "spherical joint, frame at the centre of mass" if constrained else "frame at the pivot"
    print(f"Heavy top ({form}; m = 15, ω0 = (0, 150, -4.61538) rad/s, {param} coordinates), "
          f"t = 0 … {T} s", file=out)
    t0 = time.perf_counter()
    ref = simulate(model, (0, T), method="dop853", rtol=1e-13, atol=1e-13, t_eval=[0, T])
    print(f"reference: dop853 ({DEFAULT_GROUP}, exp) at rtol = atol = 1e-13: {ref.stats['n_steps']} steps, "
          f"{time.perf_counter() - t0:.2f} s (with compiling or loading its kernels)\n", file=out)
    head = f"{'method':<13}{'group':<8}{'chart':<6}{'setting':<18}{'rot. error':>11}{'pos. error':>11}" \
           f"{'|g| max':>9}{'steps':>8}{'f evals':>9}{'wall ms':>9}"
    print(head, file=out)
    print("-" * len(head), file=out)
    rows, warm = [], 0.0
    for method, group, chart, kw in runs:
        t0 = time.perf_counter()
        _warm_up(model, T, method, group, chart, kw)
        warm += time.perf_counter() - t0
        r = simulate(model, (0, T), method=method, group=group, chart=chart, t_eval=[0, T], **kw)
        eR, er = pose_errors(model, r.q[-1], ref.q[-1])
        g = float(np.abs(model.constraints(r.q[-1])).max()) if model.n_constraints else 0.0
        setting = ", ".join(f"{k}={v:g}" for k, v in kw.items() if k != "atol")
        st = r.stats
        rows.append(dict(method=method, group=group, chart=chart, setting=setting, rot_err=eR,
                         pos_err=er, g=g, **st, success=r.success))
        flag = "" if r.success else f"  FAILED: {r.message}"
        print(f"{method:<13}{group:<8}{chart:<6}{setting:<18}{eR:11.2e}{er:11.2e}{g:9.1e}"
              f"{st['n_steps']:8d}{st['n_f']:9d}{1e3 * st['wall_s']:9.1f}{flag}", file=out)
    print(f"\nwall ms: each run alone after an untimed warm-up run of the same method, group and chart "
          f"(a few steps), so it excludes compiling or loading the kernels: the warm-ups took {warm:.2f} s. "
          f"Demo total {time.perf_counter() - wall0:.2f} s.", file=out)
    return rows
