"""group="auto" / chart="auto": per-body choices follow the scene's structure, and
the choice is the accurate one where it matters."""
import numpy as np
import pytest

from lgt_bridge import InputError, auto, scenes, simulate
from lgt_bridge.bench import pose_errors


@pytest.fixture(scope="module")
def mixed():
    m = scenes.top_and_free_bodies(3)
    ref = simulate(m, (0, 0.5), method="dopri5", rtol=1e-12, atol=1e-12, t_eval=[0.5])
    return m, ref.q[-1]


def _run(m, group, project):
    return simulate(m, (0, 0.5), method="rkmk4", dt=1e-3, group=group, chart="auto", project=project,
                    t_eval=[0.5])


def test_auto_unprojected_joint_goes_on_se3_and_stays_closed(mixed):
    m, q_ref = mixed
    r = _run(m, "auto", project=False)
    assert r.group == ["SE3", "SO3xR3", "SO3xR3", "SO3xR3"] and r.chart == ["exp"] * 4
    assert "not enforced" in r.stats["auto"][0]["reason"] and r.stats["auto"][0]["body"] == "top"
    so3 = _run(m, "SO3xR3", project=False)
    gap_auto = np.abs(m.constraints(r.q[-1])).max()
    gap_so3 = np.abs(m.constraints(so3.q[-1])).max()
    assert gap_auto < 1e-12 and gap_so3 > 1e-6           # SE(3) keeps the pinned point; SO(3)xR³ drifts
    # the free bodies integrate as on SO(3)xR³ (same numbers), the top as on SE(3)
    free = [i for b in m.layout.bodies[1:] for i in (*b.pos, *b.rot)]
    np.testing.assert_allclose(r.q[-1][free], so3.q[-1][free], rtol=0, atol=1e-14)
    se3 = _run(m, "SE3", project=False)
    top = [*m.layout.bodies[0].pos, *m.layout.bodies[0].rot]
    np.testing.assert_allclose(r.q[-1][top], se3.q[-1][top], rtol=0, atol=1e-14)
    assert sum(pose_errors(m, r.q[-1], q_ref)) <= sum(pose_errors(m, so3.q[-1], q_ref))


def test_auto_with_projection_picks_so3xr3_and_is_more_accurate_than_se3(mixed):
    m, q_ref = mixed
    r = _run(m, "auto", project=True)
    assert r.group == ["SO3xR3"] * 4 and "projection" in r.stats["auto"][0]["reason"]
    se3 = _run(m, "SE3", project=True)
    e_auto, e_se3 = sum(pose_errors(m, r.q[-1], q_ref)), sum(pose_errors(m, se3.q[-1], q_ref))
    assert e_auto < 0.2 * e_se3                            # measured: 1.5e-5 vs 3.3e-4
    g = simulate(m, (0, 0.01), method="genalpha", dt=1e-3, group="auto")
    assert g.group == ["SO3xR3"] * 4 and "index-3" in g.stats["auto"][0]["reason"]


def test_auto_mixes_with_explicit_entries_and_reads_the_jacobian():
    m = scenes.chain(3)
    assert auto.offset_joints(m) == [True, True, True]      # spherical joints at the link ends
    c = auto.choose(m, ["SE3", "auto", "auto"], "cay", method="rkmk4", project=False)
    assert c.groups == ["SE3", "SE3", "SE3"] and c.charts == ["cay"] * 3 and c.reasons[0] == "as given"
    assert "| link1 | SE3 | cay |" in c.table()
    # a joint at the frame origin (the centre of mass) does not couple ṙ and ω: no SE(3) needed
    top = scenes.heavy_top(True)
    at_com = scenes.RigidBodySystem(top.m, top.J, top.q0, top.V0, joints=[(0, np.zeros(3), -1, top.q0[:3])])
    assert auto.offset_joints(at_com) == [False]
    assert auto.choose(at_com, method="rkmk4", project=False).groups == ["SO3xR3"]
    assert auto.offset_joints(scenes.free_body()) == [False]


def test_auto_rejects_bad_entries():
    with pytest.raises(InputError, match="unknown group 'SE2'"):
        simulate(scenes.chain(2), (0, 0.01), dt=1e-3, group=["auto", "SE2"])
    with pytest.raises(InputError, match="got 1 values for 2 rigid bodies"):
        simulate(scenes.chain(2), (0, 0.01), dt=1e-3, group=["auto"])
