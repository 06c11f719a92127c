"""What ExudynModel keeps from one system for the next one built alike (the NodeLayout shared by
node signature, the initial coordinates' check, the kernels' tables by M̄'s value, and with the
layout the finished steppers of :mod:`lgt_bridge.integrators.steppers`): a model of
a system built afresh must run exactly as with nothing kept, whatever differs between the
systems (masses, inertias, names, node types, initial states)."""
import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from exudyn.utilities import RigidBodyInertia  # noqa: E402

from lgt_bridge import InputError, simulate  # noqa: E402
from lgt_bridge.integrators import steppers  # noqa: E402
from lgt_exudyn import kernel_tables, layout  # noqa: E402
from lgt_exudyn.model import ExudynModel  # noqa: E402

import exudyn_models as em  # noqa: E402


def bodies(node=em.ROTVEC, mass=1.0, inertia=(0.1, 0.2, 0.3), names=None, spin=(1.0, 2.0, 3.0), n=3, rot=None):
    """n free bodies (the first one's mass, principal inertias and spin as given)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    rng = np.random.default_rng(4)
    for k in range(n):
        J = np.diag(inertia) if k == 0 else np.diag(rng.uniform(0.1, 0.5, 3))
        kw = dict(inertia=RigidBodyInertia(mass=mass if k == 0 else 1.0 + k, inertiaTensor=J), nodeType=node,
                  referencePosition=[k, 0.0, 0.0], initialAngularVelocity=list(spin) if k == 0 else [0.0, k, 1.0],
                  initialVelocity=[0.0, 0.1 * k, 0.0], gravity=em.G)
        if names is not None:
            kw["name"] = names[k]
        if rot is not None and k == 0:
            kw["referenceRotationMatrix"] = rot
        mbs.CreateRigidBody(**kw)
    mbs.Assemble()
    return SC, mbs


def forget():
    """Nothing kept: the next model is built as the first one of its kind."""
    layout._LAYOUTS.clear()
    kernel_tables._TABLES.clear()
    kernel_tables._BLOCKS.clear()
    steppers._POOL.clear()


def run(make, **kw):
    """q, V at 0.5 s (dop853 at 1e-9) and the step count, of a model of a system built by make."""
    SC, mbs = make(**kw)
    r = simulate(ExudynModel(mbs), (0, 0.5), method="dop853", rtol=1e-9, atol=1e-9, t_eval=[0.5], progress=False)
    return r.q[-1], r.V[-1], r.stats["n_f"]


def same(a, b):
    return all(np.array_equal(x, y) for x, y in zip(a, b))


@pytest.mark.parametrize("change", [dict(mass=3.0), dict(inertia=(0.3, 0.1, 0.25)), dict(spin=(0.0, -4.0, 1.0)),
                                    dict(node=em.EP), dict(names=["a", "b", "c"]), dict(n=4)])
def test_a_system_built_after_another_runs_as_with_nothing_kept(change):
    run(bodies)                                     # the first system: its layout and tables kept
    kept = run(bodies, **change)
    forget()
    fresh = run(bodies, **change)
    assert same(kept, fresh)
    # and the first kind again, after the other
    again = run(bodies)
    forget()
    assert same(again, run(bodies))


def test_systems_built_alike_share_their_node_layout_and_tables_by_value():
    forget()
    m1, m2 = ExudynModel(bodies()[1]), ExudynModel(bodies()[1])
    assert m1.nodes is m2.nodes                     # one NodeLayout for the same signature
    m3 = ExudynModel(bodies(names=["a", "b", "c"])[1])
    assert m3.nodes is not m1.nodes                 # names are part of the layout (messages)
    heavier = ExudynModel(bodies(mass=5.0)[1])
    assert heavier.nodes is m1.nodes
    P1, P2, Ph = m1._pack(), m2._pack(), heavier._pack()
    assert P1.w is not P2.w and P1.T is not P2.T    # each model its own copies (the kernels write them)
    assert np.array_equal(P1.w, P2.w)
    assert not np.array_equal(P1.w, Ph.w)           # M̄ and its inverse follow the mass
    forget()
    Ph_fresh = ExudynModel(bodies(mass=5.0)[1])._pack()
    assert np.array_equal(Ph.w, Ph_fresh.w) and np.array_equal(Ph.T, Ph_fresh.T)


def test_the_initial_coordinates_check_is_not_skipped_for_another_state():
    forget()
    ExudynModel(bodies(node=em.EP)[1])              # a valid state passes and is remembered
    SC, mbs = bodies(node=em.EP)
    # the same layout with Euler parameters that are not a unit quaternion: still refused
    mbs.systemData.SetODE2Coordinates(mbs.systemData.GetODE2Coordinates() + 0.1, exu.ConfigurationType.Initial)
    with pytest.raises(InputError, match="Euler parameters"):
        ExudynModel(mbs)
