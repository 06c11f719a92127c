"""The second-order Cayley chart (Wiener–Milenkovic, ``chart="cay2"``) against its
definitions: ψ = cay(X/2)² by matrix products on SO(3) and SE(3), its quaternion, angle
and inverse, mpmath near its limit (a full turn), dψ and dψ⁻¹ against finite differences;
then in use: a fixed step of 1.2π per step that the Cayley chart refuses, fitted orders of
rkmk4 and dop853, and the heavy top's reference reached by dop853, radau5, generalized-α
and scipy through τ."""
import mpmath
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from lgt_bridge import ChartDomainError, charts, scenes
from lgt_bridge.groups import se3, so3
from lgt_bridge.groups import quaternion as quat
from lgt_bridge.simulate import simulate

import references as ref

CAY2 = charts.get("cay2")
vec3 = arrays(np.float64, 3, elements=st.floats(-30, 30))
vec6 = arrays(np.float64, 6, elements=st.floats(-30, 30))


def matrix_cay(c):
    """(I - ĉ)⁻¹ (I + ĉ), the definition of the Cayley map (3x3 or 4x4 from a hat matrix)."""
    n = len(c)
    return np.linalg.solve(np.eye(n) - c, np.eye(n) + c)


@given(vec3)
def test_so3_map_is_the_square_of_cayley_at_half(x):
    C = matrix_cay(so3.hat(0.5 * x))
    R = CAY2.on("SO3").psi(x[None])[0]
    assert np.abs(R - C @ C).max() < 1e-12
    d, _ = CAY2.increment(x[None])
    p = d[0] + np.array([1.0, 0, 0, 0])
    assert abs(np.linalg.norm(p) - 1.0) < 1e-15                     # rational, unit by construction
    assert np.abs(quat.to_matrix(p) - R).max() < 1e-12


@given(vec6)
def test_se3_map_is_the_square_of_cayley_at_half(X):
    C = matrix_cay(se3.hat6(0.5 * X))
    G = CAY2.on("SE3").psi(X[None])[0]
    assert np.abs(G - C @ C).max() < 1e-11 * (1 + np.abs(G).max())
    _, t = CAY2.increment(X[None, :3], X[None, 3:])
    assert np.abs(t[0] - G[:3, 3]).max() < 1e-11 * (1 + np.abs(G).max())


@given(arrays(np.float64, 3, elements=st.floats(-1, 1)), st.floats(1e-9, 2 * np.pi - 1e-3))
def test_angle_inverse_and_symmetry(axis, phi):
    if np.linalg.norm(axis) < 1e-3:
        return
    n = axis / np.linalg.norm(axis)
    x = n * float(CAY2.coordinate(phi))                     # |x| = 2 tan(φ/4)
    R = CAY2.on("SO3").psi(x[None])[0]
    assert abs(Rotation.from_matrix(R).magnitude() - min(phi, 2 * np.pi - phi)) < 1e-9
    assert abs(float(CAY2.angle(np.linalg.norm(x))) - phi) < 1e-12 * (1 + phi)
    assert np.abs(CAY2.on("SO3").psi(-x[None])[0] - R.T).max() < 1e-13     # ψ(-x) = ψ(x)⁻¹
    if phi <= np.pi - 1e-6:                                  # ψ⁻¹ returns the rotation of angle ≤ π
        assert np.abs(CAY2.on("SO3").psi_inv(R[None])[0] - x).max() < 1e-9 * (1 + np.linalg.norm(x))
    X = np.concatenate([x, n[::-1] * 0.7])
    if phi <= np.pi - 1e-6:
        assert np.abs(CAY2.on("SE3").psi_inv(CAY2.on("SE3").psi(X[None]))[0] - X).max() < 1e-9


@pytest.mark.parametrize("norm", [1e2, 1e4, 1e7])
def test_quaternion_near_the_full_turn_against_mpmath(norm):
    """Towards |x| → ∞ (a full turn) the rational quaternion ((4 - s), 4x)/(4 + s) keeps full
    relative accuracy: against cay(x/2)'s quaternion (2, x)/√(4 + s) squared at 50 digits."""
    with mpmath.workdps(50):
        x = np.array([0.3, -0.5, 0.81]) / np.linalg.norm([0.3, -0.5, 0.81]) * norm
        d, _ = CAY2.increment(x[None])
        got = d[0] + np.array([1.0, 0, 0, 0])
        xm = [mpmath.mpf(float(v)) for v in x]
        s = mpmath.sqrt(4 + sum(v * v for v in xm))
        h = [2 / s] + [v / s for v in xm]                        # the quaternion of cay(x/2)
        sq = [h[0] * h[0] - sum(v * v for v in h[1:])] + [2 * h[0] * v for v in h[1:]]
        for g, e in zip(got, sq):
            assert abs(mpmath.mpf(float(g)) - e) <= 4e-16 * max(abs(e), mpmath.mpf(1) / norm)


def _right_fd(group, X, h=1e-6):
    """Right-trivialized differential of ψ by central differences of the matrices."""
    psi = CAY2.on(group).psi
    n = X.shape[0]
    D = np.zeros((n, n))
    inv = np.linalg.inv(psi(X[None])[0])
    for k in range(n):
        e = np.zeros(n)
        e[k] = h
        A = (psi((X + e)[None])[0] - psi((X - e)[None])[0]) / (2 * h)
        T = A @ inv
        w = [T[2, 1], T[0, 2], T[1, 0]]
        if n == 3:
            D[:, k] = w
        elif group == "SE3":
            D[:, k] = [*w, *T[:3, 3]]
        else:                                                # direct product: ẏ itself
            D[:, k] = [*w, *A[:3, 3]]
    return D


@pytest.mark.parametrize("group", ["SO3", "SE3", "SO3xR3"])
def test_differentials_against_finite_differences(group, rng):
    maps = CAY2.on(group)
    n = 3 if group == "SO3" else 6
    for scale in (1e-3, 0.5, 2.0, 6.0):
        X = rng.normal(size=n) * scale
        D = maps.dpsi(X[None])[0]
        assert np.abs(D - _right_fd(group, X)).max() < 1e-7 * (1 + np.abs(D).max())
        assert np.abs(D @ maps.dpsi_inv(X[None])[0] - np.eye(n)).max() < 1e-12
        V = rng.normal(size=n)
        assert np.abs(maps.dpsi_apply(X[None], V[None])[0] - D @ V).max() < 1e-12 * (1 + np.abs(D).max())
        assert np.abs(maps.dpsi_inv_apply(X[None], V[None])[0] - np.linalg.solve(D, V)).max() < 1e-10
    # near the identity the chart agrees with the Cayley chart (scale ½: dψ_0 = 2 I; the R³
    # factor of the direct product is additive)
    d0 = np.diag([2.0] * 3 + ([1.0] * 3 if group == "SO3xR3" else [2.0] * (n - 3)))
    assert np.abs(maps.dpsi(np.zeros((1, n)))[0] - d0).max() == 0.0


def spinner(omega):
    """A symmetric body spinning about its symmetry axis (exact solution: uniform rotation)."""
    return scenes.free_body(np.array([1.0, 1.0, 2.0]), np.array([0.0, 0.0, omega]))


def _spin_angle_error(r, model, omega, T):
    b = model.layout.bodies[0]
    p = r.q[-1][list(b.rot)]
    p = p if p[0] >= 0 else -p
    angle = 2 * np.arctan2(np.linalg.norm(p[1:]) * np.sign(p[3]), p[0])     # about +z
    return abs((angle - omega * T + np.pi) % (2 * np.pi) - np.pi)


def test_fixed_step_of_1_2_pi_runs_on_cay2_and_is_refused_on_cay():
    T = 1.0
    omega = 1.2 * np.pi / 0.1                               # 216° per step of 0.1 s
    errs = []
    for dt in (0.1, 0.05):                                   # 216° and 108° per step
        m = spinner(omega)
        r = simulate(m, (0, T), method="rkmk4", chart="cay2", dt=dt)
        assert r.success, r.message
        errs.append(_spin_angle_error(r, m, omega, T))
        with pytest.raises(ChartDomainError, match="Cayley chart"):
            simulate(spinner(omega), (0, T), method="rkmk4", chart="cay", dt=dt)
    assert errs[0] < 0.25 and errs[1] < errs[0] / 10, errs  # rkmk4's order at giant steps
    a = simulate(spinner(omega), (0, T), method="dopri5", chart="cay", dt=0.1, rtol=1e-9, atol=1e-9)
    assert a.success and a.stats["n_rejected"] > 0          # adaptive: shrunk instead
    # beyond cay2's own limit (240° per stage) a fixed step is refused in the same way
    with pytest.raises(ChartDomainError, match="second-order Cayley"):
        simulate(spinner(1.9 * np.pi / 0.1), (0, T), method="rkmk4", chart="cay2", dt=0.1)


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_rkmk4_order_on_cay2(group):
    J, w0 = np.array([1.0, 2.0, 3.0]), np.array([0.4, 1.0, -0.3])
    Rref, _ = ref.rigid_rotation(np.diag(J), w0, 1.0)
    dts = [0.2, 0.1, 0.05, 0.025]
    errs = []
    for dt in dts:
        m = scenes.free_body(J, w0)
        r = simulate(m, (0, 1.0), method="rkmk4", group=group, chart="cay2", dt=dt)
        b = m.layout.bodies[0]
        errs.append(ref.angle(b.param.alpha(r.q[-1][[*b.pos, *b.rot]])[:3, :3], Rref))
    assert abs(ref.slope(dts, errs) - 4) <= 0.15, errs


def test_dop853_fixed_order_on_cay2():
    from lgt_bridge.integrators.problem import make_problem
    from lgt_bridge.integrators.rkmk import FixedRK
    from lgt_bridge.integrators.tableaux import dop853, fixed_form
    from lgt_bridge.simulation import Simulation
    J, w0 = np.array([1.0, 2.0, 3.0]), np.array([0.4, 1.0, -0.3])
    T = 2.0
    Rref, _ = ref.rigid_rotation(np.diag(J), w0, T)
    dts, errs = [0.5, 0.4, 0.3, 0.25], []
    for h in dts:
        m = scenes.free_body(J, w0)
        st = FixedRK(make_problem(m, "SO3xR3", "cay2"), fixed_form(dop853()))
        q, _ = Simulation.from_stepper(m, st, h, 0.0, m.q0, m.V0, t_end=T).advance_to(T)
        b = m.layout.bodies[0]
        errs.append(ref.angle(b.param.alpha(q[[*b.pos, *b.rot]])[:3, :3], Rref))
    assert 7.5 <= ref.slope(dts, errs) <= 8.8, (errs, ref.slope(dts, errs))


@pytest.mark.parametrize("method,kw,tol", [
    ("dop853", dict(rtol=1e-11, atol=1e-11), 1e-9),
    ("radau5", dict(rtol=1e-9, atol=1e-9), 1e-6),
    ("scipy:DOP853", dict(rtol=1e-11, atol=1e-11), 1e-8),
    ("genalpha", dict(dt=2.5e-5), 2e-4)])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_heavy_top_reference_reached_on_cay2(method, kw, tol, group):
    T = 0.05
    Rref, wref = ref.heavy_top(T)
    m = scenes.heavy_top(False)
    r = simulate(m, (0, T), method=method, group=group, chart="cay2", **kw)
    assert r.success, r.message
    b = m.layout.bodies[0]
    R = b.param.alpha(r.q[-1][[*b.pos, *b.rot]])[:3, :3]
    assert ref.angle(R, Rref) + np.abs(r.V[-1, :3] - wref).max() / 150 < tol


@pytest.mark.parametrize("param", ["quat", "quat_xyzw", "rotvec", "rxyz"])
def test_rotation_only_and_every_parameterization(param):
    """The top on its spherical joint (the pivot form: a rotation-only body) in every
    absolute parameterization agrees with the exp chart's run."""
    T = 0.05
    kw = dict(method="dop853", rtol=1e-11, atol=1e-11, t_eval=[T])
    a = simulate(scenes.heavy_top(True, param=param), (0, T), chart="cay2", **kw)
    b = simulate(scenes.heavy_top(True, param=param), (0, T), chart="exp", **kw)
    assert a.success and b.success
    assert np.abs(a.V[-1] - b.V[-1]).max() < 1e-7 * 150
