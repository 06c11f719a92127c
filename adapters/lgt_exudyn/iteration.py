"""generalized-α's Newton parts of :class:`lgt_exudyn.ExudynModel` on large models without
Exudyn's dense system Jacobian (whose transfer to Python, ~8 ms for 1100 coordinates, is
most of a step there): the Jacobians of Exudyn's ODE2 right-hand side Q_e by central
differences over colour groups of coordinates.

Q_e's pattern is the union over the objects without algebraic equations (bodies, springs,
connectors; the joints' forces Aᵀλ are not part of Q_e) of (their ODE2 coordinates)². Two
coordinates that no row of Q_e reads together get one colour (a greedy colouring of PᵀP),
so a group is moved at once and its columns read off the rows they touch: a chain of rigid
bodies needs 7 groups (one node's coordinates) whatever its length. Each Jacobian costs
2 × (groups) evaluations of Q_e through Exudyn's writable views, instead of one dense
transfer. At the analysis (the first call) the pattern is checked against Exudyn's own
Jacobians (ComputeJacobianODE2RHS: no entry outside it) and a column of each group against
its own difference; a model that fails (an object the pattern misses) keeps Exudyn's dense
Jacobians.

* :class:`ColouredJacobian` (model): ``jacobians(q, qd, t)`` -> (∂Q_e/∂q_e, ∂Q_e/∂q̇_e) as
  scipy CSR matrices, and ``agrees`` (the analysis' verdict);
* :func:`newton_matrix` (model, q, V, t, c_acc, c_vel, c_pos, sparse): ``iteration_matrix``
  itself; :func:`selected_matrix`: its one-Jacobian form without rotation coordinates;
* :func:`newton_parts` (model, q, V, t, sparse): [M̄, C_t, K_t] of ``iteration_matrix``, by
  :func:`sparse_parts` or from Exudyn's dense Jacobians;
* :func:`sparse_parts` (model, q, V, t): (M̄, C_t, K_t) of ``iteration_matrix`` as
  scipy.sparse matrices from them, or None when the model keeps the dense path;
* :func:`residual_function` (model): ``forces_and_constraints`` with its lookups bound, for
  the Newton updates (``forces_and_constraints_function``); :func:`jacobian_function`
  (model): A(q) the same way, at the state the update has just written
  (``constraint_jacobian_function``).
"""
import numpy as np

from lgt_bridge.model import combine_iteration

from .engine import engine_error

#: coordinates above which the sparse iteration matrix takes the coloured differences
#: instead of Exudyn's dense Jacobian (whose transfer grows with their square)
COLOURED_MIN = 300
#: the relative step of the central differences (∛eps: truncation and rounding balanced)
STEP = 6e-6
#: the coloured Jacobians are used when they equal Exudyn's to this, relative to their largest entry
CHECK = 1e-5


def _pattern(model):
    """Q_e's structural pattern (scipy CSR, n2 x n2, boolean)."""
    from scipy.sparse import coo_matrix
    sd, n2 = model.sd, model.n2
    rows, cols = [], []
    node_ae = set(int(i) for i in model.nodes.ep_ae)
    for k in range(sd.NumberOfObjects()):
        try:
            if set(int(i) for i in sd.GetObjectLTGAE(k)) - node_ae:
                continue                                   # constraints: no part in Q_e
        except Exception:
            pass
        try:
            idx = np.asarray(sd.GetObjectLTGODE2(k), np.int64)
        except Exception:
            continue
        if len(idx):
            rows.append(np.repeat(idx, len(idx)))
            cols.append(np.tile(idx, len(idx)))
    r = np.concatenate(rows + [np.zeros(0, np.int64)])
    c = np.concatenate(cols + [np.zeros(0, np.int64)])
    return coo_matrix((np.ones(len(r), bool), (r, c)), shape=(n2, n2)).tocsr()


def _colours(P):
    """A greedy colouring of the columns of P: columns sharing a row get different colours."""
    n = P.shape[1]
    G = (P.T.astype(np.int8) @ P.astype(np.int8)).tocsr()
    colour = np.full(n, -1, np.int64)
    for j in range(n):
        used = {int(colour[k]) for k in G.indices[G.indptr[j]:G.indptr[j + 1]] if colour[k] >= 0}
        c = 0
        while c in used:
            c += 1
        colour[j] = c
    return colour


class ColouredJacobian:
    """Exudyn's ODE2 right-hand side's Jacobians by central differences over colour groups
    (the module docstring)."""

    def __init__(self, model):
        self.model = model
        P = _pattern(model).tocoo()
        self.rows, self.cols = P.row.astype(np.int64), P.col.astype(np.int64)
        self.colour = _colours(P.tocsr())
        self.groups = [np.flatnonzero(self.colour == c) for c in range(int(self.colour.max(initial=-1)) + 1)]
        self.agrees = None

    def _residual(self):
        S, mbs, n2 = self.model.solver, self.model.mbs, self.model.n2
        S.ComputeODE2RHS(mbs)
        return np.array(S.GetSystemResidual())[:n2]

    def _derivative(self, x, base):
        """∂Q_e/∂x for the writable view x (current ODE2 coordinates or their rates) around its
        value ``base``: CSR on the pattern."""
        from scipy.sparse import csr_matrix
        n2 = self.model.n2
        d = np.empty(len(self.rows))
        for g in self.groups:
            e = STEP * np.maximum(1.0, np.abs(base[g]))
            x[g] = base[g] + e
            rp = self._residual()
            x[g] = base[g] - e
            rm = self._residual()
            x[g] = base[g]
            sel = self.colour[self.cols] == self.colour[g[0]]
            step = np.zeros(n2)
            step[g] = 2.0 * e
            d[sel] = (rp[self.rows[sel]] - rm[self.rows[sel]]) / step[self.cols[sel]]
        return csr_matrix((d, (self.rows, self.cols)), shape=(n2, n2))

    def jacobians(self, q, qd, t):
        """(∂Q_e/∂q_e, ∂Q_e/∂q̇_e) at (q total, q̇, t) as scipy CSR; the system is left at
        (q, q̇, t)."""
        m = self.model
        m.engine.write(q, qd, t)
        sd = m.sd
        xq = sd.GetODE2Coordinates(copy=False)
        xv = sd.GetODE2Coordinates_t(copy=False)
        Jq = self._derivative(xq, np.array(xq))
        Jv = self._derivative(xv, np.array(xv))
        return Jq, Jv

    def check(self, q, qd, t):
        """True when the pattern holds Exudyn's own Jacobians (zero outside it) and one column
        of each colour group equals its own central difference (every row: a coupling the
        pattern misses would show there) to CHECK, at (q, q̇, t). Exudyn's values are not the
        reference: its ∂Q_e/∂q leaves terms out (a spring-loaded body: 5e-4 of the largest
        entry against differences of its own Q_e, which these match to 1e-11)."""
        m = self.model
        S, n2 = m.solver, m.n2
        got = self.jacobians(q, qd, t)
        for fq, fv in ((1.0, 0.0), (0.0, 1.0)):
            S.ComputeJacobianODE2RHS(m.mbs, fq, fv, 1.0, 2)
            ref = np.array(S.GetSystemJacobian())[:n2, :n2]
            ref[self.rows, self.cols] = 0.0
            if np.abs(ref).max(initial=0.0) > 0.0:
                return False
        sd = m.sd
        for x, J in ((sd.GetODE2Coordinates(copy=False), got[0]), (sd.GetODE2Coordinates_t(copy=False), got[1])):
            base = np.array(x)
            scale = max(1.0, float(np.abs(J.data).max(initial=0.0)))
            for g in self.groups:
                j = int(g[0])
                e = STEP * max(1.0, abs(base[j]))
                x[j] = base[j] + e
                rp = self._residual()
                x[j] = base[j] - e
                rm = self._residual()
                x[j] = base[j]
                if np.abs((rp - rm) / (2.0 * e) - J[:, [j]].toarray()[:, 0]).max() > CHECK * scale:
                    return False
        return True


def sparse_parts(model, q, V, t):
    """(M̄, C_t, K_t) of ``iteration_matrix`` as scipy.sparse matrices from the coloured
    Jacobians (C_t = -Hᵀ (∂Q_e/∂q̇_e) H, K_t = -Hᵀ (∂Q_e/∂q_e) H with ∂q_e in Exudyn's
    increments, body-frame rotations on RotVecLG nodes), or None when the model
    takes Exudyn's dense Jacobians (small, no constant M̄, or the analysis disagreed)."""
    from scipy.sparse import csr_matrix
    if model.n2 < COLOURED_MIN or model.Mbar is None or model.ode1 is not None:
        return None
    cj = getattr(model, "_coloured", None)
    q = np.asarray(q, float)
    H = model.nodes.H_sparse(q)
    qd = H @ np.asarray(V, float)
    if cj is None:
        cj = model._coloured = ColouredJacobian(model)
        cj.agrees = cj.check(q, qd, t)
    if not cj.agrees:
        return None
    Jq, Jv = cj.jacobians(q, qd, t)
    Jq = Jq @ model.nodes.increments(q)            # in Exudyn's increments, as its own Jacobian
    if model._Mbar_sparse is None:
        model._Mbar_sparse = csr_matrix(model.Mbar)
    return [model._Mbar_sparse, -(H.T @ (Jv @ H)), -(H.T @ (Jq @ H))]


def newton_matrix(model, q, V, t, c_acc, c_vel, c_pos, sparse):
    """``ExudynModel.iteration_matrix``: :func:`selected_matrix` where it applies, else
    the combination of :func:`newton_parts`, kept for the calls at the same (q, V, t)."""
    one = selected_matrix(model, q, V, t, c_acc, c_vel, c_pos, sparse)
    if one is not None:
        return one
    key = (float(t), np.asarray(q, float).tobytes(), np.asarray(V, float).tobytes(), bool(sparse))
    cached = getattr(model, "_it_cache", None)
    if cached is None or cached[0] != key:
        cached = model._it_cache = (key, newton_parts(model, q, V, t, sparse))
    return combine_iteration(cached[1], c_acc, c_vel, c_pos)


def selected_matrix(model, q, V, t, c_acc, c_vel, c_pos, sparse):
    """M̄ c_acc + C_t c_vel + K_t c_pos of ``ExudynModel.iteration_matrix`` from one Exudyn
    Jacobian, ComputeJacobianODE2RHS(-c_pos, -c_vel), on a model without rotation coordinates
    and with a constant M̄ (H a 0/1 selection): half the Jacobian calls of :func:`newton_parts`,
    which computes ∂Q_e/∂q_e and ∂Q_e/∂q̇_e apart. None when it does not apply (rotations,
    M̄ not constant, the coloured differences of large models, or only M̄ asked)."""
    qi = model.nodes.selection()
    if qi is None or model.Mbar is None or not (c_vel or c_pos):
        return None
    if sparse and model._compiled and model.n2 >= COLOURED_MIN and model.ode1 is None:
        return None                                 # the coloured differences (newton_parts)
    model.write_back(np.asarray(q, float), np.asarray(V, float), t)       # (no ODE1 states here)
    S, n2 = model.solver, model.n2
    S.ComputeJacobianODE2RHS(model.mbs, -float(c_pos), -float(c_vel), 1.0, 2)
    J = np.asarray(S.GetSystemJacobian())
    out = J[:n2, :n2] if np.array_equal(qi, np.arange(n2)) else J[qi[:, None], qi]
    if c_acc:
        out += model.Mbar if c_acc == 1.0 else c_acc * model.Mbar
    if sparse:
        from scipy.sparse import csr_matrix
        return csr_matrix(out)
    return out


def newton_parts(model, q, V, t, sparse):
    """[M̄, C_t, K_t] of ``ExudynModel.iteration_matrix`` at (q, V, t) (``sparse``: scipy.sparse
    matrices): the coloured differences (:func:`sparse_parts`) on large compiled models, else
    Exudyn's dense ODE2 Jacobians mapped by H (a 0/1 selection when there are no rotations);
    C_t's columns of Rxyz nodes' angular velocities by differences (:func:`rxyz_columns`)."""
    parts = _jacobian_parts(model, q, V, t, sparse)
    if "RigidBodyRxyz" in model.nodes.types:
        parts[1] = rxyz_columns(model, q, V, t, parts[1])
    return parts


def rxyz_columns(model, q, V, t, C):
    """C_t with its columns of the Rxyz nodes' angular velocities from central differences of
    -Q̄(q, V, t): Exudyn's Jacobian does not see the adapter's Ḣ V term, whose dependence on
    ω is largest there (θ̇ = G(θ)⁻¹ ω: C_t was 170 % off on a spring-loaded Rxyz body); three
    pairs of force evaluations per Rxyz node. Exudyn is left at (q, V, t)."""
    cols = model.nodes.types["RigidBodyRxyz"][1].ravel()
    q, V = np.asarray(q, float), np.array(V, float)
    F = np.empty((len(V), len(cols)))
    for k, j in enumerate(cols):
        v, e = V[j], 1e-6 * max(1.0, abs(V[j]))
        V[j] = v + e
        up = np.array(model.forces(q, V, t), float)
        V[j] = v - e
        F[:, k] = (np.asarray(model.forces(q, V, t), float) - up) / (2.0 * e)
        V[j] = v
    model.forces(q, V, t)
    if not isinstance(C, np.ndarray):               # scipy.sparse
        C = C.tolil()
        C[:, cols] = F
        return C.tocsr()
    C = np.array(C)
    C[:, cols] = F
    return C


def _jacobian_parts(model, q, V, t, sparse):
    if sparse and model._compiled:                  # large models: no dense Jacobian transfer
        parts = sparse_parts(model, q, V, t)
        if parts is not None:
            return parts
    S, n2 = model.solver, model.n2
    # H a constant 0/1 selection (no rotation coordinates, or RotVecLG ones, whose block of H
    # is the identity): Hᵀ J H = J[qi][:, qi]. Building H and its sparse products had cost
    # 0.6 ms a matrix on 36 RotVecLG bodies, 40 % of a Newton matrix
    qi = model.nodes.selection(rotvec=True)
    if qi is not None:
        Mbar = model._forces_compiled(q, V, t)[1] if model._compiled else model._evaluate(q, V, t, False)[0]
        parts = [Mbar]
        for fq, fv in ((0.0, 1.0), (1.0, 0.0)):
            S.ComputeJacobianODE2RHS(model.mbs, fq, fv, 1.0, 2)
            parts.append(-np.asarray(S.GetSystemJacobian())[qi[:, None], qi])
        if sparse:
            from scipy.sparse import csr_matrix
            parts = [csr_matrix(X) for X in parts]
        return parts
    if model._compiled:
        return _compiled_parts(model, q, V, t, sparse)
    # H sparse: its products run in scipy's loops, not in a threaded BLAS whose
    # threads, woken once per matrix under load, cost ~30 ms a call
    H = model.nodes.H_sparse(np.asarray(q, float))
    Mbar = model._forces_compiled(q, V, t)[1] if model._compiled else model._evaluate(q, V, t, False)[0]
    model.engine.write(np.asarray(q, float), H @ np.asarray(V, float), t)
    if sparse:
        from scipy.sparse import csr_matrix as to
    else:
        def to(X):
            return X
    parts = [to(Mbar)]
    for fq, fv in ((0.0, 1.0), (1.0, 0.0)):
        S.ComputeJacobianODE2RHS(model.mbs, fq, fv, 1.0, 2)
        J = to(np.asarray(S.GetSystemJacobian())[:n2, :n2])
        JH = J @ H if sparse else (H.T @ J.T).T                     # J H
        parts.append(-(H.T @ JH) if sparse else -np.asarray(H.T @ JH))
    return parts


def residual_function(model):
    """(q, V, t) ↦ (Q̄, g) as ``ExudynModel.forces_and_constraints`` takes them on its compiled
    path with a constant M̄ (one state write, ComputeODE2RHS and ComputeAlgebraicEquations, one
    residual read), with what stays the same looked up once (~2 µs less a call; the ANCF cable
    pendulum's generalized-α makes 6400 of them); Exudyn's exceptions become ModelErrors as
    there. Kept on the model for its solver, kernel tables and constraint rows; None where the
    method takes another path. Without constraints: Q̄ and an empty g, Exudyn's algebraic
    equations not asked."""
    if model.ode1 is not None or not model._compiled:
        return None
    P, S, cons = model._pack(), model.solver, model.cons
    if not P.constant_mass:
        return None
    kept = getattr(model, "_residual_function", None)
    if kept is not None and kept[0] == (S, P, cons):
        return kept[1]
    K, sd, mbs, nv = model._kernels, model.sd, model.mbs, model.nv
    write, forces, of_residual = K.write, K.forces, cons.of_residual
    ode2, ae, residual, set_time = S.ComputeODE2RHS, S.ComputeAlgebraicEquations, S.GetSystemResidual, sd.SetTime
    T, off, w, qpos, qvel, empty = P.T, P.off, P.w, P.qpos, P.qvel, P.empty
    contiguous, rows = np.ascontiguousarray, cons.engine.ae0 + cons.ae_keep
    constrained, none = bool(model.n_constraints), np.zeros(0)

    def evaluate(q, V, t):
        q, V = contiguous(q, float), contiguous(V, float)
        try:
            write(T, off, w, q, V, 0.0, qpos, qvel)
            set_time(t)
            ode2(mbs)
            if constrained:
                ae(mbs, False)              # the AE rows of the residual (its ODE2 rows stay)
            res = residual()
            Q = np.empty(nv)
            forces(T, off, w, q, V, res, empty, Q, empty)
            # g: the kept rows, unless rows are velocity-level or ramped (of_residual's cases)
            if not constrained:
                g = none
            elif not cons.nonholonomic and cons.ramp is None:
                g = res[rows]
            else:
                g = of_residual(res, t)
        except Exception as exc:
            err = engine_error(sd, "forces_and_constraints", exc)
            if err is None:
                raise
            raise err from exc
        model.n_eval += 1
        return Q, g
    model._residual_function = ((S, P, cons), evaluate)
    return evaluate


def jacobian_function(model):
    """q ↦ A(q) as ``ExudynModel.constraint_jacobian`` gives it, with the lookups bound and
    without writing the state first (``constraint_jacobian_function``: its caller has just
    written it at q): rows in closed form (:func:`.kernel_sparse.joint_rows`, then A dense from
    its pattern; on a pendulum's Newton update 6 µs -> 2 µs), else Exudyn's AE Jacobian at the
    written state mapped to twists. Exudyn's exceptions become ModelErrors. None where A is
    constant or the model takes another path (ODE1 states, the numpy backend)."""
    if not model.n_constraints or model.ode1 is not None or not model._compiled:
        return None
    P = model._pack()
    sp = P.sp
    if sp is not None and sp.constant:
        return None
    T, nc, nv, contiguous = P.T, model.n_constraints, P.nv, np.ascontiguousarray
    if sp is not None and sp.joints is not None:
        rows, ja, jb, aval, gam = model._kernels.joint_rows, sp.joints[0], sp.joints[1], sp.aval, P.gam
        dense, zero = sp.dense, np.zeros(P.nv)

        def jacobian(q):
            rows(T, contiguous(q, float), zero, ja, jb, aval, gam)
            return dense(nc, nv)
        return jacobian
    matrix, engine, off, w, kept = model._kernels.constraint_matrix, model.engine, P.off, P.w, P.rows
    c_vel, sd = 1.0 if model.cons.nonholonomic else 0.0, model.sd

    def jacobian_from_exudyn(q):
        A = np.empty((nc, nv))
        try:
            matrix(T, off, w, contiguous(q, float), engine.ae_jacobian_full(1.0, c_vel), kept, A)
        except Exception as exc:
            err = engine_error(sd, "constraint_jacobian", exc)
            if err is None:
                raise
            raise err from exc
        return A
    return jacobian_from_exudyn


def _compiled_parts(model, q, V, t, sparse):
    """:func:`_jacobian_parts` with rotation coordinates on compiled models: Hᵀ J H by the
    kernel that maps Exudyn's mass matrix (``kernel_maps.forces`` with V = 0 and Q = 0, whose
    M̄ = Hᵀ M H holds for any square M), not by building H and multiplying sparse matrices
    (0.6 ms a matrix on 36 bodies)."""
    S, n2, nv = model.solver, model.n2, model.nv
    q, V = np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(V, dtype=float)
    Mbar = model._forces_compiled(q, V, t)[1]           # (the state written: q, H V)
    P, forces = model._pack(), model._kernels.forces
    zero_v, zero_q, scratch = np.zeros(nv), np.zeros(n2), np.empty(nv)
    parts = [Mbar]
    for fq, fv in ((0.0, 1.0), (1.0, 0.0)):
        S.ComputeJacobianODE2RHS(model.mbs, fq, fv, 1.0, 2)
        J = np.ascontiguousarray(np.asarray(S.GetSystemJacobian())[:n2, :n2])
        out = np.empty((nv, nv))
        forces(P.T, P.off, P.w, q, zero_v, zero_q, J, scratch, out)
        parts.append(-out)
    if sparse:
        from scipy.sparse import csr_matrix
        parts = [csr_matrix(X) for X in parts]
    return parts
