"""Generalized-α's Newton updates on small Exudyn models with a constant mass matrix in one
kernel: a dense LU of at most DENSE_MAX unknowns solved inside the fused update
(``ga_force_newton_dense``), or J⁻¹ by blocks as a CSR product (``ga_force_newton_csr``);
the residual in forces without constraints as well;
and A(q) without writing the state again
(``constraint_jacobian_function``). References: the numpy backend's run of the same script
(the residual rows of ``GenAlpha._force_rows``, scipy's LU), the model's own
``constraint_jacobian``, and ``np.add.at`` for the dense A of a pattern."""
import warnings

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.integrators import genalpha_newton  # noqa: E402
from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_exudyn import scenes  # noqa: E402
from lgt_exudyn.model import ExudynModel  # noqa: E402

import exudyn_solver_models as sm  # noqa: E402
import exudyn_special_models as esm  # noqa: E402


def _model(build, backend):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ExudynModel(build()[0], backend=backend)


@pytest.mark.parametrize("name,build,solver", [
    ("pendulum (EP node, revolute joint)", sm.pendulum, "dense"),
    ("3-link chain (EP nodes, spherical joints)", lambda: sm.rigid_chain(n=3, t_end=0.1, steps=50), "dense"),
    ("stiff spring chain (5 mass points, no constraints)", lambda: sm.stiff_spring_chain(damping=1e5), "dense"),
    ("12 free RotVecLG bodies (J inverted block by block)", lambda: (scenes.free_bodies(12)[1],), "csr"),
])
def test_the_fused_newton_updates_run_the_numpy_backends_steps(name, build, solver, monkeypatch):
    """50 steps of 2 ms through the compiled backend, whose updates run in one fused kernel
    (the dense-LU one, or the block inverse's CSR product; counted), against the numpy
    backend's residual and solves: the same states to rounding, the same number of updates."""
    calls = []
    kernels = list(genalpha_newton._KERNELS or genalpha_newton._kernels())

    def counted(k):
        def kernel(*args):
            calls.append(k)
            return kernels[k](*args)
        return kernel
    monkeypatch.setattr(genalpha_newton, "_KERNELS", [counted(k) for k in range(len(kernels))])
    fast = simulate(_model(build, "numba"), (0.0, 0.1), method="genalpha", dt=2e-3)
    assert len(calls) == fast.stats["n_newton"] > 50, (len(calls), fast.stats)
    assert set(calls) == {{"dense": 1, "csr": 2}[solver]}
    monkeypatch.setenv("LGT_BRIDGE_BACKEND", "numpy")       # the reference: no kernel anywhere
    ref = simulate(_model(build, "numpy"), (0.0, 0.1), method="genalpha", dt=2e-3)
    assert len(calls) == fast.stats["n_newton"]
    assert fast.success and ref.success
    assert fast.stats["n_newton"] == ref.stats["n_newton"]
    assert np.abs(fast.q[-1] - ref.q[-1]).max() <= 1e-12 * max(1.0, np.abs(ref.q[-1]).max())
    assert np.abs(fast.V[-1] - ref.V[-1]).max() <= 1e-10 * max(1.0, np.abs(ref.V[-1]).max())


@pytest.mark.parametrize("name,build", [
    ("3-link chain: spherical joints' rows in closed form", lambda: sm.rigid_chain(n=3)),
    ("RigidBody2D double pendulum: Exudyn's AE Jacobian of JointRevolute2D", esm.rigid2d_double_pendulum),
])
def test_the_bound_jacobian_is_the_models_constraint_jacobian(name, build, rng):
    """``constraint_jacobian_function`` at states off the motion, each written first as its
    caller (the fused Newton update) writes it: equal to ``constraint_jacobian`` (which writes
    the state itself and goes through the model's checks) and, for closed-form rows, to A
    scattered by np.add.at from its pattern."""
    m = _model(build, "numba")
    jac = m.constraint_jacobian_function()
    assert jac != m.constraint_jacobian                  # (the bound function, not the method)
    sp = m._pack().sp
    for _ in range(3):
        q = m.q0 + 0.1 * rng.normal(size=len(m.q0))
        V = rng.normal(size=m.nv)
        m.forces_and_constraints(q, V, 0.1)
        A = jac(q)
        assert np.array_equal(A, m.constraint_jacobian(q))
        if sp is not None and sp.joints is not None:
            ref = np.zeros_like(A)
            np.add.at(ref, (sp.rows, sp.acol), sp.aval)
            assert np.array_equal(A, ref)


def test_without_constraints_the_residual_in_forces_takes_the_acceleration_forms_steps(monkeypatch):
    """A constant M̄ and no constraints: generalized-α's residual in forces, M̄ Ẇ - Q (the fused
    kernel's), against the residual in accelerations, Ẇ - M̄⁻¹Q with the matrix J⁻¹M̄ (the
    path taken when the model gives no constant mass matrix). Newton's updates are the same in
    exact arithmetic, so are the steps: the same updates and matrices, states to rounding."""
    runs = []
    for form in ("forces", "accelerations"):
        if form == "accelerations":
            monkeypatch.setattr(ExudynModel, "constant_mass", property(lambda self: None))
        runs.append(simulate(_model(lambda: sm.stiff_spring_chain(damping=1e5), "numba"), (0.0, 0.2),
                             method="genalpha", dt=1e-2))
    forces, accel = runs
    assert forces.success and accel.success
    for count in ("n_newton", "n_jacobians"):
        assert forces.stats[count] == accel.stats[count]
    assert np.abs(forces.q[-1] - accel.q[-1]).max() <= 1e-12 * max(1.0, np.abs(accel.q[-1]).max())
    assert np.abs(forces.V[-1] - accel.V[-1]).max() <= 1e-9 * max(1.0, np.abs(accel.V[-1]).max())
