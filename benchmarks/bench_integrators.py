"""Cost of the bridge's integrators against the engine's own floor (issue 10), in one process.

    python benchmarks/bench_integrators.py [--out benchmarks/results] [--quick | --tiny]
        [--methods rkmk4,dop853] [--groups SO3xR3,SE3] [--charts exp[,cay]] [--Ns 1,10,...]
        [--backend numba|numpy] [--target-wall 0.4] [--min-steps 20] [--dt 1e-3] [--tol 1e-8]
        [--wp-methods dopri5,dop853] [--wp-backends numpy,numba] [--wp-tols 1e-4,...,1e-12]
        [--wp-T 0.5] [--wp-group SE3] [--wp-chart exp] [--ref-tol 1e-13] [--no-exudyn] [--no-wp]
        [--run-repeats 2] [--repeats 7] [--wp-repeats 3] [--wp-budget 1.0] [--exudyn-max-build 60]

1. Glue per stage on N engine-free free bodies (``scenes.free_bodies(N)``):
   (stepping wall - time inside the model's f) / n_f, f timed by wrapping ``model.f``.
   The stepping wall is ``result.stats["wall_s"]`` (input checks and stepper build are
   reported apart as set-up). T (or dt x steps) is calibrated per run so that a run takes
   about ``--target-wall`` seconds and at least ``--min-steps`` steps. Also time per step,
   its exponent k in time/step ~ N^k (least squares in log-log over N = 10 ... max N), and
   tracemalloc's peak during a separate short run (model built before; numba's internal
   allocations are not traced), per body, and its log-log slope.
2. The engine floor: one Exudyn evaluation of N free ``NodeRigidBodyRotVecLG`` bodies (no
   gravity, the same inertias and state as the engine-free scene): write q, q_t through
   ``systemData.GetODE2Coordinates(copy=False)`` views, ``SetTime``, the solver's
   ``ComputeODE2RHS``, read ``GetSystemResidual()[:n2]``. Best of several repeats; the
   SetODE2Coordinates path (pybind converts every element) is reported beside it.
3. glue / Exudyn evaluation per N, group, chart, method and the issue's targets:
   glue <= 2x the evaluation at N = 1, <= 0.5x at N >= 100; time per step ~ N^(1 +- 0.1)
   from N = 10 to 10 000; memory O(N).
4. Heavy top work-precision (``scenes.heavy_top(constrained=True)``): methods x backends
   (LGT_BRIDGE_BACKEND set in-process before each run) over rtol = atol; pose error at T
   against a tight reference; wall time and n_f interpolated log-log at pose error 1e-6
   and 1e-8 (``lgt_bridge.bench.wall_at_error``).

Writes integrator_cost.json and integrator_cost.md. Ratios compare runs of one process;
the machine's noise is in every absolute number.
"""
import argparse
import importlib.util
import json
import os
import platform
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

from lgt_bridge import backend as _backend
from lgt_bridge import scenes
from lgt_bridge.bench import FIXED, pose_error, wall_at_error
from lgt_bridge.simulate import simulate

from lgt_bridge.integrators import METHODS as _AVAILABLE

PRESETS = {
    "full": dict(Ns=[1, 10, 100, 1000, 10_000], target_wall=0.4, min_steps=20, wp_T=0.5,
                 wp_tols=[10.0 ** -k for k in range(4, 13)], ref_tol=1e-13, repeats=7, eval_budget=0.03,
                 run_repeats=2, wp_budget=1.0, ga_N=100, ga_steps=200),
    "quick": dict(Ns=[1, 10, 100], target_wall=0.05, min_steps=10, wp_T=0.1,
                  wp_tols=[1e-4, 1e-6, 1e-8, 1e-9], ref_tol=1e-11, repeats=3, eval_budget=0.01,
                  run_repeats=1, wp_budget=0.3, ga_N=100, ga_steps=50),
    "tiny": dict(Ns=[1, 10], target_wall=0.01, min_steps=5, wp_T=0.02,
                 wp_tols=[1e-4, 1e-6], ref_tol=1e-9, repeats=2, eval_budget=0.002,
                 run_repeats=1, wp_budget=0.0, ga_N=4, ga_steps=5),
}
TARGETS = dict(glue_N1=2.0, glue_N100=0.5, k_lo=0.9, k_hi=1.1, mem_slope=1.1)
WP_ERRORS = (1e-6, 1e-8)


# --------------------------------------------------------------------------- helpers
def _csv(s, typ=str):
    return None if s is None else [typ(x) for x in s.split(",") if x.strip()]


def _slope(xs, ys):
    """Least-squares exponent k of y ~ x^k (log-log); None with fewer than two points."""
    if len(xs) < 2:
        return None
    return float(np.polyfit(np.log(xs), np.log(ys), 1)[0])


def _resolve(methods, notes):
    """Requested methods that this lgt_bridge has (others are left out with a note)."""
    out = []
    for m in methods:
        if m not in _AVAILABLE and not m.startswith("scipy:"):
            notes.append(f"method {m!r} is not in this lgt_bridge: left out.")
            continue
        if m not in out:
            out.append(m)
    return out


class FTimer:
    """Wraps ``model.f`` (an instance attribute shadowing the method) and accumulates the
    time spent inside it and the number of calls."""

    def __init__(self, model):
        self.s, self.calls = 0.0, 0
        inner, clock = model.f, time.perf_counter

        def f(q, V, t):
            t0 = clock()
            try:
                return inner(q, V, t)
            finally:
                self.s += clock() - t0
                self.calls += 1
        model.f = f


def _timer_overhead_us():
    """What the wrapper adds per call beyond the timed window (it lands in the glue)."""
    class M:
        def f(self, q, V, t):
            return None
    m = M()
    bare = m.f
    FTimer(m)
    n, best_b, best_w = 20_000, np.inf, np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        for _ in range(n):
            bare(0, 0, 0)
        best_b = min(best_b, time.perf_counter() - t0)
        t0 = time.perf_counter()
        for _ in range(n):
            m.f(0, 0, 0)
        best_w = min(best_w, time.perf_counter() - t0)
    return 1e6 * max(best_w - best_b, 0.0) / n


def _set_backend(name):
    os.environ[_backend.ENV] = name


def _versions():
    out = dict(python=platform.python_version(), implementation=platform.python_implementation(),
               system=platform.system(), machine=platform.machine(), cpu_count=os.cpu_count())
    for mod in ("numpy", "scipy", "numba", "exudyn", "lgt_bridge"):
        try:
            m = __import__(mod)
            out[mod] = getattr(m, "__version__", None) or "unknown"
        except ImportError:
            out[mod] = None
    try:
        from importlib.metadata import version
        out["lgt_bridge"] = version("lgt-bridge")
    except Exception:
        pass
    try:
        root = Path(__file__).resolve().parents[1]
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True, text=True,
                             timeout=10)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                               capture_output=True, text=True, timeout=10)
        if rev.returncode == 0:
            out["git"] = rev.stdout.strip() + ("-dirty" if dirty.stdout.strip() else "")
    except Exception:
        pass
    return out


# --------------------------------------------------------------------------- section 1: glue
def run_bridge(N, method, group, chart, T, dt, tol, memory=False):
    """One simulate() on a fresh scenes.free_bodies(N), f timed; with ``memory`` the run
    is under tracemalloc (its timings are then not reported)."""
    model = scenes.free_bodies(N)
    timer = FTimer(model)
    kw = dict(dt=dt) if method in FIXED else dict(rtol=tol, atol=tol)
    if memory:
        tracemalloc.start()
    t0 = time.perf_counter()
    try:
        r = simulate(model, (0.0, T), method=method, group=group, chart=chart, t_eval=[0.0, T], **kw)
    finally:
        wall = time.perf_counter() - t0
        peak = tracemalloc.get_traced_memory()[1] if memory else None
        if memory:
            tracemalloc.stop()
    st = r.stats
    step_wall = st.get("wall_s", wall)
    return dict(success=bool(r.success), message=r.message, T=T, n_steps=int(st["n_steps"]), n_f=int(st["n_f"]),
                f_calls=timer.calls, wall_s=wall, step_wall_s=step_wall, setup_s=max(wall - step_wall, 0.0),
                f_s=timer.s, peak_bytes=peak)


def plan_T(N, method, group, chart, dt, tol, target_wall, min_steps):
    """End time for a run of about ``target_wall`` seconds and at least ``min_steps`` steps,
    from short calibration runs (T grown x4 until they take a few steps); also returns the
    last calibration T (used for the memory run)."""
    T = 10 * dt if method in FIXED else 0.05
    for _ in range(10):
        rec = run_bridge(N, method, group, chart, T, dt, tol)
        if not rec["success"] or rec["n_steps"] >= 8 or rec["step_wall_s"] >= target_wall / 4:
            break
        T *= 4
    if not rec["success"] or rec["n_steps"] == 0:
        return T, T
    per_step = rec["step_wall_s"] / rec["n_steps"]
    steps = max(min_steps, int(np.ceil(target_wall / per_step)))
    if method in FIXED:
        return steps * dt, T
    return T * steps / rec["n_steps"], T


def glue_row(N, method, group, chart, a):
    T, T_cal = plan_T(N, method, group, chart, a.dt, a.tol, a.target_wall, a.min_steps)
    rec = run_bridge(N, method, group, chart, T, a.dt, a.tol)
    for _ in range(3):               # an adaptive run's step count is only roughly proportional to T
        if not rec["success"] or rec["n_steps"] >= a.min_steps:
            break
        T *= 1.5 * a.min_steps / max(rec["n_steps"], 1)
        rec = run_bridge(N, method, group, chart, T, a.dt, a.tol)
    for _ in range(a.run_repeats - 1):       # the same run again: keep the least disturbed one
        again = run_bridge(N, method, group, chart, T, a.dt, a.tol)
        if again["success"] and again["step_wall_s"] < rec["step_wall_s"]:
            rec = again
    mem = run_bridge(N, method, group, chart, T_cal, a.dt, a.tol, memory=True)
    row = dict(N=N, method=method, group=group, chart=chart, setting=(f"dt={a.dt:g}" if method in FIXED
                                                                     else f"tol={a.tol:g}"), **rec)
    if rec["n_f"] and rec["n_steps"]:
        row.update(f_us_per_eval=1e6 * rec["f_s"] / rec["n_f"],
                   glue_us_per_eval=1e6 * (rec["step_wall_s"] - rec["f_s"]) / rec["n_f"],
                   us_per_step=1e6 * rec["step_wall_s"] / rec["n_steps"])
    row.update(peak_bytes=mem["peak_bytes"], bytes_per_body=mem["peak_bytes"] / N, memory_run_steps=mem["n_steps"])
    return row


# --------------------------------------------------------------------------- section 2: Exudyn floor
def exudyn_floor(N, repeats, budget):
    """µs per Exudyn evaluation of N free RotVecLG bodies (write q, q_t, t; ComputeODE2RHS;
    read the residual), best of ``repeats``; the build (create, Assemble, InitializeSolver)
    timed apart."""
    import exudyn as exu
    from exudyn.utilities import RigidBodyInertia
    twin = scenes.free_bodies(N, param="rotvec")        # q per body = [r, rotation vector]: RotVecLG's layout
    t0 = time.perf_counter()
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    for k in range(N):
        mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=float(twin.m[k]), inertiaTensor=twin.J[k]),
                            nodeType=exu.NodeType.RotationRotationVector, referencePosition=[0.0, 0.0, 0.0])
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.solution.file.write = False
    s.solution.sensors.active = False
    if hasattr(s, "linearSolver"):           # a dense solver allocates (6N)² at InitializeSolver
        s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    else:
        s.linearSolverType = exu.LinearSolverType.EigenSparse
    S = exu.MainSolverImplicitSecondOrder()
    S.InitializeSolver(mbs, s)
    build = time.perf_counter() - t0
    sd, n2 = mbs.systemData, S.GetODE2size()
    q = twin.q0.copy()                                    # reference coordinates are all zero: current = total
    W = twin.V0.reshape(N, 6)
    qd = np.concatenate([W[:, 3:], W[:, :3]], axis=1).ravel()   # RotVecLG: [ṙ inertial, ω body]
    qv, qdv = sd.GetODE2Coordinates(copy=False), sd.GetODE2Coordinates_t(copy=False)

    def ev_view():
        qv[:] = q
        qdv[:] = qd
        sd.SetTime(0.25)
        S.ComputeODE2RHS(mbs)
        return S.GetSystemResidual()[:n2]

    def ev_set():
        sd.SetODE2Coordinates(q)
        sd.SetODE2Coordinates_t(qd)
        sd.SetTime(0.25)
        S.ComputeODE2RHS(mbs)
        return S.GetSystemResidual()[:n2]

    # the views really write the state: perturb with Set*, then restore through the views
    sd.SetODE2Coordinates(q + 0.1)
    sd.SetODE2Coordinates_t(qd + 0.1)
    r_view = ev_view().copy()
    r_set = ev_set().copy()
    Fs = twin.forces(twin.q0, twin.V0, 0.0).reshape(N, 6)      # (torque body, force inertial)
    scene_gap = float(np.abs(r_set.reshape(N, 6) - np.concatenate([Fs[:, 3:], Fs[:, :3]], axis=1)).max())

    def best(fn):
        t0 = time.perf_counter()
        fn()
        reps = max(3, int(budget / max(time.perf_counter() - t0, 1e-7)))
        out = np.inf
        for _ in range(repeats):
            t0 = time.perf_counter()
            for _ in range(reps):
                fn()
            out = min(out, (time.perf_counter() - t0) / reps)
        return 1e6 * out, reps
    us_view, reps = best(ev_view)
    us_set, _ = best(ev_set)
    del S, mbs, SC
    return dict(N=N, build_s=build, us_per_eval=us_view, us_per_eval_set=us_set, us_per_body=us_view / N,
                reps=reps, repeats=repeats, view_write_matches_set=bool(np.array_equal(r_view, r_set)),
                rhs_vs_scene_forces=scene_gap)


# --------------------------------------------------------------------------- section 4: work-precision
def work_precision(a, notes):
    methods = _resolve(a.wp_methods, notes)
    backends = [b for b in a.wp_backends if b != "numba" or importlib.util.find_spec("numba")]
    if len(backends) < len(a.wp_backends):
        notes.append("numba is not importable: the numba backend is left out of the work-precision.")
    T, group, chart = a.wp_T, a.wp_group, a.wp_chart
    ref_method = "dop853"
    ref_backend = "numba" if "numba" in backends else backends[0]
    _set_backend(ref_backend)
    simulate(scenes.heavy_top(constrained=True), (0.0, T / 10), method=ref_method, group=group, chart=chart,
             rtol=1e-6, atol=1e-6)                       # warm-up: numba compiles on first use
    model = scenes.heavy_top(constrained=True)
    t0 = time.perf_counter()
    ref = simulate(model, (0.0, T), method=ref_method, group=group, chart=chart, rtol=a.ref_tol, atol=a.ref_tol,
                   t_eval=[0.0, T])
    reference = dict(method=ref_method, backend=ref_backend, group=group, chart=chart, rtol=a.ref_tol,
                     atol=a.ref_tol, t_end=T, n_steps=ref.stats["n_steps"], n_f=ref.stats["n_f"],
                     wall_s=time.perf_counter() - t0, success=bool(ref.success))
    print(f"heavy top reference: {ref_method} ({ref_backend}) {group}/{chart} rtol = atol = {a.ref_tol:g}, "
          f"{ref.stats['n_steps']} steps, {reference['wall_s']:.1f} s", flush=True)
    if not ref.success:
        notes.append(f"heavy top reference failed: {ref.message}")
        return dict(reference=reference, rows=[], at_error=[])
    q_ref = ref.q[-1]
    rows = []
    for b in backends:
        _set_backend(b)
        for m in methods:
            simulate(scenes.heavy_top(constrained=True), (0.0, T / 10), method=m, group=group, chart=chart,
                     rtol=a.wp_tols[0], atol=a.wp_tols[0])       # warm-up (numba compiles on first use)
            for tol in a.wp_tols:
                wall, spent = np.inf, 0.0
                for k in range(a.wp_repeats):    # repeat short runs (up to a time budget): least wall
                    if k and spent >= a.wp_budget:
                        break
                    model = scenes.heavy_top(constrained=True)
                    t0 = time.perf_counter()
                    r = simulate(model, (0.0, T), method=m, group=group, chart=chart, rtol=tol, atol=tol,
                                 t_eval=[0.0, T])
                    w = time.perf_counter() - t0
                    wall, spent = min(wall, w), spent + w
                row = dict(method=m, backend=b, tol=tol, success=bool(r.success), wall_s=wall,
                           n_f=int(r.stats["n_f"]), n_steps=int(r.stats["n_steps"]),
                           n_rejected=int(r.stats.get("n_rejected", 0)),
                           pose_error=pose_error(model, r.q[-1], q_ref) if r.success else None)
                rows.append(row)
                print(f"  {m:8s} {b:6s} tol {tol:7.0e}  pose error {row['pose_error'] or float('nan'):9.2e}  "
                      f"n_f {row['n_f']:7d}  wall {wall:8.3f} s", flush=True)
    at = []
    for b in backends:
        for m in methods:
            rs = [r for r in rows if r["method"] == m and r["backend"] == b and r["success"] and r["pose_error"]]
            for target in WP_ERRORS:
                w, wx = wall_at_error(rs, target)
                n, nx = wall_at_error([dict(r, wall_s=r["n_f"]) for r in rs], target)   # n_f along the same curve
                at.append(dict(method=m, backend=b, pose_error=target, wall_s=w, wall_exact=wx, n_f=n, n_f_exact=nx))
    return dict(reference=reference, group=group, chart=chart, T=T, rows=rows, at_error=at)


# --------------------------------------------------------------------------- verdicts and report
# --------------------------------------------------------------------------- section 5: genalpha
GA_TARGET = 10.0


def genalpha_cost(models, N, steps, dt, repeats):
    """Generalized-α on N free bodies on SE(3)/exp: µs per step (stats wall_s / steps, the
    least of ``repeats`` runs of ``steps`` steps) against one f of the same model at its
    start (best of a loop), for each (label, make_model)."""
    out = []
    for label, make in models:
        model = make(N)
        simulate(model, (0.0, 5 * dt), method="genalpha", group="SE3", chart="exp", dt=dt)      # warm up
        best = None
        for _ in range(repeats):
            r = simulate(model, (0.0, steps * dt), method="genalpha", group="SE3", chart="exp", dt=dt,
                         t_eval=[steps * dt])
            us = 1e6 * r.stats["wall_s"] / r.stats["n_steps"]
            if best is None or us < best[0]:
                best = (us, r.stats)
        q, V = np.array(model.q0, float), np.array(model.V0, float)
        n = max(200, int(0.02 / max(1e-7, _once(model, q, V))))
        f_us = np.inf
        for _ in range(7):
            t0 = time.perf_counter()
            for _ in range(n):
                model.f(q, V, 0.0)
            f_us = min(f_us, 1e6 * (time.perf_counter() - t0) / n)
        st = best[1]
        out.append(dict(model=label, N=N, dt=dt, steps=st["n_steps"], us_per_step=best[0], f_us=f_us,
                        ratio=best[0] / f_us, newton_per_step=st["n_newton"] / st["n_steps"],
                        f_per_step=st["n_f"] / st["n_steps"], jacobians=st.get("n_jacobians")))
    return out


def _once(model, q, V):
    t0 = time.perf_counter()
    model.f(q, V, 0.0)
    return time.perf_counter() - t0


def _exudyn_free_bodies(N):
    from lgt_exudyn import ExudynModel
    from lgt_exudyn import scenes as es
    return ExudynModel(es.free_bodies(N)[1])


def fits_and_verdicts(rows, exu_rows, Ns, ga_rows=()):
    exu = {r["N"]: r["us_per_eval"] for r in exu_rows}
    for r in rows:
        e = exu.get(r["N"])
        r["exudyn_us_per_eval"] = e
        r["glue_over_exudyn"] = r["glue_us_per_eval"] / e if e and r.get("glue_us_per_eval") is not None else None
    combos = sorted({(r["group"], r["chart"], r["method"]) for r in rows})
    lo = 10 if max(Ns) > 10 else min(Ns)
    fits = []
    for g, c, m in combos:
        sub = sorted((r for r in rows if (r["group"], r["chart"], r["method"]) == (g, c, m)
                      and r["success"] and r.get("us_per_step")), key=lambda r: r["N"])
        fit = [r for r in sub if r["N"] >= lo]
        big = [r for r in sub if r["N"] >= 1000]
        fits.append(dict(group=g, chart=c, method=m, N_range=[fit[0]["N"], fit[-1]["N"]] if fit else None,
                         k_time_per_step=_slope([r["N"] for r in fit], [r["us_per_step"] for r in fit]),
                         k_time_per_step_N_ge_1000=_slope([r["N"] for r in big], [r["us_per_step"] for r in big]),
                         memory_slope=_slope([r["N"] for r in fit], [r["peak_bytes"] for r in fit]),
                         bytes_per_body_at_max_N=fit[-1]["bytes_per_body"] if fit else None))

    def verdict(name, items, limit, key):
        vals = [(lab, v) for lab, v in items if v is not None]
        if not vals:
            return dict(target=name, ok=None, detail="not measured", values={})
        ok = all(v <= limit if key == "le" else limit[0] <= v <= limit[1] for _, v in vals)
        return dict(target=name, ok=ok, values=dict(vals))
    lab = lambda r: f"{r['group']}/{r['chart']} {r['method']} N={r['N']}"  # noqa: E731
    flab = lambda f: f"{f['group']}/{f['chart']} {f['method']}"          # noqa: E731
    verdicts = [
        verdict(f"glue ≤ {TARGETS['glue_N1']:g}× the Exudyn evaluation at N = 1",
                [(lab(r), r["glue_over_exudyn"]) for r in rows if r["N"] == 1], TARGETS["glue_N1"], "le"),
        verdict(f"glue ≤ {TARGETS['glue_N100']:g}× the Exudyn evaluation at N ≥ 100",
                [(lab(r), r["glue_over_exudyn"]) for r in rows if r["N"] >= 100], TARGETS["glue_N100"], "le"),
        verdict(f"time per step ∝ N^(1 ± 0.1) from N = {lo} to {max(Ns)}",
                [(flab(f), f["k_time_per_step"]) for f in fits], (TARGETS["k_lo"], TARGETS["k_hi"]), "in"),
        verdict(f"memory O(N): peak slope ≤ {TARGETS['mem_slope']:g} from N = {lo} to {max(Ns)}",
                [(flab(f), f["memory_slope"]) for f in fits], TARGETS["mem_slope"], "le"),
    ]
    if max(Ns) < 100:
        verdicts[1].update(ok=None, detail="no N ≥ 100 in this run")
    for g in ga_rows:
        verdicts.append(verdict(f"genalpha, {g['N']} free bodies on SE(3), {g['model']}: time per step ≤ "
                                f"{GA_TARGET:g}× one f", [(g["model"], g["ratio"])], GA_TARGET, "le"))
    return fits, verdicts


def _f(v, fmt, dash="–"):
    return dash if v is None else format(v, fmt)


def _ok(v):
    return {True: "**yes**", False: "**no**", None: "not measured"}[v]


def write_report(out, data):
    out.mkdir(parents=True, exist_ok=True)
    (out / "integrator_cost.json").write_text(json.dumps(data, indent=1))
    meta, st = data["meta"], data["settings"]
    L = ["# Integrator cost: glue per stage against Exudyn's own evaluation (issue 10)", "",
         f"Python {meta['python']}, numpy {meta['numpy']}, scipy {meta['scipy']}, numba {meta['numba']}, "
         f"exudyn {meta['exudyn']}, lgt_bridge {meta.get('lgt_bridge')} ({meta.get('git', 'no git')}); "
         f"{meta['cpu_count']} CPUs ({meta['machine']}), shared. Preset {st['preset']}, "
         f"backend {st['backend']}, total wall {data['total_wall_s']:.0f} s.", ""]
    L += [f"- {n}" for n in data["notes"]]
    L += ["", "## 3. Targets (section 3 of issue 10)", "", "| target | met | worst |", "|---|---|---|"]
    for v in data["verdicts"]:
        vals = v["values"]
        worst = ""
        if vals:
            k, x = max(vals.items(), key=lambda kv: abs(kv[1] - 1) if "∝" in v["target"] else kv[1])
            worst = f"{x:.2f} ({k})"
        L.append(f"| {v['target']} | {_ok(v['ok'])} | {worst or v.get('detail', '')} |")
    L += ["", "k < 0.9: the cost per step grows slower than N over the range (a fixed per-step cost still "
          "dominates its small end); the target asks for 1 ± 0.1. Memory: sub-linear growth is O(N).", ""]
    combos = sorted({(r["group"], r["chart"], r["method"]) for r in data["glue"]})
    if any(r.get("glue_over_exudyn") is not None for r in data["glue"]):
        ratio = {(r["N"], r["group"], r["chart"], r["method"]): r.get("glue_over_exudyn") for r in data["glue"]}
        L += ["glue / Exudyn evaluation (target ≤ 2 at N = 1, ≤ 0.5 at N ≥ 100):", "",
              "| N | " + " | ".join(f"{g}/{c} {m}" for g, c, m in combos) + " |",
              "|---:|" + "---:|" * len(combos)]
        for N in st["Ns"]:
            L.append(f"| {N} | " + " | ".join(_f(ratio.get((N, *k)), ".2f") for k in combos) + " |")
    L += ["", "## 1. Glue per stage on N free bodies", "",
          "glue = (stepping wall − time inside f) / n_f; f = the engine-free scene's own f "
          "(its backend follows LGT_BRIDGE_BACKEND). "
          f"rkmk4 at dt = {st['dt']:g}, adaptive methods at rtol = atol = {st['tol']:g}; T calibrated per run "
          f"(≈ {st['target_wall']:g} s, ≥ {st['min_steps']} steps), the least disturbed of {st['run_repeats']} "
          "identical runs. Exudyn = best µs per evaluation "
          "(section 2). Set-up = input checks + stepper build (not in the glue). Peak = tracemalloc during a "
          f"separate short run. The f timer adds ≈ {meta['timer_overhead_us']:.2f} µs per call to the glue.", "",
          "| N | group | chart | method | steps | n_f | set-up s | µs/step | f µs/eval | glue µs/eval | "
          "Exudyn µs/eval | glue/Exudyn | peak MB | B/body |",
          "|---:|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in data["glue"]:
        if not r["success"]:
            L.append(f"| {r['N']} | {r['group']} | {r['chart']} | {r['method']} | failed: {r['message']} |"
                     " | | | | | | | | |")
            continue
        L.append(f"| {r['N']} | {r['group']} | {r['chart']} | {r['method']} | {r['n_steps']} | {r['n_f']} | "
                 f"{r['setup_s']:.3f} | {r['us_per_step']:.1f} | {r['f_us_per_eval']:.1f} | "
                 f"{r['glue_us_per_eval']:.1f} | {_f(r['exudyn_us_per_eval'], '.2f')} | "
                 f"{_f(r['glue_over_exudyn'], '.2f')} | {r['peak_bytes'] / 1e6:.2f} | {r['bytes_per_body']:.0f} |")
    L += ["", "Exponents (least squares in log-log):", "",
          "| group | chart | method | N range | k of time/step | k, N ≥ 1000 | memory slope | B/body at max N |",
          "|---|---|---|---|---:|---:|---:|---:|"]
    for f in data["fits"]:
        rng = f"{f['N_range'][0]} … {f['N_range'][1]}" if f["N_range"] else "–"
        L.append(f"| {f['group']} | {f['chart']} | {f['method']} | {rng} | {_f(f['k_time_per_step'], '.3f')} | "
                 f"{_f(f['k_time_per_step_N_ge_1000'], '.3f')} | {_f(f['memory_slope'], '.3f')} | "
                 f"{_f(f['bytes_per_body_at_max_N'], '.0f')} |")
    L += ["", "## 2. Exudyn floor: one evaluation of N free RotVecLG bodies", ""]
    ex = data["exudyn"]
    if ex.get("skipped"):
        L.append(f"Skipped: {ex['skipped']}")
    else:
        L += ["Write q and q_t through `GetODE2Coordinates(copy=False)` / `GetODE2Coordinates_t(copy=False)` "
              "views, `SetTime`, `MainSolverImplicitSecondOrder.ComputeODE2RHS`, read "
              "`GetSystemResidual()[:n2]` (a copy). No gravity, no mass-matrix solve. Best of "
              f"{st['repeats']} repeats. 'Set*' writes with `SetODE2Coordinates`/`_t` instead. Build = "
              "CreateRigidBody × N + Assemble + InitializeSolver (sparse linear solver).", "",
              "| N | build s | µs/eval (views) | µs/eval (Set*) | µs per body | views = Set* | "
              "max |RHS − scene forces| |", "|---:|---:|---:|---:|---:|---|---:|"]
        for r in ex["rows"]:
            L.append(f"| {r['N']} | {r['build_s']:.3f} | {r['us_per_eval']:.2f} | {r['us_per_eval_set']:.2f} | "
                     f"{r['us_per_body']:.3f} | {r['view_write_matches_set']} | {r['rhs_vs_scene_forces']:.1e} |")
        for s in ex.get("capped", []):
            L.append(f"\nN = {s['N']} left out: estimated build {s['estimated_build_s']:.0f} s > cap "
                     f"{st['exudyn_max_build_s']:g} s.")
    ga = data.get("genalpha") or []
    if ga:
        L += ["", f"## 5. Generalized-α on {ga[0]['N']} free bodies on SE(3)/exp", "",
              f"Time per step (stats wall_s / steps, least of the repeated runs of {ga[0]['steps']} steps at "
              f"dt = {ga[0]['dt']:g}) against one f of the same model (best of a loop); target ≤ {GA_TARGET:g}×.",
              "", "| model | µs per step | f µs | ratio | Newton iterations / step | f / step | Jacobians |",
              "|---|---:|---:|---:|---:|---:|---:|"]
        for g in ga:
            L.append(f"| {g['model']} | {g['us_per_step']:.1f} | {g['f_us']:.2f} | {g['ratio']:.1f} | "
                     f"{g['newton_per_step']:.2f} | {g['f_per_step']:.2f} | {g['jacobians']} |")
    wp = data["work_precision"]
    L += ["", "## 4. Heavy top work-precision", ""]
    if not wp or wp.get("skipped"):
        L.append(f"Skipped: {wp.get('skipped') if wp else 'not run'}")
    else:
        ref = wp["reference"]
        L += [f"`scenes.heavy_top(constrained=True)`, t = 0 … {wp['T']:g} s, {wp['group']}/{wp['chart']}. "
              f"Reference: {ref['method']} ({ref['backend']} backend) at rtol = atol = {ref['rtol']:g} "
              f"({ref['n_steps']} steps, {ref['wall_s']:.1f} s). Pose error = largest rotation angle + largest "
              "position error at T (`lgt_bridge.bench.pose_error`). Wall and n_f at a target error: log-log "
              "interpolation between the runs that bracket it (`lgt_bridge.bench.wall_at_error`); ≤ marks "
              f"the cheapest run below it (not bracketed). Wall: least of up to {st['wp_repeats']} repeats "
              f"while a setting's repeats stay under {st['wp_budget_s']:g} s.", "",
              "| method | backend | wall s @ 1e-6 | n_f @ 1e-6 | wall s @ 1e-8 | n_f @ 1e-8 |",
              "|---|---|---:|---:|---:|---:|"]
        by = {(x["method"], x["backend"], x["pose_error"]): x for x in wp["at_error"]}
        for m, b in sorted({(x["method"], x["backend"]) for x in wp["at_error"]}):
            cells = []
            for e in WP_ERRORS:
                x = by[(m, b, e)]
                for key, exact, fmt in (("wall_s", "wall_exact", ".3f"), ("n_f", "n_f_exact", ".0f")):
                    cells.append(("" if x[exact] else "≤ ") + format(x[key], fmt) if x[key] else "not reached")
            L.append(f"| {m} | {b} | " + " | ".join(cells) + " |")
        meths = sorted({x["method"] for x in wp["at_error"]})
        backs = sorted({x["backend"] for x in wp["at_error"]})
        L += ["", "Ratios at equal pose error (from the interpolated values; ≤ entries are bounds):", ""]
        for e in WP_ERRORS:
            if "dopri5" in meths and "dop853" in meths:
                for b in backs:
                    x5, x8 = by[("dopri5", b, e)], by[("dop853", b, e)]
                    if x5["wall_s"] and x8["wall_s"]:
                        L.append(f"- {e:g}, {b}: dopri5 / dop853 n_f {x5['n_f'] / x8['n_f']:.2f}, "
                                 f"wall {x5['wall_s'] / x8['wall_s']:.2f}")
            if "numpy" in backs and "numba" in backs:
                for m in meths:
                    xp, xn = by[(m, "numpy", e)], by[(m, "numba", e)]
                    if xp["wall_s"] and xn["wall_s"]:
                        L.append(f"- {e:g}, {m}: numpy / numba wall {xp['wall_s'] / xn['wall_s']:.2f}")
        L += ["", "| method | backend | rtol = atol | pose error | n_f | steps | rejected | wall s |",
              "|---|---|---:|---:|---:|---:|---:|---:|"]
        for r in wp["rows"]:
            L.append(f"| {r['method']} | {r['backend']} | {r['tol']:.0e} | {_f(r['pose_error'], '.2e', 'failed')} | "
                     f"{r['n_f']} | {r['n_steps']} | {r['n_rejected']} | {r['wall_s']:.3f} |")
    (out / "integrator_cost.md").write_text("\n".join(L) + "\n")
    return L


# --------------------------------------------------------------------------- main
def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--quick", action="store_true", help="smoke run: N ≤ 100, few tolerances (< 30 s)")
    mode.add_argument("--tiny", action="store_true", help="smallest run, for the test suite")
    ap.add_argument("--methods", default="rkmk4,dop853", help="section 1 (dop853 → dopri5 until it exists)")
    ap.add_argument("--groups", default="SO3xR3,SE3")
    ap.add_argument("--charts", default="exp", help="e.g. exp,cay")
    ap.add_argument("--Ns", default=None, help="comma-separated body counts (default per preset)")
    ap.add_argument("--backend", default=None, help="section 1 backend (default: $LGT_BRIDGE_BACKEND or numba)")
    ap.add_argument("--target-wall", type=float, default=None, help="seconds per section-1 run")
    ap.add_argument("--min-steps", type=int, default=None)
    ap.add_argument("--dt", type=float, default=1e-3, help="step of the fixed-step methods")
    ap.add_argument("--tol", type=float, default=1e-8, help="rtol = atol of the adaptive methods (section 1)")
    ap.add_argument("--repeats", type=int, default=None, help="repeats of the Exudyn evaluation timing")
    ap.add_argument("--exudyn-max-build", type=float, default=60.0, help="cap on the Exudyn build time, s")
    ap.add_argument("--no-exudyn", action="store_true")
    ap.add_argument("--wp-methods", default="dopri5,dop853")
    ap.add_argument("--wp-backends", default="numpy,numba")
    ap.add_argument("--wp-tols", default=None)
    ap.add_argument("--wp-T", type=float, default=None)
    ap.add_argument("--wp-group", default="SE3")
    ap.add_argument("--wp-chart", default="exp")
    ap.add_argument("--ref-tol", type=float, default=None)
    ap.add_argument("--run-repeats", type=int, default=None, help="section-1 runs repeated, least wall kept")
    ap.add_argument("--wp-repeats", type=int, default=3, help="work-precision runs repeated while under "
                    "--wp-budget s in total; least wall kept")
    ap.add_argument("--wp-budget", type=float, default=None)
    ap.add_argument("--no-wp", action="store_true")
    ap.add_argument("--no-ga", action="store_true", help="skip section 5 (genalpha on free bodies)")
    a = ap.parse_args(argv)
    preset = "tiny" if a.tiny else "quick" if a.quick else "full"
    P = PRESETS[preset]
    a.Ns = _csv(a.Ns, int) or P["Ns"]
    a.wp_tols = _csv(a.wp_tols, float) or P["wp_tols"]
    for k in ("target_wall", "min_steps", "wp_T", "ref_tol", "repeats", "run_repeats", "wp_budget"):
        if getattr(a, k) is None:
            setattr(a, k, P[k])
    a.wp_methods, a.wp_backends = _csv(a.wp_methods), _csv(a.wp_backends)
    t_start = time.perf_counter()
    env_before = os.environ.get(_backend.ENV)
    notes = []
    try:
        backend = _backend.name(a.backend)
        _set_backend(backend)
        methods = _resolve(_csv(a.methods), notes)
        combos = [(g, c, m) for g in _csv(a.groups) for c in _csv(a.charts) for m in methods]
        meta = dict(_versions(), timer_overhead_us=_timer_overhead_us())
        have_exu = importlib.util.find_spec("exudyn") is not None and not a.no_exudyn
        if not have_exu:
            msg = "--no-exudyn" if a.no_exudyn else "exudyn is not importable (pip install 'lgt-bridge[exudyn]')"
            print(f"Exudyn floor skipped: {msg}")
            notes.append(f"Exudyn floor skipped: {msg}; glue ratios and their targets not measured.")
        for g, c, m in combos:                       # warm-up: numba compiles on first use
            run_bridge(1, m, g, c, 5 * a.dt if m in FIXED else 0.01, a.dt, a.tol)
        rows, exu_rows, capped = [], [], []
        for N in a.Ns:
            if have_exu:
                est = exu_rows[-1]["build_s"] * N / exu_rows[-1]["N"] if exu_rows else 0.0
                if est > a.exudyn_max_build:
                    capped.append(dict(N=N, estimated_build_s=est))
                    notes.append(f"Exudyn N = {N} not built: estimated {est:.0f} s > cap {a.exudyn_max_build:g} s.")
                else:
                    r = exudyn_floor(N, a.repeats, P["eval_budget"])
                    exu_rows.append(r)
                    print(f"Exudyn N={N:6d}: build {r['build_s']:7.3f} s  {r['us_per_eval']:9.2f} µs/eval (views)  "
                          f"{r['us_per_eval_set']:9.2f} (Set*)", flush=True)
            for g, c, m in combos:
                r = glue_row(N, m, g, c, a)
                rows.append(r)
                e = exu_rows[-1]["us_per_eval"] if exu_rows and exu_rows[-1]["N"] == N else None
                nan = float("nan")
                print(f"N={N:6d} {g:7s} {c:4s} {m:7s} steps {r['n_steps']:6d}  "
                      f"{r.get('us_per_step', nan):10.1f} µs/step  f {r.get('f_us_per_eval', nan):9.1f}"
                      f"  glue {r.get('glue_us_per_eval', nan):9.1f} µs/eval"
                      + (f"  glue/Exudyn {r.get('glue_us_per_eval', nan) / e:6.2f}" if e else "")
                      + f"  peak {r['peak_bytes'] / 1e6:8.2f} MB", flush=True)
        ga_rows = []
        if not a.no_ga:
            models = [("engine-free scene (compiled f)", lambda n: scenes.free_bodies(n))]
            if have_exu:
                models.append(("Exudyn RotVecLG bodies (ExudynModel)", _exudyn_free_bodies))
            ga_rows = genalpha_cost(models, P["ga_N"], P["ga_steps"], a.dt, P["run_repeats"] + 1)
            for g in ga_rows:
                print(f"genalpha N={g['N']} {g['model']}: {g['us_per_step']:.1f} µs/step, f {g['f_us']:.2f} µs, "
                      f"ratio {g['ratio']:.1f}", flush=True)
        fits, verdicts = fits_and_verdicts(rows, exu_rows, a.Ns, ga_rows)
        wp = dict(skipped="--no-wp") if a.no_wp else work_precision(a, notes)
    finally:
        if env_before is None:
            os.environ.pop(_backend.ENV, None)
        else:
            os.environ[_backend.ENV] = env_before
    settings = dict(preset=preset, backend=backend, methods=methods, groups=_csv(a.groups), charts=_csv(a.charts),
                    Ns=a.Ns, dt=a.dt, tol=a.tol, target_wall=a.target_wall, min_steps=a.min_steps,
                    repeats=a.repeats, run_repeats=a.run_repeats, wp_repeats=a.wp_repeats,
                    wp_budget_s=a.wp_budget, exudyn_max_build_s=a.exudyn_max_build, wp_methods=a.wp_methods,
                    wp_backends=a.wp_backends, wp_tols=a.wp_tols, wp_T=a.wp_T, ref_tol=a.ref_tol, targets=TARGETS)
    exu = (dict(rows=exu_rows, capped=capped) if have_exu
           else dict(skipped=notes[[n.startswith("Exudyn floor skipped") for n in notes].index(True)]))
    data = dict(meta=meta, settings=settings, notes=notes, glue=rows, fits=fits, exudyn=exu, verdicts=verdicts,
                genalpha=ga_rows,
                work_precision=wp, total_wall_s=time.perf_counter() - t_start)
    out = Path(a.out)
    write_report(out, data)
    for v in verdicts:
        print(f"{'MET ' if v['ok'] else 'not met' if v['ok'] is False else 'n/a '}  {v['target']}")
    print(f"wrote {out / 'integrator_cost.md'} ({data['total_wall_s']:.0f} s)")
    return data


if __name__ == "__main__":
    sys.exit(0 if main() is not None else 1)
