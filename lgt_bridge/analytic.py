"""Closed-form references.

:func:`torque_free_omega` — body angular velocity of a torque-free rigid body
with principal inertias (Euler's equations J ω̇ = -ω × Jω), in Jacobi elliptic
functions (Landau & Lifshitz, Mechanics §37). With the axes relabelled so that
the "dn" axis c is the one the motion circulates around (the largest inertia if
‖L‖² > 2 E J_mid, else the smallest), a the other extreme and b the middle:

    ω_a = A_a cn(u),  ω_b = s_b A_b sn(u),  ω_c = s A_c dn(u),   u = λ t + u0
    A_a² = (2E J_c - L²) / (J_a (J_c - J_a)),   A_b² = (2E J_c - L²) / (J_b (J_c - J_b)),
    A_c² = (L² - 2E J_a) / (J_c (J_c - J_a)),   λ² = (J_c - J_b)(L² - 2E J_a) / (J_a J_b J_c),
    m = k² = (J_b - J_a)(2E J_c - L²) / ((J_c - J_b)(L² - 2E J_a)),

s = sign ω_c(0), s_b = s ε sign(J_c - J_b) (ε the parity of (a, b, c)) and u0 from (cn u0, sn u0) at t = 0. Valid away from the
separatrix ‖L‖² = 2E J_mid.
"""
import numpy as np
from scipy.special import ellipj, ellipkinc

from .errors import InputError


def torque_free_omega(t, inertia, omega0):
    """ω(t) in the principal body frame, for principal inertias ``inertia`` (3,)."""
    J = np.asarray(inertia, float)
    w0 = np.asarray(omega0, float)
    t = np.atleast_1d(np.asarray(t, float))
    if J.shape != (3,) or np.any(J <= 0) or len(set(J)) < 3:
        raise InputError("torque_free_omega: give three distinct positive principal inertias.")
    E2 = np.sum(J * w0 ** 2)                       # 2E
    L2 = np.sum((J * w0) ** 2)
    order = np.argsort(J)
    mid = J[order[1]]
    if abs(L2 - E2 * mid) <= 1e-12 * L2:
        raise InputError("torque_free_omega: the motion is on the separatrix (|L|² = 2E J_mid).")
    c, a = (order[2], order[0]) if L2 > E2 * mid else (order[0], order[2])
    b = order[1]
    Ja, Jb, Jc = J[a], J[b], J[c]
    Aa = np.sqrt((E2 * Jc - L2) / (Ja * (Jc - Ja)))
    Ab = np.sqrt((E2 * Jc - L2) / (Jb * (Jc - Jb)))
    Ac = np.sqrt((L2 - E2 * Ja) / (Jc * (Jc - Ja)))
    lam = np.sqrt((Jc - Jb) * (L2 - E2 * Ja) / (Ja * Jb * Jc))
    m = (Jb - Ja) * (E2 * Jc - L2) / ((Jc - Jb) * (L2 - E2 * Ja))
    s = 1.0 if w0[c] >= 0 else -1.0
    # direction of travel: J_a ω̇_a = ε (J_b - J_c) ω_b ω_c (ε = +1 if (a, b, c) is a cyclic
    # permutation of (0, 1, 2), else -1) must equal -J_a A_a λ sn dn: s_b s_c = ε sign(J_c - J_b)
    eps = 1.0 if (a, b, c) in ((0, 1, 2), (1, 2, 0), (2, 0, 1)) else -1.0
    sb = s * eps * np.sign(Jc - Jb)
    phi0 = np.arctan2(w0[b] / (sb * Ab), w0[a] / Aa)       # amplitude: cn = cos φ, sn = sin φ
    u0 = ellipkinc(phi0, m)
    sn, cn, dn, _ = ellipj(lam * t + u0, m)
    out = np.empty((len(t), 3))
    out[:, a], out[:, b], out[:, c] = Aa * cn, sb * Ab * sn, s * Ac * dn
    return out
