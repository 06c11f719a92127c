"""Command line: ``lgt-bridge demo | run | bench``.

Errors raised on purpose (:class:`~lgt_bridge.errors.LGTError` and subclasses, a missing
script, an unknown scene, a bad option value) print ``lgt-bridge: error: <message>`` on
stderr and exit with status 2; ``--debug`` shows their traceback. Unexpected exceptions
keep their traceback.
"""
import argparse
import sys

from . import charts as _charts
from .errors import InputError, LGTError
from .integrators import registry as _methods
from .lgt import GROUPS as _lgt_groups

_GROUPS = (*_lgt_groups, "auto")
_CHARTS = (*_charts.NAMES, "auto")


def check_method(m, where):
    """InputError unless ``m`` names a method of the registry."""
    try:
        _methods.get(m)
    except InputError:
        raise InputError(f"{where}: unknown method {m!r}; use one of {_methods.choices_text()}.") from None


def _kinds():
    """The method names by kind, for the help texts (from the registry)."""
    fixed = ", ".join(_methods.by(steps="fixed"))
    adaptive = ", ".join(_methods.by(steps="adaptive"))
    implicit = ", ".join(_methods.by(steps="adaptive", implicit=True))
    scipy = ", ".join(_methods.SCIPY)
    return fixed, adaptive, implicit, scipy


def _one_line(exc):
    return " ".join(str(exc).split()) or type(exc).__name__


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose epilog may be computed when help is shown (``epilog_fn``)."""

    epilog_fn = None

    def format_help(self):
        if self.epilog_fn is not None:
            self.epilog = self.epilog_fn()
        return super().format_help()


def _exec_script(script):
    """Run ``script`` as ``python script`` would: as ``__main__`` (a fresh module in
    ``sys.modules``) with ``__file__`` its path made absolute, ``sys.argv == [script]``, its
    folder (symlinks resolved) first on ``sys.path`` so a multi-file model imports its helpers,
    in the current working directory. (``runpy.run_path`` neither puts the folder on sys.path
    nor keeps ``sys.argv[0]`` as given.) ``sys.argv``, ``sys.path`` and ``__main__`` are
    restored afterwards, and the modules and packages the script newly imported from its
    folder are forgotten, so a later run in this process imports its own helpers."""
    import builtins
    import importlib.machinery
    import io
    import os
    import types
    path = script if os.path.isabs(script) else os.path.join(os.getcwd(), script)   # as CPython 3.9+
    folder = os.path.dirname(os.path.realpath(script))
    with io.open_code(path) as f:
        code = compile(f.read(), path, "exec", dont_inherit=True)
    main = types.ModuleType("__main__")
    main.__dict__.update(__file__=path, __builtins__=builtins, __cached__=None, __package__=None,
                         __loader__=importlib.machinery.SourceFileLoader("__main__", path))
    saved_argv, saved_path, saved_modules = sys.argv, list(sys.path), set(sys.modules)
    saved_main = sys.modules.get("__main__")
    sys.argv = [script]
    sys.path.insert(0, folder)
    sys.modules["__main__"] = main
    try:
        exec(code, main.__dict__)
    finally:
        sys.argv = saved_argv
        sys.path[:] = saved_path
        if saved_main is not None:
            sys.modules["__main__"] = saved_main
        new = set(sys.modules) - saved_modules
        local = set()
        for top in {name.partition(".")[0] for name in new} & new:
            f = getattr(sys.modules[top], "__file__", None)
            if f and os.path.dirname(os.path.realpath(f)) in (folder, os.path.join(folder, top)):
                local.add(top)
        for name in new:
            if name.partition(".")[0] in local:
                del sys.modules[name]


def _run_script(a):
    """Execute ``a.script`` as __main__ with every registered adapter's solver routing active."""
    import contextlib
    import os
    import time

    from .plugins import adapters
    if not os.path.isfile(a.script):
        raise InputError(f"run: no script file {a.script!r}.")
    check_method(a.method, "run --method")
    if a.rtol is not None and not (0 <= a.rtol < float("inf")):      # 0: pure absolute tolerance
        raise InputError(f"run --rtol = {a.rtol}: must be zero or a positive number.")
    if a.atol is not None and not (0 < a.atol < float("inf")):
        raise InputError(f"run --atol = {a.atol}: must be a positive number.")
    options = dict(method=a.method, group=a.group, chart=a.chart, rtol=a.rtol, atol=a.atol,
                   progress=a.progress)
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        routed = []
        for name, ep in sorted(adapters().items()):
            try:
                plugin = ep.load()
                if hasattr(plugin, "patch"):
                    routed.append((name, getattr(plugin, "routes", ()),
                                   stack.enter_context(plugin.patch(options))))
            except ImportError:                 # the engine of this adapter is not installed
                continue
        if not routed:
            raise InputError("run: no engine adapter with solver routing is installed "
                             "(pip install 'lgt-bridge[exudyn]').")
        _exec_script(a.script)
    n = sum(len(calls) for _, _, calls in routed)
    wall = time.perf_counter() - t0
    tols = (f"rtol={a.rtol:g}, atol={a.atol:g}" if a.rtol is not None and a.atol is not None else
            "tolerances as printed per call")
    if n == 0:
        names = ", ".join(r for _, routes, _ in routed for r in routes) or "none"
        print(f"lgt-bridge run: note: {a.script} made no solver call the bridge can route, so it "
              f"ran exactly as written ({wall:.2f} s). Routed calls: {names}. A hand-written "
              "loop (e.g. Pinocchio's pin.aba + pin.integrate) is not routed: wrap the model "
              "instead, model = lgt_pinocchio.PinocchioModel(pin_model, q0=q, v0=v) and "
              "lgt_bridge.simulate(model, (0, T), method=...) (examples/pinocchio_humanoid_bridge.py).",
              file=sys.stderr)
        return 0
    print(f"lgt-bridge run: {a.script}: {n} solver call(s) routed through the bridge "
          f"({a.method}, group {a.group}, chart {a.chart}, {tols}); total {wall:.2f} s")
    return 0


def _floats(s, opt):
    out = []
    for x in s.split(","):
        if not x.strip():
            continue
        try:
            out.append(float(x))
        except ValueError:
            raise InputError(f"bench {opt}: {x!r} is not a number.") from None
    return out


def _bench(a):
    from . import bench
    words = lambda s: [x.strip() for x in s.split(",") if x.strip()]   # noqa: E731
    methods, groups, charts = words(a.methods), words(a.groups), words(a.charts)
    tols, dts = _floats(a.tols, "--tols"), _floats(a.dts, "--dts")
    if a.workers is not None and a.workers < 1:
        raise InputError(f"bench --workers = {a.workers}: must be at least 1.")
    ref, rows = bench.sweep(a.scene, methods, groups, charts, tols, dts, workers=a.workers,
                            scheduler=a.scheduler or a.dask, auto=not a.no_auto, progress=a.progress,
                            repeat=a.repeat, scenario=a.scenario)
    path = bench.write_report(a.out, a.scene, ref, rows, plots=not a.no_plots)
    print(path.read_text())
    return 0


def _scene_epilog():
    import textwrap

    from .bench import SceneFamily, all_scenes
    try:
        scenes = all_scenes()
    except Exception as exc:            # help must not fail on a broken adapter
        return f"scenes: (could not list the engines' scenes: {exc})"
    lines = ["scenes (built-in, then those of the installed engine adapters):"]
    for k, v in scenes.items():
        name = f"{k}:{v.arg}" if isinstance(v, SceneFamily) else k
        about = textwrap.wrap(v.about, 64) or [""]
        lines += [f"  {name:<22} {about[0]}"] + [f"  {'':<22} {x}" for x in about[1:]]
        for i, (sn, sv) in enumerate(v.scenarios.items()):
            text = sv if isinstance(sv, str) else sv.about
            wrapped = textwrap.wrap(f"--scenario {sn}{' (default)' if i == 0 else ''}: {text}", 62)
            lines += [f"  {'':<24}{wrapped[0]}"] + [f"  {'':<26}{x}" for x in wrapped[1:]]
    lines += ["  path/to/file.py:func   your own: func() returns (model, t_end)",
              "  extremes               the extremes suite's report",
              "",
              "files written into --out (default bench-results/):",
              "  (<scene>: the scene's name; pinocchio_robot:solo12 -> pinocchio_robot_solo12, then",
              "  _<scenario> for a scene with scenarios, e.g. pinocchio_robot_solo12_pd)",
              "  bench_<scene>.json     every run: settings, errors, f evaluations, steps, wall time",
              "  bench_<scene>.md       the report: table of runs, cheapest at 1e-6, auto vs the front",
              "  <scene>_error_vs_wall.png, <scene>_error_vs_nf.png, <scene>_energy_drift.png",
              "                         work-precision and energy plots (with matplotlib; --no-plots: none)"]
    return "\n".join(lines)


def _parser():
    fixed, adaptive, implicit, scipy = _kinds()
    charts_help = ", ".join(f"{c.name} ({c.title})" for c in _charts.CHARTS.values())
    pairs = " and ".join(_methods.by(steps="adaptive", fixed_form=True))
    others = ", ".join(_methods.by(steps="adaptive", fixed_form=False))
    ap = argparse.ArgumentParser(prog="lgt-bridge", description="Lie group integration of "
                                 "absolute-coordinate multibody models (Exudyn, Pinocchio).")
    ap.add_argument("--debug", action="store_true", help="show the traceback of errors")
    sub = ap.add_subparsers(dest="cmd", parser_class=_Parser)
    debug = dict(action="store_true", default=argparse.SUPPRESS, help="show the traceback of errors")
    progress = dict(action=argparse.BooleanOptionalAction, default=None,
                    help="progress bars on stderr (default: only for runs longer than about 1 s "
                         "when stderr is a terminal, never when CI is set or output is piped)")
    d = sub.add_parser("demo", help="heavy top on several method x group x chart choices: "
                       "error against a tight reference, f evaluations, wall time")
    d.add_argument("--T", type=float, default=0.1, help="end time in s (default 0.1)")
    d.add_argument("--param", default="quat", choices=["quat", "rotvec", "rxyz"],
                   help="absolute rotation coordinates of the top (default quat)")
    d.add_argument("--pivot", action="store_true", help="frame at the pivot instead of the joint form")
    d.add_argument("--debug", **debug)
    r = sub.add_parser("run", help="run an unmodified engine script with its solver calls "
                       "(Exudyn SolveDynamic) routed through the bridge",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Run SCRIPT unchanged as __main__; every exu.SolveDynamic /\n"
                       "mbs.SolveDynamic call it makes is integrated by the bridge (the script's\n"
                       "sensors, solution file and final state keep working). Other solver calls and\n"
                       "hand-written loops (e.g. a Pinocchio aba loop) run as written.",
                       epilog=f"tolerances: adaptive methods ({adaptive}, scipy:*) use --rtol/--atol\n"
                       "  (--rtol 0: pure absolute tolerance); when absent, the script's own\n"
                       "  simulationSettings.timeIntegration.relativeTolerance/absoluteTolerance\n"
                       "  (Exudyn's defaults: 1e-8, 1e-8) if its automaticStepSize is True. With\n"
                       f"  automaticStepSize False and no --rtol/--atol, {pairs} take fixed\n"
                       f"  steps of (endTime-startTime)/numberOfSteps ({others} keep{'s' * (',' not in others)} the settings'\n"
                       "  tolerances; scipy:* use rtol=1e-6, atol=1e-8).\n"
                       f"  Fixed-step methods ({fixed}) step at that interval.\n"
                       "  minimumStepSize, initialStepSize and startTime are honoured as by Exudyn.\n"
                       "Each routed call prints one line: method, group, chart, tolerances, steps.")
    r.add_argument("script", help="the legacy script (.py)")
    r.add_argument("--method", default="dopri5", metavar="METHOD",
                   help=f"{fixed} (fixed step); {adaptive} (adaptive; {implicit} implicit, for stiff "
                   f"models); scipy:<Name> with Name in {scipy} (default dopri5)")
    r.add_argument("--group", default="SE3", choices=_GROUPS,
                   help="Lie group of the local coordinates; auto: per body, what the model needs "
                   "(default SE3)")
    r.add_argument("--chart", default="exp", choices=_CHARTS,
                   help=f"local chart: {charts_help}; auto: per body (default exp)")
    r.add_argument("--rtol", type=float, default=None, help="relative tolerance (see below)")
    r.add_argument("--atol", type=float, default=None, help="absolute tolerance (see below)")
    r.add_argument("--progress", **progress)
    r.add_argument("--debug", **debug)
    b = sub.add_parser("bench", help="work-precision sweep of method x group x chart x tolerance/step "
                       "on a scene, against a tight reference; writes JSON, Markdown and PNG plots",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Work-precision sweep against a tight reference (dopri5 on SE3/exp,\n"
                       "rtol = atol = 1e-12). Every option is checked before the reference run; a run\n"
                       "that fails becomes a row with its error.")
    b.epilog_fn = _scene_epilog
    b.add_argument("scene", help="a scene name (listed below), path/to/file.py:function returning "
                   "(model, t_end), or 'extremes' for the extremes suite's report")
    b.add_argument("--methods", default="rkmk4,dopri5",
                   help=f"comma-separated: {', '.join(_methods.METHODS)}, scipy:<Name> "
                   "(default rkmk4,dopri5)")
    b.add_argument("--groups", default="SE3,SO3xR3", help="comma-separated: SE3, SO3xR3, auto "
                   "(default SE3,SO3xR3)")
    b.add_argument("--charts", default="exp,cay", help=f"comma-separated: {', '.join(_CHARTS)} (default exp,cay)")
    b.add_argument("--tols", default="1e-5,1e-7,1e-9", help="rtol = atol of adaptive methods")
    b.add_argument("--dts", default="1e-3,5e-4,2.5e-4", help="steps of fixed-step methods (s)")
    b.add_argument("--scenario", default=None, metavar="NAME",
                   help="a variant of a scene that declares scenarios (listed under the scene below, the "
                   "first its default), e.g. pinocchio_robot:solo12 --scenario pd; checked before any run, "
                   "an error for a scene without scenarios. Its name is added to the output files' names")
    b.add_argument("--out", default="bench-results", help="output directory (default bench-results)")
    b.add_argument("--workers", type=int, default=None, help="parallel processes (default: all cores)")
    b.add_argument("--scheduler", default=None, help="run the sweep on a Dask cluster at this address "
                   "(tcp://host:port)")
    b.add_argument("--dask", choices=["local"], default=None, help="'local': start a Dask LocalCluster")
    b.add_argument("--no-auto", action="store_true", help="leave out the group=chart='auto' runs")
    b.add_argument("--no-plots", action="store_true", help="Markdown and JSON only")
    b.add_argument("--repeat", type=int, default=3,
                   help="wall time of each run = best of this many lone runs, one at a time after the "
                        "(parallel) pass (default 3); 0 keeps the pass's times, which parallel workers distort")
    b.add_argument("--long-steps", type=int, default=1_000_000,
                   help="extremes: steps of the long run per method (default 10⁶)")
    b.add_argument("--progress", **progress)
    b.add_argument("--debug", **debug)
    return ap


def _dispatch(a):
    if a.cmd == "bench" and a.scene == "extremes":
        if a.scenario is not None:
            raise InputError(f"bench --scenario {a.scenario}: scene 'extremes' has no scenarios; leave out "
                             "--scenario.")
        from . import extremes
        path = extremes.write_report(a.out, long_steps=a.long_steps)
        print(path.read_text())
        return 0
    if a.cmd == "bench":
        return _bench(a)
    if a.cmd == "run":
        return _run_script(a)
    from . import demo
    demo.run(sys.stdout, T=getattr(a, "T", 0.1), param=getattr(a, "param", "quat"),
             constrained=not getattr(a, "pivot", False))
    return 0


def main(argv=None):
    a = _parser().parse_args(argv)
    try:
        return _dispatch(a)
    except LGTError as exc:
        if a.debug:
            raise
        print(f"lgt-bridge: error: {_one_line(exc)}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
