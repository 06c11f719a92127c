"""The Exudyn adapter and drop-in solver (skipped only when exudyn is not installed)."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge import InputError, StepError, lgt, scenes, wrap  # noqa: E402
from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_exudyn import ExudynModel, SolveDynamic  # noqa: E402

import exudyn_models as em  # noqa: E402
import references as ref  # noqa: E402

NODES = [(em.EP, "quat"), (em.ROTVEC, "rotvec"), (em.RXYZ, "rxyz")]
HERE = Path(__file__).parent


def R_of(model, q, k=0):
    b = model.layout.bodies[k]
    return b.param.alpha(q[[*b.pos, *b.rot]])[:3, :3]


def test_wrap_finds_the_exudyn_adapter():
    SC, mbs, _ = em.heavy_top()
    assert isinstance(wrap(mbs), ExudynModel)


@pytest.mark.parametrize("node,param", NODES, ids=["EP", "RotVecLG", "Rxyz"])
def test_f_equals_engine_free_scene(node, param, rng):
    SC, mbs, _ = em.heavy_top(node)
    m, s = ExudynModel(mbs), scenes.heavy_top(True, param=param)
    assert np.allclose(m.q0, s.q0, atol=1e-15) and np.allclose(m.V0, s.V0, atol=1e-13)
    for _ in range(5):
        q = lgt.tau(s.q0, rng.normal(size=6) * 0.7, param, "SO3xR3", "exp")
        V = rng.normal(size=6) * 5
        t = rng.uniform(0, 1)
        assert np.abs(m.f(q, V, t) - s.f(q, V, t)).max() < 1e-8
        assert np.abs(m.constraints(q) - s.constraints(q)).max() < 1e-14
        assert np.abs(m.constraint_jacobian(q) - s.constraint_jacobian(q)).max() < 1e-14
        assert np.abs(m.mass_matrix(q) - s.mass_matrix(q)).max() < 1e-12


@pytest.mark.parametrize("make", [lambda: em.heavy_top()[:2], em.spring_body_with_load, em.mixed_with_point_mass,
                                  lambda: em.chain(5, joint="revolute")], ids=["top", "spring", "mixed", "revchain"])
def test_initial_accelerations_match_exudyn(make):
    SC, mbs = make()
    s = em.settings(1.0, 10)
    S = exu.MainSolverImplicitSecondOrder()
    S.InitializeSolver(mbs, s)                       # computes Exudyn's consistent initial accelerations
    acc = np.array(mbs.systemData.GetODE2Coordinates_tt())
    m = ExudynModel(mbs)
    mine = m.accelerations(m.q0, m.V0, 0.0)
    assert np.abs(mine - acc).max() <= 1e-7 * max(1.0, np.abs(acc).max())


def test_heavy_top_with_joint_reproduces_reference_and_exudyn_converges():
    """EP nodes + spherical joint (Exudyn's explicit solvers refuse this model): the bridge's
    dopri5 on the Exudyn model against an independent plain-quaternion DOP853 reference
    (rtol 1e-13) at t = 2 s; Exudyn's own generalized-α converges to it at 2nd order."""
    T = 2.0
    Rref, wref = ref.heavy_top(T)
    com = np.array([0.0, 1.0, 0.0])
    SC, mbs, _ = em.heavy_top(em.EP)
    m = ExudynModel(mbs)
    r = simulate(m, (0, T), method="dopri5", group="SO3xR3", rtol=1e-10, atol=1e-10, t_eval=[T])
    assert r.success
    assert np.abs(R_of(m, r.q[-1]) - Rref).max() <= 1e-8
    assert np.abs(r.q[-1][:3] - Rref @ com).max() <= 1e-8
    assert np.abs(r.V[-1, :3] - wref).max() <= 1e-8 * np.abs(wref).max()
    errs, hs = [], [2e-4, 1e-4, 5e-5]
    for h in hs:
        SC2, mbs2, _ = em.heavy_top(em.EP)
        mbs2.SolveDynamic(em.settings(T, int(round(T / h))))
        errs.append(ref.angle(R_of(m, em.total_q(mbs2)), Rref))
    assert abs(ref.slope(hs, errs) - 2.0) <= 0.2, errs
    assert ref.angle(R_of(m, r.q[-1]), Rref) < errs[-1] / 1000


def _native_pair(make, T, n):
    """Exudyn's generalized-α at n and 2n steps: final coordinates and an error estimate."""
    out = []
    for k in (n, 2 * n):
        SC, mbs = make()[:2]
        mbs.SolveDynamic(em.settings(T, k))
        out.append(em.total_q(mbs))
    return out[1], np.abs(out[1] - out[0]).max()


@pytest.mark.parametrize("make,T,n", [
    (lambda: em.chain(5), 0.5, 4000),
    (lambda: em.chain(5, joint="revolute"), 0.5, 4000),
    (em.spring_body_with_load, 1.0, 20000),
    (em.mixed_with_point_mass, 0.1, 8000),
], ids=["spherical-chain", "revolute-chain", "spring-load", "mixed-point-mass"])
def test_bridge_agrees_with_native_generalized_alpha(make, T, n):
    """Both sides carry integration error; each is estimated by refinement (native: step
    halving, bridge: tolerance / 100), and the runs must agree within twice the sum."""
    q_native, est = _native_pair(make, T, n)
    qb = []
    for tol in (1e-10, 1e-12):
        SC, mbs = make()[:2]
        r = simulate(ExudynModel(mbs), (0, T), method="dopri5", rtol=tol, atol=tol, t_eval=[T])
        assert r.success, r.message
        qb.append(r.q[-1])
    est_b = np.abs(qb[1] - qb[0]).max()
    diff = np.abs(qb[1] - q_native).max()
    assert diff <= 2 * (est + est_b) + 1e-10, (diff, est, est_b)
    assert max(est, est_b) < 1e-6                        # both converged far enough to compare


@pytest.mark.parametrize("eps,tol", [(0.05, 1e-9), (1e-3, 1e-8)])
def test_rxyz_node_through_gimbal_lock_matches_ep(eps, tol):
    """Start eps below θ1 = π/2: the spinning top then drives θ1 through ±π/2 repeatedly.
    Exudyn gives M and Q of an Rxyz node in angle coordinates only, so mapping them to
    twists costs ~eps_mach/cos²θ1: the agreement is bounded by the closest pass."""
    from scipy.spatial.transform import Rotation
    R0 = Rotation.from_euler("XYZ", [0, np.pi / 2 - eps, 0]).as_matrix()
    T, dt = 0.1, 2e-4
    SCe, me, _ = em.heavy_top(em.EP, R0=R0)
    SCr, mr, node = em.heavy_top(em.RXYZ, R0=R0)
    Me, Mr = ExudynModel(me), ExudynModel(mr)
    re_ = simulate(Me, (0, T), method="rkmk4", dt=dt)
    rr = simulate(Mr, (0, T), method="rkmk4", dt=dt)
    assert rr.success and np.isfinite(rr.q).all()
    assert ref.angle(R_of(Me, re_.q[-1]), R_of(Mr, rr.q[-1])) < tol
    d = np.abs(np.diff(rr.q[:, 3:], axis=0))
    assert d[:, 1].max() < 2 * 150 * dt and d[:, [0, 2]].max() < np.pi / 2
    assert rr.q[:, 4].max() > 3 * np.pi / 2                            # θ1 went through π/2 and 3π/2
    assert np.allclose(em.total_q(mr), rr.q[-1], atol=1e-14)          # final state written back


def _drop_in_run(tmp_path, tag, bridge):
    SC, mbs, node = em.heavy_top(em.EP)
    s1 = mbs.AddSensor(exu.utilities.SensorNode(nodeNumber=node, storeInternal=True, fileName=str(tmp_path / f"{tag}_w.txt"),
                                                outputVariableType=exu.OutputVariableType.AngularVelocity))
    s2 = mbs.AddSensor(exu.utilities.SensorNode(nodeNumber=node, storeInternal=True,
                                                outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    s = em.settings(0.02, 200, write=True, sensors=True)
    s.solution.file.name = str(tmp_path / f"{tag}_sol.txt")
    s.solution.file.writePeriod = 0.002
    s.solution.sensors.writePeriod = 0.001
    if bridge:
        SolveDynamic(mbs, s, method="dopri5", rtol=1e-10, atol=1e-10)
    else:
        mbs.SolveDynamic(s)
    return mbs, [mbs.GetSensorStoredData(k) for k in (s1, s2)]


def _rows(path):
    lines = [ln for ln in Path(path).read_text().splitlines() if ln and not ln.startswith("#")]
    return len(lines), {len(ln.split(",")) for ln in lines}


def test_drop_in_sensors_and_solution_file_as_exudyn_writes_them(tmp_path):
    mn, native = _drop_in_run(tmp_path, "native", False)
    mb, bridged = _drop_in_run(tmp_path, "bridge", True)
    for a, b in zip(native, bridged):
        assert a.shape == b.shape and np.array_equal(a[:, 0], b[:, 0])
        assert np.abs(a[:, 1:] - b[:, 1:]).max() < 1e-2 * np.abs(a[:, 1:]).max()   # native is only 2nd order
    assert _rows(tmp_path / "native_sol.txt") == _rows(tmp_path / "bridge_sol.txt")
    assert _rows(tmp_path / "native_w.txt") == _rows(tmp_path / "bridge_w.txt")
    st = mb.sys["lgtBridgeStats"]
    assert st["success"] and st["n_f"] > 0 and st["exudyn_steps"] == 200
    sd = mb.systemData
    assert sd.GetTime() == pytest.approx(0.02)
    p = em.total_q(mb)[3:]
    assert abs(np.linalg.norm(p) - 1) < 1e-14                        # EP unit without the constraint
    acc = np.array(sd.GetODE2Coordinates_tt())
    assert np.isfinite(acc).all() and np.abs(acc).max() > 1.0         # accelerations written


def test_lgt_bridge_run_routes_a_legacy_script():
    script = HERE.parent / "models" / "legacy" / "exudyn_pendulum.py"
    native = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, check=True)
    routed = subprocess.run([sys.executable, "-m", "lgt_bridge.cli", "run", str(script), "--method", "rkmk4"],
                            capture_output=True, text=True, check=True)
    assert "ran rkmk4 on SO3xR3/exp, fixed step 0.001 s" in routed.stdout
    assert "; 300 steps" in routed.stdout and "f evaluations" in routed.stdout
    pos = lambda out: np.array([float(v) for v in out.split("FINAL_POSITION")[1].split()[:3]])
    assert np.abs(pos(native.stdout) - pos(routed.stdout)).max() < 1e-3
    assert exu.SolveDynamic.__module__ == "exudyn.solver"            # nothing left patched here
    # the implicit method takes the script's tolerances (Exudyn's defaults here) whatever
    # automaticStepSize says, and lands on the same motion as the explicit pair
    implicit = subprocess.run([sys.executable, "-m", "lgt_bridge.cli", "run", str(script), "--method", "radau5"],
                              capture_output=True, text=True, check=True)
    explicit = subprocess.run([sys.executable, "-m", "lgt_bridge.cli", "run", str(script), "--method", "dop853",
                               "--rtol", "1e-10", "--atol", "1e-10"], capture_output=True, text=True, check=True)
    assert "ran radau5 on SO3xR3/exp, rtol=" in implicit.stdout
    assert np.abs(pos(implicit.stdout) - pos(explicit.stdout)).max() < 1e-6


def test_bad_input():
    SC, mbs, _ = em.heavy_top(assemble=False)
    with pytest.raises(InputError, match="not assembled"):
        ExudynModel(mbs)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    n = mbs.AddNode(exu.utilities.NodeGenericODE1(referenceCoordinates=[0.0], initialCoordinates=[1.0],
                                                  numberOfODE1Coordinates=1))
    mbs.AddObject(exu.utilities.ObjectGenericODE1(nodeNumbers=[n], systemMatrix=-np.eye(1)))
    mbs.Assemble()
    r = simulate(ExudynModel(mbs), (0, 1), method="dop853", rtol=1e-12, atol=1e-12)
    assert r.success and r.V[-1, 0] == pytest.approx(np.exp(-1.0), abs=1e-10)    # ẏ = -y, y0 = 1
    SC, mbs, node = em.heavy_top(assemble=False)
    mbs.SetNodeParameter(node, "initialVelocities", [np.nan, 0, 0, 0, 0, 0, 0])
    mbs.Assemble()                                   # Exudyn accepts it
    with pytest.raises(InputError, match="not finite"):
        ExudynModel(mbs)


def test_failing_step_leaves_system_at_last_good_state():
    SC, mbs = em.spring_body_with_load()[:2]
    load = [i for i in range(mbs.systemData.NumberOfLoads())][0]
    mbs.SetLoadParameter(load, "loadVectorUserFunction",
                         lambda mbs, t, l: [np.nan, 0, 0] if t > 0.0205 else [1.0, 0, 0])
    m = ExudynModel(mbs)
    r = simulate(m, (0, 0.1), method="rkmk4", dt=1e-3)
    assert not r.success and "step from t = 0.02" in r.message
    assert r.t[-1] == pytest.approx(0.02)
    assert mbs.systemData.GetTime() == pytest.approx(0.02)
    assert np.allclose(em.total_q(mbs), r.q[-1], atol=1e-15) and np.isfinite(em.total_q(mbs)).all()
    SC, mbs = em.spring_body_with_load()[:2]
    mbs.SetLoadParameter(load, "loadVectorUserFunction",
                         lambda mbs, t, l: [np.nan, 0, 0] if t > 0.0205 else [1.0, 0, 0])
    with pytest.raises(StepError, match="left at t = 0.02"):
        SolveDynamic(mbs, em.settings(0.1, 100), method="rkmk4")
    assert mbs.systemData.GetTime() == pytest.approx(0.02) and np.isfinite(em.total_q(mbs)).all()


def _raising_load(mbs, t, load):
    if t > 0.0205:
        raise ValueError("the user's load function failed")
    return [1.0, 0, 0]


@pytest.mark.parametrize("method", ["rkmk4", "genalpha"])
def test_user_function_that_raises_ends_the_run_with_its_message(method):
    """An exception inside a user function reaches the user as lgt_bridge's error with the
    user's own message (not Exudyn's ModelError wrapping a traceback); the steps before are
    kept and the system is left at the last good state."""
    SC, mbs = em.spring_body_with_load()[:2]
    mbs.SetLoadParameter(0, "loadVectorUserFunction", _raising_load)
    r = simulate(ExudynModel(mbs), (0, 0.1), method=method, dt=1e-3)
    assert not r.success and "ValueError: the user's load function failed" in r.message
    assert "loadVectorUserFunction" in r.message
    assert r.t[-1] == pytest.approx(0.02) and np.isfinite(r.q).all()
    SC, mbs = em.spring_body_with_load()[:2]
    mbs.SetLoadParameter(0, "loadVectorUserFunction", _raising_load)
    with pytest.raises(StepError, match="the user's load function failed.*left at t = 0.02"):
        SolveDynamic(mbs, em.settings(0.1, 100), method=method)
    assert mbs.systemData.GetTime() == pytest.approx(0.02) and np.isfinite(em.total_q(mbs)).all()


def test_bench_scene_with_exudyn_natives(tmp_path):
    """exudyn_heavy_top: Exudyn's generalized-α on EP and on RotVecLG (converted to the EP
    model's coordinates) converge to the bridge's reference with the steps."""
    from lgt_bridge import bench
    ref, rows = bench.sweep("exudyn_heavy_top", ["dopri5"], ["SO3xR3"], ["exp"], [1e-7], [], workers=1,
                            progress=False, auto=False, repeat=1)
    model = bench.load_scene("exudyn_heavy_top")[0]
    tight = simulate(model, (0, ref["t_end"]), t_eval=[ref["t_end"]], **bench.REFERENCE)
    ref_state = (tight.q[-1], tight.V[-1])
    nat = {(r["method"], r["value"]): r for r in rows if r["group"] == "native"}
    assert len(nat) == 8 and all(r["success"] and r["constraint_residual"] < 1e-8 for r in nat.values())
    for fam in ("Exudyn generalized-α, EP", "Exudyn generalized-α, RotVecLG"):
        e = [nat[(fam, n)]["pose_error"] for n in (2000, 8000, 32000)]
        assert e[2] < e[1] < e[0] < 1e-1 and 12 < e[0] / e[1] < 20       # 2nd order: 4² = 16
    bridge = [r for r in rows if r["group"] == "SO3xR3"][0]
    assert bridge["success"] and bridge["pose_error"] < 1e-5
    assert "native" in bench.best_at(rows, 1e-3) and "bridge" in bench.best_at(rows, 1e-3)
    auto = bench.runner._one("exudyn_heavy_top", "dopri5", "auto", "auto", 1e-7, *ref_state)
    text = bench.write_report(tmp_path, "exudyn_heavy_top", ref, rows + [auto], plots=False).read_text()
    assert "| Exudyn generalized-α, EP | native | engine | n=2000 |" in text and "## auto against" in text


def test_bench_free_bodies_exudyn_dopri5_native():
    from lgt_bridge import bench
    from lgt_exudyn.bench import convert_q
    sc = bench.get_scene("exudyn_free_bodies")
    model = sc.make()
    q = sc.natives["Exudyn DOPRI5, RotVecLG"][2](1e-9)["q"]
    tight = simulate(model, (0, sc.t_end), method="dopri5", rtol=1e-12, atol=1e-12, t_eval=[sc.t_end])
    assert bench.pose_error(model, q, tight.q[-1]) < 1e-7
    ep = ExudynModel(em.heavy_top(em.EP)[1])
    rv = ExudynModel(em.heavy_top(em.ROTVEC)[1])
    q_rv = convert_q(ep, ep.q0, rv)                      # EP -> rotation vector -> EP
    np.testing.assert_allclose(convert_q(rv, q_rv, ep), ep.q0, atol=1e-15)
    assert bench.pose_error(rv, q_rv, rv.q0) < 1e-15


@pytest.mark.parametrize("group,chart", [("SO3xR3", "exp"), ("SE3", "cay2"), ("SO3xR3", "cay2")])
def test_drop_in_dop853_interpolates_exudyn_output_steps(group, chart):
    """SolveDynamic(method="dop853"): Exudyn's 400 output steps are interpolated (dense
    output), not forced as step ends, and the sensor values at those times match the
    independent plain-quaternion reference (EP heavy top with its spherical joint)."""
    from exudyn.utilities import SensorNode
    T, n_out = 0.2, 400
    SC, mbs, node = em.heavy_top(em.EP, assemble=False)
    sens = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                    outputVariableType=exu.OutputVariableType.RotationMatrix))
    mbs.Assemble()
    # max_step=None: Exudyn's cap at endTime/numberOfSteps lifted (a smooth model), so that
    # the steps are the error control's alone
    SolveDynamic(mbs, em.settings(T, n_out, sensors=True), method="dop853", group=group, chart=chart,
                 rtol=1e-10, atol=1e-10, max_step=None)
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and st["exudyn_steps"] == n_out
    assert st["n_steps"] < n_out / 4                  # output times do not shorten the steps
    data = mbs.GetSensorStoredData(sens)
    t = data[:, 0]
    assert len(t) >= 20 and t[-1] == pytest.approx(T)          # Exudyn samples sensors every 0.01 s
    sol = ref.heavy_top(T, t_eval=t[1:])
    errs = []
    for k in range(len(t) - 1):
        p = sol.y[:4, k]
        errs.append(np.abs(data[k + 1, 1:].reshape(3, 3) - ref.qmat(p / np.linalg.norm(p))).max())
    assert max(errs) < 1e-8, max(errs)


def _top_sensor_run(n, T, t0=0.0, **bridge):
    from exudyn.utilities import SensorNode
    SC, mbs, node = em.heavy_top(em.EP, assemble=False)
    sens = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                    outputVariableType=exu.OutputVariableType.AngularVelocityLocal))
    mbs.Assemble()
    s = em.settings(T, n, sensors=True)
    s.timeIntegration.startTime = t0
    s.solution.sensors.writePeriod = 1e-3
    if bridge:
        SolveDynamic(mbs, s, **bridge)
    else:
        mbs.SolveDynamic(s)
    return mbs.GetSensorStoredData(sens), mbs


@pytest.mark.parametrize("t0,T,n", [(0.0, 0.2, 200), (0.03, 0.1, 70)])
def test_drop_in_outputs_of_a_step_in_one_call_equal_one_at_a_time_and_exudyns_own(monkeypatch, t0, T, n):
    """A 1 ms ω sensor from dop853 steps of several ms (max_step=None): the states at the
    Exudyn steps one bridge step covers come from one dense-output call. The sensor rows
    equal, to rounding, those of the drop-in evaluating each Exudyn step on its own; their
    times are those Exudyn's own solver writes; and Exudyn's generalized-α converges to them
    at its second order (4x and 16x its steps: relative differences measured 3.5e-5 and
    2.2e-6 on 0.2 s). The second case starts at 0.03 s with 70 steps (Exudyn's last step
    shortened onto endTime: its time is not the predicted one and is evaluated on its own)."""
    from lgt_exudyn import solve
    kw = dict(method="dop853", rtol=1e-10, atol=1e-10, max_step=None)
    batched, mbs = _top_sensor_run(n, T, t0, **kw)
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"] and st["n_steps"] < n / 2           # several output steps per bridge step
    monkeypatch.setattr(solve.OutputRows, "at", lambda self, t, on_step: self.sim.advance_to(t, on_step))
    single, _ = _top_sensor_run(n, T, t0, **kw)
    assert np.array_equal(batched[:, 0], single[:, 0]) and len(batched) == n + 1
    assert np.abs(batched[:, 1:] - single[:, 1:]).max() <= 1e-13 * np.abs(single[:, 1:]).max()
    scale = np.abs(batched[:, 1:]).max()
    diffs = []
    for k in (4, 16):
        native, _ = _top_sensor_run(n * k, T, t0)
        assert native.shape == batched.shape and np.abs(native[:, 0] - batched[:, 0]).max() < 1e-12
        diffs.append(np.abs(native[:, 1:] - batched[:, 1:]).max() / scale)
    assert diffs[1] < 1e-5 and 10 < diffs[0] / diffs[1] < 25, diffs


@pytest.mark.parametrize("method", ["rkmk4", "genalpha"])
def test_fixed_step_outputs_are_the_states_the_steps_end_on(monkeypatch, method):
    """Fixed steps end on Exudyn's steps, and the driver has written each step's end state
    into the system: the drop-in does not write it again. The sensor rows are the states
    simulate computes at the same steps, and equal bitwise those of a run writing every
    output state again."""
    from exudyn.utilities import SensorNode
    from lgt_exudyn import solve
    T, n = 0.05, 50

    def run():
        SC, mbs, node = em.heavy_top(em.EP, assemble=False)
        sens = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                        outputVariableType=exu.OutputVariableType.Position))
        mbs.Assemble()
        s = em.settings(T, n, sensors=True)
        s.solution.sensors.writePeriod = T / n
        SolveDynamic(mbs, s, method=method)
        return mbs.GetSensorStoredData(sens)
    once = run()
    at = solve.OutputRows.at

    def rewritten(self, target, on_step):
        out = at(self, target, on_step)
        self.written = False
        return out
    monkeypatch.setattr(solve.OutputRows, "at", rewritten)
    assert np.array_equal(once, run()) and len(once) == n + 1
    SC, mbs, node = em.heavy_top(em.EP)
    r = simulate(ExudynModel(mbs), (0, T), method=method, dt=T / n, t_eval=once[:, 0])
    assert np.abs(r.q[:, :3] - once[:, 1:]).max() < 1e-12


def test_singular_mass_is_refused_before_the_first_step():
    """A body with no inertia about one axis: InputError naming it, from the constant-M̄
    path (Cholesky fails, then the eigen check names the direction)."""
    from exudyn.utilities import RigidBodyInertia
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=1.0, inertiaTensor=np.diag([0.0, 1.0, 1.0])),
                        nodeType=em.EP, referencePosition=[0, 0, 0], initialAngularVelocity=[0, 1, 0])
    mbs.Assemble()
    model = ExudynModel(mbs)
    with pytest.raises(InputError, match="mass matrix at q0 is singular.*body 0"):
        simulate(model, (0, 0.1), method="dopri5")


def test_drop_in_writes_accelerations_only_where_an_output_reads_them(monkeypatch):
    """accelerations=None: an acceleration sensor gets the same values as with
    accelerations=True; without an output that reads them the accelerations (and the
    Lagrange multipliers, one f each) are computed only for the final state, which still
    carries them."""
    from exudyn.utilities import SensorNode
    from lgt_exudyn.model import ExudynModel as EM
    calls = []
    original = EM.write_outputs

    def spy(self, q, V, t, accelerations=True, multipliers=True):
        calls.append((accelerations, multipliers))
        return original(self, q, V, t, accelerations, multipliers)
    monkeypatch.setattr(EM, "write_outputs", spy)
    T, n_out = 0.1, 200
    runs = {}
    for name, kind, acc in (("auto", exu.OutputVariableType.Acceleration, None),
                            ("forced", exu.OutputVariableType.Acceleration, True),
                            ("velocity", exu.OutputVariableType.Velocity, None)):
        SC, mbs, node = em.heavy_top(em.EP, assemble=False)
        sens = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True, outputVariableType=kind))
        mbs.Assemble()
        calls.clear()
        SolveDynamic(mbs, em.settings(T, n_out, sensors=True), method="dop853", rtol=1e-9, atol=1e-9,
                     accelerations=acc)
        runs[name] = (mbs.GetSensorStoredData(sens), [a for a, _ in calls], [m for _, m in calls],
                      mbs.systemData.GetODE2Coordinates_tt().copy())
    assert np.array_equal(runs["auto"][0], runs["forced"][0])
    assert len(runs["auto"][1]) == n_out and all(runs["auto"][1]) and all(runs["forced"][1])
    velocity = runs["velocity"]
    assert velocity[1] == [False] * (n_out - 1) + [True] and velocity[2] == [False] * (n_out - 1) + [True]
    assert np.abs(velocity[3] - runs["auto"][3]).max() < 1e-12 * (1 + np.abs(runs["auto"][3]).max())


def test_H_pinv_and_the_constant_mass_check_against_their_references(monkeypatch):
    """NodeLayout.H_pinv (closed forms for Euler-parameter and rotation-vector blocks) equals
    numpy's pseudo-inverse of H, also for a quaternion 1 % off unit norm; constant_twist_mass
    finds the same M̄ with dense products (small systems) as with sparse ones, and M̄ is
    Hᵀ M H of Exudyn's own mass matrix."""
    from lgt_exudyn import layout as model_mod
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    rng = np.random.default_rng(3)
    for node in (em.EP, em.ROTVEC, em.RXYZ, em.EP):
        mbs.CreateRigidBody(inertia=exu.utilities.RigidBodyInertia(mass=1.0 + rng.uniform(),
                                                                   inertiaTensor=np.diag(rng.uniform(1, 2, 3))),
                            nodeType=node, referencePosition=rng.normal(size=3),
                            initialAngularVelocity=rng.normal(size=3), gravity=[0, 0, -9.81])
    mbs.Assemble()
    m = ExudynModel(mbs)
    nodes = m.nodes
    q = nodes.moved(m.q0[:m.n2], rng.normal(size=m.nv), 0.8)
    np.testing.assert_allclose(nodes.H_pinv(q), np.linalg.pinv(nodes.H(q)), atol=1e-13)
    off = q.copy()
    off[list(m.layout.bodies[0].rot)] *= 1.01
    np.testing.assert_allclose(nodes.H_pinv(off), np.linalg.pinv(nodes.H(off)), atol=1e-13)
    dense = model_mod.constant_twist_mass(m.engine, nodes, m.q0[:m.n2])
    monkeypatch.setattr(model_mod, "DENSE_MASS_CHECK", 0)
    sparse = model_mod.constant_twist_mass(m.engine, nodes, m.q0[:m.n2])
    assert dense is not None and np.abs(dense - sparse).max() <= 1e-14 * np.abs(dense).max()
    H = nodes.H(m.q0[:m.n2])
    np.testing.assert_allclose(dense, H.T @ m.engine.mass_matrix() @ H, atol=1e-13)


def test_compiled_step_loop_on_free_exudyn_bodies_takes_the_python_loops_steps():
    """Free bodies (Euler parameters and rotation vectors, under gravity) through
    ``simulate(ExudynModel(mbs))``: the compiled step loop, calling Exudyn's f in its loop form
    (no argument conversions; ``f.loop_f``), takes the Python loop's steps, and the system
    holds the run's end state afterwards (written where the loop stops, not per step)."""
    import exudyn.utilities as eu
    from lgt_bridge import Simulation

    def build():
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        rng = np.random.default_rng(4)
        for node in (exu.NodeType.RotationEulerParameters, exu.NodeType.RotationRotationVector) * 2:
            mbs.CreateRigidBody(inertia=eu.InertiaCuboid(1000.0, rng.uniform(0.2, 1.0, 3)), nodeType=node,
                                referencePosition=rng.normal(size=3), initialAngularVelocity=rng.normal(size=3) * 3,
                                initialVelocity=rng.normal(size=3), gravity=[0, -9.81, 0])
        mbs.Assemble()
        return SC, mbs
    out = []
    for use in (True, False):
        SC, mbs = build()
        m = ExudynModel(mbs)
        sim = Simulation(m, method="dop853", rtol=1e-11, atol=1e-11)
        sim._use_loop = use
        r = sim.run(2.0, t_eval=[0.5, 2.0])
        out.append((r, sim, np.array(mbs.systemData.GetODE2Coordinates()), m))
    (a, sa, xa, ma), (b, sb, xb, _) = out
    assert getattr(ma.f, "loop_f", None) is not None and sa.stepper._compiled_loop.runs >= 1
    assert a.stats["n_steps"] == b.stats["n_steps"] > 10 and a.stats["n_f"] == b.stats["n_f"]
    np.testing.assert_allclose(a.q, b.q, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(xa, xb, rtol=1e-12, atol=1e-13)
