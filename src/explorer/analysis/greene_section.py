"""Greene's residue criterion on a section map (docs/greene.md, "Greene on the section of Figure 4's
scene"): symmetric orbits shot over Q half-turns of phi from a symmetry line p2 = 0 (of phi0 or
phi0 + pi, "Two symmetry lines"), their monodromy M = G0 B^-1 G0 A from the first half's Jacobians,
and :func:`section_greene`."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.analysis import budget
from explorer.analysis.fixedpoints import find_fixed_point
from explorer.analysis.greene_core import SECTION_QMAX, GreeneResult, Residue, critical_parameter, enough_convergents
from explorer.analysis.section_map import MAX_STEPS, SectionMap
from explorer.integrate.tangent import return_map_taylor
from explorer.kernels import STATUS_DONE
from explorer.model import ParameterError, validation

__all__ = ["SectionSymmetricOrbit", "first_orbit", "half_turn_p2", "island_centre", "island_line",
           "line_map", "line_point", "line_roots", "section_greene", "section_symmetric_orbit"]

#: an orbit of type P/Q turns P/Q per return around the centre to this (times Q)
ROTATION_TOL = 1e-6
PARAM_NAMES_AND_H = (*model.PARAM_NAMES, "h")
#: the reversor on the section: G0 P G0 = P^-1
G0 = np.diag([1.0, -1.0])
SECANT_TOL, SECANT_MAX_ITER = 1e-13, 40
#: samples of the line p2 = 0 scanned for the first convergent's orbit, and the scan's distance from
#: the allowed region's edge (a fraction of its half-width)
LINE_SAMPLES, EDGE_MARGIN = 200, 1e-3


def line_map(smap: SectionMap, line) -> SectionMap:
    """``smap`` on the section phi = ``line`` (``smap`` itself when ``line`` is None or its phi0)."""
    if line is None or _same_phi(line, smap.phi0):
        return smap
    return SectionMap(smap.params, smap.h, phi0=float(line), tol=smap.tol, tmax=smap.tmax)


def _same_phi(a, b) -> bool:
    return abs(math.remainder(float(a) - float(b), 2.0 * math.pi)) < 1e-12


def _flow_to(smap: SectionMap, y, phi) -> np.ndarray:
    """The state y carried by the flow to its next crossing of phi = ``phi`` (dphi/dt > 0)."""
    out = np.empty(5)
    g1, g2 = model.section_gamma(phi)
    status, _ = return_map_taylor(np.asarray(y, float), np.zeros((0, 5)), smap.P, g2, g1, 1.0, smap.tmax, smap.order,
                                  MAX_STEPS, budget.stop_switch(), out, np.zeros((0, 5)))
    if status != STATUS_DONE:
        raise ParameterError(f"the flow from p1 = {y[0]:.10g} on phi = {math.atan2(y[3], y[4]) % (2 * math.pi):.6g} "
                             f"did not reach the section phi = {phi:.6g}")
    return out


def line_point(smap: SectionMap, x, line) -> np.ndarray:
    """Where the flow from ``smap``'s point x next crosses the section phi = ``line`` (x on its own)."""
    if _same_phi(line, smap.phi0):
        return np.asarray(x, float).copy()
    return _flow_to(smap, smap.state(x), float(line))[:2].copy()


def half_turn_p2(smap: SectionMap, p1: float, Q: int, line=None) -> float:
    """p2 after Q half-turns of phi from (p1, 0) on phi = ``line`` (default phi0); NaN if not reached."""
    start = smap.phi0 if line is None else float(line)
    try:
        y = model.section_state(smap.params, [p1], [0.0], smap.h, start)[0]
    except ParameterError:
        return math.nan
    none = np.zeros((0, 5))
    out = np.empty(5)
    sections = (model.section_gamma((start + math.pi) % (2.0 * math.pi)), model.section_gamma(start))
    stop = budget.stop_switch()
    for j in range(Q):
        g1, g2 = sections[j % 2]
        status, _ = return_map_taylor(y, none, smap.P, g2, g1, 1.0, smap.tmax, smap.order, MAX_STEPS, stop, out,
                                      np.zeros((0, 5)))
        if status != STATUS_DONE:
            return math.nan
        y = out.copy()
    return float(y[1])


def line_roots(smap: SectionMap, Q: int, a: float, b: float, n: int, line=None) -> list:
    """The starts p1 in [a, b] on p2 = 0 of phi = ``line`` of the symmetric orbits of period Q (or a
    divisor): the sign changes of :func:`half_turn_p2` over n + 1 samples, refined by the secant."""
    xs = np.linspace(a, b, n + 1)
    fs = np.array([half_turn_p2(smap, x, Q, line) for x in xs])
    roots = []
    for i in np.flatnonzero(np.isfinite(fs[:-1]) & np.isfinite(fs[1:]) & (np.sign(fs[:-1]) != np.sign(fs[1:]))):
        try:
            roots.append(_secant(smap, Q, xs[i], xs[i + 1], fs[i], fs[i + 1], line))
        except ParameterError:
            continue
    return roots


def _secant(smap, Q, x0, x1, f0=None, f1=None, line=None) -> float:
    """A root of :func:`half_turn_p2` by the secant method from x0, x1."""
    f0 = half_turn_p2(smap, x0, Q, line) if f0 is None else f0
    f1 = half_turn_p2(smap, x1, Q, line) if f1 is None else f1
    for _ in range(SECANT_MAX_ITER):
        if not (math.isfinite(f0) and math.isfinite(f1)) or f1 == f0:
            break
        x2 = x1 - f1 * (x1 - x0) / (f1 - f0)
        if abs(x2 - x1) <= SECANT_TOL * max(1.0, abs(x1)) or f1 == 0.0:
            return float(x2)
        f2 = half_turn_p2(smap, x2, Q, line)
        x0, f0, x1, f1 = x1, f1, x2, f2
    raise ParameterError(f"no symmetric orbit of period {Q} near p1 = {x1:.10g} (the half-turn equation "
                         f"did not converge)")


@dataclass(frozen=True)
class SectionSymmetricOrbit(Residue):
    """A symmetric periodic orbit of the section map: ``points`` (Q, 2) on the map's section,
    ``monodromy`` on the section of its symmetry line phi = ``line`` (the same trace), ``start`` its
    p1 on that line."""

    q: int
    points: np.ndarray
    monodromy: np.ndarray
    param_value: float
    line: float = math.pi
    start: float = math.nan

    @property
    def line_start(self) -> float:
        """p1 of the orbit's point on its symmetry line."""
        return float(self.points[0, 0]) if math.isnan(self.start) else self.start

    def rotation(self, smap: SectionMap, centre) -> float:
        """Turns around ``centre`` per return, in (-1/2, 1/2], from the increments lifted through the
        flow (docs/greene.md, "Which orbits")."""
        from explorer.analysis.rotation import _lifted_increments

        inc, _, status, _ = _lifted_increments(smap.params, smap.h, self.points[:1], np.asarray(centre, float),
                                               self.q, smap.phi0, smap.tol, None)
        if status[0] != "done":
            raise ParameterError(f"the rotation of the orbit of period {self.q} around the centre is not defined "
                                 f"({status[0]})")
        turns = float(np.sum(inc[0])) / (2.0 * math.pi * self.q)
        return turns - math.ceil(turns - 0.5)


def section_symmetric_orbit(smap: SectionMap, Q: int, guess, guess2=None, *, param=None,
                            line=None) -> SectionSymmetricOrbit:
    """The symmetric orbit of period Q through (p1, 0) on phi = ``line`` (default phi0), p1 by the secant
    from ``guess``, ``guess2``; points and monodromy from the first half (docs/greene.md, "Greene on
    the section of Figure 4's scene"; phi0 + pi: solved on that line's section, "Two symmetry lines")."""
    other = line_map(smap, line)
    if other is not smap:
        orb = section_symmetric_orbit(other, Q, guess, guess2, param=param)
        x0 = _flow_to(other, other.state(orb.points[0]), smap.phi0)[:2]
        pts = smap.iterate(x0, Q - 1) if Q > 1 else x0[None, :]
        return SectionSymmetricOrbit(Q, np.asarray(pts, float)[:Q].copy(), orb.monodromy, orb.param_value,
                                     other.phi0, float(orb.points[0, 0]))
    g = float(guess)
    p1 = _secant(smap, Q, g, g + 1e-7 * max(1.0, abs(g)) if guess2 is None else float(guess2))
    n = (Q + 1) // 2
    pts = np.empty((Q + 1, 2))
    pts[0] = (p1, 0.0)
    jacs = []
    for j in range(n):
        r = smap(pts[j])
        jacs.append(r.jacobian)
        pts[j + 1] = r.point
    for j in range(n + 1, Q + 1):
        pts[j] = G0 @ pts[Q - j]
    A = np.eye(2)
    B = np.eye(2)
    for j, J in enumerate(jacs):
        A = J @ A
        if j < Q - n:
            B = A.copy()
    if Q % 2 == 0:
        B = A
    det = B[0, 0] * B[1, 1] - B[0, 1] * B[1, 0]
    if not (np.all(np.isfinite(A)) and math.isfinite(det) and det != 0.0):
        raise ParameterError(f"the half orbit's Jacobian of the orbit of period {Q} from p1 = {p1:.10g} is singular "
                             f"or not finite")
    B_inv = np.array([[B[1, 1], -B[0, 1]], [-B[1, 0], B[0, 0]]]) / det
    M = G0 @ B_inv @ G0 @ A
    value = smap.parameter_value if param is None else float(getattr(smap.params, param)) if param != "h" else smap.h
    return SectionSymmetricOrbit(Q, pts[:Q].copy(), M, value, smap.phi0, float(p1))


def _typed_orbits(smap: SectionMap, P: int, Q: int, centre, line, side: int):
    """(distance, orbit) of the symmetric orbits of type P/Q around ``centre`` on phi = ``line``, nearest
    first, scanned from the centre towards smaller (``side`` 0) or larger p1 (docs/greene.md, "Which orbits")."""
    other = line_map(smap, line)
    e = model.allowed_ellipse(other.params, other.h, other.phi0)
    if e is None:
        raise ParameterError("the allowed region is empty")
    c1, c2, r1, r2 = e
    half = r1 * math.sqrt(max(0.0, 1.0 - (c2 / r2) ** 2)) * (1.0 - EDGE_MARGIN)
    turn = -1.0 if smap.jacobian(centre)[1, 0] < 0 else 1.0
    x0 = float(line_point(smap, centre, other.phi0)[0])
    end = c1 + half if side else c1 - half
    for root in sorted(line_roots(other, Q, x0, end, LINE_SAMPLES), key=lambda r: abs(r - x0)):
        try:
            orb = section_symmetric_orbit(smap, Q, root, line=other.phi0)
            turns = orb.rotation(smap, centre)
        except ParameterError:
            continue
        if abs(turns * Q - turn * P) < 1e-6:
            yield abs(root - x0), orb


def first_orbit(smap: SectionMap, P: int, Q: int, centre, line=None) -> SectionSymmetricOrbit:
    """The symmetric orbit of type P/Q with a positive residue nearest to ``centre`` on phi = ``line``
    (default phi0; docs/greene.md, "Which orbits")."""
    best = None
    for side in (0, 1):
        dist, orb = next(((d, o) for d, o in _typed_orbits(smap, P, Q, centre, smap.phi0 if line is None else line,
                                                          side) if o.residue > 0), (math.inf, None))
        if orb is not None and (best is None or dist < best[0]):
            best = (dist, orb)
    if best is None:
        raise ParameterError(f"no symmetric orbit of type {P}/{Q} with a positive residue around "
                             f"({centre[0]:.6g}, {centre[1]:.6g}) on the line p2 = 0 of phi = "
                             f"{smap.phi0 if line is None else line:.6g} at {smap.parameter} = "
                             f"{smap.parameter_value:.8g}")
    return best[1]


def island_line(smap: SectionMap, P: int, Q: int, centre):
    """(line, orbit): the symmetry line (phi0 or phi0 + pi) of the island's elliptic orbits of even
    period Q around ``centre``, and the orbit of type P/Q that decided it (docs/greene.md, "Two
    symmetry lines")."""
    if Q % 2:
        raise ParameterError(f"island_line needs an even period (an orbit of odd period meets both lines), got {Q}")
    found = [next(_typed_orbits(smap, P, Q, centre, smap.phi0, side), None) for side in (0, 1)]
    nearest = min((f for f in found if f is not None), key=lambda t: t[0], default=None)
    if nearest is None:
        raise ParameterError(f"no symmetric orbit of type {P}/{Q} around ({centre[0]:.6g}, {centre[1]:.6g}) on "
                             f"the line p2 = 0 of phi = {smap.phi0:.6g}: the line of the island's elliptic orbits "
                             f"is not decided")
    orb = nearest[1]
    return (smap.phi0 if orb.residue > 0 else (smap.phi0 + math.pi) % (2.0 * math.pi)), orb


def island_centre(smap: SectionMap, guess) -> np.ndarray:
    """The elliptic fixed point of ``smap`` near ``guess``."""
    fp = find_fixed_point(smap, tuple(float(v) for v in guess))
    if not fp.stable:
        raise ParameterError(f"the fixed point near ({guess[0]:.6g}, {guess[1]:.6g}) is not elliptic "
                             f"(trace {fp.trace:.6g}) at {smap.parameter} = {smap.parameter_value:.6g}: Greene's "
                             f"curves surround an elliptic one; start from a parameter where it is")
    return np.asarray(fp.point, float)


def _section_line(smap, conv, centre, line):
    """(line, the first convergent's orbit if the decision found it): ``line`` if given, else
    :func:`island_line` of the first even convergent (phi0 when all are odd)."""
    if line is not None:
        value = validation.real("line", line)
        if not any(_same_phi(value, phi) for phi in (smap.phi0, smap.phi0 + math.pi)):
            raise ParameterError(f"line must be the section's phi0 = {smap.phi0:g} or phi0 + pi (the reversor's "
                                 f"two symmetry lines), got {line!r}")
        return value % (2.0 * math.pi), None
    even = [(P, Q) for P, Q in conv if Q % 2 == 0]
    if not even:
        return smap.phi0, None
    value, orb = island_line(smap, *even[0], centre)
    return value, (orb if value == smap.phi0 and even[0] == conv[0] else None)


def section_greene(smap: SectionMap, nu: float, *, qmax=None, target, line=None, around=None, param=None):
    """:func:`explorer.greene` on a section map (docs/greene.md, "Greene on the section of Figure 4's
    scene"): the curve ``nu`` around the elliptic fixed point near ``around``, broken by ``param``
    (default "mu"; its value in ``smap`` is the first guess); points on ``smap``'s section."""
    if around is None:
        raise ParameterError("greene on a section map needs around=(p1, p2), a guess of the island's elliptic "
                             "fixed point")
    pname = "mu" if param is None else param
    validation.choice("param", pname, PARAM_NAMES_AND_H)
    conv = enough_convergents(nu, SECTION_QMAX if qmax is None else qmax)
    first = smap.h if pname == "h" else float(getattr(smap.params, pname))
    centre = island_centre(smap, around)
    line, seed = _section_line(smap, conv, centre, line)

    def orbit_at(value, P, Q, guess, check):
        m = smap.with_parameter(value, pname)
        if guess is None:
            if seed is not None and value == first and (P, Q) == conv[0]:
                return seed
            return first_orbit(m, P, Q, island_centre(m, centre), line)
        orb = section_symmetric_orbit(m, Q, guess, param=pname, line=line)
        if check:
            rot = orb.rotation(m, island_centre(m, centre))
            if abs(abs(rot) * Q - P) > ROTATION_TOL:
                raise ParameterError(f"the symmetric orbit of period {Q} near p1 = {orb.points[0, 0]:.8g} "
                                     f"turns {rot:.8g} per return around the centre, not {P}/{Q}")
        return orb

    rows, crit, uncertainty, ratio = critical_parameter(conv, orbit_at, lambda orb: orb.line_start,
                                                        lambda orb: orb.points[0], first, target)
    return GreeneResult("section", pname, nu, crit, uncertainty, rows, target, ratio, float(line))
