"""Running a sweep: :func:`sweep`.

Every combination of method x group x chart x setting (tolerance for adaptive
methods, step for fixed-step ones) runs on the scene; each run's end state is
compared with a tight reference (:data:`REFERENCE`: dopri5 on SE(3)/exp at
rtol = atol = 1e-12, stated in the report). Runs execute in parallel worker processes
(or on a Dask cluster) for their numbers; their wall times are then taken again one run
at a time in this process, best of ``repeat`` (see :func:`sweep`), so that no run looks
faster or slower because of what ran beside it. Every option is checked
(:func:`~lgt_bridge.bench.registry.check_options`) before the reference run; a run that
fails (an exception in the run or in its worker) becomes a row with ``success = False``
and its error, and a worker process that dies (a crash inside an engine, the memory
exhausted) costs only the run it was running: the runs its pool could not finish are run
again, each in a process of its own. Each worker runs one BLAS/LAPACK thread
(:func:`one_blas_thread`): a pool already fills the cores, and a library thread pool per
worker on top oversubscribes them (a 38 x 38 ``eigh`` went from 0.1 ms to 10 ms per call).
"""
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool

import numpy as np

from ..errors import InputError
from ..progress import Progress
from ..simulate import simulate
from .metrics import end_errors, energy_drift
from .registry import check_options, get_scene, load_scene, method_kind, scenarios_of

REFERENCE = dict(method="dopri5", group="SE3", chart="exp", rtol=1e-12, atol=1e-12)


def _row(method, group, chart, kind, value, success, message, wall, n_f, n_steps, n_rejected):
    """The leading fields of a sweep's row; ``kind``: "dt", "tol" (or a native's kind)."""
    return dict(method=method, group=group, chart=chart, setting=kind, value=value, success=success,
                message=message, wall_s=wall, n_f=n_f, n_steps=n_steps, n_rejected=n_rejected)


def _kind(method):
    """"dt" or "tol": the setting a bridge or scipy method takes (unknown names: "tol")."""
    return "dt" if method_kind(method) == "dt" else "tol"


def _failed_row(method, group, chart, setting, exc, wall=0.0):
    return _row(method, group, chart, _kind(method), setting, False,
                f"{type(exc).__name__}: {' '.join(str(exc).split())}", wall, None, None, None)


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
    kind = _kind(method)
    kw = dict(dt=setting) if kind == "dt" else dict(rtol=setting, atol=setting)
    t0 = time.perf_counter()
    r = simulate(model, (0.0, T), method=method, group=group, chart=chart, progress=False, **kw)
    wall = time.perf_counter() - t0
    row = _row(method, group, chart, kind, setting, r.success, r.message, wall,
               r.stats["n_f"], r.stats["n_steps"], r.stats["n_rejected"])
    if "auto" in r.stats:
        row["auto"] = sorted({(c["group"], c["chart"]) for c in r.stats["auto"]})
    if r.success:
        row.update(end_errors(model, r.q[-1], q_ref, r.V[-1], V_ref))
    row.update(energy_drift(model, r.t, r.q, r.V, r.success))
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
    row = _row(name, "native", "engine", kind, setting, ok, msg, wall, out.get("n_f"), out.get("n_steps"), None)
    if ok:
        row.update(end_errors(model, out["q"], q_ref))
    return row


def one_blas_thread():
    """Limit this process's BLAS/LAPACK (OpenBLAS, MKL, BLIS) and OpenMP pools to one thread
    (:mod:`threadpoolctl`; environment variables would come too late in a forked worker,
    whose numpy is already loaded). The initializer of every sweep worker."""
    from threadpoolctl import threadpool_limits
    threadpool_limits(1)


def _executor(workers, scheduler):
    """(submit, as_completed, close) for local processes or a Dask cluster.
    scheduler: None (local processes), "local" (a Dask LocalCluster started here),
    an address "tcp://host:port", or a ``distributed.Client``."""
    if scheduler is None:
        ex = ProcessPoolExecutor(max_workers=workers, initializer=one_blas_thread)
        return ex.submit, as_completed, ex.shutdown
    try:
        from dask import distributed
    except ImportError:
        raise InputError("bench: a Dask scheduler needs dask.distributed: "
                         "pip install 'lgt-bridge[dask]'.") from None
    if isinstance(scheduler, distributed.Client):
        scheduler.run(one_blas_thread)
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
    client.run(one_blas_thread)          # the workers that exist now (a cluster's later ones keep their own)
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
    model, T = load_scene(spec, scenario, check=True)
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
            for s in (dts if _kind(m) == "dt" else tols)]
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
    with ProcessPoolExecutor(max_workers=1, initializer=one_blas_thread) as ex:
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
