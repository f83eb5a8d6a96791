"""Rotation numbers of orbits of the section map around an elliptic fixed point.

The rotation number of an orbit x_n = P^n(x_0) of the section map (phi = phi0, MODEL.md R9)
around a fixed point c is the mean angle advanced per return,

    rho = lim (1/N) sum_n d_n / (2 pi),   d_n = wrap(theta_{n+1} - theta_n) in (-pi, pi],

with theta_n = atan2(p2_n - c2, p1_n - c1) (the increments measured around c and unwrapped:
counter-clockwise positive in the (p1, p2) plane; rho is a fraction of a turn, defined modulo
1 and reported in (-1/2, 1/2]).  The average is the weighted Birkhoff average of Das, Sander,
Yorke & Meiss (Quantitative quasiperiodicity, Nonlinearity 30 (2017) 4111; Das & Yorke,
Super convergence of ergodic averages for quasiperiodic orbits, Nonlinearity 31 (2018) 491):

    WB_N = sum_{n=0}^{N-1} w(n/N) d_n / sum_{n=0}^{N-1} w(n/N),   w(t) = exp(-1/(t (1 - t))),

which converges faster than any power of N on a regular (quasi-periodic) orbit and does not
converge on a chaotic one.  The test: WB over the first N increments against WB over 2N; a
difference below ``CONVERGED_TOL`` = 1e-10 marks the orbit regular (``converged``), a larger
one flags chaos.  On an island chain of period K around c, rho = m/K exactly (plateaus of
:func:`rotation_profile`).

The orbit comes from :func:`explorer.analysis.sections.section_crossings` (the Taylor batch
driver: 2N crossings in one compiled call, ~4x faster per crossing than stepping
:class:`~explorer.analysis.fixedpoints.SectionMap`, which pays a Python call and the tangent
set-up per return), in parallel over the points of a profile.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.model import ParameterError, validation

__all__ = ["CONVERGED_TOL", "DEFAULT_ITERATES", "RotationNumber", "RotationProfile", "birkhoff_weights",
           "orbit_rotation", "rotation_number", "rotation_profile", "weighted_birkhoff"]

#: |WB_N - WB_2N| below this: the orbit is regular
CONVERGED_TOL = 1e-10
#: N (the orbit has 2N returns)
DEFAULT_ITERATES = 2000
#: Taylor tolerance of the orbits (the rotation number inherits the integration error)
DEFAULT_TOL = 1e-15


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

    ``value`` is WB over 2N increments (NaN when the orbit stopped before 2N returns),
    ``difference`` = |WB_N - WB_2N|, ``converged`` = difference < ``CONVERGED_TOL``
    (regular orbit; False flags chaos), ``status`` the orbit's stop reason.
    """

    value: float
    converged: bool
    difference: float
    iterates: int
    start: tuple
    center: tuple
    status: str = "done"

    def as_dict(self):
        return {"p1": float(self.start[0]), "p2": float(self.start[1]),
                "rotation": None if not math.isfinite(self.value) else float(self.value),
                "converged": bool(self.converged),
                "difference": None if not math.isfinite(self.difference) else float(self.difference),
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


def _rotations(params, h, starts, center, N, phi0, tol, threads, conv_tol):
    from explorer.analysis.sections import section_crossings

    starts = np.atleast_2d(np.asarray(starts, float))
    c = section_crossings(params, starts[:, 0], starts[:, 1], h, 2 * N, phi0=phi0, tol=tol, threads=threads,
                          tmax=1e3 * 2 * N)
    out = []
    for i, s in enumerate(starts):
        if c.count[i] < 2 * N:
            out.append(RotationNumber(float("nan"), False, float("nan"), int(c.count[i]), tuple(s), tuple(center),
                                      c.status_name(i)))
            continue
        pts = np.concatenate([s[None, :], c.data[i, :, 1:3]])
        d = _increments(pts, center)
        a, b = weighted_birkhoff(d, N), weighted_birkhoff(d, 2 * N)
        diff = abs(a - b) / (2.0 * np.pi)
        out.append(RotationNumber(b / (2.0 * np.pi), bool(diff < conv_tol), diff, 2 * N, tuple(s), tuple(center)))
    return out


def rotation_number(params, h, start, *, center=None, iterates=DEFAULT_ITERATES, phi0=math.pi, tol=DEFAULT_TOL,
                    conv_tol=CONVERGED_TOL, threads=None) -> RotationNumber:
    """Rotation number of the orbit of ``start`` around an elliptic fixed point (weighted Birkhoff).

    Parameters
    ----------
    params, h : Params, float
        Model parameters and energy level.
    start : (float, float)
        (p1, p2) of the orbit on the section phi = ``phi0``.
    center : (float, float), FixedPoint or None
        The fixed point; None: Newton's method (find_fixed_point) from ``start``.
    iterates : int
        N: the orbit has 2N returns; WB_N and WB_2N are compared.
    tol : float
        Taylor tolerance of the orbit.
    conv_tol : float
        ``|WB_N - WB_2N|`` (in turns) below which the orbit counts as regular.

    Returns
    -------
    RotationNumber
        The rotation number in turns per return, in (-1/2, 1/2], and the convergence flag.
    """
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

    def as_dict(self):
        return {"center": [float(v) for v in self.center], "iterates": int(self.iterates),
                "profile": [{"s": float(s), "p1": float(p[0]), "p2": float(p[1]),
                             "rotation": None if not math.isfinite(r) else float(r), "converged": bool(c)}
                            for s, p, r, c in zip(self.s, self.points, self.rotation, self.converged)]}


def rotation_profile(params, h, start, stop, n, *, center=None, iterates=DEFAULT_ITERATES, phi0=math.pi,
                     tol=DEFAULT_TOL, conv_tol=CONVERGED_TOL, threads=None) -> RotationProfile:
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
    bad = ~model.is_admissible(params, pts[:, 0], pts[:, 1], h, phi0)
    if bad.any():
        raise ParameterError(f"the segment from {tuple(a)} to {tuple(b)} leaves the allowed region; allowed: "
                             f"{model.describe_region(params, h, phi0)}")
    c = _center(params, h, center, a, phi0, tol)
    rs = _rotations(params, h, pts, c, N, phi0, tol, threads, conv_tol)
    return RotationProfile(pts, s, np.array([r.value for r in rs]), np.array([r.converged for r in rs]),
                           np.array([r.difference for r in rs]), c, 2 * N)
