"""A browser session's orbits (docs/commands/serve.md, "How it works"): an :class:`OrbitRun` streams a clicked
orbit block by block, bit for bit ``explorer orbit``; a :class:`Worker` runs them.  No web library here."""
from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np

from explorer.integrate import layout, methods
from explorer.kernels import STATUS_NAMES, STATUS_TMAX

#: crossings of an orbit's first block (the first points on screen, milliseconds after a click)
FIRST_BLOCK = 16
#: steps of an orbit's first block, and of later ones at most: a cancel stops within a block whatever dt
FIRST_STEPS = 20_000
MAX_STEPS_PER_BLOCK = 50_000_000
#: an orbit whose estimated steps (Worker._estimate) exceed this is said in the page up front
STEP_BUDGET = 50_000_000
#: steps of the probe that measures the time between crossings for the estimate
PROBE_STEPS = 20_000
#: later blocks are sized to take about this long (s), between MIN_BLOCK and MAX_BLOCK crossings
BLOCK_SECONDS = 0.05
MIN_BLOCK = 16
MAX_BLOCK = 20_000
#: time over which the chaos indicators (mean MEGNO, finite-time mLCE) of an orbit are computed
INDICATOR_TIME = 1000.0
#: an orbit's indicators are computed when it is finished, or once its blocks took this long (s)
INDICATOR_AFTER = 0.5
#: steps of an orbit's indicators at most (past them they are unknown, NaN)
INDICATOR_MAX_STEPS = 1_000_000
#: an OrbitRun's fields the page sets (while a block is computed on a copy: kept)
PAGE_FIELDS = ("paused", "sent", "readout", "marked", "hidden")
#: one colour per orbit, in turn: Tableau 10 and Vega's category20b/c, none near white or gray
COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
          "#bcbd22", "#393b79", "#637939", "#843c39", "#7b4173", "#3182bd", "#e6550d", "#31a354",
          "#5254a3", "#8ca252", "#bd9e39", "#ad494a", "#a55194", "#756bb1", "#636363", "#fd8d3c")


@dataclass
class OrbitRun:
    """One clicked orbit: its start, settings, every row computed (``rows``, of which the first
    ``done`` count: a lowered crossings per click keeps the others) and where its stream stands."""

    ident: int
    p1: float
    p2: float
    settings: Any                  # the page's settings (settings.Settings, settings.SystemSettings)
    paused: bool = False
    state: Any = None              # the stream's sections.StreamState after the last block
    block: int = FIRST_BLOCK
    steps: int = FIRST_STEPS
    done: int = 0
    status: str = "running"
    wall: float = 0.0
    wants_indicators: bool = True
    estimated: bool = False
    step_rate: float = 0.0
    turn: int = 0                  # when its last block was handed out (round robin)
    sent: int = 0                  # its rows in the browser (the page's)
    indicators: tuple | None = None   # (mean MEGNO, mLCE) over INDICATOR_TIME, once known
    readout: tuple | None = None      # (values, text) of overlays.orbit_readout once picked (the orbit list's)
    marked: bool = True               # its start's cross is drawn before its first crossings (the page's)
    hidden: bool = False              # off the page, still computed (the page's)
    rows: np.ndarray = field(default_factory=lambda: np.zeros((0, 5)))

    @property
    def colour(self) -> int:
        """Its index in COLORS: the orbits take them in turn."""
        return (self.ident - 1) % len(COLORS)

    @property
    def phase(self) -> str:
        """running, paused (set aside while running), done, or why it stopped."""
        return "paused" if self.paused and self.status == "running" else self.status

    @property
    def megno(self) -> float:
        return self.indicators[0] if self.indicators else math.nan

    @property
    def finished(self) -> bool:
        return self.state is not None and bool(self.state.finished[0])

    def advance(self) -> np.ndarray:
        """Compute the next block (at most ``block`` crossings, and ``steps`` steps where the method resumes
        exactly at any step); returns its rows (n, 5): t, p1, p2, M, H - H0 (a System's: t, a, b, solve, E - E0)."""
        s, t0 = self.settings, time.perf_counter()
        taken = 0 if self.state is None else int(self.state.carry[0, layout.CARRY_STEPS])
        steps = self.steps if methods.get(s.method).loops.resumes_at_any_step else None
        rows, state = next(s.stream(self.p1, self.p2, self.state, self.block, steps), (np.zeros((0, 5)), self.state))
        self.state, self.done, self.rows = state, int(state.done[0]), np.concatenate([self.rows, rows])
        if self.finished:
            self.status = STATUS_NAMES[int(state.status[0])]
        elapsed = time.perf_counter() - t0
        self.wall += elapsed
        rate = len(rows) / elapsed if elapsed > 0 and len(rows) else 0.0
        target = int(rate * BLOCK_SECONDS) if rate else 2 * self.block
        self.block = max(MIN_BLOCK, min(MAX_BLOCK, target, 4 * self.block))
        self.step_rate = (int(state.carry[0, layout.CARRY_STEPS]) - taken) / elapsed if elapsed > 0 else 0.0
        self.steps = max(FIRST_STEPS, min(MAX_STEPS_PER_BLOCK, int(self.step_rate * BLOCK_SECONDS)))
        return rows


def _duration(seconds: float) -> str:
    for unit, size in (("h", 3600.0), ("min", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.2g} {unit}"
    return f"{seconds:.2g} s"


def orbit_indicators(settings, p1: float, p2: float) -> tuple:
    """(mean MEGNO <Y>, finite-time mLCE) over INDICATOR_TIME of the orbit from (p1, p2); NaN if it stopped early."""
    megno, mlce = settings.megno([p1], [p2], INDICATOR_TIME, INDICATOR_MAX_STEPS, mlce=True)
    return float(megno[0]), float(mlce[0])


class Worker:
    """A session's orbits, ``runs`` {orbit id: OrbitRun} in click order (running, paused or stopped), run block
    by block by one task ``orbits`` of ``session`` (tasks.Session), which applies each block, error, notice and
    indicator on the session's loop; :meth:`cancel` ends it."""

    def __init__(self, session, on_block: Callable[[int, np.ndarray, int, str], None],
                 on_error: Callable[[int, BaseException], None] = lambda _i, _e: None,
                 on_indicators: Callable[[int, float, float], None] | None = None,
                 on_notice: Callable[[int, str], None] = lambda _i, _t: None):
        self.session = session
        self._on_block, self._on_error = on_block, on_error
        self._on_indicators, self._on_notice = on_indicators, on_notice
        self.runs: dict[int, OrbitRun] = {}
        self._next_id = self._turn = 0

    def _queue(self) -> list[OrbitRun]:
        """The orbits to compute."""
        return [r for r in self.runs.values() if r.status == "running" and not r.paused]

    def _ensure_running(self) -> None:
        if self._queue() and not self.session.running("orbits"):
            self.session.start("orbits", self._loop())

    def submit(self, p1: float, p2: float, settings, ident: int | None = None) -> OrbitRun:
        """Queue the orbit from (p1, p2) as orbit ``ident`` (None: a new id; a cancelled orbit's: its rerun)."""
        if ident is None:
            self._next_id += 1
            ident = self._next_id
        run = self.runs[ident] = OrbitRun(ident, float(p1), float(p2), settings)
        self._ensure_running()
        return run

    def cancel(self) -> None:
        """Stop every orbit (the block in progress is dropped)."""
        self.runs.clear()
        self.session.cancel("orbits")

    def recount(self, settings) -> None:
        """Every orbit at ``settings`` (only the crossings per click K differ): cut to K (its rows kept), continued,
        or rerun if its time budget stopped it."""
        for ident, run in self.runs.items():
            self.runs[ident] = self._recount(run, settings)
        self._ensure_running()

    @staticmethod
    def _recount(run: OrbitRun, settings) -> OrbitRun:
        k, n, run.settings = settings.crossings, len(run.rows), settings
        run.done = min(n, k)
        if run.status == "failed":
            return run
        end = STATUS_NAMES[int(run.state.status[0])] if run.finished else "running"
        if n >= k:
            run.status = "done" if n > k or end == "running" else end
        elif end == STATUS_NAMES[STATUS_TMAX]:     # (its time budget, 100 K, grows)
            return OrbitRun(run.ident, run.p1, run.p2, settings, paused=run.paused, hidden=run.hidden,
                            wants_indicators=run.indicators is None,    # (indicators in flight: anew)
                            indicators=run.indicators, readout=run.readout)
        elif end == "done":                         # (it reached the old count: on from where its stream stopped)
            run.state = run.state.copy()
            run.state.finished[:] = False
            run.status, run.estimated = "running", False
        else:
            run.status = end
        return run

    def pause(self) -> None:
        """Set every running orbit aside (the block in progress still applies)."""
        for r in self._queue():
            r.paused = True

    def resume(self) -> list[int]:
        """Queue the paused orbits again; returns their ids."""
        moved = self.paused()
        for r in self.runs.values():
            r.paused = False
        self._ensure_running()
        return moved

    def paused(self) -> list[int]:
        """The ids of the paused orbits."""
        return [r.ident for r in self.runs.values() if r.phase == "paused"]

    @staticmethod
    def _estimate(run: OrbitRun) -> str | None:
        """(In the executor) the notice of a fixed-step orbit expected to take more than STEP_BUDGET steps: its
        crossings times the time between two (from a Taylor probe of the page's stream) over ``dt``, within its
        budgets.  None when adaptive, finished, within the budget, or the probe finds no crossing.  Once a run."""
        run.estimated = True
        s, rate = run.settings, run.step_rate
        if s.adaptive or run.finished:
            return None
        rows, _state = next(replace(s, method="taylor", crossings=2).stream(run.p1, run.p2, None, 2, PROBE_STEPS))
        if not len(rows):
            return None
        need = min(s.crossings * float(rows[-1, 0]) / len(rows), s.effective_tmax) / s.dt
        steps = int(min(need, s.max_steps))
        if steps <= STEP_BUDGET:
            return None
        took = f", about {_duration(steps / rate)} at {rate:.2g} steps/s" if rate > 0 else ""
        return (f"orbit {run.ident} needs about {steps:.2g} steps ({s.crossings} crossings of {s.method} "
                f"at dt = {s.dt:g}{took}); it runs until Clear, Undo, a new value or closing the tab "
                "stops it; a larger dt or fewer crossings is quicker")

    def _queued(self, run: OrbitRun) -> bool:
        return self.runs.get(run.ident) is run

    async def _loop(self) -> None:
        """The task: block after block until no orbit is queued (a new one's first, then round robin); each on
        a copy of its run (_hand_out)."""
        session = self.session
        while queue := self._queue():
            run = next((r for r in reversed(queue) if r.done == 0), min(queue, key=lambda r: r.turn))
            work = copy.copy(run)
            try:
                rows = await session.run(work.advance)
                notice = None if work.estimated else await session.run(self._estimate, work)
            except Exception as exc:  # noqa: BLE001 - reported in the page; the server keeps serving
                if self._queued(run):
                    run.status = "failed"
                    await session.apply(partial(self._on_error, run.ident, exc))
                continue
            await session.apply(partial(self._hand_out, run, work, rows, notice))
            if not self._queued(run):       # removed while its block was computed
                continue
            if self._on_indicators and run.wants_indicators and (run.finished or run.wall >= INDICATOR_AFTER):
                run.wants_indicators = False
                try:
                    megno, mlce = await session.run(orbit_indicators, run.settings, run.p1, run.p2)
                except Exception:  # noqa: BLE001 - an indicator that fails is shown as unknown
                    megno = mlce = math.nan
                await session.apply(partial(self._hand_indicators, run, megno, mlce))

    def _hand_indicators(self, run: OrbitRun, megno: float, mlce: float) -> None:
        """(On the loop) the indicators computed for ``run`` become its own, and go to the page, unless it was
        removed or rerun meanwhile (a rerun's are its own)."""
        if self._queued(run) and self._on_indicators:
            run.indicators = (megno, mlce)
            self._on_indicators(run.ident, megno, mlce)

    def _hand_out(self, run: OrbitRun, work: OrbitRun, rows: np.ndarray, notice: str | None) -> None:
        """(On the loop) the block computed on ``work`` becomes ``run``'s, and goes to the page."""
        if not self._queued(run) or work.settings is not run.settings:   # removed or recounted meanwhile
            return
        self._turn += 1
        run.__dict__.update(work.__dict__, turn=self._turn, **{k: getattr(run, k) for k in PAGE_FIELDS})
        if notice is not None:
            self._on_notice(run.ident, notice)
        if len(rows) or run.finished:   # (a block cut at its steps before a crossing: nothing to show)
            self._on_block(run.ident, rows, run.done, run.status)
