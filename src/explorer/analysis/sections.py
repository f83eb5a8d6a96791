"""Crossings of the Poincaré section phi = phi0 for many orbits at once (user level).

:func:`crossings` validates its input, picks the compiled batch driver of the
method (:mod:`explorer.integrate.drivers`), runs it in parallel over orbits with numba
threads and returns a :class:`Crossings` whose status codes are already
named.  Arrays in, arrays out: no I/O here.

Methods
-------
``taylor``  adaptive Taylor series, order from ``tol`` (Jorba & Zou 2005);
            crossings are roots of the step's Taylor polynomial.
``dop853``  adaptive Dormand-Prince 8(5,3) (Hairer, Nørsett & Wanner, Solving
            ODEs I, II.5); crossings are roots of its 7th-order dense output.
``split2`` ... ``split8`` (and the variants in ``kernels.splitting.SCHEMES``)
            fixed-step symmetric compositions of the exact sub-flows of
            docs/model.md R4 (Strang; Yoshida 1990; Kahan & Li 1997); they keep the
            Casimir to round-off and the energy error bounded; crossings are
            roots in tau of g(Psi_tau(y)), Psi the composition step itself.
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from explorer import model
from explorer._jit import get_num_threads, max_threads, set_num_threads
from explorer.analysis.section_map import is_params, system_first
from explorer.integrate import layout, methods
from explorer.integrate.methods import (
    ADAPTIVE_METHODS,
    DEFAULT_DT,
    DEFAULT_TOL,
    MAX_TOL,
    METHODS,
    MIN_TOL,
    SPLIT_METHODS,
)
from explorer.kernels import STATUS_NAMES, Status
from explorer.model import ParameterError, packed_params, validation

__all__ = ["ADAPTIVE_METHODS", "DEFAULT_BLOCK", "DEFAULT_DT", "DEFAULT_MAX_STEPS", "DEFAULT_TOL", "MAX_TOL",
           "METHODS", "MIN_TOL", "SPLIT_METHODS", "CrossingBlock", "Crossings", "Integration", "StreamState",
           "crossing_settings",
           "crossings", "propagate", "energy_warning", "human_bytes", "iter_crossings",
           "max_energy_error", "result_bytes"]

DEFAULT_MAX_STEPS = 10**9
#: a run whose energy error exceeds this fraction of max(|h|, 1) gets a warning: its step
#: (splitting) or tolerance is too coarse for the scene to trust the section's fine structure
ENERGY_WARN_REL = 1e-6
#: crossings per orbit and block of a streamed run (:func:`iter_crossings`): 40 bytes a row,
#: so 1e5 rows = 4 MB per orbit in flight
DEFAULT_BLOCK = 100_000
#: bytes of one stored crossing row (t, p1, p2, M, dH as float64)
ROW_BYTES = 40
#: :func:`crossings` returns every row at once: it refuses a result larger than
#: MAX_MEMORY_FRACTION of the machine's memory (stream it with :func:`iter_crossings` instead)
MAX_MEMORY_FRACTION = validation.MAX_MEMORY_FRACTION
physical_memory = validation.physical_memory
human_bytes = validation.human_bytes


@dataclass(frozen=True)
class Crossings:
    """Result of :func:`crossings` for N orbits and up to K crossings each.

    data[i, k] = (t, p1, p2, M, H - H0) for k < count[i]; rows beyond are NaN.
    status[i] is a code of ``kernels.STATUS_*``; ``status_name(i)`` names it.
    final[i] is the state where orbit i stopped; info[i] = (t_end, steps, Casimir error).
    """

    data: np.ndarray
    count: np.ndarray
    status: np.ndarray
    final: np.ndarray
    info: np.ndarray
    method: str
    settings: dict = field(default_factory=dict)

    def orbit(self, i: int) -> np.ndarray:
        """The crossings of orbit i as an array (count_i, 5)."""
        return self.data[i, : self.count[i]]

    def status_name(self, i: int) -> str:
        return STATUS_NAMES[int(self.status[i])]

    def status_of(self, i: int) -> Status:
        """Why orbit i stopped, as a :class:`~explorer.kernels.Status`."""
        return Status(int(self.status[i]))


def max_energy_error(data) -> float:
    """max |H - H0| over the crossings in ``data`` (rows (t, p1, p2, M, H - H0), NaN padding
    ignored); 0.0 if there are none."""
    dh = np.abs(np.asarray(data, dtype=np.float64)[..., 4])
    dh = dh[np.isfinite(dh)]
    return float(dh.max()) if dh.size else 0.0


def energy_warning(max_dh: float, h: float, setting: str) -> str | None:
    """A one-line warning when the energy error max_dh exceeds ENERGY_WARN_REL * max(|h|, 1),
    naming the setting to refine; None otherwise."""
    limit = ENERGY_WARN_REL * max(abs(h), 1.0)
    if max_dh <= limit:
        return None
    return (f"energy error up to {max_dh:.2e} (> {limit:.0e} = {ENERGY_WARN_REL:g} x max(|h|, 1)): "
            f"{setting} is too coarse for this orbit; refine it to trust the section")


def result_bytes(n_orbits: int, n_crossings: int) -> int:
    """Bytes of the crossing rows of ``n_orbits`` orbits with ``n_crossings`` crossings each
    (the size of :attr:`Crossings.data`, and an upper bound of the rows a store holds before
    compression)."""
    return int(n_orbits) * int(n_crossings) * ROW_BYTES


@dataclass(frozen=True)
class Integration:
    """The settings of a run of :func:`crossings`, validated once, here (ParameterError naming
    the setting): the method and its tolerance ``tol`` or step ``dt`` (both checked, as
    :meth:`explorer.integrate.methods.Method.prepare` does), the number of ``crossings``, the
    time budget ``tmax`` (None: 100 * crossings, :attr:`effective_tmax`), ``max_steps``, the
    section angle ``phi0`` and the crossing ``direction`` (+1, -1 or 0: both).

    A scene's ``[integration]`` table is this object
    (:class:`explorer.io.scene.specs.IntegrationSpec`, which names a refused setting by its
    scene key), and so can be any other front end's settings.
    """

    method: str = "taylor"
    tol: float = DEFAULT_TOL
    dt: float = DEFAULT_DT
    crossings: int = 1
    tmax: float | None = None
    max_steps: int = DEFAULT_MAX_STEPS
    phi0: float = math.pi
    direction: int = 1

    def _label(self, name: str) -> str:
        """How a refused setting is named in the message (a scene gives its key)."""
        return name

    def _refusal(self, exc: ParameterError) -> ParameterError:
        """The error raised for a refused setting (a scene raises its SceneError)."""
        return exc

    def __post_init__(self):
        label = self._label
        try:
            values = {
                "method": validation.choice(label("method"), self.method, METHODS),
                "tol": methods.check_setting("tol", self.tol, label("tol")),
                "dt": methods.check_setting("dt", self.dt, label("dt")),
                "crossings": validation.integer(label("crossings"), self.crossings, 1),
                "tmax": None if self.tmax is None else validation.real(label("tmax"), self.tmax, 0.0,
                                                                       lo_open=True),
                "max_steps": validation.integer(label("max_steps"), self.max_steps, 1),
                "phi0": validation.real(label("phi0"), self.phi0),
                "direction": validation.integer(label("direction"), self.direction),
            }
            if values["direction"] not in (-1, 0, 1):
                raise ParameterError(f"{label('direction')} must be +1, -1 or 0 (both), got {values['direction']}")
        except ParameterError as exc:
            raise self._refusal(exc) from None
        for name, value in values.items():
            object.__setattr__(self, name, value)

    @property
    def adaptive(self) -> bool:
        """The method's accuracy is ``tol`` (else the step ``dt``)."""
        return self.method in ADAPTIVE_METHODS

    @property
    def effective_tmax(self) -> float:
        """The time budget: ``tmax``, or 100 * crossings when it is None."""
        return 100.0 * self.crossings if self.tmax is None else self.tmax


@dataclass(frozen=True)
class _Run:
    """A validated request: what every block of it shares."""

    P: np.ndarray
    Y0: np.ndarray
    K: int
    prep: methods.Prepared
    cphi: float
    sphi: float
    direction: int
    tmax: float
    max_steps: int
    threads: int | None
    settings: dict


def _validated(params, y0, n_crossings, method, tol, dt, tmax, max_steps, phi0, direction, threads) -> _Run:
    P = packed_params(params)
    s = Integration(method=method, tol=tol, dt=DEFAULT_DT if dt is None else dt, crossings=n_crossings, tmax=tmax,
                    max_steps=max_steps, phi0=phi0, direction=direction)
    m = methods.get(s.method)
    phi0, tmax, direction = s.phi0, s.effective_tmax, s.direction
    Y0 = np.ascontiguousarray(np.atleast_2d(np.asarray(y0, dtype=np.float64)))
    if Y0.ndim != 2 or Y0.shape[1] != model.STATE_DIM:
        raise ParameterError(f"y0 must have shape (N, 5) = (p1, p2, M, g1, g2) per orbit, got {np.shape(y0)}")
    if not np.all(np.isfinite(Y0)):
        i = int(np.flatnonzero(~np.all(np.isfinite(Y0), axis=1))[0])
        raise ParameterError(f"y0 must be finite; orbit {i} has {Y0[i].tolist()}")
    with np.errstate(over="ignore", invalid="ignore"):
        H0 = model.energy(P, Y0)
    if not np.all(np.isfinite(H0)):
        i = int(np.flatnonzero(~np.isfinite(H0))[0])
        raise ParameterError(f"y0 must have a finite energy; orbit {i} has H = {H0[i]!r}")
    if threads is not None:
        threads = validation.threads(threads, max_threads())
    prep = m.prepare(tol=s.tol, dt=s.dt)
    g1, g2 = model.section_gamma(phi0)
    K = s.crossings
    settings = {"method": method, "phi0": phi0, "direction": direction, "tmax": tmax,
                "max_steps": s.max_steps, "n_crossings": K}
    settings.update(prep.settings)
    return _Run(P, Y0, K, prep, g2, g1, int(direction), tmax, int(max_steps), threads, settings)


def _start(system, y0, tol, phi0, direction):
    """(params, states, tol, phi0) of a run of :func:`crossings`: a map's section points
    lifted to states at its tolerance and section, or the flow's own."""
    if is_params(system):
        return system, y0, tol, phi0
    return system.params, system.states(y0, direction), system.tol, system.phi0


def crossing_settings(params, y0, *, n_crossings: int, method: str = "taylor", tol: float = DEFAULT_TOL,
                      dt: float | None = None, tmax: float | None = None, max_steps: int = DEFAULT_MAX_STEPS,
                      phi0: float = math.pi, direction: int = 1) -> dict:
    """The settings that :func:`crossings` (or :func:`iter_crossings`) records for this request,
    validated as there (ParameterError otherwise), without running it."""
    return dict(_validated(params, y0, n_crossings, method, tol, dt, tmax, max_steps, phi0, direction,
                           None).settings)


def _outputs(n: int, width: int):
    """The arrays the drivers fill for n orbits of at most ``width`` rows: data (NaN where no
    crossing), count, status, final state, info."""
    return (np.full((n, width, 5), np.nan), np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros((n, 5)),
            np.zeros((n, 3)))


def _run_block(run: _Run, Y, carry, limits, data, count, status, final, info) -> None:
    """One block of the drivers for the orbits Y (arrays filled in place), with numba's thread
    count set for the call when ``run.threads`` says so.  An orbit whose motion the fixed step
    does not resolve (:func:`explorer.integrate.methods.unresolved`) is not integrated: no
    crossing, status UNRESOLVED, its state kept."""
    slow = methods.unresolved(run.prep, run.P, Y)
    if slow.any():
        count[slow] = 0
        status[slow] = int(Status.UNRESOLVED)
        final[slow] = Y[slow]
        info[slow] = 0.0
        info[slow, 0] = carry[slow, layout.CARRY_T]
        ok = np.flatnonzero(~slow)
        if ok.size:
            parts = [np.ascontiguousarray(a[ok]) for a in (Y, carry, limits, data, count, status, final, info)]
            _run_block(run, *parts)
            for a, part in zip((carry, data, count, status, final, info), parts[1:2] + parts[3:]):
                a[ok] = part
        return
    if run.threads is None:   # (numba's thread pool is started only when a batch asks for it)
        methods.run_crossings(run.prep, Y, run.P, run.cphi, run.sphi, run.direction, run.tmax, run.max_steps,
                              carry, limits, data, count, status, final, info)
        return
    old_threads = get_num_threads()
    set_num_threads(run.threads)
    try:
        methods.run_crossings(run.prep, Y, run.P, run.cphi, run.sphi, run.direction, run.tmax, run.max_steps,
                              carry, limits, data, count, status, final, info)
    finally:
        set_num_threads(old_threads)


@system_first(settings=("phi0", "tol"), defaults={"tol": DEFAULT_TOL}, flow=True)
def crossings(system, y0, *, n_crossings: int, method: str = "taylor", tol: float = DEFAULT_TOL,
              dt: float | None = None, tmax: float | None = None, max_steps: int = DEFAULT_MAX_STEPS,
              phi0: float = math.pi, direction: int = 1, threads: int | None = None) -> Crossings:
    """Integrate each orbit from ``y0`` until it has crossed the section phi = phi0
    ``n_crossings`` times in ``direction`` (+1: dphi/dt > 0, -1: < 0, 0: both), or until its time
    budget ``tmax`` (default 100 * n_crossings) or step budget ``max_steps`` runs out.

    The system first (docs/api.md, "The system argument"): a
    :class:`~explorer.analysis.section_map.SectionMap` (or ``params, h`` with ``phi0=`` and
    ``tol=``, default :data:`~explorer.integrate.methods.DEFAULT_TOL`) with ``y0`` its section
    points ((p1, p2) or (N, 2); M from the energy with the sign of ``direction``, docs/model.md
    R9): its ``params``, ``h``, ``phi0`` and ``tol``, and with the defaults (Taylor, direction
    +1) the rows are the map's iterates; or the flow, the model parameters alone with the
    keyword ``states=`` full states ((N, 5) or (5,)) and ``phi0=``, ``tol=`` this call's own:
    ``crossings(params, states=Y, n_crossings=K)``.

    ``tol`` is the tolerance of the adaptive methods, ``dt`` the fixed step of the splitting
    methods (default 0.05).  ``threads`` sets numba's thread count for this call (default: all).
    A start point lying on the section is not reported as a crossing.

    Every row is returned at once, (N, n_crossings, 5) float64: a request larger than half the
    machine's memory is refused (ParameterError naming its size); :func:`iter_crossings` streams
    the same rows in blocks of bounded size.

    Inside a :class:`~explorer.analysis.budget.Budget` that has stopped nothing runs
    (:class:`~explorer.analysis.budget.BudgetExceeded`), and the budget's step cap, if it has one,
    bounds ``max_steps`` (a batch reads no stop switch).
    """
    from explorer.analysis import budget

    budget.checkpoint()
    max_steps = budget.step_cap(max_steps)
    params, y0, tol, phi0 = _start(system, y0, tol, phi0, direction)
    run = _validated(params, y0, n_crossings, method, tol, dt, tmax, max_steps, phi0, direction, threads)
    N, K = run.Y0.shape[0], run.K
    need = result_bytes(N, K)
    mem = physical_memory()
    if mem and need > MAX_MEMORY_FRACTION * mem:
        raise ParameterError(f"crossings: {N} orbits x {K} crossings need {human_bytes(need)} in memory "
                             f"(this machine has {human_bytes(mem)}); stream them with iter_crossings() "
                             "or lower crossings")
    data, count, status, final, info = _outputs(N, K)
    carry = StreamState.initial(run.P, run.Y0, phi0=run.settings["phi0"]).carry
    limits = np.full((N, 2), K, np.int64)
    _run_block(run, run.Y0, carry, limits, data, count, status, final, info)
    return Crossings(data, count, status, final, info, method, run.settings)


#: crossings a run of :func:`propagate` may pass on its way to t (its row buffer; more stop it)
PROPAGATE_CROSSINGS = 16


@system_first(settings=("phi0", "tol"), defaults={"tol": DEFAULT_TOL}, flow=True)
def propagate(system, y0, *, t: float, method: str = "taylor", tol: float = DEFAULT_TOL, dt: float | None = None,
              threads: int | None = None) -> np.ndarray:
    """The states of the orbits from ``y0`` at time ``t`` > 0 (N, 5): the run of :func:`crossings`
    (the same steps) stopped by its time budget, whose last step ends exactly at t.  The system
    and ``y0`` as for :func:`crossings` (a map and its section points, or ``params`` and
    ``states=`` full states).  An orbit that crosses the section more than :data:`PROPAGATE_CROSSINGS` times on
    the way, or stops for another reason, raises ParameterError: propagate it in shorter times."""
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


@dataclass
class StreamState:
    """Where a streamed run stands between two blocks: everything but the crossings themselves.

    A run continued from it (``iter_crossings(..., state=...)``) takes exactly the steps of an
    uninterrupted run, so its rows are bit for bit the same.  Small: O(N) numbers.

    Attributes
    ----------
    y : ndarray (N, 5)
        The state of every orbit where its last block ended.
    carry : ndarray (N, N_CARRY)
        The drivers' carry (time, its Kahan compensation, sin(phi - phi0), steps, H0, DOP853's
        next step: :mod:`explorer.integrate.drivers`).
    done : ndarray (N,) int64
        Crossings found so far.
    finished : ndarray (N,) bool
        The orbit has stopped (its ``status`` is final).
    status : ndarray (N,) int64
        Status of the last block (final when ``finished``).
    info : ndarray (N, 3)
        Time reached, steps, Casimir error of ``y``.
    blocks : int
        Blocks computed so far.
    """

    y: np.ndarray
    carry: np.ndarray
    done: np.ndarray
    finished: np.ndarray
    status: np.ndarray
    info: np.ndarray
    blocks: int = 0

    ARRAYS = ("y", "carry", "done", "finished", "status", "info")

    @classmethod
    def initial(cls, params, y0, *, phi0: float = math.pi) -> StreamState:
        """The state of a run from ``y0`` before its first block (where :func:`iter_crossings`
        starts when given no state)."""
        P = packed_params(params)
        Y0 = np.ascontiguousarray(np.atleast_2d(np.asarray(y0, dtype=np.float64)))
        g1, g2 = model.section_gamma(float(phi0))
        N = Y0.shape[0]
        carry = np.empty((N, layout.N_CARRY))
        methods.start_carry(Y0, P, g2, g1, carry)
        return cls(Y0.copy(), carry, np.zeros(N, np.int64), np.zeros(N, bool), np.zeros(N, np.int64),
                   np.zeros((N, 3)), 0)

    def take(self, a: int, b: int) -> StreamState:
        """The state of orbits a..b-1 (a copy)."""
        return StreamState(*(getattr(self, n)[a:b].copy() for n in self.ARRAYS), self.blocks)

    def put(self, a: int, part: StreamState) -> None:
        """Write the state of orbits a, a+1, ... from ``part`` (of :meth:`take`)."""
        b = a + part.y.shape[0]
        for n in self.ARRAYS:
            getattr(self, n)[a:b] = getattr(part, n)

    def copy(self) -> StreamState:
        return StreamState(*(getattr(self, a).copy() for a in self.ARRAYS), self.blocks)

    def as_arrays(self) -> dict:
        """The state as plain arrays (for a checkpoint); :meth:`from_arrays` reads them back."""
        out = {a: getattr(self, a) for a in self.ARRAYS}
        out["blocks"] = np.array(self.blocks, np.int64)
        return out

    @classmethod
    def from_arrays(cls, arrays) -> StreamState:
        return cls(*(np.array(arrays[a]) for a in cls.ARRAYS), int(arrays["blocks"]))


@dataclass(frozen=True)
class CrossingBlock:
    """One block of a streamed run (:func:`iter_crossings`).

    ``index[i]`` is the orbit (row of ``y0``) whose next ``count[i]`` crossings are
    ``data[i, :count[i]]``; they follow the ``start[i]`` it had before this block.  ``state`` is
    the run's :class:`StreamState` after this block (a copy: store it to resume from here).
    """

    index: np.ndarray
    start: np.ndarray
    data: np.ndarray
    count: np.ndarray
    state: StreamState

    def rows(self, i: int) -> np.ndarray:
        """The rows of the i-th orbit of this block, (count[i], 5)."""
        return self.data[i, : self.count[i]]


@system_first(settings=("phi0", "tol"), defaults={"tol": DEFAULT_TOL}, flow=True)
def iter_crossings(system, y0, *, n_crossings: int, block: int = DEFAULT_BLOCK, state: StreamState | None = None,
                   method: str = "taylor", tol: float = DEFAULT_TOL, dt: float | None = None,
                   tmax: float | None = None, max_steps: int = DEFAULT_MAX_STEPS, phi0: float = math.pi,
                   direction: int = 1, threads: int | None = None):
    """:func:`crossings` in blocks: yields a :class:`CrossingBlock` of at most about ``block``
    crossings per orbit (at most ``block`` + the roots of one step, MAX_ROOTS_PER_STEP), until
    every orbit has its ``n_crossings`` or has stopped; memory is O(N x block), whatever
    ``n_crossings``.  The rows, final states and statuses are bit for bit those of
    :func:`crossings` (each block continues the drivers from the previous one's carry: the same
    steps, the same time sum).

    ``state``: continue a run from the :class:`StreamState` of one of its blocks (e.g. read back
    from a checkpoint), with the same arguments otherwise.  The last block's state gives the
    final ``status`` and ``info`` of every orbit.  The system and ``y0`` as for :func:`crossings`.
    """
    params, y0, tol, phi0 = _start(system, y0, tol, phi0, direction)
    run = _validated(params, y0, n_crossings, method, tol, dt, tmax, max_steps, phi0, direction, threads)
    if not isinstance(block, numbers.Integral) or block < 1:
        raise ParameterError(f"block must be an integer >= 1, got {block!r}")
    N, K = run.Y0.shape[0], run.K
    st = StreamState.initial(run.P, run.Y0, phi0=run.settings["phi0"]) if state is None else state.copy()
    if st.y.shape != (N, 5) or st.carry.shape != (N, layout.N_CARRY):
        raise ParameterError(f"state is for {st.y.shape[0]} orbits, y0 has {N}")
    width = min(K, int(block) + layout.MAX_ROOTS_PER_STEP)
    while True:
        idx = np.flatnonzero(~st.finished)
        if idx.size == 0:
            return
        n = idx.size
        remaining = K - st.done[idx]
        limits = np.empty((n, 2), np.int64)
        limits[:, layout.LIMIT_TARGET] = np.minimum(block, remaining)
        limits[:, layout.LIMIT_ROOM] = np.minimum(remaining, width)
        Y = np.ascontiguousarray(st.y[idx])
        carry = np.ascontiguousarray(st.carry[idx])
        data, count, status, final, info = _outputs(n, width)
        _run_block(run, Y, carry, limits, data, count, status, final, info)
        start = st.done[idx].copy()
        st.y[idx] = final
        st.carry[idx] = carry
        st.done[idx] += count
        st.status[idx] = status
        st.info[idx] = info
        st.finished[idx] = (status != int(Status.DONE)) | (st.done[idx] >= K)
        st.blocks += 1
        yield CrossingBlock(idx, start, data, count, st.copy())
