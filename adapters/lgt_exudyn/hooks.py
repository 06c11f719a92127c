"""What the Exudyn drop-in asks of a model between Exudyn's steps: connectors switched on or
off by a pre-step user function (the constraint rows classified again), a constraint offset
moved (spread over the step as a time dependence), and the outputs of a written state (its
accelerations and Lagrange multipliers for Exudyn's sensors and solution file); and the
system facts they depend on: a pre-step user function, the contact gaps among the data
coordinates, impact models the bridge refuses; and the system's pre-Newton residual user
function, called before each residual (:class:`PreNewtonResidual`). :class:`StepHooks` is a part of
:class:`~lgt_exudyn.model.ExudynModel`."""
import warnings

import numpy as np

from lgt_bridge.errors import InputError, ModelError, ModelNote

from . import contact as _contact
from .constraints import ConstraintRows
from .engine import engine_call
from .sparse import LAM


class StepHooks:
    """The drop-in's per-step methods of :class:`~lgt_exudyn.model.ExudynModel` (they use its
    parts: ``engine``, ``nodes``, ``cons``, ``sd``, ``mbs``)."""

    #: the state is written into Exudyn where a run stops or outputs (the drop-in's outputs,
    #: a run's end), not after every step: f writes each stage's state itself and Exudyn's
    #: sensors and solution file are written from the outputs (which lets the compiled step
    #: loop run on between them)
    step_write_back = False

    def _take_discontinuous(self, settings):
        """The discontinuous parts of the system: data coordinates (contact and friction
        states: ``post_step``, Exudyn's discontinuous iteration after each step), or else a
        GeneralContact's active sets (``switch_mode``: switches located in time,
        :mod:`lgt_bridge.switches`)."""
        mbs, engine = self.mbs, self.engine
        if self.sd.DataSize():
            self.post_step = self._post_newton
            s = settings if settings is not None else engine.exu.SimulationSettings()
            disc = s.timeIntegration.discontinuous
            self._disc_tol = float(disc.iterationTolerance)
            # Exudyn's maxIterations counts the Newton solves of a step, the first included: its
            # redos are one fewer. Unsettled states after them: kept (ignoreMaxIterations) or the
            # step cut. The count matters where they never settle: a sticking wheel's friction
            # direction flips at every solve, and the step keeps the force of its last solve
            # (createRollingDiscPenaltyTest.py with one solve more than Exudyn's: 4.5e-3 m off
            # Exudyn refined at the script's steps, Exudyn's own 2.9e-4; with Exudyn's count 1.5e-4)
            self.max_discontinuous = max(0, int(disc.maxIterations) - 1)
            self.ignore_max_discontinuous = bool(disc.ignoreMaxIterations)
            if coulomb_wheels(mbs):     # their stick never settles: kept at the step's length
                self.unsettled_cut = 1.0
            self._gap_rows, self._mode_rows = gap_rows(mbs), mode_rows(mbs)
            self._circle_rows = curve_circle_rows(mbs)
            self.locate_circle_contacts = False     # the drop-in sets it for error-controlled runs
            # gaps and modes that change sign are switches located in time (error-controlled
            # runs: the error falls with the tolerance); the drop-in's fixed steps take them as
            # Exudyn does, redone at the step's end when PostNewton's error exceeds its
            # tolerance (located there, Exudyn's rollingCoinPenaltyTest.py at its steps: the
            # coin's touch-down cut a step to 1e-8 s and its contact point ended 7.9e-4 m off
            # Exudyn refined 10x, Exudyn's own 1.7e-6; redone: 2.8e-5)
            self.locate_switches = True
            note_lagged_objects(mbs)
            refuse_impact_models(mbs)
            refuse_sliding_joints(mbs)
        elif _contact.count(mbs):
            self.switch_mode = _contact.ContactModes(self)

    def _circles_switched(self, d0, d1):
        """True when a segment of an ObjectContactCurveCircles pushed a circle in the data d0
        and not in d1, or the reverse (:func:`curve_circle_rows`); checked only when
        ``locate_circle_contacts``."""
        if not (self.locate_circle_contacts and self._circle_rows):
            return False
        return any(np.any(a != b) for a, b in zip(circles_pushed(d0, self._circle_rows),
                                                   circles_pushed(d1, self._circle_rows)))

    def _take_residual_user_function(self):
        """The system's PreNewtonResidualUserFunction (``mbs.SetPreNewtonResidualUserFunction``),
        called before each of the bridge's residuals (:class:`PreNewtonResidual`)."""
        try:
            uf = self.mbs.GetPreNewtonResidualUserFunction()
        except Exception:                   # an Exudyn without system user functions
            uf = None
        if isinstance(uf, dict):            # Exudyn 1.13: {'function': f, 'type': 'Python'}
            uf = uf.get("function")
        if not uf:
            return
        if not callable(uf):
            raise InputError(f"the system's PreNewtonResidualUserFunction ({type(uf).__name__}) cannot be "
                             "called from Python; lgt_bridge calls it before each residual. Set a Python "
                             "function with mbs.SetPreNewtonResidualUserFunction, or run the model with "
                             "Exudyn's own exu.SolveDynamic.")
        self.solver = PreNewtonResidual(self.solver, uf)

    def _connector_state(self):
        """What decides which AE rows are constraints and can be changed between steps:
        ``activeConnector`` and ``constrainedAxes`` of every object owning AE rows."""
        mbs, sd, out = self.mbs, self.sd, []
        if not self.engine.nae:
            return out
        if getattr(self, "_ae_objects", None) is None:
            self._ae_objects = []
            for k in range(sd.NumberOfObjects()):
                try:
                    if len(sd.GetObjectLTGAE(k)):
                        o = mbs.GetObject(k)
                        self._ae_objects.append((k, [p for p in ("activeConnector", "constrainedAxes") if p in o]))
                except Exception:                   # objects without algebraic equations
                    pass
        for k, params in self._ae_objects:
            out.append(tuple(np.ravel(mbs.GetObjectParameter(k, p)).tolist() for p in params))
        return out

    @engine_call
    def rows_changed(self, q, V, t):
        """Re-classify the constraint rows at (q, V, t) when a connector was switched on or
        off (or its ``constrainedAxes`` changed) since the last classification — a pre-step
        user function did it; True when the rows changed (steppers built on the old rows
        must be rebuilt)."""
        state = self._connector_state()
        if self._connectors is None or state == self._connectors:
            self._connectors = state
            return False
        self._connectors = state
        q2, V2 = q[:self.n2], V[:self.nv]
        old = (self.n_constraints, tuple(self.cons.ae_keep), self.velocity_rows)
        self.cons = ConstraintRows(self.engine, self.nodes, q2, V2, t, self.index2)
        self._take_rows()
        self.write_back(q, V, t)
        if old == (self.n_constraints, tuple(self.cons.ae_keep), self.velocity_rows):
            return False
        self.reset_caches()
        return True

    @engine_call
    def begin_step(self, q, t, h, g_end):
        """At the start of an Exudyn step after its pre-step user function ran: a change of
        the holonomic rows' residual at the unchanged state (an offset moved: a crane's
        reeving, a ramped drive) against ``g_end`` (:meth:`holonomic_residual` where the last
        step ended) is spread over the step as a time dependence (see
        :meth:`.constraints.ConstraintRows.set_ramp`), so explicit steps follow it in
        position and velocity instead of projecting a jump. Not with index 2 (Exudyn's
        velocity-level rows do not see offsets). Velocity-level offsets are looked at again.
        True when the step's velocity targets may have moved (a ramp, velocity offsets): the
        step should start with its velocities on them."""
        cons = self.cons
        cons.set_ramp(0, 1, None)
        if cons.nonholonomic:               # a velocity-level offset may have been set
            cons.detect_velocity_offset(q[:self.n2], t)
        if g_end is not None and not self.index2 and self.n_constraints and len(g_end) == cons.n:
            jump = self.holonomic_residual(q, t) - g_end
            if np.abs(jump).max() > 1e-14 * (1.0 + np.abs(g_end).max()):
                cons.set_ramp(t, h, jump)
        return cons.ramp is not None or cons.velocity_offset

    @engine_call
    def holonomic_residual(self, q, t):
        """g(q, t) of the holonomic rows (0 on the others), without any ramp."""
        if not self.n_constraints:
            return np.zeros(0)
        ramp, self.cons.ramp = self.cons.ramp, None
        try:
            return self.cons.at(q[:self.n2], t)
        finally:
            self.cons.ramp = ramp

    @engine_call
    def multipliers(self, q, V, t, Vd=None):
        """λ of the kept rows at (q, V, t): the index-1 solve's Lagrange multipliers, in
        Exudyn's convention (M q̈ + C_qᵀ λ = Q; A = C_q H, so the twist solve's λ is
        Exudyn's), from Aᵀ λ = Q̄ - M̄ V̇ with V̇ = f(q, V, t) (given as ``Vd``, or evaluated)."""
        sp = getattr(self._P, "sp", None) if self._compiled and self.ode1 is None else None
        if sp is not None:                  # the sparse solve keeps the λ of its last f
            Vd = self.f(q, V, t)
            if sp.lam_ok:
                return sp.F[sp.fo[LAM]:sp.fo[LAM + 1]].copy()
        if Vd is None:
            Vd = self.f(q, V, t)
        if not self.n_constraints:
            return np.zeros(0)
        q2, V2 = np.asarray(q[:self.n2], float), np.asarray(V[:self.nv], float)
        if self._compiled:
            Qb, Mb = self._forces_compiled(q2, V2, t)
        else:
            Mb, Qb = self._evaluate(q2, V2, t, need_gamma=False)[:2]
        A = self._jacobian2(q2)
        return np.linalg.lstsq(A.T, Qb - Mb @ Vd[:self.nv], rcond=None)[0]

    @engine_call
    def write_outputs(self, q, V, t, accelerations=True, multipliers=True):
        """After an output step: the state, and what Exudyn's sensors and solution file read
        besides it — the accelerations q̈_e (``accelerations``) and, in Exudyn's algebraic
        coordinates, the Lagrange multipliers of that state (``multipliers``; joint forces:
        ``ForceLocal`` sensors read them); rows set aside (inactive, redundant) and the
        Euler-parameter normalizations (τ keeps quaternions unit: no reaction) get 0."""
        nae = self.engine.nae if multipliers else 0
        if not accelerations and not nae:
            write = self.__dict__.get("_writer")       # (every output step: looked up once)
            if write is None:
                write = self._writer = self.writer()
            write(q, V, t)
            return
        Vd = self.f(q, V, t)
        q2, V2 = q[:self.n2], V[:self.nv]
        lam = self.multipliers(q, V, t, Vd) if nae else None
        self.write_back(q, V, t)
        if accelerations:
            self.sd.SetODE2Coordinates_tt(self.nodes.H(q2) @ Vd[:self.nv] + self.nodes.Hdot_V(q2, V2))
        if nae:
            ae = np.zeros(nae)
            ae[self.cons.ae_keep] = lam
            self.sd.SetAECoordinates(ae)

    @engine_call
    def accelerations(self, q, V, t):
        """Exudyn's ODE2 accelerations q̈_e = H V̇ + Ḣ V at (q, V, t) (the ODE1 rates are not
        part of them)."""
        q2, V2 = q[:self.n2], V[:self.nv]
        Vd = self.f(q, V, t)[:self.nv]
        return self.nodes.H(q2) @ Vd + self.nodes.Hdot_V(q2, V2)

    def writer(self):
        """``write(q, V, t)``: :meth:`write_back` with the kernel and Exudyn's views looked up
        once (the drop-in writes every output step; q, V float64 C-contiguous). It falls back
        to write_back when the model's pack was dropped (reset_caches) since."""
        if not self._compiled or self.ode1 is not None:
            return self.write_back
        P = self._pack()
        kw, T, off, w, qpos, qvel, set_time = self._kernels.write, P.T, P.off, P.w, P.qpos, P.qvel, self.sd.SetTime

        def write(q, V, t):             # (no ODE1 part: q and V are Exudyn's ODE2 part whole)
            if self._P is not P:
                return self.write_back(q, V, t)
            kw(T, off, w, q, V, 0.0, qpos, qvel)
            set_time(t)
        return write


def has_prestep(mbs):
    """True when the system has a pre-step user function (Exudyn returns 0 when unset)."""
    try:
        return bool(mbs.GetPreStepUserFunction())
    except Exception:
        return False


#: contact objects with the data coordinates that hold their gaps, as offsets among the n data
#: coordinates of the object's node (Exudyn's documentation and PostNewton of each). Their
#: forces act while the gap stored by the last PostNewton is closed, so a closing or opening
#: not located would switch the force on or off only at the end of the step it falls in
#: (ObjectContactConvexRoll and ObjectContactCoordinate: 0.4 % off at any tolerance, the
#: error of a contact onset late by up to Exudyn's step)
GAP_OBJECTS = {
    "ContactSphereSphere": lambda o, n: [0],
    "ContactSphereTorus": lambda o, n: [0],
    "ContactConvexRoll": lambda o, n: [0],
    "ContactCoordinate": lambda o, n: [0],
    "ConnectorRollingDiscPenalty": lambda o, n: [2],
    # one gap per contact segment, first (then the friction states)
    "ContactCircleCable2D": lambda o, n: range(min(n, int(o.get("numberOfContactSegments", n)))),
    "ContactFrictionCircleCable2D": lambda o, n: range(min(n, int(o.get("numberOfContactSegments", n // 3)))),
}
#: objects whose force reads a velocity their PostNewton stored at the last step's end
LAGGED_OBJECTS = {"ConnectorRollingDiscPenalty": "its friction force acts along the slip velocity stored at the "
                                                 "last step's end (data coordinates 0, 1)"}


def objects(mbs):
    """(index, type without its "Object" prefix, dict) of each object of the system."""
    for k in range(mbs.systemData.NumberOfObjects()):
        o = mbs.GetObject(k)
        yield k, str(o.get("objectType", "")).removeprefix("Object"), o


def gap_rows(mbs):
    """Indices, among the system's data coordinates, of the contact gaps (the GAP_OBJECTS'
    data); the other data coordinates (tangential and impact velocities, plastic overlaps)
    are not switches when they change sign."""
    sd, rows = mbs.systemData, []
    for k, kind, o in objects(mbs):
        if kind in GAP_OBJECTS and "nodeNumber" in o:
            try:
                ltg = list(sd.GetNodeLTGData(int(o["nodeNumber"])))
            except Exception:           # no data node (an invalid nodeNumber)
                continue
            rows += [int(ltg[i]) for i in GAP_OBJECTS[kind](o, len(ltg)) if 0 <= i < len(ltg)]
    return np.array(rows, int)


def curve_circle_rows(mbs):
    """(object index, rows of the circle numbers, rows of the gaps) among the system's data
    coordinates, for each ObjectContactCurveCircles: per curve segment [circle number, gap,
    tangential velocity], the circle nearest to the segment and its gap. A segment pushes its
    circle while its stored circle number is >= 0 and its stored gap negative (its PostNewton
    stores them; the force is computed from the state but only for those segments). So a
    switch is a pair (segment, circle) starting or ceasing to push: a circle touching down or
    lifting off, and a circle sliding from one segment onto the next. Located only by the
    error-controlled methods: at Exudyn's fixed steps genalpha takes them at the step's end
    with a redo, as Exudyn does (each cut there costs a new iteration matrix:
    contactCurveExample.py over 60 s, 3.3 s without). Not located, dopri5 followed Exudyn's
    coarse steps: a chain drive's driven sprocket 5.7991e-6 rad at 0.03 s (Exudyn refined 10x
    and 30x 5.8791e-6 and 5.8751e-6); a pin sliding down Exudyn's contactCurvePolynomial.py
    arc of 127 segments kept the segment it left pushing and the next one idle until each
    step's end: x = -2.886592 at 1 s, Exudyn refined 10x/100x -2.887466/-2.887464 (located:
    -2.887469; contactCurveExample.py 0.30961359, Exudyn 100x 0.30961360, in 27 s instead of
    8.5 s)."""
    sd, out = mbs.systemData, []
    for k, kind, o in objects(mbs):
        if kind == "ContactCurveCircles" and "nodeNumber" in o:
            try:
                ltg = np.array(sd.GetNodeLTGData(int(o["nodeNumber"])), int)
            except Exception:           # no data node (an invalid nodeNumber)
                continue
            n = 3 * (len(ltg) // 3)
            out.append((k, ltg[0:n:3], ltg[1:n:3]))
    return out


def circles_pushed(d, rows):
    """Per ObjectContactCurveCircles (``rows``: :func:`curve_circle_rows`), the circle each
    segment pushes in the data coordinates d: its stored circle number where that is >= 0
    and its stored gap < 0, else -1."""
    return [np.where((d[circle] >= 0) & (d[gap] < 0.0), d[circle], -1.0) for k, circle, gap in rows]


def note_lagged_objects(mbs):
    """One ModelNote per LAGGED_OBJECTS kind, naming every object of that kind in the system
    (a mecanum-wheel car printed the same paragraph once per wheel)."""
    found = {}
    for k, kind, o in objects(mbs):
        if kind in LAGGED_OBJECTS:
            found.setdefault(kind, []).append(f"{k} {o.get('name', '')!r}")
    for kind, names in found.items():
        which = (f"object {names[0]} (Object{kind})" if len(names) == 1
                 else f"objects {', '.join(names)} (Object{kind}, each)")
        warnings.warn(ModelNote(
            f"Exudyn {which}: {LAGGED_OBJECTS[kind]}, so the "
            "motion depends on where the steps end, converging as they shorten (Exudyn's own solver "
            "too). method='genalpha' at Exudyn's steps reproduces Exudyn's result; the adaptive "
            "methods' steps differ (a mecanum-wheel car: 2e-3 relative at 1e-8)."), stacklevel=4)


def coulomb_wheels(mbs):
    """Indices of the ConnectorRollingDiscPenalty objects with dry friction and no
    proportional zone (``dryFrictionProportionalZone = 0``, Exudyn's default): their friction
    force has its full size along the slip direction stored at the last solve, so a sticking
    wheel's force flips at every solve of Exudyn's discontinuous iteration, which never
    settles however short the step (with a zone the stick settles: PostNewton's error is 0
    while the stored slip is within it). Exudyn keeps such a step after maxIterations solves
    (ignoreMaxIterations); shortening it only multiplies the steps
    (createRollingDiscPenaltyTest.py: 16x the steps for an error 2x below Exudyn's own)."""
    return [k for k, kind, o in objects(mbs) if kind == "ConnectorRollingDiscPenalty"
            and float(o.get("dryFrictionProportionalZone", 0.0)) == 0.0
            and any(float(f) != 0.0 for f in np.ravel(o.get("dryFriction", [0.0])))]


def mode_rows(mbs):
    """Indices, among the system's data coordinates, of the modes whose sign is a state of a
    CoordinateSpringDamperExt: its limit-stop state data[2] (0 free, < 0 / > 0 at the lower /
    upper stop) and its bristle friction's mode data[0] (0 stick, ±f slip). Exudyn's
    PostNewton measures their switches by a force error from the last step's penetration,
    which misses a stop left after a shallow penetration: a step longer than Exudyn's would
    then keep pulling the mass back until its end."""
    sd, rows = mbs.systemData, []
    for k, kind, o in objects(mbs):
        if kind != "ConnectorCoordinateSpringDamperExt" or int(o.get("nodeNumber", -1)) < 0:
            continue
        try:
            base = int(sd.GetNodeLTGData(int(o["nodeNumber"]))[0])
        except Exception:
            continue
        friction = [float(o.get(name, 0.0)) for name in ("dynamicFrictionForce", "staticFrictionOffsetForce",
                                                         "fDynamicFriction", "fStaticFrictionOffset")]  # (old names)
        bristle = float(o.get("frictionProportionalZone", 0.0)) == 0.0 and any(f != 0.0 for f in friction)
        rows += ([base] if bristle else []) + ([base + 2] if o.get("useLimitStops", False) else [])
    return np.array(rows, int)


def refuse_impact_models(mbs):
    """InputError before any step for ObjectContactSphereSphere (or SphereTriangle) with
    impactModel 1 or 2: its
    damping force uses the impact velocity data[2], which Exudyn's PostNewton rewrites at
    the end of every step, so the force depends on where the steps end and the model has no
    limit an error-controlled method converges to (a Newton's cradle: dopri5 at 1e-8 and
    1e-10 differed by 3e-3 and stood 1.4e-2 from Exudyn's own refined solution)."""
    for k, kind, o in objects(mbs):
        if kind == "ContactSphereSphere" and int(o.get("impactModel", 0)) != 0:
            # Exudyn 1.13 reports an ObjectContactSphereTriangle as ContactSphereSphere
            kind = "ObjectContactSphereTriangle" if "trianglePoints" in o else "ObjectContactSphereSphere"
            raise InputError(
                f"Exudyn object {k} {o.get('name', '')!r} ({kind}) has impactModel = "
                f"{int(o['impactModel'])}: its impact damping uses the impact velocity that Exudyn's "
                "PostNewton stores at the end of each of its own steps, so the contact force depends on "
                "the step sequence and lgt_bridge's steps would not converge to Exudyn's solution. Run "
                "this model with Exudyn's own exu.SolveDynamic, or use impactModel = 0 with "
                "contactDamping for the dissipation.")


def refuse_sliding_joints(mbs):
    """InputError before any step for ObjectJointSliding2D: its third algebraic coordinate is
    not a Lagrange multiplier but the sliding coordinate s along the cable (relative to the
    start-of-step value in its data coordinate 1), fixed by an index-1 equation (the force
    along the cable vanishes, or the gap along the slope does). lgt_bridge integrates the ODE2
    coordinates with every AE coordinate a multiplier: s would stay frozen at its
    start-of-step value, the joint pinned to one point of the cable (Exudyn's
    ANCFslidingJoint2D.py: the step size fell to 1e-8 s in the first millisecond, and
    ANCFslidingAndALEjointTest.py ran past 90 s)."""
    for k, kind, o in objects(mbs):
        if kind == "JointSliding2D":
            raise InputError(
                f"Exudyn object {k} {o.get('name', '')!r} (ObjectJointSliding2D): its algebraic "
                "coordinates hold the sliding coordinate s along the cable next to its two Lagrange "
                "multipliers; lgt_bridge treats every algebraic coordinate as a multiplier and cannot "
                "move s, so the joint would stay pinned to one point of the cable. Run this model with "
                "Exudyn's own exu.SolveDynamic.")


def general_contacts(mbs, located=True, chatter=False):
    """What a failed step should say about Exudyn's GeneralContact, or "" when the system has
    none. Its forces come from the active sets its PostNewton sets from the state (a pair is
    active while its gap is closed and its force compressive): the bridge takes them at each
    step's start and, with a method that has dense output (``located``), locates where they
    switch inside the step and restarts there (:mod:`lgt_bridge.switches`); without (or when
    the system's data coordinates make it run Exudyn's discontinuous iteration instead), a
    step across a switch meets the jump of the contact damping force (``chatter``: the
    failure already says the switches follow each other at once). Names each one with its
    parts."""
    parts = []
    for i in range(_contact.count(mbs)):
        try:
            d = mbs.GetGeneralContact(i).GetPythonObject()
            what = [f"{int(d.get(key, 0))} {name}" for key, name in
                    (("numberOfSpheresMarkerBased", "spheres"), ("numberOfTrigsRigidBodyBased", "triangles"),
                     ("numberOfANCFCable2D", "ANCF cables")) if int(d.get(key, 0))]
        except Exception:
            what = []
        parts.append(f"GeneralContact {i}" + (f" ({', '.join(what)})" if what else ""))
    if not parts:
        return ""
    head = (f" The system has {' and '.join(parts)}: its contact forces switch on and off where a gap "
            "closes or a contact force would pull (Exudyn's active sets)")
    if chatter:
        return head + ("; lgt_bridge located these switches and restarted at each, and here they follow "
                       "each other at once.")
    if located:
        return (head + "; lgt_bridge located these switches and restarted at each, so the failure is not a "
                "step across one: the contact phase itself needs smaller steps (stiff contact: "
                "use method='radau5' or 'genalpha', or lower minimumStepSize).")
    return (head + ", and lgt_bridge does not locate these switches here (a method without dense output, or "
            "a system with data coordinates, whose discontinuous iteration runs instead), so a step across "
            "one meets the jump of the contact damping force. Use method='dopri5', 'dop853' or 'radau5' "
            "(switches located), loosen the tolerances, or use method='genalpha'.")


class PreNewtonResidual:
    """Exudyn's evaluator with the system's PreNewtonResidualUserFunction ``uf(mbs, t,
    newtonIt, discontinuousIt)`` called before each ODE2 residual it computes, with the state
    already written: Exudyn calls it before the residual of each Newton iteration, so that
    loads it sets from the state (Exudyn's mainSystemUserFunctionsTest.py replicates a
    spring-damper by a LoadCoordinate so set) act at every state the integrator evaluates
    (without it the load kept its last value: the spring vanished). The bridge's
    evaluations are no Newton iterations of Exudyn's: ``newtonIt`` and ``discontinuousIt``
    are 0. An exception in ``uf`` becomes a ModelError naming the function and the time."""

    def __init__(self, solver, uf):
        self._solver, self._uf = solver, uf

    def __getattr__(self, name):
        return getattr(self._solver, name)

    def ComputeODE2RHS(self, mbs):
        t = mbs.systemData.GetTime()
        try:
            self._uf(mbs, t, 0, 0)
        except Exception as exc:
            raise ModelError(f"the system's PreNewtonResidualUserFunction raised at t = {t:.9g}: "
                             f"{type(exc).__name__}: {exc}. Fix it (run the script with Exudyn's own "
                             "solver to see it in context).") from exc
        self._solver.ComputeODE2RHS(mbs)
