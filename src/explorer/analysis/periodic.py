"""Periodic orbits of any period K of a map of the protocol: Newton's method (single shooting
for K <= 4, multiple shooting above), the search seeded on the symmetry lines, isolation,
continuation and bifurcations (docs/commands/periodic.md; the reversor: docs/model.md, "Symmetries")."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, fields

import numpy as np

from explorer import model
from explorer.analysis.continuation import continuation_values, golden_section_max, secant_follower
from explorer.analysis.maps import AreaPreservingMap, difference
from explorer.analysis.maps import reduce as reduce_points
from explorer.analysis.section_map import SectionMap, system_first
from explorer.model import ParameterError, validation

__all__ = ["DEGENERATE_RESIDUE", "ISOLATION_TOL", "KIND_TOL", "MULTIPLE_SHOOTING_FROM", "PeriodicBranch",
           "PeriodicOrbit", "continue_periodic", "find_periodic_orbit", "mirror_orbit", "periodic_guesses",
           "search_periodic_orbits", "symmetry_line_points"]

#: Newton (relative to max(1, |x|)): a step below NEWTON_TOL converges; a start below
#: SOLVED_RESIDUAL takes no step; a residual below CONVERGED_RESIDUAL converges
NEWTON_TOL = 1e-12
SOLVED_RESIDUAL = 1e-15
CONVERGED_RESIDUAL = 1e-14
#: a damped step is taken when it lowers the residual or leaves it below this
LINE_SEARCH_RESIDUAL = 1e-11
NEWTON_MAX_ITER = 30
#: residual max_i |P(x_i) - x_{i+1}| accepted at the end
ACCEPT_RESIDUAL = 1e-9
MULTIPLE_SHOOTING_FROM = 5
KIND_TOL = 1e-6
MINIMAL_PERIOD_TOL = 1e-7
SAME_ORBIT_TOL = 1e-6
#: isolation and the map's relative noise floor (docs/commands/periodic.md, "Degenerate orbits")
ISOLATION_TOL = SAME_ORBIT_TOL
MAP_NOISE = 1e-15
DEGENERATE_RESIDUE = KIND_TOL / 4
MAX_HALVINGS = 6


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic orbit of minimal period K: ``points`` (K, 2) with points[i + 1] = P(points[i]),
    the monodromy ``jacobian`` at points[0], its ``eigenvalues``, ``trace``, ``det``, the K
    ``map_jacobians`` and ``return_times``, Newton's ``residual`` and ``iterations``, ``symmetric``
    under a reversor, and the isolation (``uncertainty``, ``degenerate``; docs/commands/periodic.md)."""

    points: np.ndarray
    period: int
    jacobian: np.ndarray
    eigenvalues: np.ndarray
    trace: float
    det: float
    return_times: np.ndarray
    residual: float
    iterations: int
    symmetric: bool
    map_jacobians: np.ndarray
    params: model.Params = None
    h: float = float("nan")
    phi0: float = math.pi
    uncertainty: float = 0.0
    degenerate: bool = False
    #: the map, when ``params``, ``h``, ``phi0`` do not name it
    system: object = field(default=None, repr=False, compare=False)

    def __repr__(self):
        """The fields; the map by its own repr where ``params``, ``h`` and ``phi0`` do not name it."""
        skip = () if self.system is None else ("params", "h", "phi0")
        body = [f"{f.name}={getattr(self, f.name)!r}" for f in fields(self) if f.repr and f.name not in skip]
        if self.system is not None:
            body.append(f"system={self.system!r}")
        return f"{type(self).__name__}({', '.join(body)})"

    @property
    def residue(self) -> float:
        """Greene's residue R = (2 - trace)/4: 0 < R < 1 elliptic, R < 0 or R > 1 hyperbolic."""
        return (2.0 - self.trace) / 4.0

    @property
    def stable(self) -> bool:
        """Linear stability, ``|trace| < 2`` (as :class:`~explorer.analysis.fixedpoints.FixedPoint`)."""
        return abs(self.trace) < 2.0

    @property
    def kind(self) -> str:
        """"parabolic" within KIND_TOL of ``|trace| = 2``, else "elliptic" or "hyperbolic"."""
        if abs(abs(self.trace) - 2.0) <= KIND_TOL:
            return "parabolic"
        return "elliptic" if abs(self.trace) < 2.0 else "hyperbolic"

    @property
    def total_time(self) -> float:
        """The flow's time over one period of the map: the sum of the return times."""
        return float(np.sum(self.return_times))

    def distance_to(self, x) -> float:
        """Smallest distance from the point x to a point of the orbit."""
        return float(np.min(np.linalg.norm(self.points - np.asarray(x, float), axis=1)))

    def same_orbit(self, other, tol=SAME_ORBIT_TOL) -> bool:
        """True if a point of ``other`` (an orbit or an (n, 2) array) lies within tol of this orbit."""
        pts = other.points if isinstance(other, PeriodicOrbit) else np.atleast_2d(other)
        d = np.linalg.norm(self.points[:, None, :] - pts[None, :, :], axis=2)
        return bool(np.min(d) <= tol)

    def as_dict(self):
        ev = [complex(e) for e in self.eigenvalues]
        return {"period": int(self.period), "points": [[float(a), float(b)] for a, b in self.points],
                "trace": float(self.trace), "residue": float(self.residue), "det": float(self.det),
                "eigenvalues": [[e.real, e.imag] if e.imag else e.real for e in ev],
                "kind": self.kind, "stable": bool(self.stable), "symmetric": bool(self.symmetric),
                "return_times": [float(t) for t in self.return_times], "residual": float(self.residual),
                "iterations": int(self.iterations), "degenerate": bool(self.degenerate),
                "uncertainty": float(self.uncertainty)}


class _Shooting:
    """Evaluations of the K maps along a set of points."""

    def __init__(self, smap: AreaPreservingMap, K: int):
        self.smap, self.K = smap, K

    def along(self, x0, multiple, X=None):
        """Points, images, Jacobians and times of the K maps from X (multiple) or along x0's orbit."""
        K = self.K
        pts = np.empty((K, 2))
        imgs = np.empty((K, 2))
        jacs = np.empty((K, 2, 2))
        times = np.empty(K)
        x = np.asarray(x0, float)
        for i in range(K):
            xi = X[i] if multiple else x
            if not self.smap.in_domain(xi):
                raise ParameterError(f"point ({xi[0]:.6g}, {xi[1]:.6g}) left the allowed region")
            r = self.smap(xi)
            pts[i], imgs[i], jacs[i], times[i] = xi, r.point, r.jacobian, r.time
            x = r.point
        return pts, imgs, jacs, times


def _monodromy(jacs):
    M = np.eye(2)
    for J in jacs:
        M = J @ M
    return M


def _residual(smap, pts, imgs, multiple):
    """max |P(x_i) - x_{i+1}| (multiple shooting) or |P^K(x_0) - x_0|, on the map's cylinder."""
    if multiple:
        return float(np.max(np.abs(difference(smap, imgs, np.roll(pts, -1, axis=0)))))
    return float(np.max(np.abs(difference(smap, imgs[-1], pts[0]))))


def _newton(smap, K, X0, max_iter=NEWTON_MAX_ITER, multiple=None):
    """Damped Newton for a K-periodic orbit from X0: (points, images, jacobians, times, iterations)."""
    multiple = K >= MULTIPLE_SHOOTING_FROM if multiple is None else multiple
    sh = _Shooting(smap, K)
    X0 = np.asarray(X0, float)
    if multiple:
        if X0.shape == (2,):
            X0 = sh.along(X0, False)[0]
        X = X0.reshape(K, 2).copy()
        ev = sh.along(None, True, X)
    else:
        X = (X0.reshape(-1, 2)[0]).copy()
        ev = sh.along(X, False)
    res = _residual(smap, ev[0], ev[1], multiple)
    step = np.inf
    it = 0
    for it in range(1, max_iter + 1):
        if res <= SOLVED_RESIDUAL * max(1.0, float(np.max(np.abs(X)))):
            break
        pts, imgs, jacs, _ = ev
        if multiple:
            F = difference(smap, imgs, np.roll(pts, -1, axis=0)).ravel()
            A = np.zeros((2 * K, 2 * K))
            for i in range(K):
                j = (i + 1) % K
                A[2 * i:2 * i + 2, 2 * i:2 * i + 2] += jacs[i]
                A[2 * i:2 * i + 2, 2 * j:2 * j + 2] -= np.eye(2)
        else:
            F = difference(smap, imgs[-1], pts[0])
            A = _monodromy(jacs) - np.eye(2)
        if not (np.all(np.isfinite(A)) and np.all(np.isfinite(F))):
            raise ParameterError(smap.not_finite(X.reshape(-1, 2)[0]))
        try:
            dx = np.linalg.solve(A, -F)
        except np.linalg.LinAlgError:   # trace exactly 2: the least-squares step
            dx = np.linalg.lstsq(A, -F, rcond=None)[0]
        if not np.all(np.isfinite(dx)):
            raise ParameterError("Newton's step is not finite")
        alpha = 1.0
        for _ in range(30):   # stay in the domain, do not let the residual grow
            Xn = (X.ravel() + alpha * dx).reshape(X.shape)
            try:
                evn = sh.along(Xn[0] if multiple else Xn, multiple, Xn.reshape(-1, 2))
                resn = _residual(smap, evn[0], evn[1], multiple)
            except ParameterError:
                alpha *= 0.5
                continue
            if resn < res or resn < LINE_SEARCH_RESIDUAL:
                break
            alpha *= 0.5
        else:
            if res < ACCEPT_RESIDUAL:
                break    # at the residual's noise floor
            raise ParameterError(f"Newton's method stalled (residual {res:.3g})")
        X, ev, res = Xn, evn, resn
        step = alpha * float(np.max(np.abs(dx)))
        if step < NEWTON_TOL * max(1.0, float(np.max(np.abs(X)))) or res < CONVERGED_RESIDUAL:
            break
    if not res < ACCEPT_RESIDUAL:
        raise ParameterError(f"Newton's method did not converge (residual {res:.3g}, last step {step:.3g})")
    pts, imgs, jacs, times = ev
    return pts, imgs, jacs, times, it


def _minimal_period(pts, system, tol=MINIMAL_PERIOD_TOL) -> int:
    K = len(pts)
    scale = max(1.0, float(np.max(np.abs(pts))))
    for d in range(1, K):
        if K % d == 0 and np.max(np.abs(difference(system, np.roll(pts, -d, axis=0), pts))) <= tol * scale:
            return d
    return K


def _isolation(M, residual):
    """(uncertainty, degenerate) of an orbit (docs/commands/periodic.md, "Degenerate orbits")."""
    smin = float(np.linalg.svd(M - np.eye(2), compute_uv=False)[-1])
    noise = max(float(residual), MAP_NOISE * max(1.0, float(np.linalg.norm(M, 2))))
    uncertainty = noise / smin if smin > 0 else math.inf
    residue = (2.0 - float(np.trace(M))) / 4.0
    return uncertainty, bool(uncertainty > ISOLATION_TOL or abs(residue) < DEGENERATE_RESIDUE)


def _orbit(smap, pts, jacs, times, resid, iters, symmetric=None) -> PeriodicOrbit:
    """The PeriodicOrbit through ``pts`` with map Jacobians ``jacs``."""
    M = _monodromy(jacs)
    if not np.all(np.isfinite(M)):
        raise ParameterError(smap.not_finite(pts[0]))
    uncertainty, degenerate = _isolation(M, resid)
    if symmetric is None:
        symmetric = any(_maps_onto(smap, R(pts), pts, 1e3 * MINIMAL_PERIOD_TOL) for R in smap.reversors)
    return PeriodicOrbit(np.array(pts, float), len(pts), M, np.linalg.eigvals(M), float(np.trace(M)),
                         float(np.linalg.det(M)), np.array(times, float), float(resid), int(iters), bool(symmetric),
                         np.array(jacs, float), uncertainty=uncertainty, degenerate=degenerate,
                         **smap.orbit_fields())


def _maps_onto(system, images, pts, tol) -> bool:
    """Every point of ``images`` is within ``tol`` of a point of ``pts``."""
    d = np.linalg.norm(difference(system, np.asarray(images)[:, None, :], np.asarray(pts)[None, :, :]), axis=2)
    return bool(np.all(np.min(d, axis=1) <= tol))


def _make_orbit(smap, pts, imgs, jacs, times, iters, reduce=True) -> PeriodicOrbit:
    K = len(pts)
    d = _minimal_period(pts, smap) if reduce else K
    pts, imgs, jacs, times = pts[:d], imgs[:d], jacs[:d], times[:d]
    resid = float(np.max(np.abs(difference(smap, imgs, np.roll(pts, -1, axis=0)))))
    return _orbit(smap, reduce_points(smap, pts), jacs, times, resid, iters)


def mirror_orbit(orb: PeriodicOrbit) -> PeriodicOrbit:
    """R(orbit) for the linear reversor R of the orbit's map: z_j = R x_{-j}, DP(z_j) = R DP(x_{-j-1})^-1 R,
    computed exactly (no search); ParameterError when the map has none."""
    smap = _map_of(orb)
    if smap.reflection is None:
        smap.require_reversor("the mirror image")
        raise ParameterError(f"the mirror image needs a reversor of the map linear in its coordinates (its "
                             f"reflection); {smap!r} has none")
    return _mirror(smap, orb)


def _mirror(smap, orb: PeriodicOrbit) -> PeriodicOrbit:
    """:func:`mirror_orbit` by ``smap``'s :attr:`reflection`."""
    R = smap.reflection
    G = np.asarray(R(np.eye(2)), float).T + 0.0      # + 0.0: no negative zeros
    K = orb.period
    idx = (-np.arange(K)) % K                      # x_{-j}
    prev = (-np.arange(K) - 1) % K                 # x_{-j-1}
    jacs = np.array([G @ np.linalg.inv(orb.map_jacobians[i]) @ G for i in prev])
    return _orbit(smap, R(orb.points[idx]), jacs, orb.return_times[prev], orb.residual, orb.iterations,
                  orb.symmetric)


def _map_of(orb: PeriodicOrbit):
    """The map an orbit names: its ``system``, or the section map of ``params``, ``h``, ``phi0``."""
    return orb.system if orb.system is not None else SectionMap(orb.params, orb.h, phi0=orb.phi0)


def _check_period(period) -> int:
    if isinstance(period, bool) or not isinstance(period, (int, np.integer)) or period < 1:
        raise ParameterError(f"period must be an integer K >= 1, got {period!r}")
    return int(period)


@system_first(systems="map")
def find_periodic_orbit(system, guess, period, *, max_iter=NEWTON_MAX_ITER, reduce=True) -> PeriodicOrbit:
    """The periodic orbit of period ``period`` Newton's method finds from ``guess`` (a point or
    K points), reduced to its minimal period unless ``reduce`` is False; ParameterError when
    the guess is outside the map's domain or Newton fails."""
    K = _check_period(period)
    smap = system
    g = np.asarray(guess, dtype=float)
    if g.shape not in ((2,), (K, 2)) or not np.all(np.isfinite(g)):
        raise ParameterError(f"guess must be a finite point (p1, p2) or {K} points, got shape {g.shape}")
    for x in g.reshape(-1, 2):
        if not smap.in_domain(x):
            raise ParameterError(f"guess (p1, p2) = ({x[0]:g}, {x[1]:g}) lies outside the allowed region; "
                                 f"{smap.describe_domain()}")
    max_iter = validation.integer("max_iter", max_iter, 1)
    try:
        pts, imgs, jacs, times, it = _newton(smap, K, g, max_iter)
    except ParameterError as exc:
        raise ParameterError(f"no periodic orbit of period {K} from guess ({g.reshape(-1, 2)[0][0]:.6g}, "
                             f"{g.reshape(-1, 2)[0][1]:.6g}): {exc}; try another guess") from None
    return _make_orbit(smap, pts, imgs, jacs, times, it, reduce)


@system_first(systems="map")
def symmetry_line_points(system, period, *, n=200, threads=None):
    """Seeds (m, 2) of symmetric orbits of period ``period`` on the map's symmetry lines, ``n`` per line:
    the map's ``symmetric_seeds`` (docs/commands/periodic.md)."""
    K = _check_period(period)
    return np.asarray(system.symmetric_seeds(K, validation.integer("n", n, 1), threads=threads), float)


def _points(x) -> np.ndarray:
    return x.points if isinstance(x, PeriodicOrbit) else np.atleast_2d(x)


def _near(smap, orb, x, tol) -> bool:
    """A point of ``orb`` lies within ``tol`` (strictly) of the point x, on the map's cylinder."""
    return bool(np.min(np.linalg.norm(difference(smap, orb.points, x), axis=1)) < tol)


def _same_orbit(smap, a, b, tol) -> bool:
    """A point of ``a`` lies within ``tol`` of a point of ``b`` (orbits or (n, 2) arrays), on the map's cylinder."""
    d = np.linalg.norm(difference(smap, _points(a)[:, None, :], _points(b)[None, :, :]), axis=2)
    return bool(np.min(d) <= tol)


def _canonical(smap, orb: PeriodicOrbit) -> PeriodicOrbit:
    """The same orbit from its point nearest p2 = 0 (then smallest p1)."""
    k = int(np.lexsort((orb.points[:, 0], np.round(np.abs(orb.points[:, 1]), 9)))[0])
    if k == 0:
        return orb
    return _orbit(smap, np.roll(orb.points, -k, axis=0), np.roll(orb.map_jacobians, -k, axis=0),
                  np.roll(orb.return_times, -k), orb.residual, orb.iterations, orb.symmetric)


def _partners(smap, orbits, same_tol, *, max_iter, threads) -> list:
    """The partners under the map's ``partner_points`` (an orbit run backwards) of the isolated ``orbits``
    not among them yet, each polished by Newton."""
    isolated = [o for o in orbits if not o.degenerate]
    if not isolated:
        return []
    images = smap.partner_points(np.concatenate([o.points for o in isolated]), threads=threads)
    if images is None:
        return []
    added: list[PeriodicOrbit] = []
    start = 0
    for o in isolated:
        pts = images[start:start + o.period][::-1]
        start += o.period
        if not np.all(np.isfinite(pts)) or any(_same_orbit(smap, f, pts, same_tol) for f in orbits + added):
            continue
        try:
            partner = find_periodic_orbit(smap, pts if o.period >= MULTIPLE_SHOOTING_FROM else pts[0], o.period,
                                          max_iter=max_iter)
        except ParameterError:
            continue
        if partner.period == o.period and not partner.degenerate and _same_orbit(smap, partner, pts, 1e3 * same_tol):
            added.append(partner)
    return added


@system_first(systems="map", settings=("phi0", "tol"))
def periodic_guesses(system, period, *, grid=12, line=None, tmax=None, threads=None) -> np.ndarray:
    """The Newton starts of :func:`search_periodic_orbits` in order: the map's ``symmetric_seeds``, ``line``
    per symmetry line, then its ``grid_seeds``, the local minima of ``|P^K(x) - x|`` on a ``grid`` x ``grid``
    grid, best first; ``tmax``: the time budget of one return (default the map's ``search_tmax``)."""
    K = _check_period(period)
    grid = validation.integer("grid", grid, 2, 1000)
    line = 8 * grid if line is None else validation.integer("line", line, 2)
    smap = system.with_tmax(system.search_tmax if tmax is None else tmax)
    return np.concatenate([np.asarray(smap.symmetric_seeds(K, line, threads=threads), float).reshape(-1, 2),
                           np.asarray(smap.grid_seeds(K, grid, threads=threads), float).reshape(-1, 2)])


@system_first(systems="map", settings=("phi0", "tol"))
def search_periodic_orbits(system, period, *, grid=12, line=None, max_guesses=60, max_iter=NEWTON_MAX_ITER,
                           tmax=None, time_limit=None, same_tol=SAME_ORBIT_TOL, threads=None,
                           guesses=None) -> list:
    """The periodic orbits of minimal period ``period`` found from :func:`periodic_guesses` (or
    ``guesses``), each once, completed by symmetry (the map's linear reversor, exactly; its
    ``partner_points``, by Newton), isolated before degenerate (docs/commands/periodic.md)."""
    K = _check_period(period)
    max_guesses = validation.integer("max_guesses", max_guesses, 1)
    smap = system.with_tmax(system.search_tmax if tmax is None else tmax)
    if guesses is None:
        guesses = periodic_guesses(system, K, grid=grid, line=line, tmax=tmax, threads=threads)
    else:
        guesses = np.asarray(guesses, float).reshape(-1, 2)
    R = smap.reflection
    t0 = time.perf_counter()
    newton: list[PeriodicOrbit] = []
    tried = 0
    for g in guesses:
        if tried >= max_guesses or (time_limit is not None and time.perf_counter() - t0 > time_limit):
            break
        if any(not o.degenerate and (_near(smap, o, g, 1e-4) or (R is not None and _near(smap, o, R(g), 1e-4)))
               for o in newton):
            continue
        tried += 1
        try:
            orb = find_periodic_orbit(smap, g, K, max_iter=max_iter)
        except ParameterError:
            continue
        if orb.period == K and not any(_same_orbit(smap, o, orb, same_tol) for o in newton):
            newton.append(orb)
    newton += _partners(smap, newton, same_tol, max_iter=max_iter, threads=threads)
    found: list[PeriodicOrbit] = []
    for o in newton:
        if any(_same_orbit(smap, f, o, same_tol) for f in found):
            continue
        found.append(o)
        if R is not None and not o.symmetric:
            found.append(_mirror(smap, o))
    found = [_canonical(smap, o) for o in found]
    return sorted(found, key=lambda o: (o.degenerate, o.points[0, 0], o.points[0, 1]))


@dataclass(frozen=True)
class PeriodicBranch:
    """An orbit followed by :func:`continue_periodic`: ``orbits`` at ``values``, the ``bifurcations``
    (dicts: value, type, trace, refined) and why it ``stopped`` early (None if it did not)."""

    parameter: str
    period: int
    values: np.ndarray
    orbits: list
    bifurcations: list = field(default_factory=list)
    stopped: str | None = None

    @property
    def traces(self) -> np.ndarray:
        return np.array([o.trace for o in self.orbits])


@system_first(systems="map")
def continue_periodic(system, period, parameter, start, stop, step, guess, *, bisect_tol=1e-8, touch_window=0.05,
                      touch_tol=1e-6) -> PeriodicBranch:
    """Natural-parameter continuation of an orbit of period K in ``parameter`` (one of the map's
    ``parameters``) from ``start`` to ``stop`` by ``step``, with its bifurcations: ``|trace|`` crossing
    2 bisected to ``bisect_tol``, touches of +-2 refined (docs/commands/periodic.md)."""
    K = _check_period(period)
    values = continuation_values(parameter, start, stop, step, system.parameters)
    g0 = guess.points if isinstance(guess, PeriodicOrbit) else np.asarray(guess, float)

    def solve(v, X):
        orb = find_periodic_orbit(system.with_value(parameter, v), X, K, reduce=False)
        if _minimal_period(orb.points, system) != K:
            raise ParameterError(f"the orbit collapsed to period {_minimal_period(orb.points, system)}")
        return orb

    orbits: list[PeriodicOrbit] = []
    done: list[float] = []
    advance = secant_follower(solve, g0, lambda orb: orb.points, MAX_HALVINGS)

    stopped = None
    for v in values:
        try:
            orbits.append(advance(v))
        except ParameterError as exc:
            if not orbits:
                raise
            stopped = f"no orbit at {parameter} = {v:.10g} ({exc})"
            break
        done.append(float(v))
    vals = np.array(done)

    def nearest(v):
        """The points at v interpolated linearly between the samples around v."""
        i = int(np.clip(np.searchsorted(vals, v) - 1 if step > 0 else len(vals) - np.searchsorted(vals[::-1], v) - 1,
                        0, len(vals) - 2))
        w = (v - vals[i]) / (vals[i + 1] - vals[i])
        return orbits[i].points + w * (orbits[i + 1].points - orbits[i].points)

    bif: list = []

    def crossing(a, b, oa, ob):
        """Bisection for |trace| = 2 between a (orbit oa) and b (orbit ob)."""
        lo, hi, olo, ohi = a, b, oa, ob
        kind = "tangent" if oa.trace + ob.trace > 0 else "period-doubling"
        try:
            while abs(hi - lo) > bisect_tol * max(1.0, abs(hi)):
                mid = 0.5 * (lo + hi)
                om = solve(mid, olo.points + 0.5 * (ohi.points - olo.points))
                if (abs(om.trace) < 2) == (abs(olo.trace) < 2):
                    lo, olo = mid, om
                else:
                    hi, ohi = mid, om
        except ParameterError as exc:   # reported with the bracket reached
            return {"value": 0.5 * (lo + hi), "type": kind, "trace": 2.0 if kind == "tangent" else -2.0,
                    "refined": False, "bracket": [float(lo), float(hi)], "note": str(exc)}
        return {"value": 0.5 * (lo + hi), "type": kind, "trace": 2.0 if kind == "tangent" else -2.0,
                "refined": True, "bracket": [float(lo), float(hi)]}

    tr = np.array([o.trace for o in orbits])
    for i in range(len(orbits) - 1):
        if (abs(tr[i]) < 2) != (abs(tr[i + 1]) < 2):
            bif.append(crossing(vals[i], vals[i + 1], orbits[i], orbits[i + 1]))
    for i in range(1, len(orbits) - 1):
        d0, d1 = tr[i] - tr[i - 1], tr[i + 1] - tr[i]
        s = 2.0 if tr[i] > 0 else -2.0
        if d0 * d1 >= 0 or abs(tr[i] - s) > touch_window:
            continue
        if (abs(tr[i - 1]) < 2) != (abs(tr[i + 1]) < 2) or (abs(tr[i]) < 2) != (abs(tr[i - 1]) < 2):
            continue
        sign = 1.0 if d0 > 0 else -1.0
        try:
            v_ext, f_ext = golden_section_max(lambda v: sign * solve(v, nearest(v)).trace, vals[i - 1], vals[i + 1],
                                   bisect_tol)
        except ParameterError:
            continue
        t_ext = sign * f_ext
        o_ext = solve(v_ext, nearest(v_ext))
        if abs(t_ext - s) <= touch_tol:   # first: a touch may pass +-2 by round-off
            bif.append({"value": float(v_ext), "type": f"touch {'+' if s > 0 else '-'}2", "trace": float(t_ext),
                        "refined": True})
        elif (abs(t_ext) < 2) != (abs(tr[i]) < 2):
            bif.append(crossing(vals[i - 1], v_ext, orbits[i - 1], o_ext))
            bif.append(crossing(v_ext, vals[i + 1], o_ext, orbits[i + 1]))
    bif.sort(key=lambda b: b["value"] * (1 if step > 0 else -1))
    return PeriodicBranch(parameter, K, vals, orbits, bif, stopped)
