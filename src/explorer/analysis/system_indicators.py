"""Chaos indicators (mLCE, MEGNO, FLI, SALI, GALI_2) of the orbits of a
:class:`explorer.model.system.System` or of its section map (docs/systems.md, "Chaos indicators").

:func:`explorer.analysis.lyapunov.indicators` hands a System or a System's map here and makes the
fields returned into the engine's :class:`~explorer.analysis.lyapunov.Indicators` (the same attributes,
columns and statuses), ``final`` and ``deviation`` in the system's dimension n, ``energy_error`` =
|H(final) - H(start)| (NaN without an energy).

The tangent dynamics are the variational equations of :meth:`System.variational` (the symbolic
Jacobian times the deviation vectors), whose Taylor recurrence is generated with the state's
(:mod:`explorer.integrate.codegen`); the drivers of integrate/codegen_indicators.py (scalar, or on SIMD
lanes with the same results) renormalise the vectors after every step and accumulate the indicators by
:mod:`explorer.kernels.tangent`, the engine's formulas.
"""
from __future__ import annotations

import numpy as np

from explorer._jit import max_threads
from explorer.analysis.system_section_map import refused_beside
from explorer.analysis.system_sections import DRIVERS, _states, is_system, run_driver
from explorer.integrate.methods import DEFAULT_TOL, check_setting
from explorer.kernels import indicator_table as table
from explorer.kernels.taylor_order import order_for_tolerance
from explorer.model import ParameterError, validation

__all__ = ["GENERIC_SEEDS", "default_vectors", "driver_outputs", "early_levels", "run_indicator_driver",
           "system_indicators"]

#: the engine's settings that have no meaning for a System (Chaplygin's section, energy and fixed step)
_NOT_FOR_A_SYSTEM = ("phi0", "h", "dt")
#: the irrationals whose multiples make the default deviation vectors (:func:`default_vectors`)
GENERIC_SEEDS = (0.6180339887498949, 0.4142135623730951)


def default_vectors(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The default start of the two deviation vectors in dimension n: v_i = frac((i + 1) a) - 1/2 with
    a of :data:`GENERIC_SEEDS` (a fixed direction with no symmetry of a model: no zero or equal
    entries), w the same with the second seed, made orthogonal to v; both unit.  Two generic
    vectors, not both on the energy shell: on a torus their shears differ, so SALI stays away
    from 0 (two on-shell vectors of a 2-degree-of-freedom torus would align, as the engine's note
    says, docs/commands/lyapunov.md)."""
    i = np.arange(1, n + 1)
    v, w = ((i * a) % 1.0 - 0.5 for a in GENERIC_SEEDS)
    v = v / np.linalg.norm(v)
    w = w - (w @ v) * v
    return v, w / np.linalg.norm(w)


def _vectors(label: str, given, default: np.ndarray, N: int) -> np.ndarray:
    n = default.shape[0]
    if given is None:
        return np.array(np.broadcast_to(default, (N, n)), dtype=np.float64, order="C")
    try:
        V = np.atleast_2d(np.asarray(given, dtype=np.float64))
        V = np.array(np.broadcast_to(V, (N, n)), dtype=np.float64, order="C")
    except (TypeError, ValueError):
        raise ParameterError(f"{label} must be a deviation vector of shape ({n},) or ({N}, {n}), got "
                             f"shape {np.shape(given)}") from None
    norms = np.linalg.norm(V, axis=1)
    if not np.all(np.isfinite(V)) or not np.all(norms > 0):
        raise ParameterError(f"{label} must be finite and non-zero (it is made unit)")
    return V


def _energy_error(system, Y0, final) -> np.ndarray:
    """|H(final) - H(Y0)| per orbit with the generated energy, NaN without one."""
    if system.energy is None:
        return np.full(Y0.shape[0], np.nan)
    from explorer.integrate import codegen

    mod = codegen.load(system)
    P = system.parameter_array()
    with np.errstate(invalid="ignore", over="ignore"):
        return np.array([abs(mod.energy(f, P) - mod.energy(y, P)) for f, y in zip(final, Y0)])


def early_levels(early_stop, early_sali, early_megno, early_time, nvec: int) -> dict:
    """The early stop as the indicator drivers take it and the settings record it: ``early_stop`` and,
    when set, its levels checked (SALI's in [0, 1], used with two vectors only, else 0; MEGNO's above 2;
    the earliest time >= 0: docs/commands/lyapunov.md)."""
    if not bool(early_stop):
        return {"early_stop": False, "early_sali": 0.0, "early_megno": 0.0, "early_time": 0.0}
    sali = validation.real("early_sali", early_sali, 0.0, 1.0)
    return {"early_stop": True, "early_sali": sali if nvec == 2 else 0.0,
            "early_megno": validation.real("early_megno", early_megno, 2.0, lo_open=True),
            "early_time": validation.real("early_time", early_time, 0.0)}


def driver_outputs(N: int, n: int, T: float, history) -> dict:
    """The output arrays of the indicator drivers (integrate/codegen_indicators.py) for N orbits of
    dimension n over the time T, with ``history`` (checked) log-spaced records: ``hist_t``, ``hist``,
    ``res``, ``ext``, ``status``, ``final``, ``steps``, ``dev`` in the drivers' order."""
    history = validation.fits_in_memory("history", history, N * table.N_RES * 8 + 8,
                                        f"a row of {table.N_RES} float64 per orbit and history point")
    hist_t = np.geomspace(min(1.0, T), T, history) if history else np.zeros(0)
    return {"hist_t": hist_t, "hist": np.full((N, len(hist_t), table.N_RES), np.nan),
            "res": np.zeros((N, table.N_RES)), "ext": np.full((N, table.N_EXT), np.nan),
            "status": np.zeros(N, np.int64), "final": np.zeros((N, n)), "steps": np.zeros(N, np.int64),
            "dev": np.full((N, 2, n), np.nan)}


def run_indicator_driver(mod, driver: str, threads, Y0, V0, W0, nvec: int, P, T: float, order: int, max_steps: int,
                         early: dict, out: dict, stop) -> None:
    """The indicators driver of the generated variational module ``mod`` on the orbits Y0 with the
    deviation vectors V0, W0 (:func:`~explorer.analysis.system_sections.run_driver`), into ``out``
    (:func:`driver_outputs`), with the early stop ``early`` (:func:`early_levels`)."""
    run_driver(mod, "indicators", Y0.shape[0], driver, threads,
               (Y0, V0, W0, Y0.shape[1], nvec, P, T, order, max_steps, early["early_stop"], early["early_sali"],
                early["early_megno"], early["early_time"], *out.values(), stop))


def system_indicators(system, y0=None, *, states=None, tmax: float, method, tol: float | None, history: int, v0,
                      w0, max_steps: int, threads: int | None, which: tuple, early_stop: bool, early_sali: float,
                      early_megno: float, early_time: float, dt=None, phi0=None, h=None,
                      driver: str = "auto") -> dict:
    """The fields of :class:`~explorer.analysis.lyapunov.Indicators` for the indicators ``which``
    (checked names) of the orbits of ``system`` (a System: full states ``states=``, shape (N, n) in
    its state order; a System's section map: section points, lifted by its ``states``) over the time
    ``tmax``, by the adaptive Taylor method of ``tol`` (the only method for a System; of a map, the
    map's own ``tol``) on the variational equations, with the engine's meaning of ``history``, ``v0``,
    ``w0`` (default :func:`default_vectors`), ``early_stop`` and its levels, ``max_steps`` and
    ``threads`` (docs/commands/lyapunov.md); ``driver`` as
    :func:`~explorer.analysis.system_sections.driver_for` (the same values either way).  ParameterError
    for the engine's settings of Chaplygin's model (phi0, h, dt), a method other than "taylor" and a
    ``tol`` beside a map (as Chaplygin's map refuses it: the map at another tol is ``smap.with_tol(tol)``)."""
    from explorer.analysis import budget
    from explorer.integrate import codegen

    given = [k for k, v in zip(_NOT_FOR_A_SYSTEM, (phi0, h, dt)) if v is not None]
    if given:
        raise ParameterError(f"indicators of a System: {', '.join(given)} belong(s) to Chaplygin's model and "
                             "do(es) not apply (a System's start is states=, its method the Taylor method of tol=)")
    if driver not in DRIVERS:
        raise ParameterError(f"driver must be one of {', '.join(map(repr, DRIVERS))}, got {driver!r}")
    if method not in (None, "taylor"):
        raise ParameterError(f"method must be 'taylor' for a System (the generated Taylor integrator of the "
                             f"variational equations), got {method!r}")
    nvec = max(table.BY_NAME[w].vectors for w in which)
    if is_system(system):
        if y0 is not None and states is not None:
            raise ParameterError("indicators of a System: give the start states once (states=)")
        Y0 = _states(system, states if states is not None else y0)
        smap = None
    else:
        if states is not None:
            raise ParameterError("indicators of a System's SectionMap takes section points, not states=; "
                                 "the flow takes indicators(system, states=...)")
        if y0 is None:
            raise ParameterError("indicators of a System's SectionMap: the section points are missing")
        smap, system = system, system.system
        Y0 = np.ascontiguousarray(smap.states(y0), dtype=np.float64)
        if tol is not None:
            raise refused_beside("indicators", ["tol"])
        tol = smap.tol
    stop = budget.stop_switch()         # raises when spent; a cancel ends every orbit at its next step
    max_steps = validation.integer("max_steps", budget.step_cap(max_steps), 1)
    T = validation.real("tmax", tmax, 0.0, lo_open=True)
    tol = check_setting("tol", DEFAULT_TOL if tol is None else tol)
    order = order_for_tolerance(tol)
    N, n = Y0.shape
    dv, dw = default_vectors(n)
    V0 = _vectors("v0", v0, dv, N)
    W0 = _vectors("w0", w0, dw, N)
    out = driver_outputs(N, n, T, history)
    early = early_levels(early_stop, early_sali, early_megno, early_time, nvec)
    if threads is not None:
        threads = validation.threads(threads, max_threads())
    # the variational system of nvec vectors: one recurrence, the Jacobian's subexpressions shared with f
    mod = codegen.load(system.variational(nvec))
    run_indicator_driver(mod, driver, threads, Y0, V0, W0, nvec, system.parameter_array(), T, order, max_steps,
                         early, out, stop)
    budget.raise_if_cancelled(out["status"])
    settings = {"method": "taylor", "time": T, "tol": tol, "order": order, "system": system.name,
                "states": [s.name for s in system.states], "vectors": nvec}
    if smap is not None:
        settings.update(energy=smap.energy_value, section=str(smap.section.expr), direction=smap.direction,
                        coords=[s.name for s in smap.coords], solve=smap.solve.name)
    if early["early_stop"]:
        settings.update(early)
    res, ext = out["res"], out["ext"]
    rows = {table.RESULT: res, table.EXTRA: ext}
    values = {i.name: rows[i.row][:, i.column] for i in table.TANGENT}
    return dict(time=res[:, table.RES_T], values=values, Y=res[:, table.RES_Y], status=out["status"],
                steps=out["steps"], final=out["final"], history_t=out["hist_t"], history=out["hist"], method="taylor",
                settings=settings, early=ext[:, table.EXT_EARLY].astype(np.int64), deviation=out["dev"], which=which,
                energy_error=_energy_error(system, Y0, out["final"]))
