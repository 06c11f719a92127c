"""A CoordinateVectorConstraint whose constraint user function ignores its ``velocityLevel``
argument (Exudyn's coordinateVectorConstraintGenericODE2.py writes it so; Exudyn's own
index-3 solvers never ask for the velocity level): Exudyn's velocity-level residual of those
rows is then g, not C_q q̇. The bridge took it for A V, and dopri5 drifted off the
constraints (the test model's result 2e-3 off Exudyn's converged one). Those rows' velocity
form now comes from the Jacobian, with a note; the results agree with Exudyn's own solver
refined until converged, and with the same model whose user function answers the velocity
level properly."""
import warnings

import pytest

exu = pytest.importorskip("exudyn")

import numpy as np  # noqa: E402

from lgt_bridge.errors import InputError, ModelNote  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

import exudyn_sweep_models as sm  # noqa: E402

P = exu.OutputVariableType.Position


@pytest.fixture(scope="module")
def exudyn_converged():
    """The tip's position at t = 0.5 by Exudyn's generalized-α, the step refined 4x until two
    runs agree to 1e-7 (absolute, on a 1.6 m pendulum)."""
    last = None
    for n in (500, 2000, 8000, 32000):
        mbs, s, tip = sm.pendulum_by_constraint_user_function(n=n)
        exu.SolveDynamic(mbs, s)
        p = np.array(mbs.GetNodeOutput(tip, P))
        if last is not None and np.abs(p - last).max() <= 1e-7:
            return p
        last = p
    pytest.fail("Exudyn's own solver did not converge on the reference")


@pytest.mark.parametrize("method", ["dopri5", "dop853", "radau5", "scipy:DOP853"])
def test_a_constraint_user_function_ignoring_velocity_level_is_followed(method, exudyn_converged):
    mbs, s, tip = sm.pendulum_by_constraint_user_function()
    s.timeIntegration.relativeTolerance = s.timeIntegration.absoluteTolerance = 1e-10
    with pytest.warns(ModelNote, match="velocityLevel"):
        SolveDynamic(mbs, s, method=method)
    assert np.abs(np.array(mbs.GetNodeOutput(tip, P)) - exudyn_converged).max() <= 1e-6


def test_it_matches_the_model_whose_user_function_answers_the_velocity_level():
    out = []
    for aware in (False, True):
        mbs, s, tip = sm.pendulum_by_constraint_user_function(velocity_aware=aware)
        s.timeIntegration.relativeTolerance = s.timeIntegration.absoluteTolerance = 1e-10
        with warnings.catch_warnings(record=True) as notes:
            warnings.simplefilter("always")
            SolveDynamic(mbs, s, method="dopri5")
        assert any("velocityLevel" in str(n.message) for n in notes) is not aware   # a note only when ignored
        out.append(np.array(mbs.GetNodeOutput(tip, P)))
    assert np.abs(out[0] - out[1]).max() <= 1e-8


def test_with_velocity_level_rows_as_well_it_is_an_input_error():
    mbs, s, _ = sm.pendulum_by_constraint_user_function(velocity_row=True)
    with pytest.raises(InputError, match="velocityLevel is True"):
        SolveDynamic(mbs, s, method="dopri5")
