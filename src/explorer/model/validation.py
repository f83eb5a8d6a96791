"""The checks of what users pass in (docs/bad_input.md): every public entry point validates with
these, and every refusal is a one-line :class:`ParameterError` naming the parameter and what is
allowed.  A real is a Python or numpy int or float (not bool, not str); an integer a Python or
numpy integer; ``label`` is how the message names the value.
"""
from __future__ import annotations

import difflib
import math
import numbers
import os
import re
import tempfile

import numpy as np

__all__ = ["MAX_CONTINUATION_STEPS", "MAX_JOBS", "MAX_MAGNITUDE", "MAX_MEMORY_FRACTION", "MAX_PERIOD",
           "MAX_TEXT_CHARS", "ParameterError", "angle_text", "boolean", "choice", "continuation_steps", "did_you_mean",
           "fits_in_memory", "human_bytes", "input_file", "integer", "magnitude", "number_text", "output_path",
           "physical_memory", "real", "threads", "writable_directory"]

#: largest absolute value of a model parameter, the energy h or a start coordinate.
MAX_MAGNITUDE = 1e8
#: an array sized by a user's count may take at most this fraction of the machine's memory
#: (:func:`fits_in_memory`; :func:`explorer.analysis.sections.crossings` uses it too)
MAX_MEMORY_FRACTION = 0.5
#: largest period K of a periodic orbit: multiple shooting solves a (2K x 2K) system per Newton step
MAX_PERIOD = 1000
#: largest number of parameter steps of a continuation (--continue PARAM START STOP STEP)
MAX_CONTINUATION_STEPS = 100_000
#: largest number of worker processes of a sweep (--jobs)
MAX_JOBS = 1024
#: longest text read as one value (a page's field, a link's argument, an option's word)
MAX_TEXT_CHARS = 64


class ParameterError(ValueError):
    """Bad input: the message names the parameter and what is allowed."""


def _short(v, limit=60) -> str:
    r = repr(v.item() if isinstance(v, np.generic) else v)
    return r if len(r) <= limit else r[: limit - 3] + "..."


def _got(v) -> str:
    return f"got {_short(v)} ({type(v).__name__})"


def real(label: str, value, lo: float | None = None, hi: float | None = None, *,
         lo_open: bool = False, hi_open: bool = False) -> float:
    """A finite real number in the interval given by ``lo``/``hi`` (closed unless ``*_open``)."""
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


def number_text(label: str, text, whole: bool = False):
    """A number written as text (a page's field, a link's argument): a finite float (``whole``: an int)."""
    s = str(text).strip()
    try:
        if len(s) > MAX_TEXT_CHARS:
            raise ValueError
        value = int(s) if whole else float(s)
    except ValueError:
        raise ParameterError(f"{label} must be {'a whole number' if whole else 'a number'}, "
                             f"got {s[:MAX_TEXT_CHARS]!r}") from None
    return value if whole else real(label, value)


def angle_text(label: str, text) -> float:
    """An angle written as text: a number, or ``pi`` (``π``) times or over a number (``-pi``, ``2pi``, ``pi/2``,
    ``0.5*pi``)."""
    s = str(text).strip().lower().replace("π", "pi").replace(" ", "")
    if "pi" not in s:
        return number_text(label, text)
    m = re.fullmatch(r"([+-]?)(.*?)\*?pi(?:/(.+))?", s) if len(s) <= MAX_TEXT_CHARS else None
    try:
        if m is None:
            raise ValueError
        value = float(m[1] + (m[2] or "1")) * math.pi / float(m[3] or 1)
    except (ValueError, ZeroDivisionError):
        raise ParameterError(f"{label} must be a number or a multiple of pi (pi, -pi, 2pi, pi/2), "
                             f"got {str(text).strip()[:MAX_TEXT_CHARS]!r}") from None
    return real(label, value)


def magnitude(label: str, value, limit: float = MAX_MAGNITUDE) -> float:
    """A finite real number with ``|value| <= limit`` (default :data:`MAX_MAGNITUDE`)."""
    x = real(label, value)
    if abs(x) > limit:
        name = "MAX_MAGNITUDE" if limit == MAX_MAGNITUDE else "the limit"
        raise ParameterError(f"{label} must be in [-{limit:g}, {limit:g}] ({name}), got {x:g}")
    return x


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


def did_you_mean(value: str, choices) -> str:
    """``" (did you mean 'x'?)"`` for the closest of ``choices``, or "" when none is close."""
    value = str(value)
    close = difflib.get_close_matches(value, list(choices), n=1) or [
        c for c in choices if value and (value.startswith(c) or c.startswith(value))]
    return f" (did you mean '{close[0]}'?)" if close else ""


def physical_memory() -> int:
    """Bytes of physical memory of this machine (0 when the system does not say)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 0


def human_bytes(nbytes: float) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if nbytes < 1000 or unit == "PB":
            return f"{nbytes:.3g} {unit}"
        nbytes /= 1000.0
    return f"{nbytes:.3g} PB"


def fits_in_memory(label: str, count: int, item_bytes: int, what: str, lo: int = 0) -> int:
    """``count`` (an integer >= ``lo``) when ``count * item_bytes`` bytes fit in
    :data:`MAX_MEMORY_FRACTION` of this machine's memory; else a ParameterError naming the label,
    the size and the machine's memory (``what`` says what is counted)."""
    n = integer(label, count, lo)
    need = n * int(item_bytes)
    mem = physical_memory()
    if mem and need > MAX_MEMORY_FRACTION * mem:
        raise ParameterError(f"{label} = {n} needs {human_bytes(need)} in memory ({what}); at most "
                             f"{MAX_MEMORY_FRACTION:g} x this machine's {human_bytes(mem)} (MAX_MEMORY_FRACTION)")
    return n


def continuation_steps(label: str, start, stop, step) -> tuple:
    """(start, stop, step) of a continuation: finite numbers, STEP nonzero with the sign of
    STOP - START, at most :data:`MAX_CONTINUATION_STEPS` steps."""
    start, stop, step = (real(f"{label} {n}", v) for n, v in (("START", start), ("STOP", stop), ("STEP", step)))
    if step == 0.0 or (stop - start) * step < 0.0:
        raise ParameterError(f"{label} needs a nonzero STEP of the sign of STOP - START, got START {start:g}, "
                             f"STOP {stop:g}, STEP {step:g}")
    n = abs(stop - start) / abs(step)
    if not n <= MAX_CONTINUATION_STEPS:
        raise ParameterError(f"{label} would take {n:.3g} steps; at most {MAX_CONTINUATION_STEPS} "
                             "(MAX_CONTINUATION_STEPS): raise STEP or narrow START..STOP")
    return start, stop, step


def writable_directory(label: str, target, directory) -> None:
    """Refuse (one line naming ``label`` and ``target``) unless ``directory`` exists and a file can
    be created in it (a probe file is created and removed at once: as root no permission bit
    refuses, but a read-only or virtual file system such as /proc does)."""
    directory = os.fspath(directory)
    if not os.path.isdir(directory):
        raise ParameterError(f"{label} {target}: cannot write into the directory '{directory}' (not a directory)")
    try:
        with tempfile.NamedTemporaryFile(dir=directory, prefix=".explorer-write-test-"):
            pass
    except OSError as exc:
        raise ParameterError(f"{label} {target}: cannot write into the directory '{directory}' "
                             f"({exc.strerror or exc})") from None


def output_path(label: str, path, *, directory: bool = False) -> str:
    """A place a command will write: a non-empty path whose nearest existing ancestor is a
    directory where a file can be created; with ``directory`` the path itself is (or will be) a
    directory, else it must not be one, and an existing file there must be writable (a read-only
    file is refused, never replaced).  Nothing is created (a probe file is created and removed)."""
    if not isinstance(path, (str, os.PathLike)) or not os.fspath(path).strip():
        raise ParameterError(f"{label} must be a non-empty path, got {_short(path)}")
    path = os.fspath(path)
    full = os.path.abspath(path)
    if os.path.isdir(full):
        if not directory:
            raise ParameterError(f"{label} {path}: is a directory; give a file path")
        writable_directory(label, path, full)
        return path
    if os.path.exists(full):
        if directory:
            raise ParameterError(f"{label} {path}: is a file; give a directory")
        if not os.access(full, os.W_OK):
            raise ParameterError(f"{label} {path}: the file is read-only; make it writable or choose another path")
    ancestor = os.path.dirname(full)
    while not os.path.exists(ancestor):
        ancestor = os.path.dirname(ancestor)
    writable_directory(label, path, ancestor)
    return path


def input_file(label: str, path) -> str:
    """A file a command reads: a non-empty path of an existing regular file."""
    if not isinstance(path, (str, os.PathLike)) or not os.fspath(path).strip():
        raise ParameterError(f"{label} must be a non-empty path, got {_short(path)}")
    if not os.path.isfile(path):
        raise ParameterError(f"{label} {os.fspath(path)!r} is not a file")
    return os.fspath(path)


def threads(value, available: int) -> int:
    """A thread count for one call: an integer in [1, available], ``available`` being Numba's
    NUMBA_NUM_THREADS.  A request above it is refused, never silently lowered."""
    n = integer("threads", value, 1)
    if n > available:
        raise ParameterError(f"threads must be <= {available} (NUMBA_NUM_THREADS, read when Numba "
                             f"starts; set it in the environment for more), got {n}")
    return n
