"""generalized-α's Newton matrix by finite differences (``genalpha_matrix.fd_matrix``, for
models without an ``iteration_matrix``) against the exact derivative of the step's residual,
on a force that depends steeply on the velocity: a regularised friction F·tanh(V/ε).

The difference step used to be sized to move the positions by √eps (h²β·δẆ), which moved
the velocities by √eps·γ/(hβ)·|Ẇ|: here 300 m/s across a friction whose slope lives within
ε = 1e-2 m/s, so the matrix missed the friction entirely (1.00009 for 1.22990) and Newton
bounced (Exudyn's ballBearingTest.py, an Rxyz shaft in a bearing of sphere–torus contacts)."""
import numpy as np
import pytest

from lgt_bridge.integrators import genalpha as ga_mod
from lgt_bridge.integrators import genalpha_matrix as gm
from lgt_bridge.integrators.local import LocalProblem
from lgt_bridge.model import Layout, Model


class _Slip(Model):
    """A unit mass on a spring k sliding on a regularised friction F·tanh(V/ε)."""

    def __init__(self, k=1e4, F=50.0, eps=1e-2, x0=1e-3, v0=5.0):
        self.layout = Layout.stacked([], n_vector=1)
        self.q0, self.V0 = np.array([x0]), np.array([v0])
        self.k, self.F, self.eps = k, F, eps

    def f(self, q, V, t):
        return -self.k * q - self.F * np.tanh(V / self.eps)


@pytest.mark.parametrize("v_end", [3e-3, -2e-2, 5.0])
def test_fd_matrix_takes_a_steep_friction_at_its_slope(v_end):
    """A step from 5 m/s ending at v_end (in the friction's proportional zone, past it, or at
    the start's speed): the matrix equals 1 + k h²βk' + (F/ε) sech²(V/ε) s_v, the exact
    derivative of the residual Ẇ - f in Ẇ (V = W₀ + s_v Ẇ, q moves by h²βk' Ẇ), to 1e-6."""
    m = _Slip()
    ga = ga_mod.GenAlpha(LocalProblem(m, "SO3xR3", "exp"))
    ga.set_state(m.q0, m.V0)
    ga.start(0.0)
    h = 1e-4
    c = ga._affine(h)
    Wd1 = (v_end - c.W0) / c.s_v
    J = gm.fd_matrix(ga, Wd1, np.zeros(0), h, h)
    _, V1, _, _ = ga._evaluate(Wd1, h)
    assert V1[0] == pytest.approx(v_end, rel=1e-9)
    exact = 1 + m.k * h * h * ga.beta * ga._k + m.F / m.eps * (1 - np.tanh(V1[0] / m.eps) ** 2) * c.s_v
    assert abs(J[0, 0] - exact) < 1e-6 * exact
