"""Work-precision sweeps: ``lgt-bridge bench SCENE``.

Every combination of method x group x chart x setting (tolerance for adaptive
methods, step for fixed-step ones) runs on the scene; each run's end state is
compared with a tight reference (dopri5 on SE(3)/exp at rtol = atol = 1e-12,
stated in the report). Runs execute in parallel worker processes (or on a Dask
cluster) for their numbers; their wall times are then taken again one run at a time
in this process, best of ``repeat`` (see :func:`sweep`), so that no run looks faster
or slower because of what ran beside it. Output: a JSON of every run, a Markdown table
and (with matplotlib) PNG plots. Every option is checked
(:func:`check_options`) before the reference run; a run that fails (an exception in the
run or in its worker) becomes a row with ``success = False`` and its error, and a worker
process that dies (a crash inside an engine, the memory exhausted) costs only the run it was
running: the runs its pool could not finish are run again, each in a process of its own.

A scene is a built-in name (see SCENES), ``PREFIX:ARG`` for a family of scenes an adapter
registers (:class:`SceneFamily`, e.g. ``pinocchio_robot:solo12``), or
``path/to/file.py:function`` where the function returns ``(model, t_end)``. A scene may
declare scenarios (variants such as free fall or PD control, ``--scenario NAME``); the
first is its default, and a scenario given to a scene without any is an error.
"""
import importlib.util
import json
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from . import scenes as _scenes
from .errors import InputError
from .integrators import METHODS
from .progress import Progress
from .groups import quaternion as _q
from .groups import so3
from .plugins import adapters
from .simulate import simulate

@dataclass
class BenchScene:
    """A bench scene: ``make() -> model``, the end time, and the engine's own solvers
    as baselines: ``natives[name] = (kind, settings, run)`` with kind "dt"/"tol"/"n"
    and ``run(setting) -> dict(q=final q in the model's coordinates, n_f, n_steps)``
    (n_f None where the solver does not expose its evaluations)."""

    make: Callable
    t_end: float
    natives: dict = field(default_factory=dict)
    about: str = ""
    #: scenario name -> the BenchScene of that variant (``--scenario NAME``), the first the
    #: default; empty: the scene has no scenarios
    scenarios: dict = field(default_factory=dict)


@dataclass
class SceneFamily:
    """Scenes named ``PREFIX:ARG``, registered under PREFIX: ``resolve(arg) -> BenchScene``
    (raising InputError for an ARG it does not know, cheaply: nothing is built). ``arg``
    names ARG in the help (e.g. "NAME"); ``scenarios``: scenario name -> one-line
    description, checked before ``resolve`` is called."""

    resolve: Callable
    about: str = ""
    arg: str = "ARG"
    scenarios: dict = field(default_factory=dict)


SCENES = {
    "heavy_top": BenchScene(lambda: _scenes.heavy_top(True), 0.1, about="heavy top, spherical joint"),
    "heavy_top_pivot": BenchScene(lambda: _scenes.heavy_top(False), 0.1, about="heavy top, frame at the pivot"),
    "free_body": BenchScene(lambda: _scenes.free_body((1.0, 2.0, 3.0), (0.01, 2.0, 0.01)), 10.0,
                            about="torque-free asymmetric body (Dzhanibekov flip)"),
    "chain": BenchScene(lambda: _scenes.chain(5), 1.0, about="5 links, spherical joints"),
    "top_and_free_bodies": BenchScene(lambda: _scenes.top_and_free_bodies(3), 0.5,
                                      about="jointed top + 3 free bodies"),
}
FIXED = ("euler", "rkmk2", "rkmk4", "genalpha")
REFERENCE = dict(method="dopri5", group="SE3", chart="exp", rtol=1e-12, atol=1e-12)


def all_scenes():
    """Built-in scenes plus those the installed adapters register (``bench_scenes()``
    on the plugin: the engines' example scenes with their native solvers)."""
    out = dict(SCENES)
    for name, ep in sorted(adapters().items()):
        try:
            plugin = ep.load()
        except ImportError:
            continue
        if hasattr(plugin, "bench_scenes"):
            try:
                out.update(plugin.bench_scenes())
            except ImportError:                 # the engine itself is not installed
                continue
    return out


def get_scene(spec, scenario=None):
    """The BenchScene of a name, of ``PREFIX:ARG`` (a :class:`SceneFamily`) or of
    'file.py:function' (which returns (model, t_end)); with ``scenario``, that variant of
    it (InputError when the scene has no scenarios or not this one; for a family checked
    before ARG is resolved). Without, a scene with scenarios gives its first (default)."""
    sc = _base_scene(spec, scenario)
    _check_scenario(spec, scenario, sc.scenarios)
    if sc.scenarios:
        return sc.scenarios[scenario if scenario is not None else next(iter(sc.scenarios))]
    return sc


def scenarios_of(spec):
    """The scenario names a scene declares (first: the default); () for none."""
    return tuple(_base_scene(spec).scenarios)


def _base_scene(spec, scenario=None):
    scenes = all_scenes()
    sc = scenes.get(spec)
    if isinstance(sc, SceneFamily):
        raise InputError(f"bench: {spec!r} is a family of scenes; name one as {spec}:{sc.arg} "
                         "(lgt-bridge bench --help describes it).")
    if sc is None and ":" in spec:
        prefix, arg = spec.split(":", 1)
        fam = scenes.get(prefix)
        if isinstance(fam, SceneFamily):
            _check_scenario(spec, scenario, fam.scenarios)
            sc = fam.resolve(arg)
        else:
            path, fn = spec.rsplit(":", 1)
            if Path(path).is_file():
                sc = BenchScene(lambda: _user_scene(path, fn, spec), None)
    if sc is None:
        names = [k + (f":{v.arg}" if isinstance(v, SceneFamily) else "") for k, v in sorted(scenes.items())]
        raise InputError(f"bench: unknown scene {spec!r}; use one of {names} or "
                         "'path/to/file.py:function' returning (model, t_end).")
    return sc


def _check_scenario(spec, scenario, scenarios):
    if scenario is None:
        return
    if not scenarios:
        raise InputError(f"bench --scenario {scenario}: scene {spec!r} has no scenarios; leave out "
                         "--scenario (lgt-bridge bench --help lists the scenes that have them).")
    if scenario not in scenarios:
        raise InputError(f"bench --scenario: unknown scenario {scenario!r} for scene {spec!r}; use one of "
                         f"{', '.join(scenarios)}.")


def _user_scene(path, fn, spec):
    s = importlib.util.spec_from_file_location("lgt_bench_user_scene", path)
    mod = importlib.util.module_from_spec(s)
    s.loader.exec_module(mod)
    if not hasattr(mod, fn):
        raise InputError(f"bench: {path} has no function {fn!r}; it must return (model, t_end).")
    out = getattr(mod, fn)()
    if not (isinstance(out, tuple) and len(out) == 2):
        raise InputError(f"bench: {spec} must return (model, t_end), got {type(out).__name__}.")
    return out


def load_scene(spec, scenario=None):
    """(model, t_end) from a scene name or 'file.py:function' (and a scenario of it)."""
    sc = get_scene(spec, scenario)
    out = sc.make()
    return out if sc.t_end is None else (out, sc.t_end)


def report_name(spec, scenario=None):
    """The stem of a sweep's files: the scene name, the file's stem for 'file.py:function',
    PREFIX_ARG for a family member; then _SCENARIO when one is given."""
    name = spec
    if ":" in spec:
        prefix, arg = spec.split(":", 1)
        fam = all_scenes().get(prefix)
        name = (f"{prefix}_{arg}" if isinstance(fam, SceneFamily) else Path(spec.split(":")[0]).stem)
    return name + (f"_{scenario}" if scenario else "")


def pose_error(model, q, q_ref):
    """Largest body rotation angle + largest position error (+ vector coordinates)."""
    return sum(pose_errors(model, q, q_ref))


def pose_errors(model, q, q_ref):
    """(largest body rotation angle, largest position / vector-coordinate error)."""
    e_rot = e_pos = 0.0
    for b in model.layout.bodies:
        if b.rotation_only:
            p = b.param._to_quat(q[list(b.rot)][None])
            pr = b.param._to_quat(q_ref[list(b.rot)][None])
            ang = float(np.linalg.norm(_q._to_rotvec(_q._mul(_q._conj(pr), p))[0]))
        else:
            R = b.param.alpha(q[[*b.pos, *b.rot]])[:3, :3]
            Rr = b.param.alpha(q_ref[[*b.pos, *b.rot]])[:3, :3]
            ang = float(np.linalg.norm(so3.log(R.T @ Rr)))
            e_pos = max(e_pos, float(np.abs(q[list(b.pos)] - q_ref[list(b.pos)]).max()))
        e_rot = max(e_rot, ang)
    vq = list(model.layout.vector_q)
    if vq:
        e_pos = max(e_pos, float(np.abs(q[vq] - q_ref[vq]).max()))
    for c, s in model.layout.circle_q:               # planar rotations: the angle between them
        e_rot = max(e_rot, abs(float(np.arctan2(q[s] * q_ref[c] - q[c] * q_ref[s], q[c] * q_ref[c] + q[s] * q_ref[s]))))
    return e_rot, e_pos


_SCIPY = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")


def check_options(spec, methods, groups, charts, tols, dts, scenario=None):
    """InputError on the first bad option, before anything runs (the scene and its
    scenario are looked up, not built)."""
    if not methods:
        raise InputError("bench: --methods is empty.")
    for m in methods:
        if not (m in METHODS or (m.startswith("scipy:") and m[6:] in _SCIPY)):
            raise InputError(f"bench: unknown method {m!r}; use {', '.join(METHODS)} or scipy:<Name> "
                             f"with Name in {', '.join(_SCIPY)}.")
    for opt, vals, ok in (("--groups", groups, ("SE3", "SO3xR3", "auto")), ("--charts", charts, ("exp", "cay", "auto"))):
        if not vals:
            raise InputError(f"bench: {opt} is empty.")
        for v in vals:
            if v not in ok:
                raise InputError(f"bench {opt}: unknown value {v!r}; use {', '.join(ok)}.")
    for opt, vals, needed in (("--tols", tols, any(m not in FIXED for m in methods)),
                              ("--dts", dts, any(m in FIXED for m in methods))):
        if needed and not vals:
            raise InputError(f"bench: {opt} is empty but the methods need it.")
        for v in vals:
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"bench {opt}: {v:g} must be a positive finite number.")
    get_scene(spec, scenario)


def _failed_row(method, group, chart, setting, exc, wall=0.0):
    return dict(method=method, group=group, chart=chart, setting=("dt" if method in FIXED else "tol"),
                value=setting, success=False, message=f"{type(exc).__name__}: {' '.join(str(exc).split())}",
                wall_s=wall, n_f=None, n_steps=None, n_rejected=None)


def _job_failed(job, exc):
    if job[0] is _one_native:
        return _failed_row(job[2], "native", "engine", job[3], exc)
    return _failed_row(*job[2:6], exc)


def _one(spec, method, group, chart, setting, q_ref, V_ref, scenario=None):
    t0 = time.perf_counter()
    try:
        return _one_run(spec, method, group, chart, setting, q_ref, V_ref, scenario)
    except Exception as exc:            # a failing run is a row of the sweep, not its end
        return _failed_row(method, group, chart, setting, exc, time.perf_counter() - t0)


def _one_run(spec, method, group, chart, setting, q_ref, V_ref, scenario=None):
    model, T = load_scene(spec, scenario)
    kw = dict(dt=setting) if method in FIXED else dict(rtol=setting, atol=setting)
    t0 = time.perf_counter()
    r = simulate(model, (0.0, T), method=method, group=group, chart=chart, progress=False, **kw)
    wall = time.perf_counter() - t0
    row = dict(method=method, group=group, chart=chart, setting=("dt" if method in FIXED else "tol"),
               value=setting, success=r.success, message=r.message, wall_s=wall,
               n_f=r.stats["n_f"], n_steps=r.stats["n_steps"], n_rejected=r.stats["n_rejected"])
    if "auto" in r.stats:
        row["auto"] = sorted({(c["group"], c["chart"]) for c in r.stats["auto"]})
    if r.success:
        row["pose_error"] = pose_error(model, r.q[-1], q_ref)
        row["velocity_error"] = float(np.abs(r.V[-1] - V_ref).max())
        row["constraint_residual"] = float(np.abs(model.constraints(r.q[-1])).max()) if model.n_constraints else 0.0
    if hasattr(model, "energy") and len(r.t):
        idx = np.unique(np.linspace(0, len(r.t) - 1, min(len(r.t), 60)).astype(int))
        E0 = model.energy(r.q[0], r.V[0])
        drift = [float(abs(model.energy(r.q[i], r.V[i]) - E0) / max(abs(E0), 1e-300)) for i in idx]
        row["energy_t"], row["energy_drift_t"] = r.t[idx].tolist(), drift
        if r.success:
            row["energy_drift"] = drift[-1]
    return row


def _one_native(spec, name, setting, q_ref, scenario=None):
    model, T = load_scene(spec, scenario)
    kind, _, run = get_scene(spec, scenario).natives[name]
    t0 = time.perf_counter()
    try:
        out = run(setting)
        ok = bool(np.isfinite(out["q"]).all())
        msg = "reached the end of t_span" if ok else "diverged: the final state is not finite"
    except Exception as exc:            # an engine solver failing is a result, not a crash
        out, ok, msg = dict(q=None, n_f=None, n_steps=None), False, f"{type(exc).__name__}: {exc}"
    wall = time.perf_counter() - t0
    row = dict(method=name, group="native", chart="engine", setting=kind, value=setting, success=ok,
               message=msg, wall_s=wall, n_f=out.get("n_f"), n_steps=out.get("n_steps"), n_rejected=None)
    if ok:
        row["pose_error"] = pose_error(model, out["q"], q_ref)
        row["velocity_error"] = None
        row["constraint_residual"] = (float(np.abs(model.constraints(out["q"])).max())
                                      if model.n_constraints else 0.0)
    return row


def _executor(workers, scheduler):
    """(submit, as_completed, close) for local processes or a Dask cluster.
    scheduler: None (local processes), "local" (a Dask LocalCluster started here),
    an address "tcp://host:port", or a ``distributed.Client``."""
    if scheduler is None:
        ex = ProcessPoolExecutor(max_workers=workers)
        return ex.submit, as_completed, ex.shutdown
    try:
        from dask import distributed
    except ImportError:
        raise InputError("bench: a Dask scheduler needs dask.distributed: "
                         "pip install 'lgt-bridge[dask]'.") from None
    if isinstance(scheduler, distributed.Client):
        return scheduler.submit, distributed.as_completed, lambda: None
    if scheduler == "local":
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, dashboard_address=None)
        client = distributed.Client(cluster)

        def close():
            client.close()
            cluster.close()
    else:
        client = distributed.Client(scheduler)
        close = client.close
    return (lambda fn, *a: client.submit(fn, *a, pure=False)), distributed.as_completed, close


def sweep(spec, methods, groups, charts, tols, dts, workers=None, progress=None, scheduler=None, auto=True,
          natives=True, repeat=3, scenario=None):
    """Run the sweep; returns (reference dict, rows). ``scenario``: a variant the scene
    declares (None: its default; see :func:`get_scene`). With ``auto`` every method also
    runs with group = chart = "auto"; with ``natives`` the scene's engine solvers run
    too (group "native"). ``scheduler``: see :func:`_executor`. ``progress``: bars for
    the reference run, the sweep and the timing pass, as in :func:`~lgt_bridge.simulate`
    (None: only when long, on a terminal, outside CI).

    Timing (``repeat`` ≥ 1, default 3): the runs first execute as the sweep says (in
    parallel, for their errors and counts); then every successful run is run again alone,
    one at a time in this process, and its ``wall_s`` is the best of ``repeat`` such
    runs (a serial sweep, ``workers=1`` without a scheduler, counts its own pass as the
    first of them). Each row records ``wall_repeats`` (how many lone runs its ``wall_s``
    is the best of; 0 for a failed run, whose ``wall_s`` is the time to failure),
    ``wall_samples_s`` and ``wall_pass_s`` (its time in the first, possibly parallel,
    pass). ``repeat = 0`` keeps the first pass's times: with parallel workers they are
    distorted by what ran beside them, and the report says so. ``reference["timing"]``
    describes the method; the report states it."""
    check_options(spec, methods, groups, charts, tols, dts, scenario)
    if workers is not None and workers < 1:
        raise InputError(f"bench: workers = {workers} must be at least 1.")
    if not (isinstance(repeat, (int, np.integer)) and repeat >= 0):
        raise InputError(f"bench: repeat = {repeat!r} must be a whole number ≥ 0 (0: keep the first pass's "
                         "wall times).")
    model, T = load_scene(spec, scenario)
    t0 = time.perf_counter()
    ref = simulate(model, (0.0, T), t_eval=[0.0, T], progress=progress, **REFERENCE)
    if not ref.success:
        raise InputError(f"bench: the reference run failed ({ref.message}).")
    reference = dict(REFERENCE, n_steps=ref.stats["n_steps"], wall_s=time.perf_counter() - t0, t_end=T)
    scenarios = scenarios_of(spec)
    if scenarios:
        reference["scenario"] = scenario if scenario is not None else scenarios[0]
    combos = [(g, c) for g in groups for c in charts] + ([("auto", "auto")] if auto else [])
    jobs = [(_one, spec, m, g, c, s, ref.q[-1], ref.V[-1], scenario) for m in methods for g, c in combos
            for s in (dts if m in FIXED else tols)]
    if natives:
        jobs += [(_one_native, spec, name, s, ref.q[-1], scenario) for name, (_, settings, _) in
                 get_scene(spec, scenario).natives.items() for s in settings]
    rows = [None] * len(jobs)
    done = []
    bar = Progress(progress, len(jobs), lambda: (len(done), f"{sum(not r['success'] for r in done)} failed"),
                   desc="sweep", unit=" runs", value_fmt="d")
    workers = workers or os.cpu_count() or 1
    serial = workers == 1 and scheduler is None
    if serial:
        for i, j in enumerate(jobs):
            rows[i] = _run_job(j)
            done.append(rows[i])
            bar.step()
    else:
        submit, completed, close = _executor(workers, scheduler)
        broken = []
        try:
            futs = {submit(*j): i for i, j in enumerate(jobs)}
            for f in completed(list(futs)):
                i = futs[f]
                try:
                    rows[i] = f.result()
                except BrokenProcessPool:       # a worker died: the pool fails every unfinished job
                    broken.append(i)
                    continue
                except Exception as exc:        # the worker itself failed: still a row
                    rows[i] = _job_failed(jobs[i], exc)
                done.append(rows[i])
                bar.step()
        finally:
            close()
        for i in sorted(broken):               # each again, alone in a process of its own
            rows[i] = _run_isolated(jobs[i])
            done.append(rows[i])
            bar.step()
    bar.close()
    reference["timing"] = _retime(jobs, rows, repeat, serial, workers, scheduler, progress)
    rows.sort(key=lambda r: (r["method"], r["group"], r["chart"], -r["value"]))
    return reference, rows


def _run_isolated(job):
    """A job in a fresh process of its own (after a worker died under a pool of them): its
    row, or a failed row saying that the process running it died."""
    with ProcessPoolExecutor(max_workers=1) as ex:
        try:
            return ex.submit(*job).result()
        except BrokenProcessPool:
            return _job_failed(job, WorkerDied(
                "the worker process running this job died (it exited or was killed, e.g. by a crash "
                "inside the engine or by running out of memory); the rest of the sweep ran. Run this "
                "setting alone with simulate() to see what happens."))
        except Exception as exc:
            return _job_failed(job, exc)


class WorkerDied(RuntimeError):
    """A sweep's worker process ended while running a job (the row's message)."""


def _run_job(job):
    try:
        return job[0](*job[1:])
    except Exception as exc:                    # a failing run is a row of the sweep, not its end
        return _job_failed(job, exc)


def _retime(jobs, rows, repeat, serial, workers, scheduler, progress):
    """Set every row's ``wall_s`` to the best of ``repeat`` lone runs (see :func:`sweep`);
    returns the timing description that goes into the report."""
    for r in rows:
        r["wall_pass_s"] = r["wall_s"]
        r["wall_samples_s"] = [r["wall_s"]] if serial and r["success"] else []
    if repeat:
        todo = [(i, repeat - len(rows[i]["wall_samples_s"])) for i, r in enumerate(rows) if r["success"]]
        n_done = [0]
        bar = Progress(progress, sum(k for _, k in todo), lambda: (n_done[0], "one run at a time"),
                       desc="timing", unit=" runs", value_fmt="d")
        for i, k in todo:
            for _ in range(k):
                again = _run_job(jobs[i])
                if again["success"]:
                    rows[i]["wall_samples_s"].append(again["wall_s"])
                n_done[0] += 1
                bar.step()
        bar.close()
    for r in rows:
        if repeat and r["wall_samples_s"]:
            r["wall_s"] = min(r["wall_samples_s"])
        r["wall_repeats"] = len(r["wall_samples_s"]) if repeat else 0
    where = ("serially in this process" if serial else
             f"in {workers} parallel worker processes" if scheduler is None else "on a Dask cluster")
    if repeat:
        how = (f"serial, best of {repeat}: the runs' errors and counts come from one pass {where}; each "
               f"successful run's wall time is the best (minimum) of {repeat} runs made one at a time in one "
               f"process, with nothing else of the sweep running "
               "beside it" + (" (the pass itself was the first of them)" if serial else "") +
               "; only the integration (simulate or the engine's solver) is timed, not building the model or "
               "computing errors. A failed run's wall time is its time to failure, from the pass.")
    else:
        how = (f"first pass only (repeat = 0): one run each, {where}"
               + ("" if serial else "; runs shared the machine with each other, so their wall times are "
                  "distorted and not comparable with one another") + ".")
    return dict(method="serial-best-of" if repeat else "first-pass", repeat=repeat, first_pass=where, text=how)


def wall_at_error(rows, target, key="pose_error"):
    """(wall time at ``target`` error, exact?) along one series' runs: log-log
    interpolation where the runs bracket the target, otherwise the cheapest run at or
    below it (an upper bound, exact = False); (None, False) when no run reaches it."""
    pts = sorted((r[key], r["wall_s"]) for r in rows if r.get("success", True) and r[key] > 0 and np.isfinite(r[key]))
    for (e1, w1), (e2, w2) in zip(pts, pts[1:]):
        if e1 <= target <= e2:
            f = (np.log(target) - np.log(e1)) / (np.log(e2) - np.log(e1))
            return float(np.exp(np.log(w1) + f * (np.log(w2) - np.log(w1)))), True
    below = [w for e, w in pts if e <= target]
    return (min(below), False) if below else (None, False)


def best_at(rows, target):
    """{"bridge": (series, wall, exact), "native": ...}: the cheapest series at ``target``."""
    series = {}
    for r in rows:
        series.setdefault((r["method"], r["group"], r["chart"]), []).append(r)
    best = {}
    for key, rs in series.items():
        w, exact = wall_at_error(rs, target)
        side = "native" if key[1] == "native" else "bridge"
        if w is not None and (side not in best or w < best[side][1]):
            best[side] = (" ".join(key), w, exact)
    return best


def front_gaps(rows):
    """For every "auto" run: its cost (wall time, f evaluations) over the cheapest run at
    least as accurate — among the same method's other group/chart choices (what "auto"
    decides) and among all runs (natives included). ≤ 1 or None (no other run that
    counts the quantity is as accurate): on that front."""
    def ratio(a, pool, key):
        vals = [r[key] for r in pool if r["pose_error"] <= a["pose_error"] and r[key] is not None]
        return a[key] / min(vals) if vals else None
    others = [r for r in rows if r["success"] and r["group"] != "auto"]
    out = []
    for a in rows:
        if a["group"] != "auto" or not a["success"]:
            continue
        same = [r for r in others if r["method"] == a["method"]]
        out.append(dict(method=a["method"], value=a["value"], pose_error=a["pose_error"],
                        wall_ratio_same_method=ratio(a, same, "wall_s"), n_f_ratio_same_method=ratio(a, same, "n_f"),
                        n_f_ratio_all=ratio(a, others, "n_f")))
    return out


def timing_text(reference):
    """How the wall times of a sweep were taken, in words (for the report)."""
    t = reference.get("timing")
    return t["text"] if t else "not recorded (this sweep predates the timing record); treat them as rough."


def _f(v, fmt):
    return "–" if v is None else format(v, fmt)


def write_report(out, spec, reference, rows, plots=True, target=1e-6):
    """JSON of every run, a Markdown report and (with matplotlib) the PNG plots; files
    named by :func:`report_name` (the scenario the sweep ran, ``reference["scenario"]``,
    is part of the name when the scene declares scenarios)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    scenario = reference.get("scenario")
    name = report_name(spec, scenario)
    gaps = front_gaps(rows)
    best = {k: dict(series=v[0], wall_s=v[1], exact=v[2], interpolated=v[2])
            for k, v in best_at(rows, target).items()}
    (out / f"bench_{name}.json").write_text(json.dumps(dict(scene=spec, scenario=scenario, reference=reference,
                                                            runs=rows,
                                                            auto_front=gaps, target=target, best_at_target=best),
                                                       indent=1))
    try:
        sc = get_scene(spec, scenario)
    except InputError:                  # e.g. a scene file that is gone: report without its description
        sc = BenchScene(None, None)
    lines = [f"# Work-precision: {spec}" + (f", scenario {scenario}" if scenario else ""), "",
             *([f"Scene: {sc.about}", ""] if sc.about else []),
             f"Reference: {reference['method']} on {reference['group']}/{reference['chart']} at rtol = atol = "
             f"{reference['rtol']:g}, t = 0 … {reference['t_end']:g} ({reference['n_steps']} steps).", "",
             f"Wall times: {timing_text(reference)}", "",
             "Every number in the table is measured; figures read off a line between two runs are marked "
             "*interpolated* where they appear.", "",
             "| method | group | chart | setting | pose error | velocity error | constraint | energy drift | f evals | steps | wall s | timed runs |",
             "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if r["success"]:
            lines.append(f"| {r['method']} | {r['group']} | {r['chart']} | {r['setting']}={r['value']:g} | "
                         f"{r['pose_error']:.2e} | {_f(r['velocity_error'], '.2e')} | {r['constraint_residual']:.1e} | "
                         f"{_f(r.get('energy_drift'), '.1e')} | {_f(r['n_f'], 'd')} | {_f(r['n_steps'], 'd')} | "
                         f"{r['wall_s']:.3f} | {r.get('wall_repeats', '–')} |")
        else:
            lines.append(f"| {r['method']} | {r['group']} | {r['chart']} | {r['setting']}={r['value']:g} | "
                         f"failed: {r['message']} | | | | {_f(r['n_f'], 'd')} | {_f(r['n_steps'], 'd')} | "
                         f"{r['wall_s']:.3f} | {r.get('wall_repeats', '–')} |")
    best = best_at(rows, target)
    lines += ["", f"## Cheapest at pose error {target:g}", ""]
    for side in ("bridge", "native"):
        if side in best:
            series, w, exact = best[side]
            lines.append(f"- {side}: {series}, " + (
                f"≈ {w:.3f} s, *interpolated* (log-log, between the two runs of the series that bracket the target)"
                if exact else f"≤ {w:.3f} s, measured (the cheapest run below the target; no run pair "
                              "brackets it, so nothing is interpolated)"))
        else:
            lines.append(f"- {side}: no run reached it" if side == "bridge" or sc.natives
                         else "- native: this scene has no engine solver")
    if "bridge" in best and "native" in best:
        interp = best["native"][2] or best["bridge"][2]
        lines.append(f"- native / bridge wall time: {best['native'][1] / best['bridge'][1]:.2f}"
                     + (" (*interpolated*: from the interpolated figures above)" if interp else " (measured runs)"))
    if gaps:
        chosen = sorted({tuple(x) for r in rows if "auto" in r for x in r["auto"]})
        lines += ["", "## auto against the front", "",
                  f"group = chart = \"auto\" chose {', '.join('/'.join(c) for c in chosen)}. Ratio = this run's "
                  "cost over the cheapest run at least as accurate, among the same method's other "
                  "group/chart choices (what auto decides) and among all runs (≤ 1: on that front; "
                  "wall times carry the machine's noise, f evaluations do not). Measured: every ratio is between two "
                  "runs of the sweep, nothing is interpolated.", "",
                  "| method | setting | pose error | wall ratio, same method | f-eval ratio, same method | "
                  "f-eval ratio, all runs |", "|---|---|---:|---:|---:|---:|"]
        for g in gaps:
            fmt = lambda v: "front" if v is None or v <= 1 else f"{v:.2f}"  # noqa: E731
            lines.append(f"| {g['method']} | {g['value']:g} | {g['pose_error']:.2e} | "
                         f"{fmt(g['wall_ratio_same_method'])} | {fmt(g['n_f_ratio_same_method'])} | "
                         f"{fmt(g['n_f_ratio_all'])} |")
    if plots:
        from .plots import work_precision_plots
        made = work_precision_plots(out, name, rows)
        if made:
            lines += ["", "## Plots", ""] + [f"![{p.stem}]({p.name})" for p in made]
        else:
            lines += ["", "(no plots: matplotlib is not installed; pip install 'lgt-bridge[plot]')"]
    path = out / f"bench_{name}.md"
    path.write_text("\n".join(lines) + "\n")
    return path
