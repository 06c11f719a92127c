"""The catalogue of engine-free scenes, each built on :class:`~lgt_bridge.scenes.system.RigidBodySystem`
(see :mod:`lgt_bridge.scenes` for the list). All take ``param`` = "quat" (Exudyn Euler
parameters), "quat_xyzw", "rotvec" or "rxyz" for the absolute rotation coordinates.
"""
import numpy as np

from .. import params as _params
from ..groups import quaternion as _q
from .system import RigidBodySystem


def _rot_coords(param, R0):
    p = _q._from_matrix(np.asarray(R0, float).reshape(-1, 3, 3))
    prev = np.zeros((len(p), param.nrot))
    if param.nrot == 4:
        prev[:, 0 if param.name == "quat_wxyz" else 3] = 1.0
    return param._from_quat(p, prev)


def free_body(inertia=(1.0, 2.0, 3.0), omega0=(0.01, 2.0, 0.01), *, mass=1.0, R0=None,
              r0=(0.0, 0.0, 0.0), v0=(0.0, 0.0, 0.0), param="quat"):
    """Torque-free rigid body (no gravity), frame at the centre of mass."""
    param = _params.get(param)
    J = np.diag(inertia) if np.ndim(inertia) == 1 else np.asarray(inertia, float)
    R0 = np.eye(3) if R0 is None else R0
    q0 = np.concatenate([r0, _rot_coords(param, R0)[0]])
    V0 = np.concatenate([omega0, v0]).astype(float)
    return RigidBodySystem([mass], [J], q0, V0, param=param, gravity=np.zeros(3), names=["body"])


HEAVY_TOP = dict(m=15.0, J_com=np.diag([0.234375, 0.46875, 0.234375]), com=np.array([0.0, 1.0, 0.0]),
                 omega0=np.array([0.0, 150.0, -4.61538]))


def heavy_top(constrained=False, *, param="quat", omega0=None, R0=None):
    """The heavy top benchmark (m = 15, centre of mass (0, 1, 0) from the pivot).

    constrained=False: body frame at the pivot, J = J_com + m(‖c‖²I - ccᵀ), rotation only.
    constrained=True: body frame at the centre of mass, spherical joint to ground at the pivot.
    """
    param = _params.get(param)
    m, Jc, c = HEAVY_TOP["m"], HEAVY_TOP["J_com"], HEAVY_TOP["com"]
    w0 = HEAVY_TOP["omega0"] if omega0 is None else np.asarray(omega0, float)
    R0 = np.eye(3) if R0 is None else np.asarray(R0, float)
    rot = _rot_coords(param, R0)[0]
    if not constrained:
        Jp = Jc + m * (c @ c * np.eye(3) - np.outer(c, c))
        return RigidBodySystem([m], [Jp], np.concatenate([np.zeros(3), rot]),
                               np.concatenate([w0, np.zeros(3)]), param=param,
                               pivot_com={0: c}, names=["top"])
    q0 = np.concatenate([R0 @ c, rot])
    V0 = np.concatenate([w0, R0 @ np.cross(w0, c)])
    return RigidBodySystem([m], [Jc], q0, V0, param=param, joints=[(0, -c, -1, np.zeros(3))],
                           names=["top"])


def chain(n=5, *, param="quat", length=1.0, mass=1.0, spin=2.0):
    """n slender links along x joined by spherical joints, the first to ground at the
    origin; released horizontally while the whole chain turns about the vertical at
    ``spin`` rad/s (a consistent rigid motion), so it swings and twists in 3-D."""
    param = _params.get(param)
    L = length
    J = mass * np.diag([1e-3 * L * L, L * L / 12, L * L / 12])
    rot = _rot_coords(param, np.eye(3))[0]
    q0, V0 = [], []
    for k in range(n):
        x = (k + 0.5) * L
        q0.append(np.concatenate([[x, 0.0, 0.0], rot]))
        V0.append([0.0, 0.0, spin, 0.0, spin * x, 0.0])
    half = np.array([L / 2, 0, 0])
    joints = [(0, -half, -1, np.zeros(3))] + [(k, -half, k - 1, half) for k in range(1, n)]
    return RigidBodySystem([mass] * n, [J] * n, np.concatenate(q0), np.concatenate(V0).astype(float),
                           param=param, joints=joints, names=[f"link{k}" for k in range(n)])


def pendulum(theta0=2.5, *, d=0.6, mass=2.0, inertia=(0.05, 0.08, 0.03), constrained=False, param="quat"):
    """A compound pendulum swinging about the y axis under gravity, released from rest at the
    angle ``theta0`` (rad) about y: centre of mass at c = (0, 0, -d) from the pivot in the body
    frame (so its x is -d sin θ, zero at the vertical), principal moments ``inertia`` about
    the centre of mass.

    constrained=False: body frame at the pivot (``pivot_com``), unconstrained rotation;
    constrained=True: body frame at the centre of mass, a spherical joint to ground at the
    pivot (projected after explicit steps, index 3 in genalpha). ``equivalent_length`` is
    I_pivot,yy/(m d): the simple pendulum of the same period, 4 K(sin²(θ0/2)) √(l/g)."""
    param = _params.get(param)
    c = np.array([0.0, 0.0, -float(d)])
    s, co = np.sin(theta0), np.cos(theta0)
    R0 = np.array([[co, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, co]])
    rot = _rot_coords(param, R0)[0]
    Jc = np.diag(np.asarray(inertia, float))
    Jp = Jc + mass * (c @ c * np.eye(3) - np.outer(c, c))
    if constrained:
        m = RigidBodySystem([mass], [Jc], np.concatenate([R0 @ c, rot]), np.zeros(6), param=param,
                            joints=[(0, -c, -1, np.zeros(3))], names=["pendulum"])
    else:
        m = RigidBodySystem([mass], [Jp], np.concatenate([np.zeros(3), rot]), np.zeros(6), param=param,
                            pivot_com={0: c}, names=["pendulum"])
    m.equivalent_length = Jp[1, 1] / (mass * d)
    return m


def top_and_free_bodies(n_free=3, *, param="quat", seed=0):
    """The heavy top on its spherical joint (frame at the centre of mass) plus
    ``n_free`` unjointed bodies falling and tumbling beside it: a scene whose bodies
    need different groups when the joint is not projected."""
    rng = np.random.default_rng(seed)
    param = _params.get(param)
    top = heavy_top(True, param=param)
    J = [principal_inertia(rng) for _ in range(n_free)]
    p = rng.normal(size=(n_free, 4))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    rot = _rot_coords(param, _q._to_matrix(p))
    q_free = np.concatenate([rng.normal(size=(n_free, 3)) + [3.0, 0.0, 0.0], rot], axis=1).ravel()
    V_free = np.concatenate([rng.normal(size=(n_free, 3)) * 5.0, rng.normal(size=(n_free, 3))], axis=1).ravel()
    return RigidBodySystem([top.m[0], *np.ones(n_free)], [top.J[0], *J], np.concatenate([top.q0, q_free]),
                           np.concatenate([top.V0, V_free]), param=param, joints=top.joints,
                           names=["top"] + [f"free{k}" for k in range(n_free)])


def principal_inertia(rng):
    """Random principal moments of a physical body: (b+c, a+c, a+b) for random second
    moments a, b, c > 0 of its mass distribution, so the triangle inequality holds."""
    a, b, c = rng.uniform(0.25, 1.5, 3)
    return np.diag(np.sort([b + c, a + c, a + b]))


def free_bodies(n=100, *, param="quat", seed=0):
    """n independent torque-free bodies with random inertias, attitudes and spins (for scaling)."""
    rng = np.random.default_rng(seed)
    param = _params.get(param)
    J = [principal_inertia(rng) for _ in range(n)]
    p = rng.normal(size=(n, 4))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    R0 = _q._to_matrix(p)
    rot = _rot_coords(param, R0)
    q0 = np.concatenate([rng.normal(size=(n, 3)), rot], axis=1).ravel()
    V0 = np.concatenate([rng.normal(size=(n, 3)) * 2.0, rng.normal(size=(n, 3))], axis=1).ravel()
    return RigidBodySystem(np.ones(n), J, q0, V0, param=param, gravity=np.zeros(3),
                           names=[f"body{k}" for k in range(n)])
