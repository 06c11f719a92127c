"""Cost of one PinocchioModel.f against one pin.aba, both backends (issue 12: f ≤ aba + 1.5 µs).

    python benchmarks/bench_pinocchio_f.py [--out benchmarks/results] [--repeats 25] [--quick]

Models: a free asymmetric body, pin.buildSampleModelHumanoidRandom() (pin.seed(0)) and,
when the ``example-robot-data-loaders`` package is installed (``pip install
'lgt-bridge[robots]'``; its URDFs load offline), solo12, go2, anymal and talos. State: a
seeded random configuration (the neutral one moved by a random twist) and a random twist.
Each figure is the best, over ``--repeats`` interleaved repeats, of the mean time per call
in a loop of n calls (n chosen for ≈ 5 ms a loop), in one process: pin.aba(model, data,
q, v, 0) with Pinocchio's own v, then f(q, V, t) on the compiled (numba) and the numpy
backend. No assertions: this measures. Writes pinocchio_f.{json,md}.
"""
import argparse
import json
import os
import platform
import time
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin

from lgt_pinocchio import PinocchioModel

ROBOTS = ("solo12", "go2", "anymal", "talos")


def free_body():
    m = pin.Model()
    j = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    m.appendBodyToJoint(j, pin.Inertia(1.0, np.zeros(3), np.diag([1.0, 2.0, 3.0])), pin.SE3.Identity())
    return m


def humanoid():
    pin.seed(0)
    return pin.buildSampleModelHumanoidRandom()


def robot(name):
    def make():
        import example_robot_data as erd
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return erd.load(name).model
    return make


def cases(quick):
    out = {"free body": free_body, "sample humanoid": humanoid}
    if quick:
        return out
    try:
        import example_robot_data  # noqa: F401
    except ImportError:
        print("example_robot_data not installed: robots skipped (pip install example-robot-data-loaders)")
        return out
    out.update({name: robot(name) for name in ROBOTS})
    return out


def per_call(fn, n):
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - t0) / n


def measure(model, repeats, rng):
    data = model.createData()
    comp = PinocchioModel(model, backend="numba")
    ref = PinocchioModel(model, backend="numpy")
    q = ref._moved(ref.q0, rng.normal(size=model.nv))
    V = rng.normal(size=model.nv)
    v = ref.v_from_twist(q, V)
    tau = np.zeros(model.nv)
    err = float(np.abs(comp.f(q, V, 0.0) - ref.f(q, V, 0.0)).max() / np.abs(ref.f(q, V, 0.0)).max())
    fns = {"aba": lambda: pin.aba(model, data, q, v, tau),
           "f_numba": lambda: comp.f(q, V, 0.0),
           "f_numpy": lambda: ref.f(q, V, 0.0)}
    ns = {}
    for k, fn in fns.items():                     # warm up and size the loops (≈ 5 ms each)
        t = per_call(fn, 50)
        ns[k] = max(20, int(0.005 / max(t, 1e-8)))
    best = {k: np.inf for k in fns}
    for _ in range(repeats):
        for k, fn in fns.items():
            best[k] = min(best[k], per_call(fn, ns[k]))
    us = {k: 1e6 * x for k, x in best.items()}
    return dict(nq=model.nq, nv=model.nv, njoints=model.njoints, aba_us=us["aba"], f_numba_us=us["f_numba"],
                f_numpy_us=us["f_numpy"], numba_over_aba_us=us["f_numba"] - us["aba"],
                numpy_over_aba_us=us["f_numpy"] - us["aba"], f_numba_ratio=us["f_numba"] / us["aba"],
                f_numpy_ratio=us["f_numpy"] / us["aba"], max_rel_diff=err, calls_per_loop=ns)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--repeats", type=int, default=25)
    ap.add_argument("--quick", action="store_true", help="free body and humanoid only, 3 repeats")
    a = ap.parse_args(argv)
    repeats = 3 if a.quick else a.repeats
    rows = []
    for name, make in cases(a.quick).items():
        r = dict(model=name, **measure(make(), repeats, np.random.default_rng(1)))
        rows.append(r)
        print(f"{name:16s} nv {r['nv']:3d}  aba {r['aba_us']:7.2f} µs  f numba {r['f_numba_us']:7.2f} µs "
              f"(+{r['numba_over_aba_us']:.2f})  f numpy {r['f_numpy_us']:7.2f} µs (+{r['numpy_over_aba_us']:.2f})")
    import numba
    env = dict(python=platform.python_version(), pin=pin.__version__, numpy=np.__version__,
               numba=numba.__version__, machine=platform.machine(), cpus=os.cpu_count(),
               load_average=os.getloadavg() if hasattr(os, "getloadavg") else None, repeats=repeats)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "pinocchio_f.json").write_text(json.dumps(dict(env=env, rows=rows), indent=1))
    lines = ["# PinocchioModel.f against pin.aba (µs per call, best of "
             f"{repeats} interleaved repeats, one process)", "",
             f"pin {env['pin']}, numba {env['numba']}, numpy {env['numpy']}, Python {env['python']}, "
             f"{env['cpus']} CPUs, load average {env['load_average']}.", "",
             "| model | nv | pin.aba | f (numba) | f − aba | f (numpy) | f − aba | numba/numpy max rel. diff |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    lines += [f"| {r['model']} | {r['nv']} | {r['aba_us']:.2f} | {r['f_numba_us']:.2f} | {r['numba_over_aba_us']:.2f} | "
              f"{r['f_numpy_us']:.2f} | {r['numpy_over_aba_us']:.2f} | {r['max_rel_diff']:.1e} |" for r in rows]
    (out / "pinocchio_f.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
