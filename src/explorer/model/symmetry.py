"""Discrete symmetries of the reduced system R3 and what they do to the Poincaré section.

The maps G (reflection), K (half-turn reversor) and S = G K, their conditions and derivation:
docs/model.md, "Symmetries".  Plain numpy on states ``y = (p1, p2, M, g1, g2)`` with
``(g1, g2) = (sin phi, cos phi)`` (docs/model.md R3), or on section points ``(p1, p2)``.
"""
from __future__ import annotations

import math

import numpy as np

from explorer.model.parameters import CHI, ETA, MU, XI, ZETA, packed_params
from explorer.model.validation import ParameterError

__all__ = ["half_turn", "half_turn_reversor", "half_turn_section", "half_turn_violations", "has_half_turn_symmetry",
           "is_reversible", "reversor"]

#: K on (p1, p2, M, g1, g2): p1 -> -p1, g2 = cos phi -> cos(pi - phi) = -g2
K_SIGNS = np.array([-1.0, 1.0, 1.0, 1.0, -1.0])
#: S = G K on (p1, p2, M, g1, g2): p -> -p, gamma -> -gamma (phi -> phi + pi)
S_SIGNS = np.array([-1.0, -1.0, 1.0, -1.0, -1.0])


def is_reversible(params, phi0: float = math.pi) -> bool:
    """True when the reflection G reverses R3 with zeta = xi = 0 and maps the section
    phi = phi0 to itself (phi0 = 0 or pi mod 2 pi): then :func:`reversor` reverses the section
    map, G0 P G0 = P^-1 (docs/model.md, "Symmetries")."""
    P = packed_params(params)
    on_line = abs(math.sin(phi0)) < 1e-15 or phi0 == math.pi
    return bool(P[ZETA] == 0.0 and P[XI] == 0.0 and on_line)


def reversor(x) -> np.ndarray:
    """G0(p1, p2) = (p1, -p2), the involution G induces on the section, on points (..., 2)."""
    y = np.array(x, dtype=float, copy=True)
    y[..., 1] = -y[..., 1]
    return y


def half_turn_violations(params) -> list[str]:
    """The parameters that keep K from being a symmetry of R3 (chi = 0 and mu eta = 0 needed,
    docs/model.md, "Symmetries"), each as ``"name = value"``; empty when K holds."""
    P = packed_params(params)
    out = []
    if P[CHI] != 0.0:
        out.append(f"chi = {float(P[CHI])!r}")
    if P[MU] != 0.0 and P[ETA] != 0.0:
        out.append(f"eta = {float(P[ETA])!r} (with mu = {float(P[MU])!r})")
    return out


def has_half_turn_symmetry(params, phi0: float = math.pi) -> bool:
    """True when K, and with it the partner map T of the section phi = phi0, is a symmetry of R3;
    the condition does not depend on the (finite) ``phi0``."""
    phi0 = float(phi0)
    if not math.isfinite(phi0):
        raise ParameterError(f"phi0 must be finite, got {phi0!r}")
    return not half_turn_violations(params)


def half_turn_section(phi0: float) -> float:
    """pi - phi0 in [0, 2 pi): the section K maps phi = phi0 to."""
    return (math.pi - float(phi0)) % (2.0 * math.pi)


def half_turn_reversor(y) -> np.ndarray:
    """K(y) on states (..., 5): (p1, p2, M, g1, g2) -> (-p1, p2, M, g1, -g2), time reversed."""
    return np.asarray(y, dtype=np.float64) * K_SIGNS


def half_turn(y) -> np.ndarray:
    """S(y) = G(K(y)) on states (..., 5): (p1, p2, M, g1, g2) -> (-p1, -p2, M, -g1, -g2), time kept."""
    return np.asarray(y, dtype=np.float64) * S_SIGNS
