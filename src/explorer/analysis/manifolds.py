"""Stable and unstable manifolds of hyperbolic periodic orbits of the section map, and their
intersections (homoclinic points).  docs/manifolds.md has the method and its accuracy.

Parametrisation
---------------
Let x* be a point of a hyperbolic orbit of period K of the section map P
(:class:`~explorer.analysis.section_map.SectionMap`, docs/model.md R9), F = P^m with m = K (m = 2K
when the multiplier is negative, so that F keeps each branch), Lambda > 1 the multiplier of F
along the branch (F^{-1} for a stable manifold) and e the unit eigenvector (``sign`` = +1: the
orientation with e[0] > 0, or e[1] > 0 when e[0] = 0).  Every point of the branch is

    x(sigma) = F^n(x* + exp(sigma - n L) e),   L = log Lambda,   n = floor((sigma - sigma0) / L),

with exp(sigma0) = s0 the start distance: the fundamental domain [s0, s0 Lambda) of the linear
manifold and its n-th images.  sigma is continuous along the branch (F moves sigma by L), so
the branch is the curve sigma -> x(sigma), computed exactly (to the map's accuracy) at any
sigma, with no interpolation.

Start distance: on the manifold, in the eigenbasis (u along e, v along the other eigenvector),
v = a u^2 / 2 + O(u^3), so x* + s e is off the manifold by |a| s^2 / 2.  a is measured from one
image of a trial point (the v-component of F(x* + s e) is a s^2 (Lambda^2 - 1/Lambda) / 2, the
invariance of the graph), and s0 = sqrt(2 ``tol`` / |a|): the start points are within ``tol``
of the manifold, and F contracts that transverse error by 1/Lambda per generation.

Growth (Hobson 1993, J. Comput. Phys. 104, 14; Krauskopf & Osinga 1998, J. Comput. Phys. 146,
404): start with ``INITIAL_POINTS`` points of the fundamental domain; repeat (i) refine: where
the distance between neighbours exceeds ``max_gap``, the angle at a point exceeds
``max_angle``, or distance times angle exceeds ``max_gap_angle``, insert the point at the
mid-value of sigma (computed from the fundamental domain, n maps); (ii) extend: map the last
generation once (F, one batch of the Taylor lanes, :func:`explorer.analysis.sections.crossings`)
- until the branch has the requested arclength (or ``generations`` images of the fundamental
domain) or a budget (points, wall time) runs out or a point has no return (the region's edge).
``ManifoldBranch.status`` says which.  The batches are small (tens to hundreds of points), so
they run on one thread (``explorer.analysis.maps.SERIAL_RETURNS``).

Points of the stable manifold need F^{-1}: when the reversor applies
(:func:`explorer.analysis.periodic.is_reversible`), F^{-1} = G0 F G0 and the batch runs
forward; otherwise each point is integrated backward in time by the section map
(``backward="integrate"`` forces that path).  For a fixed point on the reversor's symmetry line
(the central saddle of the Figure-4 scene) nothing needs computing at all: W^s = G0 W^u, branch
by branch (G0 keeps the first component, so the orientation and the sign agree), and the stable
branch is the reflection of the unstable one, point for point (:func:`mirror_branch`); the
tangle and the flux curve grow half the points.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from explorer.analysis.maps import images
from explorer.analysis.periodic import PeriodicOrbit, find_periodic_orbit
from explorer.analysis.section_map import SectionMap, system_first
from explorer.model import ParameterError, validation

__all__ = ["DEFAULT_MAX_ANGLE", "DEFAULT_MAX_GAP", "DEFAULT_MAX_GAP_ANGLE", "DEFAULT_START_TOL", "Homoclinic",
           "ManifoldBranch", "Saddle", "grow_branch", "heteroclinic_points", "homoclinic_orbit", "homoclinic_points",
           "manifolds", "mirror_branch", "mirrors",
           "saddle"]

#: transverse distance of the start points from the manifold (module docstring)
DEFAULT_START_TOL = 1e-12
#: a fixed point this close to the symmetry line p2 = 0 has W^s = G0 W^u (:func:`mirrors`): far
#: below DEFAULT_START_TOL, so the reflection is as close to W^s as a grown branch
MIRROR_TOL = 1e-14
#: refinement bounds (Krauskopf & Osinga 1998): distance between neighbours, angle at a point
#: (radians) and their product; the polyline deviates from the curve by about
#: gap * angle / 8 <= DEFAULT_MAX_GAP_ANGLE / 8
DEFAULT_MAX_GAP = 0.02
DEFAULT_MAX_ANGLE = 0.2
DEFAULT_MAX_GAP_ANGLE = 2e-4
#: points of the first fundamental domain
INITIAL_POINTS = 16
#: trial distance along the eigenvector for the curvature estimate
TRIAL_DISTANCE = 1e-4
#: limits of the start distance
MIN_START, MAX_START = 1e-9, 1e-3
#: an interval of sigma narrower than this is not split further
MIN_DSIGMA = 1e-11
#: Newton for intersections: step of the central differences in sigma, tolerance, iterations
DIFF_STEP = 1e-6
INTERSECTION_TOL = 1e-12
NEWTON_ITER = 30
#: two intersections closer than this are the same point
SAME_POINT = 1e-9

STATUS_ARCLENGTH = "arclength"
STATUS_GENERATIONS = "generations"
STATUS_EDGE = "edge"
STATUS_MAX_POINTS = "max_points"
STATUS_MAX_TIME = "max_time"


# ------------------------------------------------------------------ the saddle
@dataclass(frozen=True)
class Saddle:
    """A point x* of a hyperbolic orbit of period K, F = P^m (m = K, or 2K when the multiplier
    is negative), the multiplier of F along the unstable direction (> 1) and the unit
    eigenvectors of DF (unstable, stable) with the orientation of ``sign = +1``."""

    point: np.ndarray
    period: int
    maps: int
    multiplier: float
    eigenvalues: np.ndarray
    e_unstable: np.ndarray
    e_stable: np.ndarray
    smap: SectionMap
    orbit_points: np.ndarray


def _orient(v):
    v = np.asarray(v, float) / np.linalg.norm(v)
    return -v if (v[0] < 0 or (v[0] == 0 and v[1] < 0)) else v


@system_first
def saddle(system, orbit, *, index=0) -> Saddle:
    """The :class:`Saddle` at point ``index`` of a hyperbolic ``orbit`` (a
    :class:`~explorer.analysis.periodic.PeriodicOrbit` or a
    :class:`~explorer.analysis.fixedpoints.FixedPoint`) of the map ``system``."""
    if isinstance(orbit, PeriodicOrbit):
        pts, K, jacs = orbit.points, orbit.period, orbit.map_jacobians
    elif hasattr(orbit, "jacobian") and hasattr(orbit, "point"):
        pts, K, jacs = np.atleast_2d(orbit.point), 1, np.array([orbit.jacobian])
    else:
        raise ParameterError(f"orbit must be a PeriodicOrbit or a FixedPoint, got {type(orbit).__name__}")
    index = validation.integer("index", index, 0, K - 1)
    M = np.eye(2)   # monodromy at point `index`: DP(x_{index-1}) ... DP(x_index)
    for j in range(K):
        M = jacs[(index + j) % K] @ M
    w, V = np.linalg.eig(M)
    if np.iscomplexobj(w) and np.any(np.abs(np.imag(w)) > 0):
        raise ParameterError(f"the orbit is not hyperbolic (multipliers {w[0]:.6g}, {w[1]:.6g}): no manifolds")
    w, V = np.real(w), np.real(V)
    iu = int(np.argmax(np.abs(w)))
    if not abs(w[iu]) > 1.0 + 1e-9:
        raise ParameterError(f"the orbit is not hyperbolic (multipliers {w[0]:.6g}, {w[1]:.6g}): no manifolds")
    maps = K if w[iu] > 0 else 2 * K
    mult = abs(w[iu]) ** (maps // K)
    return Saddle(np.array(pts[index], float), K, maps, float(mult), w, _orient(V[:, iu]), _orient(V[:, 1 - iu]),
                  system, np.array(pts, float))


# ------------------------------------------------------------------ images in batches
def _images(smap, X, n, backward, integrate_backward=False):
    """P^n (P^-n with ``backward``) of the points X (m, 2), NaN where a return fails:
    :func:`explorer.analysis.maps.images`, or with ``integrate_backward`` the map's own
    point-by-point preimages (no reversor)."""
    X = np.asarray(X, float).reshape(-1, 2)
    if n == 0 or X.size == 0:
        return X.copy()
    if backward and integrate_backward:
        return smap.images(X, n, backward=True)[:, -1]
    return images(smap, X, n, backward=backward)[:, -1]


class _Curve:
    """sigma -> x(sigma) of one branch (module docstring)."""

    def __init__(self, sd: Saddle, stable: bool, sign: int, start_tol: float, integrate_backward: bool):
        self.sd, self.stable, self.sign = sd, stable, sign
        self.backward_integrated = integrate_backward
        self.e = sign * (sd.e_stable if stable else sd.e_unstable)
        self.L = math.log(sd.multiplier)
        # curvature a of the graph v = a u^2 / 2 from one image of a trial point
        s = TRIAL_DISTANCE
        y = self.map(sd.point + s * self.e, 1)[0]
        B = np.column_stack([sd.e_stable if stable else sd.e_unstable, sd.e_unstable if stable else sd.e_stable])
        if np.all(np.isfinite(y)):
            v = np.linalg.solve(B, y - sd.point)[1]
            lam = sd.multiplier
            a = 2.0 * abs(v) / (s * s * (lam * lam - 1.0 / lam))
        else:
            a = 1.0 / s
        self.curvature = float(a)
        s0 = math.sqrt(2.0 * start_tol / a) if a > 0 else MAX_START
        self.s0 = float(min(max(s0, MIN_START), MAX_START))
        self.sigma0 = math.log(self.s0)

    def map(self, X, generations):
        return _images(self.sd.smap, X, generations * self.sd.maps, self.stable, self.backward_integrated)

    def generation(self, sigma):
        return np.maximum(np.floor((np.asarray(sigma, float) - self.sigma0) / self.L), 0).astype(int)

    def points(self, sigma):
        """x(sigma) for an array of sigma (NaN where a map fails), each from the fundamental domain."""
        sigma = np.atleast_1d(np.asarray(sigma, float))
        n = self.generation(sigma)
        out = np.empty((sigma.size, 2))
        for g in np.unique(n):
            sel = n == g
            x0 = self.sd.point + np.exp(sigma[sel] - g * self.L)[:, None] * self.e
            out[sel] = self.map(x0, int(g))
        return out



class _MirroredCurve:
    """sigma -> G0 x_u(sigma): the stable branch of a saddle on the symmetry line as the reversor's
    image of its unstable branch (:func:`mirrors`); F^-1 = G0 F G0 maps it as the unstable curve's
    F maps that one."""

    def __init__(self, unstable: _Curve):
        self.unstable = unstable
        self.sd, self.stable, self.sign = unstable.sd, True, unstable.sign
        self.G = unstable.sd.smap.reflection
        self.backward_integrated = False
        self.e = self.G(unstable.e)
        self.L, self.curvature, self.s0, self.sigma0 = unstable.L, unstable.curvature, unstable.s0, unstable.sigma0

    def map(self, X, generations):
        return self.G(self.unstable.map(self.G(X), generations))

    def generation(self, sigma):
        return self.unstable.generation(sigma)

    def points(self, sigma):
        return self.G(self.unstable.points(sigma))


@dataclass(frozen=True)
class ManifoldBranch:
    """One branch of W^u (``kind`` "unstable") or W^s ("stable") of a saddle, as a polyline from
    the orbit's point outwards.

    ``points[0]`` is the saddle point; ``points[1:]`` are points x(sigma) of the manifold at the
    parameters ``sigma[1:]`` (``sigma[0]`` = -inf), within ``start_tol`` of the manifold
    (transversally; module docstring).  ``status``: "arclength" (grown to ``target``),
    "edge" (a point further on has no return of the map or left the allowed region),
    "max_points" or "max_time" (budgets).
    """

    kind: str
    sign: int
    points: np.ndarray
    sigma: np.ndarray
    arclength: float
    target: float
    status: str
    start_distance: float
    start_tol: float
    curvature: float
    evaluations: int
    seconds: float
    curve: _Curve = field(repr=False, compare=False, default=None)
    max_gap: float = DEFAULT_MAX_GAP
    #: where the growth stopped, before the cut at ``target``, with its settings: what
    #: ``grow_branch(..., resume=branch)`` continues from (None when it cannot be continued)
    grown: tuple | None = field(repr=False, compare=False, default=None)
    #: the unstable branch this stable one reflects (:func:`mirror_branch`), else None
    mirror_of: ManifoldBranch | None = field(repr=False, compare=False, default=None)

    @property
    def tears(self) -> np.ndarray:
        """sigma at the start of each jump of the branch: neighbours farther apart than ``max_gap``
        whose sigma differ by no more than the refinement's limit ``MIN_DSIGMA``, so that no
        point between them lies between them on the plane.  The section map is discontinuous
        there (an orbit grazes the section, M = 0 at phi = phi0: the first return time jumps,
        docs/manifolds.md), and the branch beyond is not the continuation of the arc before."""
        d = np.linalg.norm(np.diff(self.points[1:], axis=0), axis=1)
        ds = np.diff(self.sigma[1:])
        return self.sigma[1:-1][(d > self.max_gap) & (ds <= 1.5 * MIN_DSIGMA)]

    @property
    def first_tear(self) -> float:
        """The smallest sigma of :attr:`tears` (inf when the branch is unbroken)."""
        t = self.tears
        return float(t[0]) if t.size else math.inf

    def at(self, sigma) -> np.ndarray:
        """Points of the branch at parameters ``sigma`` (computed afresh, no interpolation)."""
        return self.curve.points(sigma)

    def distance(self, x, *, rounds=4, samples=24) -> float:
        """Distance from the point x to the branch, from points computed afresh: the nearest
        stored point's neighbourhood in sigma is sampled ``samples`` times and narrowed to the
        best sample's neighbours ``rounds`` times (no chord error of the polyline)."""
        x = np.asarray(x, float)
        i = int(np.argmin(np.linalg.norm(self.points[1:] - x, axis=1))) + 1
        lo = self.sigma[max(i - 1, 1)]
        hi = self.sigma[min(i + 1, len(self.sigma) - 1)]
        for _ in range(rounds):
            s = np.linspace(lo, hi, samples)
            pts = self.at(s)
            k = int(np.nanargmin(np.linalg.norm(pts - x, axis=1)))
            lo, hi = s[max(k - 1, 0)], s[min(k + 1, samples - 1)]
        # the first segment (saddle to the first point) is the linear manifold, off by <= start_tol
        return min(_polyline_distance(pts[max(k - 1, 0):k + 2], x), _polyline_distance(self.points[:2], x))

    def as_dict(self):
        return {"kind": self.kind, "sign": int(self.sign), "points": self.points.tolist(),
                "arclength": float(self.arclength), "status": self.status,
                "start_distance": self.start_distance, "start_tol": self.start_tol}


def _polyline_distance(P, x):
    """Distance from x to the polyline P (m, 2)."""
    if len(P) == 1:
        return float(np.linalg.norm(P[0] - x))
    a, b = P[:-1], P[1:]
    d = b - a
    t = np.clip(np.sum((x - a) * d, axis=1) / np.maximum(np.sum(d * d, axis=1), 1e-300), 0.0, 1.0)
    return float(np.min(np.linalg.norm(a + t[:, None] * d - x, axis=1)))


def _arc(points):
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])


def _bad_intervals(P, max_gap, max_angle, max_gap_angle, lo):
    """Indices i >= lo of intervals (P[i], P[i+1]) to split (the refinement rule)."""
    d = np.linalg.norm(np.diff(P, axis=0), axis=1)
    bad = d > max_gap
    if len(P) >= 3:
        u, v = P[1:-1] - P[:-2], P[2:] - P[1:-1]
        cross = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
        ang = np.abs(np.arctan2(cross, np.sum(u * v, axis=1)))
        worst = (ang > max_angle) | (ang * np.minimum(d[:-1], d[1:]) > max_gap_angle)
        bad[:-1] |= worst
        bad[1:] |= worst
    bad[:max(lo, 1)] = False     # never split the linear segment from the saddle point
    return np.flatnonzero(bad)


def grow_branch(sd: Saddle, *, stable=False, sign=1, arclength=5.0, start_tol=DEFAULT_START_TOL,
                max_gap=DEFAULT_MAX_GAP, max_angle=DEFAULT_MAX_ANGLE, max_gap_angle=DEFAULT_MAX_GAP_ANGLE,
                max_points=20000, max_time=None, integrate_backward=False,
                resume: ManifoldBranch | None = None, generations: int | None = None,
                unstable: ManifoldBranch | None = None) -> ManifoldBranch:
    """One branch of W^u (W^s with ``stable``) of the saddle ``sd`` grown to ``arclength``
    (module docstring: parametrisation, start distance, refinement, budgets).

    A stable branch of a saddle that :func:`mirrors` is the reflection of the unstable branch of
    its sign (:func:`mirror_branch`; the one place this is decided): that branch is grown here and
    reflected, or, given as ``unstable`` (grown by this function for ``sd`` with this sign and
    these settings, as :func:`manifolds` and the turnstile hold it), reflected without growing.

    ``generations``: grow no further than that many images of the fundamental domain (sigma
    below sigma0 + (generations + 1) L; status "generations" when that comes before the
    arclength, which may then be ``math.inf``), the extent
    :func:`explorer.analysis.fixedpoints.separatrices` draws.

    ``resume``: a branch of the same saddle, kind, sign and settings grown to a shorter
    arclength; the growth continues from where that one stopped (before its cut at its target),
    so the branch is the one a growth from the start gives, point for point, at the cost of
    the new part only (:func:`explorer.analysis.transport.turnstile` doubles the length this
    way).  A branch that cannot be continued (another saddle or setting, or stopped by a budget
    or the region's edge) is grown from the start."""
    if sign not in (1, -1):
        raise ParameterError(f"sign must be +1 or -1, got {sign!r}")
    if generations is not None:
        generations = validation.integer("generations", generations, 0)
    if generations is None or arclength != math.inf:     # inf: the extent set by generations alone
        arclength = validation.real("arclength", arclength, 0.0, lo_open=True)
    start_tol = validation.real("start_tol", start_tol, 0.0, lo_open=True)
    max_gap = validation.real("max_gap", max_gap, 0.0, lo_open=True)
    max_angle = validation.real("max_angle", max_angle, 0.0, lo_open=True)
    max_gap_angle = validation.real("max_gap_angle", max_gap_angle, 0.0, lo_open=True)
    max_points = validation.integer("max_points", max_points, 3)
    if max_time is not None:
        max_time = validation.real("max_time", max_time, 0.0)
    if stable and not integrate_backward and mirrors(sd):
        if unstable is not None:
            held = (unstable.kind, unstable.sign, unstable.target, unstable.start_tol, unstable.max_gap)
            if unstable.curve is None or unstable.curve.sd is not sd or held != ("unstable", sign, arclength,
                                                                                   start_tol, max_gap):
                raise ParameterError("unstable: the unstable branch of this saddle and sign, grown by grow_branch "
                                     "with the same arclength and settings")
            return mirror_branch(unstable)
        source = resume.mirror_of if resume is not None else None
        return mirror_branch(grow_branch(sd, sign=sign, arclength=arclength, start_tol=start_tol, max_gap=max_gap,
                                         max_angle=max_angle, max_gap_angle=max_gap_angle, max_points=max_points,
                                         max_time=max_time, resume=source, generations=generations))
    t0 = time.perf_counter()
    settings = (stable, sign, start_tol, max_gap, max_angle, max_gap_angle, max_points, integrate_backward,
                generations)
    status = None

    def cut(sig, pts, bad_sigma):
        keep = sig < bad_sigma
        return sig[keep], pts[keep]

    if (resume is not None and resume.grown is not None and resume.curve is not None and resume.curve.sd is sd
            and resume.grown[0] == settings and arclength >= resume.target):
        _, sig, pts, lo, edge, evals = resume.grown
        cv = resume.curve
        refined = True           # the state after a refinement: go on at the arclength check
    else:
        cv = _Curve(sd, stable, sign, start_tol, integrate_backward)
        sig = cv.sigma0 + cv.L * np.arange(INITIAL_POINTS + 1) / INITIAL_POINTS
        pts = cv.points(sig)
        evals = len(sig)
        edge = None              # smallest sigma known to fail
        if not np.all(np.isfinite(pts)):
            edge = float(sig[np.flatnonzero(~np.isfinite(pts[:, 0]))[0]])
            sig, pts = cut(sig, pts, edge)
        lo = 0                   # refinement starts here (earlier intervals are final)
        refined = False
    grown = None
    while True:
        # (i) refine
        while not refined:
            P = np.vstack([sd.point, pts])
            bad = _bad_intervals(P, max_gap, max_angle, max_gap_angle, lo + 1) - 1  # interval i of pts
            bad = bad[np.diff(sig)[bad] > MIN_DSIGMA]
            if bad.size == 0:
                break
            if len(sig) + bad.size > max_points:
                status = STATUS_MAX_POINTS
                bad = bad[:max(0, max_points - len(sig))]
            if bad.size == 0:
                break
            mid = 0.5 * (sig[bad] + sig[bad + 1])
            new = cv.points(mid)
            evals += len(mid)
            sig = np.insert(sig, bad + 1, mid)
            pts = np.insert(pts, bad + 1, new, axis=0)
            fail = ~np.isfinite(pts[:, 0])
            if fail.any():
                edge = float(sig[np.flatnonzero(fail)[0]])
                sig, pts = cut(sig, pts, edge)
            if status is not None:
                break
            if max_time is not None and time.perf_counter() - t0 > max_time:
                status = STATUS_MAX_TIME
                break
        refined = False
        s = _arc(np.vstack([sd.point, pts]))
        if s[-1] >= arclength:
            if status is None:   # a longer growth goes on from here (``resume``)
                grown = (settings, sig, pts, lo, edge, evals)
            k = int(np.searchsorted(s, arclength))   # first point at or beyond the target
            sig, pts = sig[:k], pts[:k]
            status = STATUS_ARCLENGTH
        # the last generation complete: its end sigma0 + (generations + 1) L reached (to rounding)
        if (status is None and generations is not None
                and sig[-1] >= cv.sigma0 + (generations + 1 - 0.5 / INITIAL_POINTS) * cv.L):
            status = STATUS_GENERATIONS
        if status is None and edge is not None:
            status = STATUS_EDGE
        if status is None and len(sig) >= max_points:
            status = STATUS_MAX_POINTS
        if status is None and max_time is not None and time.perf_counter() - t0 > max_time:
            status = STATUS_MAX_TIME
        if status is not None:
            break
        # (ii) extend: the last generation mapped once
        last = np.flatnonzero(sig > sig[-1] - cv.L)[:max_points - len(sig)]   # within the budget
        nsig = sig[last] + cv.L
        new = cv.map(pts[last], 1)
        evals += len(last)
        lo = len(sig) - 1
        fail = ~np.isfinite(new[:, 0])
        if fail.any():
            edge = float(nsig[np.flatnonzero(fail)[0]])
            nsig, new = nsig[:np.flatnonzero(fail)[0]], new[:np.flatnonzero(fail)[0]]
        sig = np.concatenate([sig, nsig])
        pts = np.vstack([pts, new])
    P = np.vstack([sd.point, pts])
    return ManifoldBranch("stable" if stable else "unstable", sign, P, np.concatenate([[-np.inf], sig]),
                          float(_arc(P)[-1]), float(arclength), status, cv.s0, float(start_tol), cv.curvature,
                          evals, time.perf_counter() - t0, cv, float(max_gap), grown)


def mirrors(sd: Saddle) -> bool:
    """True when the stable branches of ``sd`` are the reflections of its unstable ones, W^s_sign =
    G0 W^u_sign (module docstring): a section map that the reversor R reverses
    (:func:`explorer.analysis.periodic.is_reversible`) and a fixed point on its symmetry line p2 =
    0 (within MIRROR_TOL).  A point of a longer orbit is not: G0 maps it to another point of
    its orbit, or of another orbit."""
    G = sd.smap.reflection
    # |G0 x - x| = 2 |p2|: x within MIRROR_TOL of the line p2 = 0
    return G is not None and sd.period == 1 and float(np.max(np.abs(G(sd.point) - sd.point))) <= 2 * MIRROR_TOL


def mirror_branch(unstable: ManifoldBranch) -> ManifoldBranch:
    """The stable branch of the same sign as the unstable branch ``unstable`` of a saddle that
    :func:`mirrors`: every point reflected by G0 (p1, p2) -> (p1, -p2), the same parameters sigma,
    status and budgets, and no map computed.  What :func:`grow_branch` returns for ``stable=True``
    there (it grows the unstable branch and reflects it), so a caller holding the unstable branch
    saves its growth."""
    if unstable.kind != "unstable" or unstable.curve is None or not mirrors(unstable.curve.sd):
        raise ParameterError("mirror_branch needs an unstable branch grown by grow_branch of a fixed point "
                             "on the reversor's symmetry line (manifolds.mirrors)")
    G = unstable.curve.sd.smap.reflection
    return ManifoldBranch("stable", unstable.sign, G(unstable.points), unstable.sigma.copy(),
                          unstable.arclength, unstable.target, unstable.status, unstable.start_distance,
                          unstable.start_tol, unstable.curvature, 0, 0.0, _MirroredCurve(unstable.curve),
                          unstable.max_gap, None, unstable)


@system_first
def manifolds(system, orbit, *, arclength=5.0, kinds=("unstable", "stable"), signs=(1, -1), index=0, period=1,
              start_tol=DEFAULT_START_TOL, max_gap=DEFAULT_MAX_GAP, max_angle=DEFAULT_MAX_ANGLE,
              max_gap_angle=DEFAULT_MAX_GAP_ANGLE, max_points=20000, max_time=None,
              integrate_backward=False) -> list:
    """The branches of W^u and W^s of a hyperbolic ``orbit`` of the map ``system`` at its point
    ``index``, each grown to ``arclength`` (:func:`grow_branch`, whose options follow).

    ``orbit``: a :class:`~explorer.analysis.periodic.PeriodicOrbit`, a
    :class:`~explorer.analysis.fixedpoints.FixedPoint`, or a point (p1, p2) of the section: then the
    orbit of period ``period`` is found from it by Newton's method
    (:func:`~explorer.analysis.periodic.find_periodic_orbit`), e.g.
    ``manifolds(smap, (-0.011, 0.0), arclength=10)``.  Returns a list of :class:`ManifoldBranch`
    (``kind``, ``sign``, ``points``: an (M, 2) array from the orbit's point outwards), unstable
    before stable, sign +1 before -1; ParameterError when the orbit is not hyperbolic or not
    found."""
    if not isinstance(orbit, PeriodicOrbit) and not hasattr(orbit, "jacobian"):
        orbit = _orbit_from_point(system, orbit, period)
    sd = saddle(system, orbit, index=index)
    for k in kinds:
        if k not in ("unstable", "stable"):
            raise ParameterError(f"kinds must be 'unstable' and/or 'stable', got {k!r}")
    grown: dict = {}
    for k in ("unstable", "stable"):      # the unstable first: a mirrored stable branch reflects it (grow_branch)
        if k not in kinds:
            continue
        for s in signs:
            grown[k, s] = grow_branch(sd, stable=(k == "stable"), sign=s, arclength=arclength,
                                      start_tol=start_tol, max_gap=max_gap, max_angle=max_angle,
                                      max_gap_angle=max_gap_angle, max_points=max_points, max_time=max_time,
                                      integrate_backward=integrate_backward, unstable=grown.get(("unstable", s)))
    return [grown[k, s] for k in dict.fromkeys(kinds) for s in signs]


def _orbit_from_point(system, point, period):
    """The periodic orbit of period ``period`` of ``system`` found from the point (p1, p2) by Newton's method."""
    try:
        x = np.asarray(point, float)
    except (TypeError, ValueError):
        x = np.empty(0)
    if x.shape != (2,):
        raise ParameterError(f"orbit must be a PeriodicOrbit, a FixedPoint or a point (p1, p2), got {point!r}")
    period = validation.integer("period", period, 1, validation.MAX_PERIOD)
    return find_periodic_orbit(system, (float(x[0]), float(x[1])), period)


# ------------------------------------------------------------------ intersections
@dataclass(frozen=True)
class Homoclinic:
    """A point where an unstable and a stable branch meet: ``point``, the parameters
    ``sigma_u``, ``sigma_s`` on the branches, the angle between them (radians, in (0, pi/2]),
    the residual |x_u(sigma_u) - x_s(sigma_s)| and the signs of the two branches."""

    point: np.ndarray
    sigma_u: float
    sigma_s: float
    angle: float
    residual: float
    sign_u: int
    sign_s: int


def _segment_crossings(A, B):
    """Pairs (i, j, ta, tb) where segment A[i]A[i+1] crosses B[j]B[j+1] (ta, tb in [0, 1))."""
    out = []
    a0, a1 = A[:-1], A[1:]
    b0, b1 = B[:-1], B[1:]
    bl, bh = np.minimum(b0, b1), np.maximum(b0, b1)
    for i in range(len(a0)):
        lo, hi = np.minimum(a0[i], a1[i]), np.maximum(a0[i], a1[i])
        cand = np.flatnonzero(np.all((bh >= lo) & (bl <= hi), axis=1))
        if cand.size == 0:
            continue
        r = a1[i] - a0[i]
        s = b1[cand] - b0[cand]
        den = r[0] * s[:, 1] - r[1] * s[:, 0]
        q = b0[cand] - a0[i]
        with np.errstate(divide="ignore", invalid="ignore"):
            ta = (q[:, 0] * s[:, 1] - q[:, 1] * s[:, 0]) / den
            tb = (q[:, 0] * r[1] - q[:, 1] * r[0]) / den
        hit = (den != 0) & (ta >= 0) & (ta < 1) & (tb >= 0) & (tb < 1)
        out.extend((i, int(j), float(x), float(y)) for j, x, y in zip(cand[hit], ta[hit], tb[hit]))
    return out


def _refine(bu: ManifoldBranch, bs: ManifoldBranch, su, ss) -> list:
    """Newton on x_u(su) - x_s(ss) = 0 from each start (su[k], ss[k]), with tangents by central
    differences in sigma; a start stops at a residual below INTERSECTION_TOL or when two steps
    in a row fail to halve it (the map's accuracy reached), and gives the best point evaluated
    (None when none was finite).  The starts iterate in lockstep, each iteration's points of all
    of them computed in one batch per branch: every point is computed alone in the lanes (the
    same bits in any batch), so each start's iterates are those of a Newton run on its own."""
    hd = DIFF_STEP
    su = [float(x) for x in su]
    ss = [float(x) for x in ss]
    n = len(su)
    best: list = [None] * n
    stall = [0] * n
    alive = list(range(n))
    for _ in range(NEWTON_ITER):
        if not alive:
            break
        U = bu.at([x for k in alive for x in (su[k], su[k] - hd, su[k] + hd)]).reshape(len(alive), 3, 2)
        S = bs.at([x for k in alive for x in (ss[k], ss[k] - hd, ss[k] + hd)]).reshape(len(alive), 3, 2)
        still = []
        for k, Uk, Sk in zip(alive, U, S):
            if not (np.all(np.isfinite(Uk)) and np.all(np.isfinite(Sk))):
                continue
            tu, ts = (Uk[2] - Uk[1]) / (2 * hd), (Sk[2] - Sk[1]) / (2 * hd)
            F = Uk[0] - Sk[0]
            nf = float(np.linalg.norm(F))
            stall[k] = stall[k] + 1 if best[k] is not None and nf > 0.5 * best[k][0] else 0
            if best[k] is None or nf < best[k][0]:
                best[k] = (nf, su[k], ss[k], Uk[0].copy(), tu, ts)
            if nf < INTERSECTION_TOL or stall[k] >= 2:
                continue
            try:
                d = np.linalg.solve(np.column_stack([tu, -ts]), -F)
            except np.linalg.LinAlgError:
                continue
            su[k], ss[k] = su[k] + d[0], ss[k] + d[1]
            still.append(k)
        alive = still
    out: list = []
    for b in best:
        if b is None:
            out.append(None)
            continue
        nf, s_u, s_s, x, tu, ts = b
        c = abs(tu[0] * ts[1] - tu[1] * ts[0]) / (np.linalg.norm(tu) * np.linalg.norm(ts))
        out.append(Homoclinic(x, float(s_u), float(s_s), math.asin(min(1.0, c)), nf, bu.sign, bs.sign))
    return out


def homoclinic_points(unstable: ManifoldBranch, stable: ManifoldBranch, *, max_residual=1e-10) -> list:
    """The intersections of an unstable and a stable branch (of the same saddle: homoclinic; of
    two saddles: heteroclinic): crossings of the two polylines, each refined by Newton's method
    on x_u(sigma_u) = x_s(sigma_s) with the points computed afresh (no interpolation), kept when
    the residual is below ``max_residual``; sorted by sigma_u (the order along W^u)."""
    if unstable.kind != "unstable" or stable.kind != "stable":
        raise ParameterError("homoclinic_points needs an unstable branch then a stable branch")
    return _intersections(unstable, stable, max_residual, balance=False)


def _intersections(unstable: ManifoldBranch, stable: ManifoldBranch, max_residual, balance) -> list:
    """Crossings of the two polylines refined by Newton (:func:`_refine`), kept below
    ``max_residual``, one per point, sorted by sigma_u; with ``balance`` each crossing is first
    moved along its orbit to the point of the stored branches with balanced generations
    (:func:`heteroclinic_points`)."""
    cu, cs = unstable.curve, stable.curve
    balance = balance and cu is not None and cs is not None and cu.sd.maps == cs.sd.maps
    found: list[Homoclinic] = []
    # skip the first segment of each (the saddle point itself is a trivial intersection)
    starts = []
    for i, j, ta, tb in _segment_crossings(unstable.points[1:], stable.points[1:]):
        su = unstable.sigma[i + 1] + ta * (unstable.sigma[i + 2] - unstable.sigma[i + 1])
        ss = stable.sigma[j + 1] + tb * (stable.sigma[j + 2] - stable.sigma[j + 1])
        if balance:   # the generations n_u + k = n_s - k, staying on the stored branches
            k = round(((ss - cs.sigma0) / cs.L - (su - cu.sigma0) / cu.L) / 2.0)
            k = min(max(k, math.ceil((ss - stable.sigma[-1]) / cs.L)), math.floor((unstable.sigma[-1] - su) / cu.L))
            su, ss = su + k * cu.L, ss - k * cs.L
        starts.append((su, ss))
    refined = _refine(unstable, stable, [a for a, _ in starts], [b for _, b in starts]) if starts else []
    for hp in refined:
        if hp is None or hp.residual > max_residual or not math.isfinite(hp.angle):
            continue
        if min(np.linalg.norm(hp.point - unstable.points[0]), np.linalg.norm(hp.point - stable.points[0])) < \
                min(unstable.start_distance, stable.start_distance):
            continue    # Newton slid down both branches to the saddle point: the trivial intersection
        if any(np.linalg.norm(hp.point - f.point) < SAME_POINT for f in found):
            continue
        found.append(hp)
    return sorted(found, key=lambda hp: hp.sigma_u)


def heteroclinic_points(unstable: ManifoldBranch, stable: ManifoldBranch, *, max_residual=1e-10) -> list:
    """Heteroclinic points: the intersections of a branch of W^u of one saddle point
    (``unstable``) with a branch of W^s of another (``stable``): the two points of a hyperbolic
    periodic orbit (e.g. period 2: W^u(x0) and W^s(x1)), or two hyperbolic orbits.  A point z of
    both has F^-n(z) -> the first point and F^n(z) -> the second as n -> infinity.

    Found as :func:`homoclinic_points` finds its points (crossings of the polylines, Newton's
    method on x_u(sigma_u) = x_s(sigma_s) with points computed afresh, kept below
    ``max_residual``), with one difference: when both saddles use the same map F (``maps``),
    each crossing is first moved along its orbit, F^k shifting (sigma_u, sigma_s) by
    (k L_u, -k L_s), to the point of the two branches (as stored) whose two generations (F-images
    from each fundamental domain) are the most balanced; that point has the smallest rounding
    error of its orbit (a point n generations out carries the map's error times Lambda^n), and
    Newton reaches ~1e-11 there.
    One point per heteroclinic orbit, sorted by sigma_u.  Branches grown with ``start_tol`` 1e-8
    are accurate enough (their transverse start error shrinks by 1/Lambda per generation) and
    carry less rounding error than with the default 1e-12 (docs/manifolds.md)."""
    if unstable.kind != "unstable" or stable.kind != "stable":
        raise ParameterError("heteroclinic_points needs an unstable branch then a stable branch")
    if unstable.curve is None or stable.curve is None:
        raise ParameterError("heteroclinic_points needs branches grown by grow_branch (they carry their "
                             "parametrisation)")
    if np.linalg.norm(unstable.points[0] - stable.points[0]) < SAME_POINT:
        raise ParameterError("heteroclinic_points needs branches of two different saddle points "
                             "(for one saddle: homoclinic_points)")
    return _intersections(unstable, stable, max_residual, balance=True)


def homoclinic_orbit(smap: SectionMap, point, n=8) -> np.ndarray:
    """The orbit of a homoclinic point: P^-n(x), ..., x, ..., P^n(x) as a (2n + 1, 2) array
    (it tends to the saddle at both ends)."""
    n = validation.integer("n", n, 0)
    back = smap.iterate(point, n, backward=True)[::-1]
    fwd = smap.iterate(point, n)
    return np.vstack([back[:-1], fwd])
