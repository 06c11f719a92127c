"""Work-precision of Exudyn models: Exudyn's own generalized-α vs the bridge.

    python benchmarks/bench_exudyn.py [--out benchmarks/results] [--quick]

Scenes (built with Exudyn as users write them, tests/exudyn_models.py):
  heavy top, EP node + spherical joint, t = 0 … 0.5 s;
  chain of 20 links with spherical joints, t = 0 … 1 s.
Reference: the engine-free twin of each scene (lgt_bridge.scenes) integrated by the bridge's
dopri5 at rtol = atol = 1e-12 (for the top also checked against a plain quaternion DOP853).
Error = largest body rotation angle + largest position error at the end time.
For every run: wall time, f evaluations, and for bridge runs the time inside Exudyn's own
calls (Compute*/Get*/Set* on the solver and system data, timed by a proxy); the overhead
ratio is (wall - inside) / inside. The wall time each family needs for error 1e-6 is
interpolated log-log along its curve. Writes exudyn_work_precision.{json,md}.
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import exudyn_models as em  # noqa: E402

from lgt_bridge import scenes  # noqa: E402
from lgt_bridge.groups import so3  # noqa: E402
from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_exudyn import ExudynModel  # noqa: E402

from lgt_bridge.bench import wall_at_error  # noqa: E402


class Timer:
    def __init__(self):
        self.inside = 0.0


class Proxy:
    """Times every method call on the wrapped Exudyn object."""

    def __init__(self, obj, timer):
        self._obj, self._timer = obj, timer

    def __getattr__(self, name):
        attr = getattr(self._obj, name)
        if not callable(attr):
            return attr
        timer = self._timer

        def call(*a, **k):
            t0 = time.perf_counter()
            try:
                return attr(*a, **k)
            finally:
                timer.inside += time.perf_counter() - t0
        return call


def error(layout_model, q, q_ref):
    eR = er = 0.0
    for b in layout_model.layout.bodies:
        R = b.param.alpha(q[[*b.pos, *b.rot]])[:3, :3]
        Rr = b.param.alpha(q_ref[[*b.pos, *b.rot]])[:3, :3]
        eR = max(eR, float(np.linalg.norm(so3.log(R.T @ Rr))))
        er = max(er, float(np.abs(q[list(b.pos)] - q_ref[list(b.pos)]).max()))
    return eR + er


def native(make, T, n, rotvec=False):
    SC, mbs = make()[:2]
    s = em.settings(T, n)
    if rotvec:
        s.timeIntegration.generalizedAlpha.lieGroupSimplifiedKinematicRelations = True
    t0 = time.perf_counter()
    mbs.SolveDynamic(s)
    return em.total_q(mbs), time.perf_counter() - t0


def bridge(make, T, method, group, chart, **kw):
    SC, mbs = make()[:2]
    model = ExudynModel(mbs)
    timer = Timer()
    model.solver, model.sd = Proxy(model.solver, timer), Proxy(model.sd, timer)
    t0 = time.perf_counter()
    r = simulate(model, (0, T), method=method, group=group, chart=chart, t_eval=[T], **kw)
    wall = time.perf_counter() - t0
    return r, wall, timer.inside, model


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--quick", action="store_true", help="fewer runs (CI smoke)")
    a = ap.parse_args(argv)
    cases = {
        "heavy top + joint": dict(make=lambda: em.heavy_top(em.EP), make_rv=lambda: em.heavy_top(em.ROTVEC),
                                  twin=lambda: scenes.heavy_top(True), T=0.5,
                                  twin_rv=lambda: scenes.heavy_top(True, param="rotvec"),
                                  native_n=[2000, 8000, 32000, 128000], tols=[1e-5, 1e-7, 1e-9],
                                  dts=[1e-3, 5e-4, 2.5e-4]),
        "chain of 20": dict(make=lambda: em.chain(20), make_rv=lambda: em.chain(20, em.ROTVEC),
                            twin=lambda: scenes.chain(20), T=1.0,
                            twin_rv=lambda: scenes.chain(20, param="rotvec"),
                            native_n=[250, 1000, 4000, 16000], tols=[1e-5, 1e-7, 1e-9],
                            dts=[1e-2, 5e-3, 2.5e-3]),
    }
    if a.quick:
        for c in cases.values():
            c["native_n"], c["tols"], c["dts"] = c["native_n"][:2], c["tols"][:1], c["dts"][:1]
    rows, summary = [], []
    for name, c in cases.items():
        T = c["T"]
        twin = c["twin"]()
        t0 = time.perf_counter()
        ref = simulate(twin, (0, T), method="dopri5", rtol=1e-12, atol=1e-12, t_eval=[T])
        print(f"{name}: reference {time.perf_counter() - t0:.1f} s, {ref.stats['n_steps']} steps")
        qref = ref.q[-1]
        twin_rv = c["twin_rv"]()
        qref_rv = _to_rotvec_ref(twin, qref)
        for n in c["native_n"]:
            for rv in (False, True):
                q, wall = native(c["make_rv"] if rv else c["make"], T, n, rotvec=rv)
                e = error(twin_rv if rv else twin, q, qref_rv if rv else qref)
                rows.append(dict(scene=name, family="Exudyn GA " + ("RotVecLG" if rv else "EP"), setting=f"h={T / n:.2e}",
                                 error=e, wall_s=wall, n_f=None, overhead_ratio=None))
                print(f"  {rows[-1]['family']:28s} {rows[-1]['setting']:14s} error {e:9.2e}  wall {wall:8.3f} s")
        runs = [("dopri5", g, ch, dict(rtol=t, atol=t), f"tol={t:g}") for t in c["tols"]
                for g in ("SE3", "SO3xR3") for ch in ("exp", "cay")]
        runs += [("rkmk4", "SO3xR3", "exp", dict(dt=d), f"dt={d:g}") for d in c["dts"]]
        runs += [("genalpha", "SO3xR3", "exp", dict(dt=d / 4), f"dt={d / 4:g}") for d in c["dts"][:2]]
        for method, g, ch, kw, setting in runs:
            r, wall, inside, model = bridge(c["make"], T, method, g, ch, **kw)
            e = error(twin, r.q[-1], qref) if r.success else float("nan")
            rows.append(dict(scene=name, family=f"bridge {method} {g} {ch}", setting=setting, error=e, wall_s=wall,
                             n_f=r.stats["n_f"], inside_exudyn_s=inside,
                             overhead_ratio=(wall - inside) / inside if inside else None))
            print(f"  {rows[-1]['family']:28s} {setting:14s} error {e:9.2e}  wall {wall:8.3f} s  "
                  f"n_f {r.stats['n_f']:6d}  overhead {(wall - inside) / inside:6.1f}")
        fams = sorted({r["family"] for r in rows if r["scene"] == name})
        best = {}
        for f in fams:
            w, exact = wall_at_error([r for r in rows if r["scene"] == name and r["family"] == f], 1e-6, key="error")
            if w is not None:
                best[f] = (w, exact)
        nat = {f: w for f, w in best.items() if f.startswith("Exudyn")}
        br = {f: w for f, w in best.items() if f.startswith("bridge")}
        line = f"{name}: wall time at error 1e-6 — "
        if nat and br:
            fn, (wn, xn) = min(nat.items(), key=lambda kv: kv[1][0])
            fb, (wb, xb) = min(br.items(), key=lambda kv: kv[1][0])
            line += (f"best native {fn} {'' if xn else '≤ '}{wn:.3f} s, best bridge {fb} {'' if xb else '≤ '}"
                     f"{wb:.3f} s, ratio native/bridge {wn / wb:.2f} (≤: cheapest run below 1e-6, not bracketed)")
        else:
            line += f"not bracketed by the runs (native: {nat}, bridge: {br})"
        summary.append(line)
        print(line)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "exudyn_work_precision.json").write_text(json.dumps(dict(rows=rows, summary=summary), indent=1))
    lines = ["# Exudyn models: work-precision", "", *[f"- {s}" for s in summary], "",
             "| scene | family | setting | error | wall s | f evals | overhead ratio |", "|---|---|---|---:|---:|---:|---:|"]
    for r in rows:
        ov = f"{r['overhead_ratio']:.1f}" if r.get("overhead_ratio") else ""
        lines.append(f"| {r['scene']} | {r['family']} | {r['setting']} | {r['error']:.2e} | {r['wall_s']:.3f} | "
                     f"{r['n_f'] or ''} | {ov} |")
    (out / "exudyn_work_precision.md").write_text("\n".join(lines) + "\n")


def _to_rotvec_ref(twin, qref):
    """The reference in rotation-vector coordinates (position, ρ) for the RotVecLG runs."""
    from lgt_bridge import params
    out = []
    for b in twin.layout.bodies:
        p = b.param._to_quat(qref[list(b.rot)][None])
        out.append(np.concatenate([qref[list(b.pos)], params.ROTVEC._from_quat(p, np.zeros((1, 3)))[0]]))
    return np.concatenate(out)


if __name__ == "__main__":
    main()
