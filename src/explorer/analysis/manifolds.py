"""Stable and unstable manifolds of hyperbolic periodic orbits of a map, grown along their
parametrisation sigma, and their intersections (docs/manifolds.md, "Branches of W^u and W^s")."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from explorer.analysis.maps import AreaPreservingMap, images
from explorer.analysis.periodic import PeriodicOrbit, find_periodic_orbit
from explorer.analysis.section_map import system_first
from explorer.model import ParameterError, validation

__all__ = ["DEFAULT_MAX_ANGLE", "DEFAULT_MAX_GAP", "DEFAULT_MAX_GAP_ANGLE", "DEFAULT_START_TOL", "Homoclinic",
           "ManifoldBranch", "Saddle", "grow_branch", "heteroclinic_points", "homoclinic_orbit", "homoclinic_points",
           "manifolds", "mirror_branch", "mirrors",
           "saddle"]

#: transverse distance of the start points from the manifold
DEFAULT_START_TOL = 1e-12
#: a fixed point this close to p2 = 0 has W^s = G0 W^u (:func:`mirrors`)
MIRROR_TOL = 1e-14
#: refinement bounds: gap, angle (radians) and their product (docs/manifolds.md, "Growth")
DEFAULT_MAX_GAP = 0.02
DEFAULT_MAX_ANGLE = 0.2
DEFAULT_MAX_GAP_ANGLE = 2e-4
INITIAL_POINTS = 16
TRIAL_DISTANCE = 1e-4
MIN_START, MAX_START = 1e-9, 1e-3
MIN_DSIGMA = 1e-11
#: Newton for intersections: difference step in sigma, tolerance, iterations
DIFF_STEP = 1e-6
INTERSECTION_TOL = 1e-12
NEWTON_ITER = 30
SAME_POINT = 1e-9

STATUS_ARCLENGTH = "arclength"
STATUS_GENERATIONS = "generations"
STATUS_EDGE = "edge"
STATUS_MAX_POINTS = "max_points"
STATUS_MAX_TIME = "max_time"


@dataclass(frozen=True)
class Saddle:
    """A point x* of a hyperbolic orbit, F = P^m and its eigen-decomposition (docs/manifolds.md)."""

    point: np.ndarray
    period: int
    maps: int
    multiplier: float
    eigenvalues: np.ndarray
    e_unstable: np.ndarray
    e_stable: np.ndarray
    smap: AreaPreservingMap
    orbit_points: np.ndarray


def _orient(v):
    v = np.asarray(v, float) / np.linalg.norm(v)
    return -v if (v[0] < 0 or (v[0] == 0 and v[1] < 0)) else v


@system_first(systems="map")
def saddle(system, orbit, *, index=0) -> Saddle:
    """The :class:`Saddle` at point ``index`` of a hyperbolic ``orbit`` of the map ``system``."""
    if not isinstance(orbit, PeriodicOrbit):
        raise ParameterError(f"orbit must be a PeriodicOrbit or a FixedPoint, got {type(orbit).__name__}")
    pts, K, jacs = orbit.points, orbit.period, orbit.map_jacobians
    index = validation.integer("index", index, 0, K - 1)
    M = np.eye(2)
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


def _images(smap, X, n, backward, integrate_backward=False):
    """P^n (P^-n with ``backward``) of the points X (m, 2), NaN where a return fails."""
    X = np.asarray(X, float).reshape(-1, 2)
    if n == 0 or X.size == 0:
        return X.copy()
    if backward and integrate_backward:
        return smap.images(X, n, backward=True)[:, -1]
    return images(smap, X, n, backward=backward)[:, -1]


class _Curve:
    """sigma -> x(sigma) of one branch (docs/manifolds.md)."""

    def __init__(self, sd: Saddle, stable: bool, sign: int, start_tol: float, integrate_backward: bool):
        self.sd, self.stable, self.sign = sd, stable, sign
        self.backward_integrated = integrate_backward
        self.e = sign * (sd.e_stable if stable else sd.e_unstable)
        self.L = math.log(sd.multiplier)
        # the graph v = a u^2 / 2 (docs/manifolds.md, "Start distance")
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
        """x(sigma) for an array of sigma, NaN where a map fails."""
        sigma = np.atleast_1d(np.asarray(sigma, float))
        n = self.generation(sigma)
        out = np.empty((sigma.size, 2))
        for g in np.unique(n):
            sel = n == g
            x0 = self.sd.point + np.exp(sigma[sel] - g * self.L)[:, None] * self.e
            out[sel] = self.map(x0, int(g))
        return out



class _MirroredCurve:
    """sigma -> G0 x_u(sigma): a stable branch that :func:`mirrors` its unstable one."""

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
    """One branch of W^u or W^s (``kind``) as a polyline from the saddle outwards: ``points`` at
    parameters ``sigma``, within ``start_tol`` of the manifold; ``status`` says why it stopped
    ("arclength", "generations", "edge", "max_points", "max_time")."""

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
    #: the growth's state before the cut at ``target``: what ``resume=`` continues
    grown: tuple | None = field(repr=False, compare=False, default=None)
    mirror_of: ManifoldBranch | None = field(repr=False, compare=False, default=None)

    @property
    def tears(self) -> np.ndarray:
        """sigma at each jump of the branch, where the map is discontinuous (docs/manifolds.md)."""
        d = np.linalg.norm(np.diff(self.points[1:], axis=0), axis=1)
        ds = np.diff(self.sigma[1:])
        return self.sigma[1:-1][(d > self.max_gap) & (ds <= 1.5 * MIN_DSIGMA)]

    @property
    def first_tear(self) -> float:
        """The smallest sigma of :attr:`tears` (inf when the branch is unbroken)."""
        t = self.tears
        return float(t[0]) if t.size else math.inf

    def at(self, sigma) -> np.ndarray:
        """Points of the branch at parameters ``sigma``, computed afresh."""
        return self.curve.points(sigma)

    def distance(self, x, *, rounds=4, samples=24) -> float:
        """Distance from x to the branch, from points computed afresh near the nearest stored one."""
        x = np.asarray(x, float)
        i = int(np.argmin(np.linalg.norm(self.points[1:] - x, axis=1))) + 1
        lo = self.sigma[max(i - 1, 1)]
        hi = self.sigma[min(i + 1, len(self.sigma) - 1)]
        for _ in range(rounds):
            s = np.linspace(lo, hi, samples)
            pts = self.at(s)
            k = int(np.nanargmin(np.linalg.norm(pts - x, axis=1)))
            lo, hi = s[max(k - 1, 0)], s[min(k + 1, samples - 1)]
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
    bad[:max(lo, 1)] = False
    return np.flatnonzero(bad)


def grow_branch(sd: Saddle, *, stable=False, sign=1, arclength=5.0, start_tol=DEFAULT_START_TOL,
                max_gap=DEFAULT_MAX_GAP, max_angle=DEFAULT_MAX_ANGLE, max_gap_angle=DEFAULT_MAX_GAP_ANGLE,
                max_points=20000, max_time=None, integrate_backward=False,
                resume: ManifoldBranch | None = None, generations: int | None = None,
                unstable: ManifoldBranch | None = None) -> ManifoldBranch:
    """One branch of W^u (W^s with ``stable``) of ``sd`` grown to ``arclength`` (docs/manifolds.md)."""
    if sign not in (1, -1):
        raise ParameterError(f"sign must be +1 or -1, got {sign!r}")
    if generations is not None:
        generations = validation.integer("generations", generations, 0)
    if generations is None or arclength != math.inf:
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
        _, sig, pts, lo, edge, evals = resume.grown      # its last generation as mapped, refined anew below
        cv = resume.curve
    else:
        cv = _Curve(sd, stable, sign, start_tol, integrate_backward)
        sig = cv.sigma0 + cv.L * np.arange(INITIAL_POINTS + 1) / INITIAL_POINTS
        pts = cv.points(sig)
        evals = len(sig)
        edge = None              # smallest sigma known to fail
        if not np.all(np.isfinite(pts)):
            edge = float(sig[np.flatnonzero(~np.isfinite(pts[:, 0]))[0]])
            sig, pts = cut(sig, pts, edge)
        lo = 0                   # earlier intervals are final
    grown = None
    while True:
        # the generation before its refinement: a longer branch resumes from it (the same passes as from the start)
        mapped = (sig, pts, lo, edge, evals)
        while True:
            P = np.vstack([sd.point, pts])
            bad = _bad_intervals(P, max_gap, max_angle, max_gap_angle, lo + 1) - 1
            bad = bad[np.diff(sig)[bad] > MIN_DSIGMA]
            bad = bad[_arc(P)[bad + 1] < arclength]     # points past the cut are dropped: not refined
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
        s = _arc(np.vstack([sd.point, pts]))
        if s[-1] >= arclength:
            if status is None:
                grown = (settings, *mapped)
            k = int(np.searchsorted(s, arclength))
            sig, pts = sig[:k], pts[:k]
            status = STATUS_ARCLENGTH
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
        last = np.flatnonzero(sig > sig[-1] - cv.L)[:max_points - len(sig)]
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
    """W^s = G0 W^u branch by branch: a map with a reflection G0 and a fixed point on its line."""
    G = sd.smap.reflection
    # |G0 x - x| = 2 |p2|: x within MIRROR_TOL of the line p2 = 0
    return G is not None and sd.period == 1 and float(np.max(np.abs(G(sd.point) - sd.point))) <= 2 * MIRROR_TOL


def mirror_branch(unstable: ManifoldBranch) -> ManifoldBranch:
    """The stable branch reflecting ``unstable`` of a saddle that :func:`mirrors`: no map computed."""
    if unstable.kind != "unstable" or unstable.curve is None or not mirrors(unstable.curve.sd):
        raise ParameterError("mirror_branch needs an unstable branch grown by grow_branch of a fixed point "
                             "on the reversor's symmetry line (manifolds.mirrors)")
    G = unstable.curve.sd.smap.reflection
    return ManifoldBranch("stable", unstable.sign, G(unstable.points), unstable.sigma.copy(),
                          unstable.arclength, unstable.target, unstable.status, unstable.start_distance,
                          unstable.start_tol, unstable.curvature, 0, 0.0, _MirroredCurve(unstable.curve),
                          unstable.max_gap, None, unstable)


@system_first(systems="map")
def manifolds(system, orbit, *, arclength=5.0, kinds=("unstable", "stable"), signs=(1, -1), index=0, period=1,
              start_tol=DEFAULT_START_TOL, max_gap=DEFAULT_MAX_GAP, max_angle=DEFAULT_MAX_ANGLE,
              max_gap_angle=DEFAULT_MAX_GAP_ANGLE, max_points=20000, max_time=None,
              integrate_backward=False) -> list:
    """The branches of W^u and W^s of a hyperbolic ``orbit`` (or the orbit of ``period`` found from a
    point) at its point ``index``, each grown to ``arclength`` by :func:`grow_branch`."""
    if not isinstance(orbit, PeriodicOrbit):
        orbit = _orbit_from_point(system, orbit, period)
    sd = saddle(system, orbit, index=index)
    for k in kinds:
        if k not in ("unstable", "stable"):
            raise ParameterError(f"kinds must be 'unstable' and/or 'stable', got {k!r}")
    grown: dict = {}
    for k in ("unstable", "stable"):      # a mirrored stable branch reflects the unstable one
        if k not in kinds:
            continue
        for s in signs:
            grown[k, s] = grow_branch(sd, stable=(k == "stable"), sign=s, arclength=arclength,
                                      start_tol=start_tol, max_gap=max_gap, max_angle=max_angle,
                                      max_gap_angle=max_gap_angle, max_points=max_points, max_time=max_time,
                                      integrate_backward=integrate_backward, unstable=grown.get(("unstable", s)))
    return [grown[k, s] for k in dict.fromkeys(kinds) for s in signs]


def _orbit_from_point(system, point, period):
    """The orbit of period ``period`` Newton finds from the point (p1, p2)."""
    try:
        x = np.asarray(point, float)
    except (TypeError, ValueError):
        x = np.empty(0)
    if x.shape != (2,):
        raise ParameterError(f"orbit must be a PeriodicOrbit, a FixedPoint or a point (p1, p2), got {point!r}")
    period = validation.integer("period", period, 1, validation.MAX_PERIOD)
    return find_periodic_orbit(system, (float(x[0]), float(x[1])), period)


@dataclass(frozen=True)
class Homoclinic:
    """Where an unstable and a stable branch meet: the point, its sigma on each, the angle, the residual."""

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
    """Newton on x_u(su) = x_s(ss) from each start, in lockstep (one batch per branch and step;
    each point is computed alone in the lanes), the best point of each (None if none finite)."""
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
    """The intersections of an unstable and a stable branch below ``max_residual``, sorted by
    sigma_u (docs/manifolds.md, "Homoclinic points and the splitting angle")."""
    if unstable.kind != "unstable" or stable.kind != "stable":
        raise ParameterError("homoclinic_points needs an unstable branch then a stable branch")
    return _intersections(unstable, stable, max_residual, balance=False)


def _intersections(unstable: ManifoldBranch, stable: ManifoldBranch, max_residual, balance) -> list:
    """Crossings of the polylines refined by :func:`_refine`; ``balance``: see :func:`heteroclinic_points`."""
    cu, cs = unstable.curve, stable.curve
    balance = balance and cu is not None and cs is not None and cu.sd.maps == cs.sd.maps
    found: list[Homoclinic] = []
    # not the first segments: the saddle point is a trivial intersection
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
            continue    # the saddle point itself
        if any(np.linalg.norm(hp.point - f.point) < SAME_POINT for f in found):
            continue
        found.append(hp)
    return sorted(found, key=lambda hp: hp.sigma_u)


def heteroclinic_points(unstable: ManifoldBranch, stable: ManifoldBranch, *, max_residual=1e-10) -> list:
    """The intersections of W^u of one saddle point with W^s of another, each moved along its
    orbit to balanced generations before Newton (docs/manifolds.md, "Heteroclinic points")."""
    if unstable.kind != "unstable" or stable.kind != "stable":
        raise ParameterError("heteroclinic_points needs an unstable branch then a stable branch")
    if unstable.curve is None or stable.curve is None:
        raise ParameterError("heteroclinic_points needs branches grown by grow_branch (they carry their "
                             "parametrisation)")
    if np.linalg.norm(unstable.points[0] - stable.points[0]) < SAME_POINT:
        raise ParameterError("heteroclinic_points needs branches of two different saddle points "
                             "(for one saddle: homoclinic_points)")
    return _intersections(unstable, stable, max_residual, balance=True)


def homoclinic_orbit(smap: AreaPreservingMap, point, n=8) -> np.ndarray:
    """P^-n(x), ..., x, ..., P^n(x) of a homoclinic point x: a (2n + 1, 2) array."""
    n = validation.integer("n", n, 0)
    back = smap.iterate(point, n, backward=True)[::-1]
    fwd = smap.iterate(point, n)
    return np.vstack([back[:-1], fwd])
