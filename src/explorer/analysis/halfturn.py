"""Partner points of the section under the half-turn reversor T (docs/model.md, "Symmetries";
docs/commands/periodic.md, "Half-turn partners")."""
from __future__ import annotations

from explorer.analysis.section_map import system_first
from explorer.analysis.section_symmetry import Partners, half_turn_partners
from explorer.integrate.methods import MAP_TOL

__all__ = ["DEFAULT_TOL", "Partners", "partner_points"]

#: Taylor tolerance of the half-turn flow
DEFAULT_TOL = MAP_TOL


@system_first(settings=("phi0", "tol"))
def partner_points(system, points, *, threads: int | None = None) -> Partners:
    """The partners T(x) of the points x = (p1, p2) ((2,) or (n, 2)) of the section phi = phi0 at
    energy h (crossed with dphi/dt > 0) under the half-turn reversor
    (:func:`explorer.analysis.section_symmetry.half_turn_partners`)."""
    return half_turn_partners(system, points, threads)
