"""Independent references for the integrator tests: plain quaternion ODEs solved by
scipy at tight tolerance, written here without any lgt_bridge code."""
import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation


def qmul(p, q):
    return np.concatenate([[p[0] * q[0] - p[1:] @ q[1:]], p[0] * q[1:] + q[0] * p[1:] + np.cross(p[1:], q[1:])])


def qmat(p):
    return Rotation.from_quat(p, scalar_first=True).as_matrix()


def rigid_rotation(J, w0, T, torque=None, p0=(1.0, 0, 0, 0), t_eval=None):
    """Body rotation ṗ = ½ p ⊗ (0, ω), J ω̇ = -ω × Jω + torque(R): returns (R(T), ω(T))."""
    J = np.asarray(J, float)

    def rhs(t, y):
        p, w = y[:4], y[4:]
        tq = torque(qmat(p / np.linalg.norm(p))) if torque else 0.0
        return np.concatenate([0.5 * qmul(p, np.concatenate([[0.0], w])), np.linalg.solve(J, -np.cross(w, J @ w) + tq)])

    sol = solve_ivp(rhs, (0, T), np.concatenate([p0, w0]), method="DOP853", rtol=1e-13, atol=1e-13,
                    t_eval=t_eval)
    assert sol.success
    if t_eval is not None:
        return sol
    p = sol.y[:4, -1]
    return qmat(p / np.linalg.norm(p)), sol.y[4:, -1]


HT_M, HT_C = 15.0, np.array([0.0, 1.0, 0.0])
HT_JP = np.diag([0.234375, 0.46875, 0.234375]) + HT_M * (np.eye(3) - np.outer(HT_C, HT_C))
HT_W0 = np.array([0.0, 150.0, -4.61538])


def heavy_top(T, t_eval=None):
    g = np.array([0.0, 0.0, -9.81])
    return rigid_rotation(HT_JP, HT_W0, T, torque=lambda R: np.cross(HT_C, R.T @ (HT_M * g)), t_eval=t_eval)


def angle(R1, R2):
    """Rotation angle between two rotation matrices."""
    return float(np.linalg.norm(Rotation.from_matrix(R1.T @ R2).as_rotvec()))


def slope(dts, errs):
    return float(np.polyfit(np.log(dts), np.log(errs), 1)[0])
