"""What a System's scene computes beside the crossings and indicators of its panels (docs/scenes.md,
"A scene of your own system"): the separatrices of the hyperbolic fixed points of a panel's section
map and the branches of its [manifolds] orbit."""
from __future__ import annotations

import numpy as np

from explorer.analysis.fixedpoints import FixedPoint, separatrices
from explorer.analysis.manifolds import manifolds
from explorer.analysis.periodic import find_periodic_orbit, search_periodic_orbits

#: side of the grid over the map's domain whose local minima of |P(x) - x| start Newton
SEARCH_GRID = 12
#: a separatrix's images of its fundamental domain and points at most (its arclength: the domain's diagonal)
SEPARATRIX_GENERATIONS = 40
SEPARATRIX_POINTS = 6000


def hyperbolic_fixed_points(smap, grid: int = SEARCH_GRID) -> list:
    """The hyperbolic, isolated fixed points of the section map ``smap`` that
    :func:`~explorer.analysis.periodic.search_periodic_orbits` finds from a ``grid`` x ``grid``
    grid over its domain, as :class:`~explorer.analysis.fixedpoints.FixedPoint` s."""
    return [FixedPoint.from_orbit(o) for o in search_periodic_orbits(smap, 1, grid=grid)
            if not o.stable and not o.degenerate]


def separatrix_curves(smap, *, grid: int = SEARCH_GRID, arclength=None, iterations: int = SEPARATRIX_GENERATIONS,
                      max_points: int = SEPARATRIX_POINTS) -> tuple:
    """(fixed points, curves): :func:`hyperbolic_fixed_points` of ``smap`` and the four branches of
    each as (M, 2) polylines (:func:`explorer.analysis.fixedpoints.separatrices`), each grown to
    ``arclength`` (None: the diagonal of the map's domain), ``iterations`` images of its fundamental
    domain or ``max_points``, whichever comes first."""
    if arclength is None:
        (a0, a1), (b0, b1) = smap.domain
        arclength = float(np.hypot(a1 - a0, b1 - b0))
    points = hyperbolic_fixed_points(smap, grid)
    return points, [c for fp in points for c in separatrices(smap, fp, arclength=arclength, iterations=iterations,
                                                             max_points=max_points)]


def orbit_branches(smap, spec) -> list:
    """[(kind, (M, 2) points)]: W^u and W^s at every point of the orbit of period ``spec.period``
    that Newton finds from ``spec.guess`` (a :class:`~explorer.io.scene.ManifoldSpec`), each branch
    to ``spec.arclength`` (:func:`explorer.analysis.manifolds.manifolds`); ParameterError when
    there is no such hyperbolic orbit."""
    orb = find_periodic_orbit(smap, spec.guess, spec.period)
    return [(b.kind, b.points) for j in range(orb.period)
            for b in manifolds(smap, orb, index=j, arclength=spec.arclength, max_points=spec.max_points)]
