"""The sparse constraint rows of the Exudyn adapter (lgt_exudyn.sparse, lgt_exudyn.kernel_sparse)
against independent references, on chains, a tree and a closed loop of spherical joints, on
chains of generic joints (every kind of constrainedAxes, revolute-z and prismatic-x joints),
on the joint models of tests/models and on two models whose rows are gathered from Exudyn's
Jacobian (a node marker on a point mass, alternativeConstraints): the closed-form A equals Exudyn's own Jacobian mapped to
twists (C_q H) to rounding; the closed-form γ equals Richardson-extrapolated differences of
A(τ(q, sV)) V with Exudyn's Jacobian; the sparse index-1 solve equals the dense range-space
solve (lgt_bridge.model.solve_kkt), redundant rows included; the envelope of the reordered
Schur complement grows linearly with the rows; f equals the numpy backend's."""
import warnings

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.model import solve_kkt  # noqa: E402
from lgt_exudyn import kernels as K  # noqa: E402
from lgt_exudyn import scenes  # noqa: E402
from lgt_exudyn.model import ExudynModel  # noqa: E402
from lgt_exudyn.sparse import ESTART  # noqa: E402

import exudyn_joint_models as jm  # noqa: E402
import exudyn_models as em  # noqa: E402
from backend_checks import close  # noqa: E402

SPHERICAL = {
    "chain EP": lambda: scenes.chain(12, em.EP),
    "chain RotVecLG": lambda: scenes.chain(8, em.ROTVEC),
    "chain Rxyz": lambda: scenes.chain(5, em.RXYZ),
    "top EP": lambda: em.heavy_top(em.EP)[:2],
    "tree EP": lambda: em.spherical_tree(em.EP),
    "tree RotVecLG": lambda: em.spherical_tree(em.ROTVEC),
    "loop EP": lambda: em.spherical_loop(em.EP),
    "loop RotVecLG": lambda: em.spherical_loop(em.ROTVEC),
}
#: generic (every kind of constrainedAxes), revolute-z and prismatic-x joints: closed form too
JOINTS = {
    "revolute chain EP": lambda: scenes.chain(6, em.EP, joint="revolute"),
    "revolute chain RotVecLG": lambda: scenes.chain(4, em.ROTVEC, joint="revolute"),
    "generic chain EP": lambda: em.generic_chain(em.EP),
    "generic chain RotVecLG": lambda: em.generic_chain(em.ROTVEC),
    "generic chain Rxyz": lambda: em.generic_chain(em.RXYZ),
    "generic double pendulum": lambda: (None, jm.generic_double_pendulum(em.EP)),
    "slider pendulum (inactive row)": lambda: (None, jm.slider_pendulum(em.EP)),
    "four-bar": lambda: (None, jm.fourbar(em.EP)),
    "slider-crank": lambda: (None, jm.slider_crank(em.EP)),
    "Bricard loop": lambda: (None, jm.bricard(em.EP)),
}
CLOSED = {**SPHERICAL, **JOINTS}
#: other rows: A from Exudyn's dense Jacobian gathered into the objects' pattern
GATHERED = {
    "point mass on a node marker": lambda: em.point_mass_on_joint(em.EP),
    "welded by alternativeConstraints": lambda: em.welded_pair(em.EP),
}
TABLES = {**CLOSED, **GATHERED}


def build(table, name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = table[name]()
        mbs = out[1][0] if isinstance(out[1], tuple) else out[1]
        m = ExudynModel(mbs)
    return out, m, K.pack(m)


def exudyn_A(m, q):
    """Exudyn's AE Jacobian of the kept rows mapped to twists: C_q H (the numpy reference)."""
    m.sd.SetODE2Coordinates(q - m.ref)
    return m._Cq() @ m.H(q)


def closed_form(m, P, q, V):
    aval, gam = np.zeros(len(P.sp.acol)), np.zeros(m.n_constraints)
    K.joint_rows(P.T, q, V, *P.sp.joints, aval, gam)
    A = np.zeros((m.n_constraints, m.nv))
    np.add.at(A, (np.repeat(np.arange(m.n_constraints), np.diff(P.sp.aptr)), P.sp.acol), aval)
    return A, gam


@pytest.mark.parametrize("name", list(CLOSED))
def test_closed_form_rows_equal_exudyns_jacobian_and_gamma_its_differences(name, rng):
    _, m, P = build(CLOSED, name)
    assert P.sp is not None and P.sp.joints is not None
    for q, V, t in em.random_states(m, rng):
        A, gam = closed_form(m, P, q, V)
        assert close(A, exudyn_A(m, q), 1e-13)
        # γ = d/ds (A(τ(q, sV)) V) at s = 0: central differences, Richardson-extrapolated
        h = 1e-3 / max(1.0, np.abs(V).max())

        def d(e):
            return (exudyn_A(m, m._moved(q, V, e)) @ V - exudyn_A(m, m._moved(q, V, -e)) @ V) / (2 * e)
        ref = (4 * d(h / 2) - d(h)) / 3
        assert close(gam, ref, 1e-8)


@pytest.mark.parametrize("name", list(TABLES))
def test_sparse_solve_equals_the_dense_kkt_solve(name, rng):
    _, m, P = build(TABLES, name)
    sp = P.sp
    assert sp is not None and (sp.joints is None) == (name in GATHERED)
    for q, V, t in em.random_states(m, rng, 2):
        A = exudyn_A(m, q)
        sp.aval[:] = A.ravel()[sp.flat]
        assert close(sp.dense(*A.shape), A)                # the pattern holds A
        Qb, gam, Vd = rng.normal(size=m.nv), rng.normal(size=m.n_constraints), np.zeros(m.nv)
        assert K.sparse_solve(P.T, P.off, P.w, sp.I, sp.io, sp.F, sp.fo, sp.aval, Qb, gam, Vd) == 0
        want, lam = solve_kkt(m.Mbar, A, Qb, -gam)
        # both solves are backward stable: equal to a few roundings times the condition of S
        tol = max(1e-13, 10 * np.finfo(float).eps * np.linalg.cond(A @ np.linalg.solve(m.Mbar, A.T)))
        assert close(Vd, want, tol)
        assert close(sp.F[sp.fo[3]:sp.fo[4]], lam, 10 * tol)     # λ in the model's row order


@pytest.mark.parametrize("name", list(TABLES))
def test_f_equals_the_numpy_backend(name, rng):
    out, m, P = build(TABLES, name)
    ref = ExudynModel(m.mbs, backend="numpy")
    for q, V, t in em.random_states(m, rng, 2):
        V = 0.3 * V
        # the numpy backend's γ is a difference quotient over 2e-5: equal to 1e-9
        assert close(m.f(q, V, t), ref.f(q, V, t), 1e-9)
        assert close(m.constraint_jacobian(q), ref.constraint_jacobian(q), 1e-13)
        assert close(m.sd.GetODE2Coordinates_t(), m.rates_from_twist(q, V))


def test_redundant_rows_finish_with_the_minimum_norm_solve(rng):
    """Rows that repeat others make S singular: sparse_solve returns 1 and sparse_fallback
    gives the unique V̇ of the dense minimum-norm solve."""
    _, m, P = build(SPHERICAL, "chain EP")
    sp = P.sp
    A = exudyn_A(m, m.q0)
    dup = np.concatenate([np.arange(A.shape[0]), [0, 4]])
    A2 = A[dup]
    aptr = np.concatenate([[0], np.cumsum([np.count_nonzero(r) for r in A2])]).astype(np.int64)
    acol = np.concatenate([np.flatnonzero(r) for r in A2]).astype(np.int64)
    P.sp = K.SparseRows(P, aptr, acol, None)
    P.sp.aval[:] = A2.ravel()[P.sp.flat]
    Qb, gam = rng.normal(size=m.nv), rng.normal(size=A.shape[0])
    g2 = gam[dup]
    Vd = np.zeros(m.nv)
    assert K.sparse_solve(P.T, P.off, P.w, P.sp.I, P.sp.io, P.sp.F, P.sp.fo, P.sp.aval, Qb, g2, Vd) == 1
    K.sparse_fallback(m, P, m.q0, g2, Vd)
    assert close(Vd, solve_kkt(m.Mbar, A, Qb, -gam)[0], 1e-10)
    assert sp is not P.sp


@pytest.mark.parametrize("make", [lambda n: scenes.chain(n), lambda n: em.spherical_tree(length=n // 3)],
                         ids=["chain", "tree"])
def test_the_schur_envelope_grows_linearly(make):
    """Reverse Cuthill-McKee keeps the rows of neighbouring joints together: the envelope of S
    per row stays the same as the model grows (a band of a few joints), instead of nc / 2."""
    per_row = []
    for n in (20, 60):
        SC, mbs = make(n)
        m = ExudynModel(mbs)
        P = K.pack(m)
        nc = m.n_constraints
        per_row.append(P.sp.I[P.sp.io[ESTART] + nc] / nc)
        assert per_row[-1] < nc / 4
    assert per_row[1] <= 1.2 * per_row[0]


def test_unknown_joints_keep_the_dense_path():
    """A model the analysis cannot cover sparsely (no constant M̄) keeps the dense solve."""
    import test_exudyn_kernels as tk
    SC, mbs = tk.offset_com_pendulum()
    P = K.pack(ExudynModel(mbs))
    assert P.sp is None


@pytest.mark.parametrize("name", ["chain EP", "loop RotVecLG", "revolute chain EP", "generic chain EP",
                                  "point mass on a node marker"])
@pytest.mark.parametrize("dense_a", [True, False])
def test_constraint_schur_and_multipliers_equal_the_dense_ones(name, dense_a, rng, monkeypatch):
    """The projections' step (Model.constraint_schur) and the Lagrange multipliers written for
    Exudyn's sensors, from the sparse rows, against the dense defaults (lgt_bridge.model's
    dense constraint_schur, the least-squares multipliers of the numpy backend); A returned
    dense (small systems) and as a CSR matrix."""
    from lgt_bridge.model import Model
    monkeypatch.setattr(K, "DENSE_SCHUR_A", 10 ** 9 if dense_a else 0)
    _, m, P = build(TABLES, name)
    ref = ExudynModel(m.mbs, backend="numpy")
    for q, V, t in em.random_states(m, rng, 2):
        A, correct = m.constraint_schur(q)
        Ad, correct_d = Model.constraint_schur(ref, q)
        assert hasattr(A, "toarray") != dense_a
        assert close(A if dense_a else A.toarray(), Ad, 1e-13)
        r = rng.normal(size=m.n_constraints)
        tol = max(1e-12, 10 * np.finfo(float).eps * np.linalg.cond(Ad @ np.linalg.solve(m.Mbar, Ad.T)))
        assert close(correct(r), correct_d(r), tol)
        assert close(A @ correct(r), r, tol)                  # the step lands on A x = r
        assert close(m.multipliers(q, 0.3 * V, t), ref.multipliers(q, 0.3 * V, t), 1e-7)


def test_sparse_iteration_matrix_equals_the_dense_one(rng):
    """generalized-α's Newton parts asked sparse (large models) equal the dense ones."""
    _, m, P = build(SPHERICAL, "tree EP")
    for q, V, t in em.random_states(m, rng, 2):
        for c in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (2.0, 0.5, 3.0)):
            dense = m.iteration_matrix(q, V, t, *c)
            assert close(m.iteration_matrix(q, V, t, *c, sparse=True).toarray(), dense, 1e-13)
