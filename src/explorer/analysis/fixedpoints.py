"""Fixed points of the section map, their stability, continuation, and separatrices.

A fixed point of the section map P (:class:`explorer.analysis.section_map.SectionMap`, phi =
phi0, docs/model.md R9) is a periodic orbit of period 1: :func:`find_fixed_point` is
:func:`explorer.analysis.periodic.find_periodic_orbit` with K = 1 (one Newton for every
period: damped steps that keep the point in the allowed region and make the residual fall),
and :func:`continue_branch` is :func:`explorer.analysis.periodic.continue_periodic` with K = 1
(one continuation, one bifurcation detector: |trace| crossing 2 and touching +-2).  At a
fixed point det DP = 1; |trace| < 2 is stable (elliptic), > 2 unstable (hyperbolic).

Separatrices of a hyperbolic point: the branches of its stable and unstable manifolds grown by
the one manifold algorithm, :func:`explorer.analysis.manifolds.grow_branch` (a fundamental
domain along the eigenvector and its images, points inserted where the curve needs them;
Krauskopf & Osinga 1998, J. Comput. Phys. 146, 404), to a number of images of the fundamental
domain.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from explorer import model
from explorer.analysis.manifolds import DEFAULT_MAX_GAP, DEFAULT_START_TOL
from explorer.analysis.periodic import PeriodicBranch, PeriodicOrbit
from explorer.analysis.section_map import system_first
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
        Return time of the periodic orbit through the point (``return_times[0]``).
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
    or ``"h"``); ``bifurcations`` is the list of dicts of
    :class:`explorer.analysis.periodic.PeriodicBranch` (``{"value", "type", "trace", "refined"}``,
    type "tangent", "period-doubling", "touch +2" or "touch -2"); ``stopped`` says why the
    branch ended before ``stop`` (None when it reached it).
    """


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
#: the images of the fundamental domain a separatrix is drawn to, by default
SEPARATRIX_GENERATIONS = 6


def _saddle_of(system, fp: FixedPoint):
    """The :class:`~explorer.analysis.manifolds.Saddle` of the hyperbolic fixed point ``fp``
    (one eigen-decomposition for all four branches)."""
    from explorer.analysis.manifolds import saddle

    if fp.stable:
        raise ParameterError("the fixed point is elliptic: it has no separatrices")
    return saddle(system, fp)


def _grown(sd, stable, sign, iterations, arclength, max_gap, max_points, start_tol, max_time) -> np.ndarray:
    from explorer.analysis.manifolds import grow_branch

    return grow_branch(sd, stable=stable, sign=sign, arclength=math.inf if arclength is None else arclength,
                       generations=iterations, max_gap=max_gap, max_points=max_points, start_tol=start_tol,
                       max_time=max_time).points


@system_first
def manifold(system, fp: FixedPoint, *, stable=False, branch=1, iterations=SEPARATRIX_GENERATIONS,
             arclength=None, max_gap=DEFAULT_MAX_GAP, max_points=20000, start_tol=DEFAULT_START_TOL,
             max_time=None) -> np.ndarray:
    """One branch (``branch`` +1 or -1 along the eigenvector, oriented as
    :class:`~explorer.analysis.manifolds.Saddle`) of the unstable (``stable``: stable, backward
    in time) manifold of a hyperbolic fixed point ``fp`` of the map ``system``, as an (M, 2)
    polyline on the section from the fixed point outwards: ``iterations`` images of the
    fundamental domain, or less when ``arclength`` (default: none) comes first, grown by
    :func:`explorer.analysis.manifolds.grow_branch` (its ``max_gap``, ``max_points``,
    ``start_tol`` and ``max_time``)."""
    return _grown(_saddle_of(system, fp), stable, branch, iterations, arclength, max_gap,
                  max_points, start_tol, max_time)


@system_first
def separatrices(system, fp: FixedPoint, *, iterations=SEPARATRIX_GENERATIONS, arclength=None,
                 max_gap=DEFAULT_MAX_GAP, max_points=20000, start_tol=DEFAULT_START_TOL,
                 max_time=None) -> list:
    """The four branches (unstable +-, stable +-) of the hyperbolic fixed point ``fp`` of the map
    ``system`` as a list of (M, 2) polylines (:func:`manifold`, whose options these are; one
    saddle, its eigen-decomposition shared by the four)."""
    sd = _saddle_of(system, fp)
    return [_grown(sd, s, b, iterations, arclength, max_gap, max_points, start_tol, max_time)
            for s in (False, True) for b in (1, -1)]


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
