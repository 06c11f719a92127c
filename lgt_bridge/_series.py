"""Scalar coefficient functions of the rotation angle phi, robust at phi -> 0.

The closed forms of exp/dexp/dexp_inv on SO(3) and SE(3) divide small
differences by powers of phi. Below ``SERIES_MAX`` the functions are evaluated
from their Taylor series in phi**2 instead, truncated adaptively to the
largest angle in the batch (each kept term above 1e-18 relative); the series
are accurate to double precision there and the closed forms lose at most a few
ulps above it. tests/test_series.py checks every function against mpmath.

    c3(phi) = (1 - sinc phi) / phi**2          = (phi - sin phi) / phi**3
    d(phi)  = (1 - gamma) / phi**2,            gamma = (phi/2) cot(phi/2)
    e(phi)  = (1/beta + gamma - 2) / phi**4,   beta  = sinc(phi/2)**2
"""
from math import factorial

import numpy as np

SERIES_MAX = 2.0

# Taylor coefficients in phi**2 (k = 0, 1, ...).
# c3: (-1)^k / (2k+3)!
_C3 = np.array([(-1) ** k / factorial(2 * k + 3) for k in range(14)])
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


def _nterms(coef, phi2max):
    """Number of leading terms whose contribution exceeds 1e-18 relative."""
    if phi2max <= 0.0:
        return 1
    k = np.abs(coef) * phi2max ** np.arange(len(coef))
    keep = np.flatnonzero(k > 1e-18 * abs(coef[0]))
    return int(keep[-1]) + 2 if len(keep) else 1


def _horner(coef, phi2):
    n = min(_nterms(coef, float(phi2.max())), len(coef))
    out = np.full_like(phi2, coef[n - 1])
    for c in coef[n - 2::-1]:
        out *= phi2
        out += c
    return out


def _blend(phi, series, closed):
    """Series below SERIES_MAX, closed form above; each only where needed."""
    small = phi < SERIES_MAX
    if small.all():
        return series(phi * phi)
    if not small.any():
        return closed(phi)
    out = np.empty_like(phi)
    out[small] = series(phi[small] ** 2)
    out[~small] = closed(phi[~small])
    return out


def sinc(phi):
    """sin(phi)/phi (no cancellation; exact limit 1 at 0)."""
    return np.sinc(phi / np.pi)


def beta(phi):
    """sinc(phi/2)**2, so that (1 - cos phi)/phi**2 = beta/2."""
    s = np.sinc(phi / (2.0 * np.pi))
    return s * s


def c3(phi):
    return _blend(phi, lambda p2: _horner(_C3, p2),
                  lambda p: (p - np.sin(p)) / p ** 3)


def d(phi):
    def closed(p):
        h = 0.5 * p
        return (1.0 - h * np.cos(h) / np.sin(h)) / (p * p)
    return _blend(phi, lambda p2: _horner(_D, p2), closed)


def e(phi):
    def closed(p):
        h = 0.5 * p
        s, c = np.sin(h), np.cos(h)
        return ((h / s) ** 2 + h * c / s - 2.0) / p ** 4
    return _blend(phi, lambda p2: _horner(_E, p2), closed)
