"""Scalar coefficient functions of the rotation angle phi, robust at phi -> 0.

The closed forms of exp/dexp/dexp_inv on SO(3) and SE(3) divide small
differences by powers of phi. Below ``SERIES_MAX`` the functions are evaluated
from their Taylor series in phi**2 instead, truncated adaptively to the
largest angle in the batch (the first omitted term below 2e-17 relative); the series
are accurate to double precision there and the closed forms lose at most a few
ulps above it. In an integration step phi is small and only a handful of terms
are evaluated. tests/core/test_series.py checks every function against mpmath.

    sinc(phi) = sin(phi) / phi,               beta(phi) = sinc(phi/2)**2
    c3(phi) = (1 - sinc phi) / phi**2          = (phi - sin phi) / phi**3
    d(phi)  = (1 - gamma) / phi**2,            gamma = (phi/2) cot(phi/2)
    e(phi)  = (1/beta + gamma - 2) / phi**4,   beta  = sinc(phi/2)**2
    hcos(phi) = (1 - cos(phi/2)) / phi**2      (the exp chart's quaternion: p0 - 1 = -phi² hcos)
"""
from math import factorial

import numpy as np

SERIES_MAX = 2.0

# Taylor coefficients in phi**2 (k = 0, 1, ...).
# c3: (-1)^k / (2k+3)!
_C3 = np.array([(-1) ** k / factorial(2 * k + 3) for k in range(14)])
# sinc: (-1)^k / (2k+1)!;  beta = sinc(phi/2)^2 = 2 (1 - cos phi)/phi^2: 2 (-1)^k / (2k+2)!
_SINC = np.array([(-1) ** k / factorial(2 * k + 1) for k in range(14)])
_BETA = np.array([2.0 * (-1) ** k / factorial(2 * k + 2) for k in range(14)])
# hcos: (-1)^k / (4^(k+1) (2k+2)!)
_HCOS = np.array([(-1) ** k / (4.0 ** (k + 1) * factorial(2 * k + 2)) for k in range(14)])
# d: |B_{2k+2}| / (2k+2)!  (Bernoulli numbers; from (x/2) cot(x/2) = 1 - sum |B_2n| x^2n/(2n)!)
_D = np.array([
    0.08333333333333333, 0.001388888888888889, 3.306878306878307e-05, 8.267195767195768e-07,
    2.08767569878681e-08, 5.284190138687493e-10, 1.3382536530684679e-11, 3.3896802963225827e-13,
    8.586062056277845e-15, 2.174868698558062e-16, 5.5090028283602295e-18, 1.3954464685812522e-19,
    3.534707039629467e-21, 8.953517427037546e-23, 2.267952452337683e-24, 5.744790668872202e-26,
    1.455172475614865e-27, 3.6859949406653103e-29, 9.336734257095045e-31, 2.36502241570063e-32])
# e: series of (u^2 csc^2 u + u cot u - 2) / phi^4 with u = phi/2 (computed with sympy)
_E = np.array([
    0.002777777777777778, 0.00013227513227513228, 4.96031746031746e-06, 1.670140559029448e-07,
    5.2841901386874934e-09, 1.6059043836821613e-10, 4.745552414851616e-12, 1.3737699290044552e-13,
    3.914763657404511e-15, 1.1018005656720459e-16, 3.069982230878755e-18, 8.483296895110721e-20,
    2.327914531029762e-21, 6.350266866545513e-23, 1.7234372006616606e-24, 4.656551921967568e-26,
    1.2532382798262054e-27, 3.3612243325542163e-29, 8.987085179662393e-31, 2.3962687049928537e-32])


def _limits(coef):
    """lim[K-1]: largest phi**2 at which K terms suffice (first omitted term <= 2e-17 c0)."""
    lim = [abs(2e-17 * coef[0] / coef[K]) ** (1.0 / K) for K in range(1, len(coef))]
    return np.maximum.accumulate(lim).tolist() + [np.inf]


def _horner(coef, lim, phi2):
    p2max = float(phi2.max())
    n = 1
    while p2max > lim[n - 1]:
        n += 1
    out = coef[n - 1] * phi2 + coef[n - 2] if n > 1 else coef[0] + 0.0 * phi2
    for c in coef[n - 3::-1] if n > 2 else ():
        out = out * phi2 + c
    return out


def _scalar(x, coef, lim, closed):
    """One body: the same evaluation on a Python float (numpy's per-call overhead
    would dominate a single element)."""
    if x >= SERIES_MAX:
        return closed(np.array([x]))
    p2 = x * x
    n = 1
    while p2 > lim[n - 1]:
        n += 1
    out = 0.0
    for c in coef[n - 1::-1]:
        out = out * p2 + c
    return np.array([out])


def _blend(phi, coef, lim, closed):
    """Series below SERIES_MAX, closed form above; each only where needed."""
    if phi.shape == (1,):
        return _scalar(float(phi[0]), coef, lim, closed)
    pmax = float(phi.max()) if phi.size else 0.0
    if pmax < SERIES_MAX:
        return _horner(coef, lim, phi * phi)
    small = phi < SERIES_MAX
    if not small.any():
        return closed(phi)
    out = np.empty_like(phi)
    out[small] = _horner(coef, lim, phi[small] ** 2)
    out[~small] = closed(phi[~small])
    return out


_L_C3, _L_D, _L_E, _L_SINC, _L_BETA, _L_HCOS = map(_limits, (_C3, _D, _E, _SINC, _BETA, _HCOS))
_C3, _D, _E, _SINC, _BETA, _HCOS = (c.tolist() for c in (_C3, _D, _E, _SINC, _BETA, _HCOS))


def sinc(phi):
    """sin(phi)/phi."""
    return _blend(phi, _SINC, _L_SINC, lambda p: np.sin(p) / p)


def beta(phi):
    """sinc(phi/2)**2, so that (1 - cos phi)/phi**2 = beta/2."""
    def closed(p):
        s = np.sin(0.5 * p) / (0.5 * p)
        return s * s
    return _blend(phi, _BETA, _L_BETA, closed)


def c3(phi):
    return _blend(phi, _C3, _L_C3, lambda p: (p - np.sin(p)) / p ** 3)


def d(phi):
    def closed(p):
        h = 0.5 * p
        return (1.0 - h * np.cos(h) / np.sin(h)) / (p * p)
    return _blend(phi, _D, _L_D, closed)


def e(phi):
    def closed(p):
        h = 0.5 * p
        s, c = np.sin(h), np.cos(h)
        return ((h / s) ** 2 + h * c / s - 2.0) / p ** 4
    return _blend(phi, _E, _L_E, closed)


def hcos(phi):
    """(1 - cos(phi/2)) / phi**2 = 2 sin²(phi/4) / phi**2."""
    return _blend(phi, _HCOS, _L_HCOS, lambda p: 2.0 * (np.sin(0.25 * p) / p) ** 2)
