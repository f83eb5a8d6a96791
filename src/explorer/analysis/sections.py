"""Crossings of the section phi = phi0 for many orbits at once, with any method of
:mod:`explorer.integrate.methods`, in one batch or streamed in blocks (docs/commands/orbit.md)."""
from __future__ import annotations

import math
import numbers
from dataclasses import replace

import numpy as np

from explorer.analysis import system_sections
from explorer.analysis.crossings_run import (
    DEFAULT_BLOCK,
    DEFAULT_MAX_STEPS,
    ROW_BYTES,
    CrossingBlock,
    Crossings,
    Integration,
    StreamState,
    _outputs,
    _run_block,
    _validated,
    check_step_block,
    crossing_settings,
    energy_warning,
    human_bytes,
    max_energy_error,
    result_bytes,
    run,
    stream,
)
from explorer.analysis.section_map import is_params, not_a_system, system_first
from explorer.integrate import layout
from explorer.integrate.methods import (
    ADAPTIVE_METHODS,
    DEFAULT_DT,
    DEFAULT_TOL,
    MAX_TOL,
    METHODS,
    MIN_TOL,
    SPLIT_METHODS,
)
from explorer.kernels import Status
from explorer.model import ParameterError, validation

__all__ = ["ADAPTIVE_METHODS", "DEFAULT_BLOCK", "DEFAULT_DT", "DEFAULT_MAX_STEPS", "DEFAULT_TOL", "MAX_TOL",
           "METHODS", "MIN_TOL", "SPLIT_METHODS", "CrossingBlock", "Crossings", "Integration", "StreamState",
           "ROW_BYTES", "crossing_settings", "crossings", "propagate", "energy_warning", "human_bytes",
           "iter_crossings", "max_energy_error", "result_bytes"]


def _start(system, y0, tol, phi0, direction):
    """(params, states, tol, phi0) of a run: a map's points lifted to states, or the flow's own."""
    if is_params(system):
        return system, y0, tol, phi0
    return system.params, system.states(y0, direction), system.tol, system.phi0


def _or_a_system(fn):
    """``fn`` for the engine's model; a :class:`explorer.model.system.System` goes to
    :func:`explorer.analysis.system_sections.system_crossings` (docs/systems.md, "Crossings")."""

    return system_sections.or_a_system(fn, Crossings)


@_or_a_system
@system_first(settings=("phi0", "tol"), defaults={"tol": DEFAULT_TOL}, flow=True)
def crossings(system, y0, *, n_crossings: int, method: str = "taylor", tol: float = DEFAULT_TOL,
              dt: float | None = None, tmax: float | None = None, max_steps: int = DEFAULT_MAX_STEPS,
              phi0: float = math.pi, direction: int = 1, threads: int | None = None) -> Crossings:
    """Integrate each orbit from ``y0`` until it has crossed the section phi = phi0
    ``n_crossings`` times in ``direction`` (+1: dphi/dt > 0, -1: < 0, 0: both), or its time
    budget ``tmax`` (default 100 * n_crossings) or ``max_steps`` runs out.  ``y0``: a map's
    section points, or the flow's ``states=``; ``tol`` or ``dt`` per method; a result larger
    than half the memory is refused (stream it with :func:`iter_crossings`)."""
    params, y0, tol, phi0 = _start(system, y0, tol, phi0, direction)
    return run(params, y0, n_crossings=n_crossings, method=method, tol=tol, dt=dt, tmax=tmax, max_steps=max_steps,
               phi0=phi0, direction=direction, threads=threads)


#: crossings a run of :func:`propagate` may pass on its way to t
PROPAGATE_CROSSINGS = 16


@not_a_system("explorer.flow(system, states, times=[t]) gives the states at time t")
@system_first(settings=("phi0", "tol"), defaults={"tol": DEFAULT_TOL}, flow=True)
def propagate(system, y0, *, t: float, method: str = "taylor", tol: float = DEFAULT_TOL, dt: float | None = None,
              threads: int | None = None) -> np.ndarray:
    """The states (N, 5) at time ``t`` > 0 of the orbits from ``y0``: :func:`crossings`'s steps,
    the last ending at t; ParameterError for an orbit that stops sooner or crosses more than
    :data:`PROPAGATE_CROSSINGS` times."""
    t = validation.real("t", t, 0.0, lo_open=True)
    params, y0, tol, phi0 = _start(system, y0, tol, math.pi, 1)
    res = crossings(params, states=y0, n_crossings=PROPAGATE_CROSSINGS, tmax=t, method=method, tol=tol, dt=dt,
                    phi0=phi0, threads=threads)
    short = np.flatnonzero((res.status != int(Status.TMAX)) | (res.info[:, 0] != t))
    if short.size:
        i = int(short[0])
        raise ParameterError(f"propagate: orbit {i} stopped at t = {res.info[i, 0]!r} before {t!r} "
                             f"({res.status_name(i)}); propagate it in shorter times")
    return res.final.copy()


@system_sections.or_a_system
@system_first(settings=("phi0", "tol"), defaults={"tol": DEFAULT_TOL}, flow=True)
def iter_crossings(system, y0, *, n_crossings: int, block: int = DEFAULT_BLOCK, state: StreamState | None = None,
                   method: str = "taylor", tol: float = DEFAULT_TOL, dt: float | None = None,
                   tmax: float | None = None, max_steps: int = DEFAULT_MAX_STEPS, phi0: float = math.pi,
                   direction: int = 1, threads: int | None = None, step_block: int | None = None):
    """:func:`crossings` in blocks of about ``block`` crossings per orbit (:class:`CrossingBlock`),
    bit for bit the same rows, in O(N x block) memory; ``state`` resumes a run
    (docs/commands/orbit.md, "Long orbits").  With ``step_block`` a block also ends once no orbit
    may take more than that many steps in it (a block of a fixed-step orbit that finds no crossing
    for a long time stays short, so a caller can stop between blocks); such a cut is no budget's
    end: the next block continues the orbit exactly, for the methods whose kind
    ``resumes_at_any_step`` (integrate.methods.Kind; not DOP853).  A System streams its crossings of
    ``section=`` (system_sections.iter_system_crossings)."""
    params, y0, tol, phi0 = _start(system, y0, tol, phi0, direction)
    run = _validated(params, y0, n_crossings, method, tol, dt, tmax, max_steps, phi0, direction, threads)
    if not isinstance(block, numbers.Integral) or block < 1:
        raise ParameterError(f"block must be an integer >= 1, got {block!r}")
    check_step_block(step_block, method)
    N, K = run.Y0.shape[0], run.K
    st = StreamState.initial(run.P, run.Y0, phi0=run.settings["phi0"]) if state is None else state.copy()
    if st.y.shape != (N, 5) or st.carry.shape != (N, layout.N_CARRY):
        raise ParameterError(f"state is for {st.y.shape[0]} orbits, y0 has {N}")

    def run_block(Y, carry, limits, width, max_steps):
        out = _outputs(Y.shape[0], width)
        _run_block(replace(run, max_steps=max_steps), Y, carry, limits, *out)
        return out

    yield from stream(st, K, block, run_block, run.max_steps, step_block)
