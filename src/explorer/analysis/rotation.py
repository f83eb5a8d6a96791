"""Rotation numbers of orbits of the section map around an elliptic fixed point
(docs/commands/rotation.md): the increments lifted through the flow on sub-sections (or wrapped,
when every wrapped increment is within ``WRAP_SAFE`` of 0; for another map, the returns' increments
wrapped so, or lifted through the largest gap of their values mod 2 pi), averaged by the weighted Birkhoff
average of Das, Sander, Yorke & Meiss (Nonlinearity 30 (2017) 4111); ``converged`` when the
averages over N and 2N returns agree to ``CONVERGED_TOL``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.analysis.maps import is_section_map
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
#: sub-sections per return at the first try
SUBSECTIONS = 4
#: most sub-sections per return: an orbit still under-sampled there is "unresolved"
MAX_SUBSECTIONS = 256
#: largest change of the angle between two consecutive samples accepted as resolved
MAX_SUBSTEP = 0.5 * math.pi
#: the fast path: when every return's increment, wrapped to (-pi, pi], stays within this bound, the
#: wrapped increments are the lifted ones less one constant 2 pi j (docs/commands/rotation.md)
WRAP_SAFE = 0.75 * math.pi
#: time budget of an orbit per return
TMAX_PER_RETURN = 1e3


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


def _increments(points, center):
    """Angle increments around center, each wrapped to (-pi, pi]: (..., n) from (..., n + 1, 2)."""
    th = np.arctan2(points[..., 1] - center[1], points[..., 0] - center[0])
    d = np.diff(th, axis=-1)
    return d - 2.0 * np.pi * np.ceil((d - np.pi) / (2.0 * np.pi))


def orbit_rotation(points, center) -> float:
    """Rotation number m/K of a periodic orbit (K points in order) around ``center``: the sum
    of its K wrapped angle increments (around the closed orbit) over 2 pi K."""
    pts = np.asarray(points, float)
    closed = np.concatenate([pts, pts[:1]])
    return float(np.sum(_increments(closed, center)) / (2.0 * np.pi * len(pts)))


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


def _center(params, h, center, near, phi0, tol):
    if center is not None:
        c = np.asarray(getattr(center, "point", center), float)
        if c.shape != (2,) or not np.all(np.isfinite(c)):
            raise ParameterError(f"center must be a finite point (p1, p2), got {center!r}")
        return c
    from explorer.analysis.fixedpoints import find_fixed_point

    fp = find_fixed_point(params, h, near, phi0=phi0, tol=tol)
    return fp.point


class _Samples:

    def __init__(self, params, h, starts, center, n_returns, phi0, tol, threads):
        self.args = (params, n_returns, phi0, tol, threads)
        self.center = center
        self.starts = starts
        self.Y0 = model.section_state(params, np.concatenate([[center[0]], starts[:, 0]]),
                                      np.concatenate([[center[1]], starts[:, 1]]), h, phi0, 1)
        self.runs: dict = {}

    def at(self, f: float):
        """Crossings of phi0 + 2 pi f, 0 <= f < 1 (f = 0: the returns to the section)."""
        if f not in self.runs:
            from explorer.analysis.sections import crossings

            params, n_returns, phi0, tol, threads = self.args
            c = crossings(params, states=self.Y0, n_crossings=n_returns, phi0=phi0 + 2.0 * math.pi * f, tol=tol,
                          threads=threads, tmax=TMAX_PER_RETURN * n_returns)
            if c.count[0] < 1:
                raise ParameterError(f"center {tuple(self.center)} must be a point whose orbit crosses the "
                                     f"section; its orbit stopped ({c.status_name(0)})")
            self.runs[f] = c
        return self.runs[f]

    def increments(self, rows, m: int):
        """For the orbits ``rows`` sampled on m sub-sections: (per-return increments (n, n_returns),
        largest sample-to-sample change (n,), returns reached (n,), status names (n,)); rows of
        orbits that stopped early or turned back are NaN."""
        _, n_returns, _, _, _ = self.args
        n = rows.size
        xs = np.empty((n, n_returns, m, 2))     # x at phi0 + 2 pi (lap + (k + 1)/m), k = 0..m-1
        ts = np.empty((n, n_returns, m))
        ref = np.empty((m, 2))
        count = np.full(n, n_returns)
        status = np.array(["done"] * n, dtype=object)
        for k in range(1, m + 1):
            c = self.at((k % m) / m)
            ref[k - 1] = self.center if k == m else c.data[0, 0, 1:3]
            xs[:, :, k - 1] = c.data[1 + rows, :, 1:3]
            ts[:, :, k - 1] = c.data[1 + rows, :, 0]
            for i in np.flatnonzero(c.count[1 + rows] < count):
                count[i], status[i] = c.count[1 + rows[i]], c.status_name(1 + rows[i])
        theta = np.arctan2(xs[..., 1] - ref[:, 1], xs[..., 0] - ref[:, 0]).reshape(n, -1)
        x0 = self.starts[rows]
        theta0 = np.arctan2(x0[:, 1] - self.center[1], x0[:, 0] - self.center[0])
        d = np.diff(np.concatenate([theta0[:, None], theta], axis=1), axis=1)
        d -= 2.0 * np.pi * np.ceil((d - np.pi) / (2.0 * np.pi))
        t = np.concatenate([np.zeros((n, 1)), ts.reshape(n, -1)], axis=1)
        with np.errstate(invalid="ignore"):
            turned = ~np.all(np.diff(t, axis=1) > 0.0, axis=1) & (count == n_returns)
        status[turned] = "turned"
        d[turned] = np.nan
        return d.reshape(n, n_returns, m).sum(axis=2), np.abs(d).max(axis=1, initial=0.0), count, status


def _refined(samples: _Samples, n: int):
    inc = np.full((n, samples.args[1]), np.nan)
    count = np.zeros(n, np.int64)
    status = np.array(["unresolved"] * n, dtype=object)
    todo = np.arange(n)
    m = SUBSECTIONS
    while todo.size and m <= MAX_SUBSECTIONS:
        d, worst, cnt, st = samples.increments(todo, m)
        ok = (worst <= MAX_SUBSTEP) | (st != "done")
        inc[todo[ok]], count[todo[ok]], status[todo[ok]] = d[ok], cnt[ok], st[ok]
        count[todo[~ok]] = cnt[~ok]
        todo, m = todo[~ok], 2 * m
    return inc, count, status


def _lifted_increments(params, h, starts, center, n_returns, phi0, tol, threads):
    n = starts.shape[0]
    args = (params, h)
    tail = (phi0, tol, threads)
    # the returns alone (m = 1): the increments wrapped to (-pi, pi]
    inc, worst, count, status = _Samples(*args, starts, center, n_returns, *tail).increments(np.arange(n), 1)
    lifted = np.zeros(n, bool)
    safe = np.flatnonzero((status == "done") & (worst <= WRAP_SAFE))
    if safe.size:
        first, _, st = _refined(_Samples(*args, starts[safe], center, 1, *tail), safe.size)
        j = np.round((first[:, 0] - inc[safe, 0]) / (2.0 * np.pi))
        known = (st == "done") & np.isfinite(j)
        inc[safe[known]] += 2.0 * np.pi * j[known, None]
        lifted[safe[known]] = True
    rest = np.flatnonzero((status == "done") & (worst > WRAP_SAFE))
    if rest.size:
        d, cnt, st = _refined(_Samples(*args, starts[rest], center, n_returns, *tail), rest.size)
        inc[rest], count[rest], status[rest] = d, cnt, st
        lifted[rest] = st == "done"
    return inc, count, status, lifted


def _rotations(params, h, starts, center, N, phi0, tol, threads, conv_tol):
    starts = np.atleast_2d(np.asarray(starts, float))
    inc, count, status, lifted = _lifted_increments(params, h, starts, np.asarray(center, float), 2 * N, phi0, tol,
                                                    threads)
    out = []
    for i, s in enumerate(starts):
        if status[i] != "done":
            out.append(RotationNumber(float("nan"), False, float("nan"), int(count[i]), tuple(s), tuple(center),
                                      str(status[i])))
            continue
        a, b = weighted_birkhoff(inc[i], N), weighted_birkhoff(inc[i], 2 * N)
        diff = abs(a - b) / (2.0 * np.pi)
        turns = b / (2.0 * np.pi)
        out.append(RotationNumber(turns - math.ceil(turns - 0.5), bool(diff < conv_tol), diff, 2 * N, tuple(s),
                                  tuple(center), turns=turns if lifted[i] else float("nan")))
    return out


def _map_rotation(system, start, center, N, conv_tol) -> RotationNumber:
    x = np.asarray(start, float)
    if x.shape != (2,) or not np.all(np.isfinite(x)):
        raise ParameterError(f"start must be a finite point, got {start!r}")
    per = getattr(system, "periods", None)
    if center is None and not (per is not None and per[0] > 0):
        from explorer.analysis.fixedpoints import find_fixed_point

        center = find_fixed_point(system, x)
    inc = _map_increments(system, x, center, 2 * N)
    status = "done" if inc is not None else "unresolved"
    c = (float("nan"), float("nan")) if center is None else \
        tuple(float(t) for t in np.asarray(getattr(center, "point", center), float))
    if inc is None or not np.all(np.isfinite(inc)):
        return RotationNumber(float("nan"), False, float("nan"), 2 * N, tuple(x), tuple(c), status)
    a, b = weighted_birkhoff(inc, N), weighted_birkhoff(inc, 2 * N)
    diff = abs(a - b) / (2.0 * np.pi)
    turns = b / (2.0 * np.pi)
    return RotationNumber(turns - math.ceil(turns - 0.5), bool(diff < conv_tol), diff, 2 * N, tuple(x), tuple(c),
                          turns=turns)


def orbit_turns(system, start, center, n: int) -> float:
    """Turns per return around ``center`` over the first ``n`` returns from ``start`` (a section map's
    lifted through the flow); ParameterError where the lift is not defined."""
    x, c = np.asarray(start, float), np.asarray(center, float)
    if is_section_map(system):
        inc, _, status, _ = _lifted_increments(system.params, system.h, x[None, :], c, n, system.phi0, system.tol,
                                               None)
        why = status[0]
        inc = inc[0] if why == "done" else None
    else:
        inc, why = _map_increments(system, x, c, n), "unresolved"
    if inc is None or not np.all(np.isfinite(inc)):
        raise ParameterError(f"the rotation of the orbit from {tuple(x)} around the centre is not defined ({why})")
    return float(np.sum(inc)) / (2.0 * math.pi * n)


def _map_increments(system, x, center, n):
    from explorer.analysis.maps import difference

    pts = system.iterate(x, n)
    per = getattr(system, "periods", None)
    if center is None:
        if per is None or not per[0] > 0:
            raise ParameterError("center=None needs a map with an angle coordinate (periods); give center=")
        return np.diff(pts[:, 0]) * (2.0 * np.pi / per[0])
    c = np.asarray(getattr(center, "point", center), float)
    if c.shape != (2,) or not np.all(np.isfinite(c)):
        raise ParameterError(f"center must be a finite point, got {center!r}")
    inc = _increments(c + difference(system, pts, c), c)
    return inc if np.all(np.abs(inc) <= WRAP_SAFE) else _lifted_through_gap(inc)


def _lifted_through_gap(inc):
    """The increments lifted into one window of 2 pi cut in the middle of the largest gap of their
    values mod 2 pi (an invariant circle's increments span less than a turn), when that gap is at
    least the fast path's margin 2 pi - 2 WRAP_SAFE; else None."""
    v = np.sort(np.mod(inc, 2.0 * np.pi))
    gaps = np.diff(np.concatenate([v, [v[0] + 2.0 * np.pi]]))
    k = int(np.argmax(gaps))
    if not gaps[k] >= 2.0 * np.pi - 2.0 * WRAP_SAFE:
        return None
    cut = v[k] + 0.5 * gaps[k]
    return np.mod(inc - cut, 2.0 * np.pi) + cut - 2.0 * np.pi


@system_first(systems="map", settings=("phi0", "tol"))
def rotation_number(system, start, *, center=None, iterates=DEFAULT_ITERATES, conv_tol=CONVERGED_TOL,
                    threads=None) -> RotationNumber:
    """Rotation number of the orbit of ``start`` around an elliptic fixed point (weighted Birkhoff)."""
    if not is_section_map(system):
        return _map_rotation(system, start, center, validation.integer("iterates", iterates, 10), conv_tol)
    params, h, phi0, tol = system.params, system.h, system.phi0, system.tol
    N = validation.integer("iterates", iterates, 10)
    x = np.asarray(start, float)
    if x.shape != (2,) or not model.is_admissible(params, x[0], x[1], h, phi0):
        raise ParameterError(f"start {tuple(np.ravel(x))} must be a point (p1, p2) of the allowed region; allowed: "
                             f"{model.describe_region(params, h, phi0)}")
    c = _center(params, h, center, x, phi0, tol)
    return _rotations(params, h, x, c, N, phi0, tol, threads, conv_tol)[0]


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
    if not is_section_map(system):
        per = getattr(system, "periods", None)
        if center is None and not (per is not None and per[0] > 0):
            from explorer.analysis.fixedpoints import find_fixed_point

            center = find_fixed_point(system, a)
        rs = [_map_rotation(system, x, center, N, conv_tol) for x in pts]
        c = np.full(2, np.nan) if center is None else np.asarray(getattr(center, "point", center), float)
        return RotationProfile(pts, s, np.array([r.value for r in rs]), np.array([r.converged for r in rs]),
                               np.array([r.difference for r in rs]), c, 2 * N, np.array([r.turns for r in rs]),
                               tuple(r.status for r in rs))
    params, h, phi0, tol = system.params, system.h, system.phi0, system.tol
    bad = ~model.is_admissible(params, pts[:, 0], pts[:, 1], h, phi0)
    if bad.any():
        raise ParameterError(f"the segment from {tuple(a)} to {tuple(b)} leaves the allowed region; allowed: "
                             f"{model.describe_region(params, h, phi0)}")
    c = _center(params, h, center, a, phi0, tol)
    rs = _rotations(params, h, pts, c, N, phi0, tol, threads, conv_tol)
    return RotationProfile(pts, s, np.array([r.value for r in rs]), np.array([r.converged for r in rs]),
                           np.array([r.difference for r in rs]), c, 2 * N, np.array([r.turns for r in rs]),
                           tuple(r.status for r in rs))


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
    if is_section_map(system):
        if center is None:
            raise ParameterError("frequency_diffusion on a section map needs center=(p1, p2): the point the "
                                 "rotation numbers turn around (e.g. an elliptic fixed point)")
        c = np.asarray(getattr(center, "point", center), float)
        inc, count, status, _ = _lifted_increments(system.params, system.h, X, c, 2 * N, system.phi0, system.tol,
                                                   threads)
        inc[status != "done"] = np.nan
    else:
        inc = np.full((len(X), 2 * N), np.nan)
        for i, x in enumerate(X):
            r_inc = _map_increments(system, x, center, 2 * N)
            if r_inc is not None:
                inc[i] = r_inc
    w = birkhoff_weights(N)
    # per-row sums, not a BLAS product: an orbit's value must not depend on the other rows
    nu1 = (inc[:, :N] * w).sum(axis=1) / (2.0 * np.pi)
    nu2 = (inc[:, N:] * w).sum(axis=1) / (2.0 * np.pi)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log10(np.maximum(np.abs(nu1 - nu2), DIFFUSION_FLOOR))
