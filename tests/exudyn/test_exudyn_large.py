"""The Exudyn adapter's paths for large models against independent references: the ODE2
right-hand side's Jacobians by coloured central differences (lgt_exudyn.iteration) against
differences of Exudyn's Q_e column by column; the analysis refuses a pattern that misses a
coupling; generalized-α's sparse Newton parts against the dense ones from Exudyn's own
Jacobian; A as a sparse matrix and M̄⁻¹ from its blocks against the dense ones; and a
generalized-α run on the sparse paths against the same run on the dense ones."""
import warnings

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_exudyn import iteration, scenes  # noqa: E402
from lgt_exudyn.kernel_tables import sparse_inverse  # noqa: E402
from lgt_exudyn.model import ExudynModel  # noqa: E402

import exudyn_models as em  # noqa: E402

MODELS = {
    "revolute chain EP": lambda: scenes.chain(5, em.EP, joint="revolute"),
    "spring-loaded body EP": lambda: em.spring_body_with_load(em.EP),
    "spring-loaded body RotVecLG": lambda: em.spring_body_with_load(em.ROTVEC),
    "top with a point mass on a spring": lambda: em.mixed_with_point_mass(em.ROTVEC),
}


def model(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ExudynModel(MODELS[name]()[1])


def column_differences(m, q, qd, t, wrt, eps=1e-6):
    """∂Q_e/∂q_e (wrt 'q') or ∂Q_e/∂q̇_e ('qd') column by column (central differences)."""
    S = m.solver

    def Q(q, qd):
        m.engine.write(q, qd, t)
        S.ComputeODE2RHS(m.mbs)
        return np.array(S.GetSystemResidual())[:m.n2]
    J = np.empty((m.n2, m.n2))
    for j in range(m.n2):
        e = np.zeros(m.n2)
        e[j] = eps * max(1.0, abs((q if wrt == "q" else qd)[j]))
        if wrt == "q":
            J[:, j] = (Q(q + e, qd) - Q(q - e, qd)) / (2 * e[j])
        else:
            J[:, j] = (Q(q, qd + e) - Q(q, qd - e)) / (2 * e[j])
    return J


@pytest.mark.parametrize("name", list(MODELS))
def test_coloured_jacobians_equal_column_differences(name, rng):
    m = model(name)
    cj = iteration.ColouredJacobian(m)
    q = m._moved(m.q0, rng.normal(size=m.nv) * 0.3, 1.0)
    qd = m.H(q) @ (rng.normal(size=m.nv) * 2.0)
    Jq, Jv = cj.jacobians(q, qd, 0.3)
    for J, wrt in ((Jq, "q"), (Jv, "qd")):
        ref = column_differences(m, q, qd, 0.3, wrt)
        # both are differences with errors ~1e-10 of the largest entry
        assert np.abs(J.toarray() - ref).max() <= 1e-7 * max(1.0, np.abs(ref).max())
    assert cj.check(q, qd, 0.3)
    # fewer groups than coordinates wherever bodies do not interact
    if name == "revolute chain EP":
        assert len(cj.groups) == 7 < m.n2


def test_a_coupling_the_pattern_misses_fails_the_analysis():
    """A load on the last body whose user function reads the first body's position couples
    them outside every object's coordinates (Exudyn's own Jacobian misses it too): the
    check of one column per group against its own difference sees it."""
    from exudyn.utilities import LoadForceVector, MarkerBodyPosition
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    b0 = mbs.CreateRigidBody(inertia=em.RigidBodyInertia(mass=1.0, inertiaTensor=np.diag([0.1, 0.2, 0.3])),
                             referencePosition=[0, 0, 0], gravity=[0, 0, 0])
    b1 = mbs.CreateRigidBody(inertia=em.RigidBodyInertia(mass=1.0, inertiaTensor=np.diag([0.1, 0.2, 0.3])),
                             referencePosition=[1, 0, 0], gravity=[0, 0, 0])
    n0 = mbs.GetObject(b0)["nodeNumber"]
    mk = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b1, localPosition=[0, 0, 0]))

    def pull(mbs, t, load):
        x = mbs.GetNodeOutput(n0, exu.OutputVariableType.Position)
        return [-10.0 * x[0], 0.0, 0.0]
    mbs.AddLoad(LoadForceVector(markerNumber=mk, loadVector=[0, 0, 0], loadVectorUserFunction=pull))
    mbs.Assemble()
    m = ExudynModel(mbs)
    cj = iteration.ColouredJacobian(m)
    assert not cj.check(m.q0 + 0.01, np.zeros(m.n2), 0.0)


@pytest.mark.parametrize("name", ["revolute chain EP", "spring-loaded body RotVecLG"])
def test_sparse_iteration_parts_equal_the_dense_ones(name, rng, monkeypatch):
    """M̄ and C_t from the coloured Jacobians equal the dense ones from Exudyn's to the
    differences' error; K_t to Exudyn's own approximation of ∂Q_e/∂q_e (it leaves terms
    out on springs: 5e-4 of its largest entry measured)."""
    monkeypatch.setattr(iteration, "COLOURED_MIN", 0)
    m = model(name)
    q = m._moved(m.q0, rng.normal(size=m.nv) * 0.3, 1.0)
    V, t = rng.normal(size=m.nv), 0.2
    sparse = [m.iteration_matrix(q, V, t, *c, sparse=True) for c in ((1, 0, 0), (0, 1, 0), (0, 0, 1))]
    assert m._coloured is not None and m._coloured.agrees
    dense = [m.iteration_matrix(q, V, t, *c) for c in ((1, 0, 0), (0, 1, 0), (0, 0, 1))]
    for S, D, tol in zip(sparse, dense, (1e-13, 1e-7, 2e-3)):
        assert np.abs(S.toarray() - D).max() <= tol * max(1.0, np.abs(D).max())


def test_sparse_rows_and_block_inverse_equal_the_dense_ones(rng):
    m = model("revolute chain EP")
    q = m._moved(m.q0, rng.normal(size=m.nv) * 0.3, 1.0)
    A = m.constraint_jacobian(q, sparse=True)
    assert hasattr(A, "tocsr")
    assert np.abs(A.toarray() - m.constraint_jacobian(q)).max() <= 1e-15
    Mi = sparse_inverse(m.Mbar)
    assert np.abs(Mi.toarray() - np.linalg.inv(m.Mbar)).max() <= 1e-12 * np.abs(Mi).max()


def test_genalpha_on_the_sparse_paths_matches_the_dense_paths(monkeypatch):
    """A 40-body revolute chain (nv + nc = 440: sparse Newton matrix, sparse A and M̄⁻¹,
    coloured Jacobians) against the same run with every large-model path off."""
    from lgt_exudyn import model as em_model

    def run():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = ExudynModel(scenes.chain(40, em.EP, joint="revolute")[1])
        r = simulate(m, (0.0, 0.05), method="genalpha", group="SO3xR3", chart="exp", dt=2e-3)
        assert r.success, r.message
        return r, m
    monkeypatch.setattr(iteration, "COLOURED_MIN", 0)
    fast, m = run()
    # (the constant M̄ keeps generalized-α's residual in forces: products with M̄, no M̄⁻¹)
    assert m._coloured is not None and m._coloured.agrees and m._Mbar_inv is None
    assert hasattr(m.constant_mass, "tocsr")
    monkeypatch.setattr(iteration, "COLOURED_MIN", 10 ** 9)
    monkeypatch.setattr(em_model, "SPARSE_INVERSE_MIN", 10 ** 9)
    monkeypatch.setattr(em_model.ExudynModel, "constraint_jacobian",
                        lambda self, q: em_model.ExudynModel._jacobian2(self, q))
    slow, m = run()
    assert m._coloured is None
    assert fast.stats["n_steps"] == slow.stats["n_steps"]
    assert np.abs(fast.q[-1] - slow.q[-1]).max() < 1e-9 * np.abs(slow.q[-1]).max()
    assert np.abs(fast.V[-1] - slow.V[-1]).max() < 1e-7 * np.abs(slow.V[-1]).max()


def test_coordinate_constraints_are_constant_rows(rng):
    """A pinned ANCF cable (two CoordinateConstraints): A is read from Exudyn once (the same
    at every analysis state, γ = 0; constant_constraint_jacobian says so on the compiled
    backend); f and A equal the numpy backend's at moved states."""
    from lgt_exudyn import kernels as K
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        SC, mbs = scenes.ancf_pendulum(4)
        m = ExudynModel(mbs)
        ref = ExudynModel(mbs, backend="numpy")
    P = K.pack(m)
    assert P.sp is not None and P.sp.constant and P.sp.joints is None
    # says so to generalized-α, which then reads A once; a chain's revolute joints do not
    assert m.constant_constraint_jacobian and not ref.constant_constraint_jacobian
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert not ExudynModel(scenes.chain(3, joint="revolute")[1]).constant_constraint_jacobian
    for _ in range(2):
        q = m.q0 + 0.05 * rng.normal(size=m.n2)
        V = rng.normal(size=m.nv)
        assert np.abs(m.f(q, V, 0.1) - ref.f(q, V, 0.1)).max() <= 1e-9 * max(1.0, np.abs(ref.f(q, V, 0.1)).max())
        assert np.abs(m.constraint_jacobian(q) - ref.constraint_jacobian(q)).max() <= 1e-15


def test_ancf_genalpha_in_forces_equals_the_numpy_backend():
    """The pinned ANCF cable (104 vector coordinates, constant M̄): generalized-α keeps its
    residual in forces and runs its Newton updates in one kernel (sparse LU factors solved
    inside) on the compiled backend; 20 steps equal the numpy backend's (M̄ products and
    SuperLU's own solves) to rounding, and Newton ended on its tolerance, not on a failure."""
    runs = []
    for backend in ("numba", "numpy"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = ExudynModel(scenes.ancf_pendulum()[1], backend=backend)
        r = simulate(m, (0.0, 0.02), method="genalpha", dt=1e-3)
        assert r.success, r.message
        runs.append(r)
    fast, ref = runs
    assert fast.stats["n_steps"] == ref.stats["n_steps"] == 20
    assert np.abs(fast.q[-1] - ref.q[-1]).max() <= 1e-11 * np.abs(ref.q[-1]).max()
    assert np.abs(fast.V[-1] - ref.V[-1]).max() <= 1e-8 * max(1.0, np.abs(ref.V[-1]).max())


@pytest.mark.parametrize("elements", [6, 20])          # 30 unknowns: dense J; 86: sparse (CSC)
def test_ancf_genalpha_matrix_is_the_jacobian_of_its_residual(elements):
    """On vector coordinates only the Newton matrix is the model's M̄ + s_v C_t + s_p K_t with
    A's rows and columns (one iteration_matrix call; Exudyn's Jacobians indexed without H):
    against central differences of the stepper's residual in (Ẇ, λ). Exudyn's ANCF Jacobians
    are its own numerical differences (relative step 1e-7), hence 1e-5 of the largest entry;
    a wrong coefficient (s_v, s_p or k) is off by O(1)."""
    from lgt_bridge.simulate import make_stepper
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = ExudynModel(scenes.ancf_pendulum(elements)[1])
    h = 1e-3
    ga, _ = make_stepper(m, "genalpha", "SO3xR3", "exp", dt=h)
    ga.set_state(m.q0, m.V0)
    t = 0.0
    for _ in range(5):
        ga.attempt(t, h)
        t += h
    assert ga._Mc is not None and not ga.accel_form
    Wd1, lam = ga.Wd.copy(), ga.lam.copy()
    J = ga.iteration_matrix(Wd1, lam, t + h, h)
    z, n = np.concatenate([Wd1, lam]), len(Wd1)
    cols = []
    for j in range(len(z)):
        e = 1e-3 * max(1.0, abs(z[j]))
        zp, zm = z.copy(), z.copy()
        zp[j] += e
        zm[j] -= e
        cols.append((ga.residual(zp[:n], zp[n:], t + h, h) - ga.residual(zm[:n], zm[n:], t + h, h)) / (2 * e))
    Jfd = np.array(cols).T
    assert np.abs(J - Jfd).max() <= 1e-5 * np.abs(J).max(), np.abs(J - Jfd).max() / np.abs(J).max()
