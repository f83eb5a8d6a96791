"""Chaos indicators of the standard map (S1) from its tangent map DT (docs/chaos_map.md): one
deviation vector renormalised after every iterate, accumulated by the engine's formulas
(:mod:`explorer.kernels.tangent`) with the iterate count as the time, so <Y> -> 2 on a torus and
grows on a chaotic orbit (Cincotta, Giordano & Simo 2003, maps).  Each orbit is its own loop: the
numbers do not depend on the batch or the thread count."""
from __future__ import annotations

import math

import numpy as np

from explorer._jit import get_num_threads, max_threads, njit, prange, set_num_threads
from explorer.kernels import indicator_table as table
from explorer.kernels import tangent as tg
from explorer.model import ParameterError, validation

#: the indicators of one deviation vector (two vectors of a map of the plane align on a torus too)
MAP_INDICATORS = tuple(i.name for i in table.TANGENT if i.vectors == 1)
#: the default deviation vector (no symmetry of the map)
DIRECTION = (0.9236, -0.3833)


@njit(parallel=True)
def standard_tangent(X, V, k, n, early_stop, early_megno, early_time, res, early, final, steps):
    """n iterates of (S1) and of DT on V[i] from X[i]; res[i] the result row (tg.result), early[i]
    the early code (tg.EARLY_MEGNO when <Y> stayed above ``early_megno``), final[i], steps[i]."""
    for i in prange(X.shape[0]):
        acc = np.zeros(tg.N_ACC)
        th, p = X[i, 0], X[i, 1]
        v0, v1 = V[i, 0], V[i, 1]
        since = -1.0
        code = 0
        j = 0
        while j < n:
            kc = k * math.cos(th)
            v1 = v1 + kc * v0          # DT = [[1 + kc, 1], [kc, 1]] (docs/greene.md)
            v0 = v0 + v1
            p = p + k * math.sin(th)
            th = th + p
            norm = math.sqrt(v0 * v0 + v1 * v1)
            v0 /= norm
            v1 /= norm
            tg.accumulate(acc, float(j), float(j + 1), math.log(norm))
            j += 1
            if early_stop:
                stop, since = tg.megno_early(acc, since, early_megno, early_time)
                if stop:
                    code = tg.EARLY_MEGNO
                    break
        tg.result(acc, res[i])
        early[i] = code
        final[i, 0] = th
        final[i, 1] = p
        steps[i] = j


def standard_indicators(k: float, points, *, tmax, which, threads=None, early_stop=False, early_megno=8.0,
                        early_time=100.0, v0=None, history=0, max_steps=None, flow=None) -> dict:
    """The fields of :class:`~explorer.analysis.lyapunov.Indicators` of the standard map's orbits
    from ``points`` (N, 2) over ``tmax`` iterates (an integer), for ``which`` of
    :data:`MAP_INDICATORS`; ``early_stop`` ends an orbit whose <Y> stays above ``early_megno``
    (docs/commands/lyapunov.md).  ParameterError for a setting of a flow given in ``flow`` (name ->
    value, None when not given: method, tol, dt, w0, phi0, h) and for ``history``."""
    extra = [name for name, value in (flow or {}).items() if value is not None]
    if extra or history:
        raise ParameterError(f"indicators of the standard map: {', '.join(extra or ['history'])} belong(s) to a "
                             "flow; a map iterates (tmax is the number of iterates)")
    bad = [w for w in which if w not in MAP_INDICATORS]
    if bad:
        raise ParameterError(f"indicators of the standard map are {', '.join(MAP_INDICATORS)} (one deviation vector; "
                             f"two align on a torus of a map of the plane too); got {bad[0]!r}")
    if isinstance(tmax, float) and tmax.is_integer():
        tmax = int(tmax)
    n = validation.integer("tmax", tmax, 1)
    if max_steps is not None:
        n = min(n, validation.integer("max_steps", max_steps, 1))
    X = np.ascontiguousarray(np.atleast_2d(np.asarray(points, dtype=np.float64)))
    if X.ndim != 2 or X.shape[1] != 2 or not np.all(np.isfinite(X)):
        raise ParameterError(f"points of the standard map are finite (theta, p) pairs (N, 2); got shape "
                             f"{np.shape(points)}")
    N = X.shape[0]
    V = np.array(np.broadcast_to(np.asarray(DIRECTION if v0 is None else v0, float), (N, 2)), order="C")
    norms = np.linalg.norm(V, axis=1)
    if not np.all(np.isfinite(V)) or not np.all(norms > 0):
        raise ParameterError("v0 must be finite and non-zero (it is made unit)")
    V /= norms[:, None]
    early_stop = bool(early_stop)
    if early_stop:
        early_megno = validation.real("early_megno", early_megno, 2.0, lo_open=True)
        early_time = validation.real("early_time", early_time, 0.0)
    res = np.zeros((N, table.N_RES))
    early = np.zeros(N, np.int64)
    final = np.zeros((N, 2))
    steps = np.zeros(N, np.int64)
    old = get_num_threads()
    if threads is not None:
        set_num_threads(validation.threads(threads, max_threads()))
    try:
        standard_tangent(X, V, float(k), n, early_stop, float(early_megno), float(early_time), res, early, final,
                         steps)
    finally:
        if threads is not None:
            set_num_threads(old)
    values = {i.name: (res[:, i.column] if i.vectors == 1 else np.full(N, np.nan)) for i in table.TANGENT}
    settings = {"method": "standard map", "time": float(n), "k": float(k)}
    if early_stop:
        settings.update(early_stop=True, early_megno=early_megno, early_time=early_time)
    return dict(time=res[:, table.RES_T], values=values, Y=res[:, table.RES_Y], status=np.zeros(N, np.int64),
                steps=steps, final=final, history_t=np.zeros(0), history=np.zeros((N, 0, table.N_RES)),
                method="standard map", settings=settings, early=early, deviation=None, which=tuple(which),
                energy_error=np.full(N, np.nan))
