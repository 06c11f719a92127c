"""Regenerate the README's work-precision figures (≈ 8 min on 2 cores; ``--only NAME`` for one set):

    python docs/figures/make_figures.py [--only heavy_top|exudyn_heavy_top|solo12_pd] [--out DIR]

Three ``lgt-bridge bench`` sweeps, each writing its two work-precision plots here as
``<name>_error_vs_wall.png`` and ``<name>_error_vs_nf.png``:

* ``heavy_top`` — the engine-free heavy top (0.1 s, spherical joint), every method on both
  groups and charts (≈ 1 min);
* ``exudyn_heavy_top`` — the Exudyn heavy top (EP node + spherical joint, 0.5 s) with
  Exudyn's own generalized-α on EP and RotVecLG nodes in the same plot (≈ 5 min: Exudyn's
  runs go up to 128 000 steps); needs the ``exudyn`` extra;
* ``solo12_pd`` — ``pinocchio_robot:solo12 --scenario pd`` (the quadruped under PD control,
  1 s) with the Pinocchio users' loops (semi-implicit Euler + ``pin.integrate``, RK4 and
  DOP853 with renormalization) in the same plot (≈ 2 min); needs the ``robots`` extra.

The JSON and Markdown reports go to a temporary directory (``--out DIR`` keeps them).
Wall times: best of 3 lone runs each."""
import argparse
import shutil
import tempfile
from pathlib import Path

from lgt_bridge import bench

HERE = Path(__file__).resolve().parent
TOLS = [1e-5, 1e-7, 1e-9]
FIGURES = {
    "heavy_top": dict(spec="heavy_top", methods=["rkmk4", "dopri5", "dop853", "genalpha"],
                      groups=["SE3", "SO3xR3"], charts=["exp", "cay"], tols=TOLS, dts=[1e-3, 5e-4, 2.5e-4]),
    "exudyn_heavy_top": dict(spec="exudyn_heavy_top", methods=["rkmk4", "dopri5", "dop853", "genalpha"],
                             groups=["SE3", "SO3xR3"], charts=["exp"], tols=TOLS, dts=[1e-3, 5e-4, 2.5e-4]),
    "solo12_pd": dict(spec="pinocchio_robot:solo12", scenario="pd", methods=["rkmk4", "dop853", "radau5", "genalpha"],
                      groups=["SE3", "SO3xR3"], charts=["exp"], tols=TOLS, dts=[1e-3, 5e-4, 2.5e-4]),
}


def make(name, out):
    """Run one figure's sweep, write its report to ``out`` and copy its two plots here."""
    spec = FIGURES[name]
    ref, rows = bench.sweep(**spec, repeat=3)
    print(bench.write_report(out, spec["spec"], ref, rows))
    stem = bench.report_name(spec["spec"], spec.get("scenario"))
    for plot in ("error_vs_wall", "error_vs_nf"):
        shutil.copyfile(out / f"{stem}_{plot}.png", HERE / f"{name}_{plot}.png")
        print(HERE / f"{name}_{plot}.png")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=list(FIGURES), help="regenerate this figure set only")
    ap.add_argument("--out", default=None, help="keep the sweeps' JSON, Markdown and plots here")
    a = ap.parse_args(argv)
    out = Path(a.out) if a.out else Path(tempfile.mkdtemp(prefix="lgt-figures-"))
    out.mkdir(parents=True, exist_ok=True)
    for name in [a.only] if a.only else FIGURES:
        make(name, out)
    if not a.out:
        shutil.rmtree(out)


if __name__ == "__main__":
    main()
