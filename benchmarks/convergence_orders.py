"""Fitted convergence orders of the fixed-step bridge methods.

    python benchmarks/convergence_orders.py [--out benchmarks/results]

Free body J = diag(1, 2, 3), ω0 = (0.4, 1, -0.3), T = 1 s, error = rotation angle
against a plain quaternion DOP853 solve at rtol 1e-13 + |ω - ω_analytic|
(Jacobi elliptic functions); heavy top (pivot form), T = 0.02 s, error =
rotation angle against the same kind of plain reference. The order is the
least-squares slope of log(error) against log(dt). Writes orders.json/.md.
"""
import argparse
import itertools
import json
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from lgt_bridge import charts, scenes
from lgt_bridge.analytic import torque_free_omega
from lgt_bridge.simulate import simulate

ORDERS = {"euler": 1, "rkmk2": 2, "rkmk4": 4, "genalpha": 2}
FB_DTS = {"euler": [0.02, 0.01, 0.005, 0.0025], "rkmk2": [0.1, 0.05, 0.025, 0.0125],
          "rkmk4": [0.2, 0.1, 0.05, 0.025], "genalpha": [0.05, 0.025, 0.0125, 0.00625]}
HT_DTS = {"euler": [4e-5, 2e-5, 1e-5, 5e-6], "rkmk2": [2e-4, 1e-4, 5e-5, 2.5e-5],
          "rkmk4": [1e-3, 5e-4, 2.5e-4, 1.25e-4], "genalpha": [2e-4, 1e-4, 5e-5, 2.5e-5]}


def plain_rotation(J, w0, T, torque=None):
    def rhs(t, y):
        p, w = y[:4], y[4:]
        R = Rotation.from_quat(p / np.linalg.norm(p), scalar_first=True).as_matrix()
        pd = 0.5 * np.concatenate([[-p[1:] @ w], p[0] * w + np.cross(p[1:], w)])
        tq = torque(R) if torque else 0.0
        return np.concatenate([pd, np.linalg.solve(J, -np.cross(w, J @ w) + tq)])
    s = solve_ivp(rhs, (0, T), np.concatenate([[1.0, 0, 0, 0], w0]), method="DOP853", rtol=1e-13, atol=1e-13)
    p = s.y[:4, -1]
    return Rotation.from_quat(p / np.linalg.norm(p), scalar_first=True).as_matrix(), s.y[4:, -1]


def angle(A, B):
    return float(np.linalg.norm(Rotation.from_matrix(A.T @ B).as_rotvec()))


def R_of(m, q):
    b = m.layout.bodies[0]
    return b.param.alpha(q[[*b.pos, *b.rot]])[:3, :3]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    a = ap.parse_args(argv)
    J, w0 = np.array([1.0, 2.0, 3.0]), np.array([0.4, 1.0, -0.3])
    Rfb, _ = plain_rotation(np.diag(J), w0, 1.0)
    wfb = torque_free_omega(1.0, J, w0)[0]
    c, m_, g = np.array([0.0, 1.0, 0.0]), 15.0, np.array([0, 0, -9.81])
    Jp = np.diag([0.234375, 0.46875, 0.234375]) + m_ * (np.eye(3) - np.outer(c, c))
    Rht, _ = plain_rotation(Jp, np.array([0.0, 150.0, -4.61538]), 0.02, lambda R: np.cross(c, R.T @ (m_ * g)))
    rows = []
    for method, (group, chart) in itertools.product(ORDERS, itertools.product(["SE3", "SO3xR3"], charts.NAMES)):
        for scene, dts in (("free body", FB_DTS[method]), ("heavy top", HT_DTS[method])):
            errs = []
            for dt in dts:
                if scene == "free body":
                    mdl = scenes.free_body(J, w0)
                    r = simulate(mdl, (0, 1.0), method=method, group=group, chart=chart, dt=dt)
                    errs.append(angle(R_of(mdl, r.q[-1]), Rfb) + np.abs(r.V[-1, :3] - wfb).max())
                else:
                    mdl = scenes.heavy_top(False)
                    r = simulate(mdl, (0, 0.02), method=method, group=group, chart=chart, dt=dt)
                    errs.append(angle(R_of(mdl, r.q[-1]), Rht))
            order = float(np.polyfit(np.log(dts), np.log(errs), 1)[0])
            rows.append(dict(method=method, group=group, chart=chart, scene=scene, dts=dts, errors=errs,
                             fitted_order=order, theory=ORDERS[method]))
            print(f"{method:9s} {group:7s} {chart:4s} {scene:10s} order {order:5.2f} (theory {ORDERS[method]})")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "orders.json").write_text(json.dumps(rows, indent=1))
    lines = ["# Fitted convergence orders", "", "| method | group | chart | free body | heavy top | theory |",
             "|---|---|---|---:|---:|---:|"]
    for k in range(0, len(rows), 2):
        f, h = rows[k], rows[k + 1]
        lines.append(f"| {f['method']} | {f['group']} | {f['chart']} | {f['fitted_order']:.2f} | "
                     f"{h['fitted_order']:.2f} | {f['theory']} |")
    (out / "orders.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
