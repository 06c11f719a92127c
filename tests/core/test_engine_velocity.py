"""A model's f in its engine's own velocities (``Model.engine_velocity``): the compiled stages
write the engine's body-frame twist (v_lin = Rᵀṙ, ω) and read the engine's (v̇_lin, ω̇), so that
the run equals the run through f(q, V) — checked on a model whose engine form is written
here from the rotation matrices of the reference parameterizations (``param.alpha``), not
from the kernels."""
import numpy as np
import pytest

from lgt_bridge.errors import InputError
from lgt_bridge.integrators.compiled import CompiledProblem
from lgt_bridge.model import EngineVelocity
from lgt_bridge.simulate import simulate

from test_backends import Mixed, close


def _R(body, q):
    """The body's rotation matrix, from the reference parameterization's α."""
    return body.param.alpha(q[[*body.pos, *body.rot]])[:3, :3]


class EngineMixed(Mixed):
    """Mixed with the first body of each parameterization pair in an engine's velocity form;
    ``seen`` records the (q, v) the engine's f received."""

    def __init__(self, rng, bodies=None):
        super().__init__(rng)
        full = [k for k, b in enumerate(self.layout.bodies) if not b.rotation_only]
        self.engine_bodies = tuple(full[::2]) if bodies is None else tuple(bodies)
        self.engine_velocity = EngineVelocity(self.engine_bodies, self.f_engine)
        self.seen = []

    def twist_of(self, q, v):
        """V of the engine's v: ω, and ṙ = R v_lin, on the engine bodies."""
        V = np.array(v, float)
        for k in self.engine_bodies:
            b = self.layout.bodies[k]
            ang, lin = list(b.twist[:3]), list(b.twist[3:])
            V[ang], V[lin] = v[lin], _R(b, q) @ v[ang]
        return V

    def f_engine(self, q, v, t):
        self.seen.append((q.copy(), v.copy()))
        V = self.twist_of(q, v)
        Vd = self.f(q, V, t)
        a = np.array(Vd, float)
        for k in self.engine_bodies:
            b = self.layout.bodies[k]
            ang, lin = list(b.twist[:3]), list(b.twist[3:])
            w, v_lin = V[ang], v[ang]
            # v_lin = Rᵀṙ: v̇_lin = Rᵀr̈ - ω × v_lin; ω̇ as is
            a[ang], a[lin] = _R(b, q).T @ Vd[lin] - np.cross(w, v_lin), Vd[ang]
        return a


@pytest.fixture(autouse=True)
def compiled(monkeypatch):
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", "numba")


def _run(model, method, group, chart):
    kw = dict(rtol=1e-9, atol=1e-9) if method != "rkmk4" else dict(dt=0.01)
    return simulate(model, (0.0, 0.3), method=method, group=group, chart=chart, t_eval=[0.1, 0.3], **kw)


@pytest.mark.parametrize("method", ["dop853", "dopri5", "rkmk4"])
@pytest.mark.parametrize("group,chart", [("SE3", "exp"), ("SO3xR3", "exp"), ("SO3xR3", "cay"), ("mix", "cay2")])
def test_engine_form_runs_equal_the_plain_f(method, group, chart):
    plain, eng = Mixed(np.random.default_rng(7)), EngineMixed(np.random.default_rng(7))
    nb = plain.layout.nbodies
    g = [("SE3", "SO3xR3")[k % 2] for k in range(nb)] if group == "mix" else group
    r0, r1 = _run(plain, method, g, chart), _run(eng, method, g, chart)
    assert r0.success and r1.success
    assert len(eng.seen) > 10 and r1.stats["n_f"] == r0.stats["n_f"]
    assert close(r1.q, r0.q, 1e-11) and close(r1.V, r0.V, 1e-11)


def test_engine_f_receives_the_body_frame_twist(rng):
    """At a stage, the v the engine's f gets is the body-frame twist of the stage's (q, V)
    (v_lin = Rᵀṙ, ω on the engine bodies; V's entries elsewhere)."""
    m = EngineMixed(rng)
    prob = CompiledProblem(m, "SO3xR3", "exp")
    prob.start(m.q0)
    KX, KW = rng.normal(size=(4, prob.nX)) * 0.2, rng.normal(size=(4, prob.nv))
    assert prob.stage(KX, KW, 3, np.array([0.3, -0.2, 0.5]), 0.1, m.V0, 0.0, 0.05) == 0.0
    q, v = m.seen[-1]
    V = prob._V.copy()                     # the stage's V (the bridge's twist)
    assert close(q, prob._q)
    expect = V.copy()
    for k in m.engine_bodies:
        b = m.layout.bodies[k]
        ang, lin = list(b.twist[:3]), list(b.twist[3:])
        expect[ang], expect[lin] = _R(b, q).T @ V[lin], V[ang]
    assert close(v, expect)
    assert np.array_equal(m.twist_of(q, v)[[i for k in range(m.layout.nbodies) if k not in m.engine_bodies
                                            for i in m.layout.bodies[k].twist]],
                          V[[i for k in range(m.layout.nbodies) if k not in m.engine_bodies
                             for i in m.layout.bodies[k].twist]])


def test_engine_form_on_a_rotation_only_body_is_refused(rng):
    m = Mixed(rng)
    ball = next(k for k, b in enumerate(m.layout.bodies) if b.rotation_only)
    m.engine_velocity = EngineVelocity((ball,), m.f)
    with pytest.raises(InputError, match="engine_velocity"):
        CompiledProblem(m, "SO3xR3", "exp")
