"""What Pinocchio users write to integrate a free-flyer model (shared/notes/pinocchio.md),
as baselines for the bench: semi-implicit Euler + pin.integrate, fixed-step RK4 on
(q, v) with quaternion renormalization, scipy DOP853 with renormalization; and the two
example scenes (free asymmetric body, floating humanoid)."""
import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation


def root_R(q):
    return Rotation.from_quat(q[3:7] / np.linalg.norm(q[3:7])).as_matrix()    # x y z w


def qdot(model, q, v):
    """Time derivative of Pinocchio's q for a free-flyer root + nq = nv joints."""
    p = np.array([q[6], q[3], q[4], q[5]])
    w, vl = v[3:6], v[:3]
    pd = 0.5 * np.concatenate([[-p[1:] @ w], p[0] * w + np.cross(p[1:], w)])
    return np.concatenate([root_R(q) @ vl, pd[1:], [pd[0]], v[6:]])


class Counter:
    def __init__(self, model):
        self.model, self.data, self.n = model, model.createData(), 0

    def aba(self, q, v):
        self.n += 1
        return pin.aba(self.model, self.data, q, v, np.zeros(self.model.nv))


def semi_implicit_euler(model, q, v, T, dt):
    c = Counter(model)
    for _ in range(int(round(T / dt))):
        v = v + dt * c.aba(q, v)
        q = pin.integrate(model, q, v * dt)
    return q, c.n


def rk4_renorm(model, q, v, T, dt):
    c = Counter(model)
    nq = model.nq

    def rhs(y):
        return np.concatenate([qdot(model, y[:nq], y[nq:]), c.aba(y[:nq], y[nq:])])

    y = np.concatenate([q, v])
    for _ in range(int(round(T / dt))):
        k1 = rhs(y)
        k2 = rhs(y + dt / 2 * k1)
        k3 = rhs(y + dt / 2 * k2)
        k4 = rhs(y + dt * k3)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        y[3:7] /= np.linalg.norm(y[3:7])
    return y[:nq], c.n


def dop853_renorm(model, q, v, T, tol):
    c = Counter(model)
    nq = model.nq

    def rhs(t, y):
        y = y.copy()
        y[3:7] /= np.linalg.norm(y[3:7])
        return np.concatenate([qdot(model, y[:nq], y[nq:]), c.aba(y[:nq], y[nq:])])

    s = solve_ivp(rhs, (0, T), np.concatenate([q, v]), method="DOP853", rtol=tol, atol=tol)
    y = s.y[:, -1].copy()
    y[3:7] /= np.linalg.norm(y[3:7])
    return y[:nq], c.n


def free_body():
    m = pin.Model()
    j = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    m.appendBodyToJoint(j, pin.Inertia(1.0, np.zeros(3), np.diag([1.0, 2.0, 3.0])), pin.SE3.Identity())
    m.gravity.linear[:] = 0.0
    return m, pin.neutral(m), np.array([0, 0, 0, 0.01, 2.0, 0.01])


def humanoid():
    """Pinocchio's random sample humanoid, the same on every call (Pinocchio's RNG is
    seeded: the bench builds the scene once per run, in several processes)."""
    pin.seed(3)
    m = pin.buildSampleModelHumanoidRandom()
    rng = np.random.default_rng(3)
    return m, pin.randomConfiguration(m, -np.ones(m.nq), np.ones(m.nq)), rng.normal(size=m.nv) * 0.5
