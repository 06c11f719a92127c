"""A sweep's report: the JSON of every run, the Markdown table and summary, and (with
matplotlib) the PNG plots of :mod:`lgt_bridge.plots`; files named by :func:`report_name`.
"""
import json
from pathlib import Path

from ..errors import InputError
from .metrics import POSE_ERROR, best_at, front_gaps
from .registry import BenchScene, SceneFamily, all_scenes, get_scene


def report_name(spec, scenario=None):
    """The stem of a sweep's files: the scene name, the file's stem for 'file.py:function',
    PREFIX_ARG for a family member; then _SCENARIO when one is given."""
    name = spec
    if ":" in spec:
        prefix, arg = spec.split(":", 1)
        fam = all_scenes().get(prefix)
        name = (f"{prefix}_{arg}" if isinstance(fam, SceneFamily) else Path(spec.split(":")[0]).stem)
    return name + (f"_{scenario}" if scenario else "")


def timing_text(reference):
    """How the wall times of a sweep were taken, in words (for the report)."""
    t = reference.get("timing")
    return t["text"] if t else "not recorded (this sweep predates the timing record); treat them as rough."


def _f(v, fmt):
    return "–" if v is None else format(v, fmt)


def write_report(out, spec, reference, rows, plots=True, target=1e-6, written=None):
    """JSON of every run, a Markdown report and (with matplotlib) the PNG plots; files
    named by :func:`report_name` (the scenario the sweep ran, ``reference["scenario"]``,
    is part of the name when the scene declares scenarios). Returns the Markdown's path;
    ``written`` (a list): the paths of every file written are appended to it, the
    Markdown's first."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    scenario = reference.get("scenario")
    name = report_name(spec, scenario)
    gaps = front_gaps(rows)
    best = {k: dict(series=v[0], wall_s=v[1], exact=v[2], interpolated=v[2])
            for k, v in best_at(rows, target).items()}
    json_path = out / f"bench_{name}.json"
    json_path.write_text(json.dumps(dict(scene=spec, scenario=scenario, reference=reference,
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
             f"{POSE_ERROR}", "",
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
    made = []
    if plots:
        from ..plots import work_precision_plots
        made = work_precision_plots(out, name, rows)
        if made:
            lines += ["", "## Plots", ""] + [f"![{p.stem}]({p.name})" for p in made]
        else:
            lines += ["", "(no plots: matplotlib is not installed; pip install 'lgt-bridge[plot]')"]
    path = out / f"bench_{name}.md"
    path.write_text("\n".join(lines) + "\n")
    if written is not None:
        written += [path, json_path, *made]
    return path
