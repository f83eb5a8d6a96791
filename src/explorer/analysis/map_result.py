"""What one application of a section map returns (docs/greene.md, "The map protocol"), and the time
budget of one return; below both section maps (Chaplygin's and a System's)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["RETURN_TMAX", "MapResult"]

#: time budget of one return of a section map
RETURN_TMAX = 1e3


@dataclass(frozen=True)
class MapResult:
    """One application of the section map."""

    point: np.ndarray
    jacobian: np.ndarray   # None when not asked for
    time: float            # signed return time
    state: np.ndarray      # the state at the crossing ((p1, p2, M, g1, g2) in Chaplygin's model)
