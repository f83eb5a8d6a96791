"""Greene's residue criterion (docs/greene.md): :func:`greene` and :func:`symmetric_orbit`, which ask the
map for its symmetric orbits: a section map's half turns ("Greene on a System"), the standard map's
half-orbit method ("The half-orbit (symmetry-line) method")."""
from __future__ import annotations

import math

from explorer.analysis import greene_section
from explorer.analysis.greene_core import (
    CRITICAL_RESIDUE,
    DEFAULT_QMAX,
    GOLDEN,
    GreeneResult,
    convergents,
    critical_parameter,
    enough_convergents,
    rotation_value,
)
from explorer.analysis.maps import SymmetricOrbit, has_angle, reduce
from explorer.analysis.system_sections import is_system
from explorer.model import ParameterError, validation

__all__ = ["CRITICAL_RESIDUE", "GOLDEN", "GreeneResult", "SymmetricOrbit", "convergents", "greene",
           "rotation_value", "symmetric_orbit"]


def symmetric_orbit(system, p, q, *, line=None, guess=None):
    """The map's symmetric orbit of type ``p``/``q`` on its symmetry line ``line`` from ``guess`` (its
    ``symmetric_orbit``): the standard map's half-orbit method on theta = ``line`` (default pi), Newton from
    p = ``guess`` (default 2 pi p/q); a section map's shot over its half turns from ``guess`` (required) on
    the half ``line`` (default its own)."""
    return system.symmetric_orbit(p, q, line=line, guess=guess)


def greene(system, nu="golden", *, qmax=None, residue=CRITICAL_RESIDUE, line=None, around=None,
           param=None) -> GreeneResult:
    """The parameter at which the curve of rotation number ``nu`` breaks (docs/greene.md, "The
    criterion"), from ``system``'s parameter value as first guess, the convergents up to ``qmax``
    (default :data:`~explorer.analysis.greene_core.DEFAULT_QMAX` or ``SECTION_QMAX``) and the
    symmetry line ``line``; ``around`` and ``param``: a section map's island and parameter
    (:func:`~explorer.analysis.greene_section.section_greene`)."""
    x = rotation_value(nu)
    target = validation.real("residue", residue, 0.0, 1.0, lo_open=True, hi_open=True)
    if is_system(system):
        raise ParameterError("greene takes a map: give the System's section map, SectionMap(system, E, section=..., "
                             "direction=..., coords=..., solve=...), with a reversor (System(..., reversor=...))")
    if not has_angle(system):
        # no angle coordinate: an orbit's type is counted by its turns around the island's centre
        return greene_section.section_greene(system, x, qmax=qmax, target=target, line=line, around=around,
                                             param=param)
    if around is not None or param not in (None, system.parameter):
        raise ParameterError("greene: around= and param= belong to a section map; the standard map's "
                             "parameter is k")
    conv = enough_convergents(x, DEFAULT_QMAX if qmax is None else qmax)
    line = math.pi if line is None else validation.real("line", line)

    def orbit_at(k, P, Q, guess, check):
        return system.with_parameter(k).symmetric_orbit(P, Q, line=line, guess=guess)

    rows, crit, uncertainty, ratio = critical_parameter(conv, orbit_at, lambda orb: orb.points[0, 1],
                                                        lambda orb: reduce(system, orb.points[0]),
                                                        system.parameter_value, target)
    return GreeneResult("standard", system.parameter, x, crit, uncertainty, rows, target, ratio, float(line))
