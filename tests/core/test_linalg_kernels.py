"""The compiled Cholesky factorization and solve shared by the kernels
(lgt_bridge.kernels.linalg) against numpy: dense and with a row envelope, on a slice of a
larger work array; a matrix that is not positive definite is reported, not factorized."""
import numpy as np
import pytest

pytest.importorskip("numba")

from lgt_bridge.kernels.linalg import cholesky, cholesky_solve, envelope_cholesky, envelope_solve  # noqa: E402

from backend_checks import close  # noqa: E402


def spd(rng, n):
    B = rng.normal(size=(n, n))
    return B @ B.T + n * np.eye(n)


@pytest.mark.parametrize("n", [1, 2, 5, 12])
def test_dense_factor_and_solve_equal_numpy(n, rng):
    S = spd(rng, n)
    b = rng.normal(size=n)
    w = np.zeros(3 + n * n + n)                  # the factor and x as slices of a work array
    w[3:3 + n * n] = S.ravel()
    w[3 + n * n:] = b
    dense = np.zeros(0, np.int64)
    ok, dmin, dmax = cholesky(w[3:3 + n * n], n, dense)
    L = np.linalg.cholesky(S)
    assert ok and close(dmin, np.diag(L).min()) and close(dmax, np.diag(L).max())
    F = w[3:3 + n * n].reshape(n, n)
    assert close(np.tril(F, -1), np.tril(L, -1)) and close(np.diag(F), 1.0 / np.diag(L))
    cholesky_solve(w[3:3 + n * n], n, dense, w[3 + n * n:])
    assert close(w[3 + n * n:], np.linalg.solve(S, b))


def test_envelope_factor_equals_dense(rng):
    """A banded S: rows start at their envelope; the factor keeps it."""
    n, first = 9, np.array([0, 0, 0, 1, 1, 3, 3, 5, 6], np.int64)
    S = spd(rng, n)
    for i in range(n):
        S[i, :first[i]] = S[:first[i], i] = 0.0
    S += 3 * n * np.eye(n)
    x, flat = rng.normal(size=n), S.ravel().copy()
    want = np.linalg.solve(S, x)
    assert cholesky(flat, n, first)[0]
    cholesky_solve(flat, n, first, x)
    assert close(x, want)


@pytest.mark.parametrize("first", [[0, 0, 0, 1, 1, 3, 3, 5, 6], [0, 0, 1, 2, 3, 4, 5, 6, 7], list(range(9)),
                                   [0] * 9])
def test_packed_envelope_equals_numpy(first, rng):
    """The packed envelope (skyline) storage: the factor equals numpy's Cholesky factor entry
    by entry inside the envelope, and the solve numpy's solve."""
    n, first = len(first), np.array(first, np.int64)
    S = spd(rng, n)
    for i in range(n):
        S[i, :first[i]] = S[:first[i], i] = 0.0
    S += 3 * n * np.eye(n)
    start = np.concatenate([[0], np.cumsum(np.arange(n) - first + 1)]).astype(np.int64)
    packed = np.concatenate([S[i, first[i]:i + 1] for i in range(n)])
    ok, dmin, dmax = envelope_cholesky(packed, first, start)
    L = np.linalg.cholesky(S)
    assert ok and close(dmin, np.diag(L).min()) and close(dmax, np.diag(L).max())
    for i in range(n):
        row = packed[start[i]:start[i + 1]]
        assert close(row[:-1], L[i, first[i]:i]) and close(row[-1], 1.0 / L[i, i])
    x = rng.normal(size=n)
    want = np.linalg.solve(S, x)
    envelope_solve(packed, first, start, x)
    assert close(x, want)
    S[4, 4] = -50.0 * n
    packed = np.concatenate([S[i, first[i]:i + 1] for i in range(n)])
    assert not envelope_cholesky(packed, first, start)[0]


def test_not_positive_definite_is_reported(rng):
    S = spd(rng, 4)
    S[2, 2] = -1.0
    ok, dmin, dmax = cholesky(S.ravel().copy(), 4, np.zeros(0, np.int64))
    assert not ok and dmin == 0.0


@pytest.mark.parametrize("n,density", [(1, 1.0), (7, 0.5), (60, 0.08), (300, 0.02)])
def test_lu_solve_equals_superlu(n, density):
    """The compiled triangular solves on SuperLU's factors give SuperLU's own solution (the
    reference) on random nonsymmetric sparse matrices, whose pivoting permutes rows and
    columns; and that solution solves A x = b."""
    from scipy import sparse
    from scipy.sparse.linalg import splu
    from lgt_bridge.integrators.genalpha_matrix import _lu_solver
    rng = np.random.default_rng(n)
    A = (sparse.random(n, n, density=density, random_state=rng) + sparse.diags(rng.normal(size=n))).tocsc()
    lu = splu(A)
    b = rng.normal(size=n)
    x = _lu_solver(lu)(b)
    ref = lu.solve(b)
    assert np.abs(x - ref).max() <= 1e-12 * (1.0 + np.abs(ref).max())
    assert np.abs(A @ x - b).max() <= 1e-10 * (1.0 + np.abs(b).max()) * (1.0 + np.abs(x).max())


@pytest.mark.parametrize("n", [60, 106])
def test_band_lu_solves_like_superlu(n):
    """The banded LU (kernels.linalg.band_lu, through genalpha_matrix._band_solver) on a
    banded matrix with a saddle-point block (zero diagonal: pivoting needed) given in a
    scrambled order: its solution equals SuperLU's (the reference) and solves A x = b; the
    band order is kept for a matrix of the same pattern; a singular matrix raises, and a
    pattern too wide for a band gives None."""
    from scipy import sparse
    from scipy.sparse.linalg import splu
    from lgt_bridge.integrators.genalpha_matrix import _band_solver
    rng = np.random.default_rng(n)
    K = sparse.diags([rng.normal(size=n - abs(k)) for k in range(-3, 4)], list(range(-3, 4)), format="lil")
    C = sparse.csr_matrix((np.ones(2), ([0, 1], [0, 1])), shape=(2, n))
    P = rng.permutation(n + 2)
    memo = {}
    for _ in range(2):
        K.setdiag(rng.normal(size=n))
        A = sparse.bmat([[K, C.T], [C, None]]).tocsc()[P][:, P].tocsc()
        solve = _band_solver(A, memo)
        b = rng.normal(size=n + 2)
        ref = splu(A).solve(b)
        assert np.abs(solve(b) - ref).max() <= 1e-12 * (1.0 + np.abs(ref).max())
        assert np.abs(A @ solve(b) - b).max() <= 1e-10 * (1.0 + np.abs(ref).max())
    kl, ku = memo["band"][2:]
    assert kl + ku <= 14                                  # the band the order found (2 x 7 at most)
    S = A.tolil()
    S[P.tolist().index(5), :] = 0.0                       # row 5 of the unscrambled matrix
    S = S.tocsc()
    S.eliminate_zeros()
    with pytest.raises(np.linalg.LinAlgError):
        _band_solver(S, {})
    D = sparse.csc_matrix(rng.normal(size=(n, n)))
    assert _band_solver(D, {}) is None


@pytest.mark.parametrize("redundant", [False, True])
@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_schur_solver_on_both_backends_solves_the_schur_complement(backend, redundant, rng, monkeypatch):
    """lgt_bridge.model.schur_solver on S = A M⁻¹ Aᵀ (the compiled backend's own Cholesky up
    to 64 rows, numpy's otherwise): for independent rows S x = r to rounding, a vector and
    the columns of a matrix alike; for a redundant row (S singular, r consistent) the
    minimum-norm solution, whose constraint force M⁻¹Aᵀx is the one of the independent rows."""
    from lgt_bridge.model import schur_solver
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", backend)
    A = rng.normal(size=(4, 9))
    if redundant:
        A = np.vstack([A, A[0] + 2.0 * A[2]])
    M = spd(rng, 9)
    MiAt = np.linalg.solve(M, A.T)
    S = A @ MiAt
    Y = rng.normal(size=(len(A), 2))
    R = S @ Y                               # consistent; every solution x has M⁻¹Aᵀx = M⁻¹AᵀY
    solve = schur_solver(S)
    for r, y in ((R[:, 0], Y[:, 0]), (R, Y)):
        x = solve(r)
        assert x.shape == r.shape
        assert np.abs(S @ x - r).max() < 1e-10 * np.abs(r).max()
        want = MiAt @ y
        assert np.abs(MiAt @ x - want).max() < 1e-9 * np.abs(want).max()
        if redundant:                       # the minimum-norm one
            assert np.linalg.norm(x) <= np.linalg.norm(np.linalg.lstsq(S, r, rcond=None)[0]) * (1 + 1e-9)


@pytest.mark.parametrize("n", [1, 2, 5, 15, 64])
def test_dense_lu_and_its_solves_equal_scipy(n, rng):
    """kernels.linalg.dense_lu / dense_lu_solve (generalized-α's small Newton matrices, no BLAS
    threads) against scipy.linalg.lu_factor / lu_solve: the same pivots, the same J⁻¹B, and
    genalpha_matrix.factorize's compiled and scipy branches give the same J⁻¹ L r and J⁻¹ r;
    an exactly singular matrix raises LinAlgError in both."""
    import scipy.linalg as sla
    from lgt_bridge.integrators.genalpha_matrix import factorize
    from lgt_bridge.kernels.linalg import dense_lu, dense_lu_solve
    J = rng.normal(size=(n, n)) + 0.1 * np.eye(n)
    B = rng.normal(size=(n, 3))
    A, piv = J.copy(), np.empty(n, np.int64)
    assert dense_lu(A, piv) == 0
    lu, p = sla.lu_factor(J)
    assert np.array_equal(piv, p) and close(A, lu, 1e-12)
    X = B.copy()
    dense_lu_solve(A, piv, X)
    assert close(X, sla.lu_solve((lu, p), B), 1e-10)
    assert close(J @ X, B, 1e-10)
    L, r = rng.normal(size=(n, n)), rng.normal(size=n)
    for LL in (None, L):
        a, b = factorize(J, LL, compiled=True)(r), factorize(J, LL, compiled=False)(r)
        assert a.shape == b.shape == (n,) and close(a, b, 1e-10)
    S = J.copy()
    S[:, -1] = 0.0
    for compiled in (True, False):
        with pytest.raises(np.linalg.LinAlgError):
            factorize(S, L, compiled=compiled)
