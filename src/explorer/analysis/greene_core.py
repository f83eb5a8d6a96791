"""Greene's residue criterion, what both families of orbits share (docs/greene.md, "The criterion"):
convergents, residues, the secant solve of R_n(k_n) = R* and the extrapolation of the k_n."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from explorer.model import ParameterError, validation

__all__ = ["CRITICAL_RESIDUE", "GOLDEN", "GreeneResult", "Residue", "aitken", "convergents", "critical_parameter",
           "enough_convergents", "extrapolate", "rotation_value"]

GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: MacKay 1983 (Physica D 7, 283): R* of noble curves
CRITICAL_RESIDUE = 0.2500888
#: the default largest period: standard map, section map
DEFAULT_QMAX, SECTION_QMAX = 987, 55
MAX_QMAX, MIN_Q = 4181, 2
#: the secant in the parameter: tolerance, iterations, largest step (fraction of max(|k|, last step))
PARAM_TOL, PARAM_MAX_ITER, MAX_PARAM_STEP = 1e-14, 60, 0.2
#: the extrapolations whose spread is the uncertainty
SPREAD_OF = 3
NAMED = {"golden": GOLDEN, "golden2": 1.0 - GOLDEN}
NU_FORMS = "a number in (0, 1), golden, golden2, noble:A = 1/(A + golden) or noble:A,B,... = [0; A, B, ..., 1, 1, ...]"


def rotation_value(nu) -> float:
    """The rotation number ``nu`` in one of :data:`NU_FORMS`."""
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
            raise ParameterError(f"nu must be {NU_FORMS}, got {nu!r}") from None
    return validation.real("nu", nu, 0.0, 1.0, lo_open=True, hi_open=True)


def convergents(nu, qmax: int, qmin: int = MIN_Q) -> list:
    """The convergents P/Q of the continued fraction of ``nu`` with ``qmin`` <= Q <= ``qmax``, in order."""
    x = rotation_value(nu)
    qmax = validation.integer("qmax", qmax, 2, MAX_QMAX)
    h0, h1, k0, k1 = 0, 1, 1, 0
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


def enough_convergents(x: float, qmax) -> list:
    """:func:`convergents` of ``x`` up to ``qmax``, at least three of them."""
    conv = convergents(x, qmax)
    if len(conv) < 3:
        raise ParameterError(f"qmax = {qmax} gives {len(conv)} convergents of nu = {x:.10g} with q >= {MIN_Q}; "
                             f"at least 3 are needed: raise qmax")
    return conv


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
class GreeneResult:
    """:func:`explorer.greene`'s result; ``convergents``: dicts of :data:`JSON_KEYS` and ``line_start``
    (docs/commands/greene.md)."""

    map: str
    param: str
    nu: float
    critical: float
    uncertainty: float
    convergents: list = field(default_factory=list)
    critical_residue: float = CRITICAL_RESIDUE
    ratio: float = math.nan
    line: float = math.pi

    JSON_KEYS = ("p", "q", "param_n", "residue_at_critical", "point_at_critical")

    def as_dict(self) -> dict:
        """The JSON form of ``python -m explorer greene --json`` (docs/commands/greene.md)."""
        return {"map": self.map, "param": self.param, "nu": self.nu, "critical": self.critical,
                "uncertainty": self.uncertainty,
                "convergents": [{key: c[key] for key in self.JSON_KEYS} for c in self.convergents]}


def solve_param(residue_at, target, k0, k1):
    """(k, orbit) with residue_at(k).residue = target, by the secant from k0, k1."""
    fa = residue_at(k0).residue - target
    ka, kb = k0, k1
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
        kc = min(max(kc, kb - limit), kb + limit)
        ka, fa = kb, fb
        if abs(kc - kb) <= PARAM_TOL * max(1.0, abs(kb)):
            return kc, residue_at(kc)
        kb = kc
    raise ParameterError(f"the residue did not reach {target:g} (last parameter {kb:.12g})")


def aitken(x0, x1, x2) -> float:
    """Aitken's Delta^2 extrapolation of three terms of a geometric sequence."""
    d1, d2 = x1 - x0, x2 - x1
    if d2 == d1:
        return x2
    return x2 - d2 * d2 / (d2 - d1)


def extrapolate(ks) -> tuple:
    """(critical, uncertainty, last ratio) of k_n, n >= 3 (docs/greene.md, "The criterion"): Aitken's
    Delta^2 of the last three; the spread of the last :data:`SPREAD_OF` extrapolations (with k_n if fewer)."""
    ks = [float(k) for k in ks]
    if len(ks) < 3:
        raise ParameterError(f"extrapolate needs at least 3 values, got {len(ks)}")
    estimates = [aitken(*ks[i - 2:i + 1]) for i in range(2, len(ks))]
    if len(estimates) < SPREAD_OF:
        estimates.insert(0, ks[-1])
    last = estimates[-SPREAD_OF:]
    d = np.diff(ks)
    ratio = float(d[-1] / d[-2]) if d[-2] != 0 else math.nan
    return estimates[-1], max(last) - min(last), ratio


def critical_parameter(conv, orbit_at, start_of, point_of, first, target):
    """(rows of :attr:`GreeneResult.convergents`, critical, uncertainty, ratio): k_n of each convergent
    from ``first``, each orbit ``orbit_at(k, P, Q, guess, check)`` continued from ``start_of`` the
    last, and ``point_of`` each orbit at the critical value."""
    ks: list[float] = []
    start = None
    k_guess = first
    for P, Q in conv:
        state = {"guess": start}

        def residue_at(k, P=P, Q=Q, state=state):
            orb = orbit_at(k, P, Q, state["guess"], False)
            state["guess"] = start_of(orb)
            return orb

        if len(ks) >= 2:
            k_guess = ks[-1] + (ks[-1] - ks[-2]) * ((ks[-1] - ks[-2]) / (ks[-2] - ks[-3]) if len(ks) >= 3 else -0.4)
        if ks:
            k_n, orb = solve_param(residue_at, target, ks[-1], k_guess)
        else:
            k_n, orb = solve_param(residue_at, target, k_guess, k_guess + 1e-3 * max(1.0, abs(k_guess)))
        ks.append(k_n)
        start = start_of(orb)
    crit, uncertainty, ratio = extrapolate(ks)
    rows = []
    guess = None
    for (P, Q), k_n in zip(conv, ks):
        orb = orbit_at(crit, P, Q, guess, True)
        guess = start_of(orb)
        pt = point_of(orb)
        rows.append({"p": P, "q": Q, "param_n": float(k_n), "residue_at_critical": orb.residue,
                     "point_at_critical": [float(pt[0]), float(pt[1])], "line_start": float(guess)})
    return rows, float(crit), float(uncertainty), ratio
