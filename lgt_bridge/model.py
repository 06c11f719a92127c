"""The model protocol every adapter implements, and its state layout.

A model holds absolute coordinates ``q`` (the engine's own) and velocities ``V``:

* each rigid body i owns 3 position entries and ν_i - 3 rotation entries of q
  (:class:`RigidBody`), and 6 entries of V: its twist (ω_i in the body frame,
  ṙ_i in the inertial frame), angular first;
* a unit complex number (cos θ, sin θ) (``circle_q``, a planar rotation: Pinocchio's
  continuous joints) owns 2 entries of q and 1 of V, its rate θ̇; it is stepped on SO(2),
  q = q_k · exp(iX) (abelian: the exponential chart is global and dψ⁻¹ = 1);
* every other coordinate is a vector-space block: q̇ = v, entry by entry.

``f(q, V, t)`` returns dV/dt (ω̇ body, r̈ inertial, v̇), index-1: constraint
forces resolved inside. Where a model has them it also provides the mass matrix
M(q) and forces Q(q, V, t) in the same velocity coordinates (M V̇ + Aᵀλ = Q), the
constraint residual g(q), its Jacobian A(q) with respect to V (ġ = A V) and the
acceleration term γ(q, V) = (d/dt A) V. These feed the projection after
explicit steps and the Newton iteration of generalized-α.

Constraints may depend on time, g(q, t) = 0 with A V = b(q, t) = -∂g/∂t
(``time_dependent_constraints``, ``constraints_at`` and ``velocity_rhs``), and some
rows may hold on velocities only (``velocity_rows``: nonholonomic rows A(q) V = b,
rolling without slipping); their entries of g are not position residuals and are
ignored by position projection and by generalized-α's position rows.
"""
from dataclasses import dataclass, field

import numpy as np

from . import backend as _backend
from . import params as _params
from .errors import InputError


@dataclass(frozen=True)
class RigidBody:
    """Where one rigid body lives in q and V. With ``pos = ()`` it is a rotation-only
    body (a spherical joint): its twist is just ω (3 indices)."""

    param: _params.Parameterization
    pos: tuple          # 3 indices into q, or () for a rotation-only body
    rot: tuple          # ν - 3 indices into q
    twist: tuple        # 6 indices into V: (ω, ṙ); 3 (ω) for a rotation-only body
    name: str = ""

    def __post_init__(self):
        object.__setattr__(self, "param", _params.get(self.param))
        ok = len(self.rot) == self.param.nrot and (
            (len(self.pos) == 3 and len(self.twist) == 6) or (len(self.pos) == 0 and len(self.twist) == 3))
        if not ok:
            raise InputError(f"body {self.name!r}: {self.param.name} needs 3 position, "
                             f"{self.param.nrot} rotation and 6 twist indices (or no position and 3 "
                             f"twist indices for a rotation-only body), got "
                             f"{len(self.pos)}, {len(self.rot)}, {len(self.twist)}.")

    @property
    def rotation_only(self):
        return not self.pos

    def validate(self, q, name):
        """Check this body's entries of q (shape, finiteness, unit quaternion)."""
        if self.rotation_only:
            return self.param._rot(q[list(self.rot)], name)
        return self.param.validate(q[[*self.pos, *self.rot]], name)


#: how far ‖(cos θ, sin θ)‖ of a circle coordinate may be from 1 in a given state
CIRCLE_NORM_TOL = 1e-6


@dataclass(frozen=True)
class EngineVelocity:
    """f in an engine's own velocities, for a model whose f converts them (a
    ``Model.engine_velocity``). On each body of ``bodies`` (indices into ``layout.bodies``,
    bodies with a position) the engine's velocity v holds the body-frame twist (v_lin = Rᵀṙ,
    ω) over the body's six twist entries, where V holds (ω, ṙ); every other entry of v is
    V's. ``f(q, v, t)`` returns the engine's acceleration in v's layout: (v̇_lin, ω̇) on those
    bodies, so that r̈ = R (v̇_lin + ω × v_lin), and V̇'s entries elsewhere (Pinocchio's
    ``aba`` of a free-flyer). It must equal the conversion of f(q, V, t); the compiled
    stages read and write v in one kernel call (:mod:`lgt_bridge.kernels.stage`)."""

    bodies: tuple
    f: object


@dataclass
class Layout:
    """Rigid bodies, vector-space coordinates and unit complex numbers (SO(2)) of a
    model's q and V."""

    nq: int
    nv: int
    bodies: list
    vector_q: tuple = ()     # indices into q of vector-space coordinates
    vector_v: tuple = ()     # their rates, same length and order, indices into V
    names: list = field(default_factory=list)
    circle_q: tuple = ()     # (cos, sin) index pairs into q of unit complex numbers
    circle_v: tuple = ()     # their angular rates, same order, indices into V

    def __post_init__(self):
        self.vector_q = tuple(int(i) for i in self.vector_q)
        self.vector_v = tuple(int(i) for i in self.vector_v)
        self.circle_q = tuple((int(c), int(s)) for c, s in self.circle_q)
        self.circle_v = tuple(int(i) for i in self.circle_v)
        if len(self.vector_q) != len(self.vector_v):
            raise InputError(f"layout: {len(self.vector_q)} vector-space coordinates but "
                             f"{len(self.vector_v)} rates; give one rate per coordinate.")
        if len(self.circle_q) != len(self.circle_v):
            raise InputError(f"layout: {len(self.circle_q)} unit complex (circle) coordinates but "
                             f"{len(self.circle_v)} rates; give one angular rate per (cos, sin) pair.")
        used_q = ([i for b in self.bodies for i in (*b.pos, *b.rot)] + list(self.vector_q)
                  + [i for pair in self.circle_q for i in pair])
        used_v = [i for b in self.bodies for i in b.twist] + list(self.vector_v) + list(self.circle_v)
        for what, used, n in (("q", used_q, self.nq), ("V", used_v, self.nv)):
            if sorted(used) != list(range(n)):
                missing = sorted(set(range(n)) - set(used))
                dup = sorted({i for i in used if used.count(i) > 1})
                raise InputError(f"layout: the entries of {what} must be covered exactly once "
                                 f"(missing {missing[:8]}, repeated {dup[:8]}).")

    @property
    def nbodies(self):
        return len(self.bodies)

    def owner(self, kind, index):
        """Human-readable owner of entry ``index`` of q or V ('body 2 (link2)', 'coordinate 7')."""
        for k, b in enumerate(self.bodies):
            if index in ((*b.pos, *b.rot) if kind == "q" else b.twist):
                return f"body {k}" + (f" ({b.name})" if b.name else "")
        for k, (pair, v) in enumerate(zip(self.circle_q, self.circle_v)):
            if index in (pair if kind == "q" else (v,)):
                return f"{kind}[{index}] (circle coordinate {k}: q[{pair[0]}], q[{pair[1]}] = cos θ, sin θ)"
        return f"{kind}[{index}] (vector-space coordinate)"

    def validate_circles(self, q, name):
        """InputError when a circle coordinate (cos θ, sin θ) of q is not finite or not of
        unit norm (within CIRCLE_NORM_TOL)."""
        for k, (c, s) in enumerate(self.circle_q):
            r = float(np.hypot(q[c], q[s]))
            if not abs(r - 1.0) <= CIRCLE_NORM_TOL:
                raise InputError(f"{name}: {self.owner('q', c)} is ({q[c]!r}, {q[s]!r}) with norm {r:.12g}; "
                                 "a planar rotation needs cos θ² + sin θ² = 1: give (cos θ, sin θ).")

    @classmethod
    def stacked(cls, params, n_vector=0, names=None):
        """Bodies one after another, q_i = (r, θ), V_i = (ω, ṙ), then n_vector coordinates."""
        bodies, iq, iv = [], 0, 0
        for k, p in enumerate(params):
            p = _params.get(p)
            bodies.append(RigidBody(p, tuple(range(iq, iq + 3)), tuple(range(iq + 3, iq + p.nu)),
                                    tuple(range(iv, iv + 6)), names[k] if names else f"body{k}"))
            iq += p.nu
            iv += 6
        return cls(iq + n_vector, iv + n_vector, bodies,
                   tuple(range(iq, iq + n_vector)), tuple(range(iv, iv + n_vector)))


class Model:
    """Base class of the model protocol; adapters and scenes subclass it.

    Required: ``layout``, ``q0``, ``V0``, and either ``f`` or ``mass_matrix`` +
    ``forces`` (then ``f`` solves the index-1 system). Optional: constraint
    functions (``n_constraints > 0``), ``write_back``.

    ``f`` may be handed views of the integrator's buffers (the compiled backend's stages and
    generalized-α's unconstrained Newton residuals): read q and V during the call, and copy
    what you keep beyond it.
    """

    layout: Layout
    q0: np.ndarray
    V0: np.ndarray
    n_constraints = 0
    #: indices of the constraint rows that hold on velocities only (A(q) V = b(q, t))
    velocity_rows = ()
    #: True when g, b or γ depend on t (prescribed motion, moving supports)
    time_dependent_constraints = False

    def f(self, q, V, t):
        M = self.mass_matrix(q)
        Q = self.forces(q, V, t)
        if not self.n_constraints:
            return np.linalg.solve(M, Q)
        A = self.constraint_jacobian(q)
        gam = self.constraint_gamma(q, V)
        return solve_kkt(M, A, Q, -gam)[0]

    def mass_matrix(self, q):
        raise NotImplementedError(f"{type(self).__name__} provides no mass matrix")

    def forces(self, q, V, t):
        raise NotImplementedError(f"{type(self).__name__} provides no forces")

    def constraints(self, q):
        return np.zeros(0)

    def constraint_jacobian(self, q):
        return np.zeros((0, self.layout.nv))

    def constraint_gamma(self, q, V):
        return np.zeros(0)

    def constraints_at(self, q, t):
        """g(q, t): ``constraints(q)`` unless the model's constraints depend on time."""
        return self.constraints(q)

    def forces_and_constraints(self, q, V, t):
        """(Q(q, V, t), g(q, t)): both at one state (an engine writes it once)."""
        return self.forces(q, V, t), self.constraints_at(q, t)

    def forces_and_constraints_function(self):
        """A callable (q, V, t) -> ``forces_and_constraints(q, V, t)`` for a caller about to
        evaluate it many times in a row (generalized-α's Newton updates, asked once per
        step): a model may bind what stays the same. Default: the bound method itself."""
        return self.forces_and_constraints

    def constraint_jacobian_function(self):
        """A callable q -> ``constraint_jacobian(q)`` for a caller that evaluates it right after
        ``forces_and_constraints`` at the same q (generalized-α's Newton updates, asked once
        per step): a model may bind what stays the same, and an engine need not write the
        state again. Default: the bound method itself."""
        return self.constraint_jacobian

    #: the mass matrix when it is the same at every q (dense or scipy.sparse), else None:
    #: generalized-α then keeps its residual in forces, M V̇ - Q + Aᵀλ, with one product by it
    constant_mass = None

    #: True when A(q) is the same at every q (generalized-α then reads it once per step)
    constant_constraint_jacobian = False

    #: f in the engine's own velocities, when it is cheaper than f (an :class:`EngineVelocity`;
    #: the compiled explicit stages then call it instead of f), else None
    engine_velocity = None

    def velocity_rhs(self, q, t):
        """b(q, t) in A(q) V = b (-∂g/∂t for position rows); None when it is zero."""
        return None

    @property
    def position_rows(self):
        """Indices of the constraint rows that hold on positions (g(q, t) = 0)."""
        vel = set(int(i) for i in self.velocity_rows)
        return np.array([i for i in range(self.n_constraints) if i not in vel], int)

    def write_back(self, q, V, t):
        """Put the state into the engine (sensors, viewers); nothing for pure-numpy models."""

    @property
    def step_write_back(self):
        """True when :meth:`write_back` must run after every step (False: only where the run
        stops or outputs, which lets the compiled step loop run on between them)."""
        return type(self).write_back is not Model.write_back

    @property
    def has_mass_matrix(self):
        """True when the model gives both M(q) and Q(q, V, t) (the index-3 residual form)."""
        return (type(self).mass_matrix is not Model.mass_matrix
                and type(self).forces is not Model.forces)


def combine_iteration(parts, c_acc, c_vel, c_pos):
    """M c_acc + C_t c_vel + K_t c_pos from ``parts`` = (M, C_t, K_t): what a model's
    ``iteration_matrix`` returns from its three matrices (zero coefficients skipped)."""
    M, C, K = parts
    out = c_acc * M
    if c_vel:
        out = out + c_vel * C
    if c_pos:
        out = out + c_pos * K
    return out


def solve_kkt(M, A, rhs_v, rhs_c):
    """[M Aᵀ; A 0] [x; λ] = [rhs_v; rhs_c] by the range-space method (M SPD). A
    rank-deficient A (redundant constraints) gives the minimum-norm λ and the unique x."""
    L = np.linalg.cholesky(M)
    def Minv(B):
        return np.linalg.solve(L.T, np.linalg.solve(L, B))
    MiAt = Minv(A.T)
    Miv = Minv(rhs_v)
    lam = solve_schur(A @ MiAt, A @ Miv - rhs_c)
    return Miv - MiAt @ lam, lam


#: eigenvalues of A M⁻¹ Aᵀ below this fraction of the largest count as zero
SCHUR_RCOND = 1e-11


def solve_schur(S, r):
    """S x = r for the symmetric positive semi-definite Schur complement S = A M⁻¹ Aᵀ:
    Cholesky when S is well conditioned, else the minimum-norm least-squares solution
    (redundant constraints make S singular; a consistent r still has solutions, and
    M⁻¹Aᵀx, the constraint force, is the same for all of them)."""
    if len(r) == 0:
        return np.zeros(np.shape(r))
    return schur_solver(S)(r)


def schur_solver(S):
    """r ↦ x of :func:`solve_schur` (r a vector or the columns of a matrix), S factorized
    once: by the kernels' Cholesky (:mod:`.kernels.linalg`) on the compiled backend up to
    ``_COMPILED_SCHUR_MAX`` rows (numpy's per-call overhead is most of a small solve), by
    numpy's otherwise and on the numpy backend; by its eigen-decomposition when S is not
    well conditioned."""
    n = len(S)
    if 0 < n <= _COMPILED_SCHUR_MAX and _backend.compiled():
        global _KL
        if _KL is None:
            from .kernels import linalg as _KL
        L = np.array(S, dtype=float, order="C").reshape(-1)
        ok, dmin, dmax = _KL.cholesky(L, n, _NO_ENVELOPE)
        if ok and dmin > np.sqrt(SCHUR_RCOND) * dmax:
            def solve(r):
                x = np.array(r, dtype=float, order="F")
                for col in (x,) if x.ndim == 1 else x.T:       # (columns: contiguous in F order)
                    _KL.cholesky_solve(L, n, _NO_ENVELOPE, col)
                return x
            return solve
    try:
        L = np.linalg.cholesky(S)
        d = np.diagonal(L)
        if d.min() > np.sqrt(SCHUR_RCOND) * d.max():
            return lambda r: np.linalg.solve(L.T, np.linalg.solve(L, r))
    except np.linalg.LinAlgError:
        pass
    w, U = np.linalg.eigh(0.5 * (S + S.T))
    keep = w > SCHUR_RCOND * max(w.max(), 0.0)
    Ur, wk = U[:, keep], w[keep]
    return lambda r: Ur @ ((Ur.T @ r) / (wk if r.ndim == 1 else wk[:, None]))


#: the compiled backend solves Schur complements up to this size with its own Cholesky
_COMPILED_SCHUR_MAX = 64
_NO_ENVELOPE = np.zeros(0, np.int64)
_KL = None          # the kernels' linalg module, once imported


def _solve_mass_dense(model, q, B):
    return np.linalg.solve(model.mass_matrix(q), B)


def _constraint_schur_dense(model, q, rows=None):
    """(A, correct): the constraint Jacobian at q (its ``rows``, all when None; anything with
    ``A @ V``) and correct(r) = M⁻¹Aᵀ (A M⁻¹ Aᵀ)⁺ r, the M-orthogonal step onto A x = r that
    projections subtract (minimum norm, :func:`solve_schur`). Dense by default; models with
    sparse constraint rows override it."""
    A = model.constraint_jacobian(q)
    if rows is not None:
        A = A[rows]
    MiAt = model.solve_mass(q, A.T)
    if not len(A):
        return A, lambda r: MiAt @ np.zeros(np.shape(r))
    solve = schur_solver(A @ MiAt)
    return A, lambda r: MiAt @ solve(r)


Model.solve_mass = _solve_mass_dense
Model.solve_mass.__doc__ = "M(q)⁻¹ B (dense by default; models with block-diagonal M override it)."
Model.constraint_schur = _constraint_schur_dense
