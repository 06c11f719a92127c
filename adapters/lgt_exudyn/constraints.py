"""Exudyn's algebraic equations as lgt_bridge constraints: which rows are constraints
(inactive, redundant and velocity-level rows sorted out), whether they depend on time, their
residual g(q, t), A V - b and the acceleration term γ by differences (Exudyn does not provide
it), and the projection of the initial state the way Exudyn's own solver makes it consistent.

A = C_q H in twist coordinates (q̇_e = H V, :mod:`.layout`); the Euler-parameter
normalization equations are dropped (τ keeps quaternions unit).
"""
import numpy as np

from lgt_bridge.errors import InputError

#: rows of the normalized constraint Jacobian whose pivot falls below this count as dependent
RANK_TOL = 1e-9
#: the shift of the Cholesky test of clearly independent rows (:func:`_clearly_independent`)
SHIFT = 1e-10
#: the step of γ's central differences, relative to max(1, |V|∞)
EPS_GAMMA = 1e-5


def independent_rows(A):
    """Boolean mask of a maximal set of linearly independent rows of A (pivoted QR of the
    row-normalized Aᵀ: the rows picked first are kept)."""
    from scipy.linalg import qr
    n = A.shape[0]
    if n == 0:
        return np.ones(0, bool)
    norms = np.linalg.norm(A, axis=1)
    An = A / np.where(norms > 0, norms, 1.0)[:, None]
    if n > 50 and norms.min() > 0.0 and _clearly_independent(An):
        return np.ones(n, bool)
    _, R, piv = qr(An.T, mode="economic", pivoting=True)
    d = np.abs(np.diagonal(R))
    rank = int(np.sum(d > RANK_TOL * max(d.max(initial=0.0), 1e-300)))
    mask = np.zeros(n, bool)
    mask[piv[:rank]] = True
    return mask


def _clearly_independent(An):
    """True when σ_min(An)² > SHIFT (rows of unit norm): An Anᵀ - SHIFT I has a Cholesky
    factor (backward stable: its rounding, ~(band) eps ‖An Anᵀ‖ with ‖An Anᵀ‖ at most the
    number of rows a row overlaps, is far below SHIFT = 1e-10). The pivoted QR's diagonal is
    then at least σ_min > 1e-5 ≫ RANK_TOL: it would keep every row. (A 100-body revolute
    chain has σ_min² ≈ 6e-8.) Large models (where the QR costs O(n² nv)) factorize banded,
    in the rows' reverse Cuthill-McKee order."""
    from scipy.linalg import LinAlgError, cholesky_banded
    from scipy.sparse import csr_matrix, identity
    from scipy.sparse.csgraph import reverse_cuthill_mckee
    n = An.shape[0]
    S = csr_matrix(An)
    G = (S @ S.T - SHIFT * identity(n)).tocsr()
    p = reverse_cuthill_mckee(G, symmetric_mode=True)
    G = G[p][:, p].tocoo()
    band = int(np.abs(G.row - G.col).max(initial=0))
    try:
        if band > n // 4:
            np.linalg.cholesky(G.toarray())
            return True
        low = G.row >= G.col
        ab = np.zeros((band + 1, n))
        ab[(G.row - G.col)[low], G.col[low]] = G.data[low]
        cholesky_banded(ab, lower=True)
        return True
    except (LinAlgError, np.linalg.LinAlgError):
        return False


class ConstraintRows:
    """The constraint rows of an Exudyn system (:class:`.engine.Engine` ``engine``, nodes
    :class:`.layout.NodeLayout` ``nodes``), classified at the initial state (q0, V0, t0).

    ``ae_keep``: Exudyn's AE rows that are the constraints, in order; ``nonholonomic``
    (indices into them): rows with a velocity Jacobian (rolling, velocity-level
    CoordinateConstraints); ``velocity_rows``: the rows enforced on velocities only — the
    nonholonomic ones, or every row with ``index2`` (Exudyn's
    ``generalizedAlpha.useIndex2Constraints``: positions are never projected, an initial
    position violation stays, as with Exudyn's own solver); ``inactive_rows`` (Exudyn keeps
    them as λ = 0: ``constrainedAxes`` zeros, connectors with ``activeConnector`` False) and
    ``redundant_rows`` (dependent on others at q0: redundant closed loops): AE rows set
    aside; ``time_dependent``: the residual changes with time; ``velocity_offset``: a
    velocity-level row has a right-hand side at rest (``CoordinateConstraint(velocityLevel=
    True, offset=c)``: q̇ᵢ = c); ``exudyn_gt``: Exudyn's velocity-level residual carries
    ∂g/∂t; ``velocity_level``: Exudyn evaluates the velocity-level residual at all;
    ``ramp``: a jump of the position residual made between steps (a pre-step user function
    changed an offset), spread over the step as a time dependence (:meth:`set_ramp`)."""

    def __init__(self, engine, nodes, q0, V0, t0, index2=False):
        self.engine, self.nodes, self.index2 = engine, nodes, bool(index2)
        self.ae_keep = np.array(sorted(set(range(engine.nae)) - set(nodes.ep_ae)), int)
        self.n = len(self.ae_keep)
        self.nonholonomic = ()
        self.time_dependent = self.velocity_offset = False
        self.inactive_rows, self.redundant_rows = [], []
        self.velocity_level, self.exudyn_gt = True, False
        self.ramp = None
        if self.n:
            self._classify(q0, V0, t0)

    @property
    def velocity_rows(self):
        return tuple(range(self.n)) if self.index2 else self.nonholonomic

    @property
    def holonomic_rows(self):
        """Rows with a position residual g(q, t) (whether enforced on positions or not)."""
        vel = set(self.nonholonomic)
        return np.array([i for i in range(self.n) if i not in vel], int)

    @property
    def position_rows(self):
        """Rows enforced on positions: the holonomic ones, none with ``index2``."""
        return np.zeros(0, int) if self.index2 else self.holonomic_rows

    @property
    def has_rhs(self):
        """True when A V = b has a b (time dependence, velocity offsets, a ramp)."""
        return self.time_dependent or self.velocity_offset or self.ramp is not None

    def set_ramp(self, t0, h, jump):
        """A jump of the holonomic rows' residual at the step start t0 (``jump`` per kept row,
        0 on other rows; None: no ramp): over [t0, t0 + h] the residual is taken as
        g(q, t) - jump·(1 - (t - t0)/h), so the step starts where the last one ended and ends
        on the new constraints, with ∂g/∂t + jump/h as the velocity target (what a drive
        ramped by a pre-step function means)."""
        self.ramp = None if jump is None else (float(t0), float(h), np.asarray(jump, float))

    def _ramp_g(self, t):
        t0, h, jump = self.ramp
        return jump * (1.0 - min(max((t - t0) / h, 0.0), 1.0))

    # ------------------------------------------------------------------ classification
    def _classify(self, q0, V0, t0):
        """Sort Exudyn's algebraic equations (apart from the Euler-parameter norms): rows
        Exudyn keeps as λ = 0 (zero Jacobian row, unit AE diagonal) are dropped; rows with a
        velocity Jacobian are velocity-level; rows that depend linearly on others at q0 are
        set aside; and the constraints are time-dependent when their residual at q0 changes
        with the time written into the system."""
        E = self.engine
        qd0 = self.nodes.rates_from_twist(q0, V0)
        E.write(q0, qd0, t0)
        Cp, diag = E.ae_jacobian(1.0, 0.0)
        Cv, _ = E.ae_jacobian(0.0, 1.0)
        keep = []
        for i in self.ae_keep:
            if Cp[i].any() or Cv[i].any():
                keep.append(i)
            elif diag[i] == 1.0:
                self.inactive_rows.append(int(i))
            else:
                self.redundant_rows.append(int(i))
        keep = np.array(keep, int)
        vel = np.array([Cv[i].any() for i in keep], bool)
        self.velocity_level, why = self._can_evaluate_velocity_level()
        if vel.any() and not self.velocity_level:
            raise InputError(f"Exudyn model: {E.ae_owners([int(i) for i in keep[vel]])} has velocity-level "
                             "constraint equations, but Exudyn cannot evaluate the model's algebraic "
                             f"equations at velocity level ({why}); lgt_bridge needs "
                             "them. Run this model with Exudyn's own exu.SolveDynamic.")
        A = (Cp[keep] + Cv[keep]) @ self.nodes.H(q0)
        ind = independent_rows(A)
        self.redundant_rows += [int(i) for i in keep[~ind]]
        self.ae_keep, vel = keep[ind], vel[ind]
        self.n = len(self.ae_keep)
        self.nonholonomic = tuple(int(k) for k in np.flatnonzero(vel))
        if self.velocity_level and self.n:
            self._check_velocity_level(q0, qd0, t0, Cp)
        # every row set aside (e.g. a user-written Euler-parameter norm, which the bridge's
        # rotation coordinates keep by construction): nothing left to depend on time
        self.time_dependent = self._detect_time_dependence(q0, t0) if self.n else False
        self.detect_velocity_offset(q0, t0)
        E.write(q0, qd0, t0)
        if self.redundant_rows:
            import warnings

            from lgt_bridge.errors import ModelNote
            warnings.warn(ModelNote(
                f"Exudyn model: {len(self.redundant_rows)} of its {len(self.redundant_rows) + self.n} "
                f"constraint equations are redundant at the initial state (algebraic equations "
                f"{self.redundant_rows}: {E.ae_owners(self.redundant_rows)}); lgt_bridge sets them "
                "aside and enforces the others (the motion is the same; their Lagrange multipliers "
                "are not unique)."), stacklevel=5)

    def _check_velocity_level(self, q0, qd0, t0, Cp):
        """Exudyn's velocity-level residual of a position-level row of a constraint user function
        must be C_q q̇ (+ ∂g/∂t): a user function that ignores its ``velocityLevel`` argument
        returns g there (Exudyn's own index-3 solvers never ask for it). Such rows make A V and γ come
        from the Jacobian instead (``velocity_level`` False), with a note; with velocity-level
        rows in the model as well, which need Exudyn's velocity-level residual, an InputError."""
        E = self.engine
        user = set()                    # AE rows of objects with a constraint user function
        for k in range(E.sd.NumberOfObjects()):
            if E.mbs.GetObject(k).get("constraintUserFunction", 0) not in (0, None):
                user.update(int(i) for i in E.sd.GetObjectLTGAE(k))
        pos = np.array([k for k in self.holonomic_rows if int(self.ae_keep[k]) in user], int)
        if not len(pos):
            return
        rows = self.ae_keep[pos]
        qd = 1.0 + 0.37 * np.sin(np.arange(self.nodes.n2) + 1.0)     # a generic test velocity
        r0 = self.residual(q0, np.zeros(self.nodes.n2), t0, True)[pos]
        r1 = self.residual(q0, qd, t0, True)[pos]
        E.write(q0, qd0, t0)
        want = Cp[rows] @ qd
        bad = np.abs(r1 - r0 - want) > 1e-6 * (1.0 + np.abs(want) + np.abs(r1 - r0))
        if not bad.any():
            return
        owners = E.ae_owners([int(i) for i in rows[bad]])
        if self.nonholonomic:
            raise InputError(f"Exudyn model: the velocity-level constraint equations of {owners} are not "
                             "C_q q_t (a constraint user function that ignores its velocityLevel "
                             "argument?), and the model has velocity-level constraints, for which lgt_bridge "
                             "needs Exudyn's velocity-level equations; return the time derivative of the "
                             "constraint when velocityLevel is True.")
        import warnings

        from lgt_bridge.errors import ModelNote
        self.velocity_level = False
        warnings.warn(ModelNote(
            f"Exudyn model: the velocity-level constraint equations of {owners} are not C_q q_t (a "
            "constraint user function that ignores its velocityLevel argument?); lgt_bridge takes the "
            "constraints' velocity form from their Jacobian instead."), stacklevel=6)

    def detect_velocity_offset(self, q, t):
        """Set ``velocity_offset``: a velocity-level row's residual at rest is not zero at
        (q, t) (its offset; again after a pre-step function may have changed it)."""
        self.velocity_offset = False
        if self.nonholonomic and self.velocity_level:
            rest = self.residual(q, np.zeros(self.nodes.n2), t, True)[list(self.nonholonomic)]
            self.velocity_offset = bool(np.abs(rest).max() > 0.0)

    def _can_evaluate_velocity_level(self):
        """(False, Exudyn's message) when Exudyn refuses the velocity-level algebraic
        equations (e.g. a generic joint with ``offsetUserFunction_t``:
        NotImplementedFeatureError); then A V comes from the Jacobian and ∂g/∂t from
        differences in time."""
        try:
            self.engine.solver.ComputeAlgebraicEquations(self.engine.mbs, True)
            return True, ""
        except Exception as exc:          # Exudyn raises its own (non-Python) exception types
            return False, str(exc).strip().splitlines()[-1][:200]

    def _detect_time_dependence(self, q, t0):
        """True when the constraint residual at q0 (positions, and velocities at rest)
        changes with time; then also whether Exudyn's velocity-level residual carries
        ∂g/∂t (offset user functions with their ``_t`` derivative) — if not, the bridge
        differentiates g in time itself."""
        z = np.zeros(self.nodes.n2)
        ts = t0 + np.array([0.0, 0.1234567, 0.7654321])
        gp = [self.residual(q, z, t, False) for t in ts]
        gv = [self.residual(q, z, t, True) for t in ts] if self.velocity_level else gp[:1]
        scale = 1e-13 * (1.0 + np.abs(gp[0]).max() + np.abs(gv[0]).max())
        self.exudyn_gt = False
        if all(np.abs(g - gp[0]).max() <= scale for g in gp) and all(
                np.abs(g - gv[0]).max() <= scale for g in gv):
            return False
        if not self.velocity_level:
            return True
        pos = self.holonomic_rows
        ok = True
        for t in ts:
            gt = self.gt_fd(q, t)[pos]
            ev = self.residual(q, z, t, True)[pos]
            ok &= bool(np.abs(gt - ev).max() <= 1e-6 * (1.0 + np.abs(gt).max()))
        self.exudyn_gt = ok
        return True

    # ------------------------------------------------------------------ evaluation
    def residual(self, q, qd, t, velocity_level):
        """Exudyn's residual of the kept rows at (q, qd, t)."""
        return self.engine.ae_residual(q, qd, t, velocity_level, self.ae_keep)

    def Cq(self):
        """The kept rows of the AE Jacobian at the written coordinates: ∂C/∂q on position
        rows, ∂C/∂q̇ on velocity-level rows (each row has only one of the two, so one call
        with both factors gives both)."""
        return self.engine.ae_jacobian(1.0, 1.0 if len(self.nonholonomic) else 0.0)[0][self.ae_keep]

    def at(self, q, t):
        """g(q, t) of the kept rows (0 on velocity-level rows)."""
        E = self.engine
        E.sd.SetODE2Coordinates(q - E.ref)
        E.sd.SetTime(t)
        return self.at_written(t)

    def at_written(self, t):
        """g of the kept rows at the coordinates and time written in the system (t: that time)."""
        E = self.engine
        E.solver.ComputeAlgebraicEquations(E.mbs, False)
        return self.of_residual(E.solver.GetSystemResidual(), t)

    def of_residual(self, res, t):
        """g of the kept rows from Exudyn's system residual ``res`` read after
        ComputeAlgebraicEquations (position level) at time t."""
        g = np.asarray(res)[self.engine.ae0:][self.ae_keep]
        if self.nonholonomic:
            g[list(self.nonholonomic)] = 0.0
        if self.ramp is not None:
            g -= self._ramp_g(t)
        return g

    def gt_fd(self, q, t):
        """∂g/∂t at (q, t) by central differences of the position-level residual."""
        e = 1e-6 * max(1.0, abs(t))
        z = np.zeros(self.nodes.n2)
        return (self.residual(q, z, t + e, False) - self.residual(q, z, t - e, False)) / (2 * e)

    def AV_at(self, q, V, t):
        """A(q) V - b(q, t) from Exudyn's velocity-level constraint residual C_q q̇_e + ∂g/∂t
        (a vector: no dense Jacobian transfer)."""
        qd = self.nodes.rates_from_twist(q, V)
        if not self.velocity_level:                    # A V from the Jacobian, + ∂g/∂t
            self.engine.write(q, qd, t)
            r = self.Cq() @ qd
            r = r + self.gt_fd(q, t) if self.time_dependent else r
        else:
            r = self.residual(q, qd, t, True)
            if self.time_dependent and not self.exudyn_gt:
                pos = self.holonomic_rows
                r[pos] += self.gt_fd(q, t)[pos] - self.residual(q, np.zeros(self.nodes.n2), t, True)[pos]
        if self.ramp is not None:
            r += self.ramp[2] / self.ramp[1]
        return r

    def gamma(self, q, V, t):
        """γ = d/dt (A(q) V - b(q, t)) at fixed V: central differences of A V - b along the
        path (τ(q, sV), t + s), whose twist is V for all s."""
        vmax = max(1.0, float(np.abs(V).max()))
        eps = EPS_GAMMA / vmax
        td, moved = self.time_dependent, self.nodes.moved
        if td and not self.exudyn_gt:
            return self._gamma_second_difference(q, V, t, 1e-3 / vmax)
        dt = eps if td else 0.0
        return (self.AV_at(moved(q, V, eps), V, t + dt) - self.AV_at(moved(q, V, -eps), V, t - dt)) / (2 * eps)

    def _gamma_second_difference(self, q, V, t, e):
        """γ when Exudyn's velocity-level residual lacks ∂g/∂t (an offset user function
        without its ``_t``): on position rows γ = φ''(0) for φ(s) = g(τ(q, sV), t + s),
        by second differences with Richardson extrapolation (error O(e⁴) + rounding/e²);
        velocity-level rows by central differences of Exudyn's residual."""
        z, moved = np.zeros(self.nodes.n2), self.nodes.moved
        phi = {k: self.residual(moved(q, V, k * e), z, t + k * e, False) for k in (-2, -1, 0, 1, 2)}
        d1 = (phi[1] - 2 * phi[0] + phi[-1]) / e ** 2
        d2 = (phi[2] - 2 * phi[0] + phi[-2]) / (4 * e ** 2)
        gam = (4 * d1 - d2) / 3
        if self.nonholonomic:
            vr = list(self.nonholonomic)
            ev = EPS_GAMMA / max(1.0, float(np.abs(V).max()))
            cv = [self.residual(moved(q, V, k * ev), self.nodes.rates_from_twist(moved(q, V, k * ev), V),
                                t + k * ev, True)[vr] for k in (1, -1)]
            gam[vr] = (cv[0] - cv[1]) / (2 * ev)
        return gam


# ---------------------------------------------------------------------------- projection
def project_initial(model, q0, V0, t0, tol=1e-12, max_iter=60):
    """The initial state of ``model`` (an ExudynModel) moved onto the constraints the way
    Exudyn's own solver moves it in its first step (its limit for small steps): positions to
    the q₁ on g(q₁, t0) = 0 with M(q₁) Δ = C_q(q₁)ᵀ μ, Δ the step in each node's own
    coordinates (the plain difference for Euler parameters, positions, angles and vector
    coordinates; the body-frame increment for RotVecLG nodes) with Exudyn's mass matrix and
    its Euler-parameter rows; then velocities M-orthogonally onto A V = b at q₁ (lgt_bridge's
    generic projection). Returns (q, V, report) as
    :func:`lgt_bridge.integrators.constraints.project_initial`."""
    from lgt_bridge.integrators.constraints import project_initial as generic
    cons = model.cons
    if not cons.n:
        return q0, V0, None
    # index 2 (useIndex2Constraints): no position rows, the positions stay where they are
    rows = np.array(sorted(cons.nodes.ep_ae) + [int(cons.ae_keep[k]) for k in cons.position_rows], int)
    n2 = cons.nodes.n2
    q2 = _project_positions(cons, q0[:n2], t0, rows, tol, max_iter)
    q = q0 if q2 is None else np.concatenate([q2, q0[n2:]])
    q1, V1, rep = generic(model, q, V0, t0)             # velocities (positions already hold)
    if q is q0 and rep is None:
        return q0, V0, None
    g0 = _residual_rows(cons, q0[:n2], t0, rows)
    b = model.velocity_rhs(q0, t0)
    rv = model.constraint_jacobian(q0) @ V0 - (0.0 if b is None else b)
    after = float(np.abs(_residual_rows(cons, q1[:n2], t0, rows)).max()) if len(rows) else 0.0
    model.write_back(q1, V1, t0)
    return q1, V1, dict(
        position_residual=float(np.abs(g0).max()) if len(g0) else 0.0,
        velocity_residual=float(np.abs(rv).max()) if len(rv) else 0.0,
        position=float(np.abs(q1 - q0).max()), velocity=float(np.abs(V1 - V0).max()),
        position_residual_after=after,
        velocity_residual_after=(rep or {}).get("velocity_residual_after", 0.0))


def _residual_rows(cons, q, t, rows):
    """Exudyn's position-level residual of the AE ``rows`` (Euler-parameter rows included)."""
    return cons.engine.ae_residual(q, np.zeros(cons.nodes.n2), t, False, rows)


def _project_positions(cons, q0, t0, rows, tol, max_iter):
    """Exudyn's first-step rule for positions (see :func:`project_initial`); None when q0
    already satisfies the constraints."""
    E, n2 = cons.engine, cons.nodes.n2
    z = np.zeros(n2)
    g = _residual_rows(cons, q0, t0, rows)
    if not len(g) or np.abs(g).max() <= tol:
        return None
    q, D = q0, np.zeros(n2)
    nae = len(rows)
    for _ in range(max_iter):
        E.write(q, z, t0)
        M = E.mass_matrix()
        C = E.ae_jacobian(1.0, 0.0)[0][rows]
        K = np.block([[M, C.T], [C, np.zeros((nae, nae))]])
        rhs = np.concatenate([np.zeros(n2), C @ D - g])
        D_new = np.linalg.lstsq(K, rhs, rcond=1e-13)[0][:n2]
        step = np.abs(D_new - D).max()
        D = D_new
        q = cons.nodes.plus(q0, D)
        g = _residual_rows(cons, q, t0, rows)
        if np.abs(g).max() <= tol and step <= 1e-12 * (1.0 + np.abs(D).max()):
            return q
    raise InputError(f"Exudyn model: the initial positions violate the constraints by "
                     f"{np.abs(_residual_rows(cons, q0, t0, rows)).max():.3g} and could not be "
                     f"moved onto them ({max_iter} iterations left {np.abs(g).max():.3g}); "
                     "start the model closer to a consistent configuration.")
