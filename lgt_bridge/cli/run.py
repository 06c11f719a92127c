"""``lgt-bridge run SCRIPT [options] [-- ARGS]``: a legacy engine script, unchanged, with its
solver calls routed through the bridge."""
import argparse
import sys

from ..errors import InputError, LGTError
from ..lgt import DEFAULT_GROUP
from .options import CHARTS, DEBUG, GROUPS, PROGRESS, charts_help, check_method, kinds


class ScriptFailed(Exception):
    """The script raised (or does not compile): ``text`` is what ``python script.py`` would
    print for it (the script's own traceback, none of the command line's frames)."""

    def __init__(self, exc, text):
        super().__init__(text)
        self.exc, self.text = exc, text


def _script_traceback(exc, path):
    """The traceback of ``exc`` from the script's first frame on."""
    import traceback
    tb = exc.__traceback__
    while tb is not None and tb.tb_frame.f_code.co_filename != path:
        tb = tb.tb_next
    return "".join(traceback.format_exception(type(exc), exc, tb or exc.__traceback__))


def exec_script(script, args=()):
    """Run ``script`` as ``python script ARGS`` would: as ``__main__`` (a fresh module in
    ``sys.modules``) with ``__file__`` its path made absolute, ``sys.argv == [script, *args]``,
    its folder (symlinks resolved) first on ``sys.path`` so a multi-file model imports its
    helpers, in the current working directory. (``runpy.run_path`` neither puts the folder on
    sys.path nor keeps ``sys.argv[0]`` as given.) ``sys.argv``, ``sys.path`` and ``__main__``
    are restored afterwards, and the modules and packages the script newly imported from its
    folder are forgotten, so a later run in this process imports its own helpers. A syntax
    error or an exception of the script (other than an LGTError, SystemExit or
    KeyboardInterrupt) raises :class:`ScriptFailed` with the script's own traceback."""
    import builtins
    import importlib.machinery
    import io
    import os
    import traceback
    import types
    path = script if os.path.isabs(script) else os.path.join(os.getcwd(), script)   # as CPython 3.9+
    folder = os.path.dirname(os.path.realpath(script))
    with io.open_code(path) as f:
        source = f.read()
    try:
        code = compile(source, path, "exec", dont_inherit=True)
    except SyntaxError as exc:
        raise ScriptFailed(exc, "".join(traceback.format_exception_only(type(exc), exc))) from exc
    main = types.ModuleType("__main__")
    main.__dict__.update(__file__=path, __builtins__=builtins, __cached__=None, __package__=None,
                         __loader__=importlib.machinery.SourceFileLoader("__main__", path))
    saved_argv, saved_path, saved_modules = sys.argv, list(sys.path), set(sys.modules)
    saved_main = sys.modules.get("__main__")
    sys.argv = [script, *args]
    sys.path.insert(0, folder)
    sys.modules["__main__"] = main
    try:
        exec(code, main.__dict__)
    except LGTError:                         # raised on purpose: the command's one-line error
        raise
    except Exception as exc:
        raise ScriptFailed(exc, _script_traceback(exc, path)) from exc
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


def load_events(specs):
    """The event functions named by ``--events`` (``FILE.py:NAME`` or ``MODULE:NAME``), each a
    g(t, q, V) -> float with scipy's ``terminal``/``direction`` attributes (checked by the
    solve, before its first step). InputError for a spec that does not name a callable."""
    import importlib
    import importlib.util
    import os
    out = []
    for spec in specs or ():
        where, sep, name = spec.rpartition(":")
        if not sep or not where or not name:
            raise InputError(f"run --events {spec!r}: use FILE.py:FUNCTION or MODULE:FUNCTION "
                             "(a function g(t, q, V) -> float).")
        try:
            if where.endswith(".py"):
                if not os.path.isfile(where):
                    raise InputError(f"run --events {spec!r}: no file {where!r}.")
                key = f"_lgt_bridge_events_{len(out)}_{os.path.splitext(os.path.basename(where))[0]}"
                mspec = importlib.util.spec_from_file_location(key, os.path.abspath(where))
                module = importlib.util.module_from_spec(mspec)
                mspec.loader.exec_module(module)
            else:
                module = importlib.import_module(where)
        except InputError:
            raise
        except Exception as exc:
            raise InputError(f"run --events {spec!r}: importing {where!r} failed: "
                             f"{type(exc).__name__}: {exc}") from exc
        fn = getattr(module, name, None)
        if not callable(fn):
            raise InputError(f"run --events {spec!r}: {where!r} has no function {name!r}.")
        out.append(fn)
    return out


def run(a):
    """Execute ``a.script`` as __main__ with every registered adapter's solver routing active."""
    import contextlib
    import os
    import time

    from ..plugins import adapters
    if not os.path.isfile(a.script):
        raise InputError(f"run: no script file {a.script!r}.")
    check_method(a.method, "run --method")
    if a.rtol is not None and not (0 <= a.rtol < float("inf")):      # 0: pure absolute tolerance
        raise InputError(f"run --rtol = {a.rtol:g}: must be zero or a positive number.")
    if a.atol is not None and not (0 < a.atol < float("inf")):
        raise InputError(f"run --atol = {a.atol:g}: must be a positive number.")
    options = dict(method=a.method, group=a.group, chart=a.chart, rtol=a.rtol, atol=a.atol,
                   progress=a.progress)
    events = load_events(getattr(a, "events", None))
    if events:
        options["events"] = events
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
        exec_script(a.script, a.script_args)
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


def add_parser(sub):
    fixed, adaptive, implicit, scipy = kinds()
    r = sub.add_parser("run", help="run an unmodified engine script with its solver calls "
                       "(Exudyn SolveDynamic) routed through the bridge",
                       usage="lgt-bridge run SCRIPT [options] [-- ARGS ...]",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Run SCRIPT unchanged as __main__ (sys.argv = [SCRIPT, *ARGS]: the\n"
                       "script's own arguments follow --); every exu.SolveDynamic / mbs.SolveDynamic\n"
                       "call it makes is integrated by the bridge (the script's sensors, solution file\n"
                       "and final state keep working). Other solver calls and hand-written loops (e.g.\n"
                       "a Pinocchio aba loop) run as written. An error in the script shows the script's\n"
                       "own traceback, as python SCRIPT would (exit status 1).",
                       epilog=_tolerance_epilog(fixed, adaptive))
    r.add_argument("script", help="the legacy script (.py)")
    r.add_argument("--method", default="dopri5", metavar="METHOD",
                   help=f"{fixed} (fixed step); {adaptive} (adaptive; {implicit} implicit, for stiff "
                   f"models); scipy:<Name> with Name in {scipy} (default dopri5)")
    r.add_argument("--group", default=DEFAULT_GROUP, choices=GROUPS,
                   help=f"Lie group of the local coordinates; auto: per body, what the model needs "
                   f"(default {DEFAULT_GROUP})")
    r.add_argument("--chart", default="exp", choices=CHARTS,
                   help=f"local chart: {charts_help()}; auto: per body (default exp)")
    r.add_argument("--rtol", type=float, default=None, help="relative tolerance (see below)")
    r.add_argument("--atol", type=float, default=None, help="absolute tolerance (see below)")
    r.add_argument("--events", action="append", metavar="FILE.py:FUNCTION",
                   help="an event function g(t, q, V) -> float (FILE.py:FUNCTION or MODULE:FUNCTION; "
                   "repeat for more) for every routed solve: its zero crossings are located and "
                   "printed; g.terminal = True ends the solve there, g.direction = -1/0/+1 as in "
                   "scipy; q, V are the bridge's model coordinates (Exudyn's total coordinates); "
                   "the results are in mbs.sys['lgtBridgeStats']['t_events']")
    r.add_argument("--progress", **PROGRESS)
    r.add_argument("--debug", **DEBUG)
    r.set_defaults(script_args=[])
    return r


def _tolerance_epilog(fixed, adaptive):
    from ..integrators import registry as _methods
    pairs = " and ".join(_methods.by(steps="adaptive", fixed_form=True))
    others = ", ".join(_methods.by(steps="adaptive", fixed_form=False))
    return (f"tolerances: adaptive methods ({adaptive}, scipy:*) use --rtol/--atol\n"
            "  (--rtol 0: pure absolute tolerance). Without them: the script's own\n"
            "  simulationSettings.timeIntegration.relativeTolerance/absoluteTolerance\n"
            "  (Exudyn's defaults: 1e-8, 1e-8) if its automaticStepSize is True. With\n"
            f"  automaticStepSize False, {pairs} take fixed steps of\n"
            "  (endTime-startTime)/numberOfSteps with their own tableau; "
            f"{others} and scipy:*\n  still use the settings' tolerances. Given one, the other comes from the\n"
            f"  settings, or with automaticStepSize False for {pairs}, from the bridge's\n"
            "  defaults (rtol 1e-6, atol 1e-8).\n"
            f"  Fixed-step methods ({fixed}) step at (endTime-startTime)/numberOfSteps.\n"
            "  minimumStepSize, initialStepSize and startTime are honoured as by Exudyn.\n"
            "Each routed call prints one line: method, group, chart, where each tolerance\n"
            "came from (given, the script's settings, the bridge default), steps.")
