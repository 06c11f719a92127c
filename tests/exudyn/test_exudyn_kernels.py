"""The compiled kernels of the Exudyn adapter (lgt_exudyn.kernels) against ExudynModel's
numpy methods, on real Exudyn models: EP, RotVecLG and Rxyz nodes (Rxyz away from gimbal
lock), mixed with a point mass, a spring-loaded body, a revolute chain, bodies with the
node off the centre of mass (configuration-dependent M̄) and free bodies. Each kernel is
equal to its reference to 1e-13 relative; the assembled f (kernels + Exudyn calls, with the
γ finite differences) to 1e-9, since a last-bit difference of the moved state is divided
by the 1e-5 difference step. Skipped only when exudyn is not installed."""
import numba
import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from exudyn.utilities import ObjectGround, RigidBodyInertia  # noqa: E402

from lgt_bridge.model import solve_kkt  # noqa: E402
from lgt_exudyn import kernels as K  # noqa: E402
from lgt_exudyn import scenes  # noqa: E402
from lgt_exudyn.model import ExudynModel  # noqa: E402

import exudyn_models as em  # noqa: E402
from backend_checks import close, run_python  # noqa: E402


def offset_com_pendulum(node=em.EP):
    """A body hanging from a spherical joint with its node off the centre of mass: the twist
    mass matrix depends on the rotation (no constant M̄)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    g = mbs.AddObject(ObjectGround())
    inertia = RigidBodyInertia(mass=2.0, inertiaTensor=np.diag([0.1, 0.2, 0.3]), com=[0.0, 0.3, 0.1],
                               inertiaTensorAtCOM=True)
    b = mbs.CreateRigidBody(inertia=inertia, nodeType=node, referencePosition=[0, 1, 0],
                            initialAngularVelocity=[1, 2, 3], gravity=em.G)
    mbs.CreateSphericalJoint(itemNumbers=[g, b], position=[0, 0, 0])
    mbs.Assemble()
    return SC, mbs


MODELS = {
    "top EP": lambda: em.heavy_top(em.EP)[:2],
    "top RotVecLG": lambda: em.heavy_top(em.ROTVEC)[:2],
    "top Rxyz": lambda: em.heavy_top(em.RXYZ)[:2],
    "mixed EP": lambda: em.mixed_with_point_mass(em.EP),
    "mixed Rxyz": lambda: em.mixed_with_point_mass(em.RXYZ),
    "spring RotVecLG": lambda: em.spring_body_with_load(em.ROTVEC),
    "revolute chain Rxyz": lambda: em.chain(3, em.RXYZ, joint="revolute"),
    "offset com EP": lambda: offset_com_pendulum(em.EP),
    "offset com Rxyz": lambda: offset_com_pendulum(em.RXYZ),
    "free EP": lambda: scenes.free_bodies(3, em.EP),
    "tree among masses": lambda: em.tree_with_masses(),
}


@pytest.fixture(scope="module", params=list(MODELS))
def built(request):
    SC, mbs = MODELS[request.param]()
    m = ExudynModel(mbs)
    return SC, m, K.pack(m)


def residual_at(m, q, V, t):
    """Exudyn's full residual vector (ODE2 forces first) at (q, V, t)."""
    m._write(q, m.rates_from_twist(q, V), t)
    m.solver.ComputeODE2RHS(m.mbs)
    return np.array(m.solver.GetSystemResidual())


def test_state_writes_and_moved_state(built, rng):
    SC, m, P = built
    qpos, qvel = np.zeros(m.n2), np.zeros(m.n2)
    for q, V, t in em.random_states(m, rng):
        K.write(P.T, P.off, P.w, q, V, 0.0, qpos, qvel)
        assert close(qpos, q - m.ref) and close(qvel, m.rates_from_twist(q, V))
        assert close(qvel, m.H(q) @ V)
        assert K.write(P.T, P.off, P.w, q, V, 0.0, qpos, qvel) == 0.0
        for eps in (1e-5, -1e-5, 2.5):
            h = K.write(P.T, P.off, P.w, q, V, eps, qpos, qvel)
            assert h == eps / max(1.0, np.abs(V).max())
            qm = m._moved(q, V, h)
            assert close(P.qm, qm)
            assert close(qpos, qm - m.ref) and close(qvel, m.rates_from_twist(qm, V))


def test_forces_constraint_matrix_and_solve(built, rng):
    SC, m, P = built
    nv = m.nv
    for q, V, t in em.random_states(m, rng):
        Mb, Qb, A, gam = m._evaluate(q, V, t)
        H = m.H(q)
        R = residual_at(m, q, V, t)
        Q = R[:m.n2]
        # the general case: Q̄ = Hᵀ(Q - M Ḣ V), M̄ = Hᵀ M H
        m.solver.ComputeMassMatrix(m.mbs)
        M = np.array(m.solver.GetSystemMassMatrix())
        Qg, Mg = np.zeros(nv), np.zeros((nv, nv))
        K.forces(P.T, P.off, P.w, q, V, R, M, Qg, Mg)
        assert close(Qg, H.T @ (Q - M @ m.Hdot_V(q, V))) and close(Mg, H.T @ M @ H)
        Qbar = np.zeros(nv)
        if P.constant_mass:
            K.forces(P.T, P.off, P.w, q, V, R, P.empty, Qbar, P.empty)
            assert close(Qbar, Qb)
        else:
            assert close(Qg, Qb) and close(Mg, Mb)
        Vd = np.zeros(nv)
        Mpass = P.empty if P.constant_mass else Mb

        def solve(A_, g_):
            return K.solve(P.T, P.off, P.w, Mpass, A_, Qb, g_, Vd)
        if A is None:
            assert solve(np.zeros((0, nv)), np.zeros(0)) == 0
            assert close(Vd, np.linalg.solve(Mb, Qb))
            continue
        # A from the AE rows alone and from Exudyn's whole system Jacobian
        m.sd.SetODE2Coordinates(q - m.ref)
        C = np.ascontiguousarray(m._Cq())
        A1, A2 = np.zeros(A.shape), np.zeros(A.shape)
        K.constraint_matrix(P.T, P.off, P.w, q, C, np.arange(len(C), dtype=np.int64), A1)
        S = m.solver
        S.SetSystemJacobian(m._jac_zero)
        S.ComputeJacobianAE(m.mbs, 1.0, 1.0 if len(m.velocity_rows) else 0.0, 0.0, False)
        K.constraint_matrix(P.T, P.off, P.w, q, S.GetSystemJacobian(), P.rows, A2)
        assert close(A1, A) and close(A2, A) and close(A1, C @ H)
        assert solve(A, gam) == 0
        assert close(Vd, solve_kkt(Mb, A, Qb, -gam)[0])
        assert close(A @ Vd, -gam, tol=1e-10)


def test_a_configuration_dependent_mass_matrix_is_factorized_within_its_row_envelope(rng):
    """A KinematicTree among point masses (Exudyn's serialRobotKinematicTreeDigging.py in
    small): M̄ depends on q, so the kernel factorizes it at every f; it does so within M̄'s row
    envelope (row_envelope), which is that of its blocks: the point masses' rows hold their
    diagonal only. The solve equals numpy's (with and without the constraint row)."""
    from lgt_exudyn.kernel_solve import row_envelope
    SC, mbs = em.tree_with_masses(4)
    m = ExudynModel(mbs)
    P = K.pack(m)
    assert not P.constant_mass
    for q, V, t in em.random_states(m, rng):
        Mb, Qb, A, gam = m._evaluate(q, V, t)
        env = row_envelope(np.ascontiguousarray(Mb))
        rows = np.arange(m.nv)
        expect = np.array([min(np.flatnonzero(Mb[i, :i + 1])) for i in rows])
        assert np.array_equal(env, expect) and (rows - env).max() == 1    # the tree's 2 x 2 block
        Vd = np.zeros(m.nv)
        assert K.solve(P.T, P.off, P.w, np.ascontiguousarray(Mb), A, Qb, gam, Vd) == 0
        assert close(Vd, solve_kkt(Mb, A, Qb, -gam)[0])
        assert K.solve(P.T, P.off, P.w, np.ascontiguousarray(Mb), np.zeros((0, m.nv)), Qb, np.zeros(0), Vd) == 0
        assert close(Vd, np.linalg.solve(Mb, Qb))
        assert close(K.f_compiled(m, P, q, V, t), m.f(q, V, t), 1e-9)


def test_gamma_difference(rng):
    rp, rm = rng.normal(size=12), rng.normal(size=12)
    rows = np.array([9, 3, 4], np.int64)
    gam = np.zeros(3)
    K.gamma_fd(rp, rm, rows, 1e-5, gam)
    assert close(gam, (rp[rows] - rm[rows]) / (2 * 1e-5))


def test_f_compiled_equals_f_and_leaves_the_evaluated_state(built, rng):
    SC, m, P = built
    tol = 1e-13 if not m.n_constraints else 1e-9     # γ: finite differences over 2e-5
    for q, V, t in em.random_states(m, rng):
        ref = m.f(q, V, t)
        n = m.n_eval
        mine = K.f_compiled(m, P, q, V, t)
        assert m.n_eval == n + 1
        assert close(mine, ref, tol)
        assert close(m.sd.GetODE2Coordinates(), q - m.ref)
        assert close(m.sd.GetODE2Coordinates_t(), m.rates_from_twist(q, V))
        assert m.sd.GetTime() == t



def test_compiled_forces_and_iteration_matrix_equal_the_numpy_backend(built, rng):
    """ExudynModel.forces (the kernels' Q̄, one state write) and generalized-α's
    iteration_matrix (Exudyn's Jacobians mapped to twists, M̄ from the kernels) against the
    same model wrapped on the numpy reference backend, at random states."""
    SC, m, P = built
    ref = ExudynModel(m.mbs, backend="numpy")
    assert m._compiled and not ref._compiled
    for q, V, t in em.random_states(m, rng, n=2):
        assert close(m.forces(q, V, t), ref.forces(q, V, t), 1e-13)
        # Rxyz nodes' ω columns of C_t are differences of the forces (1e-13 apart) over a 1e-6 step
        cols = m.nodes.types["RigidBodyRxyz"][1].ravel() if "RigidBodyRxyz" in m.nodes.types else []
        for c in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)):
            A, B = m.iteration_matrix(q, V, t, *c), ref.iteration_matrix(q, V, t, *c)
            if c[1] and len(cols):
                assert close(A[:, cols], B[:, cols], 1e-6)
                A, B = np.delete(A, cols, 1), np.delete(B, cols, 1)
            assert close(A, B, 1e-12)

def test_bound_forces_and_constraints_equal_the_numpy_backend(built, rng):
    """forces_and_constraints_function (lgt_exudyn.iteration.residual_function on the compiled
    path with a constant M̄: one residual read for Q̄ and g, g empty without constraints) and
    forces_and_constraints itself against the numpy reference backend's forces and
    constraints_at, at random states; elsewhere the function is the method itself."""
    from lgt_exudyn.iteration import residual_function
    SC, m, P = built
    ref = ExudynModel(m.mbs, backend="numpy")
    fast = residual_function(m)
    assert residual_function(ref) is None
    if not P.constant_mass or m.ode1 is not None:
        assert fast is None
        assert m.forces_and_constraints_function() == m.forces_and_constraints
        return
    assert fast is not None and m.forces_and_constraints_function() is fast
    for q, V, t in em.random_states(m, rng, n=2):
        Q, g = ref.forces(q, V, t), ref.constraints_at(q, t)
        n = m.n_eval
        for got in (fast(q, V, t), m.forces_and_constraints(q, V, t)):
            assert close(got[0], Q, 1e-13)
            assert len(got[1]) == len(g) == m.n_constraints
            assert np.abs(got[1] - g).max(initial=0.0) <= 1e-13 * max(1.0, np.abs(q).max())
        assert m.n_eval == n + 2


SPECIAL = {"driven cart, ∂g/∂t from Exudyn": ("driven_cart_pendulum", {}),
           "driven cart, ∂g/∂t by the bridge": ("driven_cart_pendulum", {"with_t": False}),
           "moving frame": ("moving_frame_pendulum", {}),
           "rolling coin (velocity-level rows)": ("rolling_coin", {}),
           "ANCF cable": ("ancf_cable2d", {}),
           "kinematic tree (configuration-dependent M̄)": ("kinematic_tree_pendulum", {})}


@pytest.mark.parametrize("case", list(SPECIAL))
def test_f_compiled_on_special_models(case, rng):
    """Time-dependent and velocity-level constraints, 2-D and flexible coordinates."""
    import warnings

    import exudyn_special_models as sm
    name, kw = SPECIAL[case]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mbs = getattr(sm, name)(**kw)[0]
        m = ExudynModel(mbs)
    P = K.pack(m)
    for q, V, t in em.random_states(m, rng, 2):
        V = V * 0.2
        assert close(K.f_compiled(m, P, q, V, t), m.f(q, V, t), 1e-9)


@pytest.mark.parametrize("dense", [False, True], ids=["constant M̄", "dense M̄"])
def test_redundant_rows_fall_back_to_the_minimum_norm_solve(dense, rng):
    SC, mbs = offset_com_pendulum() if dense else em.heavy_top(em.EP)[:2]
    m = ExudynModel(mbs)
    P = K.pack(m, nc_max=5)
    q, V, t = em.random_states(m, rng, 1)[0]
    Mb, Qb, A, gam = m._evaluate(q, V, t)
    A2 = np.ascontiguousarray(np.vstack([A, A[:2]]))     # rows 3, 4 repeat rows 0, 1
    g2 = np.concatenate([gam, gam[:2]])
    Vd = np.zeros(m.nv)
    flag = K.solve(P.T, P.off, P.w, Mb if dense else P.empty, A2, Qb, g2, Vd)
    assert flag == 1
    K.solve_fallback(P, 5, Vd)
    assert close(Vd, solve_kkt(Mb, A2, Qb, -g2)[0])
    assert close(Vd, solve_kkt(Mb, A, Qb, -gam)[0], 1e-10)


def test_bad_arguments_raise():
    SC, mbs = em.heavy_top(em.EP)[:2]
    m = ExudynModel(mbs)
    P = K.pack(m)
    q, V, nv, z = m.q0.copy(), m.V0.copy(), m.nv, np.zeros(m.n2)
    with pytest.raises(ValueError):
        K.write(P.T, P.off, P.w, q[:-1], V, 0.0, z, z.copy())
    with pytest.raises(ValueError):                         # more rows than packed
        K.solve(P.T, P.off, P.w, P.empty, np.zeros((4, nv)), np.zeros(nv), np.zeros(4), np.zeros(nv))
    with pytest.raises(ValueError):                         # constant M̄ packed: no room for a dense factor
        K.solve(P.T, P.off, P.w, np.eye(nv), P.A0, np.zeros(nv), P.gam0, np.zeros(nv))
    Pd = K.pack(ExudynModel(offset_com_pendulum()[1]))
    with pytest.raises(ValueError):                         # no constant M̄ packed
        K.solve(Pd.T, Pd.off, Pd.w, Pd.empty, Pd.A0, np.zeros(nv), Pd.gam0, np.zeros(nv))
    with pytest.raises(ValueError):
        K.forces(Pd.T, Pd.off, Pd.w, q, V, np.zeros(m.n2), Pd.empty, np.zeros(nv), Pd.empty)
    if not numba.config.DISABLE_JIT:
        with pytest.raises(TypeError):                      # explicit signatures: no new specializations
            K.write(P.T, P.off, P.w, q.astype(np.float32), V, 0.0, z, z.copy())


def test_interpreted_kernels_give_the_same_f():
    """NUMBA_DISABLE_JIT=1 runs the same source as plain Python."""
    code = (
        "import sys, numpy as np\n"
        "sys.path[:0] = ['tests/models', 'adapters']\n"
        "import exudyn_models as em\n"
        "from lgt_exudyn.model import ExudynModel\n"
        "from lgt_exudyn import kernels as K\n"
        "for make in (lambda: em.mixed_with_point_mass(em.RXYZ), lambda: em.heavy_top(em.EP)[:2]):\n"
        "    m = ExudynModel(make()[1]); P = K.pack(m)\n"
        "    q = m._moved(m.q0, np.linspace(-0.3, 0.4, m.nv), 1.0); V = np.linspace(1, -2, m.nv)\n"
        "    a, b = K.f_compiled(m, P, q, V, 0.2), m.f(q, V, 0.2)\n"
        "    print(np.abs(a - b).max() / np.abs(b).max())\n")
    import os
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    out = run_python(f"import os; os.chdir({root!r})\n" + code, NUMBA_DISABLE_JIT="1")
    errs = [float(x) for x in out.split()]
    assert len(errs) == 2 and max(errs) < 1e-9


@pytest.mark.parametrize("name", ["free EP", "spring RotVecLG", "top EP"])
def test_plain_f_of_unconstrained_models(name, rng):
    """Models with a constant M̄, unconstrained or with joints whose rows are in closed form
    (the top's spherical joint), get the kernels' closure as f (unconstrained: forces and
    solve fused in free_rhs): equal to the numpy reference to 1e-13 (1e-9 with a joint, whose
    reference γ is a difference) and to f_compiled to rounding, leaving the evaluated state
    in Exudyn; reset_caches drops the closure with the pack."""
    SC, mbs = MODELS[name]()
    m = ExudynModel(mbs)
    ref = ExudynModel(MODELS[name]()[1], backend="numpy")
    m.f(m.q0, m.V0, 0.0)                                     # builds the pack (and the closure)
    P = m._P
    assert "f" in m.__dict__ and (not m.n_constraints or P.sp.joints is not None)
    for q, V, t in em.random_states(m, rng):
        n = m.n_eval
        mine = m.f(list(q), V[::1], t)                       # any array-like is accepted
        assert m.n_eval == n + 1
        assert close(mine, ref.f(q, V, t), 1e-13 if not m.n_constraints else 1e-9)
        assert close(mine, K.f_compiled(m, P, q, V, t), 1e-14)
        m.f(q, V, t)
        assert close(m.sd.GetODE2Coordinates(), q - m.ref)
        assert close(m.sd.GetODE2Coordinates_t(), m.rates_from_twist(q, V))
        assert m.sd.GetTime() == t
    m.reset_caches()
    assert "f" not in m.__dict__ and m._P is None
