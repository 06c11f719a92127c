"""Finished steppers kept for the next run of a model of the same layout
(:mod:`lgt_bridge.integrators.steppers`): a run on a kept stepper must be exactly the run on a
new one (the same f count, the same bytes of the final state), whatever changed between the
runs: the model (torques, a changed pinocchio.Model's inertia), the tolerance, the method,
the group, or the robot (another of the same nq)."""
import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from lgt_bridge import Simulation, simulate  # noqa: E402
from lgt_bridge.integrators import steppers  # noqa: E402
from lgt_pinocchio import PinocchioModel  # noqa: E402


@pytest.fixture(autouse=True)
def compiled(monkeypatch):
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", "numba")
    steppers._POOL.clear()
    yield
    steppers._POOL.clear()


@pytest.fixture
def taken(monkeypatch):
    """How many steppers were taken from the pool."""
    n = []
    restored = steppers._restored
    monkeypatch.setattr(steppers, "_restored", lambda st, m: (n.append(1), restored(st, m))[1])
    return n


def humanoid(seed):
    pin.seed(seed)
    m = pin.buildSampleModelHumanoidRandom()
    m.armature[:] = 1e-3
    q0 = pin.neutral(m)
    rng = np.random.default_rng(seed)
    v0 = np.concatenate([[0.3, -0.2, 0.1, 1.0, 2.0, -1.5], 0.5 * rng.normal(size=m.nv - 6)])
    return m, q0, v0


def run(m, q0, v0, method="dop853", tol=1e-8, group="SE3", tau=None):
    r = simulate(PinocchioModel(m, q0=q0, v0=v0, tau=tau), (0, 0.2), method=method, group=group, rtol=tol,
                 atol=tol, t_eval=[0.1, 0.2])
    return r.q.tobytes(), r.V.tobytes(), r.stats["n_f"], r.stats["n_steps"]


def fresh(*args, **kw):
    """The same run with nothing kept."""
    steppers._POOL.clear()
    out = run(*args, **kw)
    steppers._POOL.clear()
    return out


def test_runs_on_kept_steppers_equal_runs_on_new_ones_across_tolerances_methods_groups(taken):
    m, q0, v0 = humanoid(0)
    cases = [dict(tol=1e-8), dict(tol=1e-6), dict(tol=1e-8), dict(method="dopri5", tol=1e-7), dict(method="dopri5", tol=1e-5),
             dict(tol=1e-8, group="SO3xR3"), dict(tol=1e-8), dict(tol=1e-6)]
    kept = []
    for kw in cases:
        kept.append(run(m, q0, v0, **kw))
    assert len(taken) >= 3                       # the repeated kinds came from the pool
    for kw, got in zip(cases, kept):
        assert got == fresh(m, q0, v0, **kw), kw


def test_a_changed_model_of_the_same_layout_never_meets_what_the_last_left(taken):
    m, q0, v0 = humanoid(0)
    run(m, q0, v0)
    n0 = len(taken)
    tau = np.zeros(m.nv)
    tau[6:] = 0.5
    with_tau = run(m, q0, v0, tau=tau)           # the same pinocchio.Model: the same layout, another f
    assert len(taken) == n0 + 1
    assert with_tau == fresh(m, q0, v0, tau=tau)
    assert with_tau != fresh(m, q0, v0)
    # another initial state of the same model
    v1 = -v0
    assert run(m, q0, v1) == fresh(m, q0, v1)
    # a torque function (the loop's f with its own Python frame)
    fn = lambda t, q, v: np.concatenate([np.zeros(6), np.full(m.nv - 6, np.sin(t))])   # noqa: E731
    assert run(m, q0, v0, tau=fn) == fresh(m, q0, v0, tau=fn)


def test_changed_inertias_and_another_robot_of_the_same_size_run_as_new():
    m, q0, v0 = humanoid(0)
    base = run(m, q0, v0)
    m.inertias[5] = pin.Inertia(3.0 * m.inertias[5].mass, m.inertias[5].lever, m.inertias[5].inertia)
    heavier = run(m, q0, v0)                      # the model changed between calls
    assert heavier != base
    assert heavier == fresh(m, q0, v0)
    other, q1, v1 = humanoid(1)                   # another robot, the same nq and nv
    assert other.nq == m.nq and other.nv == m.nv
    got = run(other, q1, v1)
    assert got == fresh(other, q1, v1)
    assert run(m, q0, v0) == heavier


def test_a_user_simulation_may_take_a_kept_stepper_and_keeps_it(taken):
    m, q0, v0 = humanoid(0)
    run(m, q0, v0)
    sim = Simulation(PinocchioModel(m, q0=q0, v0=v0), method="dop853", group="SE3", rtol=1e-8, atol=1e-8, t_end=0.2)
    assert len(taken) == 1
    ref = Simulation(PinocchioModel(m, q0=q0, v0=v0), method="dop853", group="SE3", rtol=1e-8, atol=1e-8, t_end=0.2)
    for t in (0.1, 0.2):
        a, b = sim.run(t), ref.run(t)
        assert np.array_equal(a.q, b.q) and a.stats["n_f"] == b.stats["n_f"]
    assert not steppers._POOL                     # a Simulation gives nothing back: it may run on
    assert run(m, q0, v0) == fresh(m, q0, v0)


def _state(obj, skip=()):
    """An object's attributes: arrays by content, numbers and strings by value, None as None,
    other objects by type (their own state compared separately)."""
    out = {}
    for k, v in vars(obj).items():
        if k in skip:
            continue
        if isinstance(v, np.ndarray):
            out[k] = ("array", v.shape, v.tobytes())
        elif v is None or isinstance(v, (bool, int, float, str)):
            out[k] = ("nan",) if isinstance(v, float) and v != v else v
        else:
            out[k] = type(v).__name__
    return out


def test_a_kept_stepper_is_taken_in_the_state_a_new_one_is_built_in(taken):
    m, q0, v0 = humanoid(0)
    opts = dict(method="dopri5", group="SE3", rtol=1e-7, atol=1e-7, t_end=0.2)
    new = Simulation(PinocchioModel(m, q0=q0, v0=v0), **opts).stepper
    new_loop = new._compiled_loop
    simulate(PinocchioModel(m, q0=q0, v0=v0), (0, 0.2), method="dopri5", group="SE3", rtol=1e-7, atol=1e-7)
    kept = Simulation(PinocchioModel(m, q0=q0, v0=v0), **opts).stepper
    assert len(taken) == 1 and kept is not new
    for a, b in ((new, kept), (new.prob, kept.prob), (new.control, kept.control), (new_loop, kept._compiled_loop)):
        assert _state(a, skip=("_fresh",)) == _state(b, skip=("_fresh",))
