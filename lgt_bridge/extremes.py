"""The extremes suite: measurements at the edges of what the bridge is for.

Each case returns rows of measured numbers against an independent reference (the
matrix exponential, the analytic torque-free solution, a quaternion run, the
conserved energy). ``tests/core/test_extremes.py`` asserts bounds on the same
measurements; ``lgt-bridge bench extremes`` writes them as a report.
"""
import time

import numpy as np
import scipy.linalg as sla

from . import lgt as _lgt
from . import scenes
from .analytic import torque_free_omega
from .errors import ChartDomainError
from .groups import quaternion as _q
from .groups import se3, so3
from .simulate import simulate

#: per-step rotation angles of the update-accuracy case (exp chart)
ANGLES = (1e-12, 1e-8, 1e-4, 1e-1, 1.0, 3.0, np.pi - 1e-9, np.pi, np.pi + 1e-9, 4.0, 2 * np.pi - 1e-3,
          2 * np.pi + 0.5, 10.0)


def _angle(R1, R2):
    return float(np.linalg.norm(so3.log(R1.T @ R2)))


def update_cases(seed=0):
    """(param, group, |x|, q_k, X) for the update-accuracy case."""
    rng = np.random.default_rng(seed)
    out = []
    for param in ("quat", "rotvec", "rxyz"):
        for group in ("SE3", "SO3xR3"):
            for phi in ANGLES:
                p = rng.normal(size=4)
                R_k = _q._to_matrix((p / np.linalg.norm(p))[None])[0]
                q_k = np.concatenate([rng.normal(size=3), scenes._rot_coords(_lgt.params.get(param), R_k)[0]])
                u = rng.normal(size=3)
                X = np.concatenate([phi * u / np.linalg.norm(u), rng.normal(size=3)])
                out.append((param, group, phi, q_k, X))
    return out


def update_accuracy(reference=None):
    """Rotation and position error of one update τ(q_k, X) against α(q_k)·exp(X̂)
    (``reference(H_k, X, group) -> H`` defaults to scipy's expm in double)."""
    def expm_ref(H_k, X, group):
        if group == "SE3":
            return H_k @ sla.expm(se3.hat6(X))
        H = H_k.copy()
        H[:3, :3] = H_k[:3, :3] @ sla.expm(so3.hat(X[:3]))
        H[:3, 3] += X[3:]
        return H
    reference = reference or expm_ref
    rows = []
    for param, group, phi, q_k, X in update_cases():
        L = _lgt.LGT(param, group, "exp")
        H_k = L.param.alpha(q_k)
        q1 = L.tau(q_k[None], X[None])[0]
        H = L.param.alpha(q1)
        # Tait-Bryan angles are recovered from R with conditioning 1/|cos θ2|
        cond = 1.0 / abs(np.cos(q1[4])) if param == "rxyz" else 1.0
        H_ref = reference(H_k, X, group)
        rows.append(dict(param=param, group=group, step_angle=phi, conditioning=cond, rotation_error=_angle(H[:3, :3], H_ref[:3, :3]),
                         position_error=float(np.abs(H[:3, 3] - H_ref[:3, 3]).max()
                                              / max(1.0, np.abs(H_ref[:3, 3]).max()))))
    return rows


def _spinning_top(param="quat"):
    """Symmetric body spinning about its symmetry axis z at 100 rad/s: R(t) = Rz(100 t)."""
    return scenes.free_body((2.0, 2.0, 1.0), (0.0, 0.0, 100.0), param=param)


def cayley_half_turn():
    """Cayley chart with steps that rotate towards a half-turn: fixed steps must raise
    ChartDomainError (keeping the steps done), the adaptive method must shrink its steps."""
    rows = []
    T = 0.2
    exact = so3.exp(np.array([0.0, 0.0, 100.0 * T]))
    for dt in (0.005, 0.012, 0.025):            # 0.5, 1.2, 2.5 rad per step
        m = _spinning_top()
        row = dict(case="rkmk4 fixed, cay", step_angle=100 * dt)
        try:
            r = simulate(m, (0, T), method="rkmk4", dt=dt, chart="cay")
            row.update(outcome="completed", rotation_error=_angle(m.param.alpha(r.q[-1])[:3, :3], exact))
        except ChartDomainError as e:
            row.update(outcome="ChartDomainError", steps_kept=len(e.result.t) - 1,
                       t_reached=float(e.result.t[-1]), message=str(e))
        rows.append(row)
    m = _spinning_top()
    r = simulate(m, (0, T), method="dopri5", chart="cay", dt=0.03, rtol=1e-9, atol=1e-9)
    rows.append(dict(case="dopri5 adaptive, cay (first step 3 rad)", step_angle=3.0, outcome="completed"
                     if r.success else r.message, rejected=r.stats["n_rejected"],
                     max_step_angle=float(100 * np.diff(r.t).max()),
                     rotation_error=_angle(m.param.alpha(r.q[-1])[:3, :3], exact)))
    return rows


def singular_coordinates():
    """Tait-Bryan through ±π/2 and rotation vectors through 2π, against the quaternion run."""
    rows = []
    ts = np.linspace(0, 2.0, 201)
    for param, w0, what in (("rxyz", (0.0, 3.0, 0.0), "Tait-Bryan angle θ2 through ±π/2"),
                            ("rotvec", (0.1, 0.2, 10.0), "rotation vector |ρ| through 2π")):
        ref = scenes.free_body((1.0, 2.0, 3.0), w0)
        rq = simulate(ref, (0, 2.0), method="dopri5", rtol=1e-11, atol=1e-11, t_eval=ts)
        m = scenes.free_body((1.0, 2.0, 3.0), w0, param=param)
        r = simulate(m, (0, 2.0), method="dopri5", rtol=1e-11, atol=1e-11, t_eval=ts)
        err = max(_angle(m.param.alpha(a)[:3, :3], ref.param.alpha(b)[:3, :3]) for a, b in zip(r.q, rq.q))
        if param == "rxyz":     # for x-y-z angles, R[0, 2] = sin θ2
            s2 = np.array([ref.param.alpha(b)[0, 2] for b in rq.q])
            extra = dict(closest_to_lock_rad=float(np.arccos(np.clip(np.abs(s2), 0, 1)).min()),
                         lock_passes=int(np.sum(np.diff(np.sign(np.diff(np.abs(s2)))) < 0)))
        else:
            turned = np.trapezoid(np.linalg.norm(rq.V[:, :3], axis=1), ts)
            extra = dict(turns=float(turned / (2 * np.pi)),
                         max_rotvec_norm=float(np.linalg.norm(r.q[:, 3:6], axis=1).max()))
        rows.append(dict(case=what, success=r.success, max_rotation_difference=err, **extra))
    return rows


def fast_and_stiff(spring_T=0.05):
    """Spin 10³ rad/s and inertia ratio 10⁶ (analytic references), springs 10⁸ N/m."""
    return spin_rows() + inertia_rows() + spring_rows(spring_T)


def spin_rows():
    """Spin 1e3 rad/s near the intermediate axis (it flips): explicit methods resolve it."""
    J, w0, T = (1.0, 2.0, 3.0), (10.0, 1000.0, 10.0), 0.05
    return [_torque_free_row("spin 1e3 rad/s", J, w0, T, method, kw)
            for method, kw in (("dopri5", dict(rtol=1e-10, atol=1e-10)), ("rkmk4", dict(dt=1e-4)))]


def inertia_rows():
    """Inertia ratio 1e6 spinning about the major axis: the wobble has ≈ 3.2e4 rad/s."""
    J, w0, T = (1e-3, 1.0, 1e3), (1e-3, 1e-3, 1.0), 0.02
    return [_torque_free_row("inertia ratio 1e6 (wobble ω·dt = 32)", J, w0, T, method, kw)
            for method, kw in (("dopri5", dict(rtol=1e-10, atol=1e-10)), ("rkmk4", dict(dt=1e-3)),
                               ("genalpha", dict(dt=1e-3)))]


def spring_rows(T=0.05, methods=("genalpha", "rkmk4", "euler", "dopri5")):
    """A body on two 1e8 N/m springs, fixed steps of 1e-3 s (ω·dt ≈ 10)."""
    rows = []
    m = stiff_springs()
    E0 = m.energy(m.q0, m.V0)
    for method in methods:
        kw = dict(rtol=1e-6, atol=1e-9) if method == "dopri5" else dict(dt=1e-3)
        t0 = time.perf_counter()
        with np.errstate(all="ignore"):
            r = simulate(m, (0, T), method=method, group="SO3xR3", **kw)
        rows.append(dict(case="springs 1e8 N/m (ω·dt = 10)", method=method, success=r.success,
                         steps=r.stats["n_steps"], message=r.message,
                         energy_ratio=float(m.energy(r.q[-1], r.V[-1]) / E0), wall_s=time.perf_counter() - t0))
    return rows


def _torque_free_row(what, J, w0, T, method, kw):
    m = scenes.free_body(J, w0)
    E0, L0 = m.energy(m.q0, m.V0), np.linalg.norm(m.spatial_angular_momentum(m.q0, m.V0))
    with np.errstate(all="ignore"):
        r = simulate(m, (0, T), method=method, t_eval=[0, T], **kw)
    row = dict(case=what, method=method, success=r.success, steps=r.stats["n_steps"], message=r.message)
    if r.success:
        w_ref = torque_free_omega(np.array([T]), J, w0)[0]
        row.update(omega_rel_error=float(np.linalg.norm(r.V[-1, :3] - w_ref) / np.linalg.norm(w_ref)),
                   energy_drift=float(abs(m.energy(r.q[-1], r.V[-1]) - E0) / E0),
                   momentum_drift=float(abs(np.linalg.norm(m.spatial_angular_momentum(r.q[-1], r.V[-1])) - L0)
                                        / L0))
    return row


def stiff_springs(k=1e8):
    """A body held at two points by zero-length springs of stiffness k (ω ≈ 10⁴ rad/s)."""
    J = np.diag([0.1, 0.2, 0.3])
    q0 = np.array([0.001, 0.0, -0.002, 1.0, 0.0, 0.0, 0.0])
    V0 = np.array([0.5, 0.3, 0.1, 0.0, 0.0, 0.0])
    a, b = np.array([0.1, 0.0, 0.0]), np.array([-0.1, 0.05, 0.0])
    return scenes.RigidBodySystem([1.0], [J], q0, V0, gravity=np.zeros(3),
                                  springs=[(0, a, -1, a, k, 0.0), (0, b, -1, b, k, 0.0)], names=["held"])


def long_run(n_steps=1_000_000, methods=("euler", "rkmk2", "rkmk4", "genalpha"), dt=1e-3):
    """‖Q‖ - 1 and the energy drift after n_steps of each method on a free asymmetric
    body (quaternion coordinates, no renormalization anywhere)."""
    rows = []
    for method in methods:
        m = scenes.free_body((1.0, 2.0, 3.0), (0.3, 2.0, 0.1))
        E0 = m.energy(m.q0, m.V0)
        T = n_steps * dt
        t0 = time.perf_counter()
        r = simulate(m, (0, T), method=method, dt=dt, t_eval=np.linspace(0, T, 101))
        Q = r.q[:, 3:7]
        rows.append(dict(method=method, steps=r.stats["n_steps"], dt=dt,
                         quat_norm_error=float(np.abs(np.linalg.norm(Q, axis=1) - 1).max()),
                         energy_drift=float(abs(m.energy(r.q[-1], r.V[-1]) - E0) / E0),
                         wall_s=time.perf_counter() - t0))
    return rows


def _hardening_load(t, q, V):
    """Zero until t = 0.3, then a pull towards the origin that hardens exponentially."""
    k = 1e9 * np.exp(np.minimum(50 * np.abs(q[:3]).sum(), 600)) if t > 0.3 else 0.0
    return -k * q[None, :3], np.zeros((1, 3))


def failed_steps():
    """A NaN force and a diverging Newton iteration: success=False, earlier steps kept."""
    rows = []
    m = scenes.free_body()
    m.load = lambda t, q, V: ((np.full((1, 3), np.nan) if t > 0.5 else np.zeros((1, 3))), np.zeros((1, 3)))
    r = simulate(m, (0, 1), method="rkmk4", dt=0.01)
    rows.append(dict(case="NaN force after t = 0.5", success=r.success, steps_kept=len(r.t) - 1,
                     t_last=float(r.t[-1]), message=r.message))
    m = scenes.free_body(v0=(1.0, 0.0, 0.0))
    m.load = _hardening_load
    with np.errstate(all="ignore"):
        r = simulate(m, (0, 1), method="genalpha", dt=0.05)
    rows.append(dict(case="genalpha, load hardening without bound after t = 0.3", success=r.success,
                     steps_kept=len(r.t) - 1, t_last=float(r.t[-1]), message=r.message))
    return rows


def write_report(out, long_steps=1_000_000):
    """Run every case; write extremes.json and extremes.md into ``out``."""
    from pathlib import Path
    import json
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    results = {}
    for name, fn in CASES.items():
        t0 = time.perf_counter()
        with np.errstate(all="ignore"):
            results[name] = fn(long_steps) if name == "long_run" else fn()
        results[name + "_wall_s"] = time.perf_counter() - t0
    (out / "extremes.json").write_text(json.dumps(results, indent=1, default=float))
    lines = ["# Extremes suite", "", "References: update accuracy against scipy's expm (the tests use "
             "40-digit mpmath); torque-free cases against the Jacobi elliptic solution; singular "
             "coordinates against a quaternion run; energy against its initial value."]
    for name in CASES:
        rows = results[name]
        keys = list(dict.fromkeys(k for r in rows for k in r))
        lines += ["", f"## {name.replace('_', ' ')}", "", "| " + " | ".join(keys) + " |",
                  "|" + "---|" * len(keys)]
        for r in rows:
            cell = lambda v: f"{v:.3g}" if isinstance(v, float) else str(v)  # noqa: E731
            lines.append("| " + " | ".join(cell(r.get(k, "")) for k in keys) + " |")
    path = out / "extremes.md"
    path.write_text("\n".join(lines) + "\n")
    return path


CASES = dict(update_accuracy=update_accuracy, cayley_half_turn=cayley_half_turn,
             singular_coordinates=singular_coordinates, fast_and_stiff=fast_and_stiff,
             failed_steps=failed_steps, long_run=long_run)
