"""Work-precision of Pinocchio free-flyer models: user baselines vs the bridge.

    python benchmarks/bench_pinocchio.py [--out benchmarks/results] [--quick]

Scenes: the free asymmetric body (I = diag(1, 2, 3), ω0 = (0.01, 2, 0.01), 10 s: the
Dzhanibekov flip) and buildSampleModelHumanoidRandom() floating under gravity with zero
torques (1 s). Baselines, as users write them (shared/notes/pinocchio.md): semi-implicit
Euler + pin.integrate; fixed-step RK4 on (q, v) with quaternion renormalization; scipy DOP853
with renormalization. Reference: DOP853 at rtol = atol = 1e-13 (for the free body also
checked against the Jacobi-elliptic solution). Pose error: root rotation angle + largest
position / joint-coordinate error. Bridge overhead = (wall - n_aba * t_aba) / (n_aba * t_aba),
t_aba measured in the same run. Writes pinocchio_work_precision.{json,md}.
"""
import argparse
import json
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
from scipy.spatial.transform import Rotation

from lgt_bridge import simulate
from lgt_pinocchio import PinocchioModel
from lgt_pinocchio.baselines import dop853_renorm, free_body, humanoid, rk4_renorm, root_R, semi_implicit_euler

from lgt_bridge.bench import wall_at_error


def pose_error(q, qref):
    R, Rr = root_R(q), root_R(qref)
    ang = float(np.linalg.norm(Rotation.from_matrix(R.T @ Rr).as_rotvec()))
    other = np.abs(np.concatenate([q[:3] - qref[:3], q[7:] - qref[7:]]))
    return ang + (float(other.max()) if other.size else 0.0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(argv)
    cases = {"free asymmetric body, 10 s": (free_body, 10.0, [1e-2, 4e-3, 1e-3], [1e-6, 1e-8, 1e-10]),
             "floating humanoid, 1 s": (humanoid, 1.0, [1e-3, 4e-4, 1e-4], [1e-6, 1e-8, 1e-10])}
    rows, summary = [], []
    for name, (make, T, dts, tols) in cases.items():
        if a.quick:
            dts, tols = dts[:1], tols[:1]
        model, q0, v0 = make()
        qref, _ = dop853_renorm(model, q0, v0, T, 1e-13)
        data = model.createData()
        n = 2000
        t0 = time.perf_counter()
        for _ in range(n):
            pin.aba(model, data, q0, v0, np.zeros(model.nv))
        t_aba = (time.perf_counter() - t0) / n
        print(f"{name}: t_aba = {1e6 * t_aba:.2f} µs")

        def add(family, setting, fn):
            t0 = time.perf_counter()
            q, n_aba = fn()
            wall = time.perf_counter() - t0
            rows.append(dict(scene=name, family=family, setting=setting, error=pose_error(q, qref), wall_s=wall,
                             n_aba=n_aba, overhead=(wall - n_aba * t_aba) / (n_aba * t_aba)))
            r = rows[-1]
            print(f"  {family:26s} {setting:12s} error {r['error']:9.2e} wall {wall:8.3f} s  ABA {n_aba:7d}  "
                  f"overhead {r['overhead']:6.2f}")

        for dt in dts:
            add("semi-implicit Euler", f"dt={dt / 10:g}", lambda dt=dt: semi_implicit_euler(model, q0, v0, T, dt / 10))
            add("RK4 + renormalization", f"dt={dt:g}", lambda dt=dt: rk4_renorm(model, q0, v0, T, dt))
        for tol in tols:
            add("scipy DOP853 + renorm.", f"tol={tol:g}", lambda tol=tol: dop853_renorm(model, q0, v0, T, tol))
        pm = PinocchioModel(model, q0=q0, v0=v0)

        def bridge(method, group, chart, **kw):
            r = simulate(pm, (0, T), method=method, group=group, chart=chart, t_eval=[T], **kw)
            return r.q[-1], r.stats["n_f"]

        for group in ("SE3", "SO3xR3"):
            for chart in ("exp", "cay"):
                for dt in dts:
                    add(f"bridge rkmk4 {group} {chart}", f"dt={dt:g}", lambda dt=dt: bridge("rkmk4", group, chart, dt=dt))
                for tol in tols:
                    add(f"bridge dopri5 {group} {chart}", f"tol={tol:g}",
                        lambda tol=tol: bridge("dopri5", group, chart, rtol=tol, atol=tol))
        sub = [r for r in rows if r["scene"] == name]
        fams = sorted({r["family"] for r in sub})
        w = {f: wall_at_error([r for r in sub if r["family"] == f], 1e-8, key="error") for f in fams}
        base = {f: x for f, x in w.items() if x[0] and not f.startswith("bridge")}
        br = {f: x for f, x in w.items() if x[0] and f.startswith("bridge")}
        ov = [r["overhead"] for r in sub if r["family"].startswith("bridge")]
        line = f"{name}: "
        if base and br:
            fb, (wb, xb) = min(base.items(), key=lambda kv: kv[1][0])
            fr, (wr, xr) = min(br.items(), key=lambda kv: kv[1][0])
            line += (f"at pose error 1e-8 best baseline {fb} {'' if xb else '≤ '}{wb:.3f} s, best bridge {fr} "
                     f"{'' if xr else '≤ '}{wr:.3f} s, speed-up {wb / wr:.2f}x (≤ marks the cheapest run below "
                     "1e-8 where the runs do not bracket it)")
        else:
            line += f"1e-8 not bracketed (baselines {base}, bridge {br})"
        line += f"; bridge overhead over ABA {min(ov):.1f} … {max(ov):.1f}"
        summary.append(line)
        print(line)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "pinocchio_work_precision.json").write_text(json.dumps(dict(rows=rows, summary=summary), indent=1))
    lines = ["# Pinocchio models: work-precision", "", *[f"- {s}" for s in summary], "",
             "| scene | family | setting | pose error | wall s | ABA calls | overhead over ABA |",
             "|---|---|---|---:|---:|---:|---:|"]
    lines += [f"| {r['scene']} | {r['family']} | {r['setting']} | {r['error']:.2e} | {r['wall_s']:.3f} | "
              f"{r['n_aba']} | {r['overhead']:.1f} |" for r in rows]
    (out / "pinocchio_work_precision.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
