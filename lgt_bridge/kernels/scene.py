"""Kernels of the engine-free scenes (:class:`lgt_bridge.scenes.RigidBodySystem`): the
right-hand side f(q, V) = V̇ of rigid bodies in absolute coordinates, Newton-Euler in
V = (ω body, ṙ inertial), with gravity, pivoted bodies, zero-length spring-dampers and
spherical joints (index 1: A M⁻¹Aᵀ λ = A M⁻¹Q + γ), and the joints' g, A and γ.

A scene is packed once (:func:`pack`) into one int64 array ``I`` and one float64 array
``F``: a header of sizes and offsets (``I[:NHEAD]``), then flat row-major tables and work
buffers, so that a kernel call takes few arguments (numba's dispatch costs ≈ 0.1 µs per
argument) and the kernels index plain 1-D slices:

* per body (float, NBF columns): mass, translational M⁻¹ (0 for a pivoted body),
  J (3x3), J⁻¹, centre of mass c (pivoted bodies); (int) pivoted 0/1;
* ``rb``: the bodies whose rotation matrix is needed (pivot, spring or joint);
* springs ``(i, j)`` (int) and ``(s_i, s_j, k, d)`` (float); joints ``(i, j)`` and
  ``(s_i, s_j)``; j = -1 is the ground, s_j then a ground point;
* ``first``: the first non-zero column of each row of A M⁻¹Aᵀ (its envelope, which
  the Cholesky factor keeps);
* work: gravity, rotation matrices R (9 per body), the joints' blocks -R s̃ and
  J⁻¹(-R s̃)ᵀ (2 x 9 per joint), A M⁻¹Aᵀ and its factor, λ, Q.

The entry points :func:`f`, :func:`constraints`, :func:`constraint_jacobian` and
:func:`constraint_gamma` take (I, F), the state and a preallocated output. The numpy
reference is the scene's ``_f_numpy``, ``_constraints_numpy`` etc.; tests hold the two
equal (1e-13). Plain loops: ``NUMBA_DISABLE_JIT=1`` runs the same source interpreted.
"""
import math
from pathlib import Path

import numpy as np
from numba import njit

from . import guard_cache
from .linalg import cholesky, cholesky_solve
from .rotations import cross, to_quat

guard_cache(__file__, extra=(Path(__file__).with_name("linalg.py"),))

# per body float columns
MASS, MINVT, J, JINV, COM = 0, 1, 2, 11, 20
NBF = 23
# header of I: sizes, then offsets into I (int tables) and into F (float tables)
NB, CODE, NROT, NS, NJ, NRB = range(6)
I_PIVOT, I_RB, I_SP, I_JT, I_FIRST, I_END = range(6, 12)
F_G, F_BODY, F_SP, F_JT, F_R, F_B, F_G2, F_S, F_LAM, F_Q, F_END = range(12, 23)
NHEAD = 23


def pack(code, nrot, mass, inertia, inertia_inv, pivot, c, gravity, springs, joints):
    """(I, F) of a scene (see the module docstring)."""
    nb, ns, nj = len(mass), len(springs), len(joints)
    body = np.zeros((nb, NBF))
    body[:, MASS] = mass
    body[:, MINVT] = np.where(pivot, 0.0, 1.0 / np.asarray(mass, float))
    body[:, J:J + 9] = np.reshape(inertia, (nb, 9))
    body[:, JINV:JINV + 9] = np.reshape(inertia_inv, (nb, 9))
    body[:, COM:COM + 3] = c
    sp = np.array([(s[0], s[2]) for s in springs], np.int64).reshape(ns, 2)
    spf = np.array([(*np.asarray(s[1], float), *np.asarray(s[3], float), s[4], s[5]) for s in springs],
                   float).reshape(ns, 8)
    jt = np.array([(s[0], s[2]) for s in joints], np.int64).reshape(nj, 2)
    jtf = np.array([(*np.asarray(s[1], float), *np.asarray(s[3], float)) for s in joints],
                   float).reshape(nj, 6)
    need = np.asarray(pivot, bool).copy()
    for ij in (sp, jt):
        need[ij[ij >= 0]] = True
    rb = np.flatnonzero(need).astype(np.int64)
    # the envelope of A M⁻¹Aᵀ: joint k's rows start at the first joint sharing a body with it
    first_at = np.full(nb, nj)
    for k in range(nj - 1, -1, -1):
        first_at[jt[k][jt[k] >= 0]] = k
    first = np.repeat([3 * first_at[jt[k][jt[k] >= 0]].min() for k in range(nj)], 3).astype(np.int64)
    ints = [np.asarray(pivot, np.int64), rb, sp.ravel(), jt.ravel(), first]
    floats = [np.asarray(gravity, float).ravel(), body.ravel(), spf.ravel(), jtf.ravel(),
              np.zeros(9 * nb if len(rb) else 0),                         # R
              np.zeros(18 * nj), np.zeros(18 * nj),                         # -R s̃, J⁻¹(-R s̃)ᵀ
              np.zeros(9 * nj * nj), np.zeros(3 * nj), np.zeros(6 * nb)]    # A M⁻¹Aᵀ, λ, Q
    head = np.zeros(NHEAD, np.int64)
    head[[NB, CODE, NROT, NS, NJ, NRB]] = nb, code, nrot, ns, nj, len(rb)
    head[I_PIVOT:I_END + 1] = NHEAD + np.cumsum([0] + [len(a) for a in ints])
    head[F_G:F_END + 1] = np.cumsum([0] + [len(a) for a in floats])
    return np.concatenate([head] + ints).astype(np.int64), np.concatenate(floats)


@njit(cache=True)
def _rotations(I, F, q):
    """R (row major, 9 per body) of the bodies rb: the formula of
    ``quaternion._to_matrix``, I + 2 (p0 P + P P) with P = p̃."""
    code, nu = I[CODE], 3 + I[NROT]
    R = F[I[F_R]:I[F_B]]
    for n in range(I[I_RB], I[I_SP]):
        b = I[n]
        o = b * nu + 3
        r3 = q[o + 3] if nu == 7 else 0.0
        p0, p1, p2, p3 = to_quat(code, q[o], q[o + 1], q[o + 2], r3)
        a, bb, cc = p1 * p1, p2 * p2, p3 * p3
        o = 9 * b
        R[o] = 1.0 + 2.0 * (-cc - bb)
        R[o + 1] = 2.0 * (-p0 * p3 + p1 * p2)
        R[o + 2] = 2.0 * (p0 * p2 + p1 * p3)
        R[o + 3] = 2.0 * (p0 * p3 + p1 * p2)
        R[o + 4] = 1.0 + 2.0 * (-cc - a)
        R[o + 5] = 2.0 * (-p0 * p1 + p2 * p3)
        R[o + 6] = 2.0 * (-p0 * p2 + p1 * p3)
        R[o + 7] = 2.0 * (p0 * p1 + p2 * p3)
        R[o + 8] = 1.0 + 2.0 * (-bb - a)
    return R


@njit(cache=True)
def _rot(R, b, x0, x1, x2):
    o = 9 * b
    return (R[o] * x0 + R[o + 1] * x1 + R[o + 2] * x2,
            R[o + 3] * x0 + R[o + 4] * x1 + R[o + 5] * x2,
            R[o + 6] * x0 + R[o + 7] * x1 + R[o + 8] * x2)


@njit(cache=True)
def _rot_t(R, b, x0, x1, x2):
    o = 9 * b
    return (R[o] * x0 + R[o + 3] * x1 + R[o + 6] * x2,
            R[o + 1] * x0 + R[o + 4] * x1 + R[o + 7] * x2,
            R[o + 2] * x0 + R[o + 5] * x1 + R[o + 8] * x2)


@njit(cache=True)
def _point(q, V, R, nu, b, s0, s1, s2):
    """Position and velocity of the body point s (body frame) of body b."""
    o, v = b * nu, 6 * b
    x0, x1, x2 = _rot(R, b, s0, s1, s2)
    c0, c1, c2 = cross(V[v], V[v + 1], V[v + 2], s0, s1, s2)
    u0, u1, u2 = _rot(R, b, c0, c1, c2)
    return q[o] + x0, q[o + 1] + x1, q[o + 2] + x2, V[v + 3] + u0, V[v + 4] + u1, V[v + 5] + u2


@njit(cache=True)
def _pivot_moment(bf, R, b, m, g0, g1, g2):
    """Gravity moment c × Rᵀ m g of a pivoted body about its pivot (body frame)."""
    a0, a1, a2 = _rot_t(R, b, g0, g1, g2)
    c = NBF * b + COM
    return cross(bf[c], bf[c + 1], bf[c + 2], m * a0, m * a1, m * a2)


@njit(cache=True)
def _solve_mass(bf, b, out, t0, t1, t2, f0, f1, f2):
    """out[6b:6b+6] = M_b⁻¹ (t, f): J⁻¹ t and f / m (0 for a pivoted body)."""
    v, j = 6 * b, NBF * b + JINV
    out[v] = bf[j] * t0 + bf[j + 1] * t1 + bf[j + 2] * t2
    out[v + 1] = bf[j + 3] * t0 + bf[j + 4] * t1 + bf[j + 5] * t2
    out[v + 2] = bf[j + 6] * t0 + bf[j + 7] * t1 + bf[j + 8] * t2
    mi = bf[NBF * b + MINVT]
    out[v + 3], out[v + 4], out[v + 5] = mi * f0, mi * f1, mi * f2


@njit(cache=True)
def _springs(nu, q, V, R, sp, spf, Q):
    """Q += the spring-dampers' (torque body, force inertial) on their bodies."""
    for n in range(sp.shape[0] // 2):
        i, j = sp[2 * n], sp[2 * n + 1]
        o = 8 * n
        k, d = spf[o + 6], spf[o + 7]
        pi0, pi1, pi2, vi0, vi1, vi2 = _point(q, V, R, nu, i, spf[o], spf[o + 1], spf[o + 2])
        if j >= 0:
            pj0, pj1, pj2, vj0, vj1, vj2 = _point(q, V, R, nu, j, spf[o + 3], spf[o + 4], spf[o + 5])
        else:
            pj0, pj1, pj2, vj0, vj1, vj2 = spf[o + 3], spf[o + 4], spf[o + 5], 0.0, 0.0, 0.0
        F0 = k * (pj0 - pi0) + d * (vj0 - vi0)
        F1 = k * (pj1 - pi1) + d * (vj1 - vi1)
        F2 = k * (pj2 - pi2) + d * (vj2 - vi2)
        v = 6 * i
        Q[v + 3] += F0
        Q[v + 4] += F1
        Q[v + 5] += F2
        a0, a1, a2 = _rot_t(R, i, F0, F1, F2)
        c0, c1, c2 = cross(spf[o], spf[o + 1], spf[o + 2], a0, a1, a2)
        Q[v] += c0
        Q[v + 1] += c1
        Q[v + 2] += c2
        if j >= 0:
            v = 6 * j
            Q[v + 3] -= F0
            Q[v + 4] -= F1
            Q[v + 5] -= F2
            a0, a1, a2 = _rot_t(R, j, F0, F1, F2)
            c0, c1, c2 = cross(spf[o + 3], spf[o + 4], spf[o + 5], a0, a1, a2)
            Q[v] -= c0
            Q[v + 1] -= c1
            Q[v + 2] -= c2


@njit(cache=True)
def _joint_blocks(nj, jt, jtf, bf, R, B, G):
    """B[18k + 9e:] = -R s̃ of end e of joint k, G[...] = J⁻¹ Bᵀ (row major 3x3)."""
    for k in range(nj):
        for e in range(2):
            b = jt[2 * k + e]
            if b < 0:
                continue
            s0, s1, s2 = jtf[6 * k + 3 * e], jtf[6 * k + 3 * e + 1], jtf[6 * k + 3 * e + 2]
            o, ob, ji = 9 * b, 18 * k + 9 * e, NBF * b + JINV
            for r in range(3):
                R0, R1, R2 = R[o + 3 * r], R[o + 3 * r + 1], R[o + 3 * r + 2]
                B[ob + 3 * r] = -R1 * s2 + R2 * s1
                B[ob + 3 * r + 1] = R0 * s2 - R2 * s0
                B[ob + 3 * r + 2] = -R0 * s1 + R1 * s0
            for r in range(3):
                for c in range(3):
                    G[ob + 3 * r + c] = (bf[ji + 3 * r] * B[ob + 3 * c]
                                         + bf[ji + 3 * r + 1] * B[ob + 3 * c + 1]
                                         + bf[ji + 3 * r + 2] * B[ob + 3 * c + 2])


@njit(cache=True)
def _gamma(nj, jt, jtf, R, V, out):
    """out = γ = R_i (ω_i × (ω_i × s_i)) - R_j (ω_j × (ω_j × s_j)) of every joint."""
    for k in range(nj):
        out[3 * k], out[3 * k + 1], out[3 * k + 2] = 0.0, 0.0, 0.0
        for e in range(2):
            b = jt[2 * k + e]
            if b < 0:
                continue
            sg = 1.0 - 2.0 * e
            v, o = 6 * b, 6 * k + 3 * e
            w0, w1, w2 = V[v], V[v + 1], V[v + 2]
            a0, a1, a2 = cross(w0, w1, w2, jtf[o], jtf[o + 1], jtf[o + 2])
            c0, c1, c2 = cross(w0, w1, w2, a0, a1, a2)
            x0, x1, x2 = _rot(R, b, c0, c1, c2)
            out[3 * k] += sg * x0
            out[3 * k + 1] += sg * x1
            out[3 * k + 2] += sg * x2


@njit(cache=True)
def f(I, F, q, V, load, out):
    """out = V̇ = M⁻¹(Q + load - Aᵀλ), A M⁻¹Aᵀ λ = A M⁻¹(Q + load) + γ; ``load``
    (nb, 6) (torque body, force inertial) is added when it has rows."""
    nb, nj = I[NB], I[NJ]
    pivot, bf = I[I[I_PIVOT]:I[I_RB]], F[I[F_BODY]:I[F_SP]]
    R = _rotations(I, F, q)
    if I[NS] == 0 and load.shape[0] == 0:
        # no springs, no load: M⁻¹ of each body's own wrench at once (no pass over a Q
        # buffer: measurably faster at 10⁴ bodies)
        for b in range(nb):
            v = 6 * b
            _wrench(bf, R, V, pivot, F, I, b, out)
            _solve_mass(bf, b, out, out[v], out[v + 1], out[v + 2], out[v + 3], out[v + 4], out[v + 5])
    else:
        Q = F[I[F_Q]:I[F_END]]
        _forces(I, F, q, V, R, load, Q)
        for b in range(nb):
            v = 6 * b
            _solve_mass(bf, b, out, Q[v], Q[v + 1], Q[v + 2], Q[v + 3], Q[v + 4], Q[v + 5])
    if nj == 0:
        return
    jt, jtf, first = I[I[I_JT]:I[I_FIRST]], F[I[F_JT]:I[F_R]], I[I[I_FIRST]:I[I_END]]
    B, G, S, lam = F[I[F_B]:I[F_G2]], F[I[F_G2]:I[F_S]], F[I[F_S]:I[F_LAM]], F[I[F_LAM]:I[F_Q]]
    _joint_blocks(nj, jt, jtf, bf, R, B, G)
    _gamma(nj, jt, jtf, R, V, lam)
    # λ's right-hand side A M⁻¹Q + γ
    for k in range(nj):
        for e in range(2):
            b = jt[2 * k + e]
            if b < 0:
                continue
            sg = 1.0 - 2.0 * e
            v, ob = 6 * b, 18 * k + 9 * e
            for r in range(3):
                lam[3 * k + r] += sg * (B[ob + 3 * r] * out[v] + B[ob + 3 * r + 1] * out[v + 1]
                                        + B[ob + 3 * r + 2] * out[v + 2] + out[v + 3 + r])
    # A M⁻¹Aᵀ: blocks of joints sharing a body, lower triangle within the envelope
    n = 3 * nj
    for i in range(n):
        for c in range(first[i], 3 * (i // 3) + 3):
            S[n * i + c] = 0.0
    for k in range(nj):
        for l in range(first[3 * k] // 3, k + 1):
            for e in range(2):
                b = jt[2 * k + e]
                if b < 0:
                    continue
                for h in range(2):
                    if jt[2 * l + h] != b:
                        continue
                    sg = (1.0 - 2.0 * e) * (1.0 - 2.0 * h)
                    mi = bf[NBF * b + MINVT]
                    ob, og = 18 * k + 9 * e, 18 * l + 9 * h
                    for r in range(3):
                        for c in range(3):
                            s = (B[ob + 3 * r] * G[og + c] + B[ob + 3 * r + 1] * G[og + 3 + c]
                                 + B[ob + 3 * r + 2] * G[og + 6 + c])
                            if r == c:
                                s += mi
                            S[n * (3 * k + r) + 3 * l + c] += sg * s
    if not cholesky(S, n, first)[0]:         # redundant joints: no unique λ, V̇ not finite
        for i in range(out.shape[0]):
            out[i] = math.nan
        return
    cholesky_solve(S, n, first, lam)
    # V̇ -= M⁻¹Aᵀλ: J⁻¹Bᵀλ = Gλ on ω, λ/m on ṙ
    for k in range(nj):
        l0, l1, l2 = lam[3 * k], lam[3 * k + 1], lam[3 * k + 2]
        for e in range(2):
            b = jt[2 * k + e]
            if b < 0:
                continue
            sg = 1.0 - 2.0 * e
            v, og = 6 * b, 18 * k + 9 * e
            for r in range(3):
                out[v + r] -= sg * (G[og + 3 * r] * l0 + G[og + 3 * r + 1] * l1 + G[og + 3 * r + 2] * l2)
            mi = bf[NBF * b + MINVT]
            out[v + 3] -= sg * mi * l0
            out[v + 4] -= sg * mi * l1
            out[v + 5] -= sg * mi * l2


@njit(cache=True)
def forces(I, F, q, V, load, out):
    """out = Q + load: -ω × Jω and gravity (a pivoted body: the gravity moment, no force),
    the springs' forces and torques, and ``load`` (nb, 6) when it has rows (the generalized
    forces of M V̇ = Q - Aᵀλ, for generalized-α's residual)."""
    _forces(I, F, q, V, _rotations(I, F, q), load, out)


@njit(cache=True, inline="always")      # numba-level inlining: a call per body costs 2-3x at 10⁴ bodies
def _wrench(bf, R, V, pivot, F, I, b, out):
    """Body b's own wrench into out[6b:6b+6]: -ω × Jω and gravity; a pivoted body: its
    gravity moment, no force."""
    g0, g1, g2 = F[I[F_G]], F[I[F_G] + 1], F[I[F_G] + 2]
    v, o = 6 * b, NBF * b
    w0, w1, w2 = V[v], V[v + 1], V[v + 2]
    j = o + J
    Jw0 = bf[j] * w0 + bf[j + 1] * w1 + bf[j + 2] * w2
    Jw1 = bf[j + 3] * w0 + bf[j + 4] * w1 + bf[j + 5] * w2
    Jw2 = bf[j + 6] * w0 + bf[j + 7] * w1 + bf[j + 8] * w2
    t0, t1, t2 = cross(w0, w1, w2, Jw0, Jw1, Jw2)
    m = bf[o + MASS]
    if pivot[b]:
        c0, c1, c2 = _pivot_moment(bf, R, b, m, g0, g1, g2)
        out[v], out[v + 1], out[v + 2] = -t0 + c0, -t1 + c1, -t2 + c2
        out[v + 3], out[v + 4], out[v + 5] = 0.0, 0.0, 0.0
    else:
        out[v], out[v + 1], out[v + 2] = -t0, -t1, -t2
        out[v + 3], out[v + 4], out[v + 5] = m * g0, m * g1, m * g2


@njit(cache=True)
def _forces(I, F, q, V, R, load, out):
    """The generalized forces of :func:`forces` at the body rotations R."""
    nu, pivot, bf = 3 + I[NROT], I[I[I_PIVOT]:I[I_RB]], F[I[F_BODY]:I[F_SP]]
    for b in range(I[NB]):
        _wrench(bf, R, V, pivot, F, I, b, out)
    _springs(nu, q, V, R, I[I[I_SP]:I[I_JT]], F[I[F_SP]:I[F_JT]], out)
    for b in range(load.shape[0]):
        for c in range(6):
            out[6 * b + c] += load[b, c]


@njit(cache=True)
def constraints(I, F, q, out):
    """out = g(q) = p_i - p_j of every joint (p_j a ground point for j = -1)."""
    R = _rotations(I, F, q)
    nu, jt, jtf = 3 + I[NROT], I[I[I_JT]:I[I_FIRST]], F[I[F_JT]:I[F_R]]
    for k in range(I[NJ]):
        i, j, o = jt[2 * k], jt[2 * k + 1], 6 * k
        x0, x1, x2 = _rot(R, i, jtf[o], jtf[o + 1], jtf[o + 2])
        x0, x1, x2 = q[i * nu] + x0, q[i * nu + 1] + x1, q[i * nu + 2] + x2
        if j >= 0:
            y0, y1, y2 = _rot(R, j, jtf[o + 3], jtf[o + 4], jtf[o + 5])
            y0, y1, y2 = q[j * nu] + y0, q[j * nu + 1] + y1, q[j * nu + 2] + y2
        else:
            y0, y1, y2 = jtf[o + 3], jtf[o + 4], jtf[o + 5]
        out[3 * k], out[3 * k + 1], out[3 * k + 2] = x0 - y0, x1 - y1, x2 - y2


@njit(cache=True)
def constraint_gamma(I, F, q, V, out):
    """out = γ(q, V) = (d/dt A) V of every joint."""
    R = _rotations(I, F, q)
    _gamma(I[NJ], I[I[I_JT]:I[I_FIRST]], F[I[F_JT]:I[F_R]], R, V, out)


@njit(cache=True)
def constraint_jacobian(I, F, q, A):
    """A(q) (3 nj, 6 nb), zero on entry: [-R_i s̃_i, I] and [R_j s̃_j, -I] per joint."""
    R = _rotations(I, F, q)
    nj, jt = I[NJ], I[I[I_JT]:I[I_FIRST]]
    B, G = F[I[F_B]:I[F_G2]], F[I[F_G2]:I[F_S]]
    _joint_blocks(nj, jt, F[I[F_JT]:I[F_R]], F[I[F_BODY]:I[F_SP]], R, B, G)
    for k in range(nj):
        for e in range(2):
            b = jt[2 * k + e]
            if b < 0:
                continue
            sg, ob = 1.0 - 2.0 * e, 18 * k + 9 * e
            for r in range(3):
                for c in range(3):
                    A[3 * k + r, 6 * b + c] = sg * B[ob + 3 * r + c]
                A[3 * k + r, 6 * b + 3 + r] = sg
