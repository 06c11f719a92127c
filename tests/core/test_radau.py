"""radau5: Radau IIA (order 5) on the local coordinates.

The tableau against the collocation and quadrature order conditions and Hairer's published
error weights; the fitted order of fixed-step runs; the model Jacobian against differences of
F; a stiff model (critically damped stiff springs) against a tight explicit reference at a
fraction of the explicit method's evaluations; dense output; projection of a constrained
model; both backends; failures reported as results."""
import math

import numpy as np
import pytest

from lgt_bridge import scenes
from lgt_bridge.bench import pose_error
from lgt_bridge.integrators import radau as rd
from lgt_bridge.integrators.problem import make_problem
from lgt_bridge.simulate import simulate

import backend_checks


# --- the tableau -----------------------------------------------------------------------------
def test_tableau_meets_the_collocation_and_quadrature_conditions():
    c, A = rd.C, rd.A
    b = A[-1]
    for k in range(1, 4):                           # C(3): Σ_j a_ij c_j^(k-1) = c_i^k / k
        np.testing.assert_allclose(A @ c ** (k - 1), c ** k / k, rtol=0, atol=1e-15)
    for k in range(1, 6):                           # B(5): Radau quadrature of order 5
        assert abs(b @ c ** (k - 1) - 1.0 / k) < 1e-15
    assert abs(b @ c ** 5 - 1.0 / 6) > 1e-4         # ... and not 6
    # A⁻¹ = T Λ T⁻¹ with Λ = diag(γ, [[α, -β], [β, α]]) acting as conj(μ) on w2 + i w3
    Lam = rd.TI @ np.linalg.inv(A) @ rd.T
    expect = np.array([[rd.GAMMA, 0, 0], [0, rd.MU.real, -rd.MU.imag], [0, rd.MU.imag, rd.MU.real]])
    np.testing.assert_allclose(Lam, expect, atol=1e-12)
    np.testing.assert_allclose(rd.LAMBDA, expect, atol=1e-12)       # what the Newton iteration uses
    # γ: the real eigenvalue of A⁻¹, 3 + 3^(2/3) - 3^(1/3) (Hairer & Wanner IV.8)
    assert abs(rd.GAMMA - (3 + 3 ** (2 / 3) - 3 ** (1 / 3))) < 1e-13


def test_error_weights_are_hairers():
    s6 = math.sqrt(6.0)
    np.testing.assert_allclose(rd.E, np.array([-13 - 7 * s6, -13 + 7 * s6, -1]) / 3, rtol=1e-13)


def test_dense_polynomial_interpolates_the_stages():
    rng = np.random.default_rng(3)
    Z = rng.normal(size=(3, 5))
    coef = rd.P.T @ Z
    for ci, zi in zip(rd.C, Z):
        np.testing.assert_allclose(ci * coef[0] + ci ** 2 * coef[1] + ci ** 3 * coef[2], zi, atol=1e-13)


# --- order ------------------------------------------------------------------------------------
def _fixed_steps(model, T, n, group):
    """n steps of h = T/n with Newton to 1e-13 and the error control out of the way."""
    prob = make_problem(model, group, "exp")
    st = rd.Radau5(prob, rtol=1e3, atol=1e3)
    st.newton_tol = 1e-13
    st.NEWTON_MAXITER = 20
    st.set_state(model.q0, model.V0)
    h, t = T / n, 0.0
    for _ in range(n):
        ok, _ = st.attempt(t, h)
        assert ok
        t += h
    return st.q


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_fitted_order_is_five(group):
    """A free asymmetric body with a translation (both groups act on it): slope of log error
    against log h."""
    m = scenes.free_body(omega0=(0.5, 2.0, 0.3), v0=(0.2, -0.1, 0.3))
    T = 1.0
    ref = simulate(m, (0, T), method="dop853", group=group, rtol=1e-14, atol=1e-14).q[-1]
    ns = [4, 6, 8, 12]
    errs = [pose_error(m, _fixed_steps(m, T, n, group), ref) for n in ns]
    slope = -np.polyfit(np.log(ns), np.log(errs), 1)[0]
    assert 4.7 <= slope <= 5.5, (slope, errs)


# --- the model Jacobian ------------------------------------------------------------------------
def _jacobians(model, group, chart, t=0.1):
    prob = make_problem(model, group, chart)
    st = rd.Radau5(prob, 1e-6, 1e-6)
    st.set_state(model.q0, model.V0)
    f0 = st._start_rates(t)
    st._fd_jacobian(t, f0)
    return rd.model_jacobian(prob, st._kin, st.q, st.V, st.W, f0, t, st._sparse_kw), st.J


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("chart", ["exp", "cay", "cay2"])
@pytest.mark.parametrize("make", [lambda: scenes.free_bodies(3, seed=1), lambda: scenes.heavy_top(param="rotvec"),
                                  lambda: scenes.chain(3)], ids=["free_bodies", "pivoted_top", "chain"])
def test_model_jacobian_equals_differences_of_F(group, chart, make):
    m = make()
    if m.n_constraints:                             # the index-1 f of a jointed chain: differenced
        assert not rd.Radau5(make_problem(m, group, chart), 1e-6, 1e-6)._analytic
        m = scenes.free_bodies(2, seed=5)
    Ja, Jd = _jacobians(m, group, chart)
    assert np.abs(Ja - Jd).max() <= 2e-6 * max(1.0, np.abs(Jd).max())


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_model_jacobian_of_a_large_model_is_sparse_and_equals_differences(group):
    """40 bodies (480 unknowns): assembled from per-body blocks in scipy.sparse, M by SuperLU."""
    Ja, Jd = _jacobians(scenes.free_bodies(40, seed=6), group, "exp")
    assert hasattr(Ja, "tocsc") and Ja.nnz < 0.05 * Jd.size
    assert np.abs(Ja.toarray() - Jd).max() <= 2e-6 * max(1.0, np.abs(Jd).max())


# --- stiff ------------------------------------------------------------------------------------
def damped_stiff_body(k=1e8):
    """A spinning body held at two points by stiff, critically damped zero-length springs."""
    J = np.diag([0.1, 0.2, 0.3])
    q0 = np.array([0.001, 0.0, -0.002, 1.0, 0.0, 0.0, 0.0])
    V0 = np.array([0.5, 3.0, 0.1, 0.0, 0.0, 0.0])
    a, b = np.array([0.1, 0.0, 0.0]), np.array([-0.1, 0.05, 0.0])
    d = 2.0 * math.sqrt(k)
    return scenes.RigidBodySystem([1.0], [J], q0, V0, springs=[(0, a, -1, a, k, d), (0, b, -1, b, k, d)])


def test_stiff_model_at_a_fraction_of_the_explicit_evaluations():
    """|λ| ≈ 2·10⁴ s⁻¹: dopri5 is held to |λ| h ≲ 3.3 (about 6·10⁴ f over 1 s, measured), radau5
    steps by accuracy alone (about 2000 f, error about 1e-9)."""
    m = damped_stiff_body()
    ref = simulate(m, (0, 1.0), method="dop853", rtol=1e-12, atol=1e-12)
    r = simulate(m, (0, 1.0), method="radau5", rtol=1e-7, atol=1e-7)
    e = simulate(m, (0, 1.0), method="dopri5", rtol=1e-7, atol=1e-7)
    assert r.success and e.success
    assert pose_error(m, r.q[-1], ref.q[-1]) < 2e-8
    assert r.stats["n_f"] < 0.1 * e.stats["n_f"], (r.stats, e.stats)


def test_pure_absolute_tolerance_keeps_newton_accurate():
    """rtol = 0 (allowed: pure absolute tolerance) takes Newton's tolerance from atol; before,
    the tolerance was 10 eps / 0 and Newton stopped after two iterations (measured 1.6e-9
    against 7.6e-11 with rtol = atol = 1e-8 on this body)."""
    m = scenes.free_body(omega0=(0.5, 2.0, 0.3), v0=(0.1, 0.0, 0.0))
    ref = simulate(m, (0, 1.0), method="dop853", rtol=1e-13, atol=1e-13).q[-1]
    absolute = simulate(m, (0, 1.0), method="radau5", rtol=0.0, atol=1e-8)
    mixed = simulate(m, (0, 1.0), method="radau5", rtol=1e-8, atol=1e-8)
    assert absolute.success and mixed.success
    assert pose_error(m, absolute.q[-1], ref) <= 3 * pose_error(m, mixed.q[-1], ref)


# --- dense output, constraints, backends, failures ----------------------------------------------
def test_dense_output_and_output_times_do_not_shorten_steps():
    m = scenes.free_bodies(2, seed=2)
    T = 1.0
    ts = np.linspace(0, T, 1001)
    ref = simulate(m, (0, T), method="dop853", rtol=1e-13, atol=1e-13, t_eval=ts)
    plain = simulate(m, (0, T), method="radau5", rtol=1e-8, atol=1e-8)
    dense = simulate(m, (0, T), method="radau5", rtol=1e-8, atol=1e-8, t_eval=ts)
    assert dense.stats["n_steps"] <= plain.stats["n_steps"]
    errs = [pose_error(m, q, qr) for q, qr in zip(dense.q, ref.q)]
    # the collocation polynomial is cubic: within a step it is good to about h⁴, measured
    # at 3e-8 here; the end point (a step end) is the method's own order
    assert max(errs) < 3e-7, max(errs)
    assert errs[-1] < 1e-7


def test_constrained_heavy_top_is_projected():
    top = scenes.heavy_top(constrained=True, param="quat")
    ref = simulate(top, (0, 0.2), method="dop853", rtol=1e-12, atol=1e-12)
    r = simulate(top, (0, 0.2), method="radau5", group="SE3", rtol=1e-8, atol=1e-8)
    assert r.success
    assert r.stats["constraint_after_projection"] < 1e-10
    assert pose_error(top, r.q[-1], ref.q[-1]) < 1e-5


def test_backends_agree(monkeypatch):
    out = []
    for b in ("numpy", "numba"):
        monkeypatch.setenv("LGT_BRIDGE_BACKEND", b)
        m = scenes.top_and_free_bodies(2, param="rotvec")
        out.append(simulate(m, (0, 0.05), method="radau5", group=["SE3", "SO3xR3", "SE3"],
                            chart=["exp", "cay", "exp"], rtol=1e-9, atol=1e-9))
    assert out[0].success and out[1].success
    # Newton stops at a tolerance, so rounding differences move the answer by about that much
    assert backend_checks.close(out[1].q[-1], out[0].q[-1], 1e-9, floor=1.0)


def test_a_model_that_returns_nan_ends_the_run_with_the_steps_kept():
    m = scenes.free_bodies(1, seed=0)
    good = m.f

    def f(q, V, t):
        return good(q, V, t) * (np.nan if t > 0.3 else 1.0)
    m.f = f
    r = simulate(m, (0, 1.0), method="radau5", rtol=1e-6, atol=1e-6)
    assert not r.success
    assert r.t[-1] <= 0.3 + 1e-12 and len(r.t) > 2
    assert np.isfinite(r.q).all()
