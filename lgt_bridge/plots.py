"""PNG plots of a bench sweep (matplotlib, optional): error against wall time and
against f evaluations (work-precision diagrams), and energy drift over time.

One style per series (method x group x chart; an engine's own solver is the series
``(name, "native", "engine")``), fixed for the whole sweep by :func:`series_styles` and
used by every plot, so a series has the same colour, marker and line in all three.
Markers are hollow and differ in shape and size within a method, so series that lie
on top of each other (e.g. ``auto`` choosing SO3xR3/exp) stay visible; the data are
not shifted. Legends sit to the right of the axes, outside the data."""
from collections import defaultdict

# colour per method: tab10, then the darker/lighter halves of tab20 (colour-blind-friendly order)
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
           "#bcbd22", "#17becf", "#aec7e8", "#ffbb78", "#98df8a", "#ff9896", "#c5b0d5", "#c49c94",
           "#f7b6d2", "#c7c7c7", "#dbdb8d", "#9edae5")
# marker per (group, chart); "auto" and an engine's own solver have their own
MARKERS = {("SE3", "exp"): "o", ("SE3", "cay"): "D", ("SO3xR3", "exp"): "s", ("SO3xR3", "cay"): "^",
           ("auto", "auto"): "*", ("native", "engine"): "P"}
_MORE_MARKERS = ("v", "<", ">", "p", "h", "X", "8", "d", "H", "1", "2", "3", "4")
# line per group: solid SE(3), dashed SO(3)xR³, dash-dot auto, dotted the engine's solvers
LINES = {"SE3": "-", "SO3xR3": "--", "auto": "-.", "native": ":"}
# marker size per marker, largest first, so that coinciding markers nest instead of hiding each other
SIZES = {"*": 13, "D": 6, "o": 9, "s": 7.5, "^": 8, "P": 9}


def series_key(row):
    """The series a row belongs to: (method, group, chart)."""
    return (row["method"], row["group"], row["chart"])


def series_styles(keys):
    """{series key: (colour, marker, linestyle)} for every series of a sweep.

    A pure function of the set of keys (order and repetition do not matter): every plot
    of a sweep calls it with all of the sweep's series, so a series keeps its style from
    plot to plot. Injective: colour by method, marker by (group, chart), line by group;
    should two series still coincide (more than 20 methods, or unknown groups), the later
    one gets a dash pattern of its own."""
    keys = sorted(set(keys))
    methods = sorted({k[0] for k in keys})
    combos = sorted({k[1:] for k in keys} - set(MARKERS))
    extra = {c: _MORE_MARKERS[i % len(_MORE_MARKERS)] for i, c in enumerate(combos)}
    out, used = {}, set()
    for key in keys:
        m, g, c = key
        style = (PALETTE[methods.index(m) % len(PALETTE)], MARKERS.get((g, c)) or extra[(g, c)], LINES.get(g, "-"))
        n = 1
        while style in used:                    # guarantee: distinct series, distinct styles
            style = (style[0], style[1], (0, (1 + n, 1 + n % 3)))
            n += 1
        used.add(style)
        out[key] = style
    return out


def _label(key):
    m, g, c = key
    return f"{m} (engine)" if g == "native" else f"{m} {g}/{c}"


def _kw(style, key):
    colour, marker, ls = style
    auto = key[1] == "auto"
    return dict(color=colour, marker=marker, ls=ls, lw=2.2 if auto else 1.2, ms=SIZES.get(marker, 7),
                mfc="none", mew=1.4, gid="|".join(key), label=_label(key))


def work_precision_plots(out, name, rows):
    """Write the three plots into ``out``; returns their paths ([] without matplotlib)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    series = defaultdict(list)
    for r in rows:
        series[series_key(r)].append(r)
    styles = series_styles(series)
    # big markers first, small ones on top of them
    order = sorted(series, key=lambda k: (-SIZES.get(styles[k][1], 7), k))
    paths = []
    for key, xlabel, fname in (("wall_s", _wall_label(rows), "wall"), ("n_f", "f evaluations", "nf")):
        fig, ax = plt.subplots(figsize=(9.5, 5))
        for k in order:
            ok = sorted((r for r in series[k] if r["success"] and r[key] is not None), key=lambda r: r[key])
            if ok:
                ax.loglog([r[key] for r in ok], [max(r["pose_error"], 1e-17) for r in ok], **_kw(styles[k], k))
        _log_ticks(ax.xaxis)
        paths.append(_save(plt, fig, ax, out / f"{name}_error_vs_{fname}.png", xlabel, POSE_ERROR_LABEL,
                           f"{name}: work-precision"))
    if not any("energy_t" in r for r in rows):        # the model has no energy()
        return paths
    fig, ax = plt.subplots(figsize=(9.5, 5))
    for i, k in enumerate(order):
        ok = [r for r in series[k] if r["success"] and "energy_t" in r]
        if not ok:
            continue
        fine = min(ok, key=lambda r: r["value"])          # finest step / tightest tolerance
        kw = _kw(styles[k], k)
        kw["label"] += f" {fine['setting']}={fine['value']:g}"
        n = len(fine["energy_t"])
        step = max(n // 8, 1)                          # markers staggered along coinciding curves
        ax.semilogy(fine["energy_t"], [max(e, 1e-17) for e in fine["energy_drift_t"]],
                    markevery=(i % step, step), **kw)
    paths.append(_save(plt, fig, ax, out / f"{name}_energy_drift.png", "t [s]", "|E(t) - E(0)| / |E(0)|",
                       f"{name}: energy drift (finest setting of each series)"))
    return paths


#: the y label of the work-precision plots (the pose error is defined in bench.metrics.POSE_ERROR)
POSE_ERROR_LABEL = "pose error at the end time:\nlargest rotation error [rad] + largest position error [m]"


def _log_ticks(axis):
    """Readable labels on a log axis: at 1, 2, 5 × 10^k when the data span less than three
    decades (matplotlib would label crowded minor ticks there), at the decades otherwise;
    minor ticks unlabelled, labels in plain numbers ("0.02", "5000")."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    lo, hi = axis.get_data_interval()
    few = lo > 0 and hi / lo < 1e3
    axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0) if few else (1.0,)))
    axis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
    axis.set_minor_formatter(NullFormatter())
    if 0 < lo < hi:                              # data between two labels: widen to them
        ticks = axis.get_major_locator().tick_values(lo, hi)
        if sum(lo <= t <= hi for t in ticks) < 2:
            axis.set_view_interval(max([t for t in ticks if t <= lo], default=lo),
                                   min([t for t in ticks if t >= hi], default=hi), ignore=True)


def _wall_label(rows):
    reps = {r.get("wall_repeats") for r in rows if r["success"]}
    if reps and None not in reps and min(reps) >= 1:
        return f"wall time [s] (best of {max(reps)} lone runs)" if len(reps) == 1 else "wall time [s] (best of lone runs)"
    return "wall time [s]"


def _save(plt, fig, ax, path, xlabel, ylabel, title):
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    handles = sorted(ax.get_legend_handles_labels()[0], key=lambda h: h.get_gid() or "")   # by series, not draw order
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
              frameon=False)
    fig.savefig(path, dpi=100, bbox_inches="tight")
    plt.close(fig)
    return path
