"""What one application of a section map returns (docs/greene.md, "The map protocol"), the time
budget of one return, and what every section map of a flow answers alike; below both section maps
(Chaplygin's and a System's)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from explorer.model import ParameterError

__all__ = ["RETURN_TMAX", "FlowSection", "MapResult"]

#: time budget of one return of a section map
RETURN_TMAX = 1e3


@dataclass(frozen=True)
class MapResult:
    """One application of the section map."""

    point: np.ndarray
    jacobian: np.ndarray   # None when not asked for
    time: float            # signed return time
    state: np.ndarray      # the state at the crossing ((p1, p2, M, g1, g2) in Chaplygin's model)


class FlowSection:
    """The answers of the map protocol that any section map of a flow gives alike (docs/architecture.md,
    "The map protocol")."""

    def own_indicators(self, points, settings: dict):
        """None: the map's chaos indicators are its flow's (:func:`explorer.indicators` integrates them)."""
        return None

    def generating_function(self, theta, theta_next):
        """None known: ParameterError (a section of a flow, not a twist map given by its generating function)."""
        raise ParameterError(f"{self!r} has no generating function: it is the section map of a flow, not a twist "
                             "map given by F(theta, theta') (docs/greene.md)")
