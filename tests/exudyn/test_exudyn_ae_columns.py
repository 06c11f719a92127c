"""The constraint rows of Exudyn's system Jacobian from columns of the velocity-level residual
(lgt_exudyn.ae_columns, used above MIN_UNKNOWNS system unknowns: Exudyn hands its Jacobian to
Python only whole and dense, 2.5 ms at 527 unknowns) against Exudyn's own ComputeJacobianAE, and
whole runs on each. The model: Exudyn's RigidBody2D four-bar on RevoluteJoint2D (rows the
adapter takes from Exudyn's Jacobian), its crank driven at constant speed by a velocity-level
CoordinateConstraint (a row whose ∂C/∂q Exudyn leaves zero), the threshold lowered to reach it."""
import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from exudyn.itemInterface import CoordinateConstraint, MarkerNodeCoordinate, NodePointGround  # noqa: E402

from lgt_bridge.simulate import simulate  # noqa: E402
from lgt_exudyn import ae_columns  # noqa: E402
from lgt_exudyn.model import ExudynModel  # noqa: E402

from exudyn_solver_models import crank_rocker_fourbar  # noqa: E402


def driven_fourbar(drive="velocity", omega=4.0):
    """The crank driven at ``omega``: a velocity-level CoordinateConstraint (``velocity``), or a
    position-level one whose offset user functions move it as θ0 + ω t (``position``: its
    velocity-level row has -ω, the constraint's ∂C/∂t, at zero velocities)."""
    mbs, _ = crank_rocker_fourbar(omega0=omega)
    ground = mbs.AddNode(NodePointGround())
    m0 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    m1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=0, coordinate=2))     # the crank's angle
    if drive == "velocity":
        mbs.AddObject(CoordinateConstraint(markerNumbers=[m0, m1], offset=omega, velocityLevel=True))
    else:
        mbs.AddObject(CoordinateConstraint(markerNumbers=[m0, m1], offsetUserFunction=lambda mbs, t, itemNumber, offset: omega * t,
                                           offsetUserFunction_t=lambda mbs, t, itemNumber, offset: omega))
    mbs.Assemble()
    return mbs


def model(columns, monkeypatch, drive="velocity"):
    monkeypatch.setattr(ae_columns, "MIN_UNKNOWNS", 0 if columns else 10 ** 9)
    m = ExudynModel(driven_fourbar(drive))
    m.f(m.q0, m.V0, 0.0)
    return m


@pytest.mark.parametrize("drive", ["velocity", "position"])
def test_constraint_rows_by_columns_equal_exudyns_jacobian(monkeypatch, drive):
    a, b = model(True, monkeypatch, drive), model(False, monkeypatch, drive)
    assert any(isinstance(c, ae_columns.AEColumns) for c in a.engine._ae_columns.values())
    assert all(c is False for c in b.engine._ae_columns.values())
    rng = np.random.default_rng(4)
    for _ in range(5):
        q = a._moved(a.q0, rng.normal(size=a.nv) * 0.3, 1.0)
        A, B = a.constraint_jacobian(q), b.constraint_jacobian(q)
        assert np.abs(A).max() > 0.1
        assert np.abs(A - B).max() <= 1e-14 * np.abs(B).max()


@pytest.mark.parametrize("drive", ["velocity", "position"])
def test_runs_on_the_column_rows_equal_runs_on_exudyns_jacobian(monkeypatch, drive):
    runs = []
    for columns in (True, False):
        m = model(columns, monkeypatch, drive)
        r = simulate(m, (0.0, 0.3), method="dopri5", rtol=1e-9, atol=1e-9)
        assert r.success, r.message
        runs.append(r)
    a, b = runs
    assert a.stats["n_steps"] == b.stats["n_steps"]
    assert np.abs(a.q[-1] - b.q[-1]).max() <= 1e-11
    assert np.abs(a.V[-1] - b.V[-1]).max() <= 1e-9
    assert np.abs(a.q[-1] - a.q[0]).max() > 0.1                 # (the four-bar moved)


def test_a_row_exudyn_would_not_give_so_keeps_exudyns_jacobian(monkeypatch):
    """A probe that disagrees with Exudyn's Jacobian at the first state is not used."""
    monkeypatch.setattr(ae_columns, "MIN_UNKNOWNS", 0)
    monkeypatch.setattr(ae_columns, "structural_pattern",
                        lambda engine, velocity_rows=False: (np.array([engine.ae0]), np.array([0])))
    m = ExudynModel(driven_fourbar())
    m.f(m.q0, m.V0, 0.0)
    assert m.engine._ae_columns and all(c is False for c in m.engine._ae_columns.values())
