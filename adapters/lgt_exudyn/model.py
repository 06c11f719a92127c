"""ExudynModel: an assembled Exudyn MainSystem as an lgt_bridge model.

q is Exudyn's total ODE2 coordinates (reference + current), V the twists of its rigid nodes
and the rates of every other ODE2 coordinate (:mod:`.layout`); ODE1 coordinates, if any,
ride along as rates appended to V (:mod:`.ode1`). Exudyn's own M, Q and C_q (evaluated at the
state and time written into the system, so loads, springs and user functions work) are
mapped to twist coordinates through q̇_e = H(q) V:

    M̄ = Hᵀ M H,   Q̄ = Hᵀ (Q - M Ḣ V),   A = C_q H,   γ = d/dt(A V)|_V

with the constraint rows and γ from :mod:`lgt_exudyn.constraints`, composed into the ``Model``
protocol here; the compiled backend runs f through :mod:`.kernels`."""
import numpy as np

from lgt_bridge.errors import InputError
from lgt_bridge.model import Model, solve_kkt
from lgt_bridge.switches import REDO

from . import constraints as _constraints
from .constraints import ConstraintRows
from .engine import Engine, engine_call, engine_set_up, guarded_f
from .layout import constant_twist_mass, node_layout
from .hooks import StepHooks, has_prestep
from .iteration import jacobian_function, newton_matrix, residual_function
from .ode1 import ODE1States

#: velocities above which M̄⁻¹ is kept sparse (the inverses of its diagonal blocks)
SPARSE_INVERSE_MIN = 100


class ExudynModel(StepHooks, Model):
    """An assembled Exudyn ``MainSystem`` as a model for :func:`lgt_bridge.simulate`.

    Parameters
    ----------
    mbs : exudyn.MainSystem
        The system, assembled (``mbs.Assemble()``). Build the model again after another
        ``mbs.Assemble()``: the compiled path writes through views of Exudyn's state.
    simulationSettings : exudyn.SimulationSettings, optional
        The user's settings; read are
        ``timeIntegration.generalizedAlpha.useIndex2Constraints`` (``index2``: constraints on
        velocities only, as Exudyn enforces them then) and the discontinuous iteration's
        tolerance.
    backend : {"numba", "numpy"}, optional
        Compiled conversions (:mod:`.kernels`) or the reference methods; default
        $LGT_BRIDGE_BACKEND, else numba.

    Attributes
    ----------
    engine : lgt_exudyn.engine.Engine
        The evaluator and state writes.
    nodes : lgt_exudyn.layout.NodeLayout
        The layout and velocity maps.
    cons : lgt_exudyn.constraints.ConstraintRows
        The constraint rows (inactive, redundant, velocity-level, time-dependent).
    ode1 : lgt_exudyn.ode1.ODE1States or None
        First-order coordinates integrated alongside.
    Mbar : ndarray or None
        The twist mass matrix when it is constant (then Exudyn's is never evaluated again).

    See Also
    --------
    lgt_exudyn.SolveDynamic : the drop-in for ``mbs.SolveDynamic`` built on this model.
    """

    @engine_set_up
    def __init__(self, mbs, simulationSettings=None, backend=None):
        from lgt_bridge import backend as _backend
        if not getattr(mbs, "systemIsConsistent", False):
            raise InputError("Exudyn system is not assembled (mbs.systemIsConsistent is False); "
                             "call mbs.Assemble() before wrapping it.")
        nodes = self.nodes = node_layout(mbs)
        engine = self.engine = Engine(mbs)
        self.mbs = mbs
        self._take_residual_user_function()     # called before each residual (hooks.py)
        self.n2, self.nv, self.kinds, self.ref = nodes.n2, nodes.nv, nodes.kinds, engine.ref
        self._jac_zero = engine.jac_zero
        #: the compiled kernels run this model's conversions (the backend is read here, once)
        self._compiled = _backend.compiled(backend) and self.nv > 0
        self._P = None                  # the kernels' pack (built at the first f)
        self._Mbar_inv = self._Mbar_sparse = self._coloured = None
        self._Mbar_pd = None            # M̄ constant and positive definite (checked once)
        self.n_eval = 0
        sd = self.sd
        self.layout = nodes.layout
        self.q0 = np.array(sd.GetODE2Coordinates()) + self.ref
        self.t0 = float(sd.GetTime())
        nodes.check_initial(self.q0, self.ref)
        self.V0 = nodes.twist_from_rates(self.q0, np.array(sd.GetODE2Coordinates_t()))
        if not np.isfinite(self.V0).all():
            i = int(np.flatnonzero(~np.isfinite(self.V0))[0])
            raise InputError(f"Exudyn initial velocities: entry {i} of {self.layout.owner('V', i)} is not "
                             "finite; fix the node's initial velocities.")
        #: Exudyn's generalizedAlpha.useIndex2Constraints: constraints on velocities only
        self.index2 = bool(simulationSettings is not None
                           and simulationSettings.timeIntegration.generalizedAlpha.useIndex2Constraints)
        self.cons = ConstraintRows(engine, nodes, self.q0, self.V0, self.t0, self.index2)
        self._take_rows()
        # connectors a pre-step user function may switch (read once here, then each step)
        self._connectors = self._connector_state() if has_prestep(mbs) else None
        self._take_discontinuous(simulationSettings)     # contact states and modes (hooks.py)
        self.Mbar = constant_twist_mass(engine, nodes, self.q0)
        self.ode1 = None
        if sd.ODE1Size():
            self.ode1 = ODE1States(engine, self.layout, self.q0, self.V0)
            self.layout, self.q0, self.V0 = self.ode1.layout, self.ode1.q0, self.ode1.V0
        if self.ode1 is not None:
            # ODE1 rows have no analytic Jacobian here: generalized-α differences the step
            self.iteration_matrix = None

    # ------------------------------------------------------------------ constraint rows
    def _take_rows(self):
        cons = self.cons
        self.n_constraints, self.velocity_rows = cons.n, cons.velocity_rows
        self.time_dependent_constraints, self.redundant_rows = cons.time_dependent, cons.redundant_rows

    # ------------------------------------------------------------------ the parts' handles and maps
    @property
    def solver(self):
        """The evaluator (the engine's; setting it, e.g. to a timing proxy, sets the engine's)."""
        return self.engine.solver

    @solver.setter
    def solver(self, solver):
        self.engine.solver = solver

    @property
    def sd(self):
        """The system's data (the engine's; settable as ``solver``)."""
        return self.engine.sd

    @sd.setter
    def sd(self, sd):
        self.engine.sd = sd

    def H(self, q):
        """Dense H(q) (n2 x nv): q̇_e = H V."""
        return self.nodes.H(q)

    def Hdot_V(self, q, V):
        """Ḣ(q, q̇) V: the part of q̈_e not from V̇."""
        return self.nodes.Hdot_V(q, V)

    def rates_from_twist(self, q, V):
        """Exudyn's ODE2 velocity coordinates q̇_e = H(q) V."""
        return self.nodes.rates_from_twist(q, V)

    def twist_from_rates(self, q, qd):
        return self.nodes.twist_from_rates(q, qd)

    def _moved(self, q, V, eps):
        return self.nodes.moved(q, V, eps)

    def _write(self, q, qd, t):
        self.engine.write(q, qd, t)

    def _Cq(self):
        return self.cons.Cq()

    # ------------------------------------------------------------------ discontinuous states
    def _post_newton(self, q, V, t):
        """Exudyn's discontinuous iteration at the end of a step (its PostNewton: contact and
        friction states updated from the state (q, V, t)): True for a switch (``locate_switches``),
        REDO when they moved by more than timeIntegration.discontinuous.iterationTolerance, else False."""
        self.write_back(q, V, t)
        if not self.locate_switches:            # the drop-in's fixed steps: Exudyn's own rule
            return REDO if float(self.solver.PostNewton(self.mbs, self.engine.settings)) > self._disc_tol else False
        gaps, modes = self._gap_rows, self._mode_rows
        d0 = np.array(self.sd.GetDataCoordinates()) if len(gaps) or len(modes) or self._circle_rows else None
        moved = float(self.solver.PostNewton(self.mbs, self.engine.settings)) > self._disc_tol
        # a contact gap that changes sign (the contact closing or opening), or a mode whose sign
        # changes (a limit stop reached or left, stick <-> slip), is a switch to locate however
        # small the force error; a force error alone redoes the step, as Exudyn iterates
        d1 = None if d0 is None else np.array(self.sd.GetDataCoordinates())
        if d1 is not None and (np.any(d0[gaps] * d1[gaps] < 0.0) or np.any(np.sign(d0[modes]) != np.sign(d1[modes]))
                               or self._circles_switched(d0, d1)):
            return True
        return REDO if moved else False

    def discontinuous_state(self):
        """The data coordinates at a step's start (read once per step, before its first
        attempt), also made Exudyn's StartOfStep data as its own step loop does: PostNewton
        reads them (the slip force a friction sticks again with)."""
        d = self.sd.GetDataCoordinates()
        self.sd.SetDataCoordinates(d, self.engine.exu.ConfigurationType.StartOfStep)
        return np.array(d)

    def set_discontinuous_state(self, d):
        self.sd.SetDataCoordinates(d)

    # ------------------------------------------------------------------ the ODE2 part
    def _evaluate(self, q, V, t, need_gamma=True):
        """Exudyn's M, Q, C_q at (q, V, t) mapped to twists: (M̄, Q̄, A, γ) (numpy)."""
        S, mbs, nodes = self.solver, self.mbs, self.nodes
        H = nodes.H(q)
        qd = H @ V
        self.engine.write(q, qd, t)
        S.ComputeODE2RHS(mbs)
        Q = np.array(S.GetSystemResidual())[:self.n2]
        if self.Mbar is None:
            M = self.engine.mass_matrix()
            Mb = H.T @ M @ H
            Qb = H.T @ (Q - M @ nodes.Hdot_V(q, V))
        else:
            # constant twist mass matrix M̄ and M = H⁺ᵀ M̄ H⁺: Hᵀ M Ḣ V = M̄ H⁺ Ḣ V
            Mb = self.Mbar
            Qb = H.T @ Q - Mb @ nodes.Hplus_Hdot_V(q, V)
        self.n_eval += 1
        if not self.n_constraints:
            return Mb, Qb, None, None
        A = self.cons.Cq() @ H
        if need_gamma:
            gam = self.cons.gamma(q, V, t)
            self.engine.write(q, qd, t)                   # leave the evaluated state in the system
            return Mb, Qb, A, gam
        return Mb, Qb, A, None

    def _f2(self, q, V, t):
        if not self.nv:
            self.engine.write(q, np.zeros(0), t)
            return np.zeros(0)
        if self._compiled:
            P = self._P if self._P is not None else self._pack()
            q, V = np.ascontiguousarray(q, float), np.ascontiguousarray(V, float)
            if P.plain_f is not None:
                return P.plain_f(q, V, float(t))
            return self._kernels.f_compiled(self, P, q, V, float(t))
        M, Q, A, gam = self._evaluate(q, V, t)
        if A is None:
            return np.linalg.solve(M, Q)
        return solve_kkt(M, A, Q, -gam)[0]

    def _mass2(self, q):
        if self.Mbar is not None:
            return self.Mbar.copy()
        return self._evaluate(q, np.zeros(self.nv), self.sd.GetTime(), need_gamma=False)[0]

    def _forces_compiled(self, q, V, t):
        """(Q̄, M̄) from the kernels: one state write, ComputeODE2RHS (and ComputeMassMatrix when
        M̄ is not constant); the state stays written. Fresh arrays."""
        P = self._P if self._P is not None else self._pack()
        K, S, mbs = self._kernels, self.solver, self.mbs
        q, V = np.ascontiguousarray(q, float), np.ascontiguousarray(V, float)
        K.write(P.T, P.off, P.w, q, V, 0.0, P.qpos, P.qvel)
        self.sd.SetTime(t)
        S.ComputeODE2RHS(mbs)
        Qbar, Mbar = np.empty(self.nv), self.Mbar
        if P.constant_mass:
            K.forces(P.T, P.off, P.w, q, V, S.GetSystemResidual(), P.empty, Qbar, P.empty)
        else:
            S.ComputeMassMatrix(mbs)
            Mbar = np.empty((self.nv, self.nv))
            K.forces(P.T, P.off, P.w, q, V, S.GetSystemResidual(), S.GetSystemMassMatrix(), Qbar, Mbar)
        self.n_eval += 1
        return Qbar, Mbar

    def _forces2(self, q, V, t):
        if self._compiled:
            return self._forces_compiled(q, V, t)[0]
        return self._evaluate(q, V, t, need_gamma=False)[1]

    def _jacobian2(self, q):
        if not self.n_constraints:
            return np.zeros((0, self.nv))
        if self._compiled and self._pack().sp is not None and self._P.sp.constant:
            return self._P.sp.dense(self.n_constraints, self.nv)      # the same everywhere
        self.sd.SetODE2Coordinates(q - self.ref)
        if not self._compiled:
            return self.cons.Cq() @ self.nodes.H(q)
        P = self._pack()
        q = np.ascontiguousarray(q, float)
        if P.sp is not None and (P.sp.joints is not None or P.sp.constant):   # no Exudyn Jacobian
            self._kernels.sparse_values(self, P, q)
            return P.sp.dense(self.n_constraints, self.nv)
        A = np.empty((self.n_constraints, self.nv))
        C = self.engine.ae_jacobian_full(1.0, 1.0 if self.cons.nonholonomic else 0.0)
        self._kernels.constraint_matrix(P.T, P.off, P.w, q, C, P.rows, A)
        return A

    def _solve_mass2(self, q, B):
        if self.Mbar is None:
            return np.linalg.solve(self._mass2(q), B)
        if self._Mbar_inv is None:
            inv = None
            if self.nv > SPARSE_INVERSE_MIN:               # block-diagonal: its blocks' inverses
                from .kernel_tables import sparse_inverse
                inv = sparse_inverse(self.Mbar)
                if inv is not None and inv.nnz > self.nv * self.nv // 8:
                    inv = inv.toarray()                      # hardly sparse (one flexible body)
            self._Mbar_inv = inv if inv is not None else np.linalg.inv(self.Mbar)
        return self._Mbar_inv @ B

    # ------------------------------------------------------------------ model protocol
    @engine_call
    def f(self, q, V, t):
        if self.ode1 is None:
            return self._f2(q, V, t)
        self.ode1.write(V)
        return self.ode1.with_rates(self._f2(q[:self.n2], V[:self.nv], t))   # leaves (q, q̇, t) written

    @engine_call
    def mass_matrix(self, q):
        M = self._mass2(q[:self.n2])
        return M if self.ode1 is None else self.ode1.mass_matrix(M)

    @engine_call
    def forces(self, q, V, t):
        if self.ode1 is None:
            return self._forces2(q, V, t)
        q2, V2 = q[:self.n2], V[:self.nv]
        self.ode1.write(V)
        Q = self._forces2(q2, V2, t)
        self.engine.write(q2, self.nodes.rates_from_twist(q2, V2), t)
        return self.ode1.with_rates(Q)

    @property
    def constant_mass(self):
        """The twist mass matrix M̄ (scipy CSR) when it is constant and there are no ODE1
        states, else None (``Model.constant_mass``)."""
        if self.Mbar is None or self.ode1 is not None:
            return None
        if self._Mbar_sparse is None:
            from scipy.sparse import csr_matrix
            self._Mbar_sparse = csr_matrix(self.Mbar)
        return self._Mbar_sparse

    @property
    def constant_constraint_jacobian(self):
        """A read from Exudyn once, the same everywhere (``Model.constant_constraint_jacobian``)."""
        return bool(self.n_constraints and self.ode1 is None and self._compiled
                    and self._pack().sp is not None and self._P.sp.constant)

    @engine_call
    def forces_and_constraints(self, q, V, t):
        """(Q̄, g) at one state: one write for both (``Model.forces_and_constraints``)."""
        if not self.n_constraints or self.ode1 is not None or not self._compiled:
            return Model.forces_and_constraints(self, q, V, t)
        fast = residual_function(self)           # a constant M̄: one residual read
        return fast(q, V, t) if fast else (self._forces_compiled(q, V, t)[0], self.cons.at_written(t))

    def forces_and_constraints_function(self):
        return residual_function(self) or self.forces_and_constraints

    def constraint_jacobian_function(self):
        return jacobian_function(self) or self.constraint_jacobian

    def solve_mass(self, q, B):
        """M̄⁻¹ B: through the cached inverse when the twist mass matrix is constant."""
        if self.ode1 is None:
            return self._solve_mass2(q, B)
        return self.ode1.solve_mass(lambda b: self._solve_mass2(q[:self.n2], b), B)

    @engine_call
    def iteration_matrix(self, q, V, t, c_acc, c_vel, c_pos, sparse=False):
        """M̄ c_acc + C_t c_vel + K_t c_pos for generalized-α's Newton matrix, in the twists V and
        the SO(3)xR³ increments z (the derivatives of R = M̄ V̇ - Q̄(q(z), V, t)), from Exudyn's
        own Jacobians of its ODE2 right-hand side Q_e (ComputeJacobianODE2RHS, loads included):

            C_t ≈ -Hᵀ (∂Q_e/∂q̇_e) H,     K_t ≈ -Hᵀ (∂Q_e/∂q_e) H

        (q̇_e = H V, and H is also ∂q_e/∂z at z = 0). Left out: (∂Hᵀ/∂z) of the residual and
        the velocity dependence of the Ḣ V term (EP and Rxyz rotations), and the joints'
        geometric stiffness; measured against central differences of M̄ V̇ - Q̄ on a spring-loaded
        body (tests/test_exudyn_iteration.py): C_t to 3e-8, K_t to 0.1 % (RotVecLG) and 4 % (EP),
        so generalized-α's modified Newton still contracts (it refreshes the matrix when it does
        not). Rxyz nodes' ω columns of C_t by differences (K_t to 10 %). ODE1 models: none. Kept
        for the calls at the same (q, V, t); without rotations one Exudyn Jacobian for the
        combination (:func:`.iteration.selected_matrix`). ``sparse``: scipy.sparse (a sparse
        H), as generalized-α asks above its sparse size; large models with a constant M̄ take
        coloured differences of Q_e instead of Exudyn's dense Jacobian (:mod:`.iteration`)."""
        return newton_matrix(self, q, V, t, c_acc, c_vel, c_pos, sparse)

    def constraint_owners(self, rows):
        """The Exudyn objects owning the model's constraint ``rows`` (for messages)."""
        return self.engine.ae_owners([int(self.cons.ae_keep[i]) for i in rows])

    def constraints(self, q):
        return self.constraints_at(q, self.sd.GetTime())

    @engine_call
    def constraints_at(self, q, t):
        """Exudyn's position-level residuals g(q, t) of the kept rows (0 on velocity-level rows)."""
        if not self.n_constraints:
            return np.zeros(0)
        return self.cons.at(q[:self.n2], t)

    @engine_call
    def velocity_rhs(self, q, t):
        """b(q, t) in A V = b: -∂g/∂t of time-dependent rows, the offsets of velocity-level
        rows (q̇ᵢ = c), a pre-step jump spread over the step (None when all are zero)."""
        if not self.cons.has_rhs:
            return None
        return -self.cons.AV_at(q[:self.n2], np.zeros(self.nv), t)

    @engine_call
    def constraint_jacobian(self, q, sparse=False):
        """A(q); ``sparse``: a scipy CSR matrix when the compiled backend holds the rows
        sparse (generalized-α asks above its sparse size), else the dense array."""
        if sparse and self._compiled and self.ode1 is None and self.n_constraints:
            P = self._pack()
            if P.sp is not None:
                from scipy.sparse import csr_matrix
                if P.sp.joints is None and not P.sp.constant:
                    self.sd.SetODE2Coordinates(q - self.ref)
                aval = self._kernels.sparse_values(self, P, np.ascontiguousarray(q, float))
                return csr_matrix((aval.copy(), P.sp.acol, P.sp.aptr), shape=(self.n_constraints, self.nv))
        A = self._jacobian2(q[:self.n2])
        return A if self.ode1 is None else self.ode1.jacobian(A)

    @engine_call
    def constraint_schur(self, q, rows=None):
        """``Model.constraint_schur`` on the sparse rows of the compiled backend (A sparse, the
        correction by the envelope factor of A M̄⁻¹ Aᵀ), densely otherwise."""
        P = self._pack() if self._compiled and self.ode1 is None and self.n_constraints else None
        if P is None or P.sp is None or (rows is not None and len(rows) != self.n_constraints):
            return Model.constraint_schur(self, q, rows)
        return self._kernels.constraint_schur(self, P, q[:self.n2])

    @engine_call
    def constraint_gamma(self, q, V, t=None):
        if not self.n_constraints:
            return np.zeros(0)
        return self.cons.gamma(q[:self.n2], V[:self.nv], self.sd.GetTime() if t is None else t)

    def write_back(self, q, V, t):
        q2, V2 = q[:self.n2], V[:self.nv]
        if self._compiled:
            P = self._pack()
            self._kernels.write(P.T, P.off, P.w, np.ascontiguousarray(q2, float), np.ascontiguousarray(V2, float),
                                0.0, P.qpos, P.qvel)
            self.sd.SetTime(t)
        else:
            self.engine.write(q2, self.nodes.rates_from_twist(q2, V2), t)
        if self.ode1 is not None:
            self.ode1.write(V)

    def project_initial(self, q0, V0, t0, tol=1e-12, max_iter=60):
        """The initial state moved onto the constraints as Exudyn's own solver moves it
        (:func:`.constraints.project_initial`)."""
        return _constraints.project_initial(self, q0, V0, t0, tol, max_iter)

    @engine_call
    def check_mass_matrix(self, q):
        """InputError when the twist mass matrix at q is singular or indefinite, even on motions the
        constraints fix (the solves invert M̄; ``simulate`` checks before the first step; the ODE2
        part's: the ODE1 block is the identity); a constant positive definite M̄ is checked once, by the
        Cholesky factors of its diagonal blocks, for all later runs."""
        from lgt_bridge.validation import MASS_CHECK_MAX_NV, mass_defects
        from .mass_notes import singular_mass_text
        if self.Mbar is not None:
            if self._Mbar_pd is None and self._compiled and self.ode1 is None:
                # the kernels' pack (built for the first f anyway) inverted M̄'s blocks
                # through their Cholesky factors: when it could, M̄ is positive definite
                self._Mbar_pd = True if self._pack().constant_mass else None
            if self._Mbar_pd is None:
                from .kernel_tables import positive_definite
                self._Mbar_pd = positive_definite(self.Mbar)
            if self._Mbar_pd:
                return
        if self.nv > MASS_CHECK_MAX_NV:
            return
        q2 = q[:self.n2]
        M = self._mass2(q2)
        A = self._jacobian2(q2) if self.n_constraints else None
        held = mass_defects(M, A) if A is not None else None
        d = held or mass_defects(M)                  # M̄⁻¹ is formed: M itself must be regular
        if d:
            owners = [self.nodes.owner(self.mbs, i) for i, _ in d]
            raise InputError(singular_mass_text(self.mbs, d, owners, held == []))

    # ------------------------------------------------------------------ compiled backend
    def reset_caches(self):
        """Drop what the model builds on its first runs (the kernels' pack and the f built on
        it, the cached M̄⁻¹ and M̄'s definiteness): the next run pays what a run on a fresh
        model pays (benchmarks), and a system assembled again is packed again."""
        self._P = None
        self._Mbar_inv = self._Mbar_sparse = self._coloured = None
        self._Mbar_pd = None
        self.__dict__.pop("f", None)
        self.__dict__.pop("_writer", None)

    def _pack(self):
        if self._P is None:
            from . import kernels
            self._kernels = kernels
            P = self._P = kernels.pack(self)
            P.plain_f = plain = kernels.plain_f(self, P)
            if plain is not None and self.ode1 is None:
                # constant M̄, unconstrained or closed-form joint rows: f is the kernels'
                # closure from now on (the same calls as _f2's, nothing looked up per call)
                self.f = guarded_f(plain, self.sd)
        return self._P
