"""The compiled Pinocchio adapter (lgt_pinocchio.kernels) against its numpy reference path:
PinocchioModel.f on both backends, equal to 1e-13 relative, on random states of a free
body, several free-flyers, the sample humanoid, spherical joints (rotation-only bodies,
with and without a free-flyer root), a fixed-base arm and constrained models; tau as a
vector and as a callable, fext; inputs of other types; whole simulate() runs on both
backends. Skipped only when pin is not installed."""

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_pinocchio import PinocchioModel  # noqa: E402

from backend_checks import close, run_python  # noqa: E402
from pinocchio_models import ball_chain  # noqa: E402


def free_body():
    m = pin.Model()
    j = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    m.appendBodyToJoint(j, pin.Inertia(1.3, np.array([0.1, -0.2, 0.05]), np.diag([1.0, 2.0, 3.0])), pin.SE3.Identity())
    return m


def two_free_flyers():
    m = pin.Model()
    for k in range(2):
        j = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), f"ff{k}")
        m.appendBodyToJoint(j, pin.Inertia(1.0 + k, np.zeros(3), np.diag([1.0, 2 + k, 3 + k])), pin.SE3.Identity())
    return m


def humanoid():
    pin.seed(11)
    return pin.buildSampleModelHumanoidRandom()


def ball_pendulum():
    """Fixed base: two spherical joints in a chain (rotation-only bodies, no free-flyer)."""
    m = pin.Model()
    a = m.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball0")
    m.appendBodyToJoint(a, pin.Inertia(1.0, np.array([0, 0, -0.5]), np.diag([0.1, 0.12, 0.05])), pin.SE3.Identity())
    b = m.addJoint(a, pin.JointModelSpherical(), pin.SE3(np.eye(3), np.array([0, 0, -1.0])), "ball1")
    m.appendBodyToJoint(b, pin.Inertia(0.7, np.array([0.1, 0, -0.3]), np.diag([0.05, 0.06, 0.02])), pin.SE3.Identity())
    return m


MODELS = {"free body": free_body, "two free-flyers": two_free_flyers, "humanoid": humanoid,
          "ball chain": ball_chain, "ball pendulum": ball_pendulum, "arm": pin.buildSampleModelManipulator}


def pair(make, **kw):
    """The same Pinocchio model wrapped on the numpy and on the compiled backend."""
    m = make()
    a, b = PinocchioModel(m, backend="numpy", **kw), PinocchioModel(m, backend="numba", **kw)
    assert not a.compiled and b.compiled
    return a, b


def random_state(pm, rng, scale=1.0):
    q = pm._moved(pm.q0, rng.normal(size=pm.nv) * 2.0)
    return q, rng.normal(size=pm.nv) * scale


def body_forces(model):
    """fext as a callable: a state- and time-dependent force on every joint (6-vectors)."""
    def fext(t, q, v):
        return [np.zeros(6)] + [np.concatenate([np.sin(t + k) + 0.1 * v[:3] * k, np.cos(q[:3] * k) * 0.2])
                                for k in range(1, model.njoints)]
    return fext


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("inputs", ["none", "tau vector", "tau callable", "fext", "fext StdVec"])
def test_compiled_f_equals_numpy(name, inputs, rng):
    m = MODELS[name]()
    kw = {}
    if inputs == "tau vector":
        kw["tau"] = rng.normal(size=m.nv)
    elif inputs == "tau callable":
        kw["tau"] = lambda t, q, v: np.sin(t) * np.arange(m.nv) * 0.1 - 0.3 * v + 0.05 * q[:m.nv]
    elif inputs == "fext":
        kw["fext"] = body_forces(m)
    elif inputs == "fext StdVec":
        fs = pin.StdVec_Force()
        for k in range(m.njoints):
            fs.append(pin.Force(np.array([0.1, -0.2, 0.3]) * k, np.array([0.02, 0.01, -0.03]) * k))
        kw["fext"] = lambda t, q, v: fs
    a, b = PinocchioModel(m, backend="numpy", **kw), PinocchioModel(m, backend="numba", **kw)
    # the compiled stages call Pinocchio in its own velocities on models whose only converted
    # joints are free-flyers (Model.engine_velocity); the numpy reference never does
    assert a.engine_velocity is None
    assert (b.engine_velocity is not None) == bool(a.joints.roots)
    for k in range(6):
        q, V = random_state(a, rng, scale=3.0)
        t = 0.1 * k
        fa, fb = a.f(q, V, t), b.f(q, V, t)
        assert close(fb, fa) and np.isfinite(fa).all()
        if b.engine_velocity is not None:
            v = a.v_from_twist(q, V)
            assert close(a.joints.vdot_from_a(q, v, b.engine_velocity.f(q, v, t)), fa)
        assert close(b.v_from_twist(q, V), a.v_from_twist(q, V), 1e-14)
        assert close(b.twist_from_v(q, b.v_from_twist(q, V)), V, 1e-13)


@pytest.mark.parametrize("name", ["free body", "humanoid", "ball chain"])
def test_constrained_f_equals_numpy(name, rng):
    """A 6-D contact on the last joint and a 3-D contact on the first one (constraintDynamics)."""
    m = MODELS[name]()
    d = m.createData()
    q0 = pin.neutral(m)
    pin.forwardKinematics(m, d, q0)
    cms = []
    for j, kind in ((m.njoints - 1, pin.ContactType.CONTACT_6D), (1, pin.ContactType.CONTACT_3D)):
        if kind == pin.ContactType.CONTACT_3D and j == m.njoints - 1:
            continue
        pl = pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.05]))
        cm = pin.RigidConstraintModel(kind, m, j, pl, pin.LOCAL)
        cm.joint2_placement = d.oMi[j] * pl
        cms.append(cm)
    a, b = (PinocchioModel(m, backend=be, constraints=cms, tau=lambda t, q, v: -0.1 * v) for be in ("numpy", "numba"))
    assert a.n_constraints == b.n_constraints > 0
    for _ in range(4):
        q, V = random_state(a, rng)
        assert close(b.f(q, V, 0.2), a.f(q, V, 0.2))
        assert close(b.constraints(q), a.constraints(q))
        assert close(b.constraint_jacobian(q), a.constraint_jacobian(q))
        assert close(b.constraint_gamma(q, V), a.constraint_gamma(q, V))


@pytest.mark.parametrize("name", ["free body", "humanoid", "ball chain"])
def test_mass_matrix_and_forces_on_both_backends(name, rng):
    a, b = pair(MODELS[name], fext=body_forces(MODELS[name]()))
    for _ in range(3):
        q, V = random_state(a, rng)
        assert close(b.mass_matrix(q), a.mass_matrix(q))
        assert close(b.forces(q, V, 0.4), a.forces(q, V, 0.4))
        assert close(np.linalg.solve(b.mass_matrix(q), b.forces(q, V, 0.4)), b.f(q, V, 0.4), 1e-10)
        assert close(b.energy(q, V), a.energy(q, V)) and close(b.spatial_momentum(q, V), a.spatial_momentum(q, V))


def test_callbacks_see_pinocchio_state_and_f_returns_fresh_arrays(rng):
    """tau and fext get the caller's q and Pinocchio's v (a view of the model's buffer on the
    compiled backend); f's result is a new array that a later call does not overwrite."""
    seen = {}

    def tau(t, q, v):
        seen.setdefault("tau", []).append((t, q.copy(), v.copy()))
        return np.zeros(len(v))

    def fext(t, q, v):
        seen.setdefault("fext", []).append((t, q.copy(), v.copy()))
        return [pin.Force.Zero() for _ in range(4)]

    ref = PinocchioModel(ball_chain(), backend="numpy")
    pm = PinocchioModel(ball_chain(), backend="numba", tau=tau, fext=fext)
    seen.clear()
    q, V = random_state(pm, rng)
    q_in, V_in = q.copy(), V.copy()
    out1 = pm.f(q, V, 0.7)
    assert np.array_equal(q, q_in) and np.array_equal(V, V_in)            # inputs untouched
    for key in ("tau", "fext"):
        t, qs, vs = seen[key][0]
        assert t == 0.7 and np.array_equal(qs, q) and close(vs, ref.v_from_twist(q, V), 1e-15)
    keep = out1.copy()
    q2, V2 = random_state(pm, rng)
    out2 = pm.f(q2, V2, 0.8)
    assert out2 is not out1 and np.array_equal(out1, keep) and not np.shares_memory(out1, out2)
    assert close(out1, ref.f(q, V, 0.7))


def test_inputs_of_other_types_and_layouts(rng):
    a, b = pair(humanoid)
    q, V = random_state(a, rng)
    want = a.f(q, V, 0.0)
    for qq, VV in ((list(q), list(V)), (q, V.astype(np.float32)),
                   (np.repeat(q, 2)[::2], np.repeat(V, 2)[::2])):          # non-contiguous views
        assert close(b.f(qq, VV, 0.0), a.f(np.asarray(qq, float), np.asarray(VV, float), 0.0))
    assert close(b.f(q, V, 0.0), want)
    with pytest.raises(ValueError):
        b.f(q, V[:-1], 0.0)
    m = pin.buildSampleModelManipulator()                          # no free-flyer: no kernel call
    a, b = PinocchioModel(m, backend="numpy"), PinocchioModel(m, backend="numba")
    q, V = random_state(a, rng)
    assert close(b.f(list(q), list(V), 0.0), a.f(q, V, 0.0))


@pytest.mark.parametrize("name,method,kw", [
    ("humanoid", "dopri5", dict(rtol=1e-8, atol=1e-8)),
    ("ball chain", "rkmk4", dict(dt=1e-2)),
])
def test_simulate_agrees_across_backends(monkeypatch, rng, name, method, kw):
    """Whole runs with the model and the stepper on either backend."""
    m = MODELS[name]()
    q0 = pin.neutral(m)
    v0 = rng.normal(size=m.nv) * 0.5
    out = []
    for backend in ("numpy", "numba"):
        monkeypatch.setenv("LGT_BRIDGE_BACKEND", backend)
        pm = PinocchioModel(m, q0=q0, v0=v0, tau=lambda t, q, v: -0.2 * v)
        assert pm.compiled == (backend == "numba")
        out.append(simulate(pm, (0, 0.2), method=method, t_eval=[0.0, 0.1, 0.2], **kw))
    assert out[0].success and out[1].success
    assert out[0].stats["n_f"] == out[1].stats["n_f"]
    assert close(out[1].q, out[0].q, 1e-12) and close(out[1].V, out[0].V, 1e-12)


def test_numpy_backend_never_imports_numba():
    out = run_python("import sys, numpy as np, pinocchio as pin\n"
                      "from lgt_pinocchio import PinocchioModel\n"
                      "m = pin.buildSampleModelHumanoidRandom()\n"
                      "pm = PinocchioModel(m); pm.f(pm.q0, pm.V0 + 0.1, 0.0)\n"
                      "print('numba' in sys.modules)", LGT_BRIDGE_BACKEND="numpy")
    assert out.strip() == "False"


def test_kernels_run_interpreted():
    """NUMBA_DISABLE_JIT=1: the same kernel source runs as plain Python and agrees."""
    out = run_python("import numpy as np, pinocchio as pin\n"
                      "from lgt_pinocchio import PinocchioModel\n"
                      "rng, worst = np.random.default_rng(5), 0.0\n"
                      "pin.seed(2); m = pin.buildSampleModelHumanoidRandom()\n"
                      "a, b = PinocchioModel(m, backend='numpy'), PinocchioModel(m, backend='numba')\n"
                      "for _ in range(3):\n"
                      "    q, V = a._moved(a.q0, rng.normal(size=a.nv)), rng.normal(size=a.nv)\n"
                      "    x, y = a.f(q, V, 0.0), b.f(q, V, 0.0)\n"
                      "    worst = max(worst, np.abs(x - y).max() / np.abs(x).max())\n"
                      "print(worst)", NUMBA_DISABLE_JIT="1")
    assert float(out) <= 1e-13


def test_bench_pinocchio_f_quick_writes_json_and_markdown(tmp_path):
    """Smoke test of benchmarks/bench_pinocchio_f.py --quick (no timing asserted)."""
    import importlib.util
    import json
    from pathlib import Path
    script = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_pinocchio_f.py"
    spec = importlib.util.spec_from_file_location("bench_pinocchio_f", script)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    mod.main(["--quick", "--out", str(tmp_path)])
    data = json.loads((tmp_path / "pinocchio_f.json").read_text())
    assert [r["model"] for r in data["rows"]] == ["free body", "sample humanoid"]
    for r in data["rows"]:
        assert min(r["aba_us"], r["f_numba_us"], r["f_numpy_us"]) > 0 and r["max_rel_diff"] <= 1e-13
    assert "| free body | 6 |" in (tmp_path / "pinocchio_f.md").read_text()


def test_a_model_and_its_run_are_freed_at_once():
    """No reference cycle keeps a PinocchioModel (and its Pinocchio Data) alive after its
    last reference goes: a model built per call is freed then, not at the next collection."""
    import gc
    import weakref
    gc.disable()
    try:
        pm = PinocchioModel(free_body(), v0=np.array([0.1, 0.0, 0.2, 0.3, 1.0, -0.5]))
        simulate(pm, (0, 0.01), method="dop853", rtol=1e-8, atol=1e-8, t_eval=[0.01])
        ref = weakref.ref(pm)
        del pm
        assert ref() is None
    finally:
        gc.enable()


def test_a_freed_models_data_serves_the_next_model_and_live_models_never_share_one():
    """Models wrapped afresh per call take a spare pinocchio.Data given back by a model freed
    before; two live models of one pinocchio.Model never hold the same Data."""
    model = free_body()
    a, b = PinocchioModel(model), PinocchioModel(model)
    assert a.data is not b.data
    spare = a.data
    del a
    c, d = PinocchioModel(model), PinocchioModel(model)
    assert c.data is spare and d.data is not spare and len({id(x.data) for x in (b, c, d)}) == 3
    r1 = simulate(c, (0, 0.01), method="dop853", rtol=1e-9, atol=1e-9, t_eval=[0.01])
    r2 = simulate(d, (0, 0.01), method="dop853", rtol=1e-9, atol=1e-9, t_eval=[0.01])
    assert np.array_equal(r1.q, r2.q)


@pytest.mark.parametrize("torques", [None, "pd"])
def test_compiled_step_loop_takes_the_python_loops_steps(torques):
    """A free-flying humanoid (f in Pinocchio's own velocities, ABA per stage): the compiled
    step loop (whose f result goes unchecked for Pinocchio's own a, and which calls aba itself
    for constant torques) takes the Python loop's steps, with constant and with state-feedback
    torques, over consecutive horizons."""
    from lgt_bridge import Simulation
    model = humanoid()
    q0 = pin.neutral(model)
    v0 = np.linspace(-2.0, 2.0, model.nv)
    def damping(t, q, v):
        out = -2.0 * v
        out[:6] = 0.0
        return out
    tau = damping if torques == "pd" else None
    runs = []
    for use in (True, False):
        pm = PinocchioModel(model, q0=q0, v0=v0, tau=tau)
        assert pm.engine_velocity is not None
        # constant torques: the loop calls aba without f's frame; state feedback: through f
        assert (getattr(pm.engine_velocity.f, "time_free_call", None) is None) == (tau is not None)
        sim = Simulation(pm, method="dop853", rtol=1e-11, atol=1e-11)
        sim._use_loop = use
        rs = [sim.run(0.1 * k, t_eval=[0.1 * k]) for k in range(1, 5)]
        runs.append((np.concatenate([r.q for r in rs]), sim.n_steps, sim.stepper.prob.n_f,
                     getattr(sim.stepper, "_compiled_loop", None)))
    (qa, na, fa, loop), (qb, nb, fb, none) = runs
    # (a stepper kept for reuse has its loop from the start: the Python loop's never ran it)
    assert loop is not None and loop.runs >= 4 and (none is None or none.runs == 0)
    assert na == nb and fa == fb and na > 8
    np.testing.assert_allclose(qa, qb, rtol=1e-12, atol=1e-14)
