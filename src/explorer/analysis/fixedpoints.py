"""Fixed points of the section map (periodic orbits of period 1), their continuation and their
separatrices (docs/commands/fixedpoint.md)."""
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


@dataclass(frozen=True, repr=False)
class FixedPoint(PeriodicOrbit):
    """The :class:`~explorer.analysis.periodic.PeriodicOrbit` of period 1, with ``point`` and ``return_time``."""

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


@system_first(systems="map")
def find_fixed_point(system, guess=(0.0, 0.0)) -> FixedPoint:
    """The fixed point Newton's method finds from ``guess``: :func:`~explorer.analysis.periodic.find_periodic_orbit`
    with K = 1 (docs/commands/fixedpoint.md)."""
    from explorer.analysis.periodic import find_periodic_orbit

    return FixedPoint.from_orbit(find_periodic_orbit(system, guess, 1))


@dataclass(frozen=True)
class Branch(PeriodicBranch):
    """The :class:`~explorer.analysis.periodic.PeriodicBranch` of period 1, its orbits :class:`FixedPoint` s."""


@system_first(systems="map")
def continue_branch(system, parameter, start, stop, step, guess=(0.0, 0.0), *, bisect_tol=1e-8) -> Branch:
    """:func:`~explorer.analysis.periodic.continue_periodic` with K = 1."""
    from explorer.analysis.periodic import continue_periodic

    br = continue_periodic(system, 1, parameter, start, stop, step, guess, bisect_tol=bisect_tol)
    return Branch(parameter, 1, br.values, [FixedPoint.from_orbit(o) for o in br.orbits], br.bifurcations,
                  br.stopped)


#: the images of the fundamental domain a separatrix is drawn to, by default
SEPARATRIX_GENERATIONS = 6


def _saddle_of(system, fp: FixedPoint):
    """The :class:`~explorer.analysis.manifolds.Saddle` of the hyperbolic fixed point ``fp``."""
    from explorer.analysis.manifolds import saddle

    if fp.stable:
        raise ParameterError("the fixed point is elliptic: it has no separatrices")
    return saddle(system, fp)


def _grown(sd, stable, sign, iterations, arclength, max_gap, max_points, start_tol, max_time) -> np.ndarray:
    from explorer.analysis.manifolds import grow_branch

    return grow_branch(sd, stable=stable, sign=sign, arclength=math.inf if arclength is None else arclength,
                       generations=iterations, max_gap=max_gap, max_points=max_points, start_tol=start_tol,
                       max_time=max_time).points


@system_first(systems="map")
def manifold(system, fp: FixedPoint, *, stable=False, branch=1, iterations=SEPARATRIX_GENERATIONS,
             arclength=None, max_gap=DEFAULT_MAX_GAP, max_points=20000, start_tol=DEFAULT_START_TOL,
             max_time=None) -> np.ndarray:
    """Branch ``branch`` (+1 or -1) of W^u (W^s with ``stable``) of the hyperbolic fixed point
    ``fp``: an (M, 2) polyline of ``iterations`` images of the fundamental domain, or to
    ``arclength``, by :func:`explorer.analysis.manifolds.grow_branch`."""
    return _grown(_saddle_of(system, fp), stable, branch, iterations, arclength, max_gap,
                  max_points, start_tol, max_time)


@system_first(systems="map")
def separatrices(system, fp: FixedPoint, *, iterations=SEPARATRIX_GENERATIONS, arclength=None,
                 max_gap=DEFAULT_MAX_GAP, max_points=20000, start_tol=DEFAULT_START_TOL,
                 max_time=None) -> list:
    """The four branches (unstable +-, stable +-) of ``fp`` as (M, 2) polylines (:func:`manifold`)."""
    sd = _saddle_of(system, fp)
    return [_grown(sd, s, b, iterations, arclength, max_gap, max_points, start_tol, max_time)
            for s in (False, True) for b in (1, -1)]


def analytic_eigenvalues_solution_I(params, h):
    """(eigenvalues, trace) of solution I's monodromy at mu = 0, linearised (docs/model.md R6/R9)."""
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


@system_first(systems="map")
def follow(system, parameter, start, stop, guess, *, max_step=0.25) -> FixedPoint:
    """The fixed point at ``parameter = stop`` on the branch through ``guess`` at ``start``."""
    if start == stop:
        from explorer.analysis.maps import with_value

        return find_fixed_point(with_value(system, parameter, start), guess)
    n = max(1, math.ceil(abs(stop - start) / max_step))
    br = continue_branch(system, parameter, start, stop, (stop - start) / n, guess)
    if br.stopped is not None:
        raise ParameterError(f"the fixed point could not be followed to {parameter} = {stop:.10g}: {br.stopped}")
    return br.orbits[-1]
