"""Dense integrations of R6 for Figures 2 and the homoclinic figure: orbits on a time grid with
the project's Taylor integrator, meridian points and the closed curves {H = h} n {F = c}."""
import math

import numpy as np

from explorer.app.paper._common import DENSE_TOL
from explorer.app.paper.chaplygin import check_chaplygin


def advance(params, Y, tau, *, tol=DENSE_TOL):
    """States Y (N, 5) advanced by the time tau > 0 with the project's Taylor integrator
    (:func:`explorer.analysis.sections.propagate`).  One thread: the call is short."""
    from explorer.analysis import sections

    Y = np.ascontiguousarray(np.atleast_2d(Y), dtype=float)
    return sections.propagate(params, states=Y, t=float(tau), tol=tol, threads=1)


def dense_orbits(params, Y0, t_end, dt, *, tol=DENSE_TOL, stop=None):
    """Samples of the orbits from Y0 (N, 5) every dt up to t_end: returns (t (n,), Y (n, N, 5)).
    ``stop(k, Y_k) -> bool`` may end the run early (checked after every sample)."""
    Y = np.ascontiguousarray(np.atleast_2d(Y0), dtype=float)
    n = int(math.ceil(t_end / dt - 1e-9))
    out = [Y.copy()]
    for k in range(1, n + 1):
        Y = advance(params, Y, dt, tol=tol)
        out.append(Y.copy())
        if stop is not None and stop(k, Y):
            break
    Ys = np.array(out)
    return dt * np.arange(len(Ys)), Ys


def _refine_p2_root(params, y_prev, dt, tol=DENSE_TOL):
    """The state where p2 changes sign within [0, dt] from y_prev (Illinois regula falsi on
    the integrated p2); returns (tau, state)."""
    a, fa = 0.0, y_prev[1]
    yb = advance(params, y_prev, dt, tol=tol)[0]
    b, fb = dt, yb[1]
    best = (b, yb)
    side = 0
    for _ in range(60):
        if fb == 0.0 or abs(b - a) < 1e-15:
            break
        x = b - fb * (b - a) / (fb - fa)
        if not (min(a, b) < x < max(a, b)):
            x = 0.5 * (a + b)
        yx = advance(params, y_prev, x, tol=tol)[0] if x > 0 else y_prev.copy()
        fx = yx[1]
        best = (x, yx)
        if abs(fx) < 1e-13:
            break
        if fx * fb < 0:
            a, fa = b, fb
            side = 0
        else:
            fa = fa / 2 if side == 1 else fa
            side = 1
        b, fb = x, fx
    return best


def _state5(y3):
    y3 = np.atleast_2d(y3)
    Y = np.zeros((len(y3), 5))
    Y[:, :3] = y3
    Y[:, 4] = 1.0   # phi = 0: gamma does not enter R6 (mu = 0)
    return Y


def meridian_points(params, h, c, n_grid=4001):
    """Points of {H = h} n {F = c} on the meridian p2 = 0 of the energy ellipsoid:
    p1 = sqrt(2 a1 h) sin(theta), M = sqrt(2 b h) cos(theta); every closed curve of the
    level set crosses it twice (R6 is reversible under (p2, t) -> (-p2, -t))."""
    prm = check_chaplygin(params)
    R1, R3 = math.sqrt(2 * prm.a1 * h), math.sqrt(2 * prm.b * h)

    def f(th):
        return R3 * np.cos(th) + (R1 * np.sin(th)) ** 2 / (2 * prm.lam) - c

    th = np.linspace(-math.pi, math.pi, n_grid)
    v = f(th)
    idx = np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)
    roots = []
    for i in idx:
        a, b = th[i], th[i + 1]
        fa = f(a)
        for _ in range(80):
            m = 0.5 * (a + b)
            fm = f(m)
            if fm == 0.0:
                a = b = m
                break
            if np.sign(fm) == np.sign(fa):
                a, fa = m, fm
            else:
                b = m
        roots.append(0.5 * (a + b))
    th = np.array(roots)
    return np.column_stack([R1 * np.sin(th), np.zeros_like(th), R3 * np.cos(th)])


def closed_curves(params, h, c_levels, *, dt=0.02, t_max=400.0, tol=DENSE_TOL):
    """The closed curve of {H = h} n {F = c} for each c of ``c_levels``, integrated (Taylor) from
    its point on p2 = 0 over one period, duplicates dropped.  Returns dicts: c, start, y (samples,
    the last the located return), t, period, half (the other meridian point), closure."""
    prm = check_chaplygin(params)
    starts, levels = [], []
    for c in c_levels:
        pts = meridian_points(prm, h, c)
        starts += list(pts)
        levels += [float(c)] * len(pts)
    if not starts:
        return []
    Y0 = _state5(np.array(starts))
    N = len(Y0)
    changes = [[] for _ in range(N)]      # sample indices k where p2 changed sign in (k-1, k]
    last_sign = np.zeros(N)

    def stop(k, Y):
        s = np.sign(Y[:, 1])
        for i in range(N):
            if s[i] == 0.0:
                continue
            if last_sign[i] != 0.0 and s[i] != last_sign[i] and len(changes[i]) < 2:
                changes[i].append(k)
            last_sign[i] = s[i]
        return all(len(ch) >= 2 for ch in changes)

    t, Ys = dense_orbits(prm, Y0, t_max, dt, tol=tol, stop=stop)
    curves = []
    covered = []
    for i in range(N):
        if len(changes[i]) < 2:
            raise RuntimeError(f"curve c = {levels[i]:g} through {starts[i]} did not close within t = {t_max:g}")
        k1, k2 = changes[i]
        tau1, y_half = _refine_p2_root(prm, Ys[k1 - 1, i], dt, tol)
        tau2, y_end = _refine_p2_root(prm, Ys[k2 - 1, i], dt, tol)
        start = np.asarray(starts[i])
        if any(levels[j] == levels[i] and np.linalg.norm(start - covered_pt) < 1e-6
               for j, covered_pt in covered):
            continue
        covered.append((i, y_half[:3].copy()))
        y = np.vstack([Ys[:k2, i, :3], y_end[None, :3]])
        tt = np.concatenate([t[:k2], [t[k2 - 1] + tau2]])
        curves.append({"c": levels[i], "start": start, "y": y, "t": tt, "period": float(tt[-1]),
                       "half": y_half[:3].copy(), "closure": float(np.linalg.norm(y_end[:3] - start))})
    return curves
