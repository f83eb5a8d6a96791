"""One place that checks what users pass in: numbers, integers, choices, parameter sets.

Every public entry point of the package (Python API, scenes, command line) validates its
arguments with these functions, so the same input is accepted or refused the same way
everywhere, and every refusal is a :class:`ParameterError` whose one-line message names the
parameter and what is allowed::

    tol must be in [1e-16, 0.01], got 0.5
    scene key 'seeds.n' must be an integer >= 1, got 2.5 (float)

Accepted types: a real number is a Python or numpy int or float (not a bool, not a string:
the command line converts its text before calling); an integer is a Python or numpy integer
(not a bool, not a float with an integral value).  ``label`` is how the message names the
value (``"tol"``, ``"scene key 'integration.tol'"``).
"""
from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = ["ParameterError", "real", "integer", "boolean", "choice", "threads", "packed_params",
           "with_value"]


class ParameterError(ValueError):
    """Bad input: the message names the parameter and what is allowed."""


def _short(v, limit=60) -> str:
    r = repr(v.item() if isinstance(v, np.generic) else v)
    return r if len(r) <= limit else r[: limit - 3] + "..."


def _got(v) -> str:
    return f"got {_short(v)} ({type(v).__name__})"


def real(label: str, value, lo: float | None = None, hi: float | None = None, *,
         lo_open: bool = False, hi_open: bool = False) -> float:
    """A finite real number in the interval given by ``lo``/``hi`` (closed unless ``*_open``).

    Examples
    --------
    >>> real("tol", 1e-12, 1e-16, 1e-2)
    1e-12
    >>> real("dt", 0.0, 0.0, lo_open=True)
    Traceback (most recent call last):
    ...
    explorer.model.validation.ParameterError: dt must be > 0, got 0.0
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{label} must be a number, {_got(value)}")
    x = float(value)
    if not math.isfinite(x):
        raise ParameterError(f"{label} must be finite, got {_short(value)}")
    lo_ok = lo is None or (x > lo if lo_open else x >= lo)
    hi_ok = hi is None or (x < hi if hi_open else x <= hi)
    if lo_ok and hi_ok:
        return x
    if lo is not None and hi is not None:
        rng = f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
        raise ParameterError(f"{label} must be in {rng}, got {_short(value)}")
    if lo is not None:
        raise ParameterError(f"{label} must be {'>' if lo_open else '>='} {lo:g}, got {_short(value)}")
    raise ParameterError(f"{label} must be {'<' if hi_open else '<='} {hi:g}, got {_short(value)}")


def integer(label: str, value, lo: int | None = None, hi: int | None = None) -> int:
    """An integer in [lo, hi] (either bound may be None)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise ParameterError(f"{label} must be an integer, {_got(value)}")
    i = int(value)
    if lo is not None and hi is not None and not lo <= i <= hi:
        raise ParameterError(f"{label} must be an integer in [{lo}, {hi}], got {i}")
    if lo is not None and i < lo:
        raise ParameterError(f"{label} must be an integer >= {lo}, got {i}")
    if hi is not None and i > hi:
        raise ParameterError(f"{label} must be an integer <= {hi}, got {i}")
    return i


def boolean(label: str, value) -> bool:
    """True or False (a Python or numpy bool; not 0/1)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{label} must be true or false, {_got(value)}")
    return bool(value)


def choice(label: str, value, choices) -> str:
    """One of ``choices`` (strings)."""
    if not isinstance(value, str):
        raise ParameterError(f"{label} must be a string, {_got(value)}")
    if value not in choices:
        raise ParameterError(f"{label} must be one of {', '.join(choices)}; got {_short(value)}")
    return value


def threads(value, available: int) -> int:
    """A thread count for one call: an integer in [1, available], ``available`` being Numba's
    NUMBA_NUM_THREADS.  A request above it is refused, never silently lowered."""
    n = integer("threads", value, 1)
    if n > available:
        raise ParameterError(f"threads must be <= {available} (NUMBA_NUM_THREADS, read when Numba "
                             f"starts; set it in the environment for more), got {n}")
    return n


def packed_params(params) -> np.ndarray:
    """The packed float64 vector (a1, a2, b, lam, chi, zeta, mu, xi, eta) of a parameter set,
    validated (docs/model.md R3: a1, a2, b > 0, lam != 0, all finite).

    ``params``: a :class:`explorer.model.Params`, a mapping of parameter names (missing
    ones from Figure 4), or a sequence of 9 numbers.
    """
    from explorer.model.parameters import Params

    if isinstance(params, Params):
        return params.as_array()
    if isinstance(params, dict):
        return Params(**params).as_array()
    return Params.from_array(params).as_array()


def with_value(params, h: float, name: str, value):
    """``(params, h)`` with one model parameter or the energy ``h`` (``name == "h"``) replaced."""
    if name == "h":
        return params, real("h", value)
    return params.with_(**{name: real(name, value)}), h
