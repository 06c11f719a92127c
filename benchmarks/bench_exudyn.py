"""Exudyn models: the bridge against Exudyn's own solvers, and the issue's four targets.

    python benchmarks/bench_exudyn.py [--out benchmarks/results] [--quick] [--chain]

One run measures every target and writes exudyn_work_precision.{json,md}:

T1  adapter glue per f ≤ 2x Exudyn's own evaluation cost, heavy top (EP and RotVecLG
    nodes, spherical joint). A loop of f calls at the initial state: wall per f without
    any instrumentation; "inside" = the same sequence of Exudyn calls that one f makes
    (recorded once, replayed with the same arguments, no bridge code in between); glue =
    wall - inside. Also, for context: the same loop through a timing proxy, and a whole
    run (dop853) with the proxy (time inside Exudyn's calls over the run / n_f).
T2  heavy top, EP node + spherical joint, 0.5 s: the bridge's best family (dopri5, dop853
    x SE3/SO3xR3 x exp/cay, tolerance sweeps) reaches pose error 1e-6 ≥ 10x and 1e-8 ≥ 30x
    faster than Exudyn's best native family (generalized-α on EP nodes, on RotVecLG nodes
    with lieGroupSimplifiedKinematicRelations). A native family that does not reach an
    error is extrapolated along its last two runs (log-log) and marked so.
T3  N = 8 and 100 free tumbling bodies on RotVecLG nodes (random asymmetric inertias,
    attitudes, spins; gravity), built with mbs.CreateRigidBody, 2 s: the bridge (dopri5,
    dop853, every group/chart) against Exudyn's C++ explicit Lie group DOPRI5
    (automaticStepSize, tolerance sweep; timeIntegration.explicit, the 1.13 spelling of
    the deprecated explicitIntegration); bridge wall ≤ 2x Exudyn's at error 1e-6 and ≤ 1x
    at 1e-8. Reference: the bridge's dop853 at rtol = atol = 1e-13, checked against
    Exudyn's DOPRI5 at 1e-12.
T4  100 free bodies on EP nodes: one f ≤ 500 µs.

Error = largest body rotation angle + largest position error at the end time. The wall
time of a family at an error is interpolated log-log between its runs
(lgt_bridge.bench.wall_at_error). Every wall time is the best of 3 repetitions of the
same run in this process (1 with --quick), ratios from the same process; the repetitions
go in rounds (a scene's whole list of runs, natives and bridge, three times in turn), so a
noisy spell of the shared machine spoils one repetition of a run rather than all three.
The T1 f loops alternate plain and replayed blocks (3 x 10 blocks of n/10 calls each, the
fastest block counts). Exudyn runs write no files and print nothing (solution file,
sensors, verbose output, timers off).

Bridge runs reuse one ExudynModel per scene; each run drops the model's per-run caches
(the compiled kernels' pack, the cached M̄⁻¹) so it pays what a run on a fresh model pays.
The construction ExudynModel(mbs) is timed on its own (best of 3) and reported both
outside the run (the "run" wall, as Exudyn's SolveDynamic wall excludes building the
system) and added to it ("incl. model" columns).

--chain adds the 20-link chain on spherical joints (1 s; not a target, Exudyn's GA is
slow there: several minutes).
"""
import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "models"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import exudyn as exu  # noqa: E402
import exudyn_models as em  # noqa: E402
from exudyn.utilities import RigidBodyInertia  # noqa: E402

from lgt_bridge import scenes  # noqa: E402
from lgt_bridge.bench import wall_at_error  # noqa: E402
from lgt_bridge.groups import quaternion as _q  # noqa: E402
from lgt_bridge.groups import so3  # noqa: E402
from lgt_bridge.scenes import principal_inertia  # noqa: E402
from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_exudyn import ExudynModel  # noqa: E402

GROUPS, CHARTS = ("SE3", "SO3xR3"), ("exp", "cay")
BLOCKS = 10          # f loops: each repetition is BLOCKS interleaved blocks of n_loop / BLOCKS calls
TARGETS = {"T1": 2.0, "T2_1e-6": 10.0, "T2_1e-8": 30.0, "T3_1e-6": 2.0, "T3_1e-8": 1.0, "T4": 500.0}


# ----------------------------------------------------------------------------- timing tools
class Timer:
    def __init__(self):
        self.inside = 0.0
        self.calls = 0


class Proxy:
    """Times every method call on the wrapped Exudyn object."""

    def __init__(self, obj, timer):
        self._obj, self._timer = obj, timer

    def __getattr__(self, name):
        attr = getattr(self._obj, name)
        if not callable(attr):
            return attr
        timer = self._timer

        def call(*a, **k):
            t0 = time.perf_counter()
            try:
                return attr(*a, **k)
            finally:
                timer.inside += time.perf_counter() - t0
                timer.calls += 1
        return call


class Recorder:
    """Records every method call on the wrapped Exudyn object (bound method, args)."""

    def __init__(self, obj, log):
        self._obj, self._log = obj, log

    def __getattr__(self, name):
        attr = getattr(self._obj, name)
        if not callable(attr):
            return attr

        def call(*a, **k):
            self._log.append((attr, a, k))
            return attr(*a, **k)
        return call


def best_of(reps, run):
    """run() -> (result, wall); the result of the fastest of ``reps`` runs, its wall, all walls."""
    best, walls = None, []
    for _ in range(reps):
        res, wall = run()
        walls.append(wall)
        if best is None or wall < best[1]:
            best = (res, wall)
    return best[0], best[1], walls


def rounds(jobs, reps, label=None):
    """jobs: [(key, run)], run() -> (result, wall). The whole list runs ``reps`` times in turn
    (a noisy spell of the shared machine then hits one repetition of a run, not all of
    them); per key: (result of its fastest repetition, its wall, all walls)."""
    best = {}
    for k in range(reps):
        t0 = time.perf_counter()
        for key, run in jobs:
            res, wall = run()
            if key not in best:
                best[key] = [res, wall, [wall]]
            else:
                b = best[key]
                b[2].append(wall)
                if wall < b[1]:
                    b[0], b[1] = res, wall
        if label:
            say(f"  {label}: round {k + 1}/{reps}, {len(jobs)} runs, {time.perf_counter() - t0:.1f} s")
    return {key: tuple(v) for key, v in best.items()}


def error(layout_model, q, q_ref):
    eR = er = 0.0
    for b in layout_model.layout.bodies:
        R = b.param.alpha(q[[*b.pos, *b.rot]])[:3, :3]
        Rr = b.param.alpha(q_ref[[*b.pos, *b.rot]])[:3, :3]
        eR = max(eR, float(np.linalg.norm(so3.log(R.T @ Rr))))
        er = max(er, float(np.abs(q[list(b.pos)] - q_ref[list(b.pos)]).max()))
    return eR + er


def quiet_settings(T, n):
    """Exudyn settings writing no files and printing nothing."""
    s = em.settings(T, n)                 # solution file off, sensors off, verboseMode 0, no computation time
    s.timeIntegration.verboseModeFile = 0
    if hasattr(s, "show"):
        s.show.globalTimers = False
        s.show.statistics = False
    return s


# ----------------------------------------------------------------------------- scenes
def tumbling(n, node=em.ROTVEC, seed=1):
    """n free bodies as an Exudyn user builds them: random asymmetric inertias, masses,
    attitudes and spins (|ω| ≈ 5 rad/s), under gravity."""
    rng = np.random.default_rng(seed)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    for _ in range(n):
        J = principal_inertia(rng)
        p = rng.normal(size=4)
        p /= np.linalg.norm(p)
        mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=1.0 + rng.uniform(), inertiaTensor=J), nodeType=node,
                            referencePosition=rng.normal(size=3) * 3.0,
                            referenceRotationMatrix=_q._to_matrix(p[None])[0],
                            initialAngularVelocity=rng.normal(size=3) * 3.0, initialVelocity=rng.normal(size=3),
                            gravity=em.G)
    mbs.Assemble()
    return SC, mbs


# ----------------------------------------------------------------------------- runs
def native_ga(make, T, n, rotvec=False):
    """Exudyn's generalized-α with n steps: (q, wall)."""
    SC, mbs = make()[:2]
    s = quiet_settings(T, n)
    if rotvec:
        s.timeIntegration.generalizedAlpha.lieGroupSimplifiedKinematicRelations = True
    t0 = time.perf_counter()
    mbs.SolveDynamic(s)
    wall = time.perf_counter() - t0
    return dict(q=em.total_q(mbs), n_steps=n), wall


def native_dopri5(make, T, tol):
    """Exudyn's explicit Lie group DOPRI5 (C++), adaptive at rtol = atol = tol: (dict, wall)."""
    SC, mbs = make()[:2]
    s = quiet_settings(T, 1)              # Exudyn caps an adaptive step at endTime / numberOfSteps
    ti = s.timeIntegration
    ex = ti.explicit if hasattr(ti, "explicit") else ti.explicitIntegration   # 1.13: 'explicit'
    ex.useLieGroupIntegration = True
    ex.computeEndOfStepAccelerations = False          # not needed for the end state; ~10 % faster
    ti.automaticStepSize = True
    ti.absoluteTolerance = ti.relativeTolerance = tol
    ti.minimumStepSize = 1e-12
    t0 = time.perf_counter()
    mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.DOPRI5)
    wall = time.perf_counter() - t0
    it = mbs.sys["dynamicSolver"].it
    return dict(q=em.total_q(mbs), n_steps=int(it.currentStepIndex),
                n_rejected=int(it.rejectedAutomaticStepSizeSteps)), wall


def fresh(model):
    """Drop the caches a run builds on its model (so a reused model costs what a new one does)."""
    model.reset_caches()


def bridge_run(model, T, method, group, chart, timer=None, **kw):
    fresh(model)
    saved = model.solver, model.sd
    if timer is not None:
        model.solver, model.sd = Proxy(model.solver, timer), Proxy(model.sd, timer)
    try:
        t0 = time.perf_counter()
        r = simulate(model, (0, T), method=method, group=group, chart=chart, t_eval=[T], progress=False, **kw)
        wall = time.perf_counter() - t0
    finally:
        model.solver, model.sd = saved
        fresh(model)
    return r, wall


def model_build(make, reps):
    """(model, best wall of ExudynModel(mbs), walls): construction on a freshly built system."""
    def one():
        mbs = make()[1]
        t0 = time.perf_counter()
        m = ExudynModel(mbs)
        return m, time.perf_counter() - t0
    return best_of(reps, one)


def f_costs(make, n_loop, reps):
    """Per f at the initial state (µs): plain wall, Exudyn's calls replayed, proxied loop. The
    plain and replayed loops alternate in blocks of n_loop / BLOCKS calls, reps x BLOCKS of each;
    each is its fastest block."""
    model = ExudynModel(make()[1])
    q, V = model.q0.copy(), model.V0.copy()
    model.f(q, V, 0.0)

    def loop(n=n_loop):
        t0 = time.perf_counter()
        for _ in range(n):
            model.f(q, V, 0.0)
        return None, (time.perf_counter() - t0) / n

    # the wrappers go in before the model packs (an unconstrained model's f binds Exudyn's
    # methods once, when it packs), and out again with a fresh pack
    log, saved = [], (model.solver, model.sd)
    model.solver, model.sd = Recorder(model.solver, log), Recorder(model.sd, log)
    model.reset_caches()
    model.f(q, V, 0.0)
    del log[:]
    model.f(q, V, 0.0)
    model.solver, model.sd = saved
    model.reset_caches()
    model.f(q, V, 0.0)
    calls = [c[0].__name__ for c in log]

    def replay(n=n_loop // BLOCKS):
        t0 = time.perf_counter()
        for _ in range(n):
            for fn, a, k in log:
                fn(*a, **k)
        return None, (time.perf_counter() - t0) / n

    # the two in turn, in short blocks (same conditions on the shared machine): best block of each
    res = rounds([("plain", lambda: loop(n_loop // BLOCKS)), ("replay", replay)], reps * BLOCKS)
    (_, plain, plain_all), (_, inside, inside_all) = res["plain"], res["replay"]
    timer = Timer()
    model.solver, model.sd = Proxy(saved[0], timer), Proxy(saved[1], timer)
    model.reset_caches()
    model.f(q, V, 0.0)
    timer.inside = 0.0
    _, proxied, _ = best_of(1, loop)
    inside_proxy = timer.inside / n_loop
    model.solver, model.sd = saved
    model.reset_caches()
    return dict(us_per_f=plain * 1e6, inside_us=inside * 1e6, glue_us=(plain - inside) * 1e6,
                glue_over_inside=(plain - inside) / inside, exudyn_calls_per_f=len(calls), exudyn_calls=calls,
                proxied_us_per_f=proxied * 1e6, proxied_inside_us=inside_proxy * 1e6,
                plain_walls_us=[w * 1e6 for w in plain_all], inside_walls_us=[w * 1e6 for w in inside_all],
                n_loop=n_loop, nv=model.nv, n_constraints=model.n_constraints)


def at_error(rows, target):
    """{family: (wall, how)} at ``target``: how = "interpolated", "≤ (not bracketed)" or
    "extrapolated" (log-log along the family's two most accurate runs, all above target)."""
    out = {}
    for fam in sorted({r["family"] for r in rows}):
        rs = [r for r in rows if r["family"] == fam and np.isfinite(r["error"]) and r["error"] > 0]
        w, exact = wall_at_error(rs, target, key="error")
        if w is not None:
            out[fam] = (w, "interpolated" if exact else "≤ (not bracketed)")
            continue
        pts = sorted((r["error"], r["wall_s"]) for r in rs)
        if len(pts) >= 2 and pts[0][0] > target:
            (e1, w1), (e2, w2) = pts[0], pts[1]
            if e2 > e1 and w2 != w1:
                slope = (np.log(w1) - np.log(w2)) / (np.log(e1) - np.log(e2))
                out[fam] = (float(w1 * (target / e1) ** slope), "extrapolated")
    return out


def best(fams, prefix):
    sel = {f: v for f, v in fams.items() if f.startswith(prefix)}
    if not sel:
        return None
    f, (w, how) = min(sel.items(), key=lambda kv: kv[1][0])
    return dict(family=f, wall_s=w, how=how)


def _to_rotvec_ref(twin, qref):
    """The reference in rotation-vector coordinates (position, ρ) for the RotVecLG runs."""
    from lgt_bridge import params
    out = []
    for b in twin.layout.bodies:
        p = b.param._to_quat(qref[list(b.rot)][None])
        out.append(np.concatenate([qref[list(b.pos)], params.ROTVEC._from_quat(p, np.zeros((1, 3)))[0]]))
    return np.concatenate(out)


def say(*a):
    print(*a, flush=True)


# ----------------------------------------------------------------------------- sections
def t1_and_t4(cfg):
    out = {}
    for key, make in (("heavy top EP", lambda: em.heavy_top(em.EP)), ("heavy top RotVecLG", lambda: em.heavy_top(em.ROTVEC)),
                      ("8 free RotVecLG", lambda: tumbling(8)),
                      ("100 free EP", lambda: tumbling(100, em.EP)), ("100 free RotVecLG", lambda: tumbling(100))):
        c = f_costs(make, cfg["n_loop"] // 10 if key.startswith("100") else cfg["n_loop"], cfg["reps"])
        out[key] = c
        say(f"f on {key:20s}: {c['us_per_f']:7.1f} µs (Exudyn's calls {c['inside_us']:6.1f} µs, glue "
            f"{c['glue_us']:6.1f} µs, glue/inside {c['glue_over_inside']:.2f}; proxied {c['proxied_us_per_f']:.1f} µs "
            f"with {c['proxied_inside_us']:.1f} inside)")
    return out


def t2(cfg, rows, extra):
    T = 0.5
    twin = scenes.heavy_top(True)
    t0 = time.perf_counter()
    ref = simulate(twin, (0, T), method="dop853", rtol=1e-13, atol=1e-13, t_eval=[T], progress=False)
    qref = ref.q[-1]
    chk = simulate(twin, (0, T), method="dopri5", rtol=1e-12, atol=1e-12, t_eval=[T], progress=False)
    twin_rv = scenes.heavy_top(True, param="rotvec")
    qref_rv = _to_rotvec_ref(twin, qref)
    model, build, build_all = model_build(lambda: em.heavy_top(em.EP), cfg["reps"])
    viaexu, _ = bridge_run(model, T, "dop853", "SE3", "exp", rtol=1e-13, atol=1e-13)
    reference = dict(what="engine-free twin (lgt_bridge.scenes.heavy_top), dop853 rtol = atol = 1e-13",
                     n_f=ref.stats["n_f"], vs_twin_dopri5_1e12=error(twin, chk.q[-1], qref),
                     vs_bridge_on_exudyn_dop853_1e13=error(twin, viaexu.q[-1], qref),
                     model_build_s=build, model_build_walls_s=build_all)
    extra["T2_reference"] = reference
    say(f"heavy top: reference {time.perf_counter() - t0:.1f} s; twin dopri5 1e-12 differs by "
        f"{reference['vs_twin_dopri5_1e12']:.1e}, the bridge on Exudyn at 1e-13 by "
        f"{reference['vs_bridge_on_exudyn_dop853_1e13']:.1e}; ExudynModel(mbs) {build * 1e3:.1f} ms")
    scene = "T2 heavy top"
    jobs, info = [], {}
    for rv, steps in ((False, cfg["ga_ep"]), (True, cfg["ga_rv"])):
        fam = "Exudyn GA " + ("RotVecLG" if rv else "EP")
        make = (lambda: em.heavy_top(em.ROTVEC)) if rv else (lambda: em.heavy_top(em.EP))
        for n in steps:
            key = (fam, f"h={T / n:.2e}")
            jobs.append((key, lambda make=make, n=n, rv=rv: native_ga(make, T, n, rotvec=rv)))
            info[key] = dict(native=True, rv=rv)
    runs = [(m, g, ch, dict(rtol=t, atol=t), f"tol={t:g}") for m in ("dopri5", "dop853")
            for g in GROUPS for ch in CHARTS for t in cfg["tols_t2"][m]]
    runs += [("rkmk4", "SO3xR3", "exp", dict(dt=d), f"dt={d:g}") for d in cfg["dts_t2"]]
    runs += [("genalpha", "SO3xR3", "exp", dict(dt=d), f"dt={d:g}") for d in cfg["genalpha_dts_t2"]]
    for method, g, ch, kw, setting in runs:
        key = (f"bridge {method} {g} {ch}", setting)
        jobs.append((key, lambda method=method, g=g, ch=ch, kw=kw: bridge_run(model, T, method, g, ch, **kw)))
        info[key] = dict(native=False)
    res = rounds(jobs, cfg["reps"], scene)
    for key, _ in jobs:
        (fam, setting), (r, wall, walls) = key, res[key]
        if info[key]["native"]:
            rv = info[key]["rv"]
            e = error(twin_rv if rv else twin, r["q"], qref_rv if rv else qref)
            rows.append(dict(scene=scene, family=fam, setting=setting, error=e, wall_s=wall, walls_s=walls,
                             n_f=None, n_steps=r["n_steps"]))
            say(f"  {fam:28s} {setting:14s} error {e:9.2e}  wall {wall:8.3f} s  (steps {r['n_steps']})")
            continue
        e = error(twin, r.q[-1], qref) if r.success else float("nan")
        rows.append(dict(scene=scene, family=fam, setting=setting, error=e, wall_s=wall, walls_s=walls,
                         wall_incl_model_s=wall + build, n_f=r.stats["n_f"], n_steps=r.stats["n_steps"],
                         setup_s=wall - r.stats["wall_s"], us_per_f=wall / r.stats["n_f"] * 1e6))
        say(f"  {fam:28s} {setting:14s} error {e:9.2e}  wall {wall:8.3f} s  n_f {r.stats['n_f']:6d}"
            f"  {wall / r.stats['n_f'] * 1e6:5.1f} µs per f")
    return build


def t1_runs(cfg, extra):
    """T1 over a whole run: dop853 SE3 exp at tol 1e-9 on the heavy top (EP and RotVecLG)."""
    out = {}
    for key, node in (("heavy top EP", em.EP), ("heavy top RotVecLG", em.ROTVEC)):
        model = ExudynModel(em.heavy_top(node)[1])
        kw = dict(rtol=cfg["t1_tol"], atol=cfg["t1_tol"])
        r, wall, walls = best_of(cfg["reps"], lambda: bridge_run(model, 0.5, "dop853", "SE3", "exp", **kw))
        timer = Timer()
        rp, wall_p = bridge_run(model, 0.5, "dop853", "SE3", "exp", timer=timer, **kw)
        nf = r.stats["n_f"]
        out[key] = dict(run=f"dop853 SE3 exp tol={cfg['t1_tol']:g}, 0.5 s", n_f=nf, n_steps=r.stats["n_steps"],
                        wall_s=wall, us_per_f=wall / nf * 1e6, proxied_wall_s=wall_p,
                        proxied_inside_us_per_f=timer.inside / rp.stats["n_f"] * 1e6,
                        exudyn_calls_per_f=timer.calls / rp.stats["n_f"],
                        setup_s=wall - r.stats["wall_s"])
        say(f"run on {key}: {nf} f, {wall:.3f} s = {wall / nf * 1e6:.1f} µs per f (inside Exudyn, proxied: "
            f"{out[key]['proxied_inside_us_per_f']:.1f} µs per f; setup before the first step {out[key]['setup_s'] * 1e3:.1f} ms)")
    extra["T1_runs"] = out


def t3(cfg, rows, extra, N):
    T = 2.0
    scene = f"T3 {N} free RotVecLG"
    make = lambda: tumbling(N)                                    # noqa: E731
    model, build, build_all = model_build(make, cfg["reps"])
    t0 = time.perf_counter()
    ref, _ = bridge_run(model, T, "dop853", "SE3", "exp", rtol=1e-13, atol=1e-13)
    qref = ref.q[-1]
    tight, tight_wall = native_dopri5(make, T, cfg["t3_tight"])
    ref_info = dict(what="the bridge on the Exudyn model, dop853 SE3 exp, rtol = atol = 1e-13", n_f=ref.stats["n_f"],
                    exudyn_tight_tol=cfg["t3_tight"], vs_exudyn_dopri5_tight=error(model, tight["q"], qref),
                    exudyn_tight_wall_s=tight_wall,
                    model_build_s=build, model_build_walls_s=build_all)
    extra[f"T3_{N}_reference"] = ref_info
    say(f"{scene}: reference {time.perf_counter() - t0:.1f} s; Exudyn DOPRI5 at {cfg['t3_tight']:g} differs by "
        f"{ref_info['vs_exudyn_dopri5_tight']:.1e}; ExudynModel(mbs) {build * 1e3:.1f} ms (walls {build_all})")
    jobs = [(("Exudyn DOPRI5 RotVecLG", f"tol={tol:g}"), lambda tol=tol: native_dopri5(make, T, tol))
            for tol in cfg["tols_t3_exu"]]
    jobs += [((f"bridge {m} {g} {ch}", f"tol={tol:g}"),
              lambda m=m, g=g, ch=ch, tol=tol: bridge_run(model, T, m, g, ch, rtol=tol, atol=tol))
             for m in ("dopri5", "dop853") for g in GROUPS for ch in CHARTS for tol in cfg["tols_t3"][m]]
    res = rounds(jobs, cfg["reps"], scene)
    for key, _ in jobs:
        (fam, setting), (r, wall, walls) = key, res[key]
        if fam.startswith("Exudyn"):
            e = error(model, r["q"], qref)
            rows.append(dict(scene=scene, family=fam, setting=setting, error=e, wall_s=wall, walls_s=walls,
                             n_f=None, n_steps=r["n_steps"], n_rejected=r["n_rejected"]))
            say(f"  {fam:28s} {setting:14s} error {e:9.2e}  wall {wall:8.4f} s  steps {r['n_steps']} "
                f"(+{r['n_rejected']} rejected)")
            continue
        e = error(model, r.q[-1], qref) if r.success else float("nan")
        rows.append(dict(scene=scene, family=fam, setting=setting, error=e, wall_s=wall, walls_s=walls,
                         wall_incl_model_s=wall + build, n_f=r.stats["n_f"], n_steps=r.stats["n_steps"],
                         n_rejected=r.stats["n_rejected"], setup_s=wall - r.stats["wall_s"],
                         us_per_f=wall / r.stats["n_f"] * 1e6))
        say(f"  {fam:28s} {setting:14s} error {e:9.2e}  wall {wall:8.4f} s  n_f {r.stats['n_f']:5d}  "
            f"steps {r.stats['n_steps']:4d}  setup {rows[-1]['setup_s'] * 1e3:5.1f} ms")
    return build


def chain(cfg, rows):
    T, scene = 1.0, "chain of 20"
    twin = scenes.chain(20)
    qref = simulate(twin, (0, T), method="dop853", rtol=1e-13, atol=1e-13, t_eval=[T], progress=False).q[-1]
    twin_rv, qref_rv = scenes.chain(20, param="rotvec"), _to_rotvec_ref(twin, qref)
    model, build, _ = model_build(lambda: em.chain(20), 1)
    jobs, info = [], {}
    for rv in (False, True):
        fam = "Exudyn GA " + ("RotVecLG" if rv else "EP")
        make = (lambda: em.chain(20, em.ROTVEC)) if rv else (lambda: em.chain(20))
        for n in cfg["ga_chain"]:
            jobs.append(((fam, f"h={T / n:.2e}"), lambda make=make, n=n, rv=rv: native_ga(make, T, n, rotvec=rv)))
            info[jobs[-1][0]] = rv
    for m in ("dopri5", "dop853"):
        for g in GROUPS:
            for ch in CHARTS:
                for tol in (1e-5, 1e-7):
                    jobs.append(((f"bridge {m} {g} {ch}", f"tol={tol:g}"),
                                 lambda m=m, g=g, ch=ch, tol=tol: bridge_run(model, T, m, g, ch, rtol=tol, atol=tol)))
    res = rounds(jobs, cfg["reps"], scene)
    for key, _ in jobs:
        (fam, setting), (r, wall, walls) = key, res[key]
        if key in info:
            rv = info[key]
            e = error(twin_rv if rv else twin, r["q"], qref_rv if rv else qref)
            rows.append(dict(scene=scene, family=fam, setting=setting, error=e, wall_s=wall, walls_s=walls,
                             n_f=None, n_steps=r["n_steps"]))
        else:
            e = error(twin, r.q[-1], qref) if r.success else float("nan")
            rows.append(dict(scene=scene, family=fam, setting=setting, error=e, wall_s=wall, walls_s=walls,
                             wall_incl_model_s=wall + build, n_f=r.stats["n_f"], n_steps=r.stats["n_steps"]))
        say(f"  {fam:28s} {setting:14s} error {e:9.2e}  wall {wall:8.3f} s")


# ----------------------------------------------------------------------------- main
def config(quick):
    if quick:
        return dict(reps=1, n_loop=2000, t1_tol=1e-7, ga_ep=[8000, 32000], ga_rv=[8000, 32000],
                    tols_t2={"dopri5": [1e-6], "dop853": [1e-5, 1e-7]}, dts_t2=[], genalpha_dts_t2=[],
                    tols_t3_exu=[1e-5, 1e-7], tols_t3={"dopri5": [1e-6, 1e-8], "dop853": [1e-6, 1e-8]},
                    Ns=[8, 100], t3_tight=1e-9, ga_chain=[250])
    return dict(reps=3, n_loop=20000, t1_tol=1e-9, ga_ep=[2000, 8000, 32000, 128000, 512000],
                ga_rv=[2000, 8000, 32000, 128000, 512000, 1024000],
                tols_t2={"dopri5": [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
                         "dop853": [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]},
                dts_t2=[1e-3, 5e-4, 2.5e-4], genalpha_dts_t2=[2.5e-4],
                tols_t3_exu=[1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
                tols_t3={"dopri5": [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11],
                         "dop853": [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]},
                Ns=[8, 100], t3_tight=1e-12, ga_chain=[250, 1000, 4000])


def warm_up():
    """Load the compiled kernels (numba cache) and the integrators once before any timing."""
    for make in (lambda: em.heavy_top(em.EP), lambda: tumbling(2)):
        m = ExudynModel(make()[1])
        for method in ("dopri5", "dop853"):
            for g in GROUPS:
                for ch in CHARTS:
                    bridge_run(m, 0.01, method, g, ch, rtol=1e-6, atol=1e-6)
        bridge_run(m, 0.01, "rkmk4", "SO3xR3", "exp", dt=1e-3)
    bridge_run(ExudynModel(em.heavy_top(em.EP)[1]), 0.002, "genalpha", "SO3xR3", "exp", dt=1e-3)


def verdicts(rows, extra, fcost, builds, Ns):
    """The targets: list of dicts (target, measured, value, threshold, met)."""
    out = []
    for key in ("heavy top EP", "heavy top RotVecLG"):
        c = fcost[key]
        out.append(dict(id="T1", target=f"adapter glue per f ≤ 2x Exudyn's own evaluation cost ({key})",
                        measured=f"glue {c['glue_us']:.1f} µs, inside Exudyn {c['inside_us']:.1f} µs per f "
                                 f"(f {c['us_per_f']:.1f} µs); glue/inside = {c['glue_over_inside']:.2f}",
                        value=c["glue_over_inside"], threshold=TARGETS["T1"], met=c["glue_over_inside"] <= TARGETS["T1"]))
    t2rows = [r for r in rows if r["scene"] == "T2 heavy top"]
    extra["at_error"] = {}
    for target, tid in ((1e-6, "T2_1e-6"), (1e-8, "T2_1e-8")):
        fams = at_error([r for r in t2rows if not r["family"].startswith(("bridge rkmk4", "bridge genalpha"))], target)
        extra["at_error"][f"T2 {target:g}"] = {f: dict(wall_s=w, how=h) for f, (w, h) in fams.items()}
        nb, bb = best(fams, "Exudyn"), best(fams, "bridge")
        if nb and bb:
            ratio = nb["wall_s"] / bb["wall_s"]
            out.append(dict(id="T2", target=f"heavy top: error {target:g} ≥ {TARGETS[tid]:g}x faster than Exudyn's best",
                            measured=f"{bb['family']} {bb['wall_s']:.4f} s ({bb['how']}); "
                                     f"{nb['family']} {nb['wall_s']:.3f} s ({nb['how']}); Exudyn/bridge = {ratio:.1f}x "
                                     f"(incl. ExudynModel(mbs): {nb['wall_s'] / (bb['wall_s'] + builds['T2']):.1f}x)",
                            value=ratio, threshold=TARGETS[tid], met=ratio >= TARGETS[tid],
                            bridge=bb, native=nb, ratio_incl_model=nb["wall_s"] / (bb["wall_s"] + builds["T2"])))
        else:
            out.append(dict(id="T2", target=f"heavy top: error {target:g} ≥ {TARGETS[tid]:g}x faster",
                            measured=f"not reached (bridge {bb}, Exudyn {nb})", value=None,
                            threshold=TARGETS[tid], met=None))
    for N in Ns:
        scene = f"T3 {N} free RotVecLG"
        t3rows = [r for r in rows if r["scene"] == scene]
        for target, tid in ((1e-6, "T3_1e-6"), (1e-8, "T3_1e-8")):
            fams = at_error(t3rows, target)
            extra["at_error"][f"{scene} {target:g}"] = {f: dict(wall_s=w, how=h) for f, (w, h) in fams.items()}
            nb, bb = best(fams, "Exudyn"), best(fams, "bridge")
            per = {m: best(fams, f"bridge {m}") for m in ("dopri5", "dop853")}
            if nb and bb:
                ratio = bb["wall_s"] / nb["wall_s"]
                incl = (bb["wall_s"] + builds[N]) / nb["wall_s"]
                permsg = "; ".join(f"best {m} {v['wall_s'] / nb['wall_s']:.2f}x" for m, v in per.items() if v)
                out.append(dict(id="T3", target=f"{N} free RotVecLG bodies: bridge wall at error {target:g} "
                                                 f"≤ {TARGETS[tid]:g}x Exudyn DOPRI5",
                                measured=f"{bb['family']} {bb['wall_s'] * 1e3:.2f} ms ({bb['how']}); "
                                         f"Exudyn DOPRI5 {nb['wall_s'] * 1e3:.2f} ms ({nb['how']}); bridge/Exudyn = "
                                         f"{ratio:.2f}x ({permsg}; incl. ExudynModel(mbs) "
                                         f"{builds[N] * 1e3:.0f} ms: {incl:.2f}x)",
                                value=ratio, threshold=TARGETS[tid], met=ratio <= TARGETS[tid], bridge=bb, native=nb,
                                ratio_incl_model=incl, met_incl_model=incl <= TARGETS[tid],
                                per_method={m: v for m, v in per.items()}))
            else:
                out.append(dict(id="T3", target=f"{N} free RotVecLG bodies, error {target:g}",
                                measured=f"not reached (bridge {bb}, Exudyn {nb})", value=None,
                                threshold=TARGETS[tid], met=None))
    extra["breakdown"] = breakdown(rows, fcost, Ns)
    c = fcost["100 free EP"]
    out.append(dict(id="T4", target="100 free EP bodies: one f ≤ 500 µs",
                    measured=f"{c['us_per_f']:.1f} µs per f (inside Exudyn {c['inside_us']:.1f} µs)",
                    value=c["us_per_f"], threshold=TARGETS["T4"], met=c["us_per_f"] <= TARGETS["T4"]))
    return out


def breakdown(rows, fcost, Ns):
    """Where the time goes at error 1e-6 and 1e-8: per scene, the best bridge family's first run at
    or below the error (wall, setup before its first step, n_f x f from the f loop, the rest:
    the integrator's own work) and Exudyn's first run at or below it."""
    out = []
    scenes_ = [("T2 heavy top", "heavy top EP")] + [(f"T3 {N} free RotVecLG", f"{N} free RotVecLG") for N in Ns]
    for scene, fkey in scenes_:
        rs = [r for r in rows if r["scene"] == scene and not r["family"].startswith(("bridge rkmk4", "bridge genalpha"))]
        for target in (1e-6, 1e-8):
            fams = at_error(rs, target)
            item = dict(scene=scene, error=target)
            for side in ("bridge", "Exudyn"):
                b = best(fams, side)
                if b is None:
                    continue
                ok = sorted((r for r in rs if r["family"] == b["family"] and r["error"] <= target),
                            key=lambda r: r["wall_s"])
                if not ok:
                    continue
                r = ok[0]
                d = dict(family=r["family"], setting=r["setting"], error=r["error"], wall_s=r["wall_s"],
                         n_steps=r.get("n_steps"), n_rejected=r.get("n_rejected"))
                if side == "bridge" and fkey in fcost:
                    f_s = r["n_f"] * fcost[fkey]["us_per_f"] * 1e-6
                    d.update(n_f=r["n_f"], setup_s=r.get("setup_s"), f_s=f_s,
                             exudyn_s=r["n_f"] * fcost[fkey]["inside_us"] * 1e-6,
                             rest_s=r["wall_s"] - f_s - (r.get("setup_s") or 0.0))
                item[side] = d
            out.append(item)
    return out


def write(out, data):
    out.mkdir(parents=True, exist_ok=True)
    (out / "exudyn_work_precision.json").write_text(json.dumps(data, indent=1, default=str))
    m = data["meta"]
    yes = {True: "**met**", False: "**missed**", None: "n/a"}
    lines = ["# Exudyn models: the bridge against Exudyn's own solvers", "",
             f"`{m['command']}` — {m['date']}, {m['total_wall_s']:.0f} s; Python {m['python']}, Exudyn {m['exudyn']}, "
             f"numpy {m['numpy']}; {m['machine']}. Wall times: best of {m['reps']} repetitions in one process. "
             + (f"Code: git {m['git']['head']}" + (f" with {', '.join(m['git']['modified'])} modified"
                                                   if m['git']['modified'] else "") + "." if m.get("git") else ""), "",
             "## Targets", "", "| target | measured | met? |", "|---|---|---|"]
    for v in data["verdicts"]:
        extra = ""
        if v["id"] == "T3" and v.get("met_incl_model") is not None:
            extra = f" (incl. ExudynModel(mbs): {yes[v['met_incl_model']]})"
        lines.append(f"| {v['id']}: {v['target']} | {v['measured']} | {yes[v['met']]}{extra} |")
    lines += ["", "Error: largest body rotation angle + largest position error at the end time. Ratios interpolate "
              "each family's wall time log-log at the error (lgt_bridge.bench.wall_at_error); the best family of "
              "each side counts. T3 compares the integration runs (Exudyn's SolveDynamic against simulate); the "
              "bracket adds the bridge's one-off ExudynModel(mbs) construction.", "",
              "## f cost (T1, T4)", "",
              "| model | f µs | inside Exudyn µs | glue µs | glue/inside | Exudyn calls per f | proxied f µs (inside) |",
              "|---|---:|---:|---:|---:|---:|---:|"]
    for k, c in data["f_costs"].items():
        lines.append(f"| {k} | {c['us_per_f']:.1f} | {c['inside_us']:.1f} | {c['glue_us']:.1f} | "
                     f"{c['glue_over_inside']:.2f} | {c['exudyn_calls_per_f']} | {c['proxied_us_per_f']:.1f} "
                     f"({c['proxied_inside_us']:.1f}) |")
    lines += ["", "f µs: a loop of f calls at the initial state; inside = the Exudyn calls of one f replayed with "
              "the same arguments (no bridge code between them); the two alternate in blocks and each is its "
              "fastest block; glue = f - inside. The proxied loop times each call through a Python proxy, whose "
              "own cost inflates both of its numbers.", ""]
    for k, r in data["extra"].get("T1_runs", {}).items():
        lines.append(f"- Whole run on the {k} ({r['run']}): {r['n_f']} f in {r['wall_s'] * 1e3:.1f} ms = "
                     f"{r['us_per_f']:.1f} µs per f, of which inside Exudyn (proxied) {r['proxied_inside_us_per_f']:.1f} "
                     f"µs; setup before the first step {r['setup_s'] * 1e3:.1f} ms.")
    lines += ["", "## Where the time goes", "",
              "The best family's cheapest run at or below each error. Bridge: setup = simulate's work before "
              "the first step (input and mass-matrix checks, stepper), f = n_f x the f loop's cost (of which "
              "Exudyn's calls), rest = everything else: the integrator's own work (stages, τ, error control, "
              "constraint projection) and the compiled kernels' pack built at the first f.", "",
              "| scene | error | bridge run | wall ms | setup ms | n_f | steps | f ms (Exudyn) | rest ms | "
              "Exudyn run | wall ms | steps (+rejected) |", "|---|---:|---|---:|---:|---:|---:|---:|---:|---|---:|---:|"]
    for it in data["extra"].get("breakdown", []):
        b, n = it.get("bridge"), it.get("Exudyn")
        if not b:
            continue
        bs = (f"{b['family']} {b['setting']} | {b['wall_s'] * 1e3:.1f} | {(b.get('setup_s') or 0) * 1e3:.1f} | "
              f"{b.get('n_f', '')} | {b['n_steps']} | {b.get('f_s', 0) * 1e3:.1f} ({b.get('exudyn_s', 0) * 1e3:.1f}) | "
              f"{b.get('rest_s', 0) * 1e3:.1f}")
        ns = (f"{n['family']} {n['setting']} | {n['wall_s'] * 1e3:.1f} | {n['n_steps']}"
              + (f" (+{n['n_rejected']})" if n.get("n_rejected") is not None else "")) if n else " | | "
        lines.append(f"| {it['scene']} | {it['error']:g} | {bs} | {ns} |")
    lines += ["", "## References", ""]
    for k, v in data["extra"].items():
        if k.endswith("reference"):
            lines.append(f"- {k}: " + ", ".join(f"{a} = {b:.3g}" if isinstance(b, float) else f"{a} = {b}"
                                                 for a, b in v.items() if a != "model_build_walls_s"))
    lines += ["", "## Wall time at error", "", "| scene, error | family | wall s | how |", "|---|---|---:|---|"]
    for k, fams in data["extra"].get("at_error", {}).items():
        for f, v in sorted(fams.items(), key=lambda kv: kv[1]["wall_s"]):
            lines.append(f"| {k} | {f} | {v['wall_s']:.4g} | {v['how']} |")
    lines += ["", "## Runs", "", "| scene | family | setting | error | wall s | f evals | steps | µs per f |",
              "|---|---|---|---:|---:|---:|---:|---:|"]
    for r in data["rows"]:
        upf = f"{r['us_per_f']:.1f}" if r.get("us_per_f") else ""
        steps = r.get("n_steps") or ""
        if r.get("n_rejected"):
            steps = f"{steps} (+{r['n_rejected']})"
        lines.append(f"| {r['scene']} | {r['family']} | {r['setting']} | {r['error']:.2e} | {r['wall_s']:.4f} | "
                     f"{r['n_f'] or ''} | {steps} | {upf} |")
    (out / "exudyn_work_precision.md").write_text("\n".join(lines) + "\n")


def _git_state():
    """HEAD of the repository and whether its tracked files differ from it (None outside git)."""
    import subprocess
    root = Path(__file__).resolve().parents[1]
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True, text=True,
                              check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                               capture_output=True, text=True, check=True).stdout.split("\n")
        return dict(head=head, modified=[ln[3:] for ln in dirty if ln.strip()])
    except (OSError, subprocess.CalledProcessError):
        return None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--quick", action="store_true", help="fewer runs, 1 repetition (smoke test, < 60 s)")
    ap.add_argument("--chain", action="store_true", help="also the 20-link chain (slow, not a target)")
    a = ap.parse_args(argv)
    cfg = config(a.quick)
    t_start = time.perf_counter()
    warm_up()
    rows, extra = [], {}
    fcost = t1_and_t4(cfg)
    t1_runs(cfg, extra)
    builds = {"T2": t2(cfg, rows, extra)}
    for N in cfg["Ns"]:
        builds[N] = t3(cfg, rows, extra, N)
    if a.chain:
        chain(cfg, rows)
    v = verdicts(rows, extra, fcost, builds, cfg["Ns"])
    for x in v:
        say(f"{x['id']}: {x['target']}: {x['measured']} -> {'met' if x['met'] else 'MISSED' if x['met'] is False else 'n/a'}")
    import numba
    cmd = "python benchmarks/bench_exudyn.py" + (" --quick" if a.quick else "") + (" --chain" if a.chain else "")
    meta = dict(command=cmd, date=time.strftime("%Y-%m-%d %H:%M"), total_wall_s=time.perf_counter() - t_start,
                git=_git_state(),
                python=platform.python_version(), exudyn=exu.__version__, numpy=np.__version__,
                numba=numba.__version__, machine=f"{platform.machine()}, {__import__('os').cpu_count()} cores",
                reps=cfg["reps"], config=cfg)
    write(Path(a.out), dict(meta=meta, verdicts=v, f_costs=fcost, extra=extra, rows=rows))
    say(f"total {meta['total_wall_s']:.0f} s")


if __name__ == "__main__":
    main()
