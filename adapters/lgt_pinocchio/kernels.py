"""Compiled velocity / acceleration conversions of :class:`lgt_pinocchio.PinocchioModel`
(numba; imported only by a model built with the compiled backend).

Each free-flyer root has Pinocchio's q = (x y z, qx qy qz qw) and v = (v_lin body, ω body);
the bridge's twist is V = (ω body, ṙ inertial) with ṙ = R v_lin. Each planar joint has
q = (x, y, cos θ, sin θ) and v = (v_xy in the joint frame, ω); the bridge's V = (ṗ in the
parent frame, ω) with ṗ = R(θ) v_xy. Each spherical-ZYX joint has q = (θ0, θ1, θ2) and
v = θ̇; the bridge's V = ω (child frame) = G(θ) θ̇ (``params.RZYX.G``). Every other velocity
entry (spherical joints: ω as is; continuous and vector-space joints) is the same in both.

A model's roots, planar joints and work buffers are packed once (:func:`pack`) into one
float64 array ``W``, so that each kernel call takes few arguments (numba's dispatch costs
≈ 0.1 µs per argument): ``W[0]`` = n (the number of roots), ``W[1]`` = m (planar joints), ``W[2]`` = k
(spherical-ZYX joints), ``W[3 + 2 r]``, ``W[4 + 2 r]`` = root r's index into q and into v, then
the same pair for each planar and each ZYX joint (integers held exactly as floats), then
Pinocchio's v (``nv`` entries, the view handed to Pinocchio), then each root's scalar-first
quaternion (4 each), each planar joint's (cos θ, sin θ) and each ZYX joint's (sin θ1, cos θ1,
sin θ2, cos θ2), so that the second call needs neither q nor v as arguments.

* :func:`v_from_twist` (q, V, W): Pinocchio's v into W's v block, the rotations after it;
* :func:`vdot_from_a` (W, a): ABA's a, in place, into V̇ = (a_ang, R (a_lin + ω × v_lin)) on
  roots, (R (a_xy + ω J v_xy), a_ω) on planar joints (J v = (-v_y, v_x)) and ω̇ = G a + Ġ θ̇ on
  ZYX joints.

The numpy reference is ``PinocchioModel._v_from_twist_numpy`` / ``_f_numpy``; tests hold them
equal (1e-13). Plain loops: ``NUMBA_DISABLE_JIT=1`` runs the same source interpreted.
"""
import math

import numpy as np
from numba import njit

from lgt_bridge.kernels.rotations import cross, rotate, to_quat
from lgt_bridge.kernels import guard_cache

guard_cache(__file__)

XYZW = 1          # rotations.to_quat code of Pinocchio's quaternion order


def pack(roots, nv, planars=(), zyx=()):
    """The work array ``W`` of the roots, planar and spherical-ZYX joints [(iq, iv), ...] of
    a model with nv velocities, and the slice of its v block."""
    n, m, k = len(roots), len(planars), len(zyx)
    h = 3 + 2 * (n + m + k)
    W = np.zeros(h + nv + 4 * n + 2 * m + 4 * k)
    W[0], W[1], W[2] = n, m, k
    for j, (iq, iv) in enumerate(list(roots) + list(planars) + list(zyx)):
        W[3 + 2 * j], W[4 + 2 * j] = iq, iv
    return W, slice(h, h + nv)


_VEC = "float64[::1]"


# explicit signatures: other argument types raise TypeError instead of compiling a new
# specialization, so the caller converts only then (no per-call type checks in Python)
@njit(f"void({_VEC}, {_VEC}, {_VEC})", cache=True, error_model="numpy")
def v_from_twist(q, V, W):
    n, m, nz, nv = int(W[0]), int(W[1]), int(W[2]), V.shape[0]
    h = 3 + 2 * (n + m + nz)
    if h + nv + 4 * n + 2 * m + 4 * nz != W.shape[0]:
        raise ValueError("V has the wrong size for this model (expected nv entries)")
    for k in range(nv):
        W[h + k] = V[k]
    for r in range(nz):                             # ZYX: θ̇ = G(θ)⁻¹ ω
        iq, iv = int(W[3 + 2 * (n + m + r)]), int(W[4 + 2 * (n + m + r)])
        s1, c1, s2, c2 = math.sin(q[iq + 1]), math.cos(q[iq + 1]), math.sin(q[iq + 2]), math.cos(q[iq + 2])
        o, j = h + nv + 4 * n + 2 * m + 4 * r, h + iv
        W[o], W[o + 1], W[o + 2], W[o + 3] = s1, c1, s2, c2
        ad = (s2 * V[iv + 1] + c2 * V[iv + 2]) / c1
        W[j], W[j + 1], W[j + 2] = ad, c2 * V[iv + 1] - s2 * V[iv + 2], V[iv] + s1 * ad
    for r in range(m):                              # planar: v_xy = R(θ)ᵀ ṗ
        iq, iv = int(W[3 + 2 * (n + r)]), int(W[4 + 2 * (n + r)])
        c, s = q[iq + 2], q[iq + 3]
        o, j = h + nv + 4 * n + 2 * r, h + iv
        W[o], W[o + 1] = c, s
        W[j], W[j + 1] = c * V[iv] + s * V[iv + 1], c * V[iv + 1] - s * V[iv]
    for r in range(n):
        iq, iv = int(W[3 + 2 * r]), int(W[4 + 2 * r])
        p0, p1, p2, p3 = to_quat(XYZW, q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6])
        o, j = h + nv + 4 * r, h + iv
        W[o], W[o + 1], W[o + 2], W[o + 3] = p0, p1, p2, p3
        # v_lin = Rᵀ ṙ (rotation by the conjugate), ω unchanged
        x0, x1, x2 = rotate(p0, -p1, -p2, -p3, V[iv + 3], V[iv + 4], V[iv + 5])
        W[j], W[j + 1], W[j + 2] = x0, x1, x2
        W[j + 3], W[j + 4], W[j + 5] = V[iv], V[iv + 1], V[iv + 2]


@njit(f"void({_VEC}, {_VEC})", cache=True, error_model="numpy")
def vdot_from_a(W, a):
    n, m, nz, nv = int(W[0]), int(W[1]), int(W[2]), a.shape[0]
    h = 3 + 2 * (n + m + nz)
    for r in range(nz):                             # ZYX: ω̇ = G a + Ġ θ̇
        iv = int(W[4 + 2 * (n + m + r)])
        o, j = h + nv + 4 * n + 2 * m + 4 * r, h + iv
        s1, c1, s2, c2 = W[o], W[o + 1], W[o + 2], W[o + 3]
        ad, bd, cd = W[j], W[j + 1], W[j + 2]
        aa, ab, ac = a[iv], a[iv + 1], a[iv + 2]
        a[iv] = ac - s1 * aa - c1 * bd * ad
        a[iv + 1] = s2 * c1 * aa + c2 * ab + (c2 * c1 * cd - s2 * s1 * bd) * ad - s2 * cd * bd
        a[iv + 2] = c2 * c1 * aa - s2 * ab + (-s2 * c1 * cd - c2 * s1 * bd) * ad - c2 * cd * bd
    for r in range(m):                              # planar: p̈ = R (a_xy + ω J v_xy)
        iv = int(W[4 + 2 * (n + r)])
        o, j = h + nv + 4 * n + 2 * r, h + iv
        c, s, w = W[o], W[o + 1], W[j + 2]
        x, y = a[iv] - w * W[j + 1], a[iv + 1] + w * W[j]
        a[iv], a[iv + 1] = c * x - s * y, s * x + c * y
    for r in range(n):
        iv = int(W[4 + 2 * r])
        o, j = h + nv + 4 * r, h + iv
        p0, p1, p2, p3 = W[o], W[o + 1], W[o + 2], W[o + 3]
        c0, c1, c2 = cross(W[j + 3], W[j + 4], W[j + 5], W[j], W[j + 1], W[j + 2])
        x0, x1, x2 = rotate(p0, p1, p2, p3, a[iv] + c0, a[iv + 1] + c1, a[iv + 2] + c2)
        a[iv], a[iv + 1], a[iv + 2] = a[iv + 3], a[iv + 4], a[iv + 5]
        a[iv + 3], a[iv + 4], a[iv + 5] = x0, x1, x2


def _entry(kernel):
    """The compiled entry point of a kernel with one explicit signature: the call without
    numba's type dispatch (≈ 0.15 µs less). It does not check dtype or layout, so it is only
    for arguments whose types the caller guarantees. The dispatcher itself where numba
    keeps no such entry (NUMBA_DISABLE_JIT=1, other numba versions)."""
    try:
        (cres,) = kernel.overloads.values()
        entry = cres.entry_point
    except (AttributeError, ValueError):
        return kernel
    return entry if callable(entry) else kernel


#: vdot_from_a for the model's own arrays (W, and the float64 vector Pinocchio returns)
vdot_from_a_unchecked = _entry(vdot_from_a)
