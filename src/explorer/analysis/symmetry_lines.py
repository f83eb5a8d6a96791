"""The symmetry lines of a section map with a linear reversor G (docs/greene.md, "Two symmetry lines"):
the half of the section a line lies on (the map's or its :meth:`opposite`'s), G's axes, and the
symmetric orbits of period Q shot over Q half turns from Fix G (the map's ``half_turns``): an orbit
from Fix G that is back on a line Fix G after Q half turns is symmetric with period Q (or a divisor),
G P G = P^-1 (Lamb & Roberts 1998, Physica D 112, 1); its monodromy M = G B^-1 G A from the first half's
Jacobians (:func:`section_symmetric_orbit`, a section map's ``symmetric_orbit``)."""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from explorer.analysis.greene_core import Residue
from explorer.analysis.maps import orbit_turns
from explorer.model import ParameterError, validation

__all__ = ["SectionSymmetricOrbit", "axes", "half_turn_orbit", "half_turn_p2", "line_map", "line_point", "line_root",
           "line_roots", "same_line", "section_symmetric_orbit", "symmetric_seeds"]

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


def half_turn_p2(smap, t, Q: int, line=None, threads=None) -> np.ndarray:
    """u . x after Q half turns from the points t v of the symmetry line of the half ``line`` (:func:`axes`;
    p2 on Chaplygin's section); NaN where not reached; the half turns on ``threads``."""
    m, v, u = _shooting(smap, line, Q % 2)
    ts = np.atleast_1d(np.asarray(t, float))
    return m.half_turns(ts[:, None] * v[None, :], Q, threads) @ u


@functools.lru_cache(maxsize=64)
def _shooting(smap, line, odd):
    """(the map of the half ``line``, v of its line, u of the line where Q half turns end)."""
    m = line_map(smap, line)
    return m, axes(m)[1], axes(m.opposite() if odd else m)[2]


def line_roots(smap, Q: int, a: float, b: float, n: int, line=None, threads=None) -> list:
    """The starts t in [a, b] on the symmetry line of the half ``line`` of the symmetric orbits of period Q
    (or a divisor): the sign changes of :func:`half_turn_p2` over n + 1 samples (on ``threads``), refined by
    the secant."""
    xs = np.linspace(a, b, n + 1)
    fs = half_turn_p2(smap, xs, Q, line, threads)
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


def symmetric_seeds(smap, Q: int, n: int, threads=None) -> np.ndarray:
    """Seeds (m, 2) on ``smap``'s half of its symmetric orbits of period Q (or a divisor): the roots of
    :func:`half_turn_p2` among ``n`` samples of the symmetry line of each half (the map's and its
    opposite's: an orbit of even period may meet one only), carried to the map's half
    (:func:`line_point`); none without a linear reversor; the samples' half turns on ``threads``."""
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
        for t in line_roots(m, Q, float(ts.min()), float(ts.max()), n - 1, threads=threads):
            try:
                seeds.append(line_point(m, t * v, smap.section_label))
            except ParameterError:
                continue
    return np.array(seeds, float).reshape(-1, 2)


@dataclass(frozen=True)
class SectionSymmetricOrbit(Residue):
    """A symmetric periodic orbit of a section map: ``points`` (Q, 2) on the map's section,
    ``monodromy`` on the half of its symmetry line ``line`` (the same trace), ``start`` its
    coordinate t on that line (the point t v, :func:`axes`)."""

    q: int
    points: np.ndarray
    monodromy: np.ndarray
    param_value: float
    line: float = math.pi
    start: float = math.nan

    @property
    def line_start(self) -> float:
        """t of the orbit's point on its symmetry line."""
        return float(self.points[0, 0]) if math.isnan(self.start) else self.start

    def rotation(self, smap, centre) -> float:
        """Turns around ``centre`` per return, in (-1/2, 1/2] (docs/greene.md, "Which orbits")."""
        turns = orbit_turns(smap, self.points[0], centre, self.q)
        return turns - math.ceil(turns - 0.5)


def section_symmetric_orbit(smap, Q: int, guess, guess2=None, *, param=None, line=None) -> SectionSymmetricOrbit:
    """The symmetric orbit of period Q through t v on the symmetry line of the half ``line`` (default the
    map's own), t by the secant from ``guess``, ``guess2``; points and monodromy M = G B^-1 G A from the
    first half (docs/greene.md, "Greene on the section of Figure 4's scene"; the other half: solved there,
    "Two symmetry lines")."""
    other = line_map(smap, line)
    if other is not smap:
        orb = section_symmetric_orbit(other, Q, guess, guess2, param=param)
        x0 = line_point(other, orb.points[0], smap.section_label)
        pts = smap.iterate(x0, Q - 1) if Q > 1 else x0[None, :]
        return SectionSymmetricOrbit(Q, np.asarray(pts, float)[:Q].copy(), orb.monodromy, orb.param_value,
                                     other.section_label, orb.start)
    G, v, _ = axes(smap)
    g = float(guess)
    t = line_root(smap, Q, g, g + 1e-7 * max(1.0, abs(g)) if guess2 is None else float(guess2))
    n = (Q + 1) // 2
    pts = np.empty((Q + 1, 2))
    pts[0] = t * v
    jacs = []
    for j in range(n):
        r = smap(pts[j])
        jacs.append(r.jacobian)
        pts[j + 1] = r.point
    for j in range(n + 1, Q + 1):
        pts[j] = G @ pts[Q - j]
    A = np.eye(2)
    B = np.eye(2)
    for j, J in enumerate(jacs):
        A = J @ A
        if j < Q - n:
            B = A.copy()
    if Q % 2 == 0:
        B = A
    gaps = np.max(np.abs(pts[1:Q] - pts[0]), axis=1)
    if gaps.size and gaps.min() <= 1e-9 * max(1.0, float(np.max(np.abs(pts[0])))):
        raise ParameterError(f"the symmetric orbit from t = {t:.10g} has period {int(np.argmin(gaps)) + 1}, not {Q}")
    det = B[0, 0] * B[1, 1] - B[0, 1] * B[1, 0]
    if not (np.all(np.isfinite(A)) and math.isfinite(det) and det != 0.0):
        raise ParameterError(f"the half orbit's Jacobian of the orbit of period {Q} from t = {t:.10g} is singular "
                             f"or not finite")
    B_inv = np.array([[B[1, 1], -B[0, 1]], [-B[1, 0], B[0, 0]]]) / det
    M = G @ B_inv @ G @ A       # DP^Q = DP^(Q-n)(x_n) A with P^(Q-n) = G P^-(Q-n) G
    value = smap.parameter_value if param is None else smap.value_of(param)
    return SectionSymmetricOrbit(Q, pts[:Q].copy(), M, value, smap.section_label, float(t))


def half_turn_orbit(smap, p, q, line=None, guess=None) -> SectionSymmetricOrbit:
    """A section map's ``symmetric_orbit``: :func:`section_symmetric_orbit` of period ``q`` from the point
    ``guess`` v of the symmetry line of the half ``line`` (default the map's own); ``guess`` is required."""
    if guess is None:
        raise ParameterError("symmetric_orbit on a section map needs guess=t, the point t v of the symmetry "
                             "line (p1 of p2 = 0 on Chaplygin's section) near the orbit")
    validation.integer("p", p, 0)
    return section_symmetric_orbit(smap, validation.integer("q", q, 1), validation.real("guess", guess), line=line)
