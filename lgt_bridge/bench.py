"""Work-precision sweeps: ``lgt-bridge bench SCENE``.

Every combination of method x group x chart x setting (tolerance for adaptive
methods, step for fixed-step ones) runs on the scene; each run's end state is
compared with a tight reference (dopri5 on SE(3)/exp at rtol = atol = 1e-12,
stated in the report). Runs execute in parallel worker processes. Output: a JSON of
every run and a Markdown table.

A scene is a built-in name (see SCENES) or ``path/to/file.py:function`` where the
function returns ``(model, t_end)``.
"""
import importlib.util
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from . import scenes as _scenes
from .errors import InputError
from .groups import quaternion as _q
from .groups import so3
from .simulate import simulate

SCENES = {
    "heavy_top": (lambda: _scenes.heavy_top(True), 0.1),
    "heavy_top_pivot": (lambda: _scenes.heavy_top(False), 0.1),
    "free_body": (lambda: _scenes.free_body((1.0, 2.0, 3.0), (0.01, 2.0, 0.01)), 10.0),
    "chain": (lambda: _scenes.chain(5), 1.0),
}
FIXED = ("euler", "rkmk2", "rkmk4", "genalpha")
REFERENCE = dict(method="dopri5", group="SE3", chart="exp", rtol=1e-12, atol=1e-12)


def load_scene(spec):
    """(model, t_end) from a built-in name or 'file.py:function'."""
    if spec in SCENES:
        make, T = SCENES[spec]
        return make(), T
    if ":" in spec:
        path, fn = spec.rsplit(":", 1)
        if Path(path).is_file():
            s = importlib.util.spec_from_file_location("lgt_bench_user_scene", path)
            mod = importlib.util.module_from_spec(s)
            s.loader.exec_module(mod)
            if not hasattr(mod, fn):
                raise InputError(f"bench: {path} has no function {fn!r}; it must return (model, t_end).")
            out = getattr(mod, fn)()
            if not (isinstance(out, tuple) and len(out) == 2):
                raise InputError(f"bench: {spec} must return (model, t_end), got {type(out).__name__}.")
            return out
    raise InputError(f"bench: unknown scene {spec!r}; use one of {sorted(SCENES)} or "
                     "'path/to/file.py:function' returning (model, t_end).")


def pose_error(model, q, q_ref):
    """Largest body rotation angle + largest position error (+ vector coordinates)."""
    return sum(pose_errors(model, q, q_ref))


def pose_errors(model, q, q_ref):
    """(largest body rotation angle, largest position / vector-coordinate error)."""
    e_rot = e_pos = 0.0
    for b in model.layout.bodies:
        if b.rotation_only:
            p = b.param._to_quat(q[list(b.rot)][None])
            pr = b.param._to_quat(q_ref[list(b.rot)][None])
            ang = float(np.linalg.norm(_q._to_rotvec(_q._mul(_q._conj(pr), p))[0]))
        else:
            R = b.param.alpha(q[[*b.pos, *b.rot]])[:3, :3]
            Rr = b.param.alpha(q_ref[[*b.pos, *b.rot]])[:3, :3]
            ang = float(np.linalg.norm(so3.log(R.T @ Rr)))
            e_pos = max(e_pos, float(np.abs(q[list(b.pos)] - q_ref[list(b.pos)]).max()))
        e_rot = max(e_rot, ang)
    vq = list(model.layout.vector_q)
    if vq:
        e_pos = max(e_pos, float(np.abs(q[vq] - q_ref[vq]).max()))
    return e_rot, e_pos


def _one(spec, method, group, chart, setting, q_ref, V_ref):
    model, T = load_scene(spec)
    kw = dict(dt=setting) if method in FIXED else dict(rtol=setting, atol=setting)
    t0 = time.perf_counter()
    r = simulate(model, (0.0, T), method=method, group=group, chart=chart, t_eval=[0.0, T], **kw)
    wall = time.perf_counter() - t0
    row = dict(method=method, group=group, chart=chart, setting=("dt" if method in FIXED else "tol"),
               value=setting, success=r.success, message=r.message, wall_s=wall,
               n_f=r.stats["n_f"], n_steps=r.stats["n_steps"], n_rejected=r.stats["n_rejected"])
    if r.success:
        row["pose_error"] = pose_error(model, r.q[-1], q_ref)
        row["velocity_error"] = float(np.abs(r.V[-1] - V_ref).max())
        row["constraint_residual"] = float(np.abs(model.constraints(r.q[-1])).max()) if model.n_constraints else 0.0
        if hasattr(model, "energy"):
            E0, E1 = model.energy(r.q[0], r.V[0]), model.energy(r.q[-1], r.V[-1])
            row["energy_drift"] = float(abs(E1 - E0) / max(abs(E0), 1e-300))
    return row


def sweep(spec, methods, groups, charts, tols, dts, workers=None, progress=True):
    """Run the sweep; returns (reference dict, rows)."""
    model, T = load_scene(spec)
    t0 = time.perf_counter()
    ref = simulate(model, (0.0, T), t_eval=[0.0, T], **REFERENCE)
    if not ref.success:
        raise InputError(f"bench: the reference run failed ({ref.message}).")
    reference = dict(REFERENCE, n_steps=ref.stats["n_steps"], wall_s=time.perf_counter() - t0, t_end=T)
    jobs = [(spec, m, g, c, s, ref.q[-1], ref.V[-1]) for m in methods for g in groups for c in charts
            for s in (dts if m in FIXED else tols)]
    rows = []
    workers = workers or os.cpu_count() or 1
    if workers == 1:
        for k, j in enumerate(jobs):
            rows.append(_one(*j))
            _bar(progress, k + 1, len(jobs))
    else:
        with ProcessPoolExecutor(max_workers=workers) as ex:
            futs = [ex.submit(_one, *j) for j in jobs]
            for k, f in enumerate(as_completed(futs)):
                rows.append(f.result())
                _bar(progress, k + 1, len(jobs))
    rows.sort(key=lambda r: (r["method"], r["group"], r["chart"], -r["value"]))
    return reference, rows


def _bar(on, k, n):
    if on:
        sys.stderr.write(f"\r[{'#' * int(30 * k / n):<30}] {k}/{n} runs")
        if k == n:
            sys.stderr.write("\n")
        sys.stderr.flush()


def write_report(out, spec, reference, rows):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    name = Path(spec.split(":")[0]).stem if ":" in spec else spec
    (out / f"bench_{name}.json").write_text(json.dumps(dict(scene=spec, reference=reference, runs=rows), indent=1))
    lines = [f"# Work-precision: {spec}", "",
             f"Reference: {reference['method']} on {reference['group']}/{reference['chart']} at rtol = atol = "
             f"{reference['rtol']:g}, t = 0 … {reference['t_end']:g} ({reference['n_steps']} steps).", "",
             "| method | group | chart | setting | pose error | velocity error | constraint | energy drift | f evals | steps | wall s |",
             "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if r["success"]:
            lines.append(f"| {r['method']} | {r['group']} | {r['chart']} | {r['setting']}={r['value']:g} | "
                         f"{r['pose_error']:.2e} | {r['velocity_error']:.2e} | {r['constraint_residual']:.1e} | "
                         f"{r.get('energy_drift', float('nan')):.1e} | {r['n_f']} | {r['n_steps']} | {r['wall_s']:.3f} |")
        else:
            lines.append(f"| {r['method']} | {r['group']} | {r['chart']} | {r['setting']}={r['value']:g} | "
                         f"failed: {r['message']} | | | | {r['n_f']} | {r['n_steps']} | {r['wall_s']:.3f} |")
    path = out / f"bench_{name}.md"
    path.write_text("\n".join(lines) + "\n")
    return path
