"""The engine-free reference multibody model, :class:`RigidBodySystem`: rigid bodies in
absolute coordinates with springs and spherical joints, its f, mass matrix, constraints
and iteration matrix, in pure numpy (the reference) and, with numba, over the compiled
kernels of :mod:`lgt_bridge.kernels.scene`. The scenes built on it are in
:mod:`lgt_bridge.scenes.catalogue`.
"""
import numpy as np

from .. import backend as _backend
from .. import params as _params
from ..errors import InputError
from ..groups import quaternion as _q
from ..groups._vec import cross, hat
from ..model import Layout, Model

GRAVITY = np.array([0.0, 0.0, -9.81])
_ND, _F64 = np.ndarray, np.dtype(np.float64)
_KS = None          # lgt_bridge.kernels.scene, imported by the first compiled scene


def _kernels():
    global _KS
    if _KS is None:
        from ..kernels import scene
        _KS = scene
    return _KS


class RigidBodySystem(Model):
    """Rigid bodies in absolute coordinates, Newton-Euler in V = (ω body, ṙ inertial).

    bodies: per body ``mass`` and ``inertia`` (3x3, body frame); the body frame is at
    the centre of mass, unless ``pivot_com`` gives the centre of mass in the body
    frame of a body whose frame origin is a fixed pivot (then ``inertia`` is about
    the pivot and the body's position stays where it is).
    joints: spherical, ``(i, s_i, j, s_j)``: point s_i of body i coincides with point
    s_j of body j (body frames), j = -1 for ground (s_j a ground point).
    springs: ``(i, s_i, j, s_j, k, d)`` zero-length spring-dampers between points.
    load: optional ``load(t, q, V) -> (forces (N,3) inertial, torques (N,3) body)``.

    The backend (:mod:`lgt_bridge.backend`) is fixed when the scene is built: with numba,
    ``f`` and the joints' ``constraints``, ``constraint_jacobian`` and ``constraint_gamma``
    run compiled kernels (:mod:`lgt_bridge.kernels.scene`) over tables packed here, so
    masses, inertias, gravity, pivots, springs and joints are read once; ``load`` (called from
    Python) may be set or replaced later. The numpy methods ``_f_numpy`` etc. stay the
    reference.
    """

    def __init__(self, masses, inertias, q0, V0, *, param="quat", gravity=GRAVITY,
                 pivot_com=None, joints=(), springs=(), load=None, names=None):
        self.param = _params.get(param)
        self.nb = nb = len(masses)
        self.layout = Layout.stacked([self.param] * nb, names=names)
        self.m = np.asarray(masses, float)
        self.J = np.asarray(inertias, float).reshape(nb, 3, 3)
        try:
            self.Jinv = np.linalg.inv(self.J)
        except np.linalg.LinAlgError:
            k = next((i for i in range(nb) if np.linalg.det(self.J[i]) == 0.0), 0)
            raise InputError(f"body {k}: its inertia matrix {self.J[k].tolist()} is singular; give "
                             "positive principal moments of inertia.") from None
        self.g = np.asarray(gravity, float)
        self.pivot = np.zeros(nb, bool)
        self.c = np.zeros((nb, 3))
        for i, c in (pivot_com or {}).items():
            self.pivot[i], self.c[i] = True, c
        self.q0, self.V0 = np.asarray(q0, float), np.asarray(V0, float)
        self.param.validate(self.q0.reshape(nb, -1), "q0")
        nu = self.param.nu
        self._qi = np.arange(nb * nu).reshape(nb, nu)
        self.joints = joints
        self.n_constraints = 3 * len(joints)
        if joints:
            ji = np.array([j[0] for j in joints])
            jj = np.array([j[2] for j in joints])
            if np.any(self.pivot[ji]) or np.any(self.pivot[jj[jj >= 0]]):
                raise InputError("joints attach to bodies with their frame at the centre of mass; "
                                 "a pivoted body is already held at its pivot.")
            self._ji, self._jj = ji, jj
            self._si = np.array([j[1] for j in joints], float)
            self._sj = np.array([j[3] for j in joints], float)
            self._ground = jj < 0
        self.springs = springs
        self.load = load
        Minv = np.zeros((nb, 6, 6))
        Minv[:, :3, :3] = self.Jinv
        Minv[:, 3:, 3:] = np.eye(3) / self.m[:, None, None]
        Minv[self.pivot, 3:, 3:] = 0.0            # a pivot's translation is held
        self._Minv = Minv
        self.compiled = _backend.compiled()
        if self.compiled:
            self._pack()
        # the backend chosen once: the protocol's methods call these implementations
        kf = "_kernel" if self.compiled else "_numpy"
        kc = "_kernel" if self.compiled and self.n_constraints else "_numpy"
        self._f, self._forces = getattr(self, "_f" + kf), getattr(self, "_forces" + kf)
        self._constraints = getattr(self, "_constraints" + kc)
        self._constraint_jacobian = getattr(self, "_constraint_jacobian" + kc)
        self._constraint_gamma = getattr(self, "_constraint_gamma" + kc)

    def _pack(self):
        """Kernel tables and work buffers, allocated once (numba is imported here)."""
        from ..kernels.rotations import PARAM_CODES
        self._kI, self._kF = _kernels().pack(PARAM_CODES[self.param.name], self.param.nrot, self.m, self.J,
                                             self.Jinv, self.pivot, self.c, self.g, self.springs, self.joints)
        self._kload = np.zeros((self.nb, 6))
        self._knoload = np.zeros((0, 6))

    # --- kinematics ------------------------------------------------------------
    def _poses(self, q):
        Q = q[self._qi]
        return Q[:, :3], _q._to_matrix(self.param._to_quat(Q[:, 3:]))

    # --- model protocol ----------------------------------------------------------
    def mass_matrix(self, q):
        """Block diagonal and constant in these coordinates: diag(J_i, m_i I)."""
        if not hasattr(self, "_M"):
            blocks = np.zeros((self.nb, 6, 6))
            blocks[:, :3, :3] = self.J
            blocks[:, 3:, 3:] = self.m[:, None, None] * np.eye(3)
            M = np.zeros((self.nb, 6, self.nb, 6))
            M[np.arange(self.nb), :, np.arange(self.nb), :] = blocks
            self._M = M.reshape(6 * self.nb, 6 * self.nb)
        return self._M.copy()

    def solve_mass(self, q, B):
        B = np.asarray(B, float)
        Bb = B.reshape(self.nb, 6, -1)
        out = np.einsum("nij,njk->nik", self._Minv, Bb)
        return out.reshape(B.shape)

    def forces(self, q, V, t):
        """Q(q, V, t) of M V̇ = Q - Aᵀλ (torque body, force inertial per body); a new array."""
        return self._forces(q, V, t)

    def _forces_kernel(self, q, V, t):
        out = np.empty(6 * self.nb)
        (_KS or _kernels()).forces(self._kI, self._kF, *self._kernel_inputs(q, V, t), out)
        return out

    def _forces_numpy(self, q, V, t):
        r, R = self._poses(q)
        W = V.reshape(self.nb, 6)
        w = W[:, :3]
        Jw = np.einsum("nij,nj->ni", self.J, w)
        torque = -cross(w, Jw)
        force = self.m[:, None] * self.g
        if self.pivot.any():
            # gravity moment about the pivot, body frame: c × Rᵀ m g
            Rtg = np.einsum("nji,j->ni", R[self.pivot], self.g)
            torque[self.pivot] += cross(self.c[self.pivot], self.m[self.pivot, None] * Rtg)
            force[self.pivot] = 0.0
        if self.springs:
            for (i, si, j, sj, k, d) in self.springs:
                pi, vi = r[i] + R[i] @ si, W[i, 3:] + R[i] @ np.cross(w[i], si)
                if j >= 0:
                    pj, vj = r[j] + R[j] @ sj, W[j, 3:] + R[j] @ np.cross(w[j], sj)
                else:
                    pj, vj = np.asarray(sj, float), np.zeros(3)
                F = k * (pj - pi) + d * (vj - vi)                 # on body i, inertial
                force[i] += F
                torque[i] += np.cross(si, R[i].T @ F)
                if j >= 0:
                    force[j] -= F
                    torque[j] -= np.cross(sj, R[j].T @ F)
        if self.load is not None:
            F, T = self.load(t, q, V)
            force = force + F
            torque = torque + T
        return np.concatenate([torque, force], axis=1).ravel()

    def iteration_matrix(self, q, V, t, c_acc, c_vel, c_pos, lam=None, sparse=False):
        """M c_acc + C_t c_vel + K_t c_pos for generalized-α, in V = (ω body, ṙ inertial) and
        the increments z = (δθ body, δr inertial) of SO(3)xR³, with C_t = -∂Q/∂V and
        K_t = ∂(Aᵀλ - Q)/∂z: the gyroscopic damping ∂(ω × Jω)/∂ω = ω~J - (Jω)~, the gravity
        moment of a pivoted body (δ(Rᵀg) = (Rᵀg)~ δθ), the springs' damping and stiffness
        (a stiff spring needs its K_t for Newton to converge) and, given the joint forces
        ``lam``, the joints' geometric stiffness: (Aᵀλ)_i = s̃_i R_iᵀλ on body i's ω rows,
        so ∂/∂θ_i = s̃_i (R_iᵀλ)~ (the negative on body j). Without ``lam`` that term is
        left to Newton's iterations. ``sparse=True``: a scipy.sparse CSR matrix (one 6x6
        block per body and per spring pair) instead of a dense array."""
        nb = self.nb
        W = V.reshape(nb, 6)
        w = W[:, :3]
        Jw = np.einsum("nij,nj->ni", self.J, w)
        B = np.zeros((nb, 6, 6))
        B[:, :3, :3] = c_acc * self.J + c_vel * (hat(w) @ self.J - hat(Jw))
        B[:, 3:, 3:] = (c_acc * self.m)[:, None, None] * np.eye(3)
        need_R = self.pivot.any() or (lam is not None and self.n_constraints)
        R = self._poses(q)[1] if need_R and c_pos else None
        if R is not None and self.pivot.any():
            pv = self.pivot
            Rtg = np.einsum("nji,j->ni", R[pv], self.g)
            B[pv, :3, :3] -= c_pos * self.m[pv, None, None] * (hat(self.c[pv]) @ hat(Rtg))
        if R is not None and lam is not None and self.n_constraints:
            L = np.asarray(lam, float).reshape(-1, 3)
            rot = B[:, :3, :3]
            Gi = hat(self._si) @ hat(np.einsum("nji,nj->ni", R[self._ji], L))
            np.add.at(rot, self._ji, c_pos * Gi)
            body = ~self._ground
            if body.any():
                jj = self._jj[body]
                Gj = hat(self._sj[body]) @ hat(np.einsum("nji,nj->ni", R[jj], L[body]))
                np.add.at(rot, jj, -c_pos * Gj)
        ii = 6 * np.arange(nb)[:, None] + np.arange(6)
        rows = np.broadcast_to(ii[:, :, None], B.shape).ravel()
        cols = np.broadcast_to(ii[:, None, :], B.shape).ravel()
        if sparse:
            from scipy import sparse as _sp
            out = _sp.csr_matrix((B.ravel(), (rows, cols)), shape=(6 * nb, 6 * nb))
            return out + self._spring_matrix(q, c_vel, c_pos, sparse=True, V=V) if self.springs else out
        out = np.zeros((6 * nb, 6 * nb))
        out[rows, cols] = B.ravel()
        if self.springs:
            out += self._spring_matrix(q, c_vel, c_pos, V=V)
        return out

    def _spring_matrix(self, q, c_vel, c_pos, sparse=False, V=None):
        """Springs' damping c_vel·d DᵀD and stiffness c_pos·(k DᵀD - s̃ (RᵀF)~) in the
        local increments (δθ body, δr inertial) of SO(3)xR³: with D_i = [-R_i s̃_i, I]
        the point's variation δp_i = D_i δz_i, and δ(Rᵀ F) = (RᵀF)~ δθ. With velocities V
        the damping force enters F and its point velocity v_i = ṙ_i + R_i (ω_i × s_i) moves
        with the rotation, δv_i = -R_i (ω_i × s_i)~ δθ_i (V = None: at rest).
        ``sparse=True``: a scipy.sparse CSR matrix."""
        r, R = self._poses(q)
        Vb = np.zeros((self.nb, 6)) if V is None else np.asarray(V, float).reshape(self.nb, 6)
        rows, cols, vals = [], [], []
        six = np.arange(6)

        def put(a, b, block):
            n = len(block)
            rows.append(np.repeat(6 * a + six[:n], n)), cols.append(np.tile(6 * b + six[:n], n))
            vals.append(block.ravel())
        for (i, si, j, sj, k, d) in self.springs:
            ends = [(i, np.asarray(si, float), 1.0)] + ([(j, np.asarray(sj, float), -1.0)] if j >= 0 else [])
            D = {b: np.hstack([-R[b] @ hat(s[None])[0], np.eye(3)]) for b, s, _ in ends}
            ws = {b: np.cross(Vb[b, :3], s) for b, s, _ in ends}           # ω × s, body frame
            # F on body i = -Σ g (k p + d v) over the ends (g = +1 at i, -1 at j)
            F = sum(-g * (k * (r[b] + R[b] @ s) + d * (Vb[b, 3:] + R[b] @ ws[b])) for b, s, g in ends)
            if j < 0:
                F = F + k * np.asarray(sj, float)
            for a, sa, ga in ends:
                for b, _, gb in ends:
                    put(a, b, ga * gb * (c_pos * k + c_vel * d) * D[a].T @ D[b])
                    if d and c_pos:                     # -∂Q_a/∂θ_b of the damping force
                        blk = np.zeros((6, 6))
                        blk[:, :3] = -c_pos * ga * gb * d * D[a].T @ R[b] @ hat(ws[b][None])[0]
                        put(a, b, blk)
                put(a, a, -c_pos * ga * hat(sa[None])[0] @ hat((R[a].T @ F)[None])[0])
        n = 6 * self.nb
        cat = (lambda x, dt: np.concatenate(x) if x else np.zeros(0, dt))
        rows, cols, vals = cat(rows, int), cat(cols, int), cat(vals, float)
        if sparse:
            from scipy import sparse as _sp
            return _sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
        out = np.zeros((n, n))
        np.add.at(out, (rows, cols), vals)
        return out

    def f(self, q, V, t):
        """V̇ (index 1): M⁻¹(Q - Aᵀλ) with A M⁻¹Aᵀ λ = A M⁻¹Q + γ; a new array."""
        return self._f(q, V, t)

    def _f_kernel(self, q, V, t):
        out = np.empty(6 * self.nb)
        if (self.load is None and type(q) is _ND and type(V) is _ND and q.dtype is _F64 and V.dtype is _F64
                and q.flags.c_contiguous and V.flags.c_contiguous):      # (the integrators' arrays)
            (_KS or _kernels()).f(self._kI, self._kF, q, V, self._knoload, out)
        else:
            (_KS or _kernels()).f(self._kI, self._kF, *self._kernel_inputs(q, V, t), out)
        return out

    def _kernel_inputs(self, q, V, t):
        """(q, V, load) for the kernels: float64 arrays and the user load as (nb, 6) rows
        (torque body, force inertial), or no rows without a load."""
        q = np.ascontiguousarray(q, dtype=np.float64)
        V = np.ascontiguousarray(V, dtype=np.float64)
        if self.load is None:
            return q, V, self._knoload
        F, T = self.load(t, q, V)
        load = self._kload
        load[:, :3] = T
        load[:, 3:] = F
        return q, V, load

    def _f_numpy(self, q, V, t):
        Q = self._forces_numpy(q, V, t)
        if not self.n_constraints:
            return self.solve_mass(q, Q)
        A = self.constraint_jacobian(q)
        gam = self.constraint_gamma(q, V)
        MiQ = self.solve_mass(q, Q)
        MiAt = self.solve_mass(q, A.T)
        lam = np.linalg.solve(A @ MiAt, A @ MiQ + gam)
        return MiQ - MiAt @ lam

    def constraints(self, q):
        return self._constraints(q)

    def _constraints_kernel(self, q):
        out = np.empty(self.n_constraints)
        q = np.ascontiguousarray(q, dtype=np.float64)
        (_KS or _kernels()).constraints(self._kI, self._kF, q, out)
        return out

    def _constraints_numpy(self, q):
        if not self.n_constraints:
            return np.zeros(0)
        r, R = self._poses(q)
        pi = r[self._ji] + np.einsum("nij,nj->ni", R[self._ji], self._si)
        pj = np.where(self._ground[:, None], self._sj,
                      r[self._jj] + np.einsum("nij,nj->ni", R[self._jj], self._sj))
        return (pi - pj).ravel()

    def constraint_jacobian(self, q):
        """ġ = A V: for body i, [-R_i s̃_i, I] (and the negative for body j)."""
        return self._constraint_jacobian(q)

    def _constraint_jacobian_kernel(self, q):
        A = np.zeros((self.n_constraints, 6 * self.nb))
        q = np.ascontiguousarray(q, dtype=np.float64)
        (_KS or _kernels()).constraint_jacobian(self._kI, self._kF, q, A)
        return A

    def _constraint_jacobian_numpy(self, q):
        nj = len(self.joints)
        A = np.zeros((3 * nj, 6 * self.nb))
        if not nj:
            return A
        _, R = self._poses(q)
        rows = np.arange(3 * nj).reshape(nj, 3)
        ci = 6 * self._ji[:, None] + np.arange(3)                       # ω columns of body i
        A[rows[:, :, None], ci[:, None, :]] = -R[self._ji] @ hat(self._si)
        A[rows, ci + 3] = 1.0
        body = ~self._ground
        if body.any():
            jj = self._jj[body]
            cj = 6 * jj[:, None] + np.arange(3)
            A[rows[body][:, :, None], cj[:, None, :]] = R[jj] @ hat(self._sj[body])
            A[rows[body], cj + 3] = -1.0
        return A

    def constraint_gamma(self, q, V):
        """γ = (d/dt A) V = R_i (ω_i × (ω_i × s_i)) - R_j (ω_j × (ω_j × s_j))."""
        return self._constraint_gamma(q, V)

    def _constraint_gamma_kernel(self, q, V):
        out = np.empty(self.n_constraints)
        q = np.ascontiguousarray(q, dtype=np.float64)
        V = np.ascontiguousarray(V, dtype=np.float64)
        (_KS or _kernels()).constraint_gamma(self._kI, self._kF, q, V, out)
        return out

    def _constraint_gamma_numpy(self, q, V):
        if not self.n_constraints:
            return np.zeros(0)
        _, R = self._poses(q)
        w = V.reshape(self.nb, 6)[:, :3]
        wi = w[self._ji]
        gi = np.einsum("nij,nj->ni", R[self._ji], cross(wi, cross(wi, self._si)))
        wj = w[np.maximum(self._jj, 0)]
        gj = np.einsum("nij,nj->ni", R[np.maximum(self._jj, 0)], cross(wj, cross(wj, self._sj)))
        gj[self._ground] = 0.0
        return (gi - gj).ravel()

    # --- diagnostics ---------------------------------------------------------------
    def energy(self, q, V):
        r, R = self._poses(q)
        W = V.reshape(self.nb, 6)
        w, v = W[:, :3], W[:, 3:]
        T = 0.5 * np.einsum("ni,nij,nj->", w, self.J, w) + 0.5 * np.sum(self.m * np.where(self.pivot, 0, 1) * (v * v).sum(1))
        com = r + np.einsum("nij,nj->ni", R, self.c)
        U = -np.sum(self.m * (com @ self.g))
        for (i, si, j, sj, k, d) in self.springs:
            pi = r[i] + R[i] @ si
            pj = r[j] + R[j] @ sj if j >= 0 else np.asarray(sj, float)
            U += 0.5 * k * np.sum((pj - pi) ** 2)
        return T + U

    def spatial_angular_momentum(self, q, V):
        """Σ (R J ω + m r × ṙ) about the origin (for free bodies and pivoted bodies)."""
        r, R = self._poses(q)
        W = V.reshape(self.nb, 6)
        L = np.einsum("nij,njk,nk->ni", R, self.J, W[:, :3])
        L += self.m[:, None] * np.cross(r, W[:, 3:]) * (~self.pivot)[:, None]
        return L.sum(axis=0)
