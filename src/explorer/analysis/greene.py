"""Greene's residue criterion (docs/greene.md): :func:`greene`, and the standard map's symmetric orbits
by the half-orbit method ("The half-orbit (symmetry-line) method")."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer.analysis import greene_section
from explorer.analysis.greene_core import (
    CRITICAL_RESIDUE,
    DEFAULT_QMAX,
    GOLDEN,
    MIN_Q,
    GreeneResult,
    Residue,
    convergents,
    critical_parameter,
    enough_convergents,
    rotation_value,
)
from explorer.analysis.maps import StandardMap, standard_half_orbit, standard_monodromy
from explorer.analysis.system_sections import is_system
from explorer.model import ParameterError, validation

__all__ = ["CRITICAL_RESIDUE", "GOLDEN", "GreeneResult", "SymmetricOrbit", "convergents", "greene",
           "rotation_value", "symmetric_orbit"]

#: Newton on the half orbit: the step in p relative to max(1, |p|) at convergence, or below the floor
#: once the steps stop shrinking (round-off)
SHOOT_TOL, SHOOT_MAX_ITER, SHOOT_FLOOR = 1e-15, 40, 1e-11
#: the closure after Q steps, relative to max(1, |M|)
CLOSURE_TOL = 1e-9


@dataclass(frozen=True)
class SymmetricOrbit(Residue):
    """A symmetric orbit of type P/Q of the standard map: ``points`` (Q, 2) from theta = ``line``,
    theta lifted; ``closure`` = max |T^Q(x_0) - x_0 - (2 pi P, 0)|."""

    p: int
    q: int
    points: np.ndarray
    monodromy: np.ndarray
    param_value: float
    line: float
    closure: float


def _shoot(k, P, Q, theta0, p0):
    """Newton on the half-orbit equation (docs/greene.md) for the start p0 on theta = theta0."""
    even = Q % 2 == 0
    n = Q // 2 if even else (Q + 1) // 2
    p = float(p0)
    prev = math.inf
    for _ in range(SHOOT_MAX_ITER):
        th, pn, dth, dpn = standard_half_orbit(theta0, p, k, n)
        if even:
            f, df = th - theta0 - math.pi * P, dth
        else:
            f, df = 2.0 * th - pn - 2.0 * theta0 - 2.0 * math.pi * P, 2.0 * dth - dpn
        if not (math.isfinite(f) and math.isfinite(df)) or df == 0.0:
            break
        step = -f / df
        p += step
        scale = max(1.0, abs(p))
        if abs(step) <= SHOOT_TOL * scale or (abs(step) <= SHOOT_FLOOR * scale and abs(step) >= 0.5 * abs(prev)):
            return p
        prev = step
    raise ParameterError(f"no symmetric orbit of type {P}/{Q} on theta = {theta0:g} at k = {k:.12g} "
                         f"(Newton on the half orbit did not converge from p = {p0:.12g})")


def _half_orbit_monodromy(k, Q, theta0, p0) -> np.ndarray:
    """The monodromy from the half orbit's Jacobian A (docs/greene.md): Q = 2n: M = G(z_0) A^-1 G(z_n) A;
    Q = 2n - 1: M = H DT(z_0) A^-1 H A."""
    even = Q % 2 == 0
    n = Q // 2 if even else (Q + 1) // 2
    a, b, c, d, theta_n, _ = standard_monodromy(theta0, p0, k, n)
    A = np.array([[a, b], [c, d]])
    A_inv = np.array([[d, -b], [-c, a]])
    if even:
        G0 = np.array([[-1.0, 0.0], [k * math.cos(theta0), 1.0]])
        Gn = np.array([[-1.0, 0.0], [k * math.cos(theta_n), 1.0]])
        return G0 @ A_inv @ Gn @ A
    H = np.array([[-1.0, 1.0], [0.0, 1.0]])
    kc = k * math.cos(theta0)
    return H @ np.array([[1.0 + kc, 1.0], [kc, 1.0]]) @ A_inv @ H @ A


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
    if not isinstance(system, StandardMap):
        raise ParameterError(f"symmetric_orbit: the half-orbit method is implemented for StandardMap and a "
                             f"section map (with a reversor); got {type(system).__name__}")
    P = validation.integer("p", p, 0)
    Q = validation.integer("q", q, MIN_Q)
    theta0 = validation.real("line", line)
    k = system.k
    p0 = _shoot(k, P, Q, theta0, 2.0 * math.pi * P / Q if guess is None else validation.real("guess", guess))
    pts = system.iterate((theta0, p0), Q)
    M = _half_orbit_monodromy(k, Q, theta0, p0)
    closure = float(max(abs(pts[Q, 0] - theta0 - 2.0 * math.pi * P), abs(pts[Q, 1] - p0)))
    if not closure <= CLOSURE_TOL * max(1.0, float(np.max(np.abs(M)))):
        raise ParameterError(f"the orbit of type {P}/{Q} from theta = {theta0:g} does not close at k = {k:.12g} "
                             f"(error {closure:.3g}): too far above the breakup for double precision")
    return SymmetricOrbit(P, Q, pts[:Q].copy(), M, float(k), theta0, closure)


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
    if not isinstance(system, StandardMap):
        raise ParameterError(f"greene takes a StandardMap or a section map, got {type(system).__name__}")
    if around is not None or param not in (None, system.parameter):
        raise ParameterError("greene: around= and param= belong to a section map; the standard map's "
                             "parameter is k")
    conv = enough_convergents(x, DEFAULT_QMAX if qmax is None else qmax)
    line = math.pi if line is None else validation.real("line", line)

    def orbit_at(k, P, Q, guess, check):
        return symmetric_orbit(StandardMap(k), P, Q, line=line, guess=guess)

    rows, crit, uncertainty, ratio = critical_parameter(conv, orbit_at, lambda orb: orb.points[0, 1],
                                                        lambda orb: StandardMap.wrap(orb.points[0]),
                                                        system.parameter_value, target)
    return GreeneResult("standard", system.parameter, x, crit, uncertainty, rows, target, ratio, float(line))
