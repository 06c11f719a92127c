"""generalized-α's modified Newton keeps its iteration matrix across steps
(lgt_bridge.integrators.newton_control) on the pinned ANCF cable pendulum (104 coordinates),
1 s at Exudyn's 1000 steps: it refreshes the matrix at most twice as often as Exudyn's own
modified Newton, and its result is the converged solution of the same discrete equations
(the run at newton_tol 1e-13) to 1e-8 and Exudyn's own generalized-α's to the digits both
methods' tolerances give."""
import warnings

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_exudyn import SolveDynamic, scenes  # noqa: E402
from lgt_exudyn.model import ExudynModel  # noqa: E402

T, STEPS = 1.0, 1000


def _settings():
    s = scenes.settings(T, STEPS)
    s.timeIntegration.newton.useModifiedNewton = True
    return s


def test_ancf_pendulum_refreshes_its_newton_matrix_as_rarely_as_exudyn():
    SC, mbs = scenes.ancf_pendulum()
    mbs.SolveDynamic(_settings())
    native = scenes.total_q(mbs)
    n_exudyn = mbs.sys["dynamicSolver"].it.newtonJacobiCount

    SC, mbs = scenes.ancf_pendulum()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        SolveDynamic(mbs, _settings(), method="genalpha")
    st = mbs.sys["lgtBridgeStats"]
    bridge = scenes.total_q(mbs)
    assert st["success"] and st["n_rejected"] == 0
    assert st["n_jacobians"] <= 2 * n_exudyn, (st["n_jacobians"], n_exudyn)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = ExudynModel(scenes.ancf_pendulum()[1])
        runs = [simulate(m, (0.0, T), method="genalpha", dt=T / STEPS, newton_tol=tol) for tol in (1e-10, 1e-13)]
    assert all(r.success for r in runs)
    # the same steps as SolveDynamic's, and the converged solution to 1e-8
    assert np.abs(runs[0].q[-1] - bridge).max() <= 1e-12 * max(1.0, np.abs(m.q0).max())
    assert np.abs(runs[0].q[-1] - runs[1].q[-1]).max() <= 1e-8
    assert np.abs(bridge - native).max() <= 3e-9
