"""An ALE cable whose ALE coordinate a CoordinateConstraint holds (Exudyn's
ANCFmovingRigidBodyTest.py holds it so for its static solve): Exudyn's mass matrix is
singular (positive definite only on the motions the constraints allow), which Exudyn's
implicit solvers handle and the bridge's solves, which invert the mass matrix, cannot. The
check before the first step passed it (it looked at the constrained motions only) and the
first evaluation failed with a ModelError naming no coordinate and advising positive masses;
now the check refuses it up front, naming the ALE coordinate and pointing to Exudyn's own
solver."""
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.errors import InputError  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

import exudyn_sweep_models as sm  # noqa: E402


def test_exudyns_own_solver_runs_the_held_ale_cable():
    mbs, s, _ = sm.ale_cable_held()
    assert exu.SolveDynamic(mbs, s)
    assert mbs.systemData.GetTime() == pytest.approx(s.timeIntegration.endTime)


@pytest.mark.parametrize("method", ["dopri5", "rkmk4", "radau5", "genalpha"])
def test_the_bridge_names_the_ale_coordinate_before_the_first_step(method):
    mbs, s, ale = sm.ale_cable_held()
    with pytest.raises(InputError) as info:
        SolveDynamic(mbs, s, method=method)
    msg = str(info.value)
    assert f"node {ale} (NodeGenericODE2)" in msg and "ObjectALEANCFCable2D" in msg
    assert "exu.SolveDynamic" in msg                      # what to do
    assert mbs.systemData.GetTime() == 0.0                 # refused before any step
