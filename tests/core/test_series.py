"""Series/closed-form coefficient functions and small-angle maps against mpmath."""
import mpmath as mp
import numpy as np
import pytest

from lgt_bridge import _series
from lgt_bridge.groups import se3, so3

mp.mp.dps = 120  # e(φ) cancels ~φ⁴: at φ = 1e-12 that eats 48 digits


def _ref(name, phi):
    p = mp.mpf(phi)
    h = p / 2
    if name == "c3":
        return (p - mp.sin(p)) / p ** 3
    if name == "d":
        return (1 - h * mp.cot(h)) / p ** 2
    if name == "e":
        return ((h / mp.sin(h)) ** 2 + h * mp.cot(h) - 2) / p ** 4
    if name == "sinc":
        return mp.sin(p) / p
    if name == "beta":
        return (mp.sin(h) / h) ** 2
    if name == "hcos":
        return (1 - mp.cos(h)) / p ** 2


PHIS = [10.0 ** -k for k in range(3, 13)] + [0.05, 0.7, 1.3, 1.99, 2.0, 2.01, 3.0, np.pi, 4.5, 6.0]


@pytest.mark.parametrize("name", ["c3", "d", "e", "sinc", "beta", "hcos"])
def test_coefficient_against_mpmath(name):
    phi = np.array(PHIS)
    got = getattr(_series, name)(phi)
    for g, p in zip(got, PHIS):
        ref = _ref(name, p)
        assert abs(g - float(ref)) <= 1e-14 * abs(float(ref)), (name, p, g, ref)


def test_kernel_hcos_equals_the_series_function():
    """The compiled helper behind the exp chart's quaternion (p0 - 1 = -φ² hcos φ) against
    _series.hcos (itself against mpmath above), on both sides of SERIES_MAX."""
    from lgt_bridge.kernels import rotations as kr
    phi = np.array(PHIS + [0.0])
    ref = _series.hcos(phi)
    got = np.array([kr.hcos(p) for p in phi])
    np.testing.assert_allclose(got, ref, rtol=2e-16, atol=0)
    assert kr.hcos(0.0) == 1 / 8


def test_coefficients_at_zero_are_the_limits():
    z = np.zeros(1)
    assert _series.c3(z)[0] == pytest.approx(1 / 6, rel=1e-16)
    assert _series.d(z)[0] == pytest.approx(1 / 12, rel=1e-16)
    assert _series.e(z)[0] == pytest.approx(1 / 360, rel=1e-16)


def _mp_hat(x):
    return mp.matrix([[0, -x[2], x[1]], [x[2], 0, -x[0]], [-x[1], x[0], 0]])


def _mp_dexp(ad, n=60):
    """Σ adᵏ/(k+1)!: the defining series of the right-trivialized dexp."""
    out, term = mp.eye(ad.rows), mp.eye(ad.rows)
    for k in range(1, n):
        term = term * ad / (k + 1)
        out += term
    return out


def _np(m):
    return np.array(m.tolist(), dtype=float)


@pytest.mark.parametrize("k", range(3, 13))
def test_small_angle_so3_maps_against_mpmath(k, rng):
    d = rng.normal(size=3)
    x = d / np.linalg.norm(d) * 10.0 ** -k
    X = _mp_hat([mp.mpf(v) for v in x])
    R = mp.expm(X)
    D = _mp_dexp(X)
    for got, ref in [(so3.exp(x), R), (so3.dexp(x), D), (so3.dexp_inv(x), D ** -1)]:
        ref = _np(ref)
        assert np.linalg.norm(got - ref) <= 1e-14 * np.linalg.norm(ref)
    # the part that vanishes with x must also be right to 1e-14 relative
    assert np.linalg.norm((so3.exp(x) - so3.exp(x).T) - _np(R - R.T)) <= 1e-14 * np.linalg.norm(_np(R - R.T))


@pytest.mark.parametrize("k", [3, 6, 9, 12])
def test_small_angle_se3_maps_against_mpmath(k, rng):
    d = rng.normal(size=3)
    x = d / np.linalg.norm(d) * 10.0 ** -k
    y = rng.normal(size=3)
    xm, ym = _mp_hat([mp.mpf(v) for v in x]), _mp_hat([mp.mpf(v) for v in y])
    ad = mp.zeros(6, 6)
    for i in range(3):
        for j in range(3):
            ad[i, j] = xm[i, j]
            ad[i + 3, j + 3] = xm[i, j]
            ad[i + 3, j] = ym[i, j]
    D = _mp_dexp(ad)
    X = np.concatenate([x, y])
    for got, ref in [(se3.dexp(X), D), (se3.dexp_inv(X), D ** -1)]:
        ref = _np(ref)
        assert np.linalg.norm(got - ref) <= 1e-14 * np.linalg.norm(ref)
    # translation of exp: dexp_x y, whose deviation from y is O(|x|)
    t = se3.exp(X)[:3, 3]
    tref = _np(D[3:6, 3:6] * mp.matrix([mp.mpf(v) for v in y]))[:, 0]
    assert np.linalg.norm((t - y) - (tref - y)) <= 1e-10 * np.linalg.norm(tref - y) + 1e-15
