"""The compiled kernels against the numpy reference backend: every parameterization,
both groups, every chart, rotation-only bodies, vector-space blocks and per-body mixes,
at the level of one stage and of whole runs (agreement to 1e-13, relative to scale)."""
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lgt_bridge import params, scenes
from lgt_bridge.integrators.compiled import CompiledProblem
from lgt_bridge.integrators.local import LocalProblem
from lgt_bridge.kernels import rotations as kr
from lgt_bridge.model import Layout, Model, RigidBody
from lgt_bridge.simulate import simulate

import backend_checks

PARAMS = ["quat_wxyz", "quat_xyzw", "rotvec", "rxyz", "rzyx"]


def close(a, b, tol=1e-13):
    """Relative to max(1, |b|): these quantities are O(1) state and twist entries."""
    return backend_checks.close(a, b, tol, floor=1.0)


class Mixed(Model):
    """Two bodies of every parameterization, one rotation-only body per parameterization,
    two vector-space coordinates and a circle (SO(2)) coordinate, interleaved in q and V; a
    smooth coupled f."""

    def __init__(self, rng):
        bodies, iq, iv = [], 2, 1          # vector coordinates first: q[0:2], V[0] and V[nv-1]
        for name in PARAMS:
            p = params.get(name)
            for _ in range(2):
                bodies.append(RigidBody(p, tuple(range(iq, iq + 3)), tuple(range(iq + 3, iq + p.nu)),
                                        tuple(range(iv, iv + 6))))
                iq, iv = iq + p.nu, iv + 6
            bodies.append(RigidBody(p, (), tuple(range(iq, iq + p.nrot)), tuple(range(iv, iv + 3))))
            iq, iv = iq + p.nrot, iv + 3
        # the circle: q[iq:iq + 2] = (cos θ, sin θ) between the last body and nothing, its rate V[iv + 1]
        self.layout = Layout(iq + 2, iv + 2, bodies, vector_q=(0, 1), vector_v=(0, iv),
                             circle_q=((iq, iq + 1),), circle_v=(iv + 1,))
        q = rng.normal(size=iq + 2)
        th = rng.uniform(-3, 3)
        q[iq], q[iq + 1] = np.cos(th), np.sin(th)
        for b in bodies:
            rot = list(b.rot)
            if b.param.nrot == 4:
                q[rot] /= np.linalg.norm(q[rot])
            elif b.param.name == "rotvec":
                q[rot] *= 2.5 / max(np.linalg.norm(q[rot]), 1.0)
        self.q0 = q
        self.V0 = rng.normal(size=iv + 2)
        self.K = rng.normal(size=(iv + 2, iv + 2)) * 0.1

    def f(self, q, V, t):
        return -self.K @ V + np.sin(q[: len(V)] if len(q) >= len(V) else np.resize(q, len(V))) + t


def _problems(model, groups, charts):
    return LocalProblem(model, groups, charts), CompiledProblem(model, groups, charts)


@pytest.mark.parametrize("group", ["SE3", "SO3xR3", "mix"])
@pytest.mark.parametrize("chart", ["exp", "cay", "cay2", "mix"])
def test_stage_kernels_equal_numpy(group, chart, rng):
    m = Mixed(rng)
    nb = m.layout.nbodies
    g = [("SE3", "SO3xR3")[k % 2] for k in range(nb)] if group == "mix" else group
    c = [("exp", "cay", "cay2")[(k // 2) % 3] for k in range(nb)] if chart == "mix" else chart
    ref, comp = _problems(m, g, c)
    for prob in (ref, comp):
        prob.start(m.q0)
    # α(q_k) of every body; the kernel's body table lists the bodies set by set
    assert close(comp.start_quats, np.concatenate(ref.start_quats))
    for scale in (0.0, 1e-9, 0.3, 1.2):
        X = rng.normal(size=ref.nX) * scale
        W = rng.normal(size=ref.nv) * 3.0
        q0, p0 = ref.configuration(X)
        q1, p1 = comp.configuration(X)
        assert close(q1, q0), np.abs(q1 - q0).max()
        # dense output at many times: one kernel call against the reference's state_at per row
        w = rng.uniform(size=(3, 2))
        FX, FW = np.stack([X, 0.5 * X]), rng.normal(size=(2, ref.nv))
        Qr, Vr = ref.dense_states(w, FX, FW, W, ref.snapshot())
        Qc, Vc = comp.dense_states(w, FX, FW, W, comp.snapshot())
        assert close(Qr[1], ref.state_at(w[1] @ FX, W + w[1] @ FW)[0])
        assert close(Vr[2], ref.state_at(w[2] @ FX, W + w[2] @ FW)[1])
        assert close(Qc, Qr) and close(Vc, Vr)
        assert close(comp.kinematics(X, W), ref.kinematics(X, W))
        assert close(comp.model_velocity(W, p1), ref.model_velocity(W, p0))
        assert close(comp.group_velocity(W, p1), ref.group_velocity(W, p0))
        Wd = rng.normal(size=ref.nv)
        assert close(comp.group_acceleration(Wd, W, p1), ref.group_acceleration(Wd, W, p0))
        assert close(comp.model_acceleration(Wd, W, p1), ref.model_acceleration(Wd, W, p0))
        # one RK stage through the stage API (combination, τ, f, stage derivative)
        a = np.array([0.3, -0.2, 0.5])
        KXs = [np.zeros((4, ref.nX)) for _ in range(2)]
        KWs = [np.zeros((4, ref.nv)) for _ in range(2)]
        for KX, KW in zip(KXs, KWs):
            KX[:3] = rng.normal(size=(3, ref.nX)) * scale if KX is KXs[0] else KXs[0][:3]
            KW[:3] = rng.normal(size=(3, ref.nv)) if KW is KWs[0] else KWs[0][:3]
        for prob, KX, KW in zip((ref, comp), KXs, KWs):
            assert prob.stage(KX, KW, 3, a, 0.1, W, 0.0, 0.05) == 0.0
            prob.flush(KX, KW)           # the compiled backend completes KW[3] in its next call
        assert close(KXs[1][3], KXs[0][3]) and close(KWs[1][3], KWs[0][3])
        e0 = ref.end(KXs[0], KWs[0], np.array([0.1, 0.2, 0.3, 0.4]), 0.1, W)
        e1 = comp.end(KXs[1], KWs[1], np.array([0.1, 0.2, 0.3, 0.4]), 0.1, W)
        for u, v in zip(e1[:4], e0[:4]):
            assert close(u, v)
        # generalized-α's fused state (W = Wa + s_v Ẇ, X = dXa + sp Ẇ[to_local]) and residual
        tl = np.rint(ref.to_local(np.arange(ref.nv, dtype=float))).astype(np.int64)
        sp = rng.uniform(0.5, 1.0, size=ref.nX) * scale
        Wd, Vd = rng.normal(size=ref.nv), rng.normal(size=ref.nv)
        outs, res = [], []
        for prob in (ref, comp):
            q, V, quats, Wn = prob.ga_state(Wd, 0.3, sp, W, X, tl)
            r = np.empty(ref.nv)
            res.append((r, prob.ga_residual(Vd, Wd, r, Wn, quats)))
            outs.append((q.copy(), V.copy(), Wn.copy()))
        q_expect, _ = ref.configuration(X + sp * Wd[tl])
        assert close(outs[0][0], q_expect)
        for u, v in zip(outs[1], outs[0]):
            assert close(u, v)
        assert close(res[1][0], res[0][0]) and abs(res[1][1] - res[0][1]) <= 1e-12 * max(1.0, res[0][1])
        # radau5's F = [Ẋ, Ẇ] at (X, W): the state kernel with the kinematics, f, the conversion
        F0, F1 = ref.rates(X, W, 0.3), comp.rates(np.ascontiguousarray(X), np.ascontiguousarray(W), 0.3)
        assert close(F1, F0)
        assert close(F0[:ref.nX], ref.kinematics(X, W))


@given(p=st.lists(st.floats(-1, 1), min_size=4, max_size=4), prev=st.lists(st.floats(-4, 4), min_size=4, max_size=4),
       code=st.sampled_from(PARAMS), lock=st.booleans())
def test_alpha_inverse_kernel_equals_params(p, prev, code, lock):
    """α⁻¹ with branch continuity (quaternion sign, rotation-vector half-turn ties,
    Tait-Bryan branches and gimbal lock) and α, kernel vs params."""
    p = np.array(p)
    if lock and code in ("rxyz", "rzyx"):       # a rotation at gimbal lock: θ1 = ±π/2
        p = params.get(code)._to_quat(np.array([[p[0] * 3, np.sign(p[1] or 1) * np.pi / 2, p[2] * 3]]))[0]
    if np.linalg.norm(p) < 1e-3:
        p = np.array([1.0, 0, 0, 0])
    p = p / np.linalg.norm(p)
    par = params.get(code)
    prev = np.array(prev[: par.nrot])
    if par.nrot == 4:
        prev = prev / max(np.linalg.norm(prev), 1e-3)
    want = par._from_quat(p[None], prev[None])[0]
    pv = np.append(prev, 0.0) if par.nrot == 3 else prev
    got = np.array(kr.from_quat(kr.PARAM_CODES[code], *p, *pv))[: par.nrot]
    assert close(got, want, 1e-13), (got, want)
    back = np.array(kr.to_quat(kr.PARAM_CODES[code], *(np.append(want, 0.0) if par.nrot == 3 else want)))
    assert close(back, par._to_quat(want[None])[0], 1e-14)


def _run(monkeypatch, backend, make, **kw):
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", backend)
    return simulate(make(), **kw)


@pytest.mark.parametrize("method, kw", [("rkmk4", dict(dt=1e-3)), ("dopri5", dict(rtol=1e-9, atol=1e-9)),
                                        ("dop853", dict(rtol=1e-9, atol=1e-9)), ("euler", dict(dt=1e-4))])
@pytest.mark.parametrize("param", ["quat", "quat_xyzw", "rotvec", "rxyz"])
def test_runs_agree_across_backends(monkeypatch, method, kw, param):
    """Constrained heavy top (projection), mixed groups and charts per body."""
    def make():
        return scenes.top_and_free_bodies(2, param=param)
    groups, charts = ["SE3", "SO3xR3", "SE3"], ["exp", "cay", "cay2"]
    out = [_run(monkeypatch, b, make, t_span=(0, 0.05), method=method, group=groups, chart=charts,
                t_eval=[0.0, 0.02, 0.05], **kw) for b in ("numpy", "numba")]
    assert out[0].success and out[1].success
    assert out[0].stats["n_f"] == out[1].stats["n_f"]
    assert close(out[1].q, out[0].q) and close(out[1].V, out[0].V)


def test_genalpha_and_scipy_agree_across_backends(monkeypatch):
    """genalpha stops Newton at a tolerance (1e-10 relative), so rounding differences of
    the backends move its result by about that much; scipy's solver sees the same f."""
    for method, kw, tol in (("genalpha", dict(dt=1e-3), 1e-9), ("scipy:DOP853", dict(rtol=1e-9, atol=1e-9), 1e-12)):
        out = [_run(monkeypatch, b, lambda: scenes.heavy_top(True, param="rxyz"), t_span=(0, 0.02),
                    method=method, group="SE3", chart="cay", **kw) for b in ("numpy", "numba")]
        assert close(out[1].q[-1], out[0].q[-1], tol) and close(out[1].V[-1], out[0].V[-1], tol)


def test_unknown_backend_is_refused(monkeypatch):
    from lgt_bridge.errors import InputError
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", "fortran")
    with pytest.raises(InputError, match="LGT_BRIDGE_BACKEND"):
        simulate(scenes.free_body(), (0, 0.01), method="rkmk4", dt=1e-3)


def test_import_loads_no_numba_scipy_solvers_or_adapters():
    """`import lgt_bridge` stays light: numba, scipy.integrate/linalg and the adapters'
    entry points are loaded when first used (a subprocess sees a clean interpreter)."""
    import subprocess
    import sys
    code = ("import sys, lgt_bridge; print(sorted(m for m in ('numba', 'scipy.integrate', 'scipy.linalg', "
            "'lgt_exudyn', 'lgt_pinocchio', 'exudyn', 'pinocchio', 'importlib.metadata') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]", out
