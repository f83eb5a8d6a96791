"""Independent plain-numpy / scipy reference for the tests.

Written straight from ``docs/model.md`` (R1, R3, R9) without importing the
project's physics code (``explorer.equations``, ``explorer.model``).

Parameters ``P = [a1, a2, b, lam, chi, zeta, mu, xi, eta]``; reduced state
``y = [p1, p2, M, g1, g2]`` with ``(g1, g2) = (sin phi, cos phi)``.

Public functions
----------------
rhs_numpy(t, y, P)                      right-hand side of R3
energy_numpy(y, P)                      reduced energy H of R3
state_on_section(P, p1, p2, h, phi0)    point of the section phi = phi0 with H = h, M >= 0 (R9)
scipy_crossings(P, y0, n_crossings, ...)  first n crossings of phi = phi0 (DOP853 + events)
scipy_one_step_map(P, y_start, ...)     next crossing from a point on the section
"""
from __future__ import annotations

import functools

import numpy as np
from scipy.integrate import solve_ivp

A1, A2, B, LAM, CHI, ZETA, MU, XI, ETA = range(9)

# |sin(phi - phi0)| below which a start point counts as lying on the section
ON_SECTION_TOL = 1e-12


def rhs_numpy(t, y, P):
    """Right-hand side of the reduced system R3 (equations of R1 for p, M, phi
    with gamma = (sin phi, cos phi)), component by component:

        dp1/dt = (M/b)(p2 - zeta) - mu g1 - lam p2/a2
        dp2/dt = -(M/b)(p1 - chi) - mu g2 + lam p1/a1
        dM/dt  = (p1 - chi) p2/a2 - (p2 - zeta) p1/a1 - mu (xi g2 - eta g1)
        dg1/dt = (M/b) g2
        dg2/dt = -(M/b) g1

    ``y`` may be (5,) or (5, n) (vectorised along the last axis).  ``P`` a tuple of floats (what
    :func:`scipy_crossings` passes) or any sequence of 9 numbers; a (5,) state is read as Python
    floats (the same doubles, in a third of numpy scalars' time: this is scipy's inner loop).
    """
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P if type(P) is tuple else (float(v) for v in P)
    p1, p2, M, g1, g2 = y.tolist() if y.ndim == 1 else y
    w = M / b
    dp1 = w * (p2 - zeta) - mu * g1 - lam * p2 / a2
    dp2 = -w * (p1 - chi) - mu * g2 + lam * p1 / a1
    dM = (p1 - chi) * p2 / a2 - (p2 - zeta) * p1 / a1 - mu * (xi * g2 - eta * g1)
    dg1 = w * g2
    dg2 = -w * g1
    return np.array([dp1, dp2, dM, dg1, dg2])


def energy_numpy(y, P):
    """Reduced energy of R3:

        H = 1/2 (p1^2/a1 + p2^2/a2 + M^2/b)
            - (mu/lam) ((p1 - chi) g2 - (p2 - zeta) g1) + mu (xi g1 + eta g2)

    ``y`` may be (5,) or (5, n).  For mu = 0 the lam-term is skipped (so
    lam = 0 is allowed then).
    """
    a1, a2, b, lam, chi, zeta, mu, xi, eta = (float(v) for v in P)
    y = np.asarray(y, dtype=np.float64)
    p1, p2, M, g1, g2 = y[0], y[1], y[2], y[3], y[4]
    H = 0.5 * (p1 * p1 / a1 + p2 * p2 / a2 + M * M / b)
    if mu != 0.0:
        if lam == 0.0:
            raise ValueError("the reduced energy needs lam != 0 when mu != 0")
        H = H - (mu / lam) * ((p1 - chi) * g2 - (p2 - zeta) * g1) + mu * (xi * g1 + eta * g2)
    return H


def _section_gamma(phi0):
    return np.sin(phi0), np.cos(phi0)


def state_on_section(P, p1, p2, h, phi0=np.pi):
    """Point of the section phi = phi0 with coordinates (p1, p2) and energy h.

    R9 generalised to any phi0: with (g1, g2) = (sin phi0, cos phi0) (taken
    literally from np.sin/np.cos, so that the event function of
    :func:`scipy_crossings` vanishes exactly there),

        M = +sqrt( 2 b ( h - 1/2 (p1^2/a1 + p2^2/a2)
                         + (mu/lam)((p1 - chi) g2 - (p2 - zeta) g1)
                         - mu (xi g1 + eta g2) ) )

    (for phi0 = pi this is R9's ``- (mu/lam)(p1 - chi) + mu eta``).
    Raises ValueError if the bracket is negative (outside the allowed region,
    the gray area of Figure 4).  Returns y = [p1, p2, M, g1, g2].
    """
    a1, a2, b, lam, chi, zeta, mu, xi, eta = (float(v) for v in P)
    g1, g2 = _section_gamma(phi0)
    y = np.array([float(p1), float(p2), 0.0, g1, g2])
    bracket = h - energy_numpy(y, P)  # energy with M = 0
    if not bracket >= 0.0:
        raise ValueError(
            f"(p1, p2) = ({p1}, {p2}) is outside the allowed region of the "
            f"section at energy h = {h} (h - U = {bracket} < 0)")
    y[2] = np.sqrt(2.0 * b * bracket)
    return y


def _sin_cos_rel(y, phi0):
    """(sin(phi - phi0), cos(phi - phi0)) from y's (g1, g2)."""
    s0, c0 = _section_gamma(phi0)
    g1, g2 = y[3], y[4]
    return g1 * c0 - g2 * s0, g2 * c0 + g1 * s0


def scipy_crossings(P, y0, n_crossings, phi0=np.pi, direction=+1,
                    rtol=1e-13, atol=1e-13, t_max=1e4, t0=0.0):
    """First ``n_crossings`` crossings of the section phi = phi0 (mod 2 pi).

    Integrates R3 (:func:`rhs_numpy`) on the 5-dim state with
    ``scipy.integrate.solve_ivp(method='DOP853')`` and the event function
    ``g = sin(phi - phi0) = g1 cos(phi0) - g2 sin(phi0)`` with
    ``event.direction = direction``; an event is a crossing only if
    ``cos(phi - phi0) = g2 cos(phi0) + g1 sin(phi0) > 0`` there (this drops
    the phi0 + pi crossings).  Since ``dg/dt = cos(phi - phi0) M/b``,
    direction +1 keeps crossings with phi increasing (M > 0), -1 with phi
    decreasing (M < 0), 0 both.

    A start point on the section (|sin(phi - phi0)| <= 1e-12 and cos > 0) is
    not a crossing: the event scipy reports at (or within round-off of) t0 is
    discarded.  The integration runs over t in [t0, t_max] in chunks of
    growing length (stopping as soon as n crossings are found); fewer rows are
    returned if t_max is reached.  Events found twice (e.g. at a chunk
    boundary) are reported once.

    Returns
    -------
    ndarray (k, 5), k <= n_crossings, rows ``[t, p1, p2, M, H(y) - H(y0)]``
    with the state at the event time from the dense output (``y_events``).
    """
    P = np.asarray(P, dtype=np.float64)
    y0 = np.asarray(y0, dtype=np.float64).copy()
    b = P[B]
    n_crossings = int(n_crossings)
    H0 = energy_numpy(y0, P)
    s0, c0 = _section_gamma(phi0)

    def event(t, y):
        return y[3] * c0 - y[4] * s0

    floats = tuple(P.tolist())

    def fun(t, y):
        return rhs_numpy(t, y, floats)

    event.direction = float(direction)
    event.terminal = False

    sin0, cos0 = _sin_cos_rel(y0, phi0)
    start_on_section = abs(sin0) <= ON_SECTION_TOL and cos0 > 0.0
    # a genuine return to the section needs phi to turn through a finite
    # angle; the spurious start event happens within |sin0| of angle
    if start_on_section:
        w0 = abs(y0[2]) / b
        t_skip = 1e-12 * (1.0 + abs(t0))
        if w0 > 0.0:
            t_skip = max(t_skip, 1e-8 / w0)
    else:
        t_skip = -np.inf

    rows = []
    t_cur, y_cur = float(t0), y0
    # first chunk: about the time of n + 1 turns at the initial angular speed
    w0 = abs(y0[2]) / b
    chunk = (n_crossings + 1) * 2.0 * np.pi / w0 if w0 > 0.0 else 10.0
    chunk = min(max(chunk, 1.0), 1e3)
    last_t = -np.inf
    while len(rows) < n_crossings and t_cur < t_max:
        t_end = min(t_cur + chunk, t_max)
        sol = solve_ivp(fun, (t_cur, t_end), y_cur, method="DOP853",
                        rtol=rtol, atol=atol, events=[event])
        if sol.status < 0:
            raise RuntimeError(f"solve_ivp failed: {sol.message}")
        for te, ye in zip(sol.t_events[0], sol.y_events[0]):
            if te - t0 <= t_skip:
                continue
            if abs(te - last_t) <= 1e-12 * (1.0 + abs(te)):
                continue  # duplicate (event exactly at a step/chunk boundary)
            _, cos_e = _sin_cos_rel(ye, phi0)
            if not cos_e > 0.0:
                continue
            rows.append([te, ye[0], ye[1], ye[2], energy_numpy(ye, P) - H0])
            last_t = te
            if len(rows) == n_crossings:
                break
        t_cur, y_cur = float(sol.t[-1]), sol.y[:, -1].copy()
        chunk *= 2.0
    return np.array(rows, dtype=np.float64).reshape(-1, 5)


def scipy_one_step_map(P, y_start, phi0=np.pi, direction=+1, rtol=1e-13,
                       atol=1e-13, t_max=1e4):
    """Next crossing of the section phi = phi0 from a point on it.

    ``y_start`` must lie on the section (|sin(phi - phi0)| <= 1e-12 and
    cos(phi - phi0) > 0), else ValueError.  Time starts at 0.

    Returns
    -------
    1-D ndarray ``[t, p1, p2, M, H(y) - H(y_start)]`` (a row of
    :func:`scipy_crossings`), or None if no crossing happens before t_max.
    """
    y_start = np.asarray(y_start, dtype=np.float64)
    s, c = _sin_cos_rel(y_start, phi0)
    if not (abs(s) <= ON_SECTION_TOL and c > 0.0):
        raise ValueError(
            f"y_start is not on the section phi = {phi0} "
            f"(sin(phi - phi0) = {s}, cos(phi - phi0) = {c})")
    out = scipy_crossings(P, y_start, 1, phi0=phi0, direction=direction,
                          rtol=rtol, atol=atol, t_max=t_max)
    return out[0] if len(out) else None


# ---------------------------------------------------------------------------
# Stability of the central fixed point of the section map (independent of the
# package's Newton, tangent dynamics and continuation)
# ---------------------------------------------------------------------------
def trace_solution_I(a1, a2, b, lam, h):
    """Trace of the section map's Jacobian at solution I (p = 0, M = c = sqrt(2 b h), mu = 0).

    Linearising R6 about the uniform rotation: dp1/dt = alpha p2, dp2/dt = -beta p1 with
    alpha = c/b - lam/a2, beta = c/b - lam/a1; over the return time T = 2 pi b / c the
    monodromy of (p1, p2) has trace 2 cosh(sqrt(-alpha beta) T) when alpha beta < 0
    (hyperbolic), 2 cos(sqrt(alpha beta) T) otherwise.
    """
    c = np.sqrt(2.0 * b * h)
    alpha, beta = c / b - lam / a2, c / b - lam / a1
    T = 2.0 * np.pi * b / c
    ab = alpha * beta
    return 2.0 * np.cosh(np.sqrt(-ab) * T) if ab < 0 else 2.0 * np.cos(np.sqrt(ab) * T)


def section_map_p(P, p1, p2, h):
    """(p1, p2) of the next crossing of phi = pi from the section point (p1, p2) at energy h."""
    row = scipy_one_step_map(P, state_on_section(P, p1, p2, h), t_max=200.0)
    if row is None:
        raise ValueError("no return to the section")
    return row[1:3]


def symmetric_fixed_point(P, h, guess, xtol=1e-12):
    """Fixed point (p1, 0) of the section map on the line p2 = 0 (where the central point of
    the Figure 4 scene stays: with chi = zeta = xi = 0 the map is reversible with p2 = 0 as a
    symmetry line).  A point of the line whose image is on the line again is a symmetric
    fixed point or a point of a symmetric 2-cycle, so the secant method solves
    P(p1, 0)_2 = 0 from a guess near the fixed point (its derivative J21 stays away from 0
    where the trace is 2, unlike P_1 - p1, whose derivative J11 - 1 vanishes there); the
    caller checks P(p1, 0)_1 = p1."""
    x0, x1 = guess, guess + 1e-4
    f0 = section_map_p(P, x0, 0.0, h)[1]
    for _ in range(50):
        f1 = section_map_p(P, x1, 0.0, h)[1]
        if f1 == f0:
            break
        x0, x1, f0 = x1, x1 - f1 * (x1 - x0) / (f1 - f0), f1
        if abs(x1 - x0) < xtol:
            break
    return x1


def section_map_trace(P, h, p1_star, eps=1e-6):
    """Trace of the Jacobian of the section map at (p1_star, 0) by central differences."""
    tr = 0.0
    for k in range(2):
        d = np.zeros(2)
        d[k] = eps
        plus = section_map_p(P, p1_star + d[0], d[1], h)
        minus = section_map_p(P, p1_star - d[0], -d[1], h)
        tr += (plus[k] - minus[k]) / (2 * eps)
    return tr


FIGURE4_P = (1.0, 0.5, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@functools.cache
def figure4_stability_change_mu():
    """mu* where the central fixed point of Figure 4's scene (h = 2) turns elliptic: the trace
    crosses +2 between mu = 2.9 and 3.05 (about 1.5 s)."""
    return stability_change_mu(FIGURE4_P, 2.0, 2.9, 3.05, -1.5, xtol=1e-8)


def stability_change_mu(base, h, lo, hi, guess, xtol=1e-7):
    """The mu in (lo, hi) where the trace of the central fixed point's section map crosses +2
    (hyperbolic below, elliptic above), by bisection of trace - 2 on scipy's DOP853 alone.
    ``base``: the packed parameters (mu is replaced)."""
    from scipy.optimize import brentq

    def g(mu):
        P = np.array(base, dtype=float)
        P[MU] = mu
        x = symmetric_fixed_point(P, h, guess)
        if abs(section_map_p(P, x, 0.0, h)[0] - x) > 1e-9:
            raise ValueError(f"no symmetric fixed point near p1 = {guess} at mu = {mu}")
        return section_map_trace(P, h, x) - 2.0

    return brentq(g, lo, hi, xtol=xtol)
