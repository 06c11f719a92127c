"""PNG plots of a bench sweep (matplotlib, optional): error against wall time and
against f evaluations (work-precision diagrams), and energy drift over time."""
from collections import defaultdict


def _series(rows):
    out = defaultdict(list)
    for r in rows:
        out[(r["method"], r["group"], r["chart"])].append(r)
    return out


def work_precision_plots(out, name, rows):
    """Write the three plots into ``out``; returns their paths ([] without matplotlib)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    series = _series(rows)
    paths = []
    for key, xlabel, fname in (("wall_s", "wall time [s]", "wall"), ("n_f", "f evaluations", "nf")):
        fig, ax = plt.subplots(figsize=(7, 5))
        for (m, g, c), rs in sorted(series.items()):
            ok = sorted((r for r in rs if r["success"] and r[key] is not None), key=lambda r: r[key])
            if not ok:
                continue
            auto, native = g == "auto", g == "native"
            ax.loglog([r[key] for r in ok], [max(r["pose_error"], 1e-17) for r in ok],
                      marker="*" if auto else ("s" if native else "o"), ms=10 if auto else 4,
                      lw=2.5 if auto else 1, ls="--" if native else "-",
                      label=f"{m} (engine)" if native else f"{m} {g}/{c}")
        paths.append(_save(plt, fig, ax, out / f"{name}_error_vs_{fname}.png", xlabel,
                           "final pose error (rad + m)", f"{name}: work-precision"))
    if not any("energy_t" in r for r in rows):        # the model has no energy()
        return paths
    fig, ax = plt.subplots(figsize=(7, 5))
    for (m, g, c), rs in sorted(series.items()):
        ok = [r for r in rs if r["success"] and "energy_t" in r]
        if not ok:
            continue
        fine = min(ok, key=lambda r: r["value"])          # finest step / tightest tolerance
        ax.semilogy(fine["energy_t"], [max(e, 1e-17) for e in fine["energy_drift_t"]],
                    label=f"{m} {g}/{c} {fine['setting']}={fine['value']:g}")
    paths.append(_save(plt, fig, ax, out / f"{name}_energy_drift.png", "t [s]", "|E(t) - E(0)| / |E(0)|",
                       f"{name}: energy drift (finest setting of each series)"))
    return paths


def _save(plt, fig, ax, path, xlabel, ylabel, title):
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
