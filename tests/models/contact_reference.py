"""The exact motion of a mass point dropped on a floor through a penalty contact as Exudyn's
GeneralContact computes it under its implicit solver (the active-set rule of its PostNewton):
the force on the point is -(k·gap + d·ġ) upwards while the pair is active, and the pair is
active while gap < 0 and k·gap + d·ġ < 0 (a closed gap pressing); gravity g downwards.
Free flight is a parabola, contact a damped linear oscillator about gap = -m g / k, both in
closed form; each switch is the first sign change of σ = max(k·gap, k·gap + d·ġ) on a fine
grid of the phase's closed form, refined by Brent's method to rounding."""
import numpy as np
from scipy.optimize import brentq


def _flight(y0, v0, g):
    return lambda s: (y0 + v0 * s - 0.5 * g * s * s, v0 - g * s)


def _contact(y0, v0, r, m, g, k, d):
    w0 = np.sqrt(k / m)
    zeta = d / (2.0 * np.sqrt(k * m))
    wd = w0 * np.sqrt(1.0 - zeta * zeta)            # (underdamped: the models' contacts)
    yeq = r - m * g / k
    e0, a = y0 - yeq, zeta * w0
    B = (v0 + a * e0) / wd

    def at(s):
        ex, c, sn = np.exp(-a * s), np.cos(wd * s), np.sin(wd * s)
        e = ex * (e0 * c + B * sn)
        ed = ex * ((-a * e0 + wd * B) * c + (-a * B - wd * e0) * sn)
        return yeq + e, ed
    return at


def drop(y0, v0, t_end, r=0.1, m=0.1, g=9.81, k=5e3, d=20.0, grid=2e-5):
    """(y, ẏ) at t_end and the switch times, from (y0, v0) at t = 0 above the floor y = 0
    (the point's centre at height y, gap = y - r)."""
    t, active, switches = 0.0, False, []

    def sigma(y, v):
        return max(k * (y - r), k * (y - r) + d * v)

    while True:
        path = _contact(y0, v0, r, m, g, k, d) if active else _flight(y0, v0, g)
        sgn = 1.0 if active else -1.0          # the phase ends where σ reaches this side
        n = int(np.ceil((t_end - t) / grid))
        s = np.linspace(0.0, t_end - t, n + 1)
        ys, vs = path(s)
        sig = np.maximum(k * (ys - r), k * (ys - r) + d * vs)
        hit = np.flatnonzero(sgn * sig[1:] > 0.0)
        if not len(hit):
            return path(t_end - t), switches
        i = hit[0] + 1
        te = brentq(lambda x: sigma(*path(x)), s[i - 1], s[i], xtol=1e-16, rtol=4 * np.finfo(float).eps)
        # restart past the root, on the new side (as the simulations do)
        y0, v0 = path(te)
        t += te
        switches.append(t)
        active = not active


def column(heights, v0, t_end, r=0.1, m=0.1, g=9.81, k=1e4, d=10.0):
    """(y, ẏ) at t_end and the switch times of mass points in a vertical column (spheres of radius r) over the
    floor y = 0, each pair (floor-sphere 0, sphere i-sphere i+1) a contact as above with
    Exudyn's combination of its two sides' parameters (stiffness in series k/2, dampings
    added 2d); scipy's DOP853 at rtol = atol = 1e-13 with the mode frozen between switches,
    each switch located as a terminal event of its σ (crossing downwards for an inactive pair,
    upwards for an active one) and the mode toggled there."""
    from scipy.integrate import solve_ivp
    n = len(heights)
    kc, dc = k / 2.0, 2.0 * d

    def gaps(y):                  # pair 0: floor-sphere 0, pair i: sphere i-1 - sphere i
        yy = np.asarray(y)
        return np.r_[yy[:1] - r, np.diff(yy) - 2 * r]

    def rates(v):
        vv = np.asarray(v)
        return np.r_[vv[:1], np.diff(vv)]

    def sigmas(x):
        gp, gd = gaps(x[:n]), rates(x[n:])
        return np.maximum(kc * gp, kc * gp + dc * gd)

    x, t, active = np.r_[heights, v0 * np.ones(n)], 0.0, sigmas(np.r_[heights, v0 * np.ones(n)]) < 0
    switches = []

    def rhs(_, x, act):
        F = np.where(act, -(kc * gaps(x[:n]) + dc * rates(x[n:])), 0.0)   # pushes pair's upper up
        a = -g * np.ones(n) + F / m
        a[:-1] -= F[1:] / m
        return np.r_[x[n:], a]

    shift = np.zeros(n)           # σ of the pair just switched, at the restart (its event is 0 there)
    while t < t_end:
        events = []
        for p in range(n):
            def ev(_, x, *args, p=p, s=shift[p]):
                return sigmas(x)[p] - s
            ev.terminal = True
            ev.direction = 1.0 if active[p] else -1.0      # active: σ up through 0; else down
            events.append(ev)
        sol = solve_ivp(rhs, (t, t_end), x, method="DOP853", rtol=1e-13, atol=1e-13, events=events,
                        args=(active,))
        x, t = sol.y[:, -1], sol.t[-1]
        hit = [p for p in range(n) if len(sol.t_events[p])]
        if not hit:
            break
        p = min(hit, key=lambda j: sol.t_events[j][0])
        x, t = sol.y_events[p][0], sol.t_events[p][0]
        switches.append(t)
        active = active.copy()
        active[p] = not active[p]
        shift = np.zeros(n)
        shift[p] = sigmas(x)[p]
    return (x[:n], x[n:]), switches
