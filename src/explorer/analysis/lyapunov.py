"""Chaos indicators of orbits (user level): finite-time maximal Lyapunov exponent, MEGNO, FLI.

``indicators(system, y0, tmax=T, method=...)`` advances each orbit and one deviation vector for a
time T with tangent dynamics consistent with the integrator (variational equations for
``taylor`` and ``dop853``, exact tangent maps of the sub-flows for ``split*``; see
:mod:`explorer.integrate.tangent`) and returns, per orbit,

- ``mlce``  finite-time maximal Lyapunov exponent chi(T) = ln(|delta(T)|/|delta(0)|) / T
  (Benettin, Galgani, Giorgilli & Strelcyn 1980, Meccanica 15, 9);
- ``megno`` mean MEGNO <Y>(T) (Cincotta & Simó 2000, A&AS 147, 205): -> 2 for quasi-periodic
  orbits, -> 0 for stable periodic ones, grows like chi t / 2 for chaotic ones;
- ``fli``   fast Lyapunov indicator max_{t <= T} ln |delta(t)| (Froeschlé, Lega & Gonczi 1997,
  Celest. Mech. 67, 41);
- ``sali``  smaller alignment index min(|w1 + w2|, |w1 - w2|) of two unit deviation vectors
  (Skokos 2001, J. Phys. A 34, 10029) and ``gali2`` = |w1 ^ w2| (Skokos, Bountis & Antonopoulos
  2007, Physica D 231, 30), when asked for (``which``; Taylor method);

with a convergence history at ``history`` log-spaced times.  The deviation vector starts
tangent to the energy shell and to the Casimir surface (orthogonal to grad H and grad C), so
it measures stretching within the dynamics' own invariant manifold.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import overload

import numpy as np

from explorer import model
from explorer._jit import get_num_threads, max_threads, set_num_threads
from explorer.analysis.section_map import is_params, system_first
from explorer.integrate import methods
from explorer.integrate.methods import DEFAULT_DT, DEFAULT_TOL
from explorer.kernels import STATUS_NAMES, Status
from explorer.kernels import indicator_table as table
from explorer.model import ParameterError, packed_params, validation

DEFAULT_TIME = 1000.0
#: the indicators :func:`indicators` can compute (``which``): those of the registry
#: :data:`explorer.kernels.indicator_table.INDICATORS` that the tangent loops compute (frequency
#: diffusion is the sweep's, :func:`explorer.analysis.rotation.frequency_diffusion`)
INDICATOR_NAMES = table.TANGENT_NAMES
#: computed unless ``which`` says otherwise (one deviation vector)
DEFAULT_INDICATORS = table.DEFAULT_NAMES
#: early classification (``early_stop``): SALI below EARLY_SALI, or <Y> above EARLY_MEGNO at
#: every step end of [t/2, t] with t >= EARLY_TIME, classifies an orbit chaotic at t
EARLY_SALI = 1e-8
EARLY_MEGNO = 8.0
EARLY_TIME = 100.0
#: the methods whose kind has the loop of two deviation vectors with early stopping
#: (:attr:`explorer.integrate.methods.Kind.tangent_ext`): the only ones that compute the
#: indicators of the registry's extra row (SALI, GALI_2) and can stop early
TWO_VECTOR_METHODS = tuple(n for n, m in methods.REGISTRY.items() if m.loops.tangent_ext is not None)
EARLY_STOP_METHODS = TWO_VECTOR_METHODS
#: why an orbit stopped before T (``Indicators.early``)
EARLY_NAMES = ("none", "sali", "megno")
#: a generic start direction (no symmetry of the model), projected onto the shell
GENERIC_DIRECTION = np.array([0.8017, -0.3327, 0.4721, 0.1190, -0.0712])


def deviation_vector(params, y, direction=GENERIC_DIRECTION):
    """Unit vector(s) tangent to {H = H(y)} and {g1^2 + g2^2 = 1} at y: ``direction`` with its
    components along grad H and grad C removed (Gram-Schmidt)."""
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


#: a generic direction for the second deviation vector of SALI and GALI_2
SECOND_DIRECTION = np.array([-0.2113, 0.5507, 0.1342, -0.4029, 0.2977])


def second_deviation_vector(params, y, direction=SECOND_DIRECTION):
    """Unit vector(s) tangent to the Casimir surface {g1^2 + g2^2 = 1} at y, *not* restricted to
    the energy shell: the second deviation vector of SALI and GALI_2.  (Two vectors tangent to
    the shell of a regular orbit of two degrees of freedom both end up along the one direction
    in which the torus shears, so their SALI would decay like 1/t; with a component across the
    shell they shear differently and SALI stays away from 0, as Skokos 2001 assumes.)"""
    y = np.atleast_2d(np.asarray(y, float))
    gC = np.zeros_like(y)
    gC[:, 3] = y[:, 3]
    gC[:, 4] = y[:, 4]
    gC /= np.linalg.norm(gC, axis=1, keepdims=True)
    w = np.broadcast_to(np.asarray(direction, float), y.shape).copy()
    w -= np.sum(w * gC, axis=1, keepdims=True) * gC
    return w / np.linalg.norm(w, axis=1, keepdims=True)


class _Column:
    """An indicator of the registry as a declared attribute of :class:`Indicators`: its (N,)
    array, read from ``values``."""

    def __init__(self, name: str):
        self.name = name

    @overload
    def __get__(self, obj: None, owner: type | None = None) -> _Column: ...

    @overload
    def __get__(self, obj: Indicators, owner: type | None = None) -> np.ndarray: ...

    def __get__(self, obj, owner=None):
        if obj is None:
            return self      # the class attribute (documentation, introspection)
        return obj.values[self.name]


@dataclass(frozen=True)
class Indicators:
    """Per-orbit chaos indicators at time ``time`` and their history (:func:`indicators`).

    Each indicator of the registry (:data:`INDICATOR_NAMES`) is a declared attribute, ``r.megno``, an
    (N,) array (NaN where it was not computed), read from ``values`` (a new indicator adds its
    property here: ``tests/analysis/test_lyapunov.py`` checks every name has one).

    mLCE: finite-time maximal Lyapunov exponent ``ln(|w(T)| / |w(0)|) / T`` of the deviation vector w
    (Benettin et al. 1980; renormalised, Skokos 2010); MEGNO <Y>: Cincotta & Simó 2000 (-> 2 on
    quasi-periodic orbits, grows like mLCE T/2 on chaotic ones); FLI: Froeschlé, Lega & Gonczi
    1997, ``max ln |w|`` over [0, T].  ``status[i]`` is a :class:`~explorer.kernels.Status` code.
    """

    time: np.ndarray       # (N,) time reached
    values: dict           # indicator name -> (N,) array, every name of INDICATOR_NAMES
    Y: np.ndarray          # (N,) MEGNO Y at the end
    status: np.ndarray     # (N,) status codes (kernels.STATUS_*)
    steps: np.ndarray      # (N,)
    final: np.ndarray      # (N, 5) final states
    history_t: np.ndarray  # (H,) requested history times
    history: np.ndarray    # (N, H, N_RES) result rows (t, mlce, <Y>, Y, fli), NaN where not reached
    method: str
    settings: dict
    early: np.ndarray | None = None      # (N,) 0: ran to T, 1: stopped by SALI, 2: by <Y> (EARLY_NAMES)
    deviation: np.ndarray | None = None  # (N, 2, 5) final unit deviation vectors (NaN if not computed)
    which: tuple = field(default=DEFAULT_INDICATORS)

    #: finite-time maximal Lyapunov exponent per orbit
    mlce = _Column("mlce")
    #: mean MEGNO <Y> per orbit
    megno = _Column("megno")
    #: fast Lyapunov indicator per orbit
    fli = _Column("fli")
    #: smaller alignment index per orbit (NaN unless asked for)
    sali = _Column("sali")
    #: GALI_2 per orbit (NaN unless asked for)
    gali2 = _Column("gali2")

    def chaotic(self, threshold: float) -> np.ndarray:
        """Orbits classified chaotic: <Y> > ``threshold`` or stopped early as chaotic."""
        early = np.zeros(len(self.megno), bool) if self.early is None else self.early > 0
        return early | (self.megno > threshold)

    def status_name(self, i):
        return STATUS_NAMES[int(self.status[i])]

    def status_of(self, i: int) -> Status:
        """Why orbit i stopped, as a :class:`~explorer.kernels.Status`."""
        return Status(int(self.status[i]))


@system_first(settings=("phi0", "tol"), defaults={"tol": DEFAULT_TOL}, flow=True)
def indicators(system, y0, *, tmax: float = DEFAULT_TIME, method: str | None = None, tol: float | None = None,
               dt: float = DEFAULT_DT, history: int = 0, v0=None, max_steps: int = 10**9,
               threads: int | None = None, which=None, early_stop: bool = False,
               early_sali: float = EARLY_SALI, early_megno: float = EARLY_MEGNO,
               early_time: float = EARLY_TIME, w0=None) -> Indicators:
    """Chaos indicators of the orbits starting at ``y0`` over the time ``tmax``.

    Each orbit of docs/model.md R3 is integrated with one deviation vector ``w`` obeying the
    variational equations of R3 (started tangent to the energy shell and the Casimir surface,
    :func:`deviation_vector`), renormalised at every step (Benettin et al. 1980; Skokos 2010).

    The system first (docs/api.md, "The system argument"): a
    :class:`~explorer.analysis.section_map.SectionMap` (or ``params, h`` with ``phi0=`` and
    ``tol=``, default :data:`~explorer.integrate.methods.DEFAULT_TOL`) takes the start points
    ``y0`` = (p1, p2) or an (N, 2) array on its section phi = ``phi0`` at energy ``h`` (M > 0
    from the energy, :func:`explorer.model.section_state`), integrated at the map's tolerance
    (``tol`` beside a map is refused, as for every analysis); ``indicators(smap, points)`` is
    ``indicators(smap.params, states=states, tol=smap.tol)``.  The model parameters alone with the
    keyword ``states=`` full states are the flow, ``tol=`` this call's own.
    ``method`` (default Taylor, the map's) is this function's choice of integrator either way
    (every method has its tangent loop).

    Parameters
    ----------
    system : SectionMap or Params
        The section map, or the model parameters (docs/model.md, table "Notation") for full
        states (see above).
    y0 : array (N, 2) or (2,), with a map
        Section points (p1, p2).  The flow's initial states (p1, p2, M, sin phi, cos phi),
        (N, 5) or (5,), are given as ``states=`` with ``params`` instead.
    tmax : float
        Integration time (> 0): every orbit runs to t = tmax unless it stops early.
    method : str, optional
        A method of :data:`explorer.integrate.methods.METHODS` (default ``taylor``); its
        tangent dynamics are the
        Taylor series of the variational equations (``taylor``), DOP853 on the 10-dimensional
        system (``dop853``) or the exact tangent maps of the sub-flows of R4 (``split*``).
    tol : float, optional
        Tolerance of the adaptive methods with ``params`` and full states (default
        :data:`~explorer.integrate.methods.DEFAULT_TOL`); with a map, its ``tol``.
    dt : float
        Step of the splitting methods.
    history : int
        Number of log-spaced times at which the indicators are also recorded.
    v0 : array, optional
        Initial deviation vectors (default: :func:`deviation_vector`).
    max_steps : int
        Step budget per orbit.
    threads : int, optional
        Numba threads for this call (at most ``NUMBA_NUM_THREADS``).
    which : sequence of str, optional
        The indicators to compute, among :data:`INDICATOR_NAMES` (default mlce, megno, fli);
        ``sali`` or ``gali2`` add a second deviation vector (:func:`second_deviation_vector`,
        or ``w0``; Taylor method only).
    early_stop : bool
        Early classification (Taylor method): an orbit stops as chaotic at the first step end
        where SALI < ``early_sali`` (when SALI is computed) or where <Y> has stayed above
        ``early_megno`` at every step end of [t/2, t] and t >= ``early_time``; its ``time`` is
        the time reached and ``early`` says which rule fired.

    Returns
    -------
    Indicators
        mLCE ``ln(|w(T)| / |w(0)|) / T``, mean MEGNO <Y> (Cincotta & Simó 2000: -> 0 on
        stable periodic orbits, -> 2 on quasi-periodic orbits, ~ mLCE T / 2 on chaotic ones;
        docs/commands/lyapunov.md), FLI (Froeschlé, Lega & Gonczi
        1997), per orbit, with a status code each.
    """
    params = system
    if not is_params(system):   # a map: section coordinates on its section, its tolerance
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
    # writable C-contiguous copies, whatever was given: numba compiles a kernel once per kind of
    # array, read-only or not, and a broadcast of an (N, 5) array is a read-only view, which gave
    # the default vectors a compiled kernel of their own beside that of vectors passed in (and of
    # the lane tests' arrays: about 7 s of compiling each, tests/integrate/test_tangent_lanes.py)
    V0 = deviation_vector(P, Y0) if v0 is None else np.atleast_2d(np.asarray(v0, float))
    V0 = np.array(np.broadcast_to(V0, Y0.shape), dtype=np.float64, order="C")
    W0 = second_deviation_vector(P, Y0) if w0 is None else np.atleast_2d(np.asarray(w0, float))
    W0 = np.array(np.broadcast_to(W0, Y0.shape), dtype=np.float64, order="C")
    history = validation.fits_in_memory("history", history, Y0.shape[0] * table.N_RES * 8 + 8,
                                        f"a row of {table.N_RES} float64 per orbit and history point")
    early_stop = bool(early_stop)
    if early_stop:
        early_sali = validation.real("early_sali", early_sali, 0.0, 1.0)
        early_megno = validation.real("early_megno", early_megno, 2.0, lo_open=True)
        early_time = validation.real("early_time", early_time, 0.0)
    N = Y0.shape[0]
    hist_t = (np.geomspace(min(1.0, T), T, history) if history else np.zeros(0))
    hist = np.full((N, len(hist_t), table.N_RES), np.nan)
    res = np.zeros((N, table.N_RES))
    status = np.zeros(N, np.int64)
    final = np.zeros((N, 5))
    steps = np.zeros(N, np.int64)
    ext = np.full((N, table.N_EXT), np.nan)
    dev = np.full((N, 2, 5), np.nan)
    settings = {"method": method, "time": T}
    if early_stop:
        settings.update(early_stop=True, early_sali=early_sali if nvec == 2 else 0.0, early_megno=early_megno,
                        early_time=early_time)
    old = get_num_threads()
    if threads is not None:
        set_num_threads(validation.threads(threads, max_threads()))
    try:
        prep = m.prepare(tol=tol, dt=dt)
        settings.update(prep.settings)
        if m.loops.tangent_ext is not None:
            # the loop of one or two deviation vectors with early stopping (Taylor: on SIMD lanes)
            m.loops.loop("tangent_ext")(
                Y0, V0, W0, nvec, P, T, prep.order, int(max_steps), early_stop,
                float(early_sali) if nvec == 2 else 0.0, float(early_megno), float(early_time), hist_t, hist, res,
                ext, status, final, steps, dev)
        else:
            # an orbit whose motion the fixed step does not resolve is not integrated
            slow = methods.unresolved(prep, P, Y0)
            if not slow.any():
                methods.run_tangent(prep, Y0, V0, P, T, int(max_steps), hist_t, hist, res, status, final, steps)
            else:
                ok = np.flatnonzero(~slow)
                parts = [np.ascontiguousarray(a[ok]) for a in (Y0, V0, hist, res, status, final, steps)]
                if ok.size:
                    methods.run_tangent(prep, parts[0], parts[1], P, T, int(max_steps), hist_t, *parts[2:])
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
    rows = {table.RESULT: res, table.EXTRA: ext}
    values = {i.name: rows[i.row][:, i.column] for i in table.TANGENT}
    return Indicators(res[:, table.RES_T], values, res[:, table.RES_Y], status, steps, final, hist_t, hist, method,
                      settings, early=ext[:, table.EXT_EARLY].astype(np.int64), deviation=dev, which=which)


def methods_for(name: str) -> tuple:
    """The methods that compute the indicator ``name``: every method for one deviation vector,
    :data:`TWO_VECTOR_METHODS` for two (the registry's extra row); frequency diffusion, computed
    from the section map's returns, does not depend on the method: every method."""
    return TWO_VECTOR_METHODS if table.BY_NAME[name].vectors == 2 else methods.METHODS


def available(method: str) -> tuple:
    """The indicators ``method`` computes (names of :data:`INDICATOR_NAMES`, registry order)."""
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
    if bad or not which:
        raise ParameterError(f"indicators must be a non-empty list of {', '.join(INDICATOR_NAMES)}; got {which!r}")
    return tuple(dict.fromkeys(which))


def regular_bound(T: float) -> float:
    """Upper envelope of the finite-time exponent of a regular orbit, 3 ln T / T
    (the exponent of a regular orbit decays like ln T / T; Cincotta & Simó 2000)."""
    return 3.0 * math.log(T) / T


def chaotic_fraction(megno, threshold, valid=None):
    """Fraction of orbits with <Y> > threshold among the valid ones, with its binomial standard
    error sqrt(p (1 - p) / n): with seeds on a uniform grid of the allowed region this estimates
    the chaotic fraction of the section's area.  Returns (fraction, error, n)."""
    megno = np.asarray(megno, float)
    ok = np.isfinite(megno) if valid is None else (np.asarray(valid, bool) & np.isfinite(megno))
    n = int(ok.sum())
    if n == 0:
        return float("nan"), float("nan"), 0
    p = float(np.mean(megno[ok] > threshold))
    return p, math.sqrt(max(p * (1 - p), 0.25 / n) / n), n
