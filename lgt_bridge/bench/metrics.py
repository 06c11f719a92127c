"""What a sweep measures: a run's errors against the reference end state (pose, velocity,
constraint residual), its energy drift, and, over a sweep's runs, the wall time at a target
error, the cheapest series there and how far "auto" runs are from the front.
"""
import numpy as np

from ..groups import quaternion as _q
from ..groups import so3


#: what "pose error" means in the bench's reports and plots
POSE_ERROR = ("Pose error: at the end time, the largest rotation angle error of a body (rad) plus the largest "
              "position or vector-coordinate error (m), against the reference run.")


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
    for c, s in model.layout.circle_q:               # planar rotations: the angle between them
        e_rot = max(e_rot, abs(float(np.arctan2(q[s] * q_ref[c] - q[c] * q_ref[s], q[c] * q_ref[c] + q[s] * q_ref[s]))))
    return e_rot, e_pos


def end_errors(model, q, q_ref, V=None, V_ref=None):
    """A run's end state against the reference: ``pose_error`` (:func:`pose_error`),
    ``velocity_error`` (largest ‖V - V_ref‖; None without V) and ``constraint_residual``
    (largest ‖g(q)‖; 0 for a model without constraints)."""
    return dict(pose_error=pose_error(model, q, q_ref),
                velocity_error=None if V is None else float(np.abs(V - V_ref).max()),
                constraint_residual=float(np.abs(model.constraints(q)).max()) if model.n_constraints else 0.0)


def energy_drift(model, t, q, V, success):
    """Relative energy drift abs(E - E0) / abs(E0) at up to 60 of a run's output times:
    ``energy_t``, ``energy_drift_t`` and, for a run that succeeded, ``energy_drift`` at
    its end; {} for a model without ``energy`` or a run without output."""
    if not (hasattr(model, "energy") and len(t)):
        return {}
    idx = np.unique(np.linspace(0, len(t) - 1, min(len(t), 60)).astype(int))
    E0 = model.energy(q[0], V[0])
    drift = [float(abs(model.energy(q[i], V[i]) - E0) / max(abs(E0), 1e-300)) for i in idx]
    out = dict(energy_t=t[idx].tolist(), energy_drift_t=drift)
    if success:
        out["energy_drift"] = drift[-1]
    return out


def cost_at_error(points, target):
    """(cost at ``target`` error, exact?) along one series given as (error, cost) pairs:
    log-log interpolation where the runs bracket the target, otherwise the cheapest run at
    or below it (an upper bound, exact = False); (None, False) when no run reaches it."""
    pts = sorted((e, c) for e, c in points if e > 0 and np.isfinite(e) and c)
    for (e1, w1), (e2, w2) in zip(pts, pts[1:]):
        if e1 <= target <= e2:
            f = (np.log(target) - np.log(e1)) / (np.log(e2) - np.log(e1))
            return float(np.exp(np.log(w1) + f * (np.log(w2) - np.log(w1)))), True
    below = [w for e, w in pts if e <= target]
    return (min(below), False) if below else (None, False)


def wall_at_error(rows, target, key="pose_error"):
    """:func:`cost_at_error` of the wall time along one series' successful runs."""
    return cost_at_error([(r[key], r["wall_s"]) for r in rows if r.get("success", True)], target)


def best_at(rows, target):
    """{"bridge": (series, wall, exact), "native": ...}: the cheapest series at ``target``."""
    series = {}
    for r in rows:
        series.setdefault((r["method"], r["group"], r["chart"]), []).append(r)
    best = {}
    for key, rs in series.items():
        w, exact = wall_at_error(rs, target)
        side = "native" if key[1] == "native" else "bridge"
        if w is not None and (side not in best or w < best[side][1]):
            best[side] = (" ".join(key), w, exact)
    return best


def front_gaps(rows):
    """For every "auto" run: its cost (wall time, f evaluations) over the cheapest run at
    least as accurate — among the same method's other group/chart choices (what "auto"
    decides) and among all runs (natives included). ≤ 1 or None (no other run that
    counts the quantity is as accurate): on that front."""
    def ratio(a, pool, key):
        vals = [r[key] for r in pool if r["pose_error"] <= a["pose_error"] and r[key] is not None]
        return a[key] / min(vals) if vals else None
    others = [r for r in rows if r["success"] and r["group"] != "auto"]
    out = []
    for a in rows:
        if a["group"] != "auto" or not a["success"]:
            continue
        same = [r for r in others if r["method"] == a["method"]]
        out.append(dict(method=a["method"], value=a["value"], pose_error=a["pose_error"],
                        wall_ratio_same_method=ratio(a, same, "wall_s"), n_f_ratio_same_method=ratio(a, same, "n_f"),
                        n_f_ratio_all=ratio(a, others, "n_f")))
    return out
