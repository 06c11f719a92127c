"""``lgt-bridge demo``: the heavy top on several method x group x chart choices."""
import sys


def run(a):
    from .. import demo
    demo.run(sys.stdout, T=a.T, param=a.param, constrained=not a.pivot)
    return 0


def add_parser(sub):
    from .options import DEBUG
    d = sub.add_parser("demo", help="heavy top on several method x group x chart choices: "
                       "error against a tight reference, f evaluations, wall time")
    d.add_argument("--T", type=float, default=0.1, help="end time in s (default 0.1)")
    d.add_argument("--param", default="quat", choices=["quat", "rotvec", "rxyz"],
                   help="absolute rotation coordinates of the top (default quat)")
    d.add_argument("--pivot", action="store_true", help="frame at the pivot instead of the joint form")
    d.add_argument("--debug", **DEBUG)
    return d
