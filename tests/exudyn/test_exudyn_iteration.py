"""Generalized-α's Newton matrix for Exudyn models (ExudynModel.iteration_matrix, from
Exudyn's own ComputeJacobianODE2RHS mapped to twists) against central differences of the
residual R = M̄ V̇ - Q̄ along τ and V, and whole generalized-α runs on it against the same runs
with the finite-difference matrix. The bounds are the measured accuracy of what the matrix
leaves out (see its docstring): C_t is exact to the differences' error, K_t misses the
(∂Hᵀ/∂z) R term (0.09 % measured on RotVecLG, 3.6 % on EP, 9.5 % on Rxyz)."""
import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.simulate import make_stepper, simulate  # noqa: E402
from lgt_exudyn import model as em_model  # noqa: E402
from lgt_exudyn.model import ExudynModel  # noqa: E402

import exudyn_models as em  # noqa: E402

#: (node type, bound on K_t's relative difference from the residual's central differences)
SPRING = {"EP": (em.EP, 0.06), "RotVecLG": (em.ROTVEC, 0.005), "Rxyz": (em.RXYZ, 0.12)}


def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


def residual_differences(m, q, V, Vd, t, eps=1e-6):
    """(C_t, K_t) by central differences of M̄(q) V̇ - Q̄(q, V, t)."""
    def res(q, V):
        return m.mass_matrix(q) @ Vd - m.forces(q, V, t)
    C, K = np.empty((m.nv, m.nv)), np.empty((m.nv, m.nv))
    for k in range(m.nv):
        e = np.zeros(m.nv)
        e[k] = eps
        K[:, k] = (res(m._moved(q, e, 1.0), V) - res(m._moved(q, -e, 1.0), V)) / (2 * eps)
        C[:, k] = (res(q, V + e) - res(q, V - e)) / (2 * eps)
    return C, K


@pytest.mark.parametrize("node", list(SPRING))
def test_iteration_matrix_against_differences_of_the_residual(node):
    typ, k_bound = SPRING[node]
    SC, mbs = em.spring_body_with_load(typ)
    m = ExudynModel(mbs)
    rng = np.random.default_rng(3)
    q = m._moved(m.q0, rng.normal(size=m.nv) * 0.3, 1.0)
    V, t = rng.normal(size=m.nv) * 2, 0.3
    Vd = m.f(q, V, t)
    M, C, K = (m.iteration_matrix(q, V, t, *c) for c in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)))
    Cf, Kf = residual_differences(m, q, V, Vd, t)
    assert rel(M, m.mass_matrix(q)) < 1e-12
    assert rel(C, Cf) < 1e-6
    assert rel(K, Kf) < k_bound
    np.testing.assert_allclose(m.iteration_matrix(q, V, t, 2.0, -3.0, 5.0), 2 * M - 3 * C + 5 * K,
                               rtol=1e-13, atol=1e-13 * np.abs(K).max())


def test_rxyz_models_get_the_analytic_matrix_with_differenced_omega_columns():
    """Exudyn's Jacobian misses the adapter's Ḣ V term of Rxyz nodes (C_t was 170 % off): the
    nodes' ω columns of C_t come from differences of Q̄ (iteration.rxyz_columns), the rest of
    the matrix is Exudyn's; generalized-α takes it instead of differencing the whole step."""
    SC, mbs = em.spring_body_with_load(em.RXYZ)
    m = ExudynModel(mbs)
    assert m.iteration_matrix is not None
    ga, _ = make_stepper(m, "genalpha", "SO3xR3", "exp", dt=1e-3)
    assert ga.analytic


@pytest.mark.parametrize("node", list(SPRING))
def test_genalpha_on_the_analytic_matrix_matches_the_finite_difference_one(node, monkeypatch):
    """Same steps, same answer to the Newton tolerance, fewer f evaluations."""
    def run():
        SC, mbs = em.spring_body_with_load(SPRING[node][0])
        m = ExudynModel(mbs)
        r = simulate(m, (0.0, 0.2), method="genalpha", group="SO3xR3", chart="exp", dt=2e-3)
        assert r.success, r.message
        return r
    analytic = run()
    monkeypatch.setattr(em_model.ExudynModel, "iteration_matrix", None)
    fd = run()
    assert analytic.stats["n_steps"] == fd.stats["n_steps"]
    scale = np.abs(fd.q[-1]).max()
    assert np.abs(analytic.q[-1] - fd.q[-1]).max() < 1e-7 * scale
    assert np.abs(analytic.V[-1] - fd.V[-1]).max() < 1e-6 * np.abs(fd.V[-1]).max()
    assert analytic.stats["n_f"] < fd.stats["n_f"]


def test_one_jacobian_combination_equals_the_separate_jacobians():
    """Without rotation coordinates (an ANCF cable with axial and bending damping: both C_t
    and K_t) a combination c_acc M̄ + c_vel C_t + c_pos K_t is one Exudyn Jacobian call
    (iteration.selected_matrix): it equals M̄, C_t and K_t from Exudyn's two separate
    Jacobians (iteration.newton_parts) combined, to rounding."""
    from lgt_exudyn.iteration import newton_parts, selected_matrix
    from exudyn_solver_models import ancf_cable_damped
    mbs, _, _ = ancf_cable_damped()
    m = ExudynModel(mbs)
    rng = np.random.default_rng(5)
    q, V, t = m.q0 + 0.05 * rng.normal(size=m.nv), rng.normal(size=m.nv), 0.02
    M, C, K = newton_parts(m, q, V, t, False)
    assert np.abs(C).max() > 0 and np.abs(K).max() > 0
    for c in ((1.0, 0.3, 0.02), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (2.0, -3.0, 5.0)):
        one = selected_matrix(m, q, V, t, *c, False)
        ref = c[0] * M + c[1] * C + c[2] * K
        assert np.abs(one - ref).max() <= 1e-13 * np.abs(ref).max()
        assert np.abs(m.iteration_matrix(q, V, t, *c) - ref).max() <= 1e-13 * np.abs(ref).max()
    sparse = selected_matrix(m, q, V, t, 1.0, 0.3, 0.02, True)
    assert np.abs(sparse.toarray() - (M + 0.3 * C + 0.02 * K)).max() <= 1e-13 * np.abs(K).max()
    assert selected_matrix(m, q, V, t, 1.0, 0.0, 0.0, False) is None        # M̄ alone: no Jacobian


@pytest.mark.parametrize("sparse", [False, True])
def test_rotvec_newton_parts_are_a_selection_of_exudyns_jacobians(sparse, monkeypatch):
    """RotVecLG nodes' block of H is the identity, so Hᵀ J H is J's rows and columns
    selected: newton_parts takes them without building H (its sparse products had been 40 %
    of a Newton matrix on 36 RotVecLG bodies), and they equal the products with H."""
    from lgt_exudyn import iteration, layout
    SC, mbs = em.spring_body_with_load(em.ROTVEC)
    m = ExudynModel(mbs)
    rng = np.random.default_rng(11)
    q = m._moved(m.q0, rng.normal(size=m.nv) * 0.3, 1.0)
    V, t = rng.normal(size=m.nv) * 2, 0.3
    H = m.nodes.H(q)
    refs = []
    for fq, fv in ((0.0, 1.0), (1.0, 0.0)):           # Hᵀ J H from Exudyn's own Jacobians
        m._forces_compiled(q, V, t) if m._compiled else m._evaluate(q, V, t, False)
        m.solver.ComputeJacobianODE2RHS(m.mbs, fq, fv, 1.0, 2)
        refs.append(-H.T @ np.asarray(m.solver.GetSystemJacobian())[:m.n2, :m.n2] @ H)

    def no_H(*a, **k):
        raise AssertionError("H built for a RotVecLG model's Newton matrix")
    monkeypatch.setattr(layout.NodeLayout, "H_sparse", no_H)
    parts = iteration.newton_parts(m, q, V, t, sparse)
    for got, ref in zip(parts[1:], refs):
        got = got.toarray() if sparse else got
        assert np.abs(got - ref).max() <= 1e-14 * np.abs(ref).max()


@pytest.mark.parametrize("node", ["EP", "Rxyz"])
@pytest.mark.parametrize("sparse", [False, True])
def test_compiled_newton_parts_equal_the_products_with_H(node, sparse):
    """On compiled models Hᵀ J H comes from the mass-matrix kernel (kernel_maps.forces with
    V = 0, Q = 0), not from H's sparse products: the same matrices to rounding."""
    from lgt_exudyn import iteration
    SC, mbs = em.spring_body_with_load(SPRING[node][0])
    m = ExudynModel(mbs)
    assert m._compiled
    rng = np.random.default_rng(13)
    q = m._moved(m.q0, rng.normal(size=m.nv) * 0.3, 1.0)
    V, t = rng.normal(size=m.nv) * 2, 0.3
    got = iteration._jacobian_parts(m, q, V, t, sparse)
    m._compiled = False                              # the numpy path: H and its products
    try:
        ref = iteration._jacobian_parts(m, q, V, t, sparse)
    finally:
        m._compiled = True
    for g, r in zip(got, ref):
        g, r = (x.toarray() if hasattr(x, "toarray") else np.asarray(x) for x in (g, r))
        assert np.abs(g - r).max() <= 1e-13 * np.abs(r).max()
