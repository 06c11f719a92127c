"""Events on a Pinocchio model: g calls Pinocchio (a frame placement) on the bridge's q,
which is Pinocchio's own; a free-flyer's foot frame reaches the ground at √(2h/g)."""
import math

import numpy as np
import pytest

from lgt_bridge import simulate

pin = pytest.importorskip("pinocchio")


def test_pinocchio_frame_touches_ground():
    from lgt_pinocchio import PinocchioModel

    model = pin.Model()
    j = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    model.appendBodyToJoint(j, pin.Inertia(1.5, np.zeros(3), np.diag([0.1, 0.2, 0.3])), pin.SE3.Identity())
    foot = model.addFrame(pin.Frame("foot", j, 0, pin.SE3(np.eye(3), np.array([0.0, 0.0, -0.2])),
                                    pin.FrameType.OP_FRAME))
    data = model.createData()
    h = 1.0
    q0 = pin.neutral(model)
    q0[2] = h + 0.2                                      # the foot starts at height h
    m = PinocchioModel(model, q0=q0, v0=np.zeros(6))

    def foot_z(t, q, V):                                 # g calls the engine
        qp, _ = m.pin_state(q, V)
        pin.framesForwardKinematics(model, data, qp)
        return data.oMf[foot].translation[2]
    foot_z.terminal = True
    r = simulate(m, (0.0, 1.0), method="dop853", rtol=1e-12, atol=1e-12, events=[foot_z])
    assert r.success and abs(r.t_events[0][0] - math.sqrt(2 * h / 9.81)) < 1e-12
    assert abs(foot_z(0, r.q[-1], r.V[-1])) < 1e-12


def test_example_quadruped_drop_runs(capsys):
    """examples/events_quadruped_drop.py: Solo-12 stops at its first touchdown, the foot on z = 0."""
    pytest.importorskip("example_robot_data", reason="the robots extra (example-robot-data) is not installed")
    import runpy
    from pathlib import Path
    runpy.run_path(str(Path(__file__).resolve().parents[2] / "examples" / "events_quadruped_drop.py"))
    out = capsys.readouterr().out
    assert "terminal event 1 (FR_FOOT touches the ground) at t = 0.2383874" in out
