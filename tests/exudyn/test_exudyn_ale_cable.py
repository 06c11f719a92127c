"""An ALE cable whose ALE coordinate a CoordinateConstraint holds (Exudyn's
ANCFmovingRigidBodyTest.py holds it so for its static solve): Exudyn's mass matrix is
singular (positive definite only on the motions the constraints allow), which Exudyn's
implicit solvers handle and the bridge's solves, which invert the mass matrix, cannot. The
check before the first step passed it (it looked at the constrained motions only) and the
first evaluation failed with a ModelError naming no coordinate and advising positive masses;
now the check refuses it up front, naming the ALE coordinate and pointing to Exudyn's own
solver."""
import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.errors import InputError  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

import exudyn_rope_models as rm  # noqa: E402
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


def test_a_pipe_whose_whole_mass_moves_with_the_fluid_is_refused_naming_the_moving_mass_factor():
    """Exudyn's ALEANCF_pipe.py (physicsMovingMassFactor = 1, the fluid speed held by a
    velocity-level constraint): its mass matrix is singular because an ALE motion and an axial
    motion of the straight pipe carry the same kinetic energy, a direction the constraints hold.
    The refusal used to say the ALE coordinate had no inertia and advised giving every body a
    positive mass (it has 10 kg); it now says the constraints hold the motion, that Exudyn runs
    it, and that a moving-mass factor below 1 makes the mass matrix regular."""
    mbs, s, _ = rm.ale_pipe(1.0)
    assert exu.SolveDynamic(mbs, s)                        # Exudyn's own solver runs it
    for method in ("dopri5", "genalpha"):
        mbs, s, ale = rm.ale_pipe(1.0)
        with pytest.raises(InputError) as info:
            SolveDynamic(mbs, s, method=method)
        msg = str(info.value)
        assert f"node {ale} (NodeGenericODE2)" in msg and "constraints hold that motion" in msg
        assert "physicsMovingMassFactor = 1" in msg and "exu.SolveDynamic" in msg
        assert "positive mass" not in msg
        assert mbs.systemData.GetTime() == 0.0


def test_a_pipe_with_part_of_its_mass_moving_runs_and_agrees_with_exudyn():
    """The same pipe with physicsMovingMassFactor = 0.2 (what the refusal advises): the bridge
    runs it, dopri5 within 1e-8 of Exudyn's own generalized-α refined until converged (2000 and
    20000 steps agree to 4e-8; 100000 steps put 20000 within 5e-10)."""
    ref = []
    for n in (2000, 20000):
        mbs, s, _ = rm.ale_pipe(0.2, steps=n)
        assert exu.SolveDynamic(mbs, s)
        ref.append(mbs.systemData.GetODE2Coordinates().copy())
    assert np.abs(ref[0] - ref[1]).max() < 5e-8             # second order: 20000 steps within ~5e-10
    mbs, s, _ = rm.ale_pipe(0.2)
    SolveDynamic(mbs, s, method="dopri5", progress=False)
    assert np.abs(mbs.systemData.GetODE2Coordinates() - ref[1]).max() < 1e-8
