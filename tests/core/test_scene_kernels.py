"""The compiled kernels of the engine-free scenes (lgt_bridge.kernels.scene) against the
numpy reference methods of RigidBodySystem: f, the joints' g, A and γ on random states
for every scene and parameterization, springs, pivots and loads; whole runs of the chain
on both backends; numba stays unimported on the numpy backend."""

import os

import numpy as np
import pytest

from lgt_bridge import scenes
from lgt_bridge.simulate import simulate

from backend_checks import close, run_python

PARAMS = ["quat", "quat_xyzw", "rotvec", "rxyz"]


def full_inertia(rng):
    """A random full (non-diagonal) 3x3 inertia: principal moments in a random frame."""
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return Q @ scenes.principal_inertia(rng) @ Q.T


def springs_scene(param):
    """Three bodies (full inertias, gravity): springs body-ground and body-body, with
    damping, one body pivoted (its spring acts through the pivot)."""
    rng = np.random.default_rng(7)
    J = [full_inertia(rng) for _ in range(3)]
    q0 = np.concatenate([np.concatenate([rng.normal(size=3), scenes._rot_coords(scenes._params.get(param),
                                                                                 np.eye(3))[0]])
                         for _ in range(3)])
    springs = [(0, rng.normal(size=3), -1, rng.normal(size=3), 40.0, 0.5),
               (0, rng.normal(size=3), 1, rng.normal(size=3), 25.0, 0.2),
               (2, rng.normal(size=3), 1, rng.normal(size=3), 10.0, 0.0),
               (1, rng.normal(size=3), -1, rng.normal(size=3), 5.0, 1.5)]
    return scenes.RigidBodySystem([1.0, 2.0, 0.5], J, q0, rng.normal(size=18), param=param,
                                  pivot_com={2: np.array([0.1, -0.3, 0.4])}, springs=springs)


def pivots_scene(param):
    """Two pivoted bodies (full inertia about the pivot) and a free falling one."""
    rng = np.random.default_rng(8)
    rot = scenes._rot_coords(scenes._params.get(param), np.eye(3))[0]
    q0 = np.concatenate([np.concatenate([rng.normal(size=3), rot]) for _ in range(3)])
    return scenes.RigidBodySystem([3.0, 1.0, 2.0], [full_inertia(rng) for _ in range(3)], q0,
                                  rng.normal(size=18), param=param,
                                  pivot_com={0: np.array([0.0, 1.0, 0.2]), 1: np.array([0.5, 0.0, -0.1])})


def joint_graph(param):
    """Five bodies, joints listed out of order, a branch and a closed loop
    (0-ground, 3-1, 1-0, 2-0, 4-3, 4-2): A M⁻¹Aᵀ is not block tridiagonal."""
    rng = np.random.default_rng(9)
    rot = scenes._rot_coords(scenes._params.get(param), np.eye(3))[0]
    q0 = np.concatenate([np.concatenate([rng.normal(size=3), rot]) for _ in range(5)])
    pairs = [(0, -1), (3, 1), (1, 0), (2, 0), (4, 3), (4, 2)]
    joints = [(i, rng.normal(size=3), j, rng.normal(size=3)) for i, j in pairs]
    return scenes.RigidBodySystem(rng.uniform(0.5, 2.0, 5), [full_inertia(rng) for _ in range(5)], q0,
                                  rng.normal(size=30), param=param, joints=joints)


def chain_with_load(param):
    m = scenes.chain(4, param=param)
    m.load = lambda t, q, V: (np.outer(np.arange(1, 5), [np.sin(t), 0.3, -1.0]) + q[:3],
                              np.outer(np.ones(4), V[:3]) * 0.1 + t)
    return m


def free_bodies_with_load(param):
    m = scenes.free_bodies(5, param=param)
    m.load = lambda t, q, V: (np.full((5, 3), 2.0 * t), V.reshape(5, 6)[:, 3:] * 0.5)
    return m


SCENES = {
    "free_body": lambda p: scenes.free_body(param=p),
    "free_body_full_J": lambda p: scenes.free_body(full_inertia(np.random.default_rng(1)), param=p),
    "free_bodies": lambda p: scenes.free_bodies(7, param=p),
    "heavy_top_pivot": lambda p: scenes.heavy_top(False, param=p),
    "heavy_top_joint": lambda p: scenes.heavy_top(True, param=p),
    "chain": lambda p: scenes.chain(6, param=p),
    "top_and_free_bodies": lambda p: scenes.top_and_free_bodies(3, param=p),
    "joint_graph": joint_graph,
    "springs": springs_scene,
    "pivots": pivots_scene,
    "chain_with_load": chain_with_load,
    "free_bodies_with_load": free_bodies_with_load,
}


def build(monkeypatch, backend, name, param):
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", backend)
    m = SCENES[name](param)
    assert m.compiled == (backend == "numba")
    return m


def random_state(model, rng):
    """Random positions, rotations (a unit quaternion; rotation vectors beyond π;
    any angles) and twists."""
    nb, name = model.nb, model.param.name
    if name.startswith("quat"):
        rot = rng.normal(size=(nb, 4))
        rot /= np.linalg.norm(rot, axis=1, keepdims=True)
    elif name == "rotvec":
        rot = rng.normal(size=(nb, 3)) * 2.5
    else:
        rot = rng.uniform(-4.0, 4.0, size=(nb, 3))
    q = np.concatenate([rng.normal(size=(nb, 3)), rot], axis=1).ravel()
    V = rng.normal(size=6 * nb) * rng.choice([0.1, 1.0, 10.0])
    return q, V


@pytest.mark.parametrize("param", PARAMS)
@pytest.mark.parametrize("name", list(SCENES))
def test_compiled_scene_equals_numpy(monkeypatch, rng, name, param):
    ref, comp = build(monkeypatch, "numpy", name, param), build(monkeypatch, "numba", name, param)
    for _ in range(5):
        q, V = random_state(ref, rng)
        t = rng.uniform(0, 2)
        want = ref.f(q, V, t)
        got = comp.f(q, V, t)
        assert close(got, want), (np.abs(got - want).max(), np.abs(want).max())
        assert close(comp._f_numpy(q, V, t), want)
        Qw = ref.forces(q, V, t)
        assert close(comp.forces(q, V, t), Qw), np.abs(comp.forces(q, V, t) - Qw).max()
        if ref.n_constraints:
            assert close(comp.constraints(q), ref.constraints(q))
            assert close(comp.constraint_jacobian(q), ref.constraint_jacobian(q))
            assert close(comp.constraint_gamma(q, V), ref.constraint_gamma(q, V))
        else:
            assert comp.constraints(q).shape == (0,)
            assert comp.constraint_jacobian(q).shape == (0, 6 * comp.nb)


def test_index1_solution_meets_the_acceleration_constraint(monkeypatch, rng):
    """An independent check of the kernel's KKT solve: A V̇ = -γ and V̇ = M⁻¹(Q - Aᵀλ)
    for some λ (the residual M V̇ - Q lies in the range of Aᵀ)."""
    for name in ("chain", "top_and_free_bodies", "heavy_top_joint", "chain_with_load", "joint_graph"):
        m = build(monkeypatch, "numba", name, "quat")
        q, V = random_state(m, rng)
        Vd = m.f(q, V, 0.3)
        A, gam = m.constraint_jacobian(q), m.constraint_gamma(q, V)
        Q = m.forces(q, V, 0.3)
        assert np.abs(A @ Vd + gam).max() <= 1e-10 * max(1.0, np.abs(gam).max())
        r = m.mass_matrix(q) @ Vd - Q
        lam = np.linalg.lstsq(A.T, -r, rcond=None)[0]
        assert np.abs(A.T @ lam + r).max() <= 1e-10 * max(1.0, np.abs(Q).max())


def test_f_returns_a_fresh_array_and_leaves_its_inputs(monkeypatch, rng):
    m = build(monkeypatch, "numba", "chain", "rotvec")
    q1, V1 = random_state(m, rng)
    q2, V2 = random_state(m, rng)
    c1, c2 = q1.copy(), V1.copy()
    a = m.f(q1, V1, 0.0)
    a_copy = a.copy()
    b = m.f(q2, V2, 0.0)
    assert a is not b and np.array_equal(a, a_copy) and not np.array_equal(a, b)
    assert np.array_equal(q1, c1) and np.array_equal(V1, c2)


def test_inputs_of_other_layouts_and_dtypes(monkeypatch, rng):
    """Non-contiguous views, lists and float32 input give the same f (one kernel signature)."""
    ref, comp = build(monkeypatch, "numpy", "springs", "quat"), build(monkeypatch, "numba", "springs", "quat")
    q, V = random_state(ref, rng)
    qq, VV = np.zeros((len(q), 2)), np.zeros((len(V), 2))
    qq[:, 0], VV[:, 0] = q, V
    assert close(comp.f(qq[:, 0], VV[:, 0], 0.0), ref.f(q, V, 0.0))
    assert close(comp.f(list(q), list(V), 0.0), ref.f(q, V, 0.0))
    assert close(comp.f(q.astype(np.float32), V, 0.0), ref.f(q.astype(np.float32).astype(float), V, 0.0))


def test_load_set_after_building(monkeypatch):
    """extremes.failed_steps sets ``model.load`` on a built scene: the kernel path uses it."""
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", "numba")
    m = scenes.free_body()
    base = m.f(m.q0, m.V0, 0.0)
    m.load = lambda t, q, V: (np.array([[1.0, 2.0, 3.0]]), np.zeros((1, 3)))
    assert close(m.f(m.q0, m.V0, 0.0)[3:], base[3:] + [1.0, 2.0, 3.0])
    m.load = lambda t, q, V: (np.full((1, 3), np.nan), np.zeros((1, 3)))
    assert np.isnan(m.f(m.q0, m.V0, 0.0)[3:]).all()
    m.load = None
    assert close(m.f(m.q0, m.V0, 0.0), base)


@pytest.mark.parametrize("method, kw", [("rkmk4", dict(dt=2e-3)), ("dopri5", dict(rtol=1e-9, atol=1e-9))])
@pytest.mark.parametrize("param", ["quat", "rxyz"])
def test_chain_runs_agree_across_backends(monkeypatch, method, kw, param):
    """The chain (joints, projection after every step) simulated on either backend."""
    out = []
    for backend in ("numpy", "numba"):
        monkeypatch.setenv("LGT_BRIDGE_BACKEND", backend)
        m = scenes.chain(5, param=param)
        assert m.compiled == (backend == "numba")
        out.append(simulate(m, (0, 0.1), method=method, t_eval=[0.0, 0.05, 0.1], **kw))
    assert out[0].success and out[1].success
    assert out[0].stats["n_f"] == out[1].stats["n_f"]
    assert close(out[1].q, out[0].q, 1e-12) and close(out[1].V, out[0].V, 1e-12)


def test_numpy_backend_never_imports_numba():
    out = run_python("import sys, lgt_bridge\n"
                      "from lgt_bridge import scenes\n"
                      "m = scenes.chain(3); m.f(m.q0, m.V0, 0.0); m.constraint_jacobian(m.q0)\n"
                      "print('numba' in sys.modules)", LGT_BRIDGE_BACKEND="numpy")
    assert out.strip() == "False"


def test_kernels_run_interpreted():
    """NUMBA_DISABLE_JIT=1: the same source runs as plain Python and agrees, every scene."""
    out = run_python("import os, sys, numpy as np\n"
                      f"sys.path[:0] = [{os.path.dirname(__file__)!r}, {os.path.join(os.path.dirname(os.path.dirname(__file__)), 'models')!r}]\n"
                      "import test_scene_kernels as T\n"
                      "class Env:\n"
                      "    setenv = staticmethod(os.environ.__setitem__)\n"
                      "rng, worst = np.random.default_rng(5), 0.0\n"
                      "for name in T.SCENES:\n"
                      "    a, b = T.build(Env, 'numpy', name, 'rotvec'), T.build(Env, 'numba', name, 'rotvec')\n"
                      "    q, V = T.random_state(a, rng)\n"
                      "    pairs = [(a.f(q, V, 0.5), b.f(q, V, 0.5))]\n"
                      "    if a.n_constraints:\n"
                      "        pairs += [(a.constraints(q), b.constraints(q)),\n"
                      "                  (a.constraint_jacobian(q), b.constraint_jacobian(q)),\n"
                      "                  (a.constraint_gamma(q, V), b.constraint_gamma(q, V))]\n"
                      "    for x, y in pairs:\n"
                      "        worst = max(worst, np.abs(x - y).max() / np.abs(x).max())\n"
                      "print(worst)", NUMBA_DISABLE_JIT="1")
    assert float(out) <= 1e-13
