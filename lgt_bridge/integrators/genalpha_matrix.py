"""The Newton iteration matrix of generalized-α, assembled per body (block-sparse).

The unknowns are Ẇ_{k+1} (per rigid body (ω̇, u̇) on SE(3), u = Rᵀṙ body-fixed;
(ω̇, r̈) on SO(3)xR³; ω̇ for a rotation-only body; v̇ for vector coordinates) and λ.
With k = (1 - α_f)/(1 - α_m), s_v = hγk and s_p = h²βk a change δẆ moves

    d = h W_k + h²(½ - β) a_k + h²β a_{k+1}   by s_p δẆ,    X = S d   (S: the chart scale)
    W_{k+1}                                   by s_v δẆ

and the body (in the group G of its set) by the body-frame increment ξ = dψ_{-X} S δd
(T(ΔX) = dψ_{-X}, exact: no T ≈ I simplification). The model's matrices act on the
increments of SO(3)xR³, δz = (δθ body, δr inertial), and on V = (ω, ṙ):

    δz = Pᵀ ξ,  Pᵀ = blockdiag(I, R) on SE(3) (r' = r + R ξ_lin + O(ξ²)), I on SO(3)xR³
    SE(3):  V_lin = R u,              δV_lin = s_v R δu̇ - R ũ δθ
            V̇_lin = R (u̇ + ω × u),   δV̇_lin = R δu̇ + s_v R (ω̃ δu̇ - ũ δω̇) - R (u̇ + ω × u)~ δθ

(δR = R δθ~). Per body this gives three block transforms — Z = ∂z/∂Ẇ, D_v = ∂V/∂Ẇ,
D_a = ∂V̇/∂Ẇ — and the Jacobian of the residual in the model's rows

    ∂(M V̇ - Q + Aᵀλ)/∂Ẇ = M D_a + C_t D_v + K_t Z,     ∂(g/(h²β))/∂Ẇ = A Z/(h²β)

with M, C_t = -∂Q/∂V and K_t = ∂(M V̇ - Q + Aᵀλ)/∂z the model's (``iteration_matrix``).
Every product with a block transform is formed on the model matrices' nonzeros (COO
triples), and the whole matrix is built as one sparse matrix.
"""
import copy
import warnings

import numpy as np

from ..groups._vec import cross, hat

_EYE3 = np.eye(3)

SPARSE_MIN = 200        # unknowns above which the iteration matrix is factored sparse
DENSE_MAX = 64          # unknowns up to which it is assembled and factored dense (scipy.sparse's
                        # per-call overhead, ~0.5 ms a matrix, would dominate a small model's step)
BLOCK_MAX = 12          # independent diagonal blocks up to this size are inverted explicitly


def coo(X):
    """(rows, cols, values) of the nonzeros of a dense or scipy.sparse matrix."""
    if hasattr(X, "tocoo"):
        X = X.tocoo()
        keep = X.data != 0
        return X.row[keep].astype(np.int64), X.col[keep].astype(np.int64), X.data[keep]
    X = np.asarray(X, float)
    r, c = np.nonzero(X)
    return r, c, X[r, c]


def csr(shape, parts):
    """One matrix from COO triples (duplicates summed): scipy.sparse CSR, or a dense array
    up to DENSE_MAX rows."""
    return assemble(shape, parts, sparse=shape[0] > DENSE_MAX)


def assemble(shape, parts, sparse):
    """One matrix from COO triples (duplicates summed; zeros dropped): scipy.sparse CSR when
    ``sparse``, else a dense array."""
    parts = [p for p in parts if len(p[0])]
    if not sparse:
        out = np.zeros(shape)
        for r, c, v in parts:
            np.add.at(out, (r, c), v)
        return out
    from scipy import sparse as sp
    if not parts:
        return sp.csr_matrix(shape)
    r, c, v = (np.concatenate([p[i] for p in parts]) for i in range(3))
    keep = v != 0
    return sp.csr_matrix((v[keep], (r[keep], c[keep])), shape=shape)


class DensePattern:
    """Dense matrices of one nonzero pattern as scipy CSC, the pattern's index arrays kept:
    each matrix then costs one gather of its entries, not a conversion (a format change
    costs ~30 µs on a 100 x 100 matrix, a fifth of a Newton matrix). A matrix with a nonzero
    outside the kept pattern (or another shape) sets a new one; entries of the pattern that
    are zero stay as explicit zeros (the sparse LU keeps them as structural)."""

    def __init__(self):
        self.shape = None

    def csc(self, D):
        from scipy import sparse
        D = np.ascontiguousarray(D, dtype=float)
        if D.shape == self.shape:
            data = D.ravel()[self.flat]
            if np.count_nonzero(data) == np.count_nonzero(D):
                C = copy.copy(self.template)      # its index arrays shared (scipy's constructor
                C.data = data                     # checks them each time: ~25 µs)
                return C
        C = sparse.csc_matrix(D)
        C.sort_indices()
        self.shape, self.indptr, self.indices, self.template = D.shape, C.indptr, C.indices, C
        self.flat = C.indices * D.shape[1] + np.repeat(np.arange(D.shape[1]), np.diff(C.indptr))
        return copy.copy(C)


def accepts(fn, keyword):
    """True when the callable ``fn`` takes the keyword argument ``keyword``."""
    import inspect
    try:
        return keyword in inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False


class BlockDiagonal:
    """A block-diagonal matrix over V's layout, stored by rows: row j holds the row of
    its body's block (at most ``width`` entries; unused slots are zeros on the diagonal)."""

    def __init__(self, n, width=6):
        self.n = n
        self.cols = np.repeat(np.arange(n)[:, None], width, axis=1)
        self.vals = np.zeros((n, width))

    def add(self, idx, blocks):
        """idx (N, m): V indices of N bodies; blocks (N, m, m)."""
        m = idx.shape[1]
        self.cols[idx, :m] = idx[:, None, :]
        self.vals[idx, :m] = blocks

    def set_diagonal(self, idx, value):
        self.vals[idx, 0] = value

    def rmul(self, rows, cols, vals):
        """X D for X given by COO triples: COO triples (duplicates to be summed)."""
        w = self.vals.shape[1]
        return (np.repeat(rows, w), self.cols[cols].ravel(), (vals[:, None] * self.vals[cols]).ravel())

    def triples(self):
        return np.repeat(np.arange(self.n), self.vals.shape[1]), self.cols.ravel(), self.vals.ravel()


class Kinematics:
    """The per-body block transforms Z, D_v, D_a (and Pᵀ) of one local problem."""

    def __init__(self, prob):
        self.prob = prob
        self.dpsi = [s.chart.on("SO3" if s.rot_only else "SE3" if s.se3 else "SO3xR3").dpsi
                     for s in prob.sets]
        if getattr(prob, "compiled", False):    # the same blocks from a kernel (kernels.genalpha.dpsi_neg)
            from ..kernels.genalpha import dpsi_neg
            self.dpsi = [self._compiled_dpsi(dpsi_neg, s.chart.code, 0 if s.rot_only else 2 if s.se3 else 1)
                         for s in prob.sets]
        # vector and circle coordinates: dψ = 1 (circles: SO(2) is abelian)
        self.vector_v = np.array(prob.layout.vector_v + prob.layout.circle_v, int)
        self.wlin = [s.wlin for s in prob.sets if s.se3]

    @staticmethod
    def _compiled_dpsi(kernel, code, kind):
        def dpsi(X):                            # the charts' dpsi(X) as dψ_{−(−X)}
            X = np.ascontiguousarray(-X, dtype=float)
            out = np.empty((X.shape[0], X.shape[1], X.shape[1]))
            kernel(code, kind, X, out)
            return out
        return dpsi

    def rotations(self, quats):
        """R of every SE(3) body, per set, read off the problem's own V_lin = R u (whatever
        form the backend keeps its quaternions in)."""
        if not self.wlin:
            return []
        cols = []
        for j in range(3):
            E = np.zeros(self.prob.nv)
            for wl in self.wlin:
                E[wl[:, j]] = 1.0
            cols.append(self.prob.model_velocity(E, quats))
        return [np.stack([c[wl] for c in cols], axis=2) for wl in self.wlin]

    def transforms(self, dX, W, Wd, quats, s_v, s_p):
        """(Z, D_v, D_a, Pᵀ) as :class:`BlockDiagonal` at the iterate (X = dX, W, Ẇ and the
        configuration's quaternions); Pᵀ = blockdiag(I, R) per SE(3) body, None without
        SE(3) bodies."""
        prob = self.prob
        n = len(W)
        Z, Dv, Da = BlockDiagonal(n), BlockDiagonal(n), BlockDiagonal(n)
        Pt = None
        if self.wlin:
            Pt = BlockDiagonal(n)
            Pt.set_diagonal(np.arange(n), 1.0)
        Rs = iter(self.rotations(quats))
        for s, dpsi in zip(prob.sets, self.dpsi):
            X, S = dX[s.xidx], prob.chart_scale[s.xidx]
            nb, m = X.shape
            G = s_p * dpsi(-X) * S[:, None, :]                           # ∂ξ/∂Ẇ
            eye = np.broadcast_to(np.eye(m), (nb, m, m))
            if not s.se3:
                Z.add(s.vidx, G)
                Dv.add(s.vidx, s_v * eye)
                Da.add(s.vidx, eye)
                continue
            R = next(Rs)
            w, u, ud = W[s.wang], W[s.wlin], Wd[s.wlin]
            theta = G[:, :3, :]                                         # ∂δθ/∂Ẇ
            z = G.copy()
            z[:, 3:, :] = R @ G[:, 3:, :]
            RU = R @ hat(u)
            dv = np.zeros((nb, 6, 6))
            dv[:, :3, :3] = s_v * _EYE3
            dv[:, 3:, 3:] = s_v * R
            dv[:, 3:, :] -= RU @ theta
            da = np.zeros((nb, 6, 6))
            da[:, :3, :3] = _EYE3
            da[:, 3:, :3] = -s_v * RU
            da[:, 3:, 3:] = R + s_v * (R @ hat(w))
            da[:, 3:, :] -= (R @ hat(ud + cross(w, u))) @ theta
            pt = np.zeros((nb, 6, 6))
            pt[:, :3, :3] = _EYE3
            pt[:, 3:, 3:] = R
            Z.add(s.vidx, z)
            Dv.add(s.vidx, dv)
            Da.add(s.vidx, da)
            Pt.add(s.vidx, pt)
        if len(self.vector_v):
            Z.set_diagonal(self.vector_v, s_p)
            Dv.set_diagonal(self.vector_v, s_v)
            Da.set_diagonal(self.vector_v, 1.0)
        return Z, Dv, Da, Pt


def factorize(J, L=None, compiled=False, memo=None):
    """A solver r ↦ J⁻¹ (L r) (L = None: the identity) for dense or scipy.sparse J, L.
    A J that falls apart into independent blocks of at most BLOCK_MAX unknowns (bodies
    that do not interact) is inverted block by block and J⁻¹L applied as one sparse
    product (a sparse triangular solve costs more than that); otherwise sparse LU above
    SPARSE_MIN unknowns or for a sparse J under a quarter full, dense LU below; a dense J
    of at most DENSE_MAX unknowns goes straight to dense LU (and J⁻¹L is formed once).
    Raises np.linalg.LinAlgError or RuntimeError on a singular J. ``compiled``: the block
    product and the sparse LU's solves run in kernels (scipy's matrix-vector product and
    SuperLU's solve cost ~3 µs a call, most of a Newton iteration's own work on 100
    bodies), and a sparse J of at most SPARSE_MIN unknowns that a bandwidth-reducing order
    makes narrow is factored banded (:func:`_band_solver`). ``memo``: a dict kept between
    calls, where a pattern of J found not to fall apart, and its band order, are remembered
    and not searched again."""
    from scipy import sparse
    dense = not sparse.issparse(J) and J.shape[0] <= DENSE_MAX
    S = None
    if not dense:
        Jc = J if sparse.isspmatrix_csc(J) else sparse.csr_matrix(J)
        key = (Jc.format, Jc.shape, Jc.indptr.tobytes(), Jc.indices.tobytes()) if memo is not None else None
        if key is None or memo.get("one_block") != key:
            S = _block_inverse(Jc, L)
            if S is None and key is not None:
                memo["one_block"] = key
    if S is not None:
        return _csr_product(S) if compiled else S.__matmul__
    if J.shape[0] > SPARSE_MIN or (sparse.issparse(J) and 4 * J.nnz < J.shape[0] ** 2):
        # (a sparse J of a moderate size too: a dense J⁻¹L is a threaded BLAS-3 solve,
        # whose threads cost ~10 ms a call under load)
        from scipy.sparse.linalg import splu
        Jc = J if sparse.isspmatrix_csc(J) else sparse.csc_matrix(J)
        solve = _band_solver(Jc, memo) if compiled and memo is not None and J.shape[0] <= SPARSE_MIN else None
        if solve is None:
            lu = splu(Jc)
            solve = _lu_solver(lu) if compiled else lu.solve
        if L is None:
            return solve
        L = sparse.csr_matrix(L)
        return lambda r: solve(L @ r)
    if compiled:
        return _dense_solver(J.toarray() if sparse.issparse(J) else J, L)
    import scipy.linalg as sla
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sla.LinAlgWarning)       # reported below
        lu = sla.lu_factor(J.toarray() if sparse.issparse(J) else J, check_finite=False)
    if not np.all(np.diag(lu[0])):
        raise np.linalg.LinAlgError("the matrix is exactly singular")
    # LAPACK's getrs itself, as scipy's lu_solve calls it: lu_solve's argument checks cost
    # ~10 µs a call (up to 30 µs under load) against ~1 µs for the solve of a few dozen
    # unknowns, a third of a Newton update of a board on two penalty wheels
    from scipy.linalg.lapack import dgetrs
    lu, piv = lu
    if L is None:
        return lambda r: dgetrs(lu, piv, r)[0]
    # J⁻¹L column by column: a matrix right-hand side is OpenBLAS's threaded trsm below 32
    # rows, ~15 ms a call while the cores are busy (a column: 1-10 µs)
    L = L.toarray() if sparse.issparse(L) else np.asarray(L)
    X = np.empty((J.shape[0], L.shape[1]))
    for j in range(L.shape[1]):
        X[:, j] = dgetrs(lu, piv, L[:, j])[0]
    return X.dot


def _dense_solver(J, L):
    """The dense branch of :func:`factorize` in kernels (:func:`..kernels.linalg.dense_lu`): no
    BLAS threads, no scipy call per column of L (15 lu_solve calls a matrix, 0.4 ms, were most of
    a stiff 5-mass chain's run)."""
    from ..kernels.linalg import dense_lu, dense_lu_solve
    from scipy import sparse
    A = np.array(J, dtype=float, order="C")
    piv = np.empty(len(A), np.int64)
    if dense_lu(A, piv):
        raise np.linalg.LinAlgError("the matrix is exactly singular")
    if L is None:
        def solve(r):
            x = np.array(r, dtype=float).reshape(len(A), -1)
            dense_lu_solve(A, piv, x)
            return x.reshape(np.shape(r))
        solve.dense_factors = (A, piv)      # for kernels that solve inside (genalpha)
        return solve
    X = np.array(L.toarray() if sparse.issparse(L) else L, dtype=float, order="C")
    dense_lu_solve(A, piv, X)
    return X.dot


#: a band (lower + upper width) up to this fraction of the unknowns is factored banded
BAND_FRACTION = 0.25


def _band_solver(J, memo):
    """r ↦ J⁻¹ r for a CSC J through the compiled banded LU (:func:`..kernels.linalg.band_lu`,
    partial pivoting within the band) in a reverse Cuthill-McKee order of J's pattern, kept in
    ``memo`` with its widths for later J of the same pattern; None when the band is wider
    than BAND_FRACTION of the unknowns (a sparse LU then). On the 104-coordinate ANCF cable
    (widths 8) a matrix costs ~15 µs against ~90 µs for SuperLU's set-up, factorization and
    the export of its factors. Raises np.linalg.LinAlgError on a singular J."""
    from ..kernels.linalg import band_lu
    n = J.shape[0]
    key = (J.shape, J.indptr.tobytes(), J.indices.tobytes())
    band = memo.get("band")
    if band is None or band[0] != key:
        from scipy.sparse.csgraph import reverse_cuthill_mckee
        P = abs(J).tocsr()
        order = reverse_cuthill_mckee((P + P.T).tocsr(), symmetric_mode=True)
        pinv = np.empty(n, np.int64)
        pinv[order] = np.arange(n)
        C = J.tocoo()
        d = pinv[C.col] - pinv[C.row]
        kl, ku = (int(max(0, -d.min())), int(max(0, d.max()))) if len(d) else (0, 0)
        band = memo["band"] = (key, pinv, kl, ku) if kl + ku <= BAND_FRACTION * n else (key, None)
    if band[1] is None:
        return None
    pinv, kl, ku = band[1:]
    lp, up, perm = np.empty(n + 1, np.int64), np.empty(n + 1, np.int64), np.empty(2 * n, np.int64)
    li, lv = np.empty(n * kl, np.int64), np.empty(n * kl)
    ui, uv = np.empty(n * (kl + ku + 1), np.int64), np.empty(n * (kl + ku + 1))
    ok, nl, nu = band_lu(J.indptr.astype(np.int64), J.indices.astype(np.int64),
                         np.ascontiguousarray(J.data, dtype=float), pinv, kl, ku, lp, li, lv, up, ui, uv, perm)
    if not ok:
        raise np.linalg.LinAlgError("the matrix is exactly singular")
    return _factor_solver(n, (lp, li[:nl], lv[:nl], up, ui[:nu], uv[:nu], perm))


def _factor_solver(n, f):
    """r ↦ J⁻¹ r through :func:`..kernels.linalg.lu_solve` on its factors ``f``."""
    from ..kernels.linalg import lu_solve

    def solve(r):
        x = np.empty(n)
        lu_solve(*f, np.ascontiguousarray(r, dtype=float), x)
        return x
    solve.factors = tuple(f)            # for kernels that solve inside (genalpha)
    return solve


def _lu_solver(lu):
    """r ↦ J⁻¹ r from SuperLU's factors through the compiled triangular solves (SuperLU's
    own solve costs ~3 µs of overhead a call)."""
    n = lu.shape[0]
    L, U = lu.L, lu.U
    # L's entries below its diagonal; U's diagonal first in each column (lu_solve's layout)
    col = np.repeat(np.arange(n), np.diff(L.indptr))
    below = L.indices > col
    lp = np.concatenate([[0], np.cumsum(np.bincount(col[below], minlength=n))])
    col = np.repeat(np.arange(n), np.diff(U.indptr))
    order = np.lexsort((U.indices != col, col))
    f = [np.asarray(a, np.int64) if a.dtype.kind == "i" else np.ascontiguousarray(a, dtype=float)
         for a in (lp, L.indices[below], L.data[below], U.indptr, U.indices[order], U.data[order])]
    return _factor_solver(n, [*f, np.concatenate([lu.perm_r, lu.perm_c]).astype(np.int64)])


def _csr_product(S):
    """r ↦ S r through the compiled CSR kernel (a dense S: its own product)."""
    if not hasattr(S, "tocsr"):
        return S.dot
    from ..kernels.genalpha import csr_matvec
    S = S.tocsr()
    ip, ix = S.indptr.astype(np.int64), S.indices.astype(np.int64)
    data, n = np.ascontiguousarray(S.data, dtype=float), S.shape[0]

    def product(r):
        out = np.empty(n)
        csr_matvec(ip, ix, data, np.ascontiguousarray(r, dtype=float), out)
        return out
    product.csr = (ip, ix, data)        # for kernels that solve inside (genalpha)
    return product


def _block_inverse(J, L):
    """J⁻¹L as a sparse matrix when J's graph has only components of ≤ BLOCK_MAX nodes and
    L stays inside them (else None); a sparse product is faster than batched small ones."""
    from scipy.sparse.csgraph import connected_components
    n = J.shape[0]
    ncomp, label = connected_components(J, directed=False)
    sizes = np.bincount(label, minlength=ncomp)
    if sizes.max() > BLOCK_MAX:
        return None
    Lr, Lc, Lv = coo(L) if L is not None else (np.arange(n), np.arange(n), np.ones(n))
    if np.any(label[Lr] != label[Lc]):
        return None
    order = np.argsort(label, kind="stable")
    first = np.concatenate([[0], np.cumsum(sizes)])
    pos = np.empty(n, int)
    pos[order] = np.arange(n) - first[label[order]]                 # place within its block
    group = np.empty(ncomp, int)                                    # index among blocks of its size
    parts = []
    Jr, Jc, Jv = coo(J)
    for m in np.unique(sizes):
        comps = np.flatnonzero(sizes == m)
        group[comps] = np.arange(len(comps))
        blocks = np.zeros((len(comps), m, m))
        rhs = np.zeros((len(comps), m, m))
        sel = sizes[label[Jr]] == m
        np.add.at(blocks, (group[label[Jr[sel]]], pos[Jr[sel]], pos[Jc[sel]]), Jv[sel])
        sel = sizes[label[Lr]] == m
        np.add.at(rhs, (group[label[Lr[sel]]], pos[Lr[sel]], pos[Lc[sel]]), Lv[sel])
        S = np.linalg.solve(blocks, rhs)
        members = order[first[comps][:, None] + np.arange(m)]
        parts.append((np.repeat(members, m, axis=1).ravel(), np.tile(members, (1, m)).ravel(), S.ravel()))
    return csr((n, n), parts)


def fd_matrix(ga, Wd1, lam, t1, h):
    """The Newton matrix of the generalized-α stepper ``ga`` by finite differences of its
    residual in Ẇ; the λ columns (the residual is affine in λ) from A: P M⁻¹Aᵀ or P Aᵀ.

    Two step sizes. The force rows and the velocity-level constraint rows: Ẇ_j moved by √eps
    relative to max(|Ẇ_j|, 1/s_v), so V moves by √eps·max(1, the step's change of V)
    (V = W₀ + s_v Ẇ): velocity-dependent forces are linear over small velocity changes only
    (a regularised friction over 1e-2 m/s; a step scaled to move q by √eps moved a ball's
    spin by 1e3 rad/s at h = 1e-4 and Newton bounced). The position-level constraint rows
    g/(h²β): q moved by ~√eps (h²β·δẆ), or their differences are rounding noise."""
    prob, m = ga.prob, ga.prob.model
    n = len(Wd1)
    r0 = ga._residual(Wd1, lam, t1, h)
    J = np.zeros((n + ga.nc, n + ga.nc))
    s_v = float(ga._affine(h).s_v)
    pos = np.arange(n, n + ga.nc)
    if ga._vel_rows is not None:
        pos = np.setdiff1d(pos, n + np.asarray(ga._vel_rows, int))
    big = 1.5e-8 / min(1.0, h * h * ga.beta)
    for j in range(n):
        e = 1.5e-8 * max(abs(Wd1[j]), 1.0 / s_v)
        Wp = Wd1.copy()
        Wp[j] += e
        J[:, j] = (ga._residual(Wp, lam, t1, h) - r0) / e
        if len(pos):
            e = big * max(1.0, abs(Wd1[j]))
            Wp[j] = Wd1[j] + e
            J[pos, j] = (ga._residual(Wp, lam, t1, h)[pos] - r0[pos]) / e
    if ga.nc:
        q1, quats = prob.configuration(ga._state(Wd1, h)[1])
        At = m.constraint_jacobian(q1).T
        cols = m.solve_mass(q1, At) if ga.accel_form else At
        if ga.rotate_rows:
            cols = np.stack([prob.group_velocity(c, quats) for c in cols.T], axis=1)
        J[:n, n:] = cols
    return J
