"""What Pinocchio users write to integrate a free-flyer model (shared/notes/pinocchio.md),
as baselines for the bench: semi-implicit Euler + pin.integrate, fixed-step RK4 on
(q, v) with quaternion renormalization, scipy DOP853 with renormalization; the PD
torque users write (``pd_torque``); and the two example scenes (free asymmetric body,
floating humanoid).

Every loop takes ``tau``: None (zero torque) or ``tau(t, q, v)`` returning the joint
torques (size nv) from Pinocchio's own q and v, the same callable
:class:`~lgt_pinocchio.PinocchioModel` takes, so baseline and bridge integrate one model."""
import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp


def root_R(q):
    """The free-flyer root's rotation matrix (Pinocchio's own quaternion, x y z w stored)."""
    return pin.Quaternion(q[6], q[3], q[4], q[5]).normalized().toRotationMatrix()


_PLANS = {}


def _plan(model):
    """None for a free-flyer root + nq = nv joints; else (q indices, v indices) of the
    nq = nv joints after the root and (cos index, sin index, v index) arrays of its
    continuous joints (URDF ``continuous``: q = (cos θ, sin θ), v = θ̇). Kept per model object."""
    hit = _PLANS.get(id(model))
    if hit is not None and hit[0] is model:
        return hit[1]
    iq, iv, cq, sq, cv = [], [], [], [], []
    for j in range(2, model.njoints):
        jm = model.joints[j]
        if jm.nq == jm.nv:
            iq += range(jm.idx_q, jm.idx_q + jm.nq)
            iv += range(jm.idx_v, jm.idx_v + jm.nv)
        elif jm.nq == 2 and jm.nv == 1:
            cq.append(jm.idx_q), sq.append(jm.idx_q + 1), cv.append(jm.idx_v)
        else:
            raise ValueError(f"baselines: joint {model.names[j]!r} is a {jm.shortname()} (nq = {jm.nq}, "
                             f"nv = {jm.nv}); the users' loops here take nq = nv and continuous joints.")
    plan = None if not cq else tuple(np.array(x, int) for x in (iq, iv, cq, sq, cv))
    if len(_PLANS) > 64:
        _PLANS.clear()
    _PLANS[id(model)] = (model, plan)
    return plan


def qdot(model, q, v):
    """Time derivative of Pinocchio's q for a free-flyer root + nq = nv and continuous
    joints, written as fast as a user would: Pinocchio's quaternion for R, the quaternion
    rate ½ p ⊗ (0, ω) by hand (a scipy ``Rotation`` per call costs 28 µs against 4.7 µs),
    a continuous joint's (cos θ, sin θ) rate (-sin θ, cos θ) θ̇."""
    x, y, z, w = q[3], q[4], q[5], q[6]
    wx, wy, wz = v[3], v[4], v[5]
    out = np.empty(len(q))
    out[:3] = root_R(q) @ v[:3]
    out[3] = 0.5 * (w * wx + y * wz - z * wy)
    out[4] = 0.5 * (w * wy + z * wx - x * wz)
    out[5] = 0.5 * (w * wz + x * wy - y * wx)
    out[6] = -0.5 * (x * wx + y * wy + z * wz)
    plan = _plan(model)
    if plan is None:
        out[7:] = v[6:]
        return out
    iq, iv, cq, sq, cv = plan
    out[iq] = v[iv]
    out[cq] = -q[sq] * v[cv]
    out[sq] = q[cq] * v[cv]
    return out


def renormalize(model, q):
    """Project q back onto its unit constraints in place: the root's quaternion and every
    continuous joint's (cos θ, sin θ), as users do after a vector-space step."""
    q[3:7] /= np.linalg.norm(q[3:7])
    plan = _plan(model)
    if plan is not None:
        cq, sq = plan[2], plan[3]
        r = np.hypot(q[cq], q[sq])
        q[cq] /= r
        q[sq] /= r
    return q


class Counter:
    """pin.aba with the torque ``tau`` (None: zero), counting the calls."""

    def __init__(self, model, tau=None):
        self.model, self.data, self.n = model, model.createData(), 0
        self.tau, self.zero = tau, np.zeros(model.nv)

    def aba(self, q, v, t=0.0):
        self.n += 1
        tau = self.zero if self.tau is None else self.tau(t, q, v)
        return pin.aba(self.model, self.data, q, v, tau)


def semi_implicit_euler(model, q, v, T, dt, tau=None):
    c = Counter(model, tau)
    for k in range(int(round(T / dt))):
        v = v + dt * c.aba(q, v, k * dt)
        q = pin.integrate(model, q, v * dt)
    return q, c.n


def rk4_renorm(model, q, v, T, dt, tau=None):
    c = Counter(model, tau)
    nq = model.nq

    def rhs(y, t):
        return np.concatenate([qdot(model, y[:nq], y[nq:]), c.aba(y[:nq], y[nq:], t)])

    y = np.concatenate([q, v])
    for k in range(int(round(T / dt))):
        t = k * dt
        k1 = rhs(y, t)
        k2 = rhs(y + dt / 2 * k1, t + dt / 2)
        k3 = rhs(y + dt / 2 * k2, t + dt / 2)
        k4 = rhs(y + dt * k3, t + dt)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        renormalize(model, y[:nq])
    return y[:nq], c.n


def dop853_renorm(model, q, v, T, tol, tau=None):
    c = Counter(model, tau)
    nq = model.nq

    def rhs(t, y):
        y = y.copy()
        renormalize(model, y[:nq])
        return np.concatenate([qdot(model, y[:nq], y[nq:]), c.aba(y[:nq], y[nq:], t)])

    s = solve_ivp(rhs, (0, T), np.concatenate([q, v]), method="DOP853", rtol=tol, atol=tol)
    if s.status != 0:
        raise RuntimeError(f"solve_ivp DOP853: {s.message}")
    y = s.y[:, -1].copy()
    renormalize(model, y[:nq])
    return y[:nq], c.n


def pd_torque(model, q_ref, kp, kd):
    """tau(t, q, v) = kp (q_ref - q) - kd v on the actuated joints (every joint after the
    free-flyer root; their configuration spaces are vector spaces, nq = nv), zero on the
    root: what users write for joint-space PD control. kp, kd: scalars or vectors of
    size nv - 6 (one gain per actuated joint). ``tau.derivatives(t, q, v)`` gives its
    constant Jacobians (dtau_dq, dtau_dv) for PinocchioModel's tau_derivatives."""
    iq, iv = _actuated(model)
    kp = np.broadcast_to(np.asarray(kp, float), iv.shape).copy()
    kd = np.broadcast_to(np.asarray(kd, float), iv.shape).copy()
    target = np.asarray(q_ref, float)[iq].copy()
    nv = model.nv
    if np.array_equal(iq, np.arange(7, model.nq)) and np.array_equal(iv, np.arange(6, nv)):
        iq, iv = slice(7, None), slice(6, None)      # the usual layout: views, no gathers

    def tau(t, q, v):
        out = np.zeros(nv)
        out[iv] = kp * (target - q[iq]) - kd * v[iv]
        return out

    dq, dv = np.zeros((nv, nv)), np.zeros((nv, nv))
    iv_all = np.arange(nv)[iv]
    dq[iv_all, iv_all] = -kp                 # the actuated joints' tangent is their q (nq = nv)
    dv[iv_all, iv_all] = -kd

    def derivatives(t, q, v):
        return dq, dv
    tau.derivatives = derivatives            # (dtau_dq, dtau_dv): PinocchioModel(tau_derivatives=...)
    return tau


def _actuated(model):
    """(q indices, v indices) of the joints after the free-flyer root, all with nq = nv."""
    iq, iv = [], []
    for j in range(2, model.njoints):
        jm = model.joints[j]
        if jm.nq != jm.nv:
            raise ValueError(f"pd_torque: joint {model.names[j]!r} is a {jm.shortname()} (nq = {jm.nq}, "
                             f"nv = {jm.nv}); only joints with nq = nv are actuated here.")
        iq += range(jm.idx_q, jm.idx_q + jm.nq)
        iv += range(jm.idx_v, jm.idx_v + jm.nv)
    return np.array(iq, int), np.array(iv, int)


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
