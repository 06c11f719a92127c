"""Generalized-α's analytic Newton matrix of a :class:`lgt_pinocchio.PinocchioModel`, from
Pinocchio's analytic RNEA derivatives mapped to the twist coordinates (see
:meth:`lgt_pinocchio.PinocchioModel.iteration_matrix` for the formulas)."""
import numpy as np

from lgt_bridge.groups.batch import cross, hat, to_matrix

from .constraints import geometric_stiffness
from .joints import J2, planar_R


def iteration_parts(m, q, V, t, lam=None, Vdot=None):
    """(M̄, C_t, K_t) of ``m.iteration_matrix`` as dense arrays, on a Data of the model's own
    (``m._it_data``, made by the first call)."""
    pin, model, joints, nv = m.pin, m.model, m.joints, m.nv
    if getattr(m, "_it_data", None) is None:
        m._it_data = model.createData()
    d = m._it_data
    q = np.array(q, float)
    V = np.asarray(V, float)
    v = m.v_from_twist(q, V)
    T = joints.T(q)
    nc = m.n_constraints
    u = m.loads.generalized(t, q, v, d)
    residual = True                    # r(q, v, a) ≠ 0 at a: (∂Tᵀ/∂z) r is needed
    if Vdot is not None:
        a = T @ np.asarray(Vdot, float) + joints.TdV(v, q)
    elif nc and lam is not None:
        # Tᵀ r + Aᵀλ = 0 with T orthogonal: r = -T Aᵀλ, a = aba(u - T Aᵀλ)
        a = np.array(pin.aba(model, d, q, v, u - T @ (m.constraint_jacobian(q).T @ np.asarray(lam, float))))
    elif nc:
        a = np.array(m.cons.dynamics(q, v, u))
    else:
        a = np.array(pin.aba(model, d, q, v, u))
        residual = False
    r = pin.rnea(model, d, q, v, a) - u if residual else None
    dq, dv, Mp = (np.array(x) for x in pin.computeRNEADerivatives(model, d, q, v, a))
    Mp = np.triu(Mp) + np.triu(Mp, 1).T
    du = m.loads.derivatives(t, q, v, u, d)
    if du is not None:
        dq -= du[0]
        dv -= du[1]
    # ∂v/∂z, ∂a/∂z, ∂a/∂V on the free-flyers (rows v_lin; z and V columns (θ | ω, ṙ))
    Nv, Na, Ea = np.zeros((nv, nv)), np.zeros((nv, nv)), np.zeros((nv, nv))
    dT = np.zeros((nv, nv))
    if len(joints.roots):
        R = to_matrix(joints.quats(q))
        i = np.array([iv for _, iv in joints.roots])[:, None]
        vl, w, al = v[i + np.arange(3)], v[i + np.arange(3, 6)], a[i + np.arange(3)]
        Hv, Hw, Ha = hat(vl), hat(w), hat(al + cross(w, vl))     # a_lin = Rᵀr̈ - ω × Rᵀṙ
        for k, (_, iv) in enumerate(joints.roots):
            lin, ang = slice(iv, iv + 3), slice(iv + 3, iv + 6)
            Nv[lin, lin] = Hv[k]
            Na[lin, lin] = Ha[k] - Hw[k] @ Hv[k]
            Ea[lin, lin] = Hv[k]
            Ea[lin, ang] = -Hw[k] @ R[k].T
            if r is not None:
                dT[ang, lin] = -R[k] @ hat(r[None, lin])[0]              # (Tᵀ r)_ṙ = R r_lin
    for iq, iv in joints.planars:
        # planar: v_xy = R(θ)ᵀ ṗ and a_xy = R(θ)ᵀ p̈ - ω J v_xy turn with δθ (column iv + 2)
        R2, xy, th = planar_R(q, iq), slice(iv, iv + 2), iv + 2
        Nv[xy, th] = -J2 @ v[xy]
        Na[xy, th] = -J2 @ a[xy]
        Ea[xy, xy] = -v[th] * (J2 @ R2.T)
        Ea[xy, th] = -J2 @ v[xy]
        if r is not None:
            dT[xy, th] = R2 @ (J2 @ r[xy])                               # (Tᵀ r)_ṗ = R r_xy
    Tt = T.T
    M = Tt @ Mp @ T
    C = Tt @ (dv @ T + Mp @ Ea)
    K = Tt @ (dq @ T + dv @ Nv + Mp @ Na) + dT
    if nc and lam is not None:
        K += geometric_stiffness(m, q, np.asarray(lam, float))
    return M, C, K
