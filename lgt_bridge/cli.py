"""Command line: ``lgt-bridge demo`` (more subcommands join as they land)."""
import argparse
import sys


def _run_script(a):
    """Execute ``a.script`` as __main__ with every registered adapter's solver routing active."""
    import contextlib
    import runpy
    import time

    from .plugins import adapters
    options = dict(method=a.method, group=a.group, chart=a.chart, rtol=a.rtol, atol=a.atol)
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        routed = []
        for name, ep in sorted(adapters().items()):
            try:
                plugin = ep.load()
            except ImportError:
                continue
            if hasattr(plugin, "patch"):
                routed.append((name, stack.enter_context(plugin.patch(options))))
        if not routed:
            print("lgt-bridge run: no engine adapter is installed (pip install 'lgt-bridge[exudyn]').",
                  file=sys.stderr)
            return 2
        sys.argv = [a.script]
        runpy.run_path(a.script, run_name="__main__")
    n = sum(len(calls) for _, calls in routed)
    print(f"lgt-bridge run: {a.script}: {n} solver call(s) routed through the bridge "
          f"({a.method}, {a.group}, {a.chart}); total {time.perf_counter() - t0:.2f} s")
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(prog="lgt-bridge", description="Lie group integration of "
                                 "absolute-coordinate multibody models (Exudyn, Pinocchio).")
    sub = ap.add_subparsers(dest="cmd")
    d = sub.add_parser("demo", help="heavy top on several method x group x chart choices: "
                       "error against a tight reference, f evaluations, wall time")
    d.add_argument("--T", type=float, default=0.1, help="end time in s (default 0.1)")
    d.add_argument("--param", default="quat", choices=["quat", "rotvec", "rxyz"],
                   help="absolute rotation coordinates of the top (default quat)")
    d.add_argument("--pivot", action="store_true", help="frame at the pivot instead of the joint form")
    r = sub.add_parser("run", help="run an unmodified engine script with its solver calls "
                       "(Exudyn SolveDynamic) routed through the bridge")
    r.add_argument("script", help="the legacy script (.py)")
    r.add_argument("--method", default="dopri5")
    r.add_argument("--group", default="SE3", choices=["SE3", "SO3xR3"])
    r.add_argument("--chart", default="exp", choices=["exp", "cay"])
    r.add_argument("--rtol", type=float, default=None)
    r.add_argument("--atol", type=float, default=None)
    b = sub.add_parser("bench", help="work-precision sweep of method x group x chart x tolerance/step "
                       "on a scene, against a tight reference; writes JSON and Markdown")
    b.add_argument("scene", help="built-in scene (heavy_top, heavy_top_pivot, free_body, chain, "
                   "top_and_free_bodies), path/to/file.py:function returning (model, t_end), or "
                   "'extremes' for the extremes suite's report")
    b.add_argument("--methods", default="rkmk4,dopri5")
    b.add_argument("--groups", default="SE3,SO3xR3")
    b.add_argument("--charts", default="exp,cay")
    b.add_argument("--tols", default="1e-5,1e-7,1e-9", help="tolerances of adaptive methods")
    b.add_argument("--dts", default="1e-3,5e-4,2.5e-4", help="steps of fixed-step methods")
    b.add_argument("--out", default="bench-results")
    b.add_argument("--workers", type=int, default=None, help="parallel processes (default: all cores)")
    b.add_argument("--scheduler", default=None, help="run the sweep on a Dask cluster at this address "
                   "(tcp://host:port)")
    b.add_argument("--dask", choices=["local"], default=None, help="'local': start a Dask LocalCluster")
    b.add_argument("--no-auto", action="store_true", help="leave out the group=chart='auto' runs")
    b.add_argument("--no-plots", action="store_true", help="Markdown and JSON only")
    b.add_argument("--long-steps", type=int, default=1_000_000,
                   help="extremes: steps of the long run per method (default 10⁶)")
    a = ap.parse_args(argv)
    if a.cmd == "bench" and a.scene == "extremes":
        from . import extremes
        path = extremes.write_report(a.out, long_steps=a.long_steps)
        print(path.read_text())
        return 0
    if a.cmd == "bench":
        from . import bench
        floats = lambda s: [float(x) for x in s.split(",") if x]   # noqa: E731
        words = lambda s: [x for x in s.split(",") if x]           # noqa: E731
        ref, rows = bench.sweep(a.scene, words(a.methods), words(a.groups), words(a.charts),
                                floats(a.tols), floats(a.dts), workers=a.workers,
                                scheduler=a.scheduler or a.dask, auto=not a.no_auto)
        path = bench.write_report(a.out, a.scene, ref, rows, plots=not a.no_plots)
        print(path.read_text())
        return 0
    if a.cmd == "run":
        return _run_script(a)
    if a.cmd in (None, "demo"):
        from . import demo
        demo.run(sys.stdout, T=getattr(a, "T", 0.1), param=getattr(a, "param", "quat"),
                 constrained=not getattr(a, "pivot", False))
        return 0
    return 2


if __name__ == "__main__":
    sys.exit(main())
