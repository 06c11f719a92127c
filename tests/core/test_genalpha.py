"""Generalized-α's analytic, block-sparse Newton iteration matrix (issue 10 §3).

The reference for the matrix is its defining identity: the Jacobian of the Newton
residual with respect to the unknowns (Ẇ_{k+1}, λ), by central differences of
:meth:`GenAlpha.residual`. Tolerances (relative to max |J| ≈ 1 … 6 in these cases):

* central differences with step e = 1e-2·max(1, |z_j|) are exact for the parts of the
  residual that are quadratic in the unknowns (the velocity terms are; q moves by only
  h²βk·e ≈ 3e-9), so their truncation error is far below 1e-9;
* rounding: a residual row of size |r_i| is differenced to eps·|r_i|/e. The dynamic rows
  are O(1 … 1e3): ≤ 1e-11. The constraint rows g/(h²β) carry the rounding of q (≈ eps)
  amplified by 1/(h²β) ≈ 3.6e6 at h = 1e-3: eps·3.6e6/e ≈ 1e-7 — hence 1e-9 for the
  dynamic rows and 1e-6 for the constraint rows.

The matrix is exact at the solution of the step. Away from it the SE(3) rows, which the
residual turns into the body frame with the iterate's R, add (∂Rᵀ) r: a term that is
proportional to the residual and vanishes with it (tested below); T(ΔX) = dψ_{-ΔX} is
exact (no T ≈ I).
"""
import subprocess
import sys

import numpy as np
import pytest

from lgt_bridge import params, scenes, simulate
from lgt_bridge.groups import quaternion as _q
from lgt_bridge.groups._vec import hat
from lgt_bridge.integrators import genalpha as ga_mod
from lgt_bridge.integrators import genalpha_matrix as gm
from lgt_bridge.integrators.local import LocalProblem
from lgt_bridge.model import Layout, Model, RigidBody
from lgt_bridge.simulate import make_stepper

H = 1e-3
GROUPS_CHARTS = [(g, c) for g in ("SE3", "SO3xR3") for c in ("exp", "cay")]


# --- models -----------------------------------------------------------------------------
def jointed_springs():
    """Two links on spherical joints (to ground, to each other) and a third body held by
    damped springs to link 1 and to ground: joints, springs with damping, all moving."""
    J = np.diag([0.1, 0.2, 0.3])
    unit = [1.0, 0.0, 0.0, 0.0]
    q0 = np.concatenate([[0.5, 0, 0], unit, [1.5, 0, 0], unit, [2.5, 0.1, 0], unit])
    V0 = np.array([0.3, 1, 0.2, 0, 0.5, 0.0, 0.1, 0, 2, 0, 1.5, 0.0, 1, 0.5, 0, 0.2, 0, 0.3])
    half = np.array([0.5, 0.0, 0.0])
    return scenes.RigidBodySystem(
        [1.0, 2.0, 1.5], [J, 2 * J, 1.5 * J], q0, V0,
        joints=[(0, -half, -1, np.zeros(3)), (1, -half, 0, half)],
        springs=[(1, half, 2, -half, 500.0, 2.0), (2, np.array([0.2, 0.1, 0]), -1, np.array([3, 0, 1.0]), 100.0, 0.5)])


class SpinnerOnSpring(Model):
    """A rotation-only rigid body (3 unknowns) and a vector-space coordinate x coupled both
    ways: torque (1 + x) s × RᵀG and force -k x - c ẋ + α (R e)_z."""

    J = np.diag([1.0, 2.0, 3.0])
    s, G, e = np.array([0.0, 0.3, 0.1]), np.array([0.0, 0.0, -5.0]), np.array([1.0, 0.0, 0.0])
    mx, k, c, alpha = 2.0, 50.0, 0.4, 3.0

    def __init__(self, param="quat"):
        self.p = params.get(param)
        nr = self.p.nrot
        self.rot = list(range(nr))
        self.layout = Layout(nr + 1, 4, [RigidBody(self.p, (), tuple(self.rot), (0, 1, 2), "spinner")],
                             (nr,), (3,))
        R0 = _q._to_matrix(_q._from_rotvec(np.array([[0.3, -0.2, 0.5]])))
        self.q0 = np.concatenate([scenes._rot_coords(self.p, R0)[0], [0.1]])
        self.V0 = np.array([0.3, 2.0, 0.1, -0.2])

    def _R(self, q):
        return _q._to_matrix(self.p._to_quat(q[None, self.rot]))[0]

    def mass_matrix(self, q):
        M = np.zeros((4, 4))
        M[:3, :3], M[3, 3] = self.J, self.mx
        return M

    def forces(self, q, V, t):
        R, x, w = self._R(q), q[-1], V[:3]
        torque = -np.cross(w, self.J @ w) + (1 + x) * np.cross(self.s, R.T @ self.G)
        return np.concatenate([torque, [-self.k * x - self.c * V[3] + self.alpha * (R @ self.e)[2]]])

    def iteration_matrix(self, q, V, t, c_acc, c_vel, c_pos):
        R, x, w = self._R(q), q[-1], V[:3]
        out = self.mass_matrix(q) * c_acc
        out[:3, :3] += c_vel * (hat(w[None])[0] @ self.J - hat((self.J @ w)[None])[0])
        out[3, 3] += c_vel * self.c + c_pos * self.k
        S, RtG = hat(self.s[None])[0], R.T @ self.G
        out[:3, :3] -= c_pos * (1 + x) * S @ hat(RtG[None])[0]
        out[:3, 3] -= c_pos * S @ RtG
        out[3, :3] += c_pos * self.alpha * (R @ hat(self.e[None])[0])[2]
        return out


class _ForceForm(scenes.RigidBodySystem):
    """The same scene without its own solve with M: generalized-α then keeps the residual
    in forces, M V̇ - Q + Aᵀλ."""
    solve_mass = Model.solve_mass


def force_form(model):
    model.__class__ = _ForceForm
    return model


CASES = {
    "free_bodies": lambda: scenes.free_bodies(3),
    "pivoted_top": lambda: scenes.heavy_top(False),
    "jointed_top": lambda: scenes.heavy_top(True),
    "chain_with_springs": jointed_springs,
    "jointed_top_force_form": lambda: force_form(scenes.heavy_top(True)),
    "chain_with_springs_force_form": lambda: force_form(jointed_springs()),
    "rotation_only_and_vector": SpinnerOnSpring,
}


# --- helpers ------------------------------------------------------------------------------
def stepper_after(model, group, chart, steps=5):
    """A generalized-α stepper h = 1e-3 that has taken ``steps`` steps (a moving state:
    W, Ẇ, a and q_k away from their initial values); returns it and the time reached."""
    ga, _ = make_stepper(model, "genalpha", group, chart, dt=H)
    ga.set_state(model.q0, model.V0)
    t = 0.0
    for _ in range(steps):
        ga.attempt(t, H)
        t += H
    return ga, t


def solution_of_next_step(ga, t):
    """(Ẇ_{k+1}, λ) solving the next step's residual to rounding: the stepper's own Newton
    solution, polished by full Newton steps with the exact matrix (the stepper stops on
    the size of its Ẇ update and may leave λ less converged); the state is left as it was."""
    snap = (ga.q.copy(), ga.V.copy(), ga.W.copy(), ga.Wd.copy(), ga.a.copy(), ga.lam.copy(), ga._prev)
    ga.attempt(t, H)
    Wd1, lam = ga.Wd.copy(), ga.lam.copy()
    q, V, W, ga.Wd, ga.a, ga.lam, ga._prev = snap
    ga.set_state(q, V, W)
    n = len(Wd1)
    for _ in range(3):
        dz = -np.linalg.solve(ga.iteration_matrix(Wd1, lam, t + H, H), ga.residual(Wd1, lam, t + H, H))
        Wd1, lam = Wd1 + dz[:n], lam + dz[n:]
    return Wd1, lam


def fd_jacobian(ga, Wd1, lam, t1, rel=1e-2):
    """Central differences of the residual in every unknown (Ẇ then λ)."""
    n = len(Wd1)
    z = np.concatenate([Wd1, lam])
    cols = []
    for j in range(len(z)):
        e = rel * max(1.0, abs(z[j]))
        zp, zm = z.copy(), z.copy()
        zp[j] += e
        zm[j] -= e
        cols.append((ga.residual(zp[:n], zp[n:], t1, H) - ga.residual(zm[:n], zm[n:], t1, H)) / (2 * e))
    return np.array(cols).T


# --- the matrix against its defining identity -------------------------------------------
@pytest.mark.parametrize("group,chart", GROUPS_CHARTS + [("SE3", "cay2"), ("SO3xR3", "cay2")])
@pytest.mark.parametrize("case", list(CASES))
def test_iteration_matrix_is_the_jacobian_of_the_residual(case, group, chart):
    m = CASES[case]()
    ga, t = stepper_after(m, group, chart)
    assert ga.analytic and ga.accel_form == (not case.endswith("force_form"))
    Wd1, lam = solution_of_next_step(ga, t)
    r = ga.residual(Wd1, lam, t + H, H)
    assert np.abs(r).max() < 1e-8
    J = ga.iteration_matrix(Wd1, lam, t + H, H)
    Jfd = fd_jacobian(ga, Wd1, lam, t + H)
    n, scale = len(Wd1), np.abs(J).max()
    assert np.abs(J[:n] - Jfd[:n]).max() <= 1e-9 * scale, np.abs(J[:n] - Jfd[:n]).max()
    if m.n_constraints:
        assert np.abs(J[n:] - Jfd[n:]).max() <= 1e-6 * scale, np.abs(J[n:] - Jfd[n:]).max()


@pytest.mark.parametrize("param", ["quat", "rotvec"])
def test_rotation_only_body_and_vector_coordinate_get_their_blocks(param):
    """The spinner has 3 unknowns and x one: the matrix is 4x4 and couples them both ways."""
    ga, t = stepper_after(SpinnerOnSpring(param), "SE3", "cay")
    Wd1, lam = solution_of_next_step(ga, t)
    J = ga.iteration_matrix(Wd1, lam, t + H, H)
    assert J.shape == (4, 4) and np.abs(J[:3, 3]).max() > 0 and np.abs(J[3, :3]).max() > 0
    np.testing.assert_allclose(J, fd_jacobian(ga, Wd1, lam, t + H), rtol=0, atol=1e-9 * np.abs(J).max())


def test_off_the_solution_only_the_se3_frame_term_is_left_out():
    """At Ẇ* + ε δ the SE(3) matrix misses (∂Rᵀ) r, proportional to the residual: halving
    ε halves the difference. SO(3)xR³ has no such term: exact at any point."""
    m = scenes.free_bodies(3)
    gaps = {}
    for group in ("SE3", "SO3xR3"):
        ga, t = stepper_after(m, group, "exp")
        Wd1, lam = solution_of_next_step(ga, t)
        d = np.random.default_rng(0).normal(size=len(Wd1)) * (1 + np.abs(Wd1))
        gaps[group] = []
        for eps in (0.2, 0.1):
            W = Wd1 + eps * d
            gaps[group].append(np.abs(ga.iteration_matrix(W, lam, t + H, H) - fd_jacobian(ga, W, lam, t + H)).max())
    big, small = gaps["SE3"]
    assert big > 1e-8 and abs(big / small - 2.0) < 0.05, gaps
    assert max(gaps["SO3xR3"]) < 1e-11, gaps


def test_scene_damping_and_stiffness_against_finite_differences_of_the_forces():
    """C_t = -∂Q/∂V and K_t = ∂(Aᵀλ - Q)/∂z along τ on SO(3)xR³ (joints' geometric
    stiffness, springs with damping); the sparse form equals the dense one."""
    m = jointed_springs()
    rng = np.random.default_rng(7)
    prob = LocalProblem(m, "SO3xR3", "exp")
    prob.start(m.q0)
    q, _ = prob.configuration(prob.to_local(rng.normal(size=m.layout.nv) * 0.3))
    V, lam = rng.normal(size=m.layout.nv), rng.normal(size=m.n_constraints) * 10
    prob.start(q)

    def Q_at(z, dV):
        qz, _ = prob.configuration(prob.to_local(z))
        return m.forces(qz, V + dV, 0.0) - m.constraint_jacobian(qz).T @ lam

    e, n = 1e-6, m.layout.nv
    C = np.array([-(Q_at(0 * u, e * u) - Q_at(0 * u, -e * u)) / (2 * e) for u in np.eye(n)]).T
    K = np.array([-(Q_at(e * u, 0 * u) - Q_at(-e * u, 0 * u)) / (2 * e) for u in np.eye(n)]).T
    Cm = m.iteration_matrix(q, V, 0.0, 0.0, 1.0, 0.0, lam=lam)
    Km = m.iteration_matrix(q, V, 0.0, 0.0, 0.0, 1.0, lam=lam)
    np.testing.assert_allclose(Cm, C, rtol=0, atol=1e-7 * np.abs(C).max())
    np.testing.assert_allclose(Km, K, rtol=0, atol=1e-7 * np.abs(K).max())
    for c in ((1.0, 0.3, 0.2), (0.0, 0.0, 1.0)):
        dense = m.iteration_matrix(q, V, 0.0, *c, lam=lam)
        np.testing.assert_allclose(m.iteration_matrix(q, V, 0.0, *c, lam=lam, sparse=True).toarray(), dense,
                                   rtol=0, atol=1e-14 * np.abs(dense).max())


# --- 100 free bodies -----------------------------------------------------------------------
@pytest.mark.parametrize("group,chart", GROUPS_CHARTS)
def test_100_free_bodies_take_two_newton_iterations_and_one_matrix(group, chart):
    """600 unknowns, block-diagonal: one analytic matrix for the whole run and two Newton
    iterations per step (the second only confirms convergence)."""
    r = simulate(scenes.free_bodies(100), (0, 0.1), method="genalpha", dt=H, group=group, chart=chart)
    assert r.success
    s = r.stats
    assert s["n_newton"] / s["n_steps"] <= 2.0 + 1e-12
    assert s["n_jacobians"] == 1
    assert s["n_f"] <= 2 * s["n_steps"] + 1                    # no finite-difference columns


@pytest.mark.parametrize("group,chart", [("SE3", "exp"), ("SO3xR3", "cay")])
def test_100_free_bodies_analytic_matrix_converges_to_the_fd_matrix_solution(group, chart, monkeypatch):
    m = scenes.free_bodies(100)
    a = simulate(m, (0, 0.02), method="genalpha", dt=H, group=group, chart=chart)
    monkeypatch.delattr(scenes.RigidBodySystem, "iteration_matrix")
    b = simulate(m, (0, 0.02), method="genalpha", dt=H, group=group, chart=chart)
    assert a.success and b.success
    assert b.stats["n_f"] > 600                                  # b did build the FD matrix
    assert np.abs(a.q[-1] - b.q[-1]).max() < 1e-9
    assert np.abs(a.V[-1] - b.V[-1]).max() < 1e-9


@pytest.mark.parametrize("group,chart", [("SE3", "cay"), ("SO3xR3", "exp")])
def test_constrained_springs_analytic_and_fd_matrices_reach_the_same_steps(group, chart, monkeypatch):
    """Joints, damped springs, SE(3) rows in the body frame: the finite-difference fallback
    (with its λ columns from A) and the analytic matrix converge to the same solution."""
    a = simulate(jointed_springs(), (0, 0.05), method="genalpha", dt=H, group=group, chart=chart)
    monkeypatch.delattr(scenes.RigidBodySystem, "iteration_matrix")
    b = simulate(jointed_springs(), (0, 0.05), method="genalpha", dt=H, group=group, chart=chart)
    assert a.success and b.success
    assert np.abs(a.q[-1] - b.q[-1]).max() < 1e-10 and np.abs(a.V[-1] - b.V[-1]).max() < 1e-9
    assert a.stats["n_f"] < b.stats["n_f"] and a.stats["constraint_residual"] < 1e-10


# --- linear algebra paths --------------------------------------------------------------------
def test_sparse_lu_dense_lu_and_block_inverse_give_the_same_steps(monkeypatch):
    """The chain (constraints couple every body) through sparse LU instead of dense LU,
    free bodies through LU instead of per-block inverses: the same steps."""
    runs = {}
    for name, model, patch in (("chain", lambda: scenes.chain(4), ("SPARSE_MIN", 0)),
                               ("free", lambda: scenes.free_bodies(5), ("BLOCK_MAX", 0))):
        ref = simulate(model(), (0, 0.05), method="genalpha", dt=H)
        with monkeypatch.context() as mp:
            mp.setattr(gm, *patch)
            mp.setattr(ga_mod, "SPARSE_MIN", gm.SPARSE_MIN)
            alt = simulate(model(), (0, 0.05), method="genalpha", dt=H)
        assert ref.success and alt.success
        runs[name] = np.abs(ref.q[-1] - alt.q[-1]).max()
    assert max(runs.values()) < 1e-11, runs


@pytest.mark.parametrize("n,coupled", [(60, False), (60, True), (300, True)])
def test_factorize_solves_J_z_equals_L_r(n, coupled, rng):
    from scipy import sparse
    blocks = rng.normal(size=(n // 6, 6, 6)) + 6 * np.eye(6)
    J = sparse.block_diag(list(blocks), format="lil")
    if coupled:                                               # a chain of couplings between blocks
        for i in range(0, n - 6, 6):
            J[i, i + 6] = J[i + 6, i] = 0.5
    J = J.tocsr()
    L = sparse.block_diag(list(rng.normal(size=(n // 6, 6, 6))), format="csr")
    r = rng.normal(size=n)
    expect = np.linalg.solve(J.toarray(), L @ r)
    for JJ, LL in ((J, L), (J.toarray(), L.toarray())):
        for compiled in (False, True):            # the block product in scipy or in the kernel
            np.testing.assert_allclose(gm.factorize(JJ, LL, compiled)(r), expect, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(gm.factorize(J)(r), np.linalg.solve(J.toarray(), r), rtol=1e-10, atol=1e-12)
    Js = J.tolil()
    Js[3, :] = 0.0
    with pytest.raises((np.linalg.LinAlgError, RuntimeError)):
        gm.factorize(Js.tocsr(), L)
    for compiled in (False, True):                # a CSC J (DensePattern's) as it comes, memo kept
        memo = {}
        for _ in range(2):
            got = gm.factorize(J.tocsc(), LL if compiled else L, compiled, memo)(r)
            np.testing.assert_allclose(got, expect, rtol=1e-10, atol=1e-12)


def test_dense_pattern_gives_each_matrix_in_the_kept_pattern(rng):
    """DensePattern.csc equals the dense matrix; the pattern is kept while the nonzeros stay
    inside it (zeros inside it kept explicit), and set anew for a
    nonzero outside it or another shape."""
    p = gm.DensePattern()
    D = np.diag(rng.normal(size=8) + 3.0)
    D[0, 5] = D[6, 1] = 1.5
    first = p.csc(D)
    np.testing.assert_array_equal(first.toarray(), D)
    E = D * 2.0
    E[0, 5] = 0.0                                              # a zero inside the pattern
    second = p.csc(E)
    assert second.format == "csc" and second.nnz == first.nnz
    np.testing.assert_array_equal(second.indices, first.indices)
    np.testing.assert_array_equal(second.toarray(), E)
    F = D.copy()
    F[2, 7] = 4.0                                              # outside the pattern: a new one
    third = p.csc(F)
    np.testing.assert_array_equal(third.toarray(), F)
    assert third.nnz == first.nnz + 1 and len(p.indices) == third.nnz
    np.testing.assert_array_equal(p.csc(np.eye(3)).toarray(), np.eye(3))


# --- failures ------------------------------------------------------------------------------
class _Broken(scenes.RigidBodySystem):
    how = "nan"

    def iteration_matrix(self, q, V, t, c_acc, c_vel, c_pos):
        out = super().iteration_matrix(q, V, t, c_acc, c_vel, c_pos)
        return out * np.nan if self.how == "nan" else out * 0.0


@pytest.mark.parametrize("how,words", [("nan", "not finite"), ("zero", "singular")])
def test_a_broken_iteration_matrix_is_a_failed_step(how, words):
    fb = scenes.free_bodies(2)
    m = _Broken(fb.m, fb.J, fb.q0, fb.V0, gravity=np.zeros(3))
    m.how = how
    r = simulate(m, (0, 0.01), method="genalpha", dt=H)
    assert not r.success and words in r.message and "genalpha" in r.message
    assert len(r.t) == 1                                          # nothing computed is lost


def test_importing_genalpha_loads_no_scipy_linalg_or_sparse():
    code = ("import sys, lgt_bridge, lgt_bridge.integrators.genalpha, lgt_bridge.simulate; "
            "print([m for m in ('scipy.linalg', 'scipy.sparse') if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout


class _Duffing(Model):
    """x'' = -k x³ - c x' from a large amplitude: stiffness 3 k x² makes a long genalpha step's
    Newton iteration fail (it did, at dt = 0.02, before steps were cut and retried)."""

    def __init__(self, k=1e4, x0=10.0, nan_after=None, c=0.0):
        self.layout = Layout.stacked([], n_vector=1)
        self.q0, self.V0 = np.array([x0]), np.zeros(1)
        self.k, self.nan_after, self.c = k, nan_after, c

    def f(self, q, V, t):
        if self.nan_after is not None and t > self.nan_after:
            return np.full(1, np.nan)
        return -self.k * q ** 3 - self.c * V


def test_genalpha_cuts_and_retries_a_step_whose_newton_fails():
    # damped, so that steps of dt converge again once the amplitude has fallen: undamped, a
    # step of dt (h·ω ≈ 30) converged only by chance (the run's one step of dt was its last;
    # with an exact Newton matrix none did)
    m = _Duffing(c=1000.0)
    r = simulate(m, (0.0, 0.1), method="genalpha", dt=0.02)
    assert r.success, r.message
    assert r.stats["n_rejected"] >= 1            # some steps were halved ...
    assert r.stats["n_steps"] > 5                # ... so more than 0.1/0.02 steps were taken
    h = np.diff(r.t)
    assert h.max() <= 0.02 + 1e-15 and h.min() < 0.02
    # after a halved step the step grows back to dt
    first_cut = int(np.flatnonzero(h < 0.02 - 1e-15)[0])
    assert np.any(np.abs(h[first_cut:] - 0.02) <= 1e-15)
    assert np.isfinite(r.q).all() and np.isfinite(r.V).all()


def test_genalpha_gives_up_at_min_step_with_a_message_that_helps():
    m = _Duffing(k=1.0, x0=1.0, nan_after=0.05)
    r = simulate(m, (0.0, 0.1), method="genalpha", dt=0.01)
    assert not r.success
    assert "halving the step" in r.message and "min_step" in r.message
    assert r.t[-1] == pytest.approx(0.05, abs=1e-12)        # the steps before are kept


def test_the_compiled_newton_start_is_the_reference_predictor():
    """genalpha_newton.predict on compiled kernels (one call) equals its numpy reference
    (linear extrapolation, 0 where the last two values alternate in sign above a tenth of the
    RMS): vectors with alternating, small alternating, smoothly crossing and equal entries, and
    one that is not C-contiguous (the reference then)."""
    from lgt_bridge.integrators.genalpha_newton import predict
    rng = np.random.default_rng(3)
    for n in (1, 2, 7, 104):
        x, x_prev = rng.normal(size=n), rng.normal(size=n)
        x[::3] = -x_prev[::3]                       # alternating
        x[1::5] = 1e-3 * np.sign(x_prev[1::5])       # small, same sign
        ref = predict(x, x_prev, compiled=False)
        got = predict(x, x_prev, compiled=True)
        assert np.array_equal(got, ref), n
        alt = (x * x_prev < 0) & (np.abs(x) > 0.1 * np.sqrt(np.mean(x * x))) & (np.abs(x_prev) > 0.1 * np.sqrt(np.mean(x * x)))
        assert np.all(ref[alt] == 0.0) and np.allclose(ref[~alt], 2 * x[~alt] - x_prev[~alt], rtol=0, atol=0)
    y = rng.normal(size=(8, 2))
    assert np.array_equal(predict(y[:, 0], y[:, 1], compiled=True), predict(y[:, 0].copy(), y[:, 1].copy()))
    assert predict(np.zeros(0), np.zeros(0), compiled=True).shape == (0,)


@pytest.mark.parametrize("chart", ["exp", "cay", "cay2"])
@pytest.mark.parametrize("group", ["SO3", "SO3xR3", "SE3"])
def test_the_compiled_chart_differentials_of_the_newton_matrix_are_the_charts_own(chart, group):
    """kernels.genalpha.dpsi_neg (the Newton matrix's per-body dψ blocks on compiled problems:
    the inverse of the stage kernels' dψ⁻¹ rates) equals the chart's numpy dψ and inverts its
    dψ⁻¹, at coordinates up to 0.9 of the chart's limit (exp: angles up to 3 rad)."""
    from lgt_bridge.charts import CHARTS
    from lgt_bridge.kernels.genalpha import dpsi_neg
    ch = CHARTS[chart]
    maps = ch.on(group)
    m = 3 if group == "SO3" else 6
    rng = np.random.default_rng(7)
    X = rng.normal(size=(200, m))
    X[:, :3] *= (rng.uniform(0.0, 1.0, 200) * min(0.9 * ch.limit, 3.0) / np.linalg.norm(X[:, :3], axis=1))[:, None]
    X[:5, :3] = [[0, 0, 0], [1e-9, 0, 0], [0, 1e-5, 0], [0, 0, 1e-3], [1e-8, -2e-8, 3e-8]]   # near the origin
    out = np.empty((200, m, m))
    dpsi_neg(ch.code, {"SO3": 0, "SO3xR3": 1, "SE3": 2}[group], np.ascontiguousarray(-X), out)
    ref = maps.dpsi(X)
    scale = np.abs(ref).max(axis=(1, 2))[:, None, None]
    assert (np.abs(out - ref) <= 1e-13 * scale).all()
    eye = np.broadcast_to(np.eye(m), out.shape)
    assert np.abs(out @ maps.dpsi_inv(X) - eye).max() <= 1e-12
