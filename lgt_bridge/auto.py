"""``group="auto"`` / ``chart="auto"``: the cheapest group and chart each body needs.

The choice is read from the model's structure at q0, per body:

* **group** — SO(3)×R³ unless the body carries a joint attached away from its
  frame origin *and* the method leaves that joint to the integrator (an explicit
  method with ``project=False``). Only then does SE(3) pay for itself: its
  exponential moves a point fixed in the body along the body's screw, so a
  pinned point stays pinned to round-off (measured 4e-13 against 1.7e-7 on
  SO(3)×R³, Pinocchio pinned body, rkmk4, 10 s). Everywhere else SO(3)×R³ was as
  accurate or more, and cheaper, in the bench sweeps: heavy top with its joint
  projected (rkmk4, dt = 1e-3: 1.0e-6 against 2.2e-5 on SE(3)), heavy top on a
  pivot, free bodies and chains (equal error, 1.5–2.5× less wall time), a
  free-flyer whose frame is off its centre of mass (3.2e-6 against 2.8e-5).
  A joint "attached away from the frame origin" is read from the constraint
  Jacobian: a row that couples the body's translation and rotation velocities.
* **chart** — exp. The Cayley chart costs the same per step in this
  implementation (within the noise of the machine: rkmk4 on 1 and 1000 free
  bodies), is less accurate at the same step (heavy top, rkmk4: 4× on
  SO(3)×R³), and is valid only for rotations per step below a half-turn. So
  "auto" picks it nowhere; it stays available by name.

Rotation-only bodies (spherical joints) have no group to choose.
"""
from dataclasses import dataclass

import numpy as np

from .integrators import registry as _methods
from .integrators.local import per_body
from .errors import InputError
from .lgt import CHARTS, GROUPS, check_chart, check_group

#: a Jacobian entry counts as nonzero above this fraction of the body's largest entry
_COUPLING_TOL = 1e-10


@dataclass
class Choice:
    """Resolved per-body groups and charts, and why."""

    groups: list
    charts: list
    reasons: list
    names: list

    def table(self):
        rows = ["| body | group | chart | why |", "|---|---|---|---|"]
        rows += [f"| {n} | {g} | {c} | {r} |" for n, g, c, r in zip(self.names, self.groups, self.charts,
                                                                     self.reasons)]
        return "\n".join(rows)

    def as_dicts(self):
        return [dict(body=n, group=g, chart=c, reason=r)
                for n, g, c, r in zip(self.names, self.groups, self.charts, self.reasons)]


def option(kind, value):
    """``value`` when it names a group (``kind`` "group") or chart, or is "auto"; else
    InputError listing every choice, "auto" with them."""
    if value == "auto":
        return value
    try:
        return check_group(value) if kind == "group" else check_chart(value)
    except InputError:
        names = GROUPS if kind == "group" else CHARTS
        raise InputError(f"unknown {kind} {value!r}; use one of {[*names, 'auto']} (one value, "
                         "or one per body).") from None


def wants_auto(group, chart):
    """True when an entry of ``group`` or ``chart`` (one value or one per body) is "auto";
    InputError on an entry that is no group (chart) and not "auto"."""
    if type(group) is str and type(chart) is str and group in GROUPS and chart in CHARTS:
        return False                     # (the common call, without building lists)

    def has(kind, o):
        values = [o] if isinstance(o, str) else list(o)
        return any([option(kind, v) == "auto" for v in values])
    return has("group", group) | has("chart", chart)


def offset_joints(model, q=None):
    """Per body: True where a constraint row couples the body's translation and
    rotation velocities (a joint point away from the body frame origin)."""
    lay = model.layout
    out = [False] * lay.nbodies
    if not model.n_constraints:
        return out
    A = np.asarray(model.constraint_jacobian(model.q0 if q is None else q), float)
    for i, b in enumerate(lay.bodies):
        if b.rotation_only:
            continue
        Aw, Av = A[:, list(b.twist[:3])], A[:, list(b.twist[3:])]
        scale = max(np.abs(Aw).max(initial=0.0), np.abs(Av).max(initial=0.0))
        if scale == 0.0:
            continue
        tol = _COUPLING_TOL * scale
        out[i] = bool(np.any((np.abs(Aw).max(1) > tol) & (np.abs(Av).max(1) > tol)))
    return out


def choose(model, group="auto", chart="auto", *, method="rkmk4", project=True):
    """Resolve "auto" entries of ``group``/``chart`` (one value or one per body)."""
    lay = model.layout
    nb = lay.nbodies
    groups = per_body(group, nb, "group", lambda g: option("group", g))
    charts = per_body(chart, nb, "chart", lambda c: option("chart", c))
    index3 = _methods.get(method).constraints == "index3"      # the method solves them itself
    enforced = index3 or (project and model.n_constraints > 0)
    offsets = offset_joints(model) if "auto" in groups else [False] * nb
    names, reasons = [], []
    for i, b in enumerate(lay.bodies):
        names.append(b.name or f"body{i}")
        why = []
        if groups[i] == "auto":
            if b.rotation_only:
                groups[i] = "SO3xR3"
                why.append("rotation only (spherical joint): SO(3)")
            elif offsets[i] and not enforced:
                groups[i] = "SE3"
                why.append("SE(3): joint away from the body frame and not enforced by the method "
                           "(SE(3) keeps the joint point on the body's screw)")
            elif offsets[i]:
                groups[i] = "SO3xR3"
                why.append("SO(3)×R³: joint away from the body frame, enforced by "
                           + ("the index-3 solve" if index3 else "projection"))
            else:
                groups[i] = "SO3xR3"
                why.append("SO(3)×R³: no joint acts at an offset on this body")
        if charts[i] == "auto":
            charts[i] = "exp"
            why.append("exp (Cayley saves no time here and is less accurate per step)")
        reasons.append("; ".join(why) if why else "as given")
    return Choice(groups, charts, reasons, names)
