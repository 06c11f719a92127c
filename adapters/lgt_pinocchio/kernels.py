"""Compiled velocity / acceleration conversions of :class:`lgt_pinocchio.PinocchioModel`
(numba; imported only by a model built with the compiled backend).

Each free-flyer root has Pinocchio's q = (x y z, qx qy qz qw) and v = (v_lin body, ω body);
the bridge's twist is V = (ω body, ṙ inertial) with ṙ = R v_lin. Each planar joint has
q = (x, y, cos θ, sin θ) and v = (v_xy in the joint frame, ω); the bridge's V = (ṗ in the
parent frame, ω) with ṗ = R(θ) v_xy. Each spherical-ZYX joint has q = (θ0, θ1, θ2) and
v = θ̇; the bridge's V = ω (child frame) = G(θ) θ̇ (``params.RZYX.G``). Every other velocity
entry (spherical joints: ω as is; continuous and vector-space joints) is the same in both.

The packing follows the core's (:mod:`lgt_bridge.kernels.stage`): indices in an int64 table,
data in a float64 work array. The joint table ``jt`` (:func:`joint_table`) has one row per
joint whose v and V differ, columns ``KIND`` (``ROOT``, ``PLANAR``, ``ZYX``), ``IQ`` and
``IV`` (where the joint starts in q and in v). The work array ``W`` (:func:`work_array`)
holds Pinocchio's v at ``W[:nv]`` (the view handed to Pinocchio), then ``NCACHE`` floats per
table row, row r's at ``nv + NCACHE r``: a root's scalar-first quaternion, a planar joint's
(cos θ, sin θ), a ZYX joint's (sin θ1, cos θ1, sin θ2, cos θ2), so that the second call needs
neither q nor v as arguments.

* :func:`v_from_twist` (q, V, jt, W): Pinocchio's v into W's v block, the rotations after it;
* :func:`vdot_from_a` (jt, W, a): ABA's a, in place, into V̇ = (a_ang, R (a_lin + ω × v_lin))
  on roots, (R (a_xy + ω J v_xy), a_ω) on planar joints (J v = (-v_y, v_x)) and
  ω̇ = G a + Ġ θ̇ on ZYX joints.

The numpy reference is :class:`lgt_pinocchio.joints.Joints` (``v_from_twist``,
``vdot_from_a``); tests hold them equal (1e-13). Plain loops: ``NUMBA_DISABLE_JIT=1`` runs the
same source interpreted.
"""
import math

import numpy as np
from numba import njit

from lgt_bridge.kernels import entry_point, guard_cache
from lgt_bridge.kernels.rotations import cross, rotate, to_quat

guard_cache(__file__)

XYZW = 1          # rotations.to_quat code of Pinocchio's quaternion order

# columns of the joint table, and the joint kinds of its KIND column
KIND, IQ, IV = 0, 1, 2
NCOL = 3
ROOT, PLANAR, ZYX = 0, 1, 2
# floats of the work array per table row (after Pinocchio's v, nv floats at W[0])
NCACHE = 4


def joint_table(roots=(), planars=(), zyx=()):
    """The int64 joint table of the roots, planar and spherical-ZYX joints [(iq, iv), ...]."""
    rows = ([(ROOT, iq, iv) for iq, iv in roots] + [(PLANAR, iq, iv) for iq, iv in planars]
            + [(ZYX, iq, iv) for iq, iv in zyx])
    return np.array(rows, np.int64).reshape(-1, NCOL)


def work_array(jt, nv):
    """The float64 work array of a joint table and nv velocities, and the slice of its v block."""
    return np.zeros(nv + NCACHE * jt.shape[0]), slice(0, nv)


_VEC = "float64[::1]"
_TAB = "int64[:, ::1]"


# explicit signatures: other argument types raise TypeError instead of compiling a new
# specialization, so the caller converts only then (no per-call type checks in Python)
@njit(f"void({_VEC}, {_VEC}, {_TAB}, {_VEC})", cache=True, error_model="numpy")
def v_from_twist(q, V, jt, W):
    nv = V.shape[0]
    if nv + NCACHE * jt.shape[0] != W.shape[0]:
        raise ValueError("V has the wrong size for this model (expected nv entries)")
    for k in range(nv):
        W[k] = V[k]
    for r in range(jt.shape[0]):
        kind, iq, iv, o = jt[r, KIND], jt[r, IQ], jt[r, IV], nv + NCACHE * r
        if kind == ROOT:
            p0, p1, p2, p3 = to_quat(XYZW, q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6])
            W[o], W[o + 1], W[o + 2], W[o + 3] = p0, p1, p2, p3
            # v_lin = Rᵀ ṙ (rotation by the conjugate), ω unchanged
            x0, x1, x2 = rotate(p0, -p1, -p2, -p3, V[iv + 3], V[iv + 4], V[iv + 5])
            W[iv], W[iv + 1], W[iv + 2] = x0, x1, x2
            W[iv + 3], W[iv + 4], W[iv + 5] = V[iv], V[iv + 1], V[iv + 2]
        elif kind == PLANAR:                        # v_xy = R(θ)ᵀ ṗ
            c, s = q[iq + 2], q[iq + 3]
            W[o], W[o + 1] = c, s
            W[iv], W[iv + 1] = c * V[iv] + s * V[iv + 1], c * V[iv + 1] - s * V[iv]
        else:                                       # ZYX: θ̇ = G(θ)⁻¹ ω
            s1, c1 = math.sin(q[iq + 1]), math.cos(q[iq + 1])
            s2, c2 = math.sin(q[iq + 2]), math.cos(q[iq + 2])
            W[o], W[o + 1], W[o + 2], W[o + 3] = s1, c1, s2, c2
            ad = (s2 * V[iv + 1] + c2 * V[iv + 2]) / c1
            W[iv], W[iv + 1], W[iv + 2] = ad, c2 * V[iv + 1] - s2 * V[iv + 2], V[iv] + s1 * ad


@njit(f"void({_TAB}, {_VEC}, {_VEC})", cache=True, error_model="numpy")
def vdot_from_a(jt, W, a):
    nv = a.shape[0]
    for r in range(jt.shape[0]):
        kind, iv, o = jt[r, KIND], jt[r, IV], nv + NCACHE * r
        if kind == ROOT:
            p0, p1, p2, p3 = W[o], W[o + 1], W[o + 2], W[o + 3]
            c0, c1, c2 = cross(W[iv + 3], W[iv + 4], W[iv + 5], W[iv], W[iv + 1], W[iv + 2])
            x0, x1, x2 = rotate(p0, p1, p2, p3, a[iv] + c0, a[iv + 1] + c1, a[iv + 2] + c2)
            a[iv], a[iv + 1], a[iv + 2] = a[iv + 3], a[iv + 4], a[iv + 5]
            a[iv + 3], a[iv + 4], a[iv + 5] = x0, x1, x2
        elif kind == PLANAR:                        # p̈ = R (a_xy + ω J v_xy)
            c, s, w = W[o], W[o + 1], W[iv + 2]
            x, y = a[iv] - w * W[iv + 1], a[iv + 1] + w * W[iv]
            a[iv], a[iv + 1] = c * x - s * y, s * x + c * y
        else:                                       # ZYX: ω̇ = G a + Ġ θ̇
            s1, c1, s2, c2 = W[o], W[o + 1], W[o + 2], W[o + 3]
            ad, bd, cd = W[iv], W[iv + 1], W[iv + 2]
            aa, ab, ac = a[iv], a[iv + 1], a[iv + 2]
            a[iv] = ac - s1 * aa - c1 * bd * ad
            a[iv + 1] = s2 * c1 * aa + c2 * ab + (c2 * c1 * cd - s2 * s1 * bd) * ad - s2 * cd * bd
            a[iv + 2] = c2 * c1 * aa - s2 * ab + (-s2 * c1 * cd - c2 * s1 * bd) * ad - c2 * cd * bd


#: vdot_from_a for the model's own arrays (jt, W, and the float64 vector Pinocchio returns)
vdot_from_a_unchecked = entry_point(vdot_from_a)
