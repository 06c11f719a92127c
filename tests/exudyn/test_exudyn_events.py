"""Events on an Exudyn model: the period of a pendulum on a revolute joint from its crossings
of the vertical, against the complete elliptic integral (the model's own q: Exudyn's total
coordinates), through simulate, the drop-in SolveDynamic (a terminal event ends Exudyn's run
there, its state, time and sensors at the event) and ``lgt-bridge run --events``."""
import math
import os
import subprocess
import sys
from pathlib import Path

import mpmath
import numpy as np
import pytest

import lgt_bridge
from lgt_bridge import InputError, simulate

exu = pytest.importorskip("exudyn")
G = 9.81


def Ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def period(theta0, L):
    """4 K(sin²(θ0/2)) √(L/g), K the complete elliptic integral of the first kind (parameter m)."""
    return float(4 * mpmath.ellipk(math.sin(theta0 / 2) ** 2) * mpmath.sqrt(L / G))


def revolute_pendulum(theta0=2.2, sensor=False):
    """A cuboid on a revolute joint about y through the origin, released from rest at θ0 from
    the downward vertical, its centre at distance d; (SC, mbs, sensor of its position or None,
    period 4 K √(L/g) with L = I_pivot/(m d))."""
    from exudyn.utilities import InertiaCuboid, ObjectGround, SensorBody

    rho, sides = 500.0, [0.1, 0.1, 1.2]
    d = sides[2] / 2
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    inertia = InertiaCuboid(density=rho, sideLengths=sides)
    R0 = Ry(theta0)
    body = mbs.CreateRigidBody(inertia=inertia, referencePosition=R0 @ [0, 0, -d], referenceRotationMatrix=R0,
                               gravity=[0, 0, -G])
    mbs.CreateRevoluteJoint(itemNumbers=[ground, body], position=[0, 0, 0], axis=[0, 1, 0])
    s = mbs.AddSensor(SensorBody(bodyNumber=body, storeInternal=True,
                                 outputVariableType=exu.OutputVariableType.Position)) if sensor else None
    mbs.Assemble()
    mass = rho * np.prod(sides)
    I_pivot = mass * (sides[0] ** 2 + sides[2] ** 2) / 12 + mass * d * d
    return SC, mbs, s, period(theta0, I_pivot / (mass * d))


def _settings(t_end, n):
    s = exu.SimulationSettings()
    s.timeIntegration.endTime, s.timeIntegration.numberOfSteps = t_end, n
    s.timeIntegration.verboseMode = 0
    s.solution.file.write = False
    s.solution.sensors.writePeriod = t_end / n
    return s


def test_solve_dynamic_pendulum_period_from_its_crossings():
    """SolveDynamic(..., events=[g]): the crossings of the vertical in the stats, against
    4 K(sin²(θ0/2)) √(L/g); Exudyn's run goes on to endTime (no terminal event)."""
    from lgt_exudyn import SolveDynamic

    SC, mbs, _, T = revolute_pendulum()
    SolveDynamic(mbs, _settings(1.3 * T, 130), method="dop853", rtol=1e-12, atol=1e-12,
                 events=[lambda t, q, V: q[0]])
    st = mbs.sys["lgtBridgeStats"]
    te = st["t_events"][0]
    assert st["success"] and st["message"] == "reached endTime" and len(te) == 3
    assert abs(te[0] - T / 4) / T < 1e-9 and abs(te[2] - te[0] - T) / T < 1e-9
    assert np.abs(st["q_events"][0][:, 0]).max() < 1e-12
    assert mbs.systemData.GetTime() == pytest.approx(1.3 * T, rel=1e-12)


@pytest.mark.parametrize("method, kw, tol", [("dop853", dict(rtol=1e-12, atol=1e-12), 1e-9),
                                             ("rkmk4", {}, 1e-7), ("genalpha", {}, 1e-4)])
def test_solve_dynamic_terminal_event_ends_exudyns_run_there(method, kw, tol):
    """A terminal event (the second upward pass through the vertical: terminal = 2 with
    direction +1 counts every other pass) ends Exudyn's run at the located time: the stats name
    it, Exudyn's time, state and last sensor row are at the event, no sensor row lies beyond."""
    from lgt_exudyn import SolveDynamic

    SC, mbs, sensor, T = revolute_pendulum(sensor=True)

    def up(t, q, V):
        return q[0]
    up.terminal, up.direction = 2, 1
    SolveDynamic(mbs, _settings(2.0 * T, 2000), method=method, events=[up], **kw)
    st = mbs.sys["lgtBridgeStats"]
    te = st["t_events"][0]
    assert st["success"] and st["message"].startswith("terminal event 0 (up) at t = ")
    assert "(occurrence 2)" in st["message"]
    np.testing.assert_allclose(te, [T / 4, 5 * T / 4], rtol=tol)
    sd = mbs.systemData
    assert sd.GetTime() == te[-1]
    q_exu = np.array(sd.GetODE2Coordinates()) + np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))
    np.testing.assert_allclose(q_exu, st["q_events"][0][-1][:len(q_exu)], atol=1e-12)
    rows = mbs.GetSensorStoredData(sensor)
    assert rows[-1, 0] == te[-1] and rows[:, 0].max() == te[-1]
    assert abs(rows[-1, 1]) < 1e-9                              # x of the centre: on the vertical


def test_solve_dynamic_bad_event_before_the_first_step():
    from lgt_exudyn import SolveDynamic

    SC, mbs, _, T = revolute_pendulum()
    q0 = np.array(mbs.systemData.GetODE2Coordinates())
    with pytest.raises(InputError, match="not a function"):
        SolveDynamic(mbs, _settings(0.1, 10), events=["q[0]"])
    assert np.array_equal(mbs.systemData.GetODE2Coordinates(), q0)


def test_cli_run_events_option(tmp_path):
    """``lgt-bridge run SCRIPT --events FILE.py:NAME``: the legacy pendulum (released
    horizontally, L = 0.7 m) stops where its centre first reaches z = -0.25 m, at the time the
    incomplete elliptic integral gives: √(L/g) (K(k²) - F(u | k²)), k = sin(π/4),
    sin(φ/2) = k sin u, φ = acos(0.5) from the vertical; the script's own sensor ends there."""
    root = Path(__file__).resolve().parents[2]
    (tmp_path / "my_events.py").write_text(
        "def below(t, q, V):\n    return q[2] + 0.25\nbelow.terminal = True\nbelow.direction = -1\n")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(root), str(root / "adapters"), env.get("PYTHONPATH", "")])
    script = root / "tests" / "models" / "legacy" / "exudyn_pendulum.py"

    def cli(*args):
        return subprocess.run([sys.executable, "-m", "lgt_bridge.cli", "run", str(script), *args],
                              capture_output=True, text=True, env=env, cwd=tmp_path)
    p = cli("--events", "my_events.py:below", "--rtol", "1e-10", "--atol", "1e-10")
    assert p.returncode == 0, p.stderr
    k2, phi = 0.5, math.acos(0.5)
    u = math.asin(math.sin(phi / 2) / math.sqrt(k2))
    t_ref = math.sqrt(0.7 / G) * float(mpmath.ellipk(k2) - mpmath.ellipf(u, k2))
    line = next(ln for ln in p.stdout.splitlines() if "event 0 (below): 1 crossing(s) at t = " in ln)
    assert abs(float(line.rsplit("= ", 1)[1]) - t_ref) < 1e-8
    assert "ended at the terminal event 0 (below) at t = " in p.stdout
    final = next(ln for ln in p.stdout.splitlines() if ln.startswith("FINAL_POSITION")).split()[1:]
    assert abs(float(final[2]) + 0.25) < 1e-9
    p = cli("--events", "nowhere.py:below")
    assert p.returncode == 2 and "run --events 'nowhere.py:below': no file" in p.stderr
    p = cli("--events", "my_events.py:above")
    assert p.returncode == 2 and "has no function 'above'" in p.stderr


def test_exudyn_revolute_pendulum_period():
    SC, mbs, _, T = revolute_pendulum(2.2)
    m = lgt_bridge.wrap(mbs)
    r = simulate(m, (0.0, 1.3 * T), method="dop853", rtol=1e-12, atol=1e-12,
                 events=[lambda t, q, V: q[0]])          # x of the body's centre (Exudyn's own q)
    te = r.t_events[0]
    assert len(te) == 3
    assert abs(te[0] - T / 4) / T < 1e-9 and abs(te[2] - te[0] - T) / T < 1e-9
