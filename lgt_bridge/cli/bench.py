"""``lgt-bridge bench SCENE [options]``: a work-precision sweep, or the extremes suite's report."""
import argparse

from ..errors import InputError
from ..integrators import registry as _methods
from ..lgt import GROUPS as _lgt_groups
from .options import CHARTS, DEBUG, GROUPS, PROGRESS


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


def run(a):
    if a.scene == "extremes":
        if a.scenario is not None:
            raise InputError(f"bench --scenario {a.scenario}: scene 'extremes' has no scenarios; leave out "
                             "--scenario.")
        from .. import extremes
        path = extremes.write_report(a.out, long_steps=a.long_steps)
        print(path.read_text())
        _say_written([path])
        return 0
    from .. import bench
    words = lambda s: [x.strip() for x in s.split(",") if x.strip()]   # noqa: E731
    methods, groups, charts = words(a.methods), words(a.groups), words(a.charts)
    tols, dts = _floats(a.tols, "--tols"), _floats(a.dts, "--dts")
    if a.workers is not None and a.workers < 1:
        raise InputError(f"bench --workers = {a.workers}: must be at least 1.")
    ref, rows = bench.sweep(a.scene, methods, groups, charts, tols, dts, workers=a.workers,
                            scheduler=a.scheduler or a.dask, auto=not a.no_auto, progress=a.progress,
                            repeat=a.repeat, scenario=a.scenario)
    written = []
    bench.write_report(a.out, a.scene, ref, rows, plots=not a.no_plots, written=written)
    print(written[0].read_text())
    _say_written(written)
    return 0


def _say_written(paths):
    import sys
    print(f"lgt-bridge bench: wrote {', '.join(str(p) for p in paths)}", file=sys.stderr)


def _scene_epilog():
    import textwrap

    from ..bench import SceneFamily, all_scenes
    from ..bench.metrics import POSE_ERROR
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
    lines += ["  path/to/file.py:func   your own: func() returns (model, t_end); it must build the",
              "                         same model every call (seed its random numbers): the bench",
              "                         builds it once per run and compares the runs",
              "  extremes               the extremes suite's report",
              "",
              "files written into --out (default bench-results/; their paths are printed at the end):",
              "  (<scene>: the scene's name; pinocchio_robot:solo12 -> pinocchio_robot_solo12, then",
              "  _<scenario> for a scene with scenarios, e.g. pinocchio_robot_solo12_pd)",
              "  bench_<scene>.json     every run: settings, errors, f evaluations, steps, wall time",
              "  bench_<scene>.md       the report: table of runs, cheapest at 1e-6, auto vs the front",
              "  <scene>_error_vs_wall.png, <scene>_error_vs_nf.png, <scene>_energy_drift.png",
              "                         work-precision and energy plots (with matplotlib; --no-plots: none)",
              *textwrap.wrap(POSE_ERROR, 88, subsequent_indent="  ")]
    return "\n".join(lines)


def add_parser(sub):
    b = sub.add_parser("bench", help="work-precision sweep of method x group x chart x tolerance/step "
                       "on a scene, against a tight reference; writes JSON, Markdown and PNG plots",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Work-precision sweep against a tight reference (dopri5 on SE3/exp,\n"
                       "rtol = atol = 1e-12). Every option is checked before the reference run; a run\n"
                       "that fails becomes a row with its error.")
    b.epilog_fn = _scene_epilog
    b.add_argument("scene", help="a scene name (listed below), path/to/file.py:function returning "
                   "(model, t_end) (the same model on every call), or 'extremes' for the extremes suite's report")
    b.add_argument("--methods", default="rkmk4,dopri5",
                   help=f"comma-separated: {', '.join(_methods.METHODS)}, scipy:<Name> "
                   "(default rkmk4,dopri5)")
    b.add_argument("--groups", default=",".join(_lgt_groups),
                   help=f"comma-separated: {', '.join(GROUPS)} (default {','.join(_lgt_groups)})")
    b.add_argument("--charts", default="exp,cay", help=f"comma-separated: {', '.join(CHARTS)} (default exp,cay)")
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
    b.add_argument("--progress", **PROGRESS)
    b.add_argument("--debug", **DEBUG)
    return b
