"""Local-global transition maps τ and the local kinematics.

    τ(q_k, X) = α⁻¹(α(q_k) · ψ(X))

with α an absolute parameterization (params.py), ψ the exp or Cayley chart of
the group G = SE(3) or SO(3)xR³ and · the group law of G (docs/paper_corrections.md: the rule that
settles every case). τ is composed, not written per pairing: the rotation is a
quaternion product p = p_k ⊗ ψ_rot(x) (paper eq. Qprime in product form), the
translation follows the group law:

    SO(3)xR³:  r = r_k + y                         (increment in the inertial frame)
    SE(3):     r = r_k + R_k T(x) y,  T = dexp_x (exp) or I + cay(c) (Cayley)

Velocities: the model gives V = (ω body, ṙ inertial), which is the twist of
SO(3)xR³. On SE(3) the integrator uses the body twist (ω, Rᵀṙ); see
:func:`to_group_twist`. Local kinematics: Ẋ = dψ⁻¹_{-X}(V) (paper eq. dpsiinv).
"""
import numpy as np

from . import _checks, charts as _charts, params
from .errors import InputError
from .groups import quaternion as _q

GROUPS = ("SE3", "SO3xR3")
#: the group of ``simulate``, ``lgt-bridge run`` and ``demo`` when none is given: at equal cost it was as
#: accurate as SE3 or more on every scene measured (README, "Choosing a method")
DEFAULT_GROUP = "SO3xR3"
CHARTS = _charts.NAMES


def check_group(group):
    if group not in GROUPS:
        raise InputError(f"unknown group {group!r}; use one of {list(GROUPS)}.")
    return group


check_chart = _charts.check_chart


class LGT:
    """τ and the local kinematics for one (parameterization, group, chart).

    The methods work on validated (N, ν) / (N, 6) batches; use :func:`tau` and
    :func:`local_rates` for checked single-body or batched calls.
    """

    def __init__(self, param, group="SE3", chart="exp"):
        self.param = params.get(param)
        self.group = check_group(group)
        self.chart_ = _charts.get(chart)
        self.chart = self.chart_.name
        maps = self.chart_.on(self.group)
        self._dpsi_inv, self._dpsi = maps.dpsi_inv_apply, maps.dpsi_apply

    def __repr__(self):
        return f"LGT({self.param.name!r}, {self.group!r}, {self.chart!r})"

    def base(self, q):
        """What τ(q_k, ·) needs of q_k, computed once per step: (r_k, θ_k, p_k)."""
        return q[:, :3], q[:, 3:], self.param._to_quat(q[:, 3:])

    def tau(self, q, X):
        return self.tau_at(self.base(q), X)

    def tau_at(self, base, X):
        """τ(q_k, X) for a prepared ``base(q_k)`` (the stages of one step share it)."""
        return self.tau_pose(base, X)[0]

    def tau_pose(self, base, X):
        """(τ(q_k, X), p): the coordinates and the unit quaternion (scalar first) of the pose."""
        r, rot, pk = base
        x, y = X[:, :3], X[:, 3:]
        if self.group == "SO3xR3":
            d, _ = self.chart_.increment(x)
            r1 = r + y
        else:
            d, t = self.chart_.increment(x, y)
            r1 = r + _q._rotate(pk, t)
        p = _q._mul_near_identity(pk, d)
        return np.concatenate([r1, self.param._from_quat(p, rot)], axis=1), p

    def rates(self, X, V):
        """Ẋ = dψ⁻¹_{-X}(V), V in the group's velocity representation."""
        return self._dpsi_inv(-X, V)

    def twist(self, X, Xdot):
        """V = dψ_{-X}(Ẋ) (paper eq. dpsi), the inverse of :meth:`rates`."""
        return self._dpsi(-X, Xdot)


class RotationLGT:
    """τ and the local kinematics of a rotation-only body (a spherical joint): the
    rotation part of :class:`LGT`, with the increment x in the chart of SO(3)."""

    def __init__(self, param, chart="exp"):
        self.param = params.get(param)
        self.chart_ = _charts.get(chart)
        self.chart = self.chart_.name
        maps = self.chart_.on("SO3")
        self._dinv, self._d = maps.dpsi_inv_apply, maps.dpsi_apply

    def base(self, rot):
        return None, rot, self.param._to_quat(rot)

    def tau_pose(self, base, x):
        _, rot, pk = base
        d, _ = self.chart_.increment(x)
        p = _q._mul_near_identity(pk, d)
        return self.param._from_quat(p, rot), p

    def rates(self, x, w):
        return self._dinv(-x, w)

    def twist(self, x, xdot):
        return self._d(-x, xdot)


def _prepare(q, X, param, group, chart):
    lgt = LGT(param, group, chart)
    qb, sq = lgt.param.validate(q, "q")
    Xb, sx = _checks.batch(X, (6,), "X")
    if len(qb) != len(Xb) and 1 not in (len(qb), len(Xb)):
        raise InputError(f"q has {len(qb)} bodies but X has {len(Xb)}; pass one X per body.")
    n = max(len(qb), len(Xb))
    return lgt, np.broadcast_to(qb, (n, qb.shape[1])), np.broadcast_to(Xb, (n, 6)), sq and sx


def tau(q, X, param="quat", group="SE3", chart="exp"):
    """Absolute coordinates after the local increment X: τ(q, X) = α⁻¹(α(q) ψ(X)).

    q: (ν,) or (N, ν) position-first absolute coordinates of ``param``;
    X: (6,) or (N, 6) local coordinates (rotation part first).
    """
    lgt, qb, Xb, single = _prepare(q, X, param, group, chart)
    return _checks.unbatch(lgt.tau(qb, Xb), single)


def local_rates(X, V, group="SE3", chart="exp"):
    """Ẋ = dψ⁻¹_{-X}(V) with V in the group's twist: (ω, Rᵀṙ) on SE(3), (ω, ṙ) on SO(3)xR³."""
    lgt = LGT("quat", group, chart)
    Xb, sx = _checks.batch(X, (6,), "X")
    Vb, sv = _checks.batch(V, (6,), "V")
    if len(Xb) != len(Vb):
        raise InputError(f"X has {len(Xb)} bodies but V has {len(Vb)}; pass one twist per body.")
    return _checks.unbatch(lgt.rates(Xb, Vb), sx and sv)


def _convert_twist(q, V, param, group, to_group):
    par = params.get(param)
    qb, sq = par.validate(q, "q")
    Vb, _ = _checks.batch(V, (6,), "V")
    if check_group(group) == "SO3xR3":
        return _checks.unbatch(Vb.copy(), sq)
    p = par._to_quat(qb[:, 3:])
    p = _q._conj(p) if to_group else p
    return _checks.unbatch(np.concatenate([Vb[:, :3], _q._rotate(p, Vb[:, 3:])], axis=1), sq)


def to_group_twist(q, V, param="quat", group="SE3"):
    """Model twist (ω, ṙ) -> the group's twist: (ω, Rᵀṙ) on SE(3), unchanged on SO(3)xR³."""
    return _convert_twist(q, V, param, group, to_group=True)


def from_group_twist(q, V, param="quat", group="SE3"):
    """The group's twist -> model twist (ω, ṙ): ṙ = R u on SE(3)."""
    return _convert_twist(q, V, param, group, to_group=False)


def circle_tau(cs, x):
    """(c, s) · exp(i x) for rows (c, s) = (cos θ, sin θ): the unit complex number of θ + x.
    Written as cs + (cs (cos x - 1) + i cs sin x) with cos x - 1 = -2 sin²(x/2), so the
    norm does not drift step after step (the quaternions' rule in :mod:`lgt_bridge.lgt`)."""
    cs = np.asarray(cs, float)
    x = np.asarray(x, float)
    cm1, sn = -2.0 * np.sin(0.5 * x) ** 2, np.sin(x)
    c, s = cs[..., 0], cs[..., 1]
    return np.stack([c + (c * cm1 - s * sn), s + (s * cm1 + c * sn)], axis=-1)
