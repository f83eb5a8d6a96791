"""The states of a :class:`explorer.model.system.System`'s orbits at given times (docs/systems.md,
"The flow at given times"): ``flow(system, states=Y0, times=ts)``.

The integrator is the adaptive Taylor method of the crossings (Jorba & Zou 2005, Exp. Math. 14, 99),
generated into the system's module (``flow_taylor_worker``, :mod:`explorer.integrate.codegen_flow`): each
sample is the polynomial of the step that contains it, at the integrator's order, so the samples
change no step; the last step is clipped onto the last time.  By default its SIMD form (``flow_lanes_worker``)
runs the orbits, each with the scalar driver's samples bit for bit.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from explorer._jit import max_threads
from explorer.analysis.system_sections import DEFAULT_MAX_STEPS, DRIVERS, _states, check_memory, is_system, run_driver
from explorer.integrate.methods import DEFAULT_TOL, check_setting
from explorer.kernels import Status
from explorer.kernels.taylor_order import order_for_tolerance
from explorer.model import ParameterError, validation

__all__ = ["Flow", "flow"]


@dataclass(frozen=True)
class Flow:
    """Orbits sampled at the times ``t`` (M,): ``states[i, m]`` (N, M, n) the state of orbit i at
    ``t[m]``, NaN beyond where it stopped; ``energy_error[i, m]`` = ``|E - E0|`` there (NaN without an
    energy); ``status[i]`` (DONE when the last time is reached); ``steps[i]`` its Taylor steps."""

    t: np.ndarray
    states: np.ndarray
    energy_error: np.ndarray
    status: np.ndarray
    steps: np.ndarray
    settings: dict = field(default_factory=dict)

    def status_of(self, i: int) -> Status:
        """Why orbit ``i`` stopped, as a :class:`~explorer.kernels.Status`."""
        return Status(int(self.status[i]))


def _times(times) -> np.ndarray:
    if times is None:
        raise ParameterError("times is missing: give the sorted times >= 0 at which to sample the orbits")
    try:
        ts = np.asarray(times, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"times must be a sequence of real numbers, got {times!r}") from None
    ts = np.atleast_1d(ts)
    if ts.ndim != 1 or ts.size < 1:
        raise ParameterError(f"times must be a non-empty 1-D sequence of times, got shape {np.shape(times)}")
    if not np.all(np.isfinite(ts)):
        raise ParameterError(f"times must be finite, got {ts[~np.isfinite(ts)][0]} at index "
                             f"{int(np.flatnonzero(~np.isfinite(ts))[0])}")
    if ts[0] < 0.0:
        raise ParameterError(f"times must be >= 0 (the orbits start at t = 0), got {ts[0]}")
    down = np.flatnonzero(np.diff(ts) < 0.0)
    if down.size:
        k = int(down[0])
        raise ParameterError(f"times must be sorted non-decreasing, got {ts[k]} before {ts[k + 1]} at index {k + 1}")
    return np.ascontiguousarray(ts)


def flow(system, states=None, *, times=None, tol: float = DEFAULT_TOL, max_steps: int = DEFAULT_MAX_STEPS,
         threads: int | None = None, driver: str = "auto") -> Flow:
    """The state of each orbit of ``system`` (a row of ``states``, (N, n) in the system's state
    order) at each of ``times`` (finite, >= 0, sorted non-decreasing; t = 0 is the start exactly),
    with the adaptive Taylor method of tolerance ``tol`` (docs/methods.md), up to ``max_steps``
    steps an orbit, on ``threads`` threads and ``driver`` (system_sections.DRIVERS: ``auto`` the SIMD
    lanes, ``scalar`` one orbit per thread; the result depends on neither).  Returns a
    :class:`Flow` (docs/systems.md, "The flow at given times")."""
    from explorer.analysis import budget
    from explorer.integrate import codegen

    if not is_system(system):
        raise ParameterError(f"flow takes a System (explorer.System or explorer.classic), got {type(system).__name__}")
    budget.checkpoint()
    max_steps = validation.integer("max_steps", budget.step_cap(max_steps), 1)
    tol = check_setting("tol", tol)
    if threads is not None:
        threads = validation.threads(threads, max_threads())
    if driver not in DRIVERS:
        raise ParameterError(f"driver must be one of {', '.join(map(repr, DRIVERS))}, got {driver!r}")
    ts = _times(times)
    Y0 = _states(system, states)
    N, n, M = Y0.shape[0], system.dimension, ts.size
    check_memory(f"flow: {N} orbits x {M} times", N * M * (n + 1) * 8, "fewer times or orbits")
    order = order_for_tolerance(tol)
    mod = codegen.load(system)
    out = np.full((N, M, n), np.nan)
    energy_error = np.full((N, M), np.nan)
    status = np.zeros(N, np.int64)
    info = np.zeros((N, 2))
    run_driver(mod, "flow", N, driver, threads,
               (Y0, system.parameter_array(), ts, int(order), int(max_steps), out, energy_error, status, info))
    settings = {"method": "taylor", "tol": tol, "order": order, "system": system.name, "max_steps": max_steps,
                "columns": [s.name for s in system.states]}
    return Flow(ts.copy(), out, energy_error, status, info[:, 1].astype(np.int64), settings)
