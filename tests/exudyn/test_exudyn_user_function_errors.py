"""A user function that fails inside Exudyn's own step loop (found running Exudyn's test
models through ``lgt-bridge run``): the drop-in says so in the bridge's own error, naming
the user function and its Python error, never Exudyn's raw exception, on every kind of
method (in Exudyn's loop, before the first step or between steps: a ModelError; inside a
step of the bridge: the StepError of a failed step, the state kept)."""
import functools

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.errors import LGTError, ModelError  # noqa: E402
from lgt_exudyn import SolveDynamic  # noqa: E402

import exudyn_sweep_models as sm  # noqa: E402

METHODS = ["dopri5", "rkmk4", "radau5", "genalpha", "scipy:RK45"]


def _exudyns_own_error(build):
    """Exudyn's own solver on the same model: it raises too (the model is at fault)."""
    mbs, s = build()
    with pytest.raises(Exception) as info:
        exu.SolveDynamic(mbs, s)
    assert type(info.value).__module__.startswith("exudyn")
    return mbs.systemData.GetTime()


@pytest.mark.parametrize("sensor", [False, True], ids=["no-outputs", "acceleration-sensor"])
@pytest.mark.parametrize("method", METHODS)
def test_a_user_function_of_an_older_signature_is_the_bridges_error(method, sensor):
    build = functools.partial(sm.spring_with_old_user_function, acceleration_sensor=sensor)
    _exudyns_own_error(build)
    mbs, s = build()
    with pytest.raises(LGTError) as info:
        SolveDynamic(mbs, s, method=method)
    msg = str(info.value)
    assert "springForceUserFunction" in msg and "TypeError" in msg and "fix it" in msg
    assert "Python file" not in msg and "lgt_exudyn" not in msg   # no pointer to a frame of ours
    assert "At:" not in msg                                       # Exudyn's traceback left out


@pytest.mark.parametrize("method", METHODS)
def test_a_pre_step_user_function_raising_mid_run_stops_where_exudyn_stops(method):
    t_exudyn = _exudyns_own_error(sm.prestep_raising_at)
    mbs, s = sm.prestep_raising_at()
    with pytest.raises(ModelError, match=r"PreStepUserFunction.*ValueError: controller input missing"):
        SolveDynamic(mbs, s, method=method)
    assert mbs.systemData.GetTime() == pytest.approx(t_exudyn, abs=1e-12) == pytest.approx(0.05)


@pytest.mark.parametrize("method", METHODS)
def test_an_offset_user_function_of_an_older_signature_is_the_bridges_error(method):
    """Exudyn calls a constraint's offset user function while the bridge reads the
    constraint Jacobian (before the first step): its TypeError was Exudyn's raw exception."""
    build = functools.partial(sm.driven_coordinate, old_signature=True)
    _exudyns_own_error(lambda: build()[:2])
    mbs, s, _ = build()
    with pytest.raises(ModelError) as info:
        SolveDynamic(mbs, s, method=method)
    msg = str(info.value)
    assert "offsetUserFunction" in msg and "TypeError" in msg and "fix it" in msg
    assert "Python file" not in msg and "lgt_exudyn" not in msg and "At:" not in msg


@pytest.mark.parametrize("method", METHODS)
def test_the_coordinate_driven_by_its_offset_user_function_follows_it(method):
    mbs, s, node = sm.driven_coordinate()
    SolveDynamic(mbs, s, method=method)
    u = mbs.GetNodeOutput(node, exu.OutputVariableType.Displacement)[0]
    assert u == pytest.approx(0.1 * 0.5 * (1 - np.cos(0.5 * np.pi * 1.0)), abs=1e-10)   # 0.05 at t = 1
