"""Greene's residue criterion: the parameter at which an invariant curve of rotation number nu breaks.

Greene (1979, J. Math. Phys. 20, 1183) and MacKay (1983, Physica D 7, 283; 1992, Nonlinearity
5, 161): take the periodic orbits whose rotation numbers P_n/Q_n are the convergents of the
continued fraction of nu.  Their residues R = (2 - tr M)/4 (M the monodromy, the product of
the Q map Jacobians along the orbit) go to 0 while the curve of rotation number nu exists,
grow without bound once it is broken, and at the critical parameter converge to a universal
limit: for noble nu, R_n -> R* = 0.2500888 for the orbits whose residue is positive (MacKay
1983, the fixed point of renormalisation; :data:`CRITICAL_RESIDUE`).

The critical parameter
----------------------
For each convergent, k_n is the parameter at which R_n(k_n) = R* (a secant solve in k, each
orbit continued from the previous one).  Near the fixed point of renormalisation
R_n(k) ~ R* + C (k - k_c) delta^n + O(lambda^n), so k_n -> k_c geometrically; Aitken's
Delta^2 on the last three k_n gives ``critical``, and the change between the estimates from
the last two triples is its ``uncertainty``.  On the standard map the ratio
(k_{n+1} - k_n)/(k_n - k_{n-1}) settles at -0.3755 (measured, tests/analysis/test_greene.py),
and q up to 233 gives k_c to 9 digits.

The half-orbit (symmetry-line) method
-------------------------------------
With a reversible map T = I1 I0 (I0, I1 involutions, :class:`explorer.analysis.maps.StandardMap`),
a point z on Fix(I0) whose n-th image lies on Fix(I0) again starts an orbit of period 2n
(T^n z = I0 T^n z = T^-n I0 z = T^-n z), and one whose n-th image lies on Fix(I1) an orbit of
period 2n - 1 (I1 = T I0 gives I0 T^n z = T^(n-1) z, so T^(2n-1) z = z); on the lifted
cylinder the lines are theta = pi m and 2 theta - p = 2 pi m, and the difference of the m's
is the orbit's P.  So a symmetric orbit of type P/Q is one unknown (p on the line theta =
theta0) and one equation, after n = Q/2 (Q even: theta_n = theta0 + pi P) or n = (Q + 1)/2
steps (Q odd: 2 theta_n - p_n = 2 theta0 + 2 pi P), solved by Newton with the slope carried
by the tangent map.

Why this works where Newton on the whole orbit does not: the full system P^Q(x) - x = 0 has
the Jacobian M - I, and det(M - I) = 2 - tr M = 4 R.  Below k_c the residues of the
convergents fall like exp(-c Q) (to 1e-17 at Q = 233 and k = 0.5), so M - I is singular to
working precision: near an invariant curve every point of an arc nearly closes after Q steps,
and Newton's step along the curve is undetermined (multiple shooting over the Q points has
the same null direction).  Near k_c, |M| grows like Q^1.6 (6.5e3 at Q = 233) and the
cancellation in M - I costs the same digits.  The symmetry line removes the direction along
the curve: the unknown is the position across the curve on a line transverse to it, and the
slope of the shooting function, d theta_n / d p ~ n (the twist), stays of order n at every
k.  The orbit is found to ~1e-15 in p, and the residue follows from the half orbit's
Jacobian alone (:func:`_half_orbit_monodromy`), so round-off grows over Q/2 steps, not Q.

A :class:`~explorer.analysis.section_map.SectionMap` is solved the same way, its symmetric orbits
shot over Q half-turns of the flow from the line p2 = 0 of phi = pi or of phi = 0, whichever carries
the island's elliptic orbits (:mod:`explorer.analysis.greene_section`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from explorer.analysis.maps import StandardMap, standard_half_orbit, standard_monodromy
from explorer.model import PARAM_NAMES, ParameterError, validation

__all__ = ["CRITICAL_RESIDUE", "GOLDEN", "GreeneResult", "SymmetricOrbit", "convergents", "greene",
           "rotation_value", "symmetric_orbit"]

#: the golden mean's conjugate (sqrt 5 - 1)/2 = [0; 1, 1, 1, ...], the rotation number of the last
#: invariant circle of the standard map (Greene 1979)
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: the limit of the positive residues of the convergents at the critical parameter, for noble
#: rotation numbers: MacKay 1983 (Physica D 7, 283), the residue at the fixed point of
#: renormalisation, R* = 0.2500888
CRITICAL_RESIDUE = 0.2500888
#: the largest period of the convergents followed by default (the Fibonacci chain to 987)
DEFAULT_QMAX = 987
#: the largest period accepted: beyond ~1600 the half orbit's round-off (double precision) reaches the
#: residues' differences (docs/greene.md, "Accuracy")
MAX_QMAX = 4181
#: the largest period followed by default on the section map (each orbit is Q integrations of the flow)
SECTION_QMAX = 55
#: the smallest period used: Q = 1 has no half-orbit equation of this form
MIN_Q = 2
#: Newton on the half-orbit: converged when the step in p is below this (relative to max(1, |p|)),
#: in at most this many iterations
SHOOT_TOL, SHOOT_MAX_ITER = 1e-15, 40
#: ... or when the steps stop shrinking below this: the round-off floor of a long half orbit
SHOOT_FLOOR = 1e-11
#: an orbit is accepted when it closes after Q steps to this (theta_Q - theta_0 - 2 pi P and p_Q - p_0,
#: relative to max(1, |M|): the closure error of a correct orbit grows with the monodromy)
CLOSURE_TOL = 1e-9
#: the secant solve of R_n(k) = R*: stop when the step in k is below this, or after this many steps
PARAM_TOL, PARAM_MAX_ITER = 1e-14, 60
#: a secant step in the parameter is at most this fraction of max(|k|, the last step)
MAX_PARAM_STEP = 0.2
#: an orbit of type P/Q turns P/Q per return around the island's centre to this (times Q)
ROTATION_TOL = 1e-6
#: the parameters a section map's curve can be broken by
PARAM_NAMES_AND_H = (*PARAM_NAMES, "h")
#: named rotation numbers accepted by :func:`rotation_value`
NAMED = {"golden": GOLDEN, "golden2": 1.0 - GOLDEN}


def rotation_value(nu) -> float:
    """The rotation number ``nu``: a number in (0, 1), a name of :data:`NAMED` ("golden":
    (sqrt 5 - 1)/2; "golden2": its complement (3 - sqrt 5)/2), or "noble:A" (A >= 1): the noble
    number 1/(A + golden) = [0; A, 1, 1, 1, ...], equivalent to the golden mean."""
    if isinstance(nu, str):
        key = nu.strip().lower()
        if key in NAMED:
            return NAMED[key]
        if key.startswith("noble:"):
            try:
                terms = [int(t) for t in key[len("noble:"):].split(",")]
            except ValueError:
                terms = [0]
            if not terms or min(terms) < 1:
                raise ParameterError(f"nu = noble:A needs an integer A >= 1 (nu = 1/(A + golden); noble:A,B,... "
                                     f"= [0; A, B, ..., 1, 1, ...]), got {nu!r}")
            value = GOLDEN
            for a in reversed(terms):
                value = 1.0 / (a + value)
            return value
        try:
            nu = float(key)
        except ValueError:
            raise ParameterError(f"nu must be a number in (0, 1), one of {sorted(NAMED)} or noble:A, "
                                 f"got {nu!r}") from None
    return validation.real("nu", nu, 0.0, 1.0, lo_open=True, hi_open=True)


def convergents(nu, qmax: int = DEFAULT_QMAX, qmin: int = MIN_Q) -> list:
    """The convergents P/Q of the continued fraction of ``nu`` with ``qmin`` <= Q <= ``qmax``, in order
    (for the golden mean: 1/2, 2/3, 3/5, 5/8, ..., the ratios of Fibonacci numbers)."""
    x = rotation_value(nu)
    qmax = validation.integer("qmax", qmax, 2, MAX_QMAX)
    h0, h1, k0, k1 = 0, 1, 1, 0          # P_{-2}, P_{-1}, Q_{-2}, Q_{-1}
    out: list[tuple[int, int]] = []
    frac = x
    for _ in range(200):
        a = math.floor(frac)
        h0, h1 = h1, a * h1 + h0
        k0, k1 = k1, a * k1 + k0
        if k1 > qmax:
            break
        if k1 >= qmin and (not out or out[-1][1] != k1):
            out.append((int(h1), int(k1)))
        r = frac - a
        if r < 1e-15 or abs(h1 / k1 - x) < 1e-16:
            break
        frac = 1.0 / r
    return out


class Residue:
    """The trace and Greene's residue of an orbit's ``monodromy``."""

    monodromy: np.ndarray

    @property
    def trace(self) -> float:
        return float(self.monodromy[0, 0] + self.monodromy[1, 1])

    @property
    def residue(self) -> float:
        """Greene's residue R = (2 - tr M)/4 (0 < R < 1: elliptic)."""
        return (2.0 - self.trace) / 4.0


@dataclass(frozen=True)
class SymmetricOrbit(Residue):
    """A symmetric periodic orbit of type P/Q found by the half-orbit method."""

    p: int                  # turns (theta_Q - theta_0 = 2 pi P)
    q: int                  # period
    points: np.ndarray      # (Q, 2): the orbit from its point on the symmetry line, theta lifted
    monodromy: np.ndarray   # 2x2 product of the Q Jacobians
    param_value: float
    line: float             # the symmetry line theta = line of the start
    closure: float          # max |T^Q(x_0) - x_0 - (2 pi P, 0)|


def _shoot(k, P, Q, theta0, p0):
    """Newton on the half-orbit equation (module docstring) for the start p0 on theta = theta0."""
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
            return p       # converged, or at the noise floor of the shooting function (steps stop shrinking)
        prev = step
    raise ParameterError(f"no symmetric orbit of type {P}/{Q} on theta = {theta0:g} at k = {k:.12g} "
                         f"(Newton on the half orbit did not converge from p = {p0:.12g})")


def _half_orbit_monodromy(k, Q, theta0, p0) -> np.ndarray:
    """The monodromy of the symmetric orbit from z_0 = (theta0, p0) on Fix(I0), from the half-orbit
    Jacobian A = DT^n(z_0) alone (module docstring).  Differentiating T^m R = R T^-m (R a reversor)
    at the orbit's second symmetric point gives the second half's Jacobian from A^-1:

    * Q = 2n (z_n on Fix(I0)): M = G(z_0) A^-1 G(z_n) A, with G = DI0 = [[-1, 0], [k cos theta, 1]];
    * Q = 2n - 1 (z_n on Fix(I1)): M = H DT(z_0) A^-1 H A, with H = DI1 = [[-1, 1], [0, 1]].

    The points of the second half are never computed, so their round-off (amplified along the
    orbit like the partial products of the Jacobians) does not enter: at Q = 987 and k = k_c the
    residue is 1e-8 from an 80-bit full-orbit product, against 3e-6 for the double full-orbit
    product (tests/analysis/test_greene.py)."""
    even = Q % 2 == 0
    n = Q // 2 if even else (Q + 1) // 2
    a, b, c, d, theta_n, _ = standard_monodromy(theta0, p0, k, n)
    A = np.array([[a, b], [c, d]])
    A_inv = np.array([[d, -b], [-c, a]])           # det A = 1
    if even:
        G0 = np.array([[-1.0, 0.0], [k * math.cos(theta0), 1.0]])
        Gn = np.array([[-1.0, 0.0], [k * math.cos(theta_n), 1.0]])
        return G0 @ A_inv @ Gn @ A
    H = np.array([[-1.0, 1.0], [0.0, 1.0]])
    kc = k * math.cos(theta0)
    return H @ np.array([[1.0 + kc, 1.0], [kc, 1.0]]) @ A_inv @ H @ A


def symmetric_orbit(system, p, q, *, line=math.pi, guess=None):
    """The symmetric orbit of type ``p``/``q`` with a point on the symmetry line theta = ``line``.

    Half-orbit shooting (module docstring) from the start momentum ``guess`` (default
    2 pi p/q, the orbit of the integrable map k = 0); the orbit is then run for the full
    period, its monodromy formed from the q Jacobians and its closure checked.  For the
    standard map (S1), theta = pi carries the orbits with positive residue (Greene's
    "elliptic" sequence, his x = 0), theta = 0 those with negative residue when q is odd.

    A :class:`~explorer.analysis.section_map.SectionMap`: the symmetric orbit of period ``q``
    through (p1, 0) with p1 near ``guess`` (required; ``line`` does not apply: the line is
    p2 = 0), by the half-turn shooting of :func:`explorer.analysis.greene_section.section_symmetric_orbit`;
    ``p`` is not imposed there (the turns around a centre are the orbit's
    ``rotation(smap, centre)``).  Returns a ``SymmetricOrbit`` (standard map) or a
    ``SectionSymmetricOrbit``: both have ``q``, ``points``, ``monodromy`` and ``residue``."""
    from explorer.analysis.maps import is_section_map

    if is_section_map(system):
        from explorer.analysis import greene_section as gs

        if guess is None:
            raise ParameterError("symmetric_orbit on a section map needs guess=p1, a point of the line p2 = 0 "
                                 "near the orbit")
        validation.integer("p", p, 0)
        return gs.section_symmetric_orbit(system, validation.integer("q", q, 1), validation.real("guess", guess))
    if not isinstance(system, StandardMap):
        raise ParameterError(f"symmetric_orbit: the half-orbit method is implemented for StandardMap and "
                             f"SectionMap; got {type(system).__name__}")
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


@dataclass(frozen=True)
class GreeneResult:
    """The critical parameter of the curve of rotation number ``nu`` (:func:`greene`)."""

    map: str
    param: str
    nu: float
    critical: float
    uncertainty: float
    convergents: list = field(default_factory=list)   # dicts: p, q, point, param_value, residue
    critical_residue: float = CRITICAL_RESIDUE
    ratio: float = math.nan        # the last (k_{n+1} - k_n)/(k_n - k_{n-1})
    line: float = math.pi          # the orbits' symmetry line: theta (standard map), phi of p2 = 0 (section)

    def as_dict(self) -> dict:
        """The JSON form of ``python -m explorer greene --json``."""
        return {"map": self.map, "param": self.param, "nu": self.nu, "critical": self.critical,
                "uncertainty": self.uncertainty,
                "convergents": [{key: c[key] for key in ("p", "q", "point", "param_value", "residue")}
                                for c in self.convergents]}


def _solve_param(residue_at, target, k0, k1):
    """The secant solve of residue_at(k) = target from k0, k1; a trial that fails (no orbit) is pulled
    halfway back to the last good value.  Returns (k, orbit)."""
    fa_orb = residue_at(k0)
    fa = fa_orb.residue - target
    kb, fb_orb = k1, None
    ka = k0
    for _ in range(PARAM_MAX_ITER):
        try:
            fb_orb = residue_at(kb)
        except ParameterError:
            kb = 0.5 * (ka + kb)
            continue
        fb = fb_orb.residue - target
        if fb == 0.0 or fb == fa:
            return kb, fb_orb
        kc = kb - fb * (kb - ka) / (fb - fa)
        limit = MAX_PARAM_STEP * max(abs(kb), abs(kb - ka))
        kc = min(max(kc, kb - limit), kb + limit)     # residues are steep in k: no leap past the orbit's life
        ka, fa = kb, fb
        if abs(kc - kb) <= PARAM_TOL * max(1.0, abs(kb)):
            kb = kc
            return kb, residue_at(kb)
        kb = kc
    raise ParameterError(f"the residue did not reach {target:g} (last parameter {kb:.12g})")


def _aitken(x0, x1, x2) -> float:
    d1, d2 = x1 - x0, x2 - x1
    if d2 == d1:
        return x2
    return x2 - d2 * d2 / (d2 - d1)


def greene(system, nu="golden", *, qmax=None, residue=CRITICAL_RESIDUE, line=None, around=None,
           param=None) -> GreeneResult:
    """The critical parameter at which the invariant curve of rotation number ``nu`` breaks (Greene's
    residue criterion; module docstring).

    Parameters
    ----------
    system : StandardMap or SectionMap
        The map; its parameter value is the first guess of the critical one.
    nu : float or str
        The rotation number in (0, 1), or "golden" ((sqrt 5 - 1)/2) or "golden2".
    qmax : int or None
        The largest period of the convergents (default 987 for the standard map, 55 for a section
        map; at least three convergents with Q >= 2 are needed; at most :data:`MAX_QMAX`).
    residue : float
        The residue that defines k_n (default MacKay's R* = 0.2500888, :data:`CRITICAL_RESIDUE`).
    line : float or None
        The symmetry line of the orbits.  Standard map: theta = ``line`` (default pi: positive
        residues).  Section map: the line p2 = 0 of phi = ``line``, the section's phi0 or phi0 + pi
        (default: the one that carries the island's elliptic orbits of even period,
        :func:`explorer.analysis.greene_section.island_line`).
    around : (float, float)
        Section map only: a guess of the elliptic fixed point the curves surround.
    param : str
        Section map only: the model parameter (or "h") that breaks the curve (default "mu").

    Returns
    -------
    GreeneResult
        ``critical`` (Aitken's extrapolation of the k_n), ``uncertainty``, and per convergent
        ``p``, ``q``, ``param_value`` (k_n), and at the critical value its ``point`` (theta in
        [0, 2 pi), p) on the symmetry line (section map: (p1, 0)) and its ``residue``.
    """
    from explorer.analysis.section_map import SectionMap

    x = rotation_value(nu)
    target = validation.real("residue", residue, 0.0, 1.0, lo_open=True, hi_open=True)
    if isinstance(system, StandardMap):
        if around is not None or param not in (None, system.parameter):
            raise ParameterError("greene: around= and param= belong to a section map; the standard map's "
                                 "parameter is k")
        conv = _enough(x, DEFAULT_QMAX if qmax is None else qmax)
        line = math.pi if line is None else validation.real("line", line)

        def orbit_at(k, P, Q, guess, check=False):
            return symmetric_orbit(StandardMap(k), P, Q, line=line, guess=guess)

        def start_of(orb):
            return orb.points[0, 1]

        def point_of(orb):
            return StandardMap.wrap(orb.points[0])

        name, pname, first = "standard", system.parameter, system.parameter_value
    elif isinstance(system, SectionMap):
        from explorer.analysis import greene_section as gs

        if around is None:
            raise ParameterError("greene on a section map needs around=(p1, p2), a guess of the island's elliptic "
                                 "fixed point")
        pname = "mu" if param is None else param
        validation.choice("param", pname, PARAM_NAMES_AND_H)
        conv = _enough(x, SECTION_QMAX if qmax is None else qmax)
        first = system.h if pname == "h" else float(getattr(system.params, pname))
        centre = _centre(system, around)
        line, seed = _section_line(system, conv, centre, line)

        def orbit_at(value, P, Q, guess, check=False):
            smap = system.with_parameter(value, pname)
            if guess is None:
                if seed is not None and value == first and (P, Q) == conv[0]:
                    return seed         # the line's decision found the first orbit already (no second scan)
                return gs.first_orbit(smap, P, Q, _centre(smap, centre), line)
            orb = gs.section_symmetric_orbit(smap, Q, guess, param=pname, line=line)
            if check:   # continued orbits stay on their branch; the final ones are checked once more
                c = _centre(smap, centre)
                rot = orb.rotation(smap, c)
                if abs(abs(rot) * Q - P) > ROTATION_TOL:
                    raise ParameterError(f"the symmetric orbit of period {Q} near p1 = {orb.points[0, 0]:.8g} "
                                         f"turns {rot:.8g} per return around the centre, not {P}/{Q}")
            return orb

        def start_of(orb):
            return orb.line_start

        def point_of(orb):
            return orb.points[0]

        name = "section"
    else:
        raise ParameterError(f"greene takes a StandardMap or a SectionMap, got {type(system).__name__}")
    ks, crit, uncertainty, ratio = _critical(conv, orbit_at, start_of, first, target)
    rows = []
    guess = None
    for (P, Q), k_n in zip(conv, ks):
        orb = orbit_at(crit, P, Q, guess, check=True)
        guess = start_of(orb)
        pt = point_of(orb)
        rows.append({"p": P, "q": Q, "point": [float(pt[0]), float(pt[1])], "param_value": float(k_n),
                     "residue": orb.residue, "line_start": float(guess)})
    return GreeneResult(name, pname, x, float(crit), float(uncertainty), rows, target, ratio, float(line))


def _enough(x, qmax) -> list:
    conv = convergents(x, qmax)
    if len(conv) < 3:
        raise ParameterError(f"qmax = {qmax} gives {len(conv)} convergents of nu = {x:.10g} with q >= {MIN_Q}; "
                             f"at least 3 are needed: raise qmax")
    return conv


def _section_line(smap, conv, centre, line):
    """The section's symmetry line of Greene's orbits around ``centre``: ``line`` when given (phi0 or
    phi0 + pi), else the line of the island's elliptic orbits of even period, decided by the first even
    convergent (:func:`explorer.analysis.greene_section.island_line`; phi0 when every convergent is odd:
    an orbit of odd period meets both lines).  Returns (line, the first convergent's orbit when the
    decision found it, else None)."""
    from explorer.analysis import greene_section as gs

    if line is not None:
        value = validation.real("line", line)
        if not any(abs(math.remainder(value - phi, 2.0 * math.pi)) < 1e-12 for phi in (smap.phi0, smap.phi0 + math.pi)):
            raise ParameterError(f"line must be the section's phi0 = {smap.phi0:g} or phi0 + pi (the reversor's "
                                 f"two symmetry lines), got {line!r}")
        return value % (2.0 * math.pi), None
    even = [(P, Q) for P, Q in conv if Q % 2 == 0]
    if not even:
        return smap.phi0, None
    value, orb = gs.nearest_line_orbit(smap, *even[0], centre)
    return value, (orb if value == smap.phi0 and even[0] == conv[0] else None)


def _centre(smap, guess) -> np.ndarray:
    """The elliptic fixed point of the section map near ``guess`` (Newton)."""
    from explorer.analysis.fixedpoints import find_fixed_point

    fp = find_fixed_point(smap, tuple(float(v) for v in guess))
    if not fp.stable:
        raise ParameterError(f"the fixed point near ({guess[0]:.6g}, {guess[1]:.6g}) is not elliptic "
                             f"(trace {fp.trace:.6g}): Greene's curves surround an elliptic one")
    return np.asarray(fp.point, float)


def _critical(conv, orbit_at, start_of, first, target):
    """k_n for each convergent (R_n(k_n) = target, each orbit continued from the last) and Aitken's
    extrapolation: (k_n list, critical, uncertainty, last ratio)."""
    ks: list[float] = []
    start = None
    k_guess = first
    for P, Q in conv:
        state = {"guess": start}

        def residue_at(k, P=P, Q=Q, state=state):
            orb = orbit_at(k, P, Q, state["guess"])
            state["guess"] = start_of(orb)
            return orb

        if len(ks) >= 2:   # the geometric sequence's next term
            k_guess = ks[-1] + (ks[-1] - ks[-2]) * ((ks[-1] - ks[-2]) / (ks[-2] - ks[-3]) if len(ks) >= 3 else -0.4)
        k0 = ks[-1] if ks else k_guess
        step = 1e-3 * max(1.0, abs(k_guess)) if not ks else None
        k_n, orb = _solve_param(residue_at, target, k0, k_guess + step if step is not None else k_guess)
        ks.append(k_n)
        start = start_of(orb)
    crit = _aitken(*ks[-3:])
    prev = _aitken(*ks[-4:-1]) if len(ks) >= 4 else ks[-1]
    d = np.diff(ks)
    ratio = float(d[-1] / d[-2]) if len(d) >= 2 and d[-2] != 0 else math.nan
    return ks, float(crit), float(abs(crit - prev)), ratio
