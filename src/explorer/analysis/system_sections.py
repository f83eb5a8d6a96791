"""Crossings of a section ``EXPR = 0`` (EXPR linear in the state) for a
:class:`explorer.model.system.System`, many orbits at once (docs/systems.md, "Crossings").

:func:`explorer.analysis.sections.crossings` hands a System here (:func:`is_system`); the result
is the same :class:`~explorer.analysis.sections.Crossings`, with the rows of a system:
``data[i, k] = (t, x_1 .. x_n, E - E0)`` (the last column only when the system has an energy),
``final[i]`` the state where orbit i stopped and ``info[i] = (t_end, steps, nan)``.

The integrator is the adaptive Taylor method (Jorba & Zou 2005, Exp. Math. 14, 99), generated
into the system's module by :mod:`explorer.integrate.codegen` (``crossings_taylor_worker``): the order
from ``tol`` (:func:`explorer.kernels.taylor_order.order_for_tolerance`), the step from the last
two coefficients, the crossings the roots of each step's polynomial of the section function,
isolated and refined as the engine's (kernels/events.py).  By default its SIMD form
(``crossings_lanes_worker``, :mod:`explorer.integrate.codegen_lanes`) runs the orbits, each with the
scalar driver's rows bit for bit (:func:`driver_for`).

This module imports neither SymPy nor numba at import time: :func:`is_system` is asked about
every argument of ``crossings``.
"""
from __future__ import annotations

import functools
import inspect
import math
import numbers
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from explorer._jit import get_num_threads, max_threads
from explorer.integrate import layout
from explorer.integrate.methods import DEFAULT_TOL, check_setting
from explorer.kernels.taylor_order import order_for_tolerance
from explorer.model import ParameterError, validation

__all__ = ["Section", "check_memory", "initial_state", "is_system", "is_system_map", "iter_system_crossings",
           "linear_section", "or_a_system", "refuse_a_system", "run_driver", "system_crossings"]

DEFAULT_MAX_STEPS = 10**9
#: the drivers of ``system_crossings(driver=)``; every one gives the same rows bit for bit.  ``auto``
#: is the lanes: a lone orbit costs as much CPU on them as on the scalar driver, 2 orbits half,
#: 64 a sixth (benchmarks/RESULTS.md, SYSTEMS)
DRIVERS = ("auto", "lanes", "scalar")
#: the settings of the engine's crossings that have no meaning for a System
_NOT_FOR_A_SYSTEM = ("h", "phi0", "dt", "block", "state")


def is_system(obj) -> bool:
    """True if ``obj`` is an :class:`explorer.model.system.System` (without importing SymPy: no
    System exists before its module is imported)."""
    mod = sys.modules.get("explorer.model.system")
    return mod is not None and isinstance(obj, mod.System)


def is_system_map(obj) -> bool:
    """True for a System's section map (an object whose ``system`` is a System)."""
    return is_system(getattr(obj, "system", None))


def refuse_a_system(name: str, obj) -> None:
    """ParameterError if ``obj`` is a System or a System's section map: analysis ``name`` takes
    Chaplygin's model and the maps of the plane only (docs/systems.md, "What is next")."""
    if is_system(obj) or is_system_map(obj):
        what = "a System" if is_system(obj) else "a System's SectionMap"
        raise ParameterError(f"{name} does not take a System yet (got {what}): of a System, explorer computes "
                             "crossings (explorer.crossings(system, states=..., section=...) or "
                             "explorer.crossings(SectionMap(system, ...), points, ...)) (docs/systems.md)")


def or_a_system(fn, result=None):
    """``fn`` (the engine's crossings) with a System path: a System as first argument goes to
    :func:`system_crossings`, its arrays made into ``result`` (the Crossings type), or with
    ``result`` None (``fn`` streams) to :func:`iter_system_crossings`; a System's map to its own
    ``crossings`` / ``iter_crossings``; ``section=`` is added to the signature and refused for the
    engine's model."""

    @functools.wraps(fn)
    def call(system, *args, section=None, **kw):
        if is_system(system):
            if result is None:
                return iter_system_crossings(system, *args, section=section, **kw)
            return result(*system_crossings(system, *args, section=section, **kw))
        if is_system_map(system):   # its points lifted to states, its section and direction
            if result is None:
                return system.iter_crossings(*args, section=section, **kw)
            return result(*system.crossings(*args, section=section, **kw))
        if section is not None:
            raise ParameterError("section= is the hyperplane EXPR = 0 of a System (docs/systems.md); the section of "
                                 "Chaplygin's model is phi = phi0 (phi0=)")
        return fn(system, *args, **kw)

    sig = inspect.signature(fn)
    call.__signature__ = sig.replace(parameters=[*sig.parameters.values(),
                                                 inspect.Parameter("section", inspect.Parameter.KEYWORD_ONLY,
                                                                   default=None)])
    call.__doc__ = (fn.__doc__ or "") + (
        f"\n    A System (docs/systems.md, \"Crossings of a section\"): ``{fn.__name__}(system, states=Y0, "
        "n_crossings=K, section=EXPR, direction=+1 or -1)``, the section EXPR = 0 with EXPR linear in the "
        "state; rows (t, state, E - E0).\n")
    return call


class Section:
    """The hyperplane s(x) = a . x + b = 0 of a system's state, with its expression."""

    def __init__(self, expr, a: np.ndarray, b: float):
        self.expr = expr
        self.a = a
        self.b = b

    def __call__(self, y) -> np.ndarray:
        """s at the states ``y`` (..., n)."""
        return np.asarray(y, dtype=np.float64) @ self.a + self.b


#: (content hash, parameter values, section) -> its Section: a map's section, parsed once
_SECTIONS: dict = {}
_SECTIONS_KEPT = 256


def linear_section(system, section) -> Section:
    """The section ``section = 0`` of ``system``: a SymPy expression (or a state symbol) linear in
    the state, with numbers and the system's parameters (at their values) as coefficients, parsed
    once per system content, parameter values and expression.  ParameterError naming ``section``
    otherwise: not an expression, a symbol that is neither a state variable nor a parameter, a term
    that is not linear in the state, no state at all."""
    import sympy as sp

    key = None
    if isinstance(section, sp.Basic):
        key = (system.content_hash, tuple(system.parameter_array()), section)
        if key in _SECTIONS:
            return _SECTIONS[key]
        if len(_SECTIONS) >= _SECTIONS_KEPT:
            _SECTIONS.clear()
    sec = _parse_section(system, section)
    if key is not None:
        _SECTIONS[key] = sec
    return sec


def _parse_section(system, section) -> Section:
    import sympy as sp

    from explorer.model.validation import did_you_mean

    if section is None:
        raise ParameterError("section is missing: give EXPR of the section EXPR = 0, linear in the state "
                             f"({', '.join(s.name for s in system.states)}), e.g. section={system.states[0].name}")
    if isinstance(section, bool):
        raise ParameterError(f"section must be a sympy expression linear in the state, got {section!r}")
    try:
        expr = sp.sympify(section, strict=True)
    except (sp.SympifyError, TypeError):
        raise ParameterError(f"section must be a sympy expression linear in the state, got {section!r} "
                             f"({type(section).__name__})") from None
    if not isinstance(expr, sp.Expr):
        raise ParameterError(f"section must be a sympy expression linear in the state, got {section!r}")
    states = system.states
    known = set(states) | set(system.parameters)
    unknown = sorted((s for s in expr.free_symbols if s not in known), key=lambda s: s.name)
    if unknown:
        u = unknown[0]
        hint = did_you_mean(u.name, [s.name for s in known])
        raise ParameterError(f"section {expr} uses {u.name}, which is neither a state variable "
                             f"({', '.join(s.name for s in states)}) nor a parameter of {system.name}{hint}")
    coefficients = []
    for s in states:
        d = sp.diff(expr, s)
        if d.free_symbols & set(states):
            raise ParameterError(f"section {expr} is not linear in the state: its derivative by {s.name} is {d}; "
                                 "give a sum of numbers (or parameters) times state variables, plus a constant")
        coefficients.append(d)
    offset = sp.expand(expr - sum(c * s for c, s in zip(coefficients, states)))
    if offset.free_symbols & set(states):
        raise ParameterError(f"section {expr} is not linear in the state")
    values = {p: v for p, v in system.parameters.items()}
    try:
        a = np.array([float(sp.sympify(c).subs(values)) for c in coefficients], dtype=np.float64)
        b = float(sp.sympify(offset).subs(values))
    except TypeError:
        raise ParameterError(f"section {expr} must have real coefficients") from None
    if not (np.all(np.isfinite(a)) and math.isfinite(b)):
        raise ParameterError(f"section {expr} must have finite coefficients, got {a.tolist()} and {b}")
    if not np.any(a != 0.0):
        raise ParameterError(f"section {expr} does not depend on the state: give EXPR of EXPR = 0 with at least "
                             f"one state variable ({', '.join(s.name for s in states)})")
    return Section(expr, a, b)


def _states(system, states) -> np.ndarray:
    n = system.dimension
    names = ", ".join(s.name for s in system.states)
    if states is None:
        raise ParameterError(f"states is missing: give the start of each orbit, shape (N, {n}) = ({names})")
    try:
        Y0 = np.atleast_2d(np.asarray(states, dtype=np.float64))
    except (TypeError, ValueError):
        raise ParameterError(f"states must be an array of shape (N, {n}) = ({names}) per orbit, got {states!r}") \
            from None
    if Y0.ndim != 2 or Y0.shape[1] != n or Y0.shape[0] < 1:
        raise ParameterError(f"states must have shape (N, {n}) = ({names}) per orbit, got {np.shape(states)}")
    if not np.all(np.isfinite(Y0)):
        i = int(np.flatnonzero(~np.all(np.isfinite(Y0), axis=1))[0])
        raise ParameterError(f"states must be finite; orbit {i} has {Y0[i].tolist()}")
    return np.ascontiguousarray(Y0)


def system_crossings(system, states=None, *, n_crossings: int, section=None, direction: int = 1,
                     method: str = "taylor", tol: float = DEFAULT_TOL, tmax: float | None = None,
                     max_steps: int = DEFAULT_MAX_STEPS, threads: int | None = None, driver: str = "auto",
                     backward: bool = False, **other):
    """Integrate each orbit of ``system`` from ``states`` (N, n) until it has crossed the section
    ``section = 0`` ``n_crossings`` times in ``direction`` (+1: ds/dt > 0, -1: ds/dt < 0), or its
    time budget ``tmax`` (default 100 * n_crossings) or ``max_steps`` runs out.  Returns the
    arguments of :class:`~explorer.analysis.sections.Crossings` (data, count, status, final,
    info, method, settings); the rows and statuses as in the module docstring.  ``tol``: the
    Taylor method's, as the engine's (docs/methods.md).  ``driver``: one of :data:`DRIVERS`
    (:func:`driver_for`); the rows do not depend on it.  ``backward``: backward in time (the flow of
    -f, exactly), t the time elapsed backward and ``direction`` the sign of ds/dt along it."""
    run = _SystemRun(system, states, n_crossings, section, direction, method, tol, tmax, max_steps, threads, driver,
                     backward, other)
    N, K = run.Y0.shape[0], run.K
    check_memory(f"crossings: {N} orbits x {K} crossings", N * K * run.width * 8, "lower n_crossings or the orbits")
    carry = run.start(run.Y0)
    data, count, status, final, info = run.block(run.Y0, carry, np.full((N, 2), K, np.int64), K, run.max_steps)
    return data, count, status, final, info, "taylor", run.settings


def iter_system_crossings(system, states=None, *, n_crossings: int, section=None, direction: int = 1,
                          block: int | None = None, state=None, method: str = "taylor", tol: float = DEFAULT_TOL,
                          tmax: float | None = None, max_steps: int = DEFAULT_MAX_STEPS, threads: int | None = None,
                          driver: str = "auto", backward: bool = False, step_block: int | None = None, **other):
    """:func:`system_crossings` in blocks of about ``block`` crossings per orbit (default
    crossings_run.DEFAULT_BLOCK), each a :class:`~explorer.analysis.crossings_run.CrossingBlock` whose
    rows continue the orbits' carry bit for bit, so the blocks concatenate to one run's rows, in
    O(N x block) memory; ``state`` (a block's ``state``) resumes the run (docs/systems.md, "Crossings").
    ``step_block``: a block also ends once no orbit may take more than that many steps in it, and the next
    continues it exactly, as Chaplygin's (explorer.analysis.sections.iter_crossings).  Checks its arguments at
    the call."""
    from explorer.analysis.crossings_run import DEFAULT_BLOCK, StreamState, check_step_block, stream

    run = _SystemRun(system, states, n_crossings, section, direction, method, tol, tmax, max_steps, threads, driver,
                     backward, other)
    block = DEFAULT_BLOCK if block is None else block
    if isinstance(block, bool) or not isinstance(block, numbers.Integral) or block < 1:
        raise ParameterError(f"block must be an integer >= 1, got {block!r}")
    check_step_block(step_block, method)
    N = run.Y0.shape[0]
    if state is None:
        state = run.initial()
    elif not isinstance(state, StreamState) or state.y.shape != run.Y0.shape \
            or state.carry.shape != (N, layout.N_CARRY):
        raise ParameterError(f"state must be the StreamState of a block of these {N} orbits of {system.name}")
    else:
        state = state.copy()
    return stream(state, run.K, int(block), run.block, run.max_steps, step_block)


def initial_state(system, states=None, *, n_crossings: int, section=None, direction: int = 1, **kw):
    """The StreamState that :func:`iter_system_crossings` with these arguments starts from (a store of
    blocks resumes from it, io.store.stream)."""
    return _SystemRun(system, states, n_crossings, section, direction, kw.pop("method", "taylor"),
                      kw.pop("tol", DEFAULT_TOL), kw.pop("tmax", None), kw.pop("max_steps", DEFAULT_MAX_STEPS),
                      kw.pop("threads", None), kw.pop("driver", "auto"), kw.pop("backward", False), kw).initial()


class _SystemRun:
    """The checked settings of a System's crossings and its generated module: :meth:`start` the carry of
    states, :meth:`block` one block of the crossing driver."""

    def __init__(self, system, states, n_crossings, section, direction, method, tol, tmax, max_steps, threads,
                 driver, backward, other):
        from explorer.analysis import budget
        from explorer.integrate import codegen

        given = [k for k in _NOT_FOR_A_SYSTEM if k in other]
        if given:
            raise ParameterError(f"crossings of a System: {', '.join(given)} do(es) not apply (the section is "
                                 "section=EXPR, the start states=)")
        if other:
            raise ParameterError(f"crossings of a System has no setting {', '.join(sorted(other))}")
        if method != "taylor":
            raise ParameterError(f"method must be 'taylor' for a System (the generated Taylor integrator), "
                                 f"got {method!r}")
        budget.checkpoint()
        max_steps = budget.step_cap(max_steps)
        self.K = K = validation.integer("n_crossings", n_crossings, 1)
        if isinstance(direction, bool) or not isinstance(direction, numbers.Integral) or direction not in (-1, 1):
            raise ParameterError(f"direction must be +1 (ds/dt > 0) or -1 (ds/dt < 0), got {direction!r}")
        tol = check_setting("tol", tol)
        tmax = 100.0 * K if tmax is None else validation.real("tmax", tmax, 0.0, lo_open=True)
        max_steps = validation.integer("max_steps", max_steps, 1)
        if threads is not None:
            threads = validation.threads(threads, max_threads())
        if not isinstance(backward, bool):
            raise ParameterError(f"backward must be True or False, got {backward!r}")
        if driver not in DRIVERS:
            raise ParameterError(f"driver must be one of {', '.join(map(repr, DRIVERS))}, got {driver!r}")
        self.sec = sec = linear_section(system, section)
        self.Y0 = _states(system, states)
        self.order = order = order_for_tolerance(tol)
        self.mod = codegen.load(system)
        self.P = system.parameter_array()
        self.dimension = n = system.dimension
        self.width = 1 + n + (system.energy is not None)
        self.args = (sec.a, float(sec.b), every_crossing(n), np.arange(n), int(direction), float(tmax), int(order))
        self.max_steps = int(max_steps)
        self.driver, self.threads, self.backward = driver, threads, backward
        columns = ["t", *(s.name for s in system.states)] + (["E - E0"] if system.energy is not None else [])
        self.settings = {"method": "taylor", "tol": tol, "order": order, "system": system.name,
                         "section": str(sec.expr), "direction": int(direction), "tmax": tmax,
                         "max_steps": max_steps, "n_crossings": K, "columns": columns}
        if backward:
            self.settings["backward"] = True

    def initial(self):
        """The StreamState of these orbits before their first block."""
        from explorer.analysis.crossings_run import StreamState

        N = self.Y0.shape[0]
        return StreamState(self.Y0.copy(), self.start(self.Y0), np.zeros(N, np.int64), np.zeros(N, bool),
                           np.zeros(N, np.int64), np.zeros((N, 3)), 0)

    def start(self, Y) -> np.ndarray:
        """The carry of orbits starting at the states ``Y``: t = 0, s(y), no steps, E0."""
        carry = np.empty((Y.shape[0], layout.N_CARRY))
        self.mod.crossings_start(Y, self.P, self.sec.a, float(self.sec.b), carry)
        return carry

    def block(self, Y, carry, limits, width: int, max_steps: int):
        """(data, count, status, final, info) of the orbits from ``Y`` continued from ``carry`` (in place)
        up to ``limits`` (target, room), ``width`` rows each, and ``max_steps`` steps."""
        N = Y.shape[0]
        data = np.full((N, width, self.width), np.nan)
        count, status = np.zeros(N, np.int64), np.zeros(N, np.int64)
        final, info = np.zeros((N, self.dimension)), np.zeros((N, 3))
        run_driver(self.mod, "crossings", N, self.driver, self.threads,
                   (Y, self.P, *self.args, max_steps, carry, limits, data, count, status, final, info, self.backward))
        return data, count, status, final, info


def every_crossing(dimension: int) -> np.ndarray:
    """The ``keep`` of the generated crossing drivers that keeps every root: keep . (y, 1) = 1 > 0."""
    keep = np.zeros(dimension + 1)
    keep[dimension] = 1.0
    return keep


def check_memory(what: str, need: int, hint: str) -> None:
    """ParameterError when ``need`` bytes exceed validation.MAX_MEMORY_FRACTION of this machine's memory."""
    mem = validation.physical_memory()
    if mem and need > validation.MAX_MEMORY_FRACTION * mem:
        raise ParameterError(f"{what} need {validation.human_bytes(need)} in memory "
                             f"(this machine has {validation.human_bytes(mem)}); {hint}")


#: the threads that run a driver's workers beside the calling thread, shared by every call (numba's
#: thread count less one): a call starts no thread of its own, so a long-lived caller (the page) keeps
#: a fixed set of threads
DRIVER_THREADS = max(1, max_threads() - 1)
_POOL = ThreadPoolExecutor(max_workers=DRIVER_THREADS, thread_name_prefix="explorer-driver")


def run_driver(mod, name: str, n: int, driver: str, threads, args: tuple) -> None:
    """The generated driver ``name`` of module ``mod`` on ``n`` orbits with ``args``: ``<name>_taylor_worker``
    (the scalar form) or ``<name>_lanes_worker`` (groups of LANES lanes, :func:`driver_for`), on ``threads``
    threads (None: numba's thread count) that take the orbits from one queue.  The workers release the
    GIL, so the threads run at once; each orbit is computed alone, so the result does not depend on the
    threads.  Plain threads, not a numba parallel region: a parallel region would be compiled anew for
    every generated module, a few seconds each (docs/systems.md, "The cache")."""
    count = get_num_threads() if threads is None else int(threads)
    workers = driver_for(n, driver, count)
    # (interned: CPython's type-lookup cache keeps a reference to each distinct name string it sees, so a
    # new string per call held about 70 bytes per call alive, up to the cache's 4096 entries)
    worker = getattr(mod, sys.intern(f"{name}_lanes_worker" if workers else f"{name}_taylor_worker"))
    workers = workers or max(1, min(count, n))
    queue = np.zeros(1, np.int64)
    if workers == 1:
        worker(queue, *args)
        return
    others = [_POOL.submit(worker, queue, *args) for _ in range(workers - 1)]   # this thread is the last worker
    worker(queue, *args)
    for done in others:
        done.result()


def driver_for(n: int, driver: str = "auto", threads: int | None = None) -> int:
    """How ``n`` orbits run: 0 on the scalar driver (one orbit per thread), else on that many groups of
    LANES SIMD lanes (one per thread of ``threads``, numba's count by default, no more than
    ceil(n / LANES)); ``auto`` is the lanes."""
    from explorer.integrate.simd import LANES

    if driver == "scalar":
        return 0
    return max(1, min(get_num_threads() if threads is None else threads, -(-n // LANES)))
