"""A rigid body written by the user as an ObjectGenericODE2 on Euler parameters, its norm
a user-written CoordinateVectorConstraint (Exudyn's rigidBodyAsUserFunctionTest.py): the
bridge's rotation coordinates keep the norm by construction, so that constraint is its only
row and is set aside; with no constraint row left the drop-in raised numpy's ValueError
(a maximum over no rows) before the first step. It now runs, and agrees with Exudyn's own
solver refined until converged and with the same body as an ObjectRigidBody."""
import pytest

exu = pytest.importorskip("exudyn")

import numpy as np  # noqa: E402

from lgt_bridge.errors import ModelNote  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

import exudyn_sweep_models as sm  # noqa: E402

W = exu.OutputVariableType.AngularVelocity
P = exu.OutputVariableType.Position


@pytest.fixture(scope="module")
def exudyn_converged():
    """ω and position of the user-function body at t = 0.05 by Exudyn's generalized-α,
    the step refined 4x until two runs agree to 1e-6 (relative)."""
    last = None
    for n in (200, 800, 3200):
        mbs, s, _, b = sm.rigid_body_as_user_function(n=n)
        exu.SolveDynamic(mbs, s)
        w = np.array(mbs.GetNodeOutput(b, W))
        if last is not None and np.abs(w - last).max() <= 1e-6 * np.abs(w).max():
            return w, np.array(mbs.GetNodeOutput(b, P))
        last = w
    pytest.fail("Exudyn's own solver did not converge on the reference")


@pytest.mark.parametrize("method, rtol", [("dopri5", 1e-6), ("radau5", 1e-6), ("genalpha", 1e-5)])
def test_the_user_written_rigid_body_agrees_with_exudyn_converged(method, rtol, exudyn_converged):
    w_ref, p_ref = exudyn_converged
    mbs, s, a, b = sm.rigid_body_as_user_function(n=50 if method != "genalpha" else 3200)
    s.timeIntegration.relativeTolerance = s.timeIntegration.absoluteTolerance = 1e-10
    with pytest.warns(ModelNote, match="redundant"):            # the norm row, set aside
        SolveDynamic(mbs, s, method=method)
    w = np.array(mbs.GetNodeOutput(b, W))
    assert np.abs(w - w_ref).max() <= rtol * np.abs(w_ref).max()
    assert np.array(mbs.GetNodeOutput(b, P)) == pytest.approx(p_ref, abs=1e-12)
    # the same body as Exudyn's ObjectRigidBody, integrated alongside
    assert np.abs(np.array(mbs.GetNodeOutput(a, W)) - w).max() <= 1e-8 * np.abs(w).max()
