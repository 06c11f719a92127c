"""ObjectJointSliding2D (a body sliding along an ANCF cable) is refused before the first
step: its third algebraic coordinate is the sliding coordinate, not a multiplier (Exudyn's
ANCFslidingJoint2D.py: dopri5's step size fell to 1e-8 s within the first millisecond,
genalpha's Newton diverged; ANCFslidingAndALEjointTest.py ran past 90 s)."""
import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge import InputError  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

import exudyn_sweep_models as sm  # noqa: E402


def _coords(mbs, node):
    return np.array(mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates))


@pytest.mark.parametrize("method", ["dopri5", "genalpha"])
def test_sliding_joint_is_refused_before_the_first_step_and_leaves_the_system_to_exudyn(method):
    """The refusal (before any note on the constraint rows) names the object and the reason
    and says what to do; the system is untouched: Exudyn's own solver then gives what it
    gives on a fresh copy, and the hanger has really slid along the wire (the joint is not
    pinned in Exudyn's solution)."""
    import warnings
    mbs, s, node = sm.slider_on_cable()
    with warnings.catch_warnings(record=True) as notes, pytest.raises(InputError) as exc:
        warnings.simplefilter("always")
        SolveDynamic(mbs, s, method=method)
    assert not [w for w in notes if "lgt_bridge" in str(w.message) or "constraint" in str(w.message)], \
        [str(w.message) for w in notes]           # refused before the rows are classified
    msg = str(exc.value)
    assert "ObjectJointSliding2D" in msg and "sliding coordinate" in msg and "exu.SolveDynamic" in msg
    mbs.SolveDynamic(s)
    after = _coords(mbs, node)
    fresh, s2, node2 = sm.slider_on_cable()
    fresh.SolveDynamic(s2)
    ref = _coords(fresh, node2)
    assert np.abs(after - ref).max() < 1e-12, (after, ref)
    assert ref[0] > 1e-4 and ref[1] < -1e-4, ref   # slid along (x) and sagged (y)
