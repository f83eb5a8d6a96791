"""Rotation numbers of orbits of a map around an elliptic fixed point (docs/commands/rotation.md):
the angle increments the map gives (``lifted_increments``: Chaplygin's section map lifts them through
the flow, another map wraps its returns' increments, :func:`explorer.analysis.maps.returns_increments`),
averaged by the weighted Birkhoff average of Das, Sander, Yorke & Meiss (Nonlinearity 30 (2017) 4111);
``converged`` when the averages over N and 2N returns agree to ``CONVERGED_TOL``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer.analysis.maps import angle_increments, has_angle, orbit_turns
from explorer.analysis.section_map import system_first
from explorer.integrate.methods import MAP_TOL
from explorer.model import ParameterError, validation

__all__ = ["CONVERGED_TOL", "DEFAULT_ITERATES", "DIFFUSION_FLOOR", "RotationNumber", "RotationProfile",
           "birkhoff_weights", "frequency_diffusion", "orbit_rotation", "orbit_turns", "rotation_number",
           "rotation_profile", "weighted_birkhoff"]

#: |WB_N - WB_2N| below this: the orbit is regular
CONVERGED_TOL = 1e-10
#: N (the orbit has 2N returns)
DEFAULT_ITERATES = 2000
#: Taylor tolerance of the orbits (the rotation number inherits the integration error)
DEFAULT_TOL = MAP_TOL
def birkhoff_weights(N: int) -> np.ndarray:
    """Normalised weights w(n/N), n = 0..N-1, w(t) = exp(-1/(t (1 - t))) (w(0) = 0)."""
    t = np.arange(N) / N
    w = np.zeros(N)
    inner = (t > 0) & (t < 1)
    w[inner] = np.exp(-1.0 / (t[inner] * (1.0 - t[inner])))
    return w / w.sum()


def weighted_birkhoff(values, N: int | None = None) -> float:
    """Weighted Birkhoff average of the first N values (all by default)."""
    v = np.asarray(values, dtype=float)
    N = len(v) if N is None else N
    return float(birkhoff_weights(N) @ v[:N])


def orbit_rotation(points, center) -> float:
    """Rotation number m/K of a periodic orbit (K points in order) around ``center``: the sum
    of its K wrapped angle increments (around the closed orbit) over 2 pi K."""
    pts = np.asarray(points, float)
    closed = np.concatenate([pts, pts[:1]])
    return float(np.sum(angle_increments(closed, center)) / (2.0 * np.pi * len(pts)))


@dataclass(frozen=True)
class RotationNumber:
    """Rotation number of one orbit around ``center`` (docs/commands/rotation.md)."""

    value: float
    converged: bool
    difference: float
    iterates: int
    start: tuple[float, float]
    center: tuple[float, float]
    status: str = "done"
    turns: float = float("nan")

    def as_dict(self):
        return {"p1": float(self.start[0]), "p2": float(self.start[1]),
                "rotation": None if not math.isfinite(self.value) else float(self.value),
                "converged": bool(self.converged),
                "difference": None if not math.isfinite(self.difference) else float(self.difference),
                "turns": None if not math.isfinite(self.turns) else float(self.turns),
                "iterates": int(self.iterates), "status": self.status}


def _center(system, center, near):
    """The centre the rotation is measured around: ``center``, or on a map with an angle coordinate
    none (its angle itself), else the fixed point Newton finds from ``near``."""
    if center is None:
        if has_angle(system):
            return None
        from explorer.analysis.fixedpoints import find_fixed_point

        return find_fixed_point(system, near).point
    c = np.asarray(getattr(center, "point", center), float)
    if c.shape != (2,) or not np.all(np.isfinite(c)):
        raise ParameterError(f"center must be a finite point (p1, p2), got {center!r}")
    return c


def _inside(system, points) -> bool:
    return all(system.in_domain(x) for x in np.reshape(points, (-1, 2)))


def _rotations(system, starts, center, N, threads, conv_tol):
    starts = np.atleast_2d(np.asarray(starts, float))
    inc, count, status, lifted = system.lifted_increments(starts, center, 2 * N, threads)
    c = tuple(np.full(2, np.nan) if center is None else center)
    out = []
    for i, s in enumerate(starts):
        if status[i] != "done" or not np.all(np.isfinite(inc[i])):
            out.append(RotationNumber(float("nan"), False, float("nan"), int(count[i]), tuple(s), c, str(status[i])))
            continue
        a, b = weighted_birkhoff(inc[i], N), weighted_birkhoff(inc[i], 2 * N)
        diff = abs(a - b) / (2.0 * np.pi)
        turns = b / (2.0 * np.pi)
        out.append(RotationNumber(turns - math.ceil(turns - 0.5), bool(diff < conv_tol), diff, 2 * N, tuple(s), c,
                                  turns=turns if lifted[i] else float("nan")))
    return out


@system_first(systems="map", settings=("phi0", "tol"))
def rotation_number(system, start, *, center=None, iterates=DEFAULT_ITERATES, conv_tol=CONVERGED_TOL,
                    threads=None) -> RotationNumber:
    """Rotation number of the orbit of ``start`` around ``center`` (default: the fixed point Newton finds
    from ``start``; on a map with an angle coordinate, the angle itself), by the weighted Birkhoff average
    of the map's ``lifted_increments``."""
    N = validation.integer("iterates", iterates, 10)
    x = np.asarray(start, float)
    if x.shape != (2,) or not np.all(np.isfinite(x)) or not _inside(system, x):
        raise ParameterError(f"start {tuple(np.ravel(x))} must be a point of the map's allowed region; "
                             f"{system.describe_domain()}")
    return _rotations(system, x, _center(system, center, x), N, threads, conv_tol)[0]


@dataclass(frozen=True)
class RotationProfile:
    """Rotation numbers along a segment of the section (:func:`rotation_profile`)."""

    points: np.ndarray
    s: np.ndarray
    rotation: np.ndarray
    converged: np.ndarray
    difference: np.ndarray
    center: np.ndarray
    iterates: int
    turns: np.ndarray | None = None
    status: tuple = ()

    def as_dict(self):
        n = len(self.s)
        turns = np.full(n, np.nan) if self.turns is None else self.turns
        status = self.status or ("done",) * n
        return {"center": [float(v) for v in self.center], "iterates": int(self.iterates),
                "profile": [{"s": float(s), "p1": float(p[0]), "p2": float(p[1]),
                             "rotation": None if not math.isfinite(r) else float(r), "converged": bool(c),
                             "turns": None if not math.isfinite(t) else float(t), "status": st}
                            for s, p, r, c, t, st in zip(self.s, self.points, self.rotation, self.converged,
                                                         turns, status)]}


@system_first(systems="map", settings=("phi0", "tol"))
def rotation_profile(system, start, stop, *, n, center=None, iterates=DEFAULT_ITERATES, conv_tol=CONVERGED_TOL,
                     threads=None) -> RotationProfile:
    """Rotation numbers of n orbits started on the segment from ``start`` to ``stop``."""
    n = validation.integer("n", n, 2)
    N = validation.integer("iterates", iterates, 10)
    a, b = np.asarray(start, float), np.asarray(stop, float)
    s = np.linspace(0.0, 1.0, n)
    pts = a[None, :] + s[:, None] * (b - a)[None, :]
    if not _inside(system, pts):
        raise ParameterError(f"the segment from {tuple(a)} to {tuple(b)} leaves the map's allowed region; "
                             f"{system.describe_domain()}")
    c = _center(system, center, a)
    rs = _rotations(system, pts, c, N, threads, conv_tol)
    return RotationProfile(pts, s, np.array([r.value for r in rs]), np.array([r.converged for r in rs]),
                           np.array([r.difference for r in rs]), np.full(2, np.nan) if c is None else c, 2 * N,
                           np.array([r.turns for r in rs]), tuple(r.status for r in rs))


#: log10 |nu1 - nu2| is reported no lower than log10 of this (a difference of exactly 0: a point at
#: the centre, or halves equal to round-off)
DIFFUSION_FLOOR = 1e-17


@system_first(systems="map", settings=("phi0", "tol"))
def frequency_diffusion(system, starts, *, center, iterates=DEFAULT_ITERATES, threads=None) -> np.ndarray:
    """Frequency diffusion ``log10 |nu1 - nu2|`` of the orbits of ``starts`` (Laskar 1990, Icarus 88, 266,
    with the weighted Birkhoff average of Das, Sander, Yorke & Meiss 2017 in place of frequency
    analysis): nu1 the weighted-Birkhoff rotation number (turns per return around ``center``) of the
    first N = ``iterates`` returns, nu2 that of the next N.  On a regular orbit both converge to
    the same number faster than any power of N (below 1e-12 at N ~ 1000); on a chaotic one they
    differ by the drift of the frequency, 1e-8 to 1e-2."""
    X = np.atleast_2d(np.asarray(starts, float))
    if X.ndim != 2 or X.shape[1] != 2:
        raise ParameterError(f"starts must be points (n, 2), got shape {np.shape(starts)}")
    N = validation.integer("iterates", iterates, 10)
    c = None if center is None else _center(system, center, None)
    inc, _, status, _ = system.lifted_increments(X, c, 2 * N, threads)
    inc[status != "done"] = np.nan
    w = birkhoff_weights(N)
    # per-row sums, not a BLAS product: an orbit's value must not depend on the other rows
    nu1 = (inc[:, :N] * w).sum(axis=1) / (2.0 * np.pi)
    nu2 = (inc[:, N:] * w).sum(axis=1) / (2.0 * np.pi)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log10(np.maximum(np.abs(nu1 - nu2), DIFFUSION_FLOOR))
