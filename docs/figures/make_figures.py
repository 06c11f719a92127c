"""Regenerate the README's work-precision figures (≈ 1 min on 2 cores):

    python docs/figures/make_figures.py

A ``lgt-bridge bench heavy_top`` sweep (the engine-free heavy top, 0.1 s, spherical
joint) whose two work-precision plots are written here as ``heavy_top_error_vs_wall.png``
and ``heavy_top_error_vs_nf.png``; the JSON and Markdown report go to a temporary
directory (pass ``--out DIR`` to keep them). Wall times: best of 3 lone runs each."""
import argparse
import shutil
import tempfile
from pathlib import Path

from lgt_bridge import bench

HERE = Path(__file__).resolve().parent
SWEEP = dict(spec="heavy_top", methods=["rkmk4", "dopri5", "dop853", "genalpha"], groups=["SE3", "SO3xR3"],
             charts=["exp", "cay"], tols=[1e-5, 1e-7, 1e-9], dts=[1e-3, 5e-4, 2.5e-4])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None, help="keep the sweep's JSON, Markdown and plots here")
    a = ap.parse_args(argv)
    ref, rows = bench.sweep(**SWEEP, repeat=3)
    out = Path(a.out) if a.out else Path(tempfile.mkdtemp(prefix="lgt-figures-"))
    print(bench.write_report(out, SWEEP["spec"], ref, rows))
    for name in ("error_vs_wall", "error_vs_nf"):
        shutil.copyfile(out / f"heavy_top_{name}.png", HERE / f"heavy_top_{name}.png")
        print(HERE / f"heavy_top_{name}.png")
    if not a.out:
        shutil.rmtree(out)


if __name__ == "__main__":
    main()
