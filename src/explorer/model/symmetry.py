"""Discrete symmetries of the reduced system R3 and what they do to the Poincaré section.

Plain numpy on states ``y = (p1, p2, M, g1, g2)`` with ``(g1, g2) = (sin phi, cos phi)``
(docs/model.md R3).  Derivation and consequences: docs/model.md, "Symmetries".

- G, the reflection: (p1, p2, M, phi, t) -> (p1, -p2, M, -phi, -t), reversing; a symmetry
  exactly when zeta = 0 and mu xi = 0;
- K, the half-turn reversor: (p1, p2, M, phi, t) -> (-p1, p2, M, pi - phi, -t), reversing;
  exactly when chi = 0 and mu eta = 0;
- S = G K, the half-turn: (p1, p2, M, phi, t) -> (-p1, -p2, M, phi + pi, t), time kept;
  exactly when chi = zeta = 0 and mu xi = mu eta = 0.

G is the reflection p2 -> -p2 of the section phi = pi (``explorer.analysis.periodic.reversor``).
K, the half-turn reversor, maps the section phi = phi0 to phi = pi - phi0 (phi = pi to phi = 0)
keeping M, hence the crossing direction.  Followed by the flow from phi = pi - phi0 forward to
phi = phi0 it gives an involution T of the section phi0 that reverses the section map P:
T P = P^{-1} T (:func:`explorer.analysis.halfturn.partner_points`).  T maps a fixed point of P to
a fixed point with the same trace and the same return time, and a periodic orbit
x_0, ..., x_{K-1} to the periodic orbit T(x_{K-1}), ..., T(x_0) with the same trace of DP^K and
the same period (the sum of its return times).  For the Figure 4 scene (chi = zeta = xi = eta = 0) it pairs
the elliptic fixed points (-1.0444, 0) and (1.5711, 0) at mu = 0.1 (trace -0.1779019687, return
time 6.083720437 each); eta = 0.3 breaks the pairing.

Functions
---------
``half_turn_violations(params) -> list[str]``   the parameters that break K (empty: K holds)
``has_half_turn_symmetry(params, phi0=pi) -> bool``
``half_turn_section(phi0) -> float``            pi - phi0 in [0, 2 pi): where K maps phi = phi0
``half_turn_reversor(y) -> ndarray``             K on states (time reversed)
``half_turn(y) -> ndarray``                      S = G K on states (time kept)
"""
from __future__ import annotations

import math

import numpy as np

from explorer.model.parameters import CHI, ETA, MU, packed_params
from explorer.model.validation import ParameterError

__all__ = ["half_turn", "half_turn_reversor", "half_turn_section", "half_turn_violations", "has_half_turn_symmetry"]

#: K on (p1, p2, M, g1, g2): p1 -> -p1, g2 = cos phi -> cos(pi - phi) = -g2
K_SIGNS = np.array([-1.0, 1.0, 1.0, 1.0, -1.0])
#: S = G K on (p1, p2, M, g1, g2): p -> -p, gamma -> -gamma (phi -> phi + pi)
S_SIGNS = np.array([-1.0, -1.0, 1.0, -1.0, -1.0])


def half_turn_violations(params) -> list[str]:
    """The parameters that keep the half-turn reversor K from being a symmetry of R3, each as
    ``"name = value"`` (docs/model.md: K reverses R3 exactly when chi = 0 and mu eta = 0; zeta,
    xi, lam, a1, a2, b are free).  Empty when K holds."""
    P = packed_params(params)
    out = []
    if P[CHI] != 0.0:
        out.append(f"chi = {float(P[CHI])!r}")
    if P[MU] != 0.0 and P[ETA] != 0.0:
        out.append(f"eta = {float(P[ETA])!r} (with mu = {float(P[MU])!r})")
    return out


def has_half_turn_symmetry(params, phi0: float = math.pi) -> bool:
    """True when the half-turn reversor K (and with it the partner map T of the section
    phi = phi0) is a symmetry of R3: chi = 0 and mu eta = 0.  The condition does not depend
    on phi0 (any finite phi0: K maps the section phi0 to pi - phi0 and the flow brings it back)."""
    phi0 = float(phi0)
    if not math.isfinite(phi0):
        raise ParameterError(f"phi0 must be finite, got {phi0!r}")
    return not half_turn_violations(params)


def half_turn_section(phi0: float) -> float:
    """pi - phi0 reduced to [0, 2 pi): the section that K maps the section phi = phi0 to
    (phi = pi goes to phi = 0)."""
    return (math.pi - float(phi0)) % (2.0 * math.pi)


def half_turn_reversor(y) -> np.ndarray:
    """K(y) for states y (..., 5): (p1, p2, M, g1, g2) -> (-p1, p2, M, g1, -g2).  The orbit of
    K(y) is the orbit of y run backwards in time (when :func:`has_half_turn_symmetry`)."""
    return np.asarray(y, dtype=np.float64) * K_SIGNS


def half_turn(y) -> np.ndarray:
    """S(y) = G(K(y)) for states y (..., 5): (p1, p2, M, g1, g2) -> (-p1, -p2, M, -g1, -g2),
    phi -> phi + pi.  Maps orbits to orbits with time kept when chi = zeta = 0 and
    mu xi = mu eta = 0."""
    return np.asarray(y, dtype=np.float64) * S_SIGNS
