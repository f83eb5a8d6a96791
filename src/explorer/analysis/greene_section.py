"""Symmetric periodic orbits of the section map by the half-orbit method (Greene on Chaplygin's section).

With zeta = xi = 0 the reduced system is reversible under R: (p1, p2, M, phi, t) ->
(p1, -p2, M, -phi, -t) (:mod:`explorer.analysis.periodic`, "Reversing symmetry"), whose fixed
set is {p2 = 0, phi = 0 or pi}.  A flow orbit that meets this set twice is periodic, with twice
the time between the meetings.  So a start z = (p1, 0) on the section phi = pi whose state
after Q half-turns of phi (the crossings of phi = 0, pi, 0, ... with dphi/dt > 0) has p2 = 0
again starts an orbit of the section map P of period Q: one unknown (p1 on the line p2 = 0),
one equation after Q/2 returns, solved by the secant method.

The reversor's fixed set is two lines, p2 = 0 on phi = pi and p2 = 0 on phi = 0: an orbit of even
period meets only one of them, and of an island chain's symmetric orbits the elliptic one is on
one line, the hyperbolic one on the other.  The right island of Figure 4's scene has its elliptic
orbits on phi = pi, the left one (its image under the half-turn) on phi = 0 (:func:`island_line`
decides; docs/greene.md, "The left island").  An orbit of the other line is shot on that line's
own section (:func:`line_map`) and reported on the map's section.

On the section, G0(p1, p2) = (p1, -p2) satisfies G0 P G0 = P^-1, so the orbit's points are
x_{Q-j} = G0 x_j (j = 0..Q) and its monodromy needs the Jacobians of the first half only:
differentiating P G0 = G0 P^-1 gives DP(x_{Q-j}) = G0 DP(x_{j-1})^-1 G0, hence

    M = G0 B^-1 G0 A,    A = DP^n(x_0),  B = DP^(Q-n)(x_0),  n = ceil(Q/2)

(B = A for even Q).  This is the standard map's formula (:mod:`explorer.analysis.greene`) with
the constant reversor G0, and for the same reason: the second half's points, whose round-off
grows along the orbit, are never computed.
"""
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

#: an orbit of type P/Q turns P/Q per return around the island's centre to this (times Q)
ROTATION_TOL = 1e-6
#: the parameters a section map's curve can be broken by
PARAM_NAMES_AND_H = (*model.PARAM_NAMES, "h")

#: the reversor G0 on the section phi = pi
G0 = np.diag([1.0, -1.0])
#: the secant solve of the half-turn equation: converged when the step in p1 is below this
SECANT_TOL = 1e-13
SECANT_MAX_ITER = 40
#: samples of the symmetry line p2 = 0 scanned for the first convergent's orbit
LINE_SAMPLES = 200
#: the scan keeps this fraction of the allowed region's half-width away from its edge
EDGE_MARGIN = 1e-3


def line_map(smap: SectionMap, line) -> SectionMap:
    """The section map of the symmetry line's own section phi = ``line`` (``smap`` itself when ``line`` is
    None or ``smap.phi0``): the same system, tolerance and time budget."""
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
    """The point (p1, p2) of the section phi = ``line`` where the flow from the point x of ``smap``'s section
    next crosses it: half a turn of phi for the other symmetry line (x itself on the section's own)."""
    if _same_phi(line, smap.phi0):
        return np.asarray(x, float).copy()
    return _flow_to(smap, smap.state(x), float(line))[:2].copy()


def half_turn_p2(smap: SectionMap, p1: float, Q: int, line=None) -> float:
    """p2 after Q half-turns of phi from (p1, 0) on the symmetry line phi = ``line`` (default the section's
    own phi0; phi0 + pi is the other line of the reversor), NaN when the flow does not get there."""
    start = smap.phi0 if line is None else float(line)
    try:
        y = model.section_state(smap.params, [p1], [0.0], smap.h, start)[0]
    except ParameterError:
        return math.nan
    none = np.zeros((0, 5))
    out = np.empty(5)
    sections = (model.section_gamma((start + math.pi) % (2.0 * math.pi)), model.section_gamma(start))
    stop = budget.stop_switch()          # a budget's cancel reaches the half-turns too
    for j in range(Q):
        g1, g2 = sections[j % 2]
        status, _ = return_map_taylor(y, none, smap.P, g2, g1, 1.0, smap.tmax, smap.order, MAX_STEPS, stop, out,
                                      np.zeros((0, 5)))
        if status != STATUS_DONE:
            return math.nan
        y = out.copy()
    return float(y[1])


def line_roots(smap: SectionMap, Q: int, a: float, b: float, n: int, line=None) -> list:
    """The p1 in [a, b] where the half-turn function changes sign between n + 1 samples, refined by
    the secant method: the starts on p2 = 0 (of phi = ``line``, default the section's) of the symmetric
    orbits of period Q (or a divisor)."""
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
    """A root of the half-turn function from x0, x1 (kept bracketed when f0, f1 change sign)."""
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
    """A symmetric periodic orbit of the section map from the half-orbit method."""

    q: int
    points: np.ndarray      # (Q, 2): the orbit on the map's section from x_0 (x_0 = (p1, 0) on the line p2 = 0
                            # of the section's own phi0; x_{Q-j} = G0 x_j)
    monodromy: np.ndarray   # at the orbit's point on its symmetry line, on that line's section (the same trace)
    param_value: float
    line: float = math.pi   # phi of the symmetry line the orbit was shot from (the section's phi0, or phi0 + pi)
    start: float = math.nan  # p1 of the orbit's point (p1, 0) on that line

    @property
    def line_start(self) -> float:
        """p1 of the orbit's point on its symmetry line (``start``; ``points[0, 0]`` on the section's own)."""
        return float(self.points[0, 0]) if math.isnan(self.start) else self.start

    def rotation(self, smap: SectionMap, centre) -> float:
        """Turns around ``centre`` per return, in (-1/2, 1/2]: the angle increments over the Q returns
        lifted through the flow (:mod:`explorer.analysis.rotation`, "The lift": near the edge of the
        allowed region one return may turn by more than half a turn, and wrapped increments would
        miscount it), summed over 2 pi Q."""
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
    """The symmetric orbit of period Q through (p1, 0) of the symmetry line phi = ``line`` (default the
    section's own phi0), p1 near ``guess`` (secant from ``guess``, ``guess2``); points and monodromy from
    the first half (module docstring).

    The reversor's fixed set has two lines, p2 = 0 on phi = phi0 and on phi = phi0 + pi (docs/greene.md,
    "The left island"): an orbit of even period meets only one of them (twice), so each island chain's
    elliptic and hyperbolic orbits sit on different lines.  For ``line`` = phi0 + pi the orbit is solved
    on that line's own section (the same flow orbit), its monodromy is taken there (conjugate by the
    half-turn flow, so the same trace and residue), and its ``points`` are its crossings of ``smap``'s
    section, the first half a turn after the point on the line."""
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
    """The symmetric orbits of type P/Q around ``centre`` with a point on the symmetry line phi = ``line``,
    scanned outward from the centre's crossing of that line on one side (``side`` 0: towards smaller
    p1, 1: larger; :func:`line_roots`) up to the allowed region's edge: yields (distance, orbit),
    nearest first.  An orbit turns P/Q per return the way the centre turns (the sign of DP's lower-left
    entry)."""
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
        except ParameterError:      # no orbit there, or one whose turns around the centre are
            continue                # not defined (it passes the centre): not of type P/Q around it
        if abs(turns * Q - turn * P) < 1e-6:
            yield abs(root - x0), orb


def first_orbit(smap: SectionMap, P: int, Q: int, centre, line=None) -> SectionSymmetricOrbit:
    """The symmetric orbit of type P/Q around the elliptic fixed point ``centre`` nearest to it on the
    symmetry line phi = ``line`` (default the section's own, p2 = 0) with a positive residue (Greene's
    sequence: the elliptic members of the island chains while the curves exist), turning the way the
    centre turns.  Scanned outward from the centre on each side (:func:`_typed_orbits`): the first such
    orbit is inside the island, the farther ones may circle both islands."""
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
    """The symmetry line (phi0 or phi0 + pi) that carries the island's elliptic orbits of even period
    around ``centre``, and the orbit that decided it (docs/greene.md, "Two symmetry lines"): the
    orbit of type P/Q (``Q`` even) nearest to the centre on the section's own line is on it when its
    residue is positive, else the line is phi0 + pi."""
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
    """The elliptic fixed point of ``smap`` near ``guess`` (Newton), the centre of Greene's curves."""
    fp = find_fixed_point(smap, tuple(float(v) for v in guess))
    if not fp.stable:
        raise ParameterError(f"the fixed point near ({guess[0]:.6g}, {guess[1]:.6g}) is not elliptic "
                             f"(trace {fp.trace:.6g}) at {smap.parameter} = {smap.parameter_value:.6g}: Greene's "
                             f"curves surround an elliptic one; start from a parameter where it is")
    return np.asarray(fp.point, float)


def _section_line(smap, conv, centre, line):
    """The symmetry line of Greene's orbits around ``centre``: ``line`` when given (phi0 or phi0 + pi),
    else :func:`island_line` of the first even convergent (phi0 when every convergent is odd).
    Returns (line, the first convergent's orbit when the decision found it, else None)."""
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
    scene"): the curves of rotation number ``nu`` around the elliptic fixed point near ``around``,
    broken by the model parameter ``param`` (or "h"; default "mu"), whose value in ``smap`` is the
    first guess.  ``line``: phi0 or phi0 + pi, default the line of the island's elliptic orbits
    (:func:`island_line`).  The points reported are on ``smap``'s section."""
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
                return seed         # the line's decision found the first orbit already
            return first_orbit(m, P, Q, island_centre(m, centre), line)
        orb = section_symmetric_orbit(m, Q, guess, param=pname, line=line)
        if check:   # continued orbits stay on their branch; the final ones are checked once more
            rot = orb.rotation(m, island_centre(m, centre))
            if abs(abs(rot) * Q - P) > ROTATION_TOL:
                raise ParameterError(f"the symmetric orbit of period {Q} near p1 = {orb.points[0, 0]:.8g} "
                                     f"turns {rot:.8g} per return around the centre, not {P}/{Q}")
        return orb

    rows, crit, uncertainty, ratio = critical_parameter(conv, orbit_at, lambda orb: orb.line_start,
                                                        lambda orb: orb.points[0], first, target)
    return GreeneResult("section", pname, nu, crit, uncertainty, rows, target, ratio, float(line))
