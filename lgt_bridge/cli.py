"""Command line: ``lgt-bridge demo`` (more subcommands join as they land)."""
import argparse
import sys


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
    a = ap.parse_args(argv)
    if a.cmd in (None, "demo"):
        from . import demo
        demo.run(sys.stdout, T=getattr(a, "T", 0.1), param=getattr(a, "param", "quat"),
                 constrained=not getattr(a, "pivot", False))
        return 0
    return 2


if __name__ == "__main__":
    sys.exit(main())
