"""The symmetry lines of a section map with a linear reversor G (docs/greene.md, "Two symmetry lines"):
the half of the section a line lies on (the map's or its :meth:`opposite`'s), G's axes, and the
symmetric orbits of period Q shot over Q half turns from Fix G (the map's ``half_turns``): an orbit
from Fix G that is back on a line Fix G after Q half turns is symmetric with period Q (or a divisor),
G P G = P^-1 (Lamb & Roberts 1998, Physica D 112, 1)."""
from __future__ import annotations

import functools
import math

import numpy as np

from explorer.model import ParameterError

__all__ = ["axes", "half_turn_p2", "line_map", "line_point", "line_root", "line_roots", "same_line",
           "symmetric_seeds"]

SECANT_TOL, SECANT_MAX_ITER = 1e-13, 40


def line_map(smap, line):
    """``smap`` on the half of the section labelled ``line`` (its own, None, or :meth:`opposite`'s)."""
    if line is None or same_line(line, smap.section_label):
        return smap
    other = smap.opposite()
    if not same_line(line, other.section_label):
        raise ParameterError(f"line must be {smap.section_label:g} or {other.section_label:g} (the map's and the "
                             f"opposite half's symmetry lines), got {line!r}")
    return other


def same_line(a, b) -> bool:
    return abs(math.remainder(float(a) - float(b), 2.0 * math.pi)) < 1e-12


def axes(smap):
    """(G, v, u) of the map's linear reversor: its matrix G, v spanning Fix G (G v = v) and u with
    u . x = 0 on Fix G (u G = -u); the largest component of each positive."""
    R = smap.require_reversor("greene")
    if not callable(R):
        raise ParameterError("greene needs a reversor of the map")
    G = np.asarray(R(np.eye(2)), float).T
    if not np.allclose(G @ G, np.eye(2), atol=1e-12) or abs(np.trace(G)) > 1e-12:
        raise ParameterError(f"greene needs a reversor of the map that is a reflection (linear, with a fixed line), "
                             f"got the matrix {G.tolist()}")
    w, V = np.linalg.eig(G)
    wl, U = np.linalg.eig(G.T)
    v, u = np.real(V[:, np.argmax(np.real(w))]), np.real(U[:, np.argmin(np.real(wl))])
    v, u = v * np.sign(v[np.argmax(np.abs(v))]), u / np.linalg.norm(u) * np.sign(u[np.argmax(np.abs(u))])
    return G, v / np.linalg.norm(v), u


def line_point(smap, x, line) -> np.ndarray:
    """Where the flow from ``smap``'s point x next crosses the half labelled ``line`` (x on its own)."""
    if same_line(line, smap.section_label):
        return np.asarray(x, float).copy()
    y = smap.half_turns(np.asarray(x, float)[None, :], 1)[0]
    if not np.all(np.isfinite(y)):
        raise ParameterError(f"the flow from {tuple(np.ravel(x))} did not reach the section's half {line:g}")
    return y


def half_turn_p2(smap, t, Q: int, line=None) -> np.ndarray:
    """u . x after Q half turns from the points t v of the symmetry line of the half ``line`` (:func:`axes`;
    p2 on Chaplygin's section); NaN where not reached."""
    m, v, u = _shooting(smap, line, Q % 2)
    ts = np.atleast_1d(np.asarray(t, float))
    return m.half_turns(ts[:, None] * v[None, :], Q) @ u


@functools.lru_cache(maxsize=64)
def _shooting(smap, line, odd):
    """(the map of the half ``line``, v of its line, u of the line where Q half turns end)."""
    m = line_map(smap, line)
    return m, axes(m)[1], axes(m.opposite() if odd else m)[2]


def line_roots(smap, Q: int, a: float, b: float, n: int, line=None) -> list:
    """The starts t in [a, b] on the symmetry line of the half ``line`` of the symmetric orbits of period Q
    (or a divisor): the sign changes of :func:`half_turn_p2` over n + 1 samples, refined by the secant."""
    xs = np.linspace(a, b, n + 1)
    fs = half_turn_p2(smap, xs, Q, line)
    roots = []
    for i in np.flatnonzero(np.isfinite(fs[:-1]) & np.isfinite(fs[1:]) & (np.sign(fs[:-1]) != np.sign(fs[1:]))):
        try:
            roots.append(line_root(smap, Q, xs[i], xs[i + 1], fs[i], fs[i + 1], line))
        except ParameterError:
            continue
    return roots


def line_root(smap, Q, x0, x1, f0=None, f1=None, line=None) -> float:
    """A root of :func:`half_turn_p2` by the secant method from x0, x1."""
    f0 = half_turn_p2(smap, x0, Q, line)[0] if f0 is None else f0
    f1 = half_turn_p2(smap, x1, Q, line)[0] if f1 is None else f1
    for _ in range(SECANT_MAX_ITER):
        if not (math.isfinite(f0) and math.isfinite(f1)) or f1 == f0:
            break
        x2 = x1 - f1 * (x1 - x0) / (f1 - f0)
        if abs(x2 - x1) <= SECANT_TOL * max(1.0, abs(x1)) or f1 == 0.0:
            return float(x2)
        f2 = half_turn_p2(smap, x2, Q, line)[0]
        x0, f0, x1, f1 = x1, f1, x2, f2
    raise ParameterError(f"no symmetric orbit of period {Q} near {x1:.10g} on the symmetry line (the half-turn "
                         f"equation did not converge)")


def symmetric_seeds(smap, Q: int, n: int) -> np.ndarray:
    """Seeds (m, 2) on ``smap``'s half of its symmetric orbits of period Q (or a divisor): the roots of
    :func:`half_turn_p2` among ``n`` samples of the symmetry line of each half (the map's and its
    opposite's: an orbit of even period may meet one only), carried to the map's half
    (:func:`line_point`); none without a linear reversor."""
    seeds = []
    for m in (smap, smap.opposite()):
        try:
            v = axes(m)[1] if m.reflection is not None else None
        except ParameterError:      # its first reversor is not the linear one
            v = None
        if v is None:
            continue
        ts = m.symmetry_line_points(n) @ v
        if ts.size < 2:
            continue
        for t in line_roots(m, Q, float(ts.min()), float(ts.max()), n - 1):
            try:
                seeds.append(line_point(m, t * v, smap.section_label))
            except ParameterError:
                continue
    return np.array(seeds, float).reshape(-1, 2)
