"""The flux through a cantorus of the standard map (docs/greene.md, The cantorus flux): MacKay,
Meiss & Percival's action difference Delta W = W(minimax) - W(minimizing) of the symmetric orbits
of the convergents P/Q of nu, W = sum F(theta_t, theta_{t+1}), F = (theta' - theta)^2/2 - k cos
theta, cut where the orbits are lost and extrapolated by Aitken's Delta^2.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer.analysis import greene as gm
from explorer.analysis.greene_core import MAX_QMAX, MIN_Q, aitken
from explorer.analysis.maps import StandardMap, has_angle
from explorer.model import ParameterError, validation

__all__ = ["CantorusFlux", "action", "cantorus_flux", "minimizing_orbit"]

#: the closure error |T^Q(x) - x - (2 pi P, 0)| of an orbit is accepted below this fraction of its
#: action difference (beyond, the orbit's round-off is of the size of what is measured)
CLOSURE_FRACTION = 1e-3
#: the largest period followed by default
DEFAULT_QMAX = 610


def action(system, points, P: int) -> float:
    """W = sum_{t=0}^{Q-1} F(theta_t, theta_{t+1}) of the orbit ``points`` ((Q, 2), theta lifted) of
    type P/Q, with theta_Q = theta_0 + 2 pi P and F the map's ``generating_function``."""
    th = np.append(np.asarray(points, float)[:, 0], points[0][0] + 2.0 * math.pi * P)
    return float(np.sum(system.generating_function(th[:-1], th[1:])))


#: the even-period scan of the line 2 theta - p = 0: this many samples within SCAN_WIDTH of the guess
SCAN_SAMPLES = 2000
SCAN_WIDTH = 1.0
#: halvings of a scan's bracket (2 / 2000 to below the spacing of doubles near p ~ 4)
BISECTIONS = 60


def _i1_function(system, P, Q, s) -> np.ndarray:
    """2 theta_n - p_n - 2 pi P after n = Q/2 steps from the points (s/2, s) of Fix I1 (s an array): zero
    on a symmetric orbit."""
    end = system.images(np.column_stack([0.5 * s, s]), Q // 2)[:, -1]
    return 2.0 * end[:, 0] - end[:, 1] - 2.0 * math.pi * P


def _bisect(fn, a, b, fa) -> float:
    for _ in range(BISECTIONS):
        m = 0.5 * (a + b)
        if m in (a, b):
            break
        fm = fn(m)
        if (fm < 0.0) == (fa < 0.0):
            a, fa = m, fm
        else:
            b = m
    return 0.5 * (a + b)


def minimizing_orbit(system: StandardMap, p: int, q: int, *, guess=None) -> np.ndarray:
    """The points (Q, 2) of the minimizing symmetric orbit of type ``p``/``q`` (docs/greene.md):
    from theta = 0 for odd q (:func:`explorer.analysis.greene.symmetric_orbit`, Newton from
    ``guess``, default 2 pi p/q); for even q the orbit of least action among the roots of the
    half-orbit equation on the line 2 theta - p = 0 within ``SCAN_WIDTH`` of ``guess`` (a scan of
    ``SCAN_SAMPLES`` points, each sign change refined by bisection: far above k_c the shooting function
    oscillates and Newton from a continued guess alone can land on the minimax orbit or fail; the
    minimizing orbit is the one of least action among all of its type, Aubry-Mather theory)."""
    P = validation.integer("p", p, 0)
    Q = validation.integer("q", q, MIN_Q)
    k = system.parameter_value
    g = 2.0 * math.pi * P / Q if guess is None else float(guess)
    if Q % 2:
        return gm.symmetric_orbit(system, P, Q, line=0.0, guess=g).points
    s = g + SCAN_WIDTH * np.linspace(-1.0, 1.0, SCAN_SAMPLES + 1)
    f = _i1_function(system, P, Q, s)
    best = None
    for i in np.flatnonzero(np.isfinite(f[:-1]) & np.isfinite(f[1:]) & (np.sign(f[:-1]) != np.sign(f[1:]))):
        p0 = _bisect(lambda x: _i1_function(system, P, Q, np.array([x]))[0], s[i], s[i + 1], f[i])
        pts = system.iterate((0.5 * p0, p0), Q)[:Q]
        w = action(system, pts, P)
        if best is None or w < best[0]:
            best = (w, pts)
    if best is None:
        raise ParameterError(f"no symmetric orbit of type {P}/{Q} on the line 2 theta - p = 0 near p = {g:.10g} at "
                             f"k = {k:.12g}")
    return best[1]


@dataclass(frozen=True)
class CantorusFlux:
    """The action differences of the convergents and their limit (:func:`cantorus_flux`)."""

    k: float
    nu: float
    q: list
    delta_w: list
    flux: float
    stopped: str


def _first(solve, guess):
    try:
        return solve(guess)
    except ParameterError:
        if guess is None:
            raise
        return solve(None)


def _closure(system, pts, P) -> float:
    end = system.iterate(pts[0], len(pts))[-1]
    return float(max(abs(end[0] - pts[0, 0] - 2.0 * math.pi * P), abs(end[1] - pts[0, 1])))


def cantorus_flux(system: StandardMap, nu="golden", *, qmax=DEFAULT_QMAX, qmin=5) -> CantorusFlux:
    """The flux Delta W through the cantorus of rotation number ``nu`` of the standard map above its
    breakup (MacKay, Meiss & Percival 1984; docs/greene.md), in the map's (theta, p) units (the
    papers' (x, y) = (theta/2 pi, p/2 pi) units give Delta W / (2 pi)^2)."""
    if not has_angle(system):
        raise ParameterError(f"cantorus_flux needs a twist map with an angle coordinate (periods: its lift counts "
                             f"the orbits' types) and a generating_function, as StandardMap's; {system!r} has no "
                             "angle coordinate")
    x = gm.rotation_value(nu)
    k = system.parameter_value
    qs: list[int] = []
    dws: list[float] = []
    g_max = g_min_odd = g_min_even = None
    stopped = ""
    for P, Q in gm.convergents(x, validation.integer("qmax", qmax, 3, MAX_QMAX)):
        try:
            mx = _first(lambda g: gm.symmetric_orbit(system, P, Q, line=math.pi, guess=g), g_max)
            mn = _first(lambda g: minimizing_orbit(system, P, Q, guess=g), g_min_odd if Q % 2 else g_min_even)
        except ParameterError as exc:
            stopped = f"q = {Q}: {exc}"
            break
        g_max = mx.points[0, 1]
        if Q % 2:
            g_min_odd = mn[0, 1]
        else:
            g_min_even = mn[0, 1]
        if Q < qmin:
            continue
        dw = action(system, mx.points, P) - action(system, mn, P)
        err = max(_closure(system, mx.points, P), _closure(system, mn, P))
        if not err <= CLOSURE_FRACTION * abs(dw):
            stopped = f"q = {Q}: the orbits close only to {err:.2g} (Delta W_n = {dw:.3g}): double precision's end"
            break
        if dws and not 0.0 < dw < dws[-1]:
            stopped = f"q = {Q}: Delta W_n = {dw:.3g} after {dws[-1]:.3g} stopped decreasing: the orbits are lost"
            break
        qs.append(Q)
        dws.append(dw)
    if not dws:
        raise ParameterError(f"no convergent of nu = {x:.10g} with q >= {qmin} gave an action difference at "
                             f"k = {k:.12g} ({stopped})")
    flux = aitken(*dws[-3:]) if len(dws) >= 3 else dws[-1]
    return CantorusFlux(float(k), x, qs, dws, float(flux), stopped)
