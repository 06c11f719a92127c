"""A load a user function switches on exactly at endTime (Exudyn's pickleCopyMbs.py, issue 21
item 3): every step landing on endTime sees the switch in its last stage, so at a tight
tolerance the steps collapsed below minimumStepSize just before the end. The motion up to
endTime does not depend on the load at that instant: the run ends at the left limit."""
import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

import exudyn_solver_models as sm  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402


def _q_total(mbs):
    sd = mbs.systemData
    return np.array(sd.GetODE2Coordinates()) + np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))


@pytest.mark.parametrize("tol", [1e-10, 1e-12])
def test_a_torque_switched_on_at_end_time_runs_at_tight_tolerances(tol):
    """dopri5 at rtol = atol = 1e-10 and 1e-12 (1e-10 used to stop at t = 0.999999993,
    "below minimumStepSize") reaches endTime and reports the jump; its end state agrees with
    Exudyn's own generalized-α at the script's spectral radius 0.6, refined (4000/8000 steps,
    Richardson-extrapolated: 5.6e-8 from the bridge's reference below), and with the bridge's dop853 at 1e-13 on the same model without the
    torque (the motion up to endTime, independent of the switch) to 1e-9."""
    mbs, s = sm.slider_torque_at_end()
    SolveDynamic(mbs, s, method="dopri5", rtol=tol, atol=tol)
    st = mbs.sys["lgtBridgeStats"]
    assert st["success"], st["message"]
    assert st["end_jump"] == pytest.approx(19.2, rel=0.05)
    q = _q_total(mbs)
    mbs, s = sm.slider_torque_at_end(switched=False)
    SolveDynamic(mbs, s, method="dop853", rtol=1e-13, atol=1e-13)
    assert np.abs(q - _q_total(mbs)).max() < 1e-9
    exu_q = []
    for n in (4000, 8000):
        mbs, s = sm.slider_torque_at_end(steps=n)
        s.timeIntegration.generalizedAlpha.spectralRadius = 0.6
        mbs.SolveDynamic(s)
        exu_q.append(_q_total(mbs))
    assert np.abs(exu_q[1] + (exu_q[1] - exu_q[0]) / 3 - q).max() < 2e-7
