"""Exudyn's GeneralContact as a model with switching modes (:mod:`lgt_bridge.switches`).

A GeneralContact's forces in Exudyn's implicit solver come from its active sets: the
contact pairs its PostNewton found active at the last step's end (a sphere with a sphere,
a triangle or an ANCF cable; active while the gap is closed and the contact force is
compressive, k·gap + d·ġ < 0; with friction, also whether the pair slides or sticks in
the regularized zone). The evaluator of :class:`~lgt_exudyn.model.ExudynModel` is such a
solver, so f reads those sets and is smooth as long as they stay. :class:`ContactModes`
gives the model its ``switch_mode(q, V, t)``: the state written, Exudyn's PostNewton sets
the active sets from it, and the sets are read back (``GetActiveContacts`` of every
sphere and cable) as the mode :class:`lgt_bridge.switches.SwitchLocator` compares.

This is the law of Exudyn's implicit solvers; its explicit solvers keep no active sets and
apply the force wherever a gap is closed (a pull too, as a pair separates): RK44 converges
to another motion (a sphere of tests/models' general_contact_spheres ends 1.2e-3 lower).
"""
import warnings

import numpy as np

from lgt_bridge.errors import ModelNote

#: Exudyn's explicit DynamicSolverTypes: their GeneralContact law has no active sets
EXPLICIT_SOLVERS = ("ExplicitEuler", "ExplicitMidpoint", "RK33", "RK44", "RK67", "ODE23", "DOPRI5",
                    "VelocityVerlet")


def note_explicit_law(mbs, solver_type):
    """A ModelNote when the script asked Exudyn for an explicit solver (``solver_type``, the
    ``solverType`` of its SolveDynamic call) on a system with a GeneralContact whose spheres
    are damped (or that holds ANCF cables, whose damping cannot be read): Exudyn's explicit
    solvers let a damped pair pull as it separates, the bridge (as Exudyn's implicit
    solvers) releases it, so the motions can differ (see the module docstring)."""
    name = str(solver_type).rsplit(".", 1)[-1] if solver_type is not None else ""
    if name not in EXPLICIT_SOLVERS:
        return
    for i in range(count(mbs)):
        gc = mbs.GetGeneralContact(i)
        d = gc.GetPythonObject()
        n_spheres, n_cables = int(d.get("numberOfSpheresMarkerBased", 0)), int(d.get("numberOfANCFCable2D", 0))
        damped = sum(gc.GetSphereMarkerBased(j, addData=True).get("contactDamping", 0.0) > 0.0
                     for j in range(n_spheres))
        if damped or n_cables:
            warnings.warn(ModelNote(
                f"GeneralContact {i} has damped contacts and the script asked Exudyn for solverType = {name}: "
                "Exudyn's explicit solvers apply k·gap + d·ġ wherever a gap is closed, a pull too as a pair "
                "separates; lgt_bridge follows Exudyn's implicit solvers, which release a pair whose force "
                "turns to a pull (the active sets of Exudyn's PostNewton). Where pairs separate while "
                "damped the motions differ (Exudyn's generalContactCylinderTest.py, a cylinder of 160 "
                "spheres rolling on triangles: 0.5 % at 2 s). For the explicit law run exu.SolveDynamic "
                "itself; for the bridge's, compare with Exudyn's GeneralizedAlpha."), stacklevel=3)
            return


def count(mbs):
    """How many GeneralContacts the system has (0 when Exudyn cannot say)."""
    try:
        return int(mbs.NumberOfGeneralContacts())
    except Exception:
        return 0


class ContactModes:
    """The active sets of a system's GeneralContacts as one mode (see the module docstring);
    ``model``: the :class:`~lgt_exudyn.model.ExudynModel` (its state write and evaluator)."""

    def __init__(self, model):
        exu = model.engine.exu
        self.model, self.mbs = model, model.mbs
        types = exu.ContactTypeIndex
        self.items = []                  # (contact, type index, item) whose active sets make the mode
        self.spheres = []                # (contact, sphere)
        for i in range(count(self.mbs)):
            gc = self.mbs.GetGeneralContact(i)
            d = gc.GetPythonObject()
            for key, kind in (("numberOfSpheresMarkerBased", types.IndexSpheresMarkerBased),
                              ("numberOfANCFCable2D", types.IndexANCFCable2D)):
                self.items.extend((gc, kind, j) for j in range(int(d.get(key, 0))))
            self.spheres.extend((gc, j) for j in range(int(d.get("numberOfSpheresMarkerBased", 0))))
        radii = [gc.GetSphereMarkerBased(j, addData=True)["radius"] for gc, j in self.spheres]
        self.r_min = float(min(radii)) if radii else 0.0
        if not self.r_min > 0.0:
            self.spheres = []
        self._trail = []                 # the spheres at the last two calls

    #: the mode is a tuple over ``items``; a call may ask for some of them (``items=``)
    partial = True

    def __call__(self, q, V, t, items=None):
        """Set the active sets from the state (q, V, t) (Exudyn's PostNewton) and return them:
        one tuple per sphere and cable (``items``: of those items only; the spheres' travel
        is recorded for :meth:`test_points` on calls asking for all)."""
        m = self.model
        m.write_back(q, V, t)
        m.solver.PostNewton(self.mbs, m.engine.settings)
        its = self.items if items is None else [self.items[i] for i in items]
        if items is None and self.spheres:
            self._trail = self._trail[-1:] + [self._spheres()]
        return tuple(tuple(np.asarray(gc.GetActiveContacts(kind, j)).tolist()) for gc, kind, j in its)

    def _spheres(self):
        """Positions and speeds of the spheres where PostNewton last put them."""
        data = [gc.GetSphereMarkerBased(j) for gc, j in self.spheres]
        return (np.array([d["position"] for d in data]),
                np.linalg.norm(np.array([d["velocity"] for d in data]), axis=1))

    def test_points(self, h):
        """Interior test points for the step of length h between the states of the last two
        calls: enough that no sphere moves more than half the smallest radius between two
        (so no contact can begin and end between them: a sphere crossing a triangle's plane
        or another sphere's surface overlaps it at a test point)."""
        if len(self._trail) < 2 or not self.spheres:
            return 0
        (p0, v0), (p1, v1) = self._trail
        travel = max(np.linalg.norm(p1 - p0, axis=1).max(), 0.5 * h * (v0 + v1).max())
        return int(np.ceil(2.0 * travel / self.r_min))
