"""Partner points of the section under the half-turn reversor (docs/model.md, "Symmetries").

When chi = 0 and mu eta = 0 (:func:`explorer.model.symmetry.has_half_turn_symmetry`) the map
K: (p1, p2, M, phi, t) -> (-p1, p2, M, pi - phi, -t) reverses R3.  The partner of a point x of
the section phi = phi0 is T(x): K(x), on the section phi = pi - phi0, carried by the flow forward
to its next crossing of phi = phi0 (half a turn of phi for phi0 = pi).  T is an involution and
reverses the section map P (T P = P^{-1} T), so

- a fixed point x of P has the fixed point T(x) as partner, with the same trace of DP and the same
  return time (the orbit of T(x) is the orbit of x run backwards and turned by K);
- a periodic orbit x_0, ..., x_{K-1} (x_{i+1} = P(x_i)) has the partner orbit
  T(x_{K-1}), ..., T(x_0) (P T(x_i) = T(x_{i-1})), with the same trace of DP^K and the same period
  (sum of the return times; each single return time of the partner is a time between two
  crossings of phi = pi - phi0 of the original, in reverse order);
- an orbit with T(x) on itself is half-turn symmetric (its own partner).

``partner_points`` integrates with the Taylor method (tol 1e-15 by default) through
:func:`explorer.analysis.sections.crossings`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.analysis.section_map import system_first
from explorer.integrate.methods import MAP_TOL
from explorer.model import ParameterError, symmetry

__all__ = ["DEFAULT_TOL", "Partners", "partner_points"]

#: Taylor tolerance of the half-turn flow
DEFAULT_TOL = MAP_TOL
#: time budget of the half-turn flow, per point
TMAX = 1e3
#: |pi - 2 phi0| (mod 2 pi) below which K maps the section phi0 to itself
SAME_SECTION = 1e-15


@dataclass(frozen=True)
class Partners:
    """Result of :func:`partner_points` for n points: the partner ``points`` (n, 2), the ``times``
    (n,) of the flow from K(x) to the section (NaN where it did not get there) and the ``status``
    name of each flow."""

    points: np.ndarray
    times: np.ndarray
    status: tuple


@system_first(settings=("phi0", "tol"))
def partner_points(system, points, *, threads: int | None = None) -> Partners:
    """The partners T(x) of the points x = (p1, p2) ((2,) or (n, 2)) of the section phi = phi0 at
    energy h (crossed with dphi/dt > 0) under the half-turn reversor (module docstring).

    Raises ParameterError naming the parameters when the half-turn is not a symmetry
    (chi != 0, or eta != 0 with mu != 0), or the point when it is outside the allowed region.
    A point whose flow does not reach the section within the time budget gets NaN and its status.
    """
    from explorer.analysis.sections import crossings

    params, h, phi0, tol = system.params, system.h, system.phi0, system.tol
    bad = symmetry.half_turn_violations(params)
    if bad:
        raise ParameterError(f"the half-turn is a symmetry only when chi = 0 and mu eta = 0; here {', '.join(bad)}")
    x = np.atleast_2d(np.asarray(points, dtype=np.float64))
    if x.ndim != 2 or x.shape[1] != 2:
        raise ParameterError(f"points must be (p1, p2) or an (n, 2) array, got shape {np.shape(points)}")
    y = symmetry.half_turn_reversor(model.section_state(params, x[:, 0], x[:, 1], h, phi0))
    image = symmetry.half_turn_section(phi0)
    if abs(math.remainder(image - phi0, 2.0 * math.pi)) < SAME_SECTION:
        # K maps the section to itself (phi0 = pi/2 or 3 pi/2): T = K
        return Partners(y[:, :2].copy(), np.zeros(len(x)), ("done",) * len(x))
    c = crossings(params, states=y, n_crossings=1, phi0=phi0, tol=tol, threads=threads, tmax=TMAX)
    return Partners(c.data[:, 0, 1:3].copy(), c.data[:, 0, 0].copy(), tuple(c.status_name(i) for i in range(len(x))))
