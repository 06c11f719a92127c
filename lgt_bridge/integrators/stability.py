"""The stability limit of an explicit method on a model: the largest step its stability
function allows for the model's stiffest modes, from the model's own Jacobian.

Hairer's stiffness test (``AdaptiveRK._detect_stiffness``) measures the stiffest rate the
steps see and compares h·ρ with the method's bound on the negative real axis (DOPRI5 3.3,
DOP853 6.4). An undamped or lightly damped stiff oscillation (an ANCF cable's axial
vibration, an undamped stiff spring) has eigenvalues near the imaginary axis, where the
bound is far lower (DOPRI5: |hλ| ≤ 1.0 on the axis itself, and only weakly unstable up to
about 2.5): the steps sit there, at h|λ| ≈ 1, and the real-axis test never fires. So the
budget check (:func:`lgt_bridge.diagnosis.unaffordable`) asks the model itself:

- :func:`dominant_eigenvalues` — the largest eigenvalues of the local ODE's Jacobian
  ∂(Ẋ, Ẇ)/∂(X, W) at the current state, by Arnoldi on central differences of f (2 f per
  Krylov vector, about 60 f: a few of the run's steps);
- :func:`ray_bound` — |hλ| at the edge of the method's stability region along λ's ray
  (the stability polynomial R(z) = 1 + z bᵀ(I - zA)⁻¹1 of the explicit tableau);
- :func:`jacobian_limit` — the step the most restrictive of those eigenvalues allows.
"""
import math

import numpy as np

#: Krylov vectors of the Arnoldi estimate (fewer when the state is smaller)
KRYLOV = 30

_POLY = {}


def stability_polynomial(tab):
    """Coefficients c_k of R(z) = Σ c_k z^k of an explicit tableau (c_k = bᵀA^(k-1)1)."""
    got = _POLY.get(id(tab))
    if got is None or got[0] is not tab:
        n = tab.stages
        A = np.zeros((n, n))
        for i, row in enumerate(tab.A):
            A[i, :len(row)] = row
        b, v, c = np.asarray(tab.b, float), np.ones(n), [1.0]
        for _ in range(n):
            c.append(float(b @ v))
            v = A @ v
        got = _POLY[id(tab)] = (tab, np.array(c))
    return got[1]


def ray_bound(tab, lam, r_max=20.0):
    """|hλ| at the edge of the explicit tableau's stability region along the ray of λ: the
    first r with |R(r e^{iθ})| > 1. θ is taken in [90°, 180°] (conjugates give the same;
    a positive real part, from the differences' noise or a mode that grows whatever the
    method, counts as on the imaginary axis)."""
    c = stability_polynomial(tab)[::-1]
    theta = math.atan2(abs(lam.imag), lam.real) if lam != 0 else math.pi
    theta = max(theta, 0.5 * math.pi)
    d = complex(math.cos(theta), math.sin(theta))
    r = np.linspace(0.0, r_max, 4001)[1:]
    out = np.abs(np.polyval(c, r * d)) > 1.0
    if not out.any():
        return r_max
    k = int(np.argmax(out))
    lo, hi = (r[k - 1] if k else 0.0), r[k]
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if abs(np.polyval(c, mid * d)) > 1.0:
            hi = mid
        else:
            lo = mid
    return lo


def dominant_eigenvalues(prob, W, t, m=KRYLOV, seed=0):
    """The largest eigenvalues (Ritz values of an m-step Arnoldi, by modulus, largest first)
    of the Jacobian of the local ODE F(X, W) = (Ẋ, Ẇ) at X = 0 (the problem's base) and the
    velocities W, from central differences of F along the Krylov vectors. None when f is not
    finite or raises next to the state. The differences are taken of D⁻¹ F(y0 + D y) with
    D = max(1, |y0|) per entry (a similar matrix: the same eigenvalues), so that entries of
    different scales are each moved by 1e-6 of their size (a hydraulic model's pressures of
    1e7 Pa beside positions of 0.1 m: one step for all moved the positions by 10 m, and the
    eigenvalues came out at ±1e8 1/s where the steps showed 1.2e4)."""
    nX = prob.nX
    W = np.asarray(W, float)
    y0 = np.concatenate([np.zeros(nX), W])
    n = len(y0)
    m = min(m, n)
    D = np.maximum(1.0, np.abs(y0))
    eps = 1e-6

    def Jv(v):
        yp, ym = y0 + eps * D * v, y0 - eps * D * v
        return (prob.rates(yp[:nX].copy(), yp[nX:].copy(), t)
                - prob.rates(ym[:nX].copy(), ym[nX:].copy(), t)) / (2.0 * eps * D)
    Q = np.zeros((n, m + 1))
    H = np.zeros((m + 1, m))
    v = np.random.default_rng(seed).standard_normal(n)
    Q[:, 0] = v / np.linalg.norm(v)
    k = m
    try:
        with np.errstate(all="ignore"):
            for j in range(m):
                w = Jv(Q[:, j])
                if not np.isfinite(w).all():
                    return None
                for _ in range(2):                       # Gram-Schmidt, twice
                    c = Q[:, :j + 1].T @ w
                    H[:j + 1, j] += c
                    w = w - Q[:, :j + 1] @ c
                H[j + 1, j] = nw = float(np.linalg.norm(w))
                if nw <= 1e-12 * max(1.0, float(np.abs(H[:j + 1, :j + 1]).max())):
                    k = j + 1                            # an invariant subspace: exact
                    break
                Q[:, j + 1] = w / nw
    except Exception:                  # (a diagnosis: the run's own verdict stands without it)
        return None
    ev = np.linalg.eigvals(H[:k, :k])
    return ev[np.argsort(-np.abs(ev))]


def jacobian_limit(stepper, t, top=4):
    """(h_stab, λ): the step the explicit stepper's stability region allows for the model's
    dominant eigenvalues at its current state (the most restrictive of the ``top`` largest),
    and that eigenvalue; None when not measurable. The problem's work state is kept (the
    differences evaluate f at other states)."""
    prob = stepper.prob
    work = getattr(prob, "work", None)
    saved = work.copy() if work is not None else None
    try:
        ev = dominant_eigenvalues(prob, stepper.W.copy(), t)
    finally:
        if saved is not None:
            work[:] = saved
    if ev is None or not len(ev) or not abs(ev[0]) > 0.0:
        return None
    best = None
    for lam in ev[:top]:
        if abs(lam) < 0.2 * abs(ev[0]):
            break
        h = ray_bound(stepper.tab, complex(lam)) / abs(lam)
        if best is None or h < best[0]:
            best = (h, complex(lam))
    return best
