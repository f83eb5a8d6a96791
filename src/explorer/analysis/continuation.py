"""Natural-parameter continuation shared by fixed points and periodic orbits: the parameter
values, a secant follower and golden-section refinement (docs/commands/periodic.md)."""
from __future__ import annotations

import math

import numpy as np

from explorer import model
from explorer.model import ParameterError

__all__ = ["continuation_values", "golden_section_max", "secant_follower"]


def continuation_values(parameter, start, stop, step, allowed=None) -> np.ndarray:
    """The values start, start + step, ..., up to stop of a continuation in ``parameter`` (one of
    ``allowed``; default a model parameter or "h": a section map's), validated (ParameterError
    naming what is allowed)."""
    allowed = model.PARAM_NAMES + ("h",) if allowed is None else tuple(allowed)
    if parameter not in allowed:
        raise ParameterError(f"continuation parameter must be one of {', '.join(allowed)}")
    if step == 0 or not all(math.isfinite(v) for v in (start, stop, step)) or (stop - start) * step < 0:
        raise ParameterError("--continue needs finite START, STOP and a STEP of the sign of STOP - START")
    n = int(math.floor((stop - start) / step + 1e-9)) + 1
    return start + step * np.arange(n)


def secant_follower(solve, guess, state_of, max_halvings):
    """Natural-parameter continuation: returns ``advance(v)``, the solution at parameter value
    ``v`` by ``solve(v, prediction)``, predicted from the last two solutions by a secant (from
    ``guess`` at first); when ``solve`` raises ParameterError the step is halved (the midpoint
    solved first), at most ``max_halvings`` times.  ``state_of(solution)`` is what is predicted
    (a point, or the K points of a periodic orbit)."""
    prev: list = []  # (value, state) of the last two solutions

    def predict(v):
        if len(prev) < 2:
            return prev[-1][1] if prev else guess
        (v0, x0), (v1, x1) = prev[-2], prev[-1]
        return x1 + (x1 - x0) * (v - v1) / (v1 - v0)

    def advance(v, depth=0):
        try:
            sol = solve(v, predict(v))
        except ParameterError:
            if depth >= max_halvings or not prev:
                raise
            advance(0.5 * (prev[-1][0] + v), depth + 1)
            return advance(v, depth + 1)
        prev.append((v, state_of(sol)))
        del prev[:-2]
        return sol

    return advance


def golden_section_max(f, a, b, tol):
    """Maximum of a unimodal f on [a, b] by golden-section search, to ``tol`` relative to
    max(1, |b|); returns (x, f(x))."""
    g = (math.sqrt(5.0) - 1.0) / 2.0
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = f(c), f(d)
    while abs(b - a) > tol * max(1.0, abs(b)):
        if fc > fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = f(d)
    return (c, fc) if fc > fd else (d, fd)
