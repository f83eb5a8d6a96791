"""Chaos indicators of orbits over a time T: finite-time mLCE, MEGNO, FLI, SALI and GALI_2 from
tangent dynamics consistent with the integrator (docs/commands/lyapunov.md)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import overload

import numpy as np

from explorer import model
from explorer._jit import get_num_threads, max_threads, set_num_threads
from explorer.analysis import budget, system_sections
from explorer.analysis.classification import fraction, orbit_classes
from explorer.analysis.section_map import is_params, system_first
from explorer.analysis.system_indicators import driver_outputs, early_levels, run_indicator_driver, system_indicators
from explorer.integrate import methods
from explorer.integrate.methods import DEFAULT_DT, DEFAULT_TOL
from explorer.kernels import STATUS_NAMES, Status
from explorer.kernels import indicator_table as table
from explorer.model import ParameterError, packed_params, validation

DEFAULT_TIME = 1000.0
#: the indicators of the registry that the tangent loops compute (``which``)
INDICATOR_NAMES = table.TANGENT_NAMES
DEFAULT_INDICATORS = table.DEFAULT_NAMES
#: the thresholds of ``early_stop`` (:func:`indicators`)
EARLY_SALI = 1e-8
EARLY_MEGNO = 8.0
EARLY_TIME = 100.0
#: the methods with the loop of two deviation vectors (SALI, GALI_2) and early stopping
TWO_VECTOR_METHODS = tuple(n for n, m in methods.REGISTRY.items() if m.loops.tangent_ext is not None)
EARLY_STOP_METHODS = TWO_VECTOR_METHODS
EARLY_NAMES = ("none", "sali", "megno")
#: generic start directions (no symmetry of the model) of the two deviation vectors
GENERIC_DIRECTION = np.array([0.8017, -0.3327, 0.4721, 0.1190, -0.0712])


def deviation_vector(params, y, direction=GENERIC_DIRECTION):
    """Unit vector(s) tangent to {H = H(y)} and {g1^2 + g2^2 = 1} at y (Gram-Schmidt)."""
    y = np.atleast_2d(np.asarray(y, float))
    gH = model.energy_gradient(params, y)
    gC = np.zeros_like(y)
    gC[:, 3] = 2 * y[:, 3]
    gC[:, 4] = 2 * y[:, 4]
    v = np.broadcast_to(np.asarray(direction, float), y.shape).copy()
    e1 = gC / np.linalg.norm(gC, axis=1, keepdims=True)
    gH = gH - np.sum(gH * e1, axis=1, keepdims=True) * e1
    nH = np.linalg.norm(gH, axis=1, keepdims=True)
    e2 = np.divide(gH, nH, out=np.zeros_like(gH), where=nH > 0)
    for e in (e1, e2):
        v -= np.sum(v * e, axis=1, keepdims=True) * e
    return v / np.linalg.norm(v, axis=1, keepdims=True)


SECOND_DIRECTION = np.array([-0.2113, 0.5507, 0.1342, -0.4029, 0.2977])


def second_deviation_vector(params, y, direction=SECOND_DIRECTION):
    """Unit vector(s) tangent to the Casimir surface at y, across the energy shell: the second
    deviation vector of SALI and GALI_2 (two on the shell would align on a regular orbit)."""
    y = np.atleast_2d(np.asarray(y, float))
    gC = np.zeros_like(y)
    gC[:, 3] = y[:, 3]
    gC[:, 4] = y[:, 4]
    gC /= np.linalg.norm(gC, axis=1, keepdims=True)
    w = np.broadcast_to(np.asarray(direction, float), y.shape).copy()
    w -= np.sum(w * gC, axis=1, keepdims=True) * gC
    return w / np.linalg.norm(w, axis=1, keepdims=True)


class _Column:
    """An indicator of the registry as an attribute of :class:`Indicators`, read from ``values``."""

    def __init__(self, name: str):
        self.name = name

    @overload
    def __get__(self, obj: None, owner: type | None = None) -> _Column: ...

    @overload
    def __get__(self, obj: Indicators, owner: type | None = None) -> np.ndarray: ...

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        return obj.values[self.name]


@dataclass(frozen=True)
class Indicators:
    """Per-orbit chaos indicators at ``time`` (``r.megno`` etc., NaN where not computed), the
    Status codes ``status``, why an orbit stopped ``early`` and the ``history``."""

    time: np.ndarray       # (N,) time reached
    values: dict           # indicator name -> (N,) array
    Y: np.ndarray
    status: np.ndarray
    steps: np.ndarray
    final: np.ndarray
    history_t: np.ndarray
    history: np.ndarray    # (N, H, N_RES) rows (t, mlce, <Y>, Y, fli)
    method: str
    settings: dict
    early: np.ndarray | None = None      # index of EARLY_NAMES
    deviation: np.ndarray | None = None  # (N, 2, n) final unit deviation vectors (n = 5 for the model)
    which: tuple = field(default=DEFAULT_INDICATORS)
    energy_error: np.ndarray | None = None   # (N,) |H(final) - H(start)|, NaN for a System without an energy

    mlce = _Column("mlce")
    megno = _Column("megno")
    fli = _Column("fli")
    sali = _Column("sali")
    gali2 = _Column("gali2")

    def chaotic(self, threshold: float, indicator: str = "megno") -> np.ndarray:
        """Orbits classified chaotic by ``indicator`` (MEGNO: <Y> > ``threshold``) or stopped early
        as chaotic (explorer.analysis.classification.orbit_classes; docs/chaos_map.md)."""
        if indicator not in self.which:
            raise ParameterError(f"indicator must be one of the computed indicators {list(self.which)}; "
                                 f"got {indicator!r}")
        return orbit_classes(self.values[indicator], indicator, threshold, self.early)[0]

    def status_name(self, i):
        return STATUS_NAMES[int(self.status[i])]

    def status_of(self, i: int) -> Status:
        """Why orbit i stopped, as a :class:`~explorer.kernels.Status`."""
        return Status(int(self.status[i]))


@system_first(settings=("phi0", "tol"), defaults={"tol": DEFAULT_TOL}, flow=True, systems=True)
def indicators(system, y0=None, *, tmax: float = DEFAULT_TIME, method: str | None = None, tol: float | None = None,
               dt: float | None = None, history: int = 0, v0=None, max_steps: int = 10**9,
               threads: int | None = None, which=None, early_stop: bool = False,
               early_sali: float = EARLY_SALI, early_megno: float = EARLY_MEGNO,
               early_time: float = EARLY_TIME, w0=None, states=None, phi0=None, h=None) -> Indicators:
    """Chaos indicators (``which`` of :data:`INDICATOR_NAMES`) of the orbits from ``y0`` over the
    time ``tmax``, each with one deviation vector (two for SALI, GALI_2) renormalised at every step,
    with ``method``'s tangent dynamics; ``early_stop`` ends an orbit classified chaotic by SALI or
    <Y>; ``history`` log-spaced records (docs/commands/lyapunov.md).  A System or its section map:
    :func:`explorer.analysis.system_indicators.system_indicators` (``states=`` the flow's start; a map
    at its own ``tol``, another is ``smap.with_tol(tol)``; ``phi0``, ``h`` and ``dt`` are refused).  For
    the model, ``states``, ``phi0`` and ``h`` are the system argument's
    (:func:`~explorer.analysis.section_map.system_first`)."""
    if system_sections.is_system(system) or system_sections.is_system_map(system):
        return Indicators(**system_indicators(
            system, y0, tmax=tmax, method=method, tol=tol, dt=dt, history=history, v0=v0, w0=w0, max_steps=max_steps,
            threads=threads, which=check_which(which), early_stop=early_stop, early_sali=early_sali,
            early_megno=early_megno, early_time=early_time, states=states, phi0=phi0, h=h))
    own = None if is_params(system) else system.own_indicators(y0, dict(
        tmax=tmax, which=check_which(which), threads=threads, early_stop=early_stop, early_megno=early_megno,
        early_time=early_time, v0=v0, history=history, max_steps=max_steps, method=method, tol=tol, dt=dt, w0=w0,
        phi0=phi0, h=h))
    if own is not None:   # the map's own tangent map (the standard map, docs/chaos_map.md)
        return Indicators(**own)
    dt = DEFAULT_DT if dt is None else dt
    params = system
    if not is_params(system):   # a map: its section points, its tolerance
        method = system.method if method is None else method
        tol = system.tol
        params, y0 = system.params, system.states(y0)
    method = "taylor" if method is None else method
    tol = DEFAULT_TOL if tol is None else tol
    P = packed_params(params)
    m = methods.get(method)
    T = validation.real("tmax", tmax, 0.0, lo_open=True)
    Y0 = np.ascontiguousarray(np.atleast_2d(np.asarray(y0, dtype=np.float64)))
    if Y0.ndim != 2 or Y0.shape[1] != 5 or not np.all(np.isfinite(Y0)):
        raise ParameterError("y0 must be finite with shape (N, 5) = (p1, p2, M, g1, g2) per orbit")
    which = check_which(which)
    nvec = max(table.BY_NAME[w].vectors for w in which)
    for w in which:
        if method not in methods_for(w):
            raise ParameterError(f"indicator {w} needs method {' or '.join(repr(n) for n in methods_for(w))}; "
                                 f"got method {method!r}")
    if early_stop and method not in EARLY_STOP_METHODS:
        raise ParameterError(f"early_stop needs method {' or '.join(repr(n) for n in EARLY_STOP_METHODS)}; "
                             f"got method {method!r}")
    # writable C-contiguous copies: numba compiles once per array kind (read-only or not)
    V0 = deviation_vector(P, Y0) if v0 is None else np.atleast_2d(np.asarray(v0, float))
    V0 = np.array(np.broadcast_to(V0, Y0.shape), dtype=np.float64, order="C")
    W0 = second_deviation_vector(P, Y0) if w0 is None else np.atleast_2d(np.asarray(w0, float))
    W0 = np.array(np.broadcast_to(W0, Y0.shape), dtype=np.float64, order="C")
    out = driver_outputs(Y0.shape[0], 5, T, history)
    hist_t, hist, res, ext, status, final, steps, dev = out.values()
    early = early_levels(early_stop, early_sali, early_megno, early_time, nvec)
    settings = {"method": method, "time": T}
    if early["early_stop"]:
        settings.update(early)
    stop = budget.stop_switch()         # a budget's cancel ends every orbit at its next step
    old = get_num_threads()
    if threads is not None:
        set_num_threads(validation.threads(threads, max_threads()))
    try:
        prep = m.prepare(tol=tol, dt=dt)
        settings.update(prep.settings)
        if m.loops.tangent_ext is not None:   # the indicators template of every System (docs/systems.md)
            run_indicator_driver(m.loops.loop("tangent_ext")(nvec), "auto", None, Y0, V0, W0, nvec, P, T, prep.order,
                                 int(max_steps), early, out, stop)
        else:
            # an orbit the fixed step does not resolve is not integrated
            slow = methods.unresolved(prep, P, Y0)
            if not slow.any():
                methods.run_tangent(prep, Y0, V0, P, T, int(max_steps), hist_t, hist, res, status, final, steps,
                                    stop)
            else:
                ok = np.flatnonzero(~slow)
                parts = [np.ascontiguousarray(a[ok]) for a in (Y0, V0, hist, res, status, final, steps)]
                if ok.size:
                    methods.run_tangent(prep, parts[0], parts[1], P, T, int(max_steps), hist_t, *parts[2:], stop)
                for a, part in zip((hist, res, status, final, steps), parts[2:]):
                    a[ok] = part
                res[slow] = np.nan
                res[slow, table.RES_T] = 0.0
                status[slow] = int(Status.UNRESOLVED)
                final[slow] = Y0[slow]
            ext[:, table.EXT_EARLY] = 0
    finally:
        if threads is not None:
            set_num_threads(old)
    budget.raise_if_cancelled(status)
    rows = {table.RESULT: res, table.EXTRA: ext}
    values = {i.name: rows[i.row][:, i.column] for i in table.TANGENT}
    with np.errstate(invalid="ignore", over="ignore"):
        dh = np.abs(model.energy(P, final) - model.energy(P, Y0))
    return Indicators(res[:, table.RES_T], values, res[:, table.RES_Y], status, steps, final, hist_t, hist, method,
                      settings, early=ext[:, table.EXT_EARLY].astype(np.int64), deviation=dev, which=which,
                      energy_error=dh)


def methods_for(name: str) -> tuple:
    """The methods that compute the indicator ``name``."""
    return TWO_VECTOR_METHODS if table.BY_NAME[name].vectors == 2 else methods.METHODS


def available(method: str) -> tuple:
    """The indicators ``method`` computes, in registry order."""
    methods.get(method)
    return tuple(i.name for i in table.TANGENT if method in methods_for(i.name))


def check_which(which) -> tuple:
    """The indicator names asked for (ParameterError naming the allowed ones)."""
    if which is None:
        return DEFAULT_INDICATORS
    if isinstance(which, str):
        which = (which,)
    which = tuple(which)
    bad = [w for w in which if w not in INDICATOR_NAMES]
    orbit = [w for w in bad if w in table.BY_NAME]
    if orbit:
        raise ParameterError(f"indicator {orbit[0]} is not computed along deviation vectors: it comes from a section "
                             f"map's returns around a centre (explorer.{orbit[0]}(map, points, center=...)); ask for "
                             f"{', '.join(INDICATOR_NAMES)}")
    if bad or not which:
        raise ParameterError(f"indicators must be a non-empty list of {', '.join(INDICATOR_NAMES)}; got {which!r}")
    return tuple(dict.fromkeys(which))


def regular_bound(T: float) -> float:
    """3 ln T / T: an upper envelope of the finite-time exponent of a regular orbit."""
    return 3.0 * math.log(T) / T


def chaotic_fraction(megno, threshold, valid=None):
    """(fraction, binomial standard error, n) of the valid orbits (finite, and ``valid``) with
    <Y> > threshold (explorer.analysis.classification.fraction)."""
    return fraction(*orbit_classes(megno, "megno", threshold, ok=valid))
