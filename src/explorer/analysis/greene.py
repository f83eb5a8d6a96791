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
from explorer.analysis.maps import SymmetricOrbit
from explorer.analysis.system_sections import is_system
from explorer.model import ParameterError, validation

__all__ = ["CRITICAL_RESIDUE", "GOLDEN", "GreeneResult", "SymmetricOrbit", "convergents", "greene",
           "rotation_value", "symmetric_orbit"]


def symmetric_orbit(system, p, q, *, line=math.pi, guess=None):
    """The symmetric orbit of type ``p``/``q`` through theta = ``line``, Newton from p = ``guess``
    (default 2 pi p/q).  A section map: :func:`~explorer.analysis.greene_section.section_symmetric_orbit`
    of period ``q`` from p1 = ``guess`` (required)."""
    if hasattr(system, "half_turns"):       # a section map: shot over half turns
        if guess is None:
            raise ParameterError("symmetric_orbit on a section map needs guess=t, the point t v of the symmetry "
                                 "line (p1 of p2 = 0 on Chaplygin's section) near the orbit")
        validation.integer("p", p, 0)
        return greene_section.section_symmetric_orbit(system, validation.integer("q", q, 1),
                                                      validation.real("guess", guess),
                                                      line=None if line == math.pi else line)
    shoot = getattr(system, "symmetric_orbit", None)
    if shoot is None:
        raise ParameterError(f"symmetric_orbit: the half-orbit method is implemented for StandardMap and a "
                             f"section map (with a reversor); got {type(system).__name__}")
    return shoot(p, q, line=line, guess=guess)


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
    if hasattr(system, "half_turns"):       # a section map: shot over half turns
        return greene_section.section_greene(system, x, qmax=qmax, target=target, line=line, around=around,
                                             param=param)
    if not hasattr(system, "symmetric_orbit"):
        raise ParameterError(f"greene takes a StandardMap or a section map, got {type(system).__name__}")
    if around is not None or param not in (None, system.parameter):
        raise ParameterError("greene: around= and param= belong to a section map; the standard map's "
                             "parameter is k")
    conv = enough_convergents(x, DEFAULT_QMAX if qmax is None else qmax)
    line = math.pi if line is None else validation.real("line", line)

    def orbit_at(k, P, Q, guess, check):
        return system.with_parameter(k).symmetric_orbit(P, Q, line=line, guess=guess)

    rows, crit, uncertainty, ratio = critical_parameter(conv, orbit_at, lambda orb: orb.points[0, 1],
                                                        lambda orb: system.wrap(orb.points[0]),
                                                        system.parameter_value, target)
    return GreeneResult("standard", system.parameter, x, crit, uncertainty, rows, target, ratio, float(line))
