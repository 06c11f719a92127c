"""PinocchioModel: a Pinocchio model as an lgt_bridge model.

q is Pinocchio's own configuration vector; V holds the bridge's twists. The model composes:

* :mod:`.joints` — which joints are rigid bodies (free-flyers: (ω body, ṙ inertial); spherical
  and spherical-ZYX joints: rotation-only bodies), circle coordinates (continuous joints, the
  rotation of a planar joint) and vector-space blocks, i.e. the bridge's Layout, and the maps
  between Pinocchio's v and V (v = T(q) V);
* :mod:`.loads` — the user's tau, tau_derivatives and fext, checked and converted;
* :mod:`lgt_pinocchio.constraints` — RigidConstraintModels (and Pinocchio 4's point and frame anchors): f from
  constraintDynamics, g, A from Pinocchio's frame Jacobians and γ from its frame accelerations;
  default anchors, redundant rows, unclosed loops (:meth:`PinocchioModel.project_initial`) and
  passages near singular configurations (:meth:`PinocchioModel.write_back`);
* :mod:`.rhs` — f(q, V, t) = Pinocchio's ABA (constraintDynamics with constraints), with
  r̈ = R (a_lin + ω × v_lin) for the roots, on either backend;
* :mod:`.iteration` — generalized-α's Newton matrix from Pinocchio's analytic RNEA derivatives.

Backends (:mod:`lgt_bridge.backend`, read once when the model is built: ``backend``): with
numba, f converts V to Pinocchio's v and ABA's a to V̇ by two compiled calls
(:mod:`.kernels`) over a preallocated v; with numpy it runs the readable reference.
"""
import warnings
from functools import lru_cache

import numpy as np

from lgt_bridge import backend as _backend
from lgt_bridge.errors import InputError, ModelNote
from lgt_bridge.model import EngineVelocity, Model, combine_iteration

from .constraints import CLOSED_TOL, Constraints, gamma_fd, independent_rows, jacobian_fd
from .iteration import iteration_parts
from .memo import give_back, initial_state, lend_data, model_memo
from .loads import Loads
from .rhs import compiled_f, f_numpy


def _pin():
    global _PIN
    if _PIN is None:
        import pinocchio
        _PIN = pinocchio
    return _PIN


_PIN = None


#: smallest singular value of the constraint Jacobian A (twist coordinates), relative to its largest,
#: below which a configuration counts as near-singular (assembly branches may meet there)
SINGULAR_TOL = 1e-3
#: jump of V over a step, beyond the trapezoidal rule's prediction, relative to |V|, that counts
#: as a switch of assembly branch (a smooth passage changes V by h f)
BRANCH_JUMP_TOL = 1e-3


#: the oldest Pinocchio the adapter runs on (tested: 3.3.1, 3.9.0, 4.1.0)
MIN_PIN = (3, 0)


@lru_cache(maxsize=16)
def _upper(n):
    """The n x n upper triangle (with the diagonal) as a boolean mask, made once per size."""
    return np.triu(np.ones((n, n), bool))


def _check_pin_version(pin):
    """InputError on a Pinocchio older than MIN_PIN (2.x has other constraint classes and
    constructors), before anything is built."""
    _check_version(getattr(pin, "__version__", "0"))


@lru_cache(maxsize=4)
def _check_version(version):
    """(_check_pin_version on the version string, once per string.)"""
    try:
        found = tuple(int(x) for x in version.split(".")[:2])
    except ValueError:
        return
    if found < MIN_PIN:
        raise InputError(f"lgt_pinocchio needs Pinocchio >= {'.'.join(map(str, MIN_PIN))}; this is Pinocchio "
                         f"{version}. Upgrade it: pip install 'pin>=3' (or 'lgt-bridge[pinocchio]').")


def _check_pin_model(pin, model):
    _check_pin_version(pin)
    if isinstance(model, pin.Model):
        return
    if isinstance(model, pin.Data):
        raise InputError("PinocchioModel: got a pinocchio.Data; pass the pinocchio.Model it was created "
                         "from (e.g. PinocchioModel(model), not PinocchioModel(data)): the adapter makes "
                         "its own Data with model.createData().")
    hint = " (a RobotWrapper: pass robot.model)" if isinstance(getattr(model, "model", None), pin.Model) else ""
    raise InputError(f"PinocchioModel: expected a pinocchio.Model, got a {type(model).__name__}{hint}.")


class PinocchioModel(Model):
    """A ``pinocchio.Model`` as a model for :func:`lgt_bridge.simulate` and :class:`lgt_bridge.Simulation`.

    Parameters
    ----------
    model : pinocchio.Model
        The robot (free-flyers, spherical, continuous, planar, ZYX and vector-space joints).
    tau : array_like or callable, optional
        None (zero), a vector of size nv, or ``tau(t, q, v)`` (Pinocchio's q and v).
    fext : callable, optional
        ``fext(t, q, v)`` returning one ``pinocchio.Force`` (or 6-vector (linear, angular)) per
        joint, ``model.njoints`` of them, in each joint's frame (a ``pinocchio.StdVec_Force``
        is passed on without conversion: the cheapest form).
    constraints : list, optional
        ``pinocchio.RigidConstraintModel`` objects (3-D/6-D, to the world or loop closures;
        Pinocchio 3 or 4) and, on Pinocchio 4, ``PointAnchorConstraintModel`` and
        ``FrameAnchorConstraintModel`` (also inside a ``ConstraintModel``). They are copied
        when the model is wrapped: changing one afterwards does not change this model (wrap it
        again). Unilateral, friction and joint-limit constraints are refused, naming the class
        and why. As Pinocchio means them: a constraint to the world left at the default
        identity placement (``RigidConstraintModel(type, model, joint1_id, placement)``) holds
        its frame where it is at q0; a loop not closed at q0 is projected onto closure before
        the first step (:meth:`project_initial`; ``result.stats["initial_projection"]`` says how
        far), and refused when that fails; rows redundant at q0 are set aside
        (``redundant_rows``, a ModelNote).
    q0, v0 : ndarray, optional
        The initial state in Pinocchio's own coordinates (default: neutral, zero).
    backend : {"numba", "numpy"}, optional
        Default: $LGT_BRIDGE_BACKEND, else numba.
    tau_derivatives : callable, optional
        ``tau_derivatives(t, q, v) -> (dtau_dq, dtau_dv)``, the controller's Jacobians (nv x nv
        each; dtau_dq in Pinocchio's tangent coordinates, the columns of pin.integrate's
        increments): radau5's and generalized-α's Newton matrices then use them instead of
        2 nv extra calls of tau per matrix (forward differences).
    prox_settings : pinocchio.ProximalSettings, optional
        The settings constraintDynamics uses (default ``ProximalSettings(1e-12, 1e-12, 50)``:
        accuracy, mu, max_iter).

    Attributes
    ----------
    branch_switches, singular_passages : list of (float, float)
        After a run: the (start, end) times of the passages near a singular configuration of
        the constraints in which the solution switched assembly branch or stayed on it (each
        also a ModelNote; :meth:`write_back`).

    Notes
    -----
    With the compiled backend, ``tau`` and ``fext`` receive the caller's q and the model's own
    velocity buffer v, not copies: both are valid during the call only (copy them to keep
    them) and must not be written to. f returns a new array either way. Results hold
    Pinocchio's own q but the bridge's twists V (angular first): :meth:`pin_state` converts.

    Examples
    --------
    >>> import numpy as np, pinocchio as pin
    >>> from lgt_bridge import simulate
    >>> from lgt_pinocchio import PinocchioModel
    >>> pin.seed(0)
    >>> model = pin.buildSampleModelHumanoidRandom()
    >>> m = PinocchioModel(model, tau=np.zeros(model.nv))
    >>> r = simulate(m, (0.0, 0.01), method="dop853", rtol=1e-8, atol=1e-8)
    >>> q, v = m.pin_state(r.q[-1], r.V[-1])
    """

    def __init__(self, model, *, tau=None, fext=None, constraints=None, q0=None, v0=None, backend=None,
                 tau_derivatives=None, prox_settings=None):
        pin = self.pin = _pin()
        _check_pin_model(pin, model)
        self.backend = _backend.name(backend)
        self.model = model
        self.nq, self.nv = model.nq, model.nv
        self._memo = model_memo(pin, model)
        self.data = lend_data(pin, self._memo, self, constraints)
        self.joints = self._memo["joints"]
        self.layout = self.joints.layout
        if self.joints.zyx:
            # generalized-α's analytic matrix has no blocks for G(q)⁻¹: it differences the step
            self.iteration_matrix = None
        self.loads = Loads(pin, model, tau, fext, tau_derivatives)
        self.q0, v0, self.V0 = initial_state(self._memo, pin, model, q0, v0)
        # write_back's watch of singular configurations: times, the passage under way, the last step
        self.branch_switches, self.singular_passages, self._branch, self._last = [], [], None, None
        self._A_last = None
        self.cons = Constraints(pin, model, self.data, self.joints, [] if constraints is None else constraints,
                                self.q0, prox_settings)
        self.n_constraints = self.cons.n
        if self.n_constraints:
            self._rank_constraints()
        if self.compiled:
            self.f, f_engine = compiled_f(self)
            self._f_compiled = self.f
            self.f.__doc__ = PinocchioModel.f.__doc__
            if f_engine is not None:
                self.engine_velocity = EngineVelocity(self.joints.root_bodies, f_engine)
        self.loads.check(self.q0, v0)          # a wrong tau or fext fails before any step

    def __del__(self):
        give_back(self)            # the lent pinocchio.Data, for the next model of this pinocchio.Model

    def _rank_constraints(self):
        """Set aside the constraint rows that are redundant at q0 (at its projection onto the
        constraints when q0 does not close them: refused when that fails)."""
        q = self.q0
        if np.abs(self.cons.residual_all(q)).max() > CLOSED_TOL:
            q = self._closed(self.q0, self.V0, 0.0)[0]
        self.cons.set_rows(independent_rows(self.cons.jacobian_all(q)))
        self.n_constraints = self.cons.n
        self._A_last = None                      # the projection's A had every row

    def _closed(self, q0, V0, t0):
        """The core's projection of (q0, V0) onto the constraints (:func:`project_initial`), or
        InputError naming the constraint it could not close."""
        from lgt_bridge.integrators.constraints import project_initial
        with np.errstate(all="ignore"):
            try:
                q, V, rep = project_initial(self, q0, V0, t0)
            except np.linalg.LinAlgError as exc:
                q, V, rep = q0, V0, {"position_residual_after": np.inf, "error": str(exc)}
        if rep is None:
            return q, V, rep
        g = self.cons.residual_all(q)
        if not np.isfinite(q).all() or not np.abs(g).max() <= 1e-9:
            g0 = self.cons.residual_all(q0)
            k = int(np.argmax(np.abs(g0)))
            raise InputError(
                f"constraint residual {k} of {self.cons._owner(k)} is {g0[k]:.3g} at q0 and the projection onto "
                f"the constraints failed (residual {np.abs(g).max() if np.isfinite(g).all() else np.inf:.3g} "
                "after it): the constraint frames cannot be brought together from this configuration. "
                "Check joint1/joint2 placements, or start from a configuration that closes the loop.")
        return q, V, rep

    def project_initial(self, q0, V0, t0):
        """(q, V, report): the initial state moved onto the constraints (a loop not closed at q0,
        as Pinocchio's examples start it; velocities onto A V = 0) by the core's projection;
        ``report`` None when it was consistent. InputError when the projection fails."""
        self._branch = self._last = None
        self.branch_switches, self.singular_passages = [], []        # of this run
        return self._closed(q0, V0, t0)

    @property
    def step_write_back(self):
        """write_back watches constrained runs only."""
        return self.n_constraints > 0

    def write_back(self, q, V, t):
        """After each step of a constrained run: watch for passages near a singular configuration
        of the constraints (A's smallest singular value below SINGULAR_TOL of its largest), where
        assembly branches meet and a numerical solution can leave its branch (a four-bar at its
        collinear configuration). Through such a passage the velocity change
        is checked against the smooth motion's, Σ (V_{k+1} - V_k - h (f_k + f_{k+1})/2); when it
        leaves the passage a ModelNote names its times and says whether the velocity jumped (the
        motion switched branch: ``branch_switches``) or stayed continuous (``singular_passages``)."""
        if not self.n_constraints:
            return
        A = self.constraint_jacobian(q)
        w = np.linalg.eigvalsh(A @ A.T)                          # σ² of A, ascending
        ratio = np.sqrt(max(w[0], 0.0) / max(w[-1], 1e-300))
        z = self._branch
        q, V = np.array(q, float), np.array(V, float)        # the stepper's buffers: keep copies
        if z is None and not ratio < SINGULAR_TOL:
            self._last = (t, q, V)
            return
        f = self.f(q, V, t)
        if z is None:                            # entering: from the last step before, if any
            z = self._branch = {"t0": t, "min": ratio, "dev": np.zeros(len(V)), "scale": np.linalg.norm(V)}
            last = self._last
            if last is not None and last[0] < t:
                z["t0"] = last[0]
                z["prev"] = (last[0], last[2], self.f(last[1], last[2], last[0]))
        prev = z.get("prev")
        if prev is not None and t > prev[0]:
            z["dev"] += V - prev[1] - 0.5 * (t - prev[0]) * (f + prev[2])
        z["prev"] = (t, V, f)
        z["min"] = min(z["min"], ratio)
        z["scale"] = max(z["scale"], np.linalg.norm(V))
        self._last = (t, q, V)
        if ratio < SINGULAR_TOL:
            return
        self._branch = None                      # left the passage
        jump = float(np.linalg.norm(z["dev"])) / max(z["scale"], 1e-300)
        where = (f"between t = {z['t0']:.9g} and t = {t:.9g} the motion passed a singular configuration of its "
                 f"constraints (smallest relative singular value of A {z['min']:.2g}), where assembly branches meet")
        if jump > BRANCH_JUMP_TOL:
            self.branch_switches.append((z["t0"], float(t)))
            warnings.warn(ModelNote(
                f"Pinocchio model: {where}, and the solution switched branch there: its velocity departed from "
                f"the smooth motion's by {jump:.2g} of |V|. The solution after t = {z['t0']:.9g} follows another "
                "assembly branch than the one it was on; rerun with a tighter tolerance or a smaller step to "
                "pass the singular configuration on the branch the motion was on."), stacklevel=2)
        else:
            self.singular_passages.append((z["t0"], float(t)))
            warnings.warn(ModelNote(
                f"Pinocchio model: {where}; the velocity stayed continuous through it (departure {jump:.2g} of "
                "|V|), so the motion is still on its branch."), stacklevel=2)

    @property
    def compiled(self):
        """True when f runs the compiled kernels (``backend``, fixed when the model is built)."""
        return self.backend == "numba"

    # the parts' names, as the model has always had them
    roots = property(lambda self: self.joints.roots, doc="(iq, iv) of each free-flyer")
    balls = property(lambda self: self.joints.balls, doc="(iq, iv) of each spherical joint")
    planars = property(lambda self: self.joints.planars, doc="(iq, iv) of each planar joint")
    zyx = property(lambda self: self.joints.zyx, doc="(iq, iv) of each spherical-ZYX joint")
    cms = property(lambda self: self.cons.cms, doc="the RigidConstraintModels")
    cds = property(lambda self: self.cons.cds, doc="their RigidConstraintData")
    prox = property(lambda self: self.cons.prox, doc="constraintDynamics' ProximalSettings")
    redundant_rows = property(lambda self: self.cons.redundant_rows,
                              doc="constraint rows set aside as redundant at q0 (among all rows)")
    _tau = property(lambda self: self.loads.tau, doc="tau as given (a float vector, callable or None)")

    def joint_of(self, kind, index):
        """The joint that owns entry ``index`` of q (kind 'q') or of v / V (kind 'v'), for messages:
        "joint 'l_hip_pitch' (Pinocchio joint 3)"."""
        return self.joints.joint_of(kind, index)

    def check_mass_matrix(self, q):
        """InputError when Pinocchio's joint-space mass matrix (CRBA) at q is singular or
        indefinite (e.g. links with zero inertia, as in example-robot-data's iCub and Romeo),
        naming the joints; with constraints, on the motions they allow. Called by
        :func:`lgt_bridge.simulate.simulate` before the first step."""
        q = np.asarray(q, float)
        # a model wrapped afresh for each run is checked once per configuration while the
        # pinocchio.Model is unchanged (model_memo compares it with a copy)
        memo = self._memo if not self.n_constraints else None
        key = q.tobytes()
        if memo is not None and key in memo["mass_ok"] and self.model == memo["copy"]:
            return
        from lgt_bridge.validation import mass_defects
        M = self._crba(q)
        A = None
        if self.n_constraints:
            # A is with respect to V; v = T V, so with respect to v it is A T⁻¹
            A = np.linalg.solve(self.joints.T(q).T, self.constraint_jacobian(q).T).T
        defects = mass_defects(M, A)
        if not defects:
            if memo is not None and len(memo["mass_ok"]) < 64 and self.model == memo["copy"]:
                memo["mass_ok"].add(key)
            return
        i, lam = defects[0]
        names = list(dict.fromkeys(self.joint_of("v", k) for k, _ in defects))
        more = ""
        if len(defects) > 1:
            more = (f"; {len(defects)} such directions, in {', '.join(names[:6])}"
                    + (", ..." if len(names) > 6 else ""))
        kind = "indefinite" if lam < 0 else "singular"
        raise InputError(
            f"Pinocchio mass matrix (crba) at q0 is {kind}: the motion of {names[0]} (v index {i}) "
            f"has {'negative' if lam < 0 else 'no'} inertia (scaled eigenvalue {lam:.2g}){more}. "
            "Its acceleration is undefined and an integrator would fail or crawl to max_steps. "
            "Give the links moved by these joints positive inertias, or set a rotor inertia "
            "(e.g. model.armature[:] = 1e-3 for every joint; model.armature[idx_v] for one) "
            "before wrapping the model.")

    # --- Pinocchio velocity (v_lin body, ω body) <-> model twist (ω body, ṙ inertial) ---------
    def v_from_twist(self, q, V):
        """Pinocchio's v of the model twist V at q (a new array)."""
        if not self.compiled:
            return self.joints.v_from_twist(q, V)
        W = self._kW.copy()
        self._kernels.v_from_twist(np.ascontiguousarray(q, dtype=np.float64), np.ascontiguousarray(V, dtype=np.float64),
                     self._jt, W)
        return W[self._kv].copy()

    def _v_from_twist_numpy(self, q, V):
        return self.joints.v_from_twist(q, V)

    def twist_from_v(self, q, v):
        """The model twist V of Pinocchio's v at q (a new array)."""
        return self.joints.twist_from_v(q, v)

    def pin_state(self, q, V):
        """(q, v) in Pinocchio's own coordinates, for pin.forwardKinematics, frames, viewers.

        ``q`` is one state of a result's ``r.q`` (already Pinocchio's q, ``x y z w``
        quaternions); ``V`` the same state of ``r.V``, in the bridge's twist order (ω, v),
        which this turns into Pinocchio's v (linear first). InputError for an empty or
        ill-shaped state, e.g. ``r.q[-1]`` of a run that failed before its only output time
        (check ``r.success``)."""
        q, V = np.asarray(q, float), np.asarray(V, float)
        if q.shape != (self.nq,) or V.shape != (self.layout.nv,):
            raise InputError(f"pin_state(q, V): expected one state, q of shape ({self.nq},) and V of shape "
                             f"({self.layout.nv},); got {q.shape} and {V.shape}. Pass r.q[i], r.V[i] of a "
                             "result that has states (an empty r.q: the run failed before its first output "
                             "time, see r.success and r.message).")
        return q.copy(), self.v_from_twist(q, V)

    def _moved(self, q, d):
        """τ(q, d): q moved by the twist increment d (SO(3)xR³, exp chart)."""
        return self.joints.moved(q, d)

    # --- model protocol ---------------------------------------------------------------------------
    def f(self, q, V, t):
        """V̇ = f(q, V, t): one Pinocchio ABA (constraintDynamics with constraints); a new array.
        (A compiled model replaces this by the closure of :func:`lgt_pinocchio.rhs.build_f` on
        the instance.)"""
        if self.compiled:
            return self._f_compiled(q, V, t)
        return f_numpy(self, q, V, t)

    def mass_matrix(self, q):
        """M̄ = Tᵀ M T in twist coordinates (Pinocchio's CRBA, symmetrized)."""
        T = self.joints.T(q)
        return T.T @ self._crba(q) @ T

    def _crba(self, q):
        """Pinocchio's joint-space mass matrix at q (CRBA fills the upper triangle only)."""
        M = self.pin.crba(self.model, self.data, q)
        return np.where(_upper(len(M)), M, M.T)

    def forces(self, q, V, t):
        """Q̄ with M̄ V̇ = Q̄ (+ constraint forces): Tᵀ (τ - rnea(q, v, 0, fext) - M Ṫ V), where
        v = T V and Ṫ V = (-ω × v_lin, 0) on each free-flyer (d/dt of Rᵀ ṙ at fixed ṙ)."""
        pin = self.pin
        v = self.v_from_twist(q, V)
        tau = self.loads.torques(t, q, v)
        z = np.zeros(self.nv)
        if self.loads.fext is None:
            b = pin.rnea(self.model, self.data, q, v, z)
        else:
            b = pin.rnea(self.model, self.data, q, v, z, self.loads.forces(t, q, v))
        return self.joints.T(q).T @ (tau - b - self._crba(q) @ self.joints.TdV(v, q))

    def constraints(self, q):
        return self.cons.residual(q)

    def constraint_jacobian(self, q):
        """A(q) = ∂g/∂V (ġ = A V) from Pinocchio's frame Jacobians
        (:meth:`lgt_pinocchio.constraints.Constraints.jacobian`). The last one is kept: the
        projection after a step ends with A at the step's q, which write_back reads again."""
        key = np.asarray(q, float).tobytes()
        if self._A_last is None or self._A_last[0] != key:
            self._A_last = (key, self.cons.jacobian(q))
        return self._A_last[1].copy()

    def constraint_gamma(self, q, V):
        """γ(q, V) = (d/dt A) V, so that g̈ = A V̇ + γ, from Pinocchio's frame accelerations
        (:meth:`lgt_pinocchio.constraints.Constraints.gamma`)."""
        if not self.n_constraints:
            return np.zeros(0)
        q, V = np.asarray(q, float), np.asarray(V, float)
        return self.cons.gamma(q, self.v_from_twist(q, V))

    def _constraint_jacobian_fd(self, q, eps=1e-6):
        return jacobian_fd(self, q, eps)

    def _constraint_gamma_fd(self, q, V, eps=2e-3):
        return gamma_fd(self, q, V, eps)

    # --- generalized-α: the iteration matrix ------------------------------------------------------
    def iteration_matrix(self, q, V, t, c_acc, c_vel, c_pos, lam=None, Vdot=None):
        """M c_acc + C_t c_vel + K_t c_pos for generalized-α's analytic Newton matrix, in
        V = (ω body, ṙ inertial) and the SO(3)xR³ increments z = (δθ body, δr inertial):
        the derivatives of the residual R = M̄ V̇ - Q̄ (+ Aᵀλ) = Tᵀ r(q, v, a) (+ Aᵀλ), with
        r = rnea(q, v, a) - u(t, q, v) (u: tau and the joint torques of fext), v = T V and
        a = T V̇ + Ṫ V, from Pinocchio's analytic RNEA derivatives (∂r/∂q in its tangent
        coordinates, ∂r/∂v, ∂r/∂a = M):

            M̄   = Tᵀ M T
            C_t = Tᵀ (∂r/∂v T + M ∂a/∂V)
            K_t = Tᵀ (∂r/∂q T + ∂r/∂v ∂v/∂z + M ∂a/∂z) + (∂Tᵀ/∂z) r + ∂(Aᵀλ)/∂z

        (Pinocchio's tangent increment of a free-flyer or planar joint is T z to first order;
        ∂v/∂z, ∂a/∂z, ∂a/∂V and ∂Tᵀ/∂z are nonzero on those only: v_lin = Rᵀṙ turns with δθ).
        ∂u/∂q and ∂u/∂v from ``tau_derivatives`` when given, else by forward differences when
        tau or fext is a callable. Models with spherical-ZYX joints have no analytic matrix.

        The derivatives are taken at V̇ = ``Vdot``, by default at the acceleration Newton
        converges to: ABA's, M̄⁻¹(Q̄ - Aᵀλ) given the constraint forces ``lam``, else
        constraintDynamics'. With ``lam`` the constraints' geometric stiffness ∂(Aᵀλ)/∂z is
        included, by central differences of the analytic A. The three matrices are computed
        once per (q, V, t, lam) and kept for the next calls (generalized-α asks for each)."""
        key = (float(t), np.asarray(q, float).tobytes(), np.asarray(V, float).tobytes(),
               None if lam is None or not self.n_constraints else np.asarray(lam, float).tobytes(),
               None if Vdot is None else np.asarray(Vdot, float).tobytes())
        cached = getattr(self, "_it_cache", None)
        if cached is None or cached[0] != key:
            with np.errstate(over="ignore", invalid="ignore"):   # a diverging iterate: genalpha
                parts = iteration_parts(self, q, V, t, lam, Vdot)  # checks the matrix is finite
            cached = self._it_cache = (key, parts)
        return combine_iteration(cached[1], c_acc, c_vel, c_pos)

    # --- diagnostics ------------------------------------------------------------------------------
    def energy(self, q, V):
        pin = self.pin
        v = self.v_from_twist(q, V)
        return pin.computeKineticEnergy(self.model, self.data, q, v) + pin.computePotentialEnergy(self.model, self.data, q)

    def spatial_momentum(self, q, V):
        """Total spatial momentum (linear, angular about the world origin) in the world frame."""
        pin = self.pin
        v = self.v_from_twist(q, V)
        pin.forwardKinematics(self.model, self.data, q, v)
        h = pin.Force.Zero()
        for j in range(1, self.model.njoints):
            h += self.data.oMi[j].act(self.model.inertias[j] * self.data.v[j])
        return np.concatenate([h.linear, h.angular])
