"""Partner points of the section under the half-turn reversor T (docs/model.md, "Symmetries";
docs/commands/periodic.md, "Half-turn partners")."""
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
    energy h (crossed with dphi/dt > 0) under the half-turn reversor (module docstring)."""
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
