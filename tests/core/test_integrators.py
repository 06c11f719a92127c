"""Bridge integrators against independent references: fitted convergence orders,
the analytic torque-free top, conserved quantities, the heavy top in both forms,
gimbal lock and rotation-vector wrap, and failure handling."""
import itertools

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from lgt_bridge import ChartDomainError, InputError, params, scenes
from lgt_bridge.analytic import torque_free_omega
from lgt_bridge.simulate import simulate

import references as ref

COMBOS = list(itertools.product(["SE3", "SO3xR3"], ["exp", "cay"]))
FB_J, FB_W0 = np.array([1.0, 2.0, 3.0]), np.array([0.4, 1.0, -0.3])


def R_of(model, q, k=0):
    b = model.layout.bodies[k]
    return b.param.alpha(q[[*b.pos, *b.rot]])[:3, :3]


def test_analytic_torque_free_solution_solves_euler_equations():
    for J, w0 in [((1, 2, 3), (0.01, 2, 0.01)), ((3, 1, 2), (0.5, -1, 0.3)),
                  ((1, 2, 3), (1, 0.1, 0.2)), ((2, 5, 3), (-0.3, 0.2, -1.5))]:
        J, w0 = np.array(J, float), np.array(w0, float)
        sol = solve_ivp(lambda t, w: -np.cross(w, J * w) / J, (0, 10), w0, rtol=1e-12, atol=1e-14,
                        dense_output=True)
        ts = np.linspace(0, 10, 40)
        assert np.abs(torque_free_omega(ts, J, w0) - sol.sol(ts).T).max() < 1e-9


ORDERS = {"euler": 1, "rkmk2": 2, "rkmk4": 4, "genalpha": 2}
FB_DTS = {"euler": [0.02, 0.01, 0.005, 0.0025], "rkmk2": [0.1, 0.05, 0.025, 0.0125],
          "rkmk4": [0.2, 0.1, 0.05, 0.025], "genalpha": [0.05, 0.025, 0.0125, 0.00625]}


def free_body_error(method, group, chart, dt, T=1.0):
    m = scenes.free_body(FB_J, FB_W0)
    r = simulate(m, (0, T), method=method, group=group, chart=chart, dt=dt)
    assert r.success, r.message
    Rref, wref = ref.rigid_rotation(np.diag(FB_J), FB_W0, T)
    w_an = torque_free_omega(T, FB_J, FB_W0)[0]
    assert np.abs(wref - w_an).max() < 1e-10          # the two references agree
    return ref.angle(R_of(m, r.q[-1]), Rref) + np.abs(r.V[-1, :3] - w_an).max()


@pytest.mark.parametrize("method", list(ORDERS))
@pytest.mark.parametrize("group,chart", COMBOS)
def test_order_on_free_body(method, group, chart):
    dts = FB_DTS[method]
    errs = [free_body_error(method, group, chart, dt) for dt in dts]
    assert abs(ref.slope(dts, errs) - ORDERS[method]) <= 0.15, (errs, ref.slope(dts, errs))


HT_DTS = {"euler": [4e-5, 2e-5, 1e-5, 5e-6], "rkmk2": [2e-4, 1e-4, 5e-5, 2.5e-5],
          "rkmk4": [1e-3, 5e-4, 2.5e-4, 1.25e-4], "genalpha": [2e-4, 1e-4, 5e-5, 2.5e-5]}


@pytest.mark.parametrize("method", list(ORDERS))
@pytest.mark.parametrize("group,chart", [("SE3", "exp"), ("SO3xR3", "cay")])
def test_order_on_heavy_top(method, group, chart):
    T = 0.02
    Rref, wref = ref.heavy_top(T)
    m = scenes.heavy_top(False)
    errs = []
    for dt in HT_DTS[method]:
        r = simulate(m, (0, T), method=method, group=group, chart=chart, dt=dt)
        assert r.success, r.message
        errs.append(ref.angle(R_of(m, r.q[-1]), Rref) + np.abs(r.V[-1, :3] - wref).max() / 150)
    assert abs(ref.slope(HT_DTS[method], errs) - ORDERS[method]) <= 0.15, errs


@pytest.mark.parametrize("group,chart", COMBOS)
def test_dopri5_error_scales_with_tolerance(group, chart):
    T = 0.05
    Rref, wref = ref.heavy_top(T)
    m = scenes.heavy_top(False)
    tols, errs, nfs = [1e-5, 1e-7, 1e-9, 1e-11], [], []
    for tol in tols:
        r = simulate(m, (0, T), method="dopri5", group=group, chart=chart, rtol=tol, atol=tol)
        errs.append(ref.angle(R_of(m, r.q[-1]), Rref))
        nfs.append(r.stats["n_f"])
    assert all(e2 < e1 for e1, e2 in zip(errs, errs[1:])) and all(n2 > n1 for n1, n2 in zip(nfs, nfs[1:]))
    assert 0.7 <= ref.slope(tols, errs) <= 1.2, errs
    assert errs[-1] < 1e-8


@pytest.mark.parametrize("group,chart", COMBOS)
@pytest.mark.parametrize("param", ["quat", "rotvec", "rxyz"])
def test_torque_free_body_against_analytic_solution(param, group, chart):
    J, w0 = np.array([1.0, 2.0, 3.0]), np.array([0.01, 2.0, 0.01])      # Dzhanibekov flip
    m = scenes.free_body(J, w0, param=param)
    ts = np.linspace(0, 10, 21)
    r = simulate(m, (0, 10), method="dopri5", group=group, chart=chart, rtol=1e-10, atol=1e-12, t_eval=ts)
    assert r.success and np.allclose(r.t, ts, rtol=0, atol=1e-12)
    assert np.abs(r.V[:, :3] - torque_free_omega(ts, J, w0)).max() < 2e-7
    assert min(r.V[:, 1]) < -1.9                                      # it did flip
    E = [m.energy(q, V) for q, V in zip(r.q, r.V)]
    L = np.array([m.spatial_angular_momentum(q, V) for q, V in zip(r.q, r.V)])
    assert np.ptp(E) / E[0] < 1e-8
    assert np.abs(L - L[0]).max() / np.linalg.norm(L[0]) < 1e-7


def test_conservation_improves_at_the_methods_order():
    J, w0 = np.array([1.0, 2.0, 3.0]), np.array([0.4, 1.0, -0.3])
    m = scenes.free_body(J, w0)
    drift = []
    for dt in (0.04, 0.02):
        r = simulate(m, (0, 5), method="rkmk4", dt=dt)
        E = np.array([m.energy(q, V) for q, V in zip(r.q, r.V)])
        drift.append(np.abs(E - E[0]).max())
    assert 3.5 < np.log2(drift[0] / drift[1]) < 4.5


def test_heavy_top_forms_agree_and_match_exudyn_figure():
    T = 0.1
    mu, mc = scenes.heavy_top(False), scenes.heavy_top(True)
    ru = simulate(mu, (0, T), method="dopri5", rtol=1e-11, atol=1e-11)
    rc = simulate(mc, (0, T), method="dopri5", rtol=1e-11, atol=1e-11)
    assert ref.angle(R_of(mu, ru.q[-1]), R_of(mc, rc.q[-1])) < 1e-8
    assert np.abs(ru.V[-1, :3] - rc.V[-1, :3]).max() < 1e-6
    Rref, _ = ref.heavy_top(T)
    assert ref.angle(R_of(mu, ru.q[-1]), Rref) < 1e-8
    assert rc.stats["constraint_after_projection"] <= 1e-10
    assert max(np.abs(mc.constraints(q)).max() for q in rc.q) <= 1e-10
    # Exudyn's test suite quotes the converged global ω_y of this top at t = 0.01 s
    r = simulate(mc, (0, 0.01), method="dopri5", rtol=1e-12, atol=1e-12)
    assert abs((R_of(mc, r.q[-1]) @ r.V[-1, :3])[1] - 149.8473939540758) < 1e-8


@pytest.mark.parametrize("constrained", [False, True])
def test_genalpha_second_order_on_heavy_top(constrained):
    T = 0.02
    Rref, wref = ref.heavy_top(T)
    m = scenes.heavy_top(constrained)
    dts, errs = [2e-4, 1e-4, 5e-5], []
    for dt in dts:
        r = simulate(m, (0, T), method="genalpha", dt=dt)
        assert r.success
        errs.append(ref.angle(R_of(m, r.q[-1]), Rref))
        if constrained:
            assert r.stats["constraint_residual"] < 1e-10
    assert abs(ref.slope(dts, errs) - 2) <= 0.15, errs


@pytest.mark.parametrize("method,dt", [("rkmk4", 5e-3), ("dopri5", None), ("euler", 1e-3)])
def test_projection_keeps_chain_on_constraints(method, dt):
    m = scenes.chain(6)
    r = simulate(m, (0, 1.0), method=method, dt=dt, rtol=1e-6, atol=1e-8)
    assert r.success
    assert r.stats["constraint_before_projection"] > 1e-10          # there was drift to remove
    assert r.stats["constraint_after_projection"] <= 1e-10
    assert r.stats["velocity_constraint_after_projection"] <= 1e-10
    assert max(np.abs(m.constraints(q)).max() for q in r.q) <= 1e-10


def test_chain_genalpha_agrees_with_projected_dopri5():
    m = scenes.chain(5)
    a = simulate(m, (0, 0.5), method="genalpha", dt=1e-3)
    b = simulate(m, (0, 0.5), method="dopri5", rtol=1e-10, atol=1e-10)
    assert a.success and b.success
    pos = lambda q: q.reshape(5, 7)[:, :3]
    assert np.abs(pos(a.q[-1]) - pos(b.q[-1])).max() < 1e-3
    assert a.stats["constraint_residual"] < 1e-9


@pytest.mark.parametrize("name", ["RK45", "DOP853", "Radau"])
def test_scipy_methods_through_tau(name):
    T = 0.05
    Rref, wref = ref.heavy_top(T)
    m = scenes.heavy_top(False, param="rotvec")
    r = simulate(m, (0, T), method=f"scipy:{name}", rtol=1e-10, atol=1e-10)
    assert r.success
    assert ref.angle(R_of(m, r.q[-1]), Rref) < 1e-7
    assert np.all(np.linalg.norm(r.q[:, 3:], axis=1) <= np.pi + 1e-12)


def _plain_rk4(param, th0, w0, T, dt):
    """The legacy way: fixed-step RK4 on θ̇ = H(θ)⁻¹ω, Jω̇ = -ω×Jω + c×Rᵀmg (pivot top)."""
    JP, C, M, g = ref.HT_JP, ref.HT_C, ref.HT_M, np.array([0, 0, -9.81])

    def rhs(y):
        th, w = y[:3], y[3:]
        R = param.alpha(np.concatenate([np.zeros(3), th]))[:3, :3]
        return np.concatenate([param._rates_from_omega(th[None], w[None])[0],
                               np.linalg.solve(JP, -np.cross(w, JP @ w) + np.cross(C, R.T @ (M * g)))])

    y = np.concatenate([th0, w0])
    with np.errstate(all="ignore"):
        for _ in range(int(round(T / dt))):
            k1 = rhs(y)
            k2 = rhs(y + dt / 2 * k1)
            k3 = rhs(y + dt / 2 * k2)
            k4 = rhs(y + dt * k3)
            y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return y[:3]


def test_gimbal_lock_tait_bryan_vs_quaternion_and_plain_ode():
    """The top starts 1e-7 rad from gimbal lock (θ1 = π/2 - 1e-7). With the same RK4 and dt,
    the bridge in Tait-Bryan coordinates matches the quaternion run; θ̇ = G(θ)⁻¹ω does not."""
    from scipy.spatial.transform import Rotation
    T, dt = 0.1, 1e-4
    R0 = Rotation.from_euler("XYZ", [0, np.pi / 2 - 1e-7, 0]).as_matrix()
    mq, mt = scenes.heavy_top(False, R0=R0), scenes.heavy_top(False, param="rxyz", R0=R0)
    assert abs(np.cos(mt.q0[4])) < 2e-7
    exact = simulate(mq, (0, T), method="dopri5", rtol=1e-11, atol=1e-11)
    Rx = R_of(mq, exact.q[-1])
    rt = simulate(mt, (0, T), method="rkmk4", dt=dt)
    rq = simulate(mq, (0, T), method="rkmk4", dt=dt)
    assert rt.success and np.isfinite(rt.q).all()
    # continuous write-back: θ1 moves by about |ω| dt per step and crosses π/2 (and 3π/2);
    # no branch flip (which would jump θ0, θ2 by π). Near the lock θ0 and θ2 themselves turn
    # fast (only θ0 ± θ2 is defined there), so their steps are bounded by π/2, not by |ω| dt.
    d = np.abs(np.diff(rt.q[:, 3:], axis=0))
    assert d[:, 1].max() < 2 * 150 * dt and d[:, [0, 2]].max() < np.pi / 2
    assert rt.q[:, 4].max() > 3 * np.pi / 2 and rt.q[1, 4] > np.pi / 2
    assert ref.angle(R_of(mt, rt.q[-1]), Rx) < 1e-8
    assert ref.angle(R_of(mt, rt.q[-1]), R_of(mq, rq.q[-1])) < 1e-8
    th = _plain_rk4(params.RXYZ, mt.q0[3:], mt.V0[:3], T, dt)
    plain = ref.angle(params.RXYZ.alpha(np.concatenate([np.zeros(3), th]))[:3, :3], Rx) if np.isfinite(th).all() else np.inf
    assert plain > 1e-3


def test_rotation_vector_through_two_pi():
    """Rotation vectors: the bridge re-wraps to |ρ| <= π after every step, also from a start at
    |ρ| = 2π - 1e-6 (where ρ̇ = dexp⁻¹_{-ρ}ω is singular), and matches the quaternion run."""
    T, dt = 0.1, 1e-4
    n = np.array([0.6, 0.0, 0.8])
    rho0 = (2 * np.pi - 1e-6) * n                          # the rotation by -1e-6 about n
    mq = scenes.heavy_top(False, R0=params.ROTVEC.alpha(np.concatenate([np.zeros(3), rho0]))[:3, :3])
    mr = scenes.heavy_top(False, param="rotvec")
    q0 = np.concatenate([np.zeros(3), rho0])
    rr = simulate(mr, (0, T), method="rkmk4", dt=dt, q0=q0)
    rq = simulate(mq, (0, T), method="rkmk4", dt=dt)
    assert rr.success
    assert np.all(np.linalg.norm(rr.q[1:, 3:], axis=1) <= np.pi + 1e-12)
    assert ref.angle(R_of(mq, rq.q[-1]), R_of(mr, rr.q[-1])) < 1e-10
    exact = simulate(mq, (0, T), method="dopri5", rtol=1e-11, atol=1e-11)
    assert ref.angle(R_of(mr, rr.q[-1]), R_of(mq, exact.q[-1])) < 1e-8
    rho = _plain_rk4(params.ROTVEC, rho0, mr.V0[:3], T, dt)
    plain = ref.angle(params.ROTVEC.alpha(np.concatenate([np.zeros(3), rho]))[:3, :3],
                      R_of(mq, exact.q[-1])) if np.isfinite(rho).all() else np.inf
    assert plain > 1e-3


def test_mixed_groups_and_charts_per_body():
    m = scenes.chain(4)
    ref_run = simulate(m, (0, 0.3), method="dopri5", rtol=1e-10, atol=1e-10)
    mix = simulate(m, (0, 0.3), method="dopri5", rtol=1e-10, atol=1e-10,
                   group=["SE3", "SO3xR3", "SE3", "SO3xR3"], chart=["exp", "cay", "cay", "exp"])
    assert np.abs(mix.q[-1] - ref_run.q[-1]).max() < 1e-7


class Counting(scenes.RigidBodySystem):
    calls = 0
    writes = []
    nan_after = np.inf

    def f(self, q, V, t):
        self.calls += 1
        out = super().f(q, V, t)
        return out * np.nan if t > self.nan_after else out

    def write_back(self, q, V, t):
        self.writes.append((t, q.copy()))


def counting_free_body():
    m = scenes.free_body(FB_J, FB_W0)
    c = Counting.__new__(Counting)
    c.__dict__.update(m.__dict__)
    c.writes = []
    return c


@pytest.mark.parametrize("kwargs,match", [
    (dict(t_span=(1.0, 0.5), dt=0.1), "t_end = 0.5 must be greater than t0 = 1.0"),
    (dict(t_span=(0, 1), dt=0.0), "dt = 0.0 must be a positive"),
    (dict(t_span=(0, 1), dt=-1e-3), "must be a positive"),
    (dict(t_span=(0, 1)), "takes fixed steps: pass dt"),
    (dict(t_span=(0, 1), dt=0.1, method="rk5"), "unknown method 'rk5'"),
    (dict(t_span=(0, 1), dt=0.1, method="scipy:Euler"), "unknown scipy method"),
    (dict(t_span=(0, 1), dt=0.1, group="SE2"), "unknown group"),
    (dict(t_span=(0, 1), dt=0.1, chart="rodrigues"), "unknown chart"),
    (dict(t_span=(0, 1), dt=0.1, group=["SE3", "SE3"]), "group: got 2 values for 1 rigid bodies"),
    (dict(t_span=(0, 1), dt=0.1, V0=[np.nan, 0, 0, 0, 0, 0]), r"V0: entry 0 \(body 0 \(body\)\) is nan"),
    (dict(t_span=(0, 1), dt=0.1, q0=[0, 0, 0, 1.1, 0, 0, 0]), r"q0 of body 0.*off by 0.1"),
    (dict(t_span=(0, 1), dt=0.1, q0=np.zeros(6)), r"q0: got shape \(6,\)"),
])
def test_bad_input_rejected_before_stepping(kwargs, match):
    m = counting_free_body()
    kw = dict(method="rkmk4") | kwargs
    with pytest.raises(InputError, match=match):
        simulate(m, kw.pop("t_span"), **kw)
    assert m.calls == 0 and not m.writes


def test_bad_body_among_many_is_named():
    m = scenes.chain(4)
    q0 = m.q0.copy()
    q0[2 * 7 + 3:2 * 7 + 7] *= 1.01                    # third link's quaternion off the unit sphere
    with pytest.raises(InputError, match=r"q0 of body 2 \(link2\)"):
        simulate(m, (0, 1), dt=0.1, q0=q0)


def test_nan_step_stops_with_earlier_steps_kept():
    m = counting_free_body()
    m.nan_after = 0.0505
    r = simulate(m, (0, 1), method="rkmk4", dt=0.01)
    assert not r.success
    assert "step from t = 0.05" in r.message and "body 0" in r.message
    assert len(r.t) == 6 and r.t[-1] == pytest.approx(0.05)          # t = 0 ... 0.05 kept
    assert np.isfinite(r.q).all() and np.isfinite(r.V).all()
    assert m.writes[-1][0] == pytest.approx(0.05)                      # engine left at the last good state
    assert np.array_equal(m.writes[-1][1], r.q[-1])


def test_cayley_fixed_step_past_half_turn_raises_with_partial_result():
    m = scenes.heavy_top(False)
    with pytest.raises(ChartDomainError, match="Cayley chart") as exc:
        simulate(m, (0, 0.1), method="rkmk4", chart="cay", dt=0.02)
    assert exc.value.result.success is False and len(exc.value.result.t) >= 1


def test_cayley_adaptive_shrinks_step_instead():
    T = 0.05
    Rref, _ = ref.heavy_top(T)
    m = scenes.heavy_top(False)
    r = simulate(m, (0, T), method="dopri5", chart="cay", dt=0.03, rtol=1e-9, atol=1e-9)
    assert r.success and r.stats["n_rejected"] > 0
    assert ref.angle(R_of(m, r.q[-1]), Rref) < 1e-7


def test_t_eval_and_write_back():
    m = counting_free_body()
    ts = [0.0, 0.013, 0.5, 0.77]
    r = simulate(m, (0, 1), method="rkmk4", dt=0.1, t_eval=ts)
    assert np.array_equal(r.t, ts)
    assert m.writes[-1][0] == pytest.approx(1.0)
    assert r.stats["n_steps"] == len(m.writes)
    # after a step shortened to land on an output time, fixed steps go back to dt:
    # steps of 0.1 up to 0.013 (1), 0.5 (5), 0.77 (3), 1.0 (3) = 12
    assert r.stats["n_steps"] == 12


def test_genalpha_uses_the_models_iteration_matrix(monkeypatch):
    """With iteration_matrix from the model (SO(3)xR³) Newton needs no finite-difference
    columns, and converges to the same solution as with the FD iteration matrix."""
    m = scenes.chain(4)
    a = simulate(m, (0, 0.2), method="genalpha", group="SO3xR3", dt=1e-3)
    monkeypatch.delattr(scenes.RigidBodySystem, "iteration_matrix")
    b = simulate(m, (0, 0.2), method="genalpha", group="SO3xR3", dt=1e-3)
    assert a.success and b.success
    assert np.abs(a.q[-1] - b.q[-1]).max() < 1e-10
    assert a.stats["n_f"] < b.stats["n_f"]                         # no FD columns
    assert a.stats["constraint_residual"] < 1e-10


def test_scene_constraint_jacobian_and_gamma_against_finite_differences(rng):
    """ġ = A(q) V and γ = d/dt(A V) at fixed V, both along q(s) = τ(q, sV) on SO(3)xR³
    (the model twist's own increments)."""
    from lgt_bridge.integrators.local import LocalProblem
    m = scenes.chain(4)
    prob = LocalProblem(m, "SO3xR3", "exp")
    prob.start(m.q0)
    q, _ = prob.configuration(prob.to_local(rng.normal(size=m.layout.nv) * 0.3))
    V = rng.normal(size=m.layout.nv)
    prob.start(q)
    at = lambda s: prob.configuration(prob.to_local(s * V))[0]          # noqa: E731
    h = 1e-6
    gdot = (m.constraints(at(h)) - m.constraints(at(-h))) / (2 * h)
    assert np.abs(m.constraint_jacobian(q) @ V - gdot).max() < 1e-8
    gam = (m.constraint_jacobian(at(h)) @ V - m.constraint_jacobian(at(-h)) @ V) / (2 * h)
    assert np.abs(m.constraint_gamma(q, V) - gam).max() < 1e-6
