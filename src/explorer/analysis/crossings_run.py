"""Runs of Chaplygin's model to its section phi = phi0, below the system argument's rule: the
settings, the drivers' blocks and their results (:func:`run`; explorer.analysis.sections takes the
system first, docs/commands/orbit.md)."""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from explorer import model
from explorer._jit import get_num_threads, max_threads, set_num_threads
from explorer.integrate import layout, methods
from explorer.integrate.methods import ADAPTIVE_METHODS, DEFAULT_DT, DEFAULT_TOL, METHODS
from explorer.kernels import STATUS_NAMES, Status
from explorer.model import ParameterError, packed_params, validation

__all__ = ["DEFAULT_MAX_STEPS", "CrossingBlock", "Crossings", "Integration", "StreamState", "crossing_settings",
           "energy_warning", "human_bytes", "max_energy_error", "result_bytes", "run", "stream"]

DEFAULT_MAX_STEPS = 10**9
#: an energy error above this fraction of max(|h|, 1) is warned about (:func:`energy_warning`)
ENERGY_WARN_REL = 1e-6
#: crossings per orbit and block of :func:`iter_crossings`
DEFAULT_BLOCK = 100_000
ROW_BYTES = 40
#: :func:`crossings` refuses a result larger than this fraction of the machine's memory
MAX_MEMORY_FRACTION = validation.MAX_MEMORY_FRACTION
physical_memory = validation.physical_memory
human_bytes = validation.human_bytes


@dataclass(frozen=True)
class Crossings:
    """Result of :func:`crossings` for N orbits and up to K crossings each: data[i, k] =
    (t, p1, p2, M, H - H0) for k < count[i], NaN beyond (a System's rows: t, its state, E - E0 if
    it has an energy, named by ``settings["columns"]``, docs/systems.md); ``status[i]`` a Status
    code; ``final[i]`` the last state; info[i] = (t_end, steps, Casimir error or NaN)."""

    data: np.ndarray
    count: np.ndarray
    status: np.ndarray
    final: np.ndarray
    info: np.ndarray
    method: str
    settings: dict = field(default_factory=dict)

    def orbit(self, i: int) -> np.ndarray:
        """The crossings of orbit i as an array (count_i, columns)."""
        return self.data[i, : self.count[i]]

    def status_name(self, i: int) -> str:
        return STATUS_NAMES[int(self.status[i])]

    def status_of(self, i: int) -> Status:
        """Why orbit i stopped, as a :class:`~explorer.kernels.Status`."""
        return Status(int(self.status[i]))


def max_energy_error(data) -> float:
    """max |H - H0| over the rows in ``data``, NaN ignored; 0.0 if there are none.  ``data``: rows
    of Chaplygin's model (H - H0 in column 4), or a :class:`Crossings` (a System's energy column
    is its last, ``settings["columns"]``; ParameterError for a System without an energy)."""
    column = 4
    if isinstance(data, Crossings):
        columns = data.settings.get("columns")
        if columns is not None:
            if columns[-1] != "E - E0":
                raise ParameterError(f"max_energy_error: the crossings of {data.settings.get('system')} have no "
                                     "energy column (the System has no energy)")
            column = len(columns) - 1
        data = data.data
    dh = np.abs(np.asarray(data, dtype=np.float64)[..., column])
    dh = dh[np.isfinite(dh)]
    return float(dh.max()) if dh.size else 0.0


def energy_warning(max_dh: float, h: float, setting: str) -> str | None:
    """A warning naming ``setting`` when max_dh > ENERGY_WARN_REL * max(|h|, 1), else None."""
    limit = ENERGY_WARN_REL * max(abs(h), 1.0)
    if max_dh <= limit:
        return None
    return (f"energy error up to {max_dh:.2e} (> {limit:.0e} = {ENERGY_WARN_REL:g} x max(|h|, 1)): "
            f"{setting} is too coarse for this orbit; refine it to trust the section")


def result_bytes(n_orbits: int, n_crossings: int) -> int:
    """Bytes of :attr:`Crossings.data` for ``n_orbits`` x ``n_crossings`` rows."""
    return int(n_orbits) * int(n_crossings) * ROW_BYTES


@dataclass(frozen=True)
class Integration:
    """The settings of a run of :func:`crossings`, validated here (ParameterError naming the
    setting); a scene's ``[integration]`` table is one (docs/scenes.md)."""

    method: str = "taylor"
    tol: float = DEFAULT_TOL
    dt: float = DEFAULT_DT
    crossings: int = 1
    tmax: float | None = None
    max_steps: int = DEFAULT_MAX_STEPS
    phi0: float = math.pi
    direction: int = 1

    def _label(self, name: str) -> str:
        """How a refused setting is named in the message."""
        return name

    def _refusal(self, exc: ParameterError) -> ParameterError:
        """The error raised for a refused setting."""
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


def crossing_settings(params, y0, *, n_crossings: int, method: str = "taylor", tol: float = DEFAULT_TOL,
                      dt: float | None = None, tmax: float | None = None, max_steps: int = DEFAULT_MAX_STEPS,
                      phi0: float = math.pi, direction: int = 1) -> dict:
    """The settings :func:`crossings` records for this request, validated, without running it."""
    return dict(_validated(params, y0, n_crossings, method, tol, dt, tmax, max_steps, phi0, direction,
                           None).settings)


def _outputs(n: int, width: int):
    """The arrays the drivers fill: data (NaN), count, status, final state, info."""
    return (np.full((n, width, 5), np.nan), np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros((n, 5)),
            np.zeros((n, 3)))


def _run_block(run: _Run, Y, carry, limits, data, count, status, final, info) -> None:
    """One block of the drivers for the orbits Y, in place; an orbit the fixed step does not
    resolve is not integrated (status UNRESOLVED)."""
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
    if run.threads is None:
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


@dataclass
class StreamState:
    """Where a streamed run stands between two blocks: everything but the crossings themselves."""

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
        """The state of a run from ``y0`` before its first block."""
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
        """The state as plain arrays; :meth:`from_arrays` reads them back."""
        out = {a: getattr(self, a) for a in self.ARRAYS}
        out["blocks"] = np.array(self.blocks, np.int64)
        return out

    @classmethod
    def from_arrays(cls, arrays) -> StreamState:
        return cls(*(np.array(arrays[a]) for a in cls.ARRAYS), int(arrays["blocks"]))


@dataclass(frozen=True)
class CrossingBlock:
    """One block of :func:`iter_crossings`: orbit ``index[i]``'s next ``count[i]`` crossings, after
    its ``start[i]`` earlier ones, and the run's ``state`` after the block (resume from it)."""

    index: np.ndarray
    start: np.ndarray
    data: np.ndarray
    count: np.ndarray
    state: StreamState

    def rows(self, i: int) -> np.ndarray:
        """The rows of the i-th orbit of this block, (count[i], 5)."""
        return self.data[i, : self.count[i]]


def check_step_block(step_block, method: str) -> None:
    """ParameterError unless ``step_block`` of a stream of ``method`` is None, or an integer >= 1 for the methods a
    step cap does not change (whose kind ``resumes_at_any_step``, integrate.methods.Kind; not DOP853)."""
    if step_block is not None and (isinstance(step_block, bool) or not isinstance(step_block, numbers.Integral)
                                   or step_block < 1):
        raise ParameterError(f"step_block must be an integer >= 1 or None, got {step_block!r}")
    if step_block is not None and not methods.get(method).loops.resumes_at_any_step:
        raise ParameterError(f"step_block is for the methods a step cap does not change "
                             f"({', '.join(n for n, m in methods.REGISTRY.items() if m.loops.resumes_at_any_step)}), "
                             f"got method {method!r}")


def stream(st: StreamState, K: int, block: int, run_block, max_steps: int, step_block: int | None = None):
    """The blocks of a streamed run from ``st`` (updated in place) until every orbit has ``K`` crossings or
    stopped: per block, the unfinished orbits' limits (target: ``block`` more crossings, room for the
    roots of the last step) and ``run_block(Y, carry, limits, width, max_steps)`` -> (data, count, status,
    final, info) with ``carry`` continued in place, so the blocks take one run's steps (docs/architecture.md,
    "Streaming").  With ``step_block`` (check_step_block) a block's step cap is the least advanced orbit's
    steps plus ``step_block``: a stop at that cap, below the run's ``max_steps``, is no end (the next block
    continues the orbit exactly)."""
    width = min(K, int(block) + layout.MAX_ROOTS_PER_STEP)
    while True:
        idx = np.flatnonzero(~st.finished)
        if idx.size == 0:
            return
        remaining = K - st.done[idx]
        limits = np.empty((idx.size, 2), np.int64)
        limits[:, layout.LIMIT_TARGET] = np.minimum(block, remaining)
        limits[:, layout.LIMIT_ROOM] = np.minimum(remaining, width)
        carry = np.ascontiguousarray(st.carry[idx])
        cap = max_steps
        if step_block is not None:   # the step cap of this block: the orbit least advanced takes step_block
            cap = min(max_steps, int(carry[:, layout.CARRY_STEPS].min()) + step_block)
        data, count, status, final, info = run_block(np.ascontiguousarray(st.y[idx]), carry, limits, width, cap)
        if cap < max_steps:          # stopped at this block's cap, not at the run's budget: not finished
            status[(status == int(Status.MAX_STEPS)) & (carry[:, layout.CARRY_STEPS] < max_steps)] = int(Status.DONE)
        start = st.done[idx].copy()
        st.y[idx] = final
        st.carry[idx] = carry
        st.done[idx] += count
        st.status[idx] = status
        st.info[idx] = info
        st.finished[idx] = (status != int(Status.DONE)) | (st.done[idx] >= K)
        st.blocks += 1
        yield CrossingBlock(idx, start, data, count, st.copy())


def run(params, y0, *, n_crossings: int, method: str = "taylor", tol: float = DEFAULT_TOL, dt: float | None = None,
        tmax: float | None = None, max_steps: int = DEFAULT_MAX_STEPS, phi0: float = math.pi, direction: int = 1,
        threads: int | None = None) -> Crossings:
    """The crossings of Chaplygin's model from the states ``y0`` (N, 5): what :func:`explorer.crossings`
    runs once its first argument is read (docs/commands/orbit.md)."""
    from explorer.analysis import budget

    budget.checkpoint()
    max_steps = budget.step_cap(max_steps)
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
