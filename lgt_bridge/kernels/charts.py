"""The charts' branches of the kernels: one body's chart quantities on plain floats, by
chart code (``lgt_bridge.charts``: 0 exp, 1 cay, 2 cay2). The numpy references are the
charts' ``increment`` and ``GroupMaps.dpsi_inv_apply``; tests hold them equal.

    increment     quaternion of ψ_SO(3)(x) − 1 (and, for exp, φ = |x| and sinc(φ/2))
    translation   the translation of ψ_SE(3)(x, y): T(x) y
    rot_rates     dψ⁻¹_{−x}(w) of SO(3)
    se3_rates     the translation rows of dψ⁻¹_{−X}(W) of SE(3)
    usage         |x| / the chart's limit (> 1: the stage leaves the chart's domain)
"""
import math

from numba import njit

from ..charts import INV_LIMITS
from . import guard_cache
from .rotations import c3, cross, dser, eser, gibbs_minus_one, rotate, rotvec_minus_one

guard_cache(__file__)

EXP, CAY, CAY2 = 0, 1, 2


@njit(cache=True, error_model="numpy", inline="always")
def increment(code, x0, x1, x2):
    """(d0, d1, d2, d3, φ, sinc(φ/2)); φ and sinc only for exp (else 0, 1)."""
    if code == EXP:
        return rotvec_minus_one(x0, x1, x2)
    if code == CAY:
        d0, d1, d2, d3 = gibbs_minus_one(x0, x1, x2)
        return d0, d1, d2, d3, 0.0, 1.0
    s = x0 * x0 + x1 * x1 + x2 * x2
    k = 1.0 / (4.0 + s)
    return -2.0 * s * k, 4.0 * k * x0, 4.0 * k * x1, 4.0 * k * x2, 0.0, 1.0


@njit(cache=True, error_model="numpy", inline="always")
def usage(code, x0, x1, x2):
    if code == EXP:
        return 0.0
    return math.sqrt(x0 * x0 + x1 * x1 + x2 * x2) * INV_LIMITS[code]


@njit(cache=True, error_model="numpy", inline="always")
def _half_rotate(sign, x0, x1, x2, s, v0, v1, v2):
    """cay(±x/2) v = v + (±4 x × v + 2 x × (x × v))/(4 + s)."""
    a0, a1, a2 = cross(x0, x1, x2, v0, v1, v2)
    b0, b1, b2 = cross(x0, x1, x2, a0, a1, a2)
    k = 1.0 / (4.0 + s)
    return (v0 + k * (sign * 4.0 * a0 + 2.0 * b0), v1 + k * (sign * 4.0 * a1 + 2.0 * b1),
            v2 + k * (sign * 4.0 * a2 + 2.0 * b2))


@njit(cache=True, error_model="numpy", inline="always")
def translation(code, x0, x1, x2, y0, y1, y2, d0, d1, d2, d3, phi, sh):
    """T(x) y: dexp_x y (exp), (I + cay x) y (cay), ½ (I + cay(x/2))² y (cay2)."""
    if code == EXP:
        xy0, xy1, xy2 = cross(x0, x1, x2, y0, y1, y2)
        xx0, xx1, xx2 = cross(x0, x1, x2, xy0, xy1, xy2)
        f1, f2 = 0.5 * sh * sh, c3(phi)
        return y0 + f1 * xy0 + f2 * xx0, y1 + f1 * xy1 + f2 * xx1, y2 + f1 * xy2 + f2 * xx2
    if code == CAY:
        v0, v1, v2 = rotate(1.0 + d0, d1, d2, d3, y0, y1, y2)
        return y0 + v0, y1 + v1, y2 + v2
    s = x0 * x0 + x1 * x1 + x2 * x2
    h0, h1, h2 = _half_rotate(1.0, x0, x1, x2, s, y0, y1, y2)
    w0, w1, w2 = y0 + h0, y1 + h1, y2 + h2
    g0, g1, g2 = _half_rotate(1.0, x0, x1, x2, s, w0, w1, w2)
    return 0.5 * (w0 + g0), 0.5 * (w1 + g1), 0.5 * (w2 + g2)


@njit(cache=True, error_model="numpy", inline="always")
def rot_rates(code, x0, x1, x2, w0, w1, w2, phi):
    """dψ⁻¹_{−x}(w) on SO(3)."""
    xw0, xw1, xw2 = cross(x0, x1, x2, w0, w1, w2)
    if code == EXP:
        dd = dser(phi)
        xxw0, xxw1, xxw2 = cross(x0, x1, x2, xw0, xw1, xw2)
        return w0 + 0.5 * xw0 + dd * xxw0, w1 + 0.5 * xw1 + dd * xxw1, w2 + 0.5 * xw2 + dd * xxw2
    cw = x0 * w0 + x1 * w1 + x2 * w2
    if code == CAY:
        return 0.5 * (w0 + xw0 + cw * x0), 0.5 * (w1 + xw1 + cw * x1), 0.5 * (w2 + xw2 + cw * x2)
    # cay2: ((4 − s) w + 4 x × w + 2 (x·w) x)/8
    f = 0.125 * (4.0 - (x0 * x0 + x1 * x1 + x2 * x2))
    return (f * w0 + 0.5 * xw0 + 0.25 * cw * x0, f * w1 + 0.5 * xw1 + 0.25 * cw * x1,
            f * w2 + 0.5 * xw2 + 0.25 * cw * x2)


@njit(cache=True, error_model="numpy", inline="always")
def se3_rates(code, x0, x1, x2, y0, y1, y2, w0, w1, w2, u0, u1, u2, phi):
    """The translation rows of dψ⁻¹_{−X}(ω, u) on SE(3)."""
    yw0, yw1, yw2 = cross(y0, y1, y2, w0, w1, w2)
    if code == EXP:
        xw0, xw1, xw2 = cross(x0, x1, x2, w0, w1, w2)
        xxw0, xxw1, xxw2 = cross(x0, x1, x2, xw0, xw1, xw2)
        xu0, xu1, xu2 = cross(x0, x1, x2, u0, u1, u2)
        xxu0, xxu1, xxu2 = cross(x0, x1, x2, xu0, xu1, xu2)
        xyw0, xyw1, xyw2 = cross(x0, x1, x2, yw0, yw1, yw2)
        yxw0, yxw1, yxw2 = cross(y0, y1, y2, xw0, xw1, xw2)
        dd = dser(phi)
        ee = eser(phi) * (x0 * y0 + x1 * y1 + x2 * y2)
        return (u0 + 0.5 * (xu0 + yw0) + dd * (xxu0 + xyw0 + yxw0) + ee * xxw0,
                u1 + 0.5 * (xu1 + yw1) + dd * (xxu1 + xyw1 + yxw1) + ee * xxw1,
                u2 + 0.5 * (xu2 + yw2) + dd * (xxu2 + xyw2 + yxw2) + ee * xxw2)
    if code == CAY:
        z0, z1, z2 = u0 + yw0, u1 + yw1, u2 + yw2
        cz0, cz1, cz2 = cross(x0, x1, x2, z0, z1, z2)
        return 0.5 * (z0 + cz0), 0.5 * (z1 + cz1), 0.5 * (z2 + cz2)
    # cay2 at U = −X: 2 dcay⁻¹_{U/2} (I + Ad_{cay(U/2)})⁻¹ (ω, u) with a = −x/2, b = −y/2:
    # z_ω = ½ (ω + ½ x × ω), m = R₁ z_ω = ½ (ω − ½ x × ω), t₁ = (I + R₁) b,
    # z_v = ½ (I + ½ x̃)(u − t₁ × m), Ẋ_v = ¼ x × (y × z_ω) + ½ y × z_ω + z_v + ½ x × z_v
    s = x0 * x0 + x1 * x1 + x2 * x2
    xw0, xw1, xw2 = cross(x0, x1, x2, w0, w1, w2)
    zw0, zw1, zw2 = 0.5 * (w0 + 0.5 * xw0), 0.5 * (w1 + 0.5 * xw1), 0.5 * (w2 + 0.5 * xw2)
    m0, m1, m2 = 0.5 * (w0 - 0.5 * xw0), 0.5 * (w1 - 0.5 * xw1), 0.5 * (w2 - 0.5 * xw2)
    h0, h1, h2 = _half_rotate(-1.0, x0, x1, x2, s, -0.5 * y0, -0.5 * y1, -0.5 * y2)
    t0, t1, t2 = h0 - 0.5 * y0, h1 - 0.5 * y1, h2 - 0.5 * y2
    tm0, tm1, tm2 = cross(t0, t1, t2, m0, m1, m2)
    r0, r1, r2 = u0 - tm0, u1 - tm1, u2 - tm2
    xr0, xr1, xr2 = cross(x0, x1, x2, r0, r1, r2)
    zv0, zv1, zv2 = 0.5 * (r0 + 0.5 * xr0), 0.5 * (r1 + 0.5 * xr1), 0.5 * (r2 + 0.5 * xr2)
    yz0, yz1, yz2 = cross(y0, y1, y2, zw0, zw1, zw2)
    xyz0, xyz1, xyz2 = cross(x0, x1, x2, yz0, yz1, yz2)
    xz0, xz1, xz2 = cross(x0, x1, x2, zv0, zv1, zv2)
    return (0.25 * xyz0 + 0.5 * yz0 + zv0 + 0.5 * xz0, 0.25 * xyz1 + 0.5 * yz1 + zv1 + 0.5 * xz1,
            0.25 * xyz2 + 0.5 * yz2 + zv2 + 0.5 * xz2)
