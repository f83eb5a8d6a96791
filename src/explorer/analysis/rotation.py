"""Rotation numbers of orbits of the section map around an elliptic fixed point.

The rotation number of an orbit x_n = P^n(x_0) of the section map (phi = phi0, docs/model.md R9)
around a fixed point c is the mean angle advanced per return,

    rho = lim (1/N) sum_n d_n / (2 pi),

d_n the angle turned by x - c from x_n to x_{n+1} (counter-clockwise positive in the (p1, p2)
plane; rho is a fraction of a turn, defined modulo 1 and reported in (-1/2, 1/2]; the lifted
value, turns per return through the flow, is kept as ``turns``).

The lift
--------
Measuring d_n as atan2 at x_{n+1} minus atan2 at x_n, wrapped to (-pi, pi], is right only
while every return turns by less than half a turn: where the increments straddle pi (at
mu = 0 from p1 ~ 1.75 on the axis of the Figure 4 section to its edge at p1 = 2) a wrapped
average is neither the rotation number nor converged.  The increment is lifted through the
flow instead.  While M > 0 the angle phi is a time, the section map is the time-2 pi map of a
planar flow in phi, and the periodic orbit x*(phi) of c never meets another orbit x(phi) at
the same phi, so the angle theta(phi) of x(phi) - x*(phi) is a continuous function: d_n is
its change over phi in [phi0 + 2 pi n, phi0 + 2 pi (n + 1)], a continuous function of x_n
(the lift of the circle map).  theta is sampled on the m sub-sections phi0 + 2 pi k/m
(k = 0..m-1, m = ``SUBSECTIONS`` doubled up to ``MAX_SUBSECTIONS`` until no sample-to-sample
change exceeds ``MAX_SUBSTEP`` = pi/2) and unwrapped between samples.  At mu = 0 (docs/model.md
R6) x*(phi) is the point c itself (solution II) and d_n sums to the exact 2 pi T/tau of
the integrable motion (T the return time, tau the period of (p1, p2, M)).  An orbit whose
phi turns back across a sub-section (M changes sign, the flow in phi is not defined) is
reported with status ``"turned"`` and no rotation number; one whose samples still change by
more than ``MAX_SUBSTEP`` at ``MAX_SUBSECTIONS`` with ``"unresolved"``.

Sampling every return on m sub-sections costs m runs.  Most orbits need no such cost: the lift
L(x) of the increment is continuous on the orbit's closure (an invariant circle, or a connected
chaotic zone) and the wrapped increment is L - 2 pi j(x) with j integer, constant wherever L stays
clear of the odd multiples of pi.  When every one of the 2N wrapped increments lies within
``WRAP_SAFE`` = 3 pi/4 of 0, L cannot cross an odd multiple of pi on the orbit without a jump of
more than pi/2 between neighbouring points of the orbit, so j is one constant: the wrapped
increments are used, and j is read from the first lap sampled on sub-sections (``turns``).
The other orbits are sampled on sub-sections at every return.

The average
-----------
The weighted Birkhoff average of Das, Sander,
Yorke & Meiss (Quantitative quasiperiodicity, Nonlinearity 30 (2017) 4111; Das & Yorke,
Super convergence of ergodic averages for quasiperiodic orbits, Nonlinearity 31 (2018) 491):

    WB_N = sum_{n=0}^{N-1} w(n/N) d_n / sum_{n=0}^{N-1} w(n/N),   w(t) = exp(-1/(t (1 - t))),

which converges faster than any power of N on a regular (quasi-periodic) orbit and does not
converge on a chaotic one.  The test: WB over the first N increments against WB over 2N; a
difference below ``CONVERGED_TOL`` = 1e-10 marks the orbit regular (``converged``), a larger
one flags chaos.  On an island chain of period K around c, rho = m/K exactly (plateaus of
:func:`rotation_profile`).

The orbit comes from :func:`explorer.analysis.sections.crossings` (the Taylor batch driver:
2N crossings of one sub-section in one compiled call, ~4x faster per crossing than stepping
:class:`~explorer.analysis.section_map.SectionMap`, which pays a Python call and the tangent
set-up per return), in parallel over the points of a profile; a rotation number costs m runs.
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
           "birkhoff_weights", "frequency_diffusion", "orbit_rotation", "rotation_number", "rotation_profile",
           "weighted_birkhoff"]

#: |WB_N - WB_2N| below this: the orbit is regular
CONVERGED_TOL = 1e-10
#: N (the orbit has 2N returns)
DEFAULT_ITERATES = 2000
#: Taylor tolerance of the orbits (the rotation number inherits the integration error)
DEFAULT_TOL = MAP_TOL
#: sub-sections per return at the first try (the angle is sampled at phi0 + 2 pi k/m, see the module)
SUBSECTIONS = 4
#: most sub-sections per return: an orbit still under-sampled there is "unresolved"
MAX_SUBSECTIONS = 256
#: largest change of the angle between two consecutive samples accepted as resolved
MAX_SUBSTEP = 0.5 * math.pi
#: the fast path: when every return's increment, wrapped to (-pi, pi], stays within this bound, the
#: wrapped increments are the lifted ones less one constant 2 pi j (see the module)
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
    """Rotation number of one orbit around ``center`` (see the module).

    ``value`` is WB over 2N increments reduced to (-1/2, 1/2] (NaN when the orbit stopped before
    2N returns or could not be lifted, ``status`` "turned" or "unresolved"), ``turns`` the same
    average lifted through the flow (turns per return, not reduced),
    ``difference`` = |WB_N - WB_2N|, ``converged`` = difference < ``CONVERGED_TOL``
    (regular orbit; False flags chaos), ``status`` the orbit's stop reason.
    """

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
    """The orbits of ``starts`` (and of ``center``, row 0) sampled on sub-sections phi0 + 2 pi f,
    each sub-section run once and kept while the sampling is refined (see the module)."""

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
        ref = np.empty((m, 2))                  # x*(phi0 + 2 pi (k + 1)/m); x*(phi0 + 2 pi) = center
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
        d -= 2.0 * np.pi * np.ceil((d - np.pi) / (2.0 * np.pi))     # each sample-to-sample change in (-pi, pi]
        t = np.concatenate([np.zeros((n, 1)), ts.reshape(n, -1)], axis=1)
        with np.errstate(invalid="ignore"):
            turned = ~np.all(np.diff(t, axis=1) > 0.0, axis=1) & (count == n_returns)
        status[turned] = "turned"     # phi went back across a sub-section: the samples are not in phi order
        d[turned] = np.nan
        return d.reshape(n, n_returns, m).sum(axis=2), np.abs(d).max(axis=1, initial=0.0), count, status


def _refined(samples: _Samples, n: int):
    """:meth:`_Samples.increments` for the n orbits of ``samples``, the sub-sections doubled from
    ``SUBSECTIONS`` for the orbits that need them (up to ``MAX_SUBSECTIONS``).  Returns
    (increments, returns reached, status names); "unresolved" where the doubling ran out."""
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
    """Per-return angle increments around the orbit of ``center``, lifted through the flow (see
    the module).  Returns (increments, returns reached, status names, lifted): where ``lifted``
    is False the increments are right modulo 2 pi only (the first lap could not be resolved)."""
    n = starts.shape[0]
    args = (params, h)
    tail = (phi0, tol, threads)
    # the returns alone (m = 1): the increments wrapped to (-pi, pi]
    inc, worst, count, status = _Samples(*args, starts, center, n_returns, *tail).increments(np.arange(n), 1)
    lifted = np.zeros(n, bool)
    safe = np.flatnonzero((status == "done") & (worst <= WRAP_SAFE))
    if safe.size:
        # every wrapped increment is away from +-pi: the lift differs from it by one constant 2 pi j,
        # read from the first lap sampled on sub-sections
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
    """:func:`rotation_number` on a map of the protocol other than a section map (no flow to lift
    the angle through): its 2N iterates' angle increments around ``center``, each wrapped to
    (-pi, pi].  The wrapped increments are the lifted ones less one constant 2 pi j when every one
    of them stays within ``WRAP_SAFE`` of 0 (the module's argument), so the value mod 1 is right;
    otherwise the orbit is "unresolved".  ``turns`` is the wrapped average (the lift with j = 0).
    ``center=None`` on a map with an angle coordinate (``periods``, the standard map's theta): the
    rotation number of the angle itself, (theta_2N - theta_0)/(2 pi 2N) weighted, lifted exactly
    (the rotational invariant circles of the standard map: Greene's golden curve has 0.618...)."""
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


def _map_increments(system, x, center, n):
    """The n angle increments of the orbit of x under a map of the protocol (:func:`_map_rotation`):
    around ``center`` wrapped to (-pi, pi] (None when one comes within pi/4 of a half turn, where
    the wrap may be wrong), or with ``center=None`` on a map with an angle coordinate, the angle's
    own increments (exact)."""
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
    return inc if np.all(np.abs(inc) <= WRAP_SAFE) else None


@system_first(settings=("phi0", "tol"))
def rotation_number(system, start, *, center=None, iterates=DEFAULT_ITERATES, conv_tol=CONVERGED_TOL,
                    threads=None) -> RotationNumber:
    """Rotation number of the orbit of ``start`` around an elliptic fixed point (weighted Birkhoff).

    Parameters
    ----------
    system : SectionMap
        The section map, or ``params, h`` (docs/api.md, "The system argument") (its energy,
        section angle phi0 and Taylor tolerance, that of the orbits).
    start : (float, float)
        (p1, p2) of the orbit on the section phi = ``phi0``.
    center : (float, float), FixedPoint or None
        The fixed point; None: Newton's method (find_fixed_point) from ``start``.
    iterates : int
        N: the orbit has 2N returns; WB_N and WB_2N are compared.
    conv_tol : float
        ``|WB_N - WB_2N|`` (in turns) below which the orbit counts as regular.

    Returns
    -------
    RotationNumber
        The rotation number in turns per return, in (-1/2, 1/2], and the convergence flag.
    """
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

    points: np.ndarray     # (n, 2)
    s: np.ndarray          # (n,) position along the segment, 0 at start, 1 at stop
    rotation: np.ndarray   # (n,) NaN where the orbit stopped
    converged: np.ndarray  # (n,) bool
    difference: np.ndarray
    center: np.ndarray
    iterates: int
    turns: np.ndarray | None = None    # (n,) lifted rotation (turns per return through the flow)
    status: tuple = ()                 # (n,) why each orbit stopped ("done", "turned", ...)

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


@system_first(settings=("phi0", "tol"))
def rotation_profile(system, start, stop, *, n, center=None, iterates=DEFAULT_ITERATES, conv_tol=CONVERGED_TOL,
                     threads=None) -> RotationProfile:
    """Rotation numbers of n orbits started on the segment from ``start`` to ``stop``.

    ``center`` defaults to the fixed point found by Newton's method from ``start`` (start a
    profile at the elliptic point).  Points outside the allowed region are refused.  Plateaus
    at m/K mark island chains of period K (converged, rational); non-converged points flag
    chaotic orbits.  The orbits run in parallel (Numba threads, ``threads``).
    """
    n = validation.integer("n", n, 2)
    N = validation.integer("iterates", iterates, 10)
    a, b = np.asarray(start, float), np.asarray(stop, float)
    s = np.linspace(0.0, 1.0, n)
    pts = a[None, :] + s[:, None] * (b - a)[None, :]
    if not is_section_map(system):    # another map of the protocol: one orbit at a time
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


@system_first(settings=("phi0", "tol"))
def frequency_diffusion(system, starts, *, center, iterates=DEFAULT_ITERATES, threads=None) -> np.ndarray:
    """Frequency diffusion ``log10 |nu1 - nu2|`` of the orbits of ``starts`` (Laskar 1990, Icarus 88, 266,
    with the weighted Birkhoff average of Das, Sander, Yorke & Meiss 2017 in place of frequency
    analysis): nu1 the weighted-Birkhoff rotation number (turns per return around ``center``) of the
    first N = ``iterates`` returns, nu2 that of the next N.  On a regular orbit both converge to
    the same number faster than any power of N (below 1e-12 at N ~ 1000); on a chaotic one they
    differ by the drift of the frequency, 1e-8 to 1e-2.

    ``center``: the point the angle turns around, required (docs/greene.md, "Frequency
    diffusion": any point off the orbits gives a valid indicator, the rotation number of an orbit
    that does not circle it being 0; the elliptic fixed point of the island studied gives its
    rotation numbers).  A :class:`SectionMap` lifts the increments through the flow (module
    docstring); another map of the protocol uses the wrapped increments (the fast path's
    condition; NaN where an increment comes within pi/4 of a half turn) or, with
    ``center=None`` on a map with an angle (the standard map), the angle's own increments.
    Returns an array (n,) (NaN where an orbit stopped early)."""
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
    # row by row (numpy's pairwise sum of each row), not a BLAS product whose rounding depends on the
    # number of rows: an orbit's value does not depend on the others (a sweep's chunks)
    nu1 = (inc[:, :N] * w).sum(axis=1) / (2.0 * np.pi)
    nu2 = (inc[:, N:] * w).sum(axis=1) / (2.0 * np.pi)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log10(np.maximum(np.abs(nu1 - nu2), DIFFUSION_FLOOR))
