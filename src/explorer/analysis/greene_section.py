"""Symmetric periodic orbits of the section map by the half-orbit method (Greene on Chaplygin's section).

With zeta = xi = 0 the reduced system is reversible under R: (p1, p2, M, phi, t) ->
(p1, -p2, M, -phi, -t) (:mod:`explorer.analysis.periodic`, "Reversing symmetry"), whose fixed
set is {p2 = 0, phi = 0 or pi}.  A flow orbit that meets this set twice is periodic, with twice
the time between the meetings.  So a start z = (p1, 0) on the section phi = pi whose state
after Q half-turns of phi (the crossings of phi = 0, pi, 0, ... with dphi/dt > 0) has p2 = 0
again starts an orbit of the section map P of period Q: one unknown (p1 on the line p2 = 0),
one equation after Q/2 returns, solved by the secant method.

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
from explorer.analysis.greene import Residue
from explorer.analysis.section_map import MAX_STEPS, SectionMap
from explorer.integrate.tangent import return_map_taylor
from explorer.kernels import STATUS_DONE
from explorer.model import ParameterError

__all__ = ["SectionSymmetricOrbit", "first_orbit", "half_turn_p2", "line_roots", "section_symmetric_orbit"]

#: the reversor G0 on the section phi = pi
G0 = np.diag([1.0, -1.0])
#: the secant solve of the half-turn equation: converged when the step in p1 is below this
SECANT_TOL = 1e-13
SECANT_MAX_ITER = 40
#: samples of the symmetry line p2 = 0 scanned for the first convergent's orbit
LINE_SAMPLES = 200
#: the scan keeps this fraction of the allowed region's half-width away from its edge
EDGE_MARGIN = 1e-3


def half_turn_p2(smap: SectionMap, p1: float, Q: int) -> float:
    """p2 after Q half-turns of phi from (p1, 0) on phi = pi (NaN when the flow does not get there)."""
    try:
        y = smap.state((p1, 0.0))
    except ParameterError:
        return math.nan
    none = np.zeros((0, 5))
    out = np.empty(5)
    sections = (model.section_gamma(0.0), model.section_gamma(math.pi))
    stop = budget.stop_switch()          # a budget's cancel reaches the half-turns too
    for j in range(Q):
        g1, g2 = sections[j % 2]
        status, _ = return_map_taylor(y, none, smap.P, g2, g1, 1.0, smap.tmax, smap.order, MAX_STEPS, stop, out,
                                      np.zeros((0, 5)))
        if status != STATUS_DONE:
            return math.nan
        y = out.copy()
    return float(y[1])


def line_roots(smap: SectionMap, Q: int, a: float, b: float, n: int) -> list:
    """The p1 in [a, b] where the half-turn function changes sign between n + 1 samples, refined by
    the secant method: the starts on p2 = 0 of the symmetric orbits of period Q (or a divisor)."""
    xs = np.linspace(a, b, n + 1)
    fs = np.array([half_turn_p2(smap, x, Q) for x in xs])
    roots = []
    for i in np.flatnonzero(np.isfinite(fs[:-1]) & np.isfinite(fs[1:]) & (np.sign(fs[:-1]) != np.sign(fs[1:]))):
        try:
            roots.append(_secant(smap, Q, xs[i], xs[i + 1], fs[i], fs[i + 1]))
        except ParameterError:
            continue
    return roots


def _secant(smap, Q, x0, x1, f0=None, f1=None) -> float:
    """A root of the half-turn function from x0, x1 (kept bracketed when f0, f1 change sign)."""
    f0 = half_turn_p2(smap, x0, Q) if f0 is None else f0
    f1 = half_turn_p2(smap, x1, Q) if f1 is None else f1
    for _ in range(SECANT_MAX_ITER):
        if not (math.isfinite(f0) and math.isfinite(f1)) or f1 == f0:
            break
        x2 = x1 - f1 * (x1 - x0) / (f1 - f0)
        if abs(x2 - x1) <= SECANT_TOL * max(1.0, abs(x1)) or f1 == 0.0:
            return float(x2)
        f2 = half_turn_p2(smap, x2, Q)
        x0, f0, x1, f1 = x1, f1, x2, f2
    raise ParameterError(f"no symmetric orbit of period {Q} near p1 = {x1:.10g} (the half-turn equation "
                         f"did not converge)")


@dataclass(frozen=True)
class SectionSymmetricOrbit(Residue):
    """A symmetric periodic orbit of the section map from the half-orbit method."""

    q: int
    points: np.ndarray      # (Q, 2): x_0 = (p1, 0) on the symmetry line, x_{Q-j} = G0 x_j
    monodromy: np.ndarray
    param_value: float

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


def section_symmetric_orbit(smap: SectionMap, Q: int, guess, guess2=None, *, param=None) -> SectionSymmetricOrbit:
    """The symmetric orbit of period Q through (p1, 0), p1 near ``guess`` (secant from ``guess``,
    ``guess2``); points and monodromy from the first half (module docstring)."""
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
    return SectionSymmetricOrbit(Q, pts[:Q].copy(), M, value)


def first_orbit(smap: SectionMap, P: int, Q: int, centre) -> SectionSymmetricOrbit:
    """The symmetric orbit of type P/Q around the elliptic fixed point ``centre`` nearest to it on the
    line p2 = 0 with a positive residue (Greene's sequence: the elliptic members of the island chains
    while the curves exist), turning the way the centre turns (the sign of DP's lower-left entry).
    Scanned outward from the centre on each side (:func:`line_roots`) up to the allowed region's
    edge: the first such orbit is inside the island, the farther ones may circle both islands."""
    e = model.allowed_ellipse(smap.params, smap.h, smap.phi0)
    if e is None:
        raise ParameterError("the allowed region is empty")
    c1, c2, r1, r2 = e
    half = r1 * math.sqrt(max(0.0, 1.0 - (c2 / r2) ** 2)) * (1.0 - EDGE_MARGIN)
    turn = -1.0 if smap.jacobian(centre)[1, 0] < 0 else 1.0
    best = None
    x0 = float(centre[0])
    for end in (c1 - half, c1 + half):
        for root in sorted(line_roots(smap, Q, x0, end, LINE_SAMPLES), key=lambda r: abs(r - x0)):
            try:
                orb = section_symmetric_orbit(smap, Q, root)
                turns = orb.rotation(smap, centre)
            except ParameterError:      # no orbit there, or one whose turns around the centre are
                continue                # not defined (it passes the centre): not of type P/Q around it
            if abs(turns * Q - turn * P) < 1e-6 and orb.residue > 0:
                if best is None or abs(root - x0) < abs(best.points[0, 0] - x0):
                    best = orb
                break
    if best is None:
        raise ParameterError(f"no symmetric orbit of type {P}/{Q} with a positive residue around "
                             f"({centre[0]:.6g}, {centre[1]:.6g}) on the line p2 = 0 at "
                             f"{smap.parameter} = {smap.parameter_value:.8g}")
    return best


def curve_orbit(smap: SectionMap, nu: float, centre, a: float, b: float, *, iterates: int, steps: int = 24,
                search_iterates: int = 300):
    """The rotation number (weighted Birkhoff, :func:`explorer.analysis.rotation.rotation_number`) of the
    orbit through the point of the line p2 = 0 between p1 = ``a`` and ``b`` where |rotation| = ``nu``:
    bisection on p1 (``steps`` halvings, each orbit averaged over 2 ``search_iterates`` returns; the
    twist makes |rotation| monotone across the bracket of two consecutive convergents' orbits), then
    the orbit of the last midpoint averaged over 2 ``iterates`` returns.  Below the breakup that orbit
    lies on the invariant curve and its average converges (``converged``); above it the curve is a
    cantorus and it does not."""
    from explorer.analysis.rotation import rotation_number

    def rot(x, n):
        return rotation_number(smap, (x, 0.0), center=centre, iterates=n)

    sign_a = math.copysign(1.0, abs(rot(a, search_iterates).value) - nu)
    for _ in range(steps):
        m = 0.5 * (a + b)
        r = rot(m, search_iterates)
        if not math.isfinite(r.value):
            break
        if math.copysign(1.0, abs(r.value) - nu) == sign_a:
            a = m
        else:
            b = m
    return rot(0.5 * (a + b), iterates)
