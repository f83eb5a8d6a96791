"""Periodic orbits of any period K >= 1 of the section map, their stability and bifurcations.

The section map P: (p1, p2) -> (p1', p2') of phi = phi0 at energy h (docs/model.md R9) is
:class:`explorer.analysis.section_map.SectionMap`: the image point and the 2x2 Jacobian DP
from the tangent dynamics of R3.  A periodic orbit of period K is a point x with
P^K(x) = x; its monodromy is the product DP(x_{K-1}) ... DP(x_0) of the K map Jacobians
along the orbit x_i = P^i(x_0).

Newton's method
---------------
* K <= ``MULTIPLE_SHOOTING_FROM - 1`` = 4: single shooting, Newton on P^K(x) - x = 0 with the
  matrix (monodromy - I) (the period-1 case is :func:`explorer.analysis.fixedpoints.find_fixed_point`
  written for K = 1, and gives its numbers);
* K >= ``MULTIPLE_SHOOTING_FROM`` = 5: multiple shooting over the K points, unknowns
  X = (x_0, ..., x_{K-1}) and residuals F_i = P(x_i) - x_{i+1 mod K}, a 2K x 2K Newton system
  with DP(x_i) on the block diagonal and -I on the cyclic block superdiagonal.  The iterates of
  P^K grow like |lambda|^K near a hyperbolic orbit; the K short maps do not.

Steps are damped (halved) so that every point stays in the allowed region and the residual
decreases.  A converged orbit is reduced to its minimal period: if x_{i+d} = x_i for a divisor
d of K (within ``MINIMAL_PERIOD_TOL``) it is an orbit of period d, reported as such.

Degenerate orbits
-----------------
Newton's answer is an isolated orbit only if the map's accuracy pins it down.  Near a
resonant curve (a torus of rotation number m/K that the perturbation barely breaks) P^K is
the identity along the curve to round-off: ``|P^K(x) - x|`` stays at its noise floor over a
whole arc, and Newton stops anywhere on it, at a point that depends on rounding and so on the
CPU.  The rule: with M the monodromy, the noise floor of the residual is
eps = max(residual, ``MAP_NOISE`` max(1, |M|)) and the position is determined to
eps / s_min(M - I), the smallest singular value of M - I.  An orbit is **degenerate** when that
``uncertainty`` exceeds ``ISOLATION_TOL`` (the distance below which two orbits are the same),
or when |residue| < ``DEGENERATE_RESIDUE`` (|trace - 2| <= ``KIND_TOL``).  Degenerate orbits are
flagged (``PeriodicOrbit.degenerate``), listed after the isolated ones by the search, never
counted with them, and drawn apart in the figures; isolated orbits (s_min of order 1e-3 and
more, uncertainty 1e-12 .. 1e-9) come out the same on every CPU.

Reversing symmetry
------------------
With zeta = xi = 0 (chi, eta, mu, lam any), the reduced system R3 in (p1, p2, M, phi) is
reversible under

    R: (p1, p2, M, phi) -> (p1, -p2, M, -phi),   t -> -t,

i.e. (p1, p2, M, g1, g2) -> (p1, -p2, M, -g1, g2).  Derivation: let y(t) solve R3 and
z(t) = R y(-t).  Then dphi_z/dt = phi'(-t) = M/b = M_z/b; dp1_z/dt = -p1'(-t) =
-(M/b) p2 + mu sin phi + lam p2/a2, which is R3's right-hand side at z,
(M/b)(-p2) - mu sin(-phi) - lam(-p2)/a2 (this needs zeta = 0); dp2_z/dt = -d(-p2)/dt(-t)
= p2'(-t) = -(M/b)(p1 - chi) - mu cos phi + lam p1/a1, the right-hand side at z since
cos(-phi) = cos phi; dM_z/dt = -M'(-t) = -(p1 - chi) p2/a2 + (p2 - zeta) p1/a1
+ mu(xi cos phi - eta sin phi), and the right-hand side at z is (p1 - chi)(-p2)/a2
- (-p2 - zeta) p1/a1 - mu(xi cos phi + eta sin phi): equal when zeta = xi = 0.  R keeps M
(so dphi/dt > 0) and maps phi = pi (and phi = 0) to itself, so on the section phi0 = pi
(or 0) it induces the involution G0(p1, p2) = (p1, -p2) with G0 P G0 = P^{-1}.  The
symmetry line Fix(G0) is p2 = 0; the second one, Fix(P G0), is the image on phi = pi of the
line p2 = 0 of the section phi = 0 (the other set of R's fixed points) after half a turn.  A
symmetric orbit of period K has two of its points on R's fixed set {p2 = 0, phi = 0 or pi},
K half-turns apart; :func:`search_periodic_orbits` seeds Newton on both lines, where it
finds the roots of p2 after K half-turns (tests/analysis/test_periodic.py proves the symmetry
with an independent scipy integration).  The image G0(orbit) of an orbit is an orbit with the
same trace, computed exactly by :func:`mirror_orbit`: the search completes its set with it.

Bifurcations
------------
:func:`continue_periodic` steps a parameter and reports (i) where |trace| crosses 2 between
samples (bisection): at trace = +2 a tangent (saddle-node or, for symmetric orbits, pitchfork)
bifurcation, at trace = -2 a period doubling; (ii) where the trace only touches +-2: at an
interior sample where the sampled trace has a local extremum within ``touch_window`` of +-2,
the extremum is refined by golden-section search over the two neighbouring intervals; if the
refined trace passes +-2 the two crossings on either side are located by bisection, and if it
comes within ``touch_tol`` of +-2 without passing it is reported as a touch.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from explorer import model
from explorer.analysis.continuation import continuation_values, golden_section_max, secant_follower
from explorer.analysis.halfturn import partner_points
from explorer.analysis.maps import difference, images, is_section_map
from explorer.analysis.maps import reduce as reduce_points
from explorer.analysis.section_map import SectionMap, system_first
from explorer.analysis.sections import crossings
from explorer.integrate.methods import DEFAULT_TOL as SECTIONS_TOL
from explorer.model import ParameterError, symmetry, validation
from explorer.model.symmetry import is_reversible, reversor

__all__ = ["DEGENERATE_RESIDUE", "ISOLATION_TOL", "KIND_TOL", "MULTIPLE_SHOOTING_FROM", "PeriodicBranch",
           "PeriodicOrbit", "continue_periodic", "find_periodic_orbit", "mirror_orbit", "periodic_guesses",
           "search_periodic_orbits", "symmetry_line_points"]

#: Newton: converged when the step is below this (relative to max(1, |x|))
NEWTON_TOL = 1e-12
#: Newton: a start whose residual is below this (relative to max(1, |x|)) is already a solution
#: (e.g. continued from an exact one): no step is taken
SOLVED_RESIDUAL = 1e-15
#: Newton: converged when the residual is below this, whatever the step
CONVERGED_RESIDUAL = 1e-14
#: Newton's line search: a damped step is taken when it lowers the residual or leaves it below this
LINE_SEARCH_RESIDUAL = 1e-11
NEWTON_MAX_ITER = 30
#: residual max_i |P(x_i) - x_{i+1}| accepted at the end (near |trace| = 2 Newton is slow)
ACCEPT_RESIDUAL = 1e-9
#: periods from which Newton uses multiple shooting (K > 4); single shooting below
MULTIPLE_SHOOTING_FROM = 5
#: |trace| within KIND_TOL of 2: "parabolic"
KIND_TOL = 1e-6
#: two points of an orbit closer than this are the same point (minimal period)
MINIMAL_PERIOD_TOL = 1e-7
#: two orbits are the same if a point of one is within this of a point of the other
SAME_ORBIT_TOL = 1e-6
#: isolation (module docstring, "Degenerate orbits"): an orbit whose position is determined only
#: to worse than this by the map's accuracy is not isolated at the search's tolerance
ISOLATION_TOL = SAME_ORBIT_TOL
#: accuracy of one evaluation of P^K at the map's default tolerance, relative to the size of
#: its Jacobian: the noise floor of |P^K(x) - x| is MAP_NOISE * max(1, |D(P^K)|).  Measured at
#: the Figure-4 scene (mu = 0.03, K <= 4, |D(P^K)| from 5 to 4e3): P^K at tol 1e-15 against
#: tol 1e-16 differs by 5e-17 .. 1e-16 times |D(P^K)|; the constant is ten times that.
MAP_NOISE = 1e-15
#: |residue| below this (|trace - 2| <= KIND_TOL) is degenerate whatever the conditioning
DEGENERATE_RESIDUE = KIND_TOL / 4
#: time budget of one return of the map in a search (typical returns take ~6 at Figure 4's
#: scene; orbits near the boundary of the region that hardly turn would cost up to RETURN_TMAX)
SEARCH_TMAX = 50.0
#: continuation: a failed step is split in two at most this many times
MAX_HALVINGS = 6


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic orbit of minimal period ``period`` of the section map P (phi = phi0).

    Attributes
    ----------
    points : ndarray (K, 2)
        (p1, p2) of the orbit, ``points[i + 1] = P(points[i])``.
    period : int
        Minimal period K.
    jacobian : ndarray (2, 2)
        Monodromy D(P^K) at ``points[0]``: the product of the K map Jacobians.
    eigenvalues : ndarray (2,)
        Eigenvalues of ``jacobian`` (multipliers).
    trace, det : float
        Trace and determinant of ``jacobian`` (det = 1: the map preserves area).
    return_times : ndarray (K,)
        Time from ``points[i]`` to ``points[i + 1]``.
    residual : float
        ``max_i |P(points[i]) - points[i + 1 mod K]|``.
    iterations : int
        Newton iterations taken.
    symmetric : bool
        The set of points is invariant under the reversor G0(p1, p2) = (p1, -p2) (only when
        :func:`is_reversible`; else False).
    map_jacobians : ndarray (K, 2, 2)
        DP at each point.
    uncertainty : float
        How well the map's accuracy determines the orbit's position: the noise floor of
        ``|P^K(x) - x|`` over the smallest singular value of ``jacobian - I`` (module docstring).
    degenerate : bool
        Not isolated at the search's tolerance: ``uncertainty > ISOLATION_TOL`` or
        ``|residue| < DEGENERATE_RESIDUE`` (a near-parabolic orbit on a resonant curve, where
        Newton lands anywhere along the curve: the point reported is one of a continuum).
    """

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
    #: the map of the protocol the orbit belongs to, when it is not a section map (None for one:
    #: ``params``, ``h``, ``phi0`` name it)
    system: object = field(default=None, repr=False, compare=False)

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
        """``"parabolic"`` if ``||trace| - 2| <= KIND_TOL``, else ``"elliptic"`` (``|trace| < 2``) or
        ``"hyperbolic"``."""
        if abs(abs(self.trace) - 2.0) <= KIND_TOL:
            return "parabolic"
        return "elliptic" if abs(self.trace) < 2.0 else "hyperbolic"

    @property
    def total_time(self) -> float:
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


# ------------------------------------------------------------------ Newton
class _Shooting:
    """Evaluations of the K maps along a set of points (one call of the Taylor return map each)."""

    def __init__(self, smap: SectionMap, K: int):
        self.smap, self.K = smap, K

    def along(self, x0, multiple, X=None):
        """Images, Jacobians and times of the K maps: from the points X (multiple shooting) or
        along the orbit of x0 (single shooting).  Raises ParameterError if a map fails."""
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
    """max |P(x_i) - x_{i+1}| (multiple shooting) or |P^K(x_0) - x_0|, on the map's cylinder
    (:func:`explorer.analysis.maps.difference`)."""
    if multiple:
        return float(np.max(np.abs(difference(smap, imgs, np.roll(pts, -1, axis=0)))))
    return float(np.max(np.abs(difference(smap, imgs[-1], pts[0]))))


def _newton(smap, K, X0, max_iter=NEWTON_MAX_ITER, multiple=None):
    """Newton's method for a K-periodic orbit from the points X0 ((K, 2), or (2,) for single
    shooting).  Returns (points, images, jacobians, times, iterations); ParameterError on failure."""
    multiple = K >= MULTIPLE_SHOOTING_FROM if multiple is None else multiple
    sh = _Shooting(smap, K)
    X0 = np.asarray(X0, float)
    if multiple:
        if X0.shape == (2,):  # start from the orbit of the guess
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
            break   # already a solution (e.g. continued from an exact one): no step to take
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
        for _ in range(30):   # damped step: stay in the allowed region, do not let the residual grow
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
                break    # at the residual's noise floor: no step can lower it (near-parabolic orbits)
            raise ParameterError(f"Newton's method stalled (residual {res:.3g})")
        X, ev, res = Xn, evn, resn
        step = alpha * float(np.max(np.abs(dx)))
        if step < NEWTON_TOL * max(1.0, float(np.max(np.abs(X)))) or res < CONVERGED_RESIDUAL:
            break
    if not res < ACCEPT_RESIDUAL:
        raise ParameterError(f"Newton's method did not converge (residual {res:.3g}, last step {step:.3g})")
    pts, imgs, jacs, times = ev
    return pts, imgs, jacs, times, it


def _minimal_period(pts, tol=MINIMAL_PERIOD_TOL, system=None) -> int:
    K = len(pts)
    scale = max(1.0, float(np.max(np.abs(pts))))
    for d in range(1, K):
        if K % d == 0 and np.max(np.abs(difference(system, np.roll(pts, -d, axis=0), pts))) <= tol * scale:
            return d
    return K


def _isolation(M, residual):
    """(uncertainty, degenerate) of an orbit with monodromy M and Newton residual (module
    docstring, "Degenerate orbits")."""
    smin = float(np.linalg.svd(M - np.eye(2), compute_uv=False)[-1])
    noise = max(float(residual), MAP_NOISE * max(1.0, float(np.linalg.norm(M, 2))))
    uncertainty = noise / smin if smin > 0 else math.inf
    residue = (2.0 - float(np.trace(M))) / 4.0
    return uncertainty, bool(uncertainty > ISOLATION_TOL or abs(residue) < DEGENERATE_RESIDUE)


def _orbit(smap, pts, jacs, times, resid, iters, symmetric=None) -> PeriodicOrbit:
    """The PeriodicOrbit through ``pts`` with map Jacobians ``jacs`` (monodromy, eigenvalues,
    symmetry and isolation derived from them)."""
    M = _monodromy(jacs)
    if not np.all(np.isfinite(M)):
        raise ParameterError(smap.not_finite(pts[0]))
    uncertainty, degenerate = _isolation(M, resid)
    if symmetric is None:     # symmetric under one of the map's reversors
        symmetric = any(_maps_onto(smap, R(pts), pts, 1e3 * MINIMAL_PERIOD_TOL) for R in smap.reversors)
    return PeriodicOrbit(np.array(pts, float), len(pts), M, np.linalg.eigvals(M), float(np.trace(M)),
                         float(np.linalg.det(M)), np.array(times, float), float(resid), int(iters), bool(symmetric),
                         np.array(jacs, float), uncertainty=uncertainty, degenerate=degenerate,
                         **smap.orbit_fields())


def _maps_onto(system, images, pts, tol) -> bool:
    """Every point of ``images`` is within ``tol`` of a point of ``pts`` (on the map's cylinder)."""
    d = np.linalg.norm(difference(system, np.asarray(images)[:, None, :], np.asarray(pts)[None, :, :]), axis=2)
    return bool(np.all(np.min(d, axis=1) <= tol))


def _make_orbit(smap, pts, imgs, jacs, times, iters, reduce=True) -> PeriodicOrbit:
    K = len(pts)
    d = _minimal_period(pts, system=smap) if reduce else K
    pts, imgs, jacs, times = pts[:d], imgs[:d], jacs[:d], times[:d]
    resid = float(np.max(np.abs(difference(smap, imgs, np.roll(pts, -1, axis=0)))))
    return _orbit(smap, reduce_points(smap, pts), jacs, times, resid, iters)


def mirror_orbit(orb: PeriodicOrbit) -> PeriodicOrbit:
    """The image G0(orbit) of a periodic orbit under the reversor, computed exactly (no search).

    With G0 P G0 = P^-1 (module docstring), the points z_j = G0 x_{-j} (indices mod K) form an
    orbit: P(z_j) = G0 P^-1(x_{-j}) = G0 x_{-j-1} = z_{j+1}.  Differentiating P = G0 P^-1 G0
    gives DP(z_j) = G0 DP(x_{-j-1})^-1 G0, so the monodromy at z_0 is G0 M^-1 G0 (same
    trace, det 1), and the return time from z_j to z_{j+1} is the time from x_{-j-1} to x_{-j}.
    Raises ParameterError when the reversor does not apply (``is_reversible`` is False)."""
    if not is_reversible(orb.params, orb.phi0):
        raise ParameterError("the mirror image needs a reversible system (zeta = xi = 0) and phi0 = 0 or pi")
    K = orb.period
    G = np.diag([1.0, -1.0])
    idx = (-np.arange(K)) % K                      # x_{-j}
    prev = (-np.arange(K) - 1) % K                 # x_{-j-1}
    pts = reversor(orb.points[idx])
    jacs = np.array([G @ np.linalg.inv(orb.map_jacobians[i]) @ G for i in prev])
    return _orbit(_section_map_of(orb), pts, jacs, orb.return_times[prev], orb.residual, orb.iterations,
                  orb.symmetric)


def _section_map_of(orb: PeriodicOrbit) -> SectionMap:
    """The section map an orbit names (``params``, ``h``, ``phi0``), to build orbits of it."""
    return SectionMap(orb.params, orb.h, phi0=orb.phi0)


def _check_period(period) -> int:
    if isinstance(period, bool) or not isinstance(period, (int, np.integer)) or period < 1:
        raise ParameterError(f"period must be an integer K >= 1, got {period!r}")
    return int(period)


@system_first
def find_periodic_orbit(system, guess, period, *, max_iter=NEWTON_MAX_ITER, reduce=True) -> PeriodicOrbit:
    """A periodic orbit of period ``period`` of the section map phi = ``phi0`` at energy ``h``.

    Newton's method on P^K(x) = x (single shooting for K <= 4, multiple shooting over the K
    points for K >= 5), the Jacobian from the tangent dynamics of docs/model.md R3 (the product of
    the K map Jacobians).  For K = 1 it gives the numbers of
    :func:`explorer.analysis.fixedpoints.find_fixed_point`.

    Parameters
    ----------
    system : SectionMap
        The section map, or ``params, h`` (docs/api.md, "The system argument"; docs/model.md
        R9): its energy, section angle, Taylor tolerance and the time budget of one return.
    guess : (float, float) or array (K, 2)
        Start of Newton's method: a point in the allowed region, or K points (multiple shooting).
    period : int
        K >= 1.
    max_iter : int
        Budget of Newton iterations.
    reduce : bool
        Report the orbit with its minimal period (an orbit of period 2 found with K = 4 has
        period 2); with False, keep K points.

    Returns
    -------
    PeriodicOrbit
        The points, monodromy, eigenvalues, trace, residue, symmetry, return times.

    Raises
    ------
    ParameterError
        K < 1, a guess outside the allowed region, or Newton's method failing (the message says so).
    """
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


# ------------------------------------------------------------------ search
def _line_p1(params, h, phi0, n):
    e = model.allowed_ellipse(params, h, phi0)
    if e is None:
        return np.empty(0)
    c1, c2, r1, r2 = e
    if abs(c2) > r2:
        return np.empty(0)
    half = r1 * math.sqrt(max(0.0, 1.0 - (c2 / r2) ** 2))
    return c1 + half * np.linspace(-1.0, 1.0, n + 2)[1:-1]


@system_first
def symmetry_line_points(system, period, *, n=200, threads=None):
    """Seeds of symmetric orbits of period ``period`` on the two symmetry lines (see the module).

    Start points z on R's fixed set: p2 = 0 on the section phi = phi0 (line 0) and p2 = 0 on
    phi = phi0 + pi (line 1), n each across the allowed region; p2 after ``period`` half-turns
    changes sign between neighbours where a symmetric orbit of that period (or a divisor)
    passes; each bracket is refined by bisection (a few map evaluations) and the point on the
    section phi = phi0 of that orbit is returned.  Returns an (m, 2) array of seeds.

    Another map of the protocol: its own ``symmetry_line_points(n)`` (n points on each of its
    symmetry lines, unrefined: Newton starts), or none when it has no reversors.
    """
    K = _check_period(period)
    if not is_section_map(system):
        seeds = getattr(system, "symmetry_line_points", None)
        return np.empty((0, 2)) if seeds is None else np.asarray(seeds(validation.integer("n", n, 1)), float)
    prm, h, phi0, tol, tmax = system.params, system.h, system.phi0, system.tol, system.tmax
    if not is_reversible(prm, phi0):
        return np.empty((0, 2))
    other = phi0 + math.pi

    def run(p1, line, threads=threads):
        """(p2 after K half-turns, point on phi0) for starts p1 on line 0 or 1 (NaN when stopped)."""
        start_phi = phi0 if line == 0 else other
        Y0 = model.section_state(prm, p1, np.zeros_like(p1), h, start_phi)
        # half-turn K lands on phi0 if (K even) == (line 0)
        target = phi0 if (K % 2 == 0) == (line == 0) else other
        n_target = (K + line) // 2 if target == phi0 else (K + 1 - line) // 2
        n_target = max(n_target, 1)
        c = crossings(prm, states=Y0, n_crossings=n_target, phi0=target, tol=tol, tmax=tmax * n_target, threads=threads)
        f = np.where(c.count >= n_target, c.data[:, n_target - 1, 2], np.nan)
        if line == 0:
            on = np.column_stack([p1, np.zeros_like(p1)])
        else:
            c1 = crossings(prm, states=Y0, n_crossings=1, phi0=phi0, tol=tol, tmax=tmax, threads=threads)
            on = np.where((c1.count >= 1)[:, None], c1.data[:, 0, 1:3], np.nan)
        return f, on

    seeds = []
    for line in (0, 1):
        p1 = _line_p1(prm, h, phi0 if line == 0 else other, n)
        if len(p1) < 2:
            continue
        f, _ = run(p1, line)
        for i in np.flatnonzero(np.isfinite(f[:-1]) & np.isfinite(f[1:]) & (np.sign(f[:-1]) != np.sign(f[1:]))):
            a, b, fa = p1[i], p1[i + 1], f[i]
            for _ in range(16):   # bisection to 2^-16 of the bracket (Newton does the rest)
                m = 0.5 * (a + b)
                fm, _ = run(np.array([m]), line, 1)
                if not np.isfinite(fm[0]):
                    break
                if np.sign(fm[0]) == np.sign(fa):
                    a, fa = m, fm[0]
                else:
                    b = m
            _, on = run(np.array([0.5 * (a + b)]), line, 1)
            if np.all(np.isfinite(on[0])):
                seeds.append(on[0])
    return np.array(seeds).reshape(-1, 2)


def _grid_seeds(prm, h, K, grid, phi0, tol, tmax, threads):
    """Grid points of the allowed region where |P^K(x) - x| has a local minimum, best first."""
    e = model.allowed_ellipse(prm, h, phi0)
    if e is None:
        return np.empty((0, 2))
    c1, c2, r1, r2 = e
    u = np.linspace(-1.0, 1.0, grid + 2)[1:-1]
    U, V = np.meshgrid(c1 + r1 * u, c2 + r2 * u, indexing="ij")
    inside = model.section_M2(prm, U, V, h, phi0) > 0
    R = np.full(U.shape, np.inf)
    if inside.any():
        c = crossings(prm, h, np.column_stack([U[inside], V[inside]]), n_crossings=K, phi0=phi0,
                      tol=max(tol, SECTIONS_TOL), tmax=tmax * K, threads=threads)
        ok = c.count >= K
        r = np.full(ok.shape, np.inf)
        r[ok] = np.hypot(c.data[ok, K - 1, 1] - U[inside][ok], c.data[ok, K - 1, 2] - V[inside][ok])
        R[inside] = r
    pad = np.pad(R, 1, constant_values=np.inf)
    nb = np.stack([pad[1 + di:1 + di + grid, 1 + dj:1 + dj + grid]
                   for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj])
    ismin = np.isfinite(R) & (R <= nb.min(axis=0))
    idx = np.flatnonzero(ismin.ravel())
    idx = idx[np.argsort(R.ravel()[idx])]
    return np.column_stack([U.ravel()[idx], V.ravel()[idx]])


def _map_guesses(system, K, grid, line) -> np.ndarray:
    """:func:`periodic_guesses` for a map of the protocol other than a section map: ``line`` points
    on each of its symmetry lines (``system.symmetry_line_points``, where it has reversors), then
    the points of a ``grid`` x ``grid`` grid of ``system.domain`` where |P^K(x) - x| (on its
    cylinder) is a local minimum, best first."""
    seeds = [np.asarray(system.symmetry_line_points(line), float).reshape(-1, 2)] \
        if hasattr(system, "symmetry_line_points") else []
    domain = getattr(system, "domain", None)
    if domain is None:
        if not seeds:
            raise ParameterError(f"{type(system).__name__} has no domain and no symmetry lines to search: give "
                                 "guesses=")
        return seeds[0]
    (a0, a1), (b0, b1) = domain
    u = (np.arange(grid) + 0.5) / grid
    U, V = np.meshgrid(a0 + (a1 - a0) * u, b0 + (b1 - b0) * u, indexing="ij")
    X = np.column_stack([U.ravel(), V.ravel()])
    img = images(system, X, K)[:, -1]
    R = np.linalg.norm(difference(system, img, X), axis=1).reshape(grid, grid)
    R[~np.isfinite(R)] = np.inf
    pad = np.pad(R, 1, constant_values=np.inf)
    nb = np.stack([pad[1 + di:1 + di + grid, 1 + dj:1 + dj + grid]
                   for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj])
    idx = np.flatnonzero((np.isfinite(R) & (R <= nb.min(axis=0))).ravel())
    idx = idx[np.argsort(R.ravel()[idx])]
    return np.concatenate(seeds + [X[idx]])


def _map_search(system, K, grid, line, max_guesses, max_iter, same_tol, guesses) -> list:
    """:func:`search_periodic_orbits` for a map of the protocol other than a section map: Newton
    (:func:`find_periodic_orbit`) from the guesses (:func:`_map_guesses`), orbits of minimal period
    K kept once (points compared on the map's cylinder), isolated before degenerate, each from its
    point of smallest (reduced) first coordinate."""
    G = _map_guesses(system, K, grid, line) if guesses is None else np.asarray(guesses, float).reshape(-1, 2)
    found: list[PeriodicOrbit] = []
    tried = 0
    for g in G:
        if tried >= max_guesses:
            break
        if any(not o.degenerate and _maps_onto(system, g[None, :], o.points, 1e-4) for o in found):
            continue
        tried += 1
        try:
            orb = find_periodic_orbit(system, g, K, max_iter=max_iter)
        except ParameterError:
            continue
        if orb.period == K and not any(_maps_onto(system, orb.points[:1], o.points, same_tol) for o in found):
            found.append(orb)
    out = []
    for o in found:
        k = int(np.lexsort((o.points[:, 1], o.points[:, 0]))[0])
        out.append(o if k == 0 else _orbit(system, np.roll(o.points, -k, axis=0), np.roll(o.map_jacobians, -k, axis=0),
                                           np.roll(o.return_times, -k), o.residual, o.iterations, o.symmetric))
    return sorted(out, key=lambda o: (o.degenerate, o.points[0, 0], o.points[0, 1]))


def _canonical(orb: PeriodicOrbit) -> PeriodicOrbit:
    """The same orbit starting at its point nearest the symmetry line p2 = 0 (then smallest p1)."""
    k = int(np.lexsort((orb.points[:, 0], np.round(np.abs(orb.points[:, 1]), 9)))[0])
    if k == 0:
        return orb
    return _orbit(_section_map_of(orb), np.roll(orb.points, -k, axis=0),
                  np.roll(orb.map_jacobians, -k, axis=0), np.roll(orb.return_times, -k), orb.residual,
                  orb.iterations, orb.symmetric)


def _half_turn_partners(prm, h, orbits, same_tol, *, tol, max_iter, tmax, threads) -> list:
    """The partners under the half-turn reversor T (docs/model.md, "Symmetries";
    :mod:`explorer.analysis.halfturn`) of the isolated ``orbits`` that are not among them yet.

    T P = P^-1 T, so the partner of x_0, ..., x_{K-1} is the orbit T(x_{K-1}), ..., T(x_0), with the
    same trace and period.  The T-images of every point of every orbit are one batch of half-turn
    flows; only an orbit whose image matches no orbit found gets a Newton polish (from a start
    that is the orbit to the flow's accuracy: one or two iterations)."""
    isolated = [o for o in orbits if not o.degenerate]
    if not isolated:
        return []
    images = partner_points(prm, h, np.concatenate([o.points for o in isolated]), phi0=isolated[0].phi0, tol=tol,
                            threads=threads).points
    added: list[PeriodicOrbit] = []
    start = 0
    for o in isolated:
        pts = images[start:start + o.period][::-1]
        start += o.period
        if not np.all(np.isfinite(pts)) or any(f.same_orbit(pts, same_tol) for f in orbits + added):
            continue
        try:
            partner = find_periodic_orbit(prm, h, pts if o.period >= MULTIPLE_SHOOTING_FROM else pts[0], o.period,
                                          phi0=o.phi0, tol=tol, max_iter=max_iter, tmax=tmax)
        except ParameterError:
            continue
        if partner.period == o.period and not partner.degenerate and partner.same_orbit(pts, 1e3 * same_tol):
            added.append(partner)
    return added


@system_first(settings=("phi0", "tol"))
def periodic_guesses(system, period, *, grid=12, line=None, tmax=SEARCH_TMAX, threads=None) -> np.ndarray:
    """The Newton starts of :func:`search_periodic_orbits`, in the order it tries them: the seeds on
    the symmetry lines (:func:`symmetry_line_points`, ``line`` per line, default 8 ``grid``), then
    the points of a ``grid`` x ``grid`` grid of the allowed region where ``|P^K(x) - x|`` is a
    local minimum (best first).  An (m, 2) array."""
    K = _check_period(period)
    grid = validation.integer("grid", grid, 2, 1000)
    line = 8 * grid if line is None else validation.integer("line", line, 2)
    if not is_section_map(system):
        return _map_guesses(system, K, grid, line)
    prm, h, phi0, tol = system.params, system.h, system.phi0, system.tol
    if model.allowed_ellipse(prm, h, phi0) is None:
        raise ParameterError(f"the allowed region is empty at h = {h:g}; allowed: "
                             f"{model.describe_region(prm, h, phi0)}")
    return np.concatenate([symmetry_line_points(prm, h, K, n=line, phi0=phi0, tol=tol, tmax=tmax, threads=threads),
                           _grid_seeds(prm, h, K, grid, phi0, tol, tmax, threads)])


@system_first(settings=("phi0", "tol"))
def search_periodic_orbits(system, period, *, grid=12, line=None, max_guesses=60, max_iter=NEWTON_MAX_ITER,
                           tmax=SEARCH_TMAX, time_limit=None, same_tol=SAME_ORBIT_TOL, threads=None,
                           guesses=None) -> list:
    """All periodic orbits of minimal period ``period`` found from guesses covering the section.

    Guesses: :func:`periodic_guesses` (the symmetry lines first, then the local minima of
    ``|P^K(x) - x|`` on a grid), or the (m, 2) array ``guesses``.  Newton's method
    (:func:`find_periodic_orbit`) runs from at most ``max_guesses`` of them, skipping a guess
    within 1e-4 of an isolated orbit already found (never near a degenerate one: where those
    land depends on rounding, and what is tried must not); orbits are reduced to their minimal
    period (those of a smaller period are dropped) and deduplicated (two orbits are the same if
    a point of one lies within ``same_tol`` of a point of the other).  When the reversor
    applies, the set is completed by symmetry: every asymmetric orbit comes with its mirror
    image :func:`mirror_orbit`, computed exactly, and an orbit Newton also found as the mirror
    of an earlier one is replaced by that exact image.

    Degenerate orbits (``orbit.degenerate``: not isolated at the map's accuracy, module
    docstring) are reported after the isolated ones and never counted with them; their number
    and points may differ between CPUs, the isolated orbits may not.

    Parameters
    ----------
    system : SectionMap
        The section map, or ``params, h`` (docs/api.md, "The system argument") (its energy,
        section angle and Taylor tolerance; the time budget of one
        return is ``tmax``).
    period : int
        K >= 1.
    grid : int
        Grid points per axis (>= 2).
    line : int or None
        Start points per symmetry line.
    max_guesses : int
        Budget of Newton starts.
    max_iter : int
        Budget of Newton iterations per start.
    tmax : float
        Time budget of one return of the map (``SEARCH_TMAX``).
    time_limit : float or None
        Wall-clock budget in seconds of the Newton phase (None: none; a limit makes the
        result depend on the machine's speed).
    threads : int or None
        Numba threads of the batch integrations.
    guesses : array (m, 2) or None
        Newton starts to use instead of :func:`periodic_guesses`.

    Returns
    -------
    list of PeriodicOrbit
        The isolated orbits, then the degenerate ones; each orbit once, starting at its point
        nearest p2 = 0, sorted by that point's p1 within each group.
    """
    K = _check_period(period)
    max_guesses = validation.integer("max_guesses", max_guesses, 1)
    if not is_section_map(system):
        return _map_search(system, K, grid, line, max_guesses, max_iter, same_tol, guesses)
    prm, h, phi0, tol = system.params, system.h, system.phi0, system.tol
    if guesses is None:
        guesses = periodic_guesses(prm, h, K, grid=grid, line=line, phi0=phi0, tol=tol, tmax=tmax, threads=threads)
    else:
        guesses = np.asarray(guesses, float).reshape(-1, 2)
    reversible = is_reversible(prm, phi0)
    t0 = time.perf_counter()
    newton: list[PeriodicOrbit] = []
    tried = 0
    for g in guesses:
        if tried >= max_guesses or (time_limit is not None and time.perf_counter() - t0 > time_limit):
            break
        if any(not o.degenerate and (o.distance_to(g) < 1e-4 or (reversible and o.distance_to(reversor(g)) < 1e-4))
               for o in newton):
            continue   # on an isolated orbit found already, or on its mirror image
        tried += 1
        try:
            orb = find_periodic_orbit(prm, h, g, K, phi0=phi0, tol=tol, max_iter=max_iter, tmax=tmax)
        except ParameterError:
            continue
        if orb.period == K and not any(o.same_orbit(orb, same_tol) for o in newton):
            newton.append(orb)
    if symmetry.has_half_turn_symmetry(prm, phi0):
        newton += _half_turn_partners(prm, h, newton, same_tol, tol=tol, max_iter=max_iter, tmax=tmax,
                                      threads=threads)
    found: list[PeriodicOrbit] = []
    for o in newton:   # completed by symmetry: an orbit, then its exact mirror image
        if any(f.same_orbit(o, same_tol) for f in found):
            continue
        found.append(o)
        if reversible and not o.symmetric:
            found.append(mirror_orbit(o))
    found = [_canonical(o) for o in found]
    return sorted(found, key=lambda o: (o.degenerate, o.points[0, 0], o.points[0, 1]))


# ------------------------------------------------------------------ continuation
@dataclass(frozen=True)
class PeriodicBranch:
    """A periodic orbit followed in one parameter by :func:`continue_periodic`.

    ``orbits[i]`` is the orbit at ``values[i]``; ``bifurcations`` is a list of dicts
    ``{"value", "type", "trace", "refined"}`` with type "tangent" (trace = +2), "period-doubling"
    (trace = -2), "touch +2" or "touch -2" (``refined`` False: the bisection stopped where
    Newton failed, ``bracket`` gives the interval reached); ``stopped`` says why the branch
    ended early (None when it reached ``stop``).
    """

    parameter: str
    period: int
    values: np.ndarray
    orbits: list
    bifurcations: list = field(default_factory=list)
    stopped: str | None = None

    @property
    def traces(self) -> np.ndarray:
        return np.array([o.trace for o in self.orbits])


@system_first
def continue_periodic(system, period, parameter, start, stop, step, guess, *, bisect_tol=1e-8, touch_window=0.05,
                      touch_tol=1e-6) -> PeriodicBranch:
    """Natural-parameter continuation of a periodic orbit of period K in a model parameter or "h".

    From ``start`` to ``stop`` by ``step``; each orbit from the previous one (secant predictor
    on all K points, steps halved on failure); the branch ends early (``stopped``) where
    Newton fails, e.g. at a fold (trace -> +2), or where the orbit collapses to a smaller
    period.  Stability changes (rule in the module docstring): ``|trace|`` crossing 2 located by
    bisection to ``bisect_tol`` (relative), "tangent" at trace = +2, "period-doubling" at
    trace = -2; a local extremum of the sampled trace within ``touch_window`` of +-2 is
    refined by golden-section search and reported as a touch when it comes within
    ``touch_tol`` of +-2 (or as two crossings when it passes it).

    Parameters
    ----------
    system : SectionMap
        The section map, or ``params, h`` (docs/api.md, "The system argument") at which
        ``guess`` is an orbit (``parameter`` set to ``start``).
    period : int
        K >= 1.
    parameter : str
        A model parameter name or "h".
    start, stop, step : float
        The parameter values.
    guess : (float, float), array (K, 2) or PeriodicOrbit
        A point of the orbit at ``start``.

    Returns
    -------
    PeriodicBranch
    """
    K = _check_period(period)
    values = continuation_values(parameter, start, stop, step, system.parameters)
    g0 = guess.points if isinstance(guess, PeriodicOrbit) else np.asarray(guess, float)

    def solve(v, X):
        orb = find_periodic_orbit(system.with_value(parameter, v), X, K, reduce=False)
        if _minimal_period(orb.points, system=system) != K:
            raise ParameterError(f"the orbit collapsed to period {_minimal_period(orb.points, system=system)}")
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
        """Bisection for the value where |trace| = 2 between a (orbit oa) and b (orbit ob), each
        new orbit from the points interpolated between the bracket's orbits."""
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
        except ParameterError as exc:   # reported with the bracket reached, not dropped
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
            continue      # crossings already reported
        sign = 1.0 if d0 > 0 else -1.0    # maximum or minimum of the trace
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
