"""Greene's residue criterion on a section map with a linear reversor G (docs/greene.md, "Greene on
the section of Figure 4's scene"; a System's map: "Greene on a System"): the symmetric orbits of each
type around the island's centre on the symmetry line of the map's half or its opposite's ("Two symmetry
lines"; shot over half turns, :func:`explorer.analysis.symmetry_lines.section_symmetric_orbit`), and
:func:`section_greene`."""
from __future__ import annotations

import math

import numpy as np

from explorer.analysis.fixedpoints import find_fixed_point
from explorer.analysis.greene_core import SECTION_QMAX, GreeneResult, critical_parameter, enough_convergents
from explorer.analysis.symmetry_lines import (
    SectionSymmetricOrbit,
    axes,
    line_map,
    line_point,
    line_roots,
    section_symmetric_orbit,
)
from explorer.model import ParameterError, validation

__all__ = ["SectionSymmetricOrbit", "first_orbit", "island_centre", "island_line", "section_greene",
           "section_symmetric_orbit"]

#: an orbit of type P/Q turns P/Q per return around the centre to this (times Q)
ROTATION_TOL = 1e-6
#: samples of the symmetry line scanned for the first convergent's orbit
LINE_SAMPLES = 200


def _typed_orbits(smap, P: int, Q: int, centre, line, side: int):
    """(distance, orbit) of the symmetric orbits of type P/Q around ``centre`` on the half ``line``, nearest
    first, scanned from the centre towards smaller (``side`` 0) or larger t (docs/greene.md, "Which orbits")."""
    other = line_map(smap, line)
    _, v, _ = axes(other)
    ts = other.symmetry_line_points(LINE_SAMPLES) @ v
    if not ts.size:
        raise ParameterError("the symmetry line has no point in the map's domain")
    turn = -1.0 if smap.jacobian(centre)[1, 0] < 0 else 1.0
    x0 = float(line_point(smap, centre, other.section_label) @ v)
    end = float(ts.max() if side else ts.min())
    for root in sorted(line_roots(other, Q, x0, end, LINE_SAMPLES), key=lambda r: abs(r - x0)):
        try:
            orb = section_symmetric_orbit(smap, Q, root, line=other.section_label)
            turns = orb.rotation(smap, centre)
        except ParameterError:
            continue
        if abs(turns * Q - turn * P) < 1e-6:
            yield abs(root - x0), orb


def first_orbit(smap, P: int, Q: int, centre, line=None) -> SectionSymmetricOrbit:
    """The symmetric orbit of type P/Q with a positive residue nearest to ``centre`` on the half ``line``
    (default the map's own; docs/greene.md, "Which orbits")."""
    best = None
    label = smap.section_label if line is None else line
    for side in (0, 1):
        dist, orb = next(((d, o) for d, o in _typed_orbits(smap, P, Q, centre, label, side) if o.residue > 0),
                         (math.inf, None))
        if orb is not None and (best is None or dist < best[0]):
            best = (dist, orb)
    if best is None:
        raise ParameterError(f"no symmetric orbit of type {P}/{Q} with a positive residue around "
                             f"({centre[0]:.6g}, {centre[1]:.6g}) on the symmetry line of the half {label:g} at "
                             f"{smap.parameter} = {smap.parameter_value:.8g}")
    return best[1]


def island_line(smap, P: int, Q: int, centre):
    """(line, orbit): the half (the map's or its opposite's) whose symmetry line holds the island's elliptic
    orbits of even period Q around ``centre``, and the orbit of type P/Q that decided it (docs/greene.md,
    "Two symmetry lines")."""
    if Q % 2:
        raise ParameterError(f"island_line needs an even period (an orbit of odd period meets both lines), got {Q}")
    found = [next(_typed_orbits(smap, P, Q, centre, smap.section_label, side), None) for side in (0, 1)]
    nearest = min((f for f in found if f is not None), key=lambda t: t[0], default=None)
    if nearest is None:
        raise ParameterError(f"no symmetric orbit of type {P}/{Q} around ({centre[0]:.6g}, {centre[1]:.6g}) on "
                             f"the symmetry line of the half {smap.section_label:g}: the line of the island's "
                             "elliptic orbits is not decided")
    orb = nearest[1]
    return (smap.section_label if orb.residue > 0 else smap.opposite().section_label), orb


def island_centre(smap, guess) -> np.ndarray:
    """The elliptic fixed point of ``smap`` near ``guess``."""
    fp = find_fixed_point(smap, tuple(float(v) for v in guess))
    if not fp.stable:
        raise ParameterError(f"the fixed point near ({guess[0]:.6g}, {guess[1]:.6g}) is not elliptic "
                             f"(trace {fp.trace:.6g}) at {smap.parameter} = {smap.parameter_value:.6g}: Greene's "
                             f"curves surround an elliptic one; start from a parameter where it is")
    return np.asarray(fp.point, float)


def _section_line(smap, conv, centre, line):
    """(line, the first convergent's orbit if the decision found it): ``line`` if given, else
    :func:`island_line` of the first even convergent (the map's own when all are odd)."""
    if line is not None:
        return line_map(smap, validation.real("line", line)).section_label, None
    even = [(P, Q) for P, Q in conv if Q % 2 == 0]
    if not even:
        return smap.section_label, None
    value, orb = island_line(smap, *even[0], centre)
    return value, (orb if value == smap.section_label and even[0] == conv[0] else None)


def section_greene(smap, nu: float, *, qmax=None, target, line=None, around=None, param=None):
    """:func:`explorer.greene` on a section map with a linear reversor (docs/greene.md, "Greene on the
    section of Figure 4's scene"): the curve ``nu`` around the elliptic fixed point near ``around``,
    broken by ``param`` (default the map's :attr:`parameter`; its value in ``smap`` is the first guess);
    points on ``smap``'s section."""
    axes(smap)
    if around is None:
        raise ParameterError("greene on a section map needs around=(a, b), a guess of the island's elliptic "
                             "fixed point")
    pname = smap.parameter if param is None else param
    first = smap.value_of(pname)
    conv = enough_convergents(nu, SECTION_QMAX if qmax is None else qmax)
    centre = island_centre(smap, around)
    line, seed = _section_line(smap, conv, centre, line)

    typed = set()      # the convergents whose orbit was checked once; the first guess is the previous one's

    def orbit_at(value, P, Q, guess, check):
        m = smap.with_parameter(value, pname)
        if guess is None:
            if seed is not None and value == first and (P, Q) == conv[0]:
                return seed
            typed.add((P, Q))
            return first_orbit(m, P, Q, island_centre(m, centre), line)
        try:
            orb = section_symmetric_orbit(m, Q, guess, param=pname, line=line)
            rot = orb.rotation(m, island_centre(m, centre)) if check or (P, Q) not in typed else P / Q
        except ParameterError:
            if check or (P, Q) in typed:
                raise
            rot = math.nan
        if abs(abs(rot) * Q - P) > ROTATION_TOL or not math.isfinite(rot):
            if check:
                raise ParameterError(f"the symmetric orbit of period {Q} near {orb.line_start:.8g} turns {rot:.8g} "
                                     f"per return around the centre, not {P}/{Q}")
            if (P, Q) not in typed:
                typed.add((P, Q))
                return first_orbit(m, P, Q, island_centre(m, centre), line)
        typed.add((P, Q))
        return orb

    rows, crit, uncertainty, ratio = critical_parameter(conv, orbit_at, lambda orb: orb.line_start,
                                                        lambda orb: orb.points[0], first, target)
    return GreeneResult("section", pname, nu, crit, uncertainty, rows, target, ratio, float(line))
