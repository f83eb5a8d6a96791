"""Fixed points of the section map, their stability, continuation, and separatrices.

A fixed point of the section map P (:class:`explorer.analysis.section_map.SectionMap`, phi =
phi0, docs/model.md R9) is a periodic orbit of period 1: :func:`find_fixed_point` is
:func:`explorer.analysis.periodic.find_periodic_orbit` with K = 1 (one Newton for every
period: damped steps that keep the point in the allowed region and make the residual fall),
and :func:`continue_branch` is :func:`explorer.analysis.periodic.continue_periodic` with K = 1
(one continuation, one bifurcation detector: |trace| crossing 2 and touching +-2).  At a
fixed point det DP = 1; |trace| < 2 is stable (elliptic), > 2 unstable (hyperbolic).

Separatrices of a hyperbolic point: a fundamental domain along the unstable (stable)
eigenvector iterated forward (backward in time), with points inserted where consecutive
images are far apart, so the curves stay smooth (Parker & Chua, Practical Numerical
Algorithms for Chaotic Systems, 1989, Sec. 6; Krauskopf et al., Int. J. Bifurc. Chaos 15
(2005) 763).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from explorer import model
from explorer.analysis.periodic import PeriodicBranch, PeriodicOrbit
from explorer.analysis.section_map import deprecated, orbit_first, system_first
from explorer.model import ParameterError

__all__ = ["Branch", "FixedPoint", "analytic_eigenvalues_solution_I", "continue_branch", "find_fixed_point", "follow",
           "manifold", "separatrices"]


@dataclass(frozen=True)
class FixedPoint(PeriodicOrbit):
    """A fixed point of the section map P (phi = phi0, docs/model.md R9): the
    :class:`~explorer.analysis.periodic.PeriodicOrbit` of period 1 (one type, every attribute
    of an orbit), with the shorthands of a point.

    Attributes
    ----------
    point : ndarray (2,)
        (p1, p2) with P(point) = point (``points[0]``; Newton residual ``residual``).
    jacobian : ndarray (2, 2)
        DP at the point, from the tangent dynamics (variational equations of R3) projected on
        the section; area-preserving, so ``det`` = 1 up to the integration error.
    eigenvalues : ndarray (2,)
        Eigenvalues of ``jacobian``; ``trace`` their sum. ``|trace| < 2``: elliptic (``stable``),
        ``|trace| > 2``: hyperbolic.
    return_time : float
        Return time of the periodic orbit through the point (``return_times[0]``;
        ``period_time`` is its deprecated name).
    iterations : int
        Newton iterations taken.
    """

    @classmethod
    def from_orbit(cls, orb: PeriodicOrbit) -> FixedPoint:
        """The fixed point of a period-1 :class:`~explorer.analysis.periodic.PeriodicOrbit`."""
        if orb.period != 1:
            raise ParameterError(f"a fixed point is an orbit of period 1, got period {orb.period}")
        return cls(**{f.name: getattr(orb, f.name) for f in fields(PeriodicOrbit)})

    @property
    def point(self) -> np.ndarray:
        return self.points[0]

    @property
    def return_time(self) -> float:
        return float(self.return_times[0])

    @property
    def period_time(self) -> float:
        """Deprecated name of :attr:`return_time`."""
        deprecated("FixedPoint.period_time", "FixedPoint.return_time")
        return self.return_time

    @property
    def kind(self) -> str:
        return "elliptic (stable)" if self.stable else "hyperbolic (unstable)"

    def as_dict(self):
        ev = [complex(e) for e in self.eigenvalues]
        return {"p1": float(self.point[0]), "p2": float(self.point[1]), "trace": float(self.trace),
                "det": float(self.det), "eigenvalues": [[e.real, e.imag] if e.imag else e.real for e in ev],
                "stable": bool(self.stable), "return_time": self.return_time, "iterations": self.iterations,
                "residual": self.residual, "degenerate": bool(self.degenerate)}


@system_first
def find_fixed_point(system, guess=(0.0, 0.0)) -> FixedPoint:
    """A fixed point of the section map P of phi = ``phi0`` at energy ``h`` (docs/model.md R9).

    Newton's method on P(x) - x = 0 in (p1, p2) (:func:`explorer.analysis.periodic.find_periodic_orbit`
    with K = 1), with DP from the tangent dynamics of R3 carried to the next crossing and
    projected on the section; steps halved until the point stays in the allowed region and the
    residual falls. At mu = 0 the central fixed point is solution I of R6, with the eigenvalues
    of its linearisation.

    Parameters
    ----------
    system : SectionMap
        The section map, or ``params, h`` (docs/api.md, "The system argument") (its energy,
        section angle, Taylor tolerance and return budget).
    guess : (float, float)
        Start of Newton's method, (p1, p2) inside the allowed region.

    Returns
    -------
    FixedPoint
        The point, DP, its eigenvalues, trace and determinant, the return time.

    Raises
    ------
    ParameterError
        When Newton's method does not converge from ``guess`` (the message says so).
    """
    from explorer.analysis.periodic import find_periodic_orbit

    return FixedPoint.from_orbit(find_periodic_orbit(system, guess, 1))


@dataclass(frozen=True)
class Branch(PeriodicBranch):
    """A branch of fixed points followed in one parameter by :func:`continue_branch`: the
    :class:`~explorer.analysis.periodic.PeriodicBranch` of period 1 whose orbits are
    :class:`FixedPoint` s.

    ``orbits[i]`` is the :class:`FixedPoint` at ``values[i]`` of ``parameter`` (a model parameter
    or ``"h"``; ``points`` is the deprecated name of ``orbits``); ``bifurcations`` is the list of dicts of
    :class:`explorer.analysis.periodic.PeriodicBranch` (``{"value", "type", "trace", "refined"}``,
    type "tangent", "period-doubling", "touch +2" or "touch -2"); ``stopped`` says why the
    branch ended before ``stop`` (None when it reached it).
    """

    @property
    def points(self) -> list:
        """Deprecated name of ``orbits``."""
        deprecated("Branch.points", "Branch.orbits")
        return self.orbits


@system_first
def continue_branch(system, parameter, start, stop, step, guess=(0.0, 0.0), *, bisect_tol=1e-8) -> Branch:
    """Natural-parameter continuation of a fixed point in any model parameter (or "h").

    :func:`explorer.analysis.periodic.continue_periodic` with K = 1: from ``start`` to ``stop``
    by ``step``, each point from the previous ones (secant predictor, steps halved on failure);
    where ``|trace|`` crosses 2 (elliptic <-> hyperbolic) the value is bisected to
    ``bisect_tol`` (relative), and a sampled extremum of the trace near +-2 is refined into a
    touch.  For Figure 4 (docs/model.md R9, h = 2) the central point turns stable at mu* ~ 2.98316.

    Returns
    -------
    Branch
        The parameter values, the fixed points and the bifurcations.
    """
    from explorer.analysis.periodic import continue_periodic

    br = continue_periodic(system, 1, parameter, start, stop, step, guess, bisect_tol=bisect_tol)
    return Branch(parameter, 1, br.values, [FixedPoint.from_orbit(o) for o in br.orbits], br.bifurcations,
                  br.stopped)


# ---------------------------------------------------------------- separatrices
@orbit_first
@system_first
def manifold(system, fp: FixedPoint, *, stable=False, branch=1, iterations=6, n_domain=60, first=1e-6,
             max_gap=0.02, max_points=20000):
    """One branch (+1 or -1 along the eigenvector) of the unstable (stable: backward in time)
    manifold of a hyperbolic fixed point ``fp`` of the map ``system``, as an (M, 2) polyline on
    the section.

    A fundamental domain x* + s e, s in [first, first |lambda|) (log-spaced), is iterated
    ``iterations`` times; wherever two consecutive images are more than ``max_gap`` apart the
    parameter interval is bisected (the new point iterated from scratch), up to max_points."""
    if fp.stable:
        raise ParameterError("the fixed point is elliptic: it has no separatrices")
    smap = system
    w, V = np.linalg.eig(fp.jacobian)
    w = np.real(w)
    V = np.real(V)
    i = int(np.argmin(np.abs(w))) if stable else int(np.argmax(np.abs(w)))
    lam = abs(w[i])
    lam_u = max(lam, 1.0 / lam)
    e = V[:, i] / np.linalg.norm(V[:, i]) * branch
    x0 = fp.point

    def images(s):
        """x* + s e and its first ``iterations`` images (n + 1, 2)."""
        out = np.empty((iterations + 1, 2))
        x = x0 + s * e
        out[0] = x
        for k in range(iterations):
            x = smap(x, backward=stable, jacobian=False).point
            out[k + 1] = x
        return out

    s_vals = list(first * np.geomspace(1.0, lam_u, n_domain))
    orbits = [images(v) for v in s_vals]
    # refine: wherever two consecutive points of any image of the fundamental domain are more
    # than max_gap apart, insert the (geometric) midpoint of their parameters
    k = 0
    while k < len(s_vals) - 1 and len(s_vals) < max_points:
        gap = np.max(np.linalg.norm(orbits[k + 1] - orbits[k], axis=1))
        if gap > max_gap and s_vals[k + 1] - s_vals[k] > 1e-13 * s_vals[k]:
            s_mid = math.sqrt(s_vals[k] * s_vals[k + 1])
            s_vals.insert(k + 1, s_mid)
            orbits.insert(k + 1, images(s_mid))
        else:
            k += 1
    # the manifold from the fixed point outwards: image 0 of the domain, then image 1, ...
    curve = np.concatenate([np.array([x0])] + [np.array([o[j] for o in orbits]) for j in range(iterations + 1)])
    return curve


@orbit_first
@system_first
def separatrices(system, fp: FixedPoint, *, iterations=6, n_domain=60, first=1e-6, max_gap=0.02,
                 max_points=20000):
    """The four branches (unstable +-, stable +-) of the hyperbolic fixed point ``fp`` of the map
    ``system`` as a list of polylines (:func:`manifold`, whose options these are)."""
    return [manifold(system, fp, stable=s, branch=b, iterations=iterations, n_domain=n_domain, first=first,
                     max_gap=max_gap, max_points=max_points) for s in (False, True) for b in (1, -1)]


def analytic_eigenvalues_solution_I(params, h):
    """docs/model.md R6/R9: at mu = 0 (chi = zeta = 0) the point p = 0 is solution I, M = c = sqrt(2 b h),
    a uniform rotation with return time T = 2 pi b / c.  Linearising R6 about it,
    dp1/dt = alpha p2, dp2/dt = -beta p1 with alpha = c/b - lam/a2, beta = c/b - lam/a1
    (dM is of second order), so the monodromy over T has eigenvalues exp(+-sqrt(-alpha beta) T)
    when alpha beta < 0 (lam b/a1 < c < lam b/a2: hyperbolic) and exp(+-i sqrt(alpha beta) T)
    otherwise."""
    P = params.as_array()
    a1, a2, b, lam = P[model.A1], P[model.A2], P[model.B], P[model.LAM]
    c = math.sqrt(2 * b * h)
    alpha = c / b - lam / a2
    beta = c / b - lam / a1
    T = 2 * math.pi * b / c
    ab = alpha * beta
    if ab < 0:
        k = math.sqrt(-ab) * T
        return np.array([math.exp(k), math.exp(-k)]), 2 * math.cosh(k)
    w = math.sqrt(ab) * T
    return np.array([complex(math.cos(w), math.sin(w)), complex(math.cos(w), -math.sin(w))]), 2 * math.cos(w)


@system_first
def follow(system, parameter, start, stop, guess, *, max_step=0.25) -> FixedPoint:
    """The fixed point at ``parameter = stop`` on the branch through the point found near
    ``guess`` at ``parameter = start`` (continuation in steps of at most ``max_step``)."""
    if start == stop:
        from explorer.analysis.maps import with_value

        return find_fixed_point(with_value(system, parameter, start), guess)
    n = max(1, math.ceil(abs(stop - start) / max_step))
    br = continue_branch(system, parameter, start, stop, (stop - start) / n, guess)
    if br.stopped is not None:
        raise ParameterError(f"the fixed point could not be followed to {parameter} = {stop:.10g}: {br.stopped}")
    return br.orbits[-1]
