"""The orbits of one browser session, block by block (docs/commands/serve.md, "How it works"): an
:class:`OrbitRun` (a :class:`SystemRun` for a System) continues a clicked orbit where its last block
ended, rows bit for bit those of ``explorer orbit``; a :class:`Worker` runs them newest first, then
round robin.  No web library here."""
from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np

from explorer import model
from explorer.analysis import sections
from explorer.integrate import layout, methods
from explorer.kernels import STATUS_NAMES, STATUS_TMAX

#: crossings of an orbit's first block (the first points on screen, milliseconds after a click)
FIRST_BLOCK = 16
#: steps of an orbit's first block, and of later ones at most: a cancel stops within a block whatever dt
FIRST_STEPS = 20_000
MAX_STEPS_PER_BLOCK = 50_000_000
#: an orbit whose estimated steps (:func:`step_estimate`) exceed this is said in the page up front
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
#: steps of an orbit's indicators at most (past it they are unknown, NaN)
INDICATOR_MAX_STEPS = 1_000_000
#: mean MEGNO above this is called "chaotic-like" (quasi-periodic orbits: <Y> -> 2)
CHAOTIC_MEGNO = 3.0
#: one colour per orbit, in turn: Tableau 10 and Vega's category20b/c, none near white or gray
COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
          "#bcbd22", "#393b79", "#637939", "#843c39", "#7b4173", "#3182bd", "#e6550d", "#31a354",
          "#5254a3", "#8ca252", "#bd9e39", "#ad494a", "#a55194", "#756bb1", "#636363", "#fd8d3c")


@dataclass
class OrbitRun:
    """One clicked orbit: its start, settings and where its stream stands."""

    ident: int
    p1: float
    p2: float
    settings: Any                  # the page's settings (explorer.app.serve.settings)
    y0: np.ndarray = field(init=False)
    state: sections.StreamState = field(init=False)
    block: int = FIRST_BLOCK
    steps: int = FIRST_STEPS
    done: int = 0
    status: str = "running"
    wall: float = 0.0
    wants_indicators: bool = True
    estimated: bool = False
    step_rate: float = 0.0
    ahead: np.ndarray = field(default_factory=lambda: np.zeros((0, 5)))   # rows computed past ``done``, cut
    after: str = "running"         # the status once ``ahead`` is handed out

    def __post_init__(self):
        s = self.settings
        self.y0 = model.section_state(s.params, [self.p1], [self.p2], s.h, s.phi0, s.direction or 1)
        self.state = sections.StreamState.initial(s.params, self.y0, phi0=s.phi0)

    @property
    def finished(self) -> bool:
        return bool(self.state.finished[0])

    def reopen(self) -> None:
        """Compute on to a larger count from where the run stopped at its own."""
        self.state = self.state.copy()
        self.state.finished[:] = False
        self.status = "running"

    def advance(self) -> np.ndarray:
        """Compute the next block (at most ``block`` crossings and ``steps`` steps); returns its
        rows (n, 5): t, p1, p2, M, H - H0 (a System's: t, a, b, solve, H - H0)."""
        t0 = time.perf_counter()
        rows, steps = self._next_block()
        elapsed = time.perf_counter() - t0
        self.wall += elapsed
        rate = len(rows) / elapsed if elapsed > 0 and len(rows) else 0.0
        target = int(rate * BLOCK_SECONDS) if rate else 2 * self.block
        self.block = max(MIN_BLOCK, min(MAX_BLOCK, target, 4 * self.block))
        self.step_rate = steps / elapsed if elapsed > 0 else 0.0
        self.steps = max(FIRST_STEPS, min(MAX_STEPS_PER_BLOCK, int(self.step_rate * BLOCK_SECONDS)))
        return rows

    def _next_block(self) -> tuple:
        """(rows, steps taken) of the next block."""
        s = self.settings
        taken = int(self.state.carry[0, layout.CARRY_STEPS])
        exact = methods.get(s.method).loops.resumes_at_any_step    # (a block may end at ``steps`` then)
        b = next(sections.iter_crossings(s.params, states=self.y0, n_crossings=s.crossings, block=self.block,
                                         state=self.state, max_steps=s.max_steps,
                                         step_block=self.steps if exact else None,
                                         **s.section_kwargs()), None)
        if b is None:           # nothing left (the state was finished already)
            return np.zeros((0, 5)), 0
        rows = b.rows(0).copy() if b.count.size else np.zeros((0, 5))
        self.state = b.state
        self.done = int(self.state.done[0])
        if self.finished:
            self.status = STATUS_NAMES[int(self.state.status[0])]
        return rows, int(self.state.carry[0, layout.CARRY_STEPS]) - taken


def _duration(seconds: float) -> str:
    for unit, size in (("h", 3600.0), ("min", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.2g} {unit}"
    return f"{seconds:.2g} s"


def step_estimate(settings, y0) -> int | None:
    """Steps a fixed-step orbit from ``y0`` is expected to take (its crossings times the time between
    two, from a Taylor probe, over ``dt``, within its budgets); None if adaptive or the probe finds none."""
    if settings.adaptive:
        return None
    probe = sections.crossings(settings.params, states=y0, n_crossings=2, max_steps=PROBE_STEPS,
                               phi0=settings.phi0, direction=settings.direction)
    n = int(probe.count[0])
    if n == 0:
        return None
    period = float(probe.orbit(0)[n - 1, 0]) / n
    need = min(settings.crossings * period, settings.effective_tmax) / settings.dt
    return int(min(need, settings.max_steps))


class SystemRun(OrbitRun):
    """A clicked orbit of a System's section map (system_page.SystemSettings): each block continues the
    flow from its last state (analysis.system_sections.system_crossings); rows (t, a, b, solve, H - H0)."""

    def __post_init__(self):
        smap = self.settings.smap
        self.y0 = smap.states([(self.p1, self.p2)])
        self._y, self._t, self._h0 = self.y0, 0.0, float(smap.energy_of(self.y0)[0])
        self._cols = [1 + smap.system.states.index(s) for s in (*smap.coords, smap.solve)]
        self._finished = False

    @property
    def finished(self) -> bool:
        return self._finished

    def reopen(self) -> None:
        self._finished, self.status = False, "running"

    def _next_block(self) -> tuple:
        from explorer.analysis.system_sections import system_crossings
        from explorer.kernels import STATUS_DONE, STATUS_MAX_STEPS

        s, smap = self.settings, self.settings.smap
        k = min(self.block, s.crossings - self.done)
        data, count, status, final, info, *_ = system_crossings(
            smap.system, self._y, n_crossings=k, section=smap.section.expr, direction=smap.direction, tol=s.tol,
            tmax=smap.tmax * k, max_steps=self.steps, threads=1)
        n, code = int(count[0]), int(status[0])
        d = data[0, :n]
        rows = np.column_stack([d[:, 0] + self._t, d[:, self._cols], smap.energy_of(d[:, 1:5]) - self._h0])
        self._y, self._t, self.done = final[:1].copy(), self._t + float(info[0, 0]), self.done + n
        if self.done >= s.crossings or code not in (STATUS_DONE, STATUS_MAX_STEPS):
            self._finished = True
            self.status = "done" if self.done >= s.crossings else STATUS_NAMES[code]
        return rows, int(info[0, 1])


def warm_up(settings) -> None:
    """Load (or compile) the crossing kernels of ``settings``' method: one crossing from the region's centre."""
    region = settings.region
    if region is None:
        return
    try:
        replace(settings, crossings=1).new_run(0, region[0], region[1]).advance()
    except Exception:  # noqa: BLE001 - the click will report the same error with its orbit
        return


def orbit_indicators(settings, p1: float, p2: float) -> tuple:
    """(mean MEGNO <Y>, finite-time mLCE) over INDICATOR_TIME of the orbit from (p1, p2); NaN if it stopped early."""
    megno, mlce = settings.megno([p1], [p2], INDICATOR_TIME, INDICATOR_MAX_STEPS, mlce=True)
    return float(megno[0]), float(mlce[0])


class Worker:
    """A session's orbits, run block by block by one task ``orbits`` of ``session`` (tasks.Session), which
    applies each block, error, notice and indicator on the session's loop; :meth:`cancel` ends it."""

    def __init__(self, session, on_block: Callable[[int, np.ndarray, int, str], None],
                 on_error: Callable[[int, BaseException], None] = lambda _i, _e: None,
                 on_indicators: Callable[[int, float, float], None] | None = None,
                 on_notice: Callable[[int, str], None] = lambda _i, _t: None):
        self.session = session
        self._on_block, self._on_error = on_block, on_error
        self._on_indicators, self._on_notice = on_indicators, on_notice
        self._runs: list[OrbitRun] = []
        self._paused: list[OrbitRun] = []     # set aside by pause(), in the order they had
        self._ended: list[OrbitRun] = []      # finished, kept for a change of the crossings (recount)
        self._next_id = 0
        self._rr = 0

    def _ensure_running(self) -> None:
        if self._runs and not self.session.running("orbits"):
            self.session.start("orbits", self._loop())

    def submit(self, p1: float, p2: float, settings, ident: int | None = None) -> OrbitRun:
        """Queue the orbit from (p1, p2) as orbit ``ident`` (None: a new id; a cancelled orbit's: its rerun)."""
        if ident is None:
            self._next_id += 1
            ident = self._next_id
        run = settings.new_run(ident, float(p1), float(p2))
        self._runs.insert(0, run)      # newest first: its first block comes next
        self._ensure_running()
        return run

    def cancel(self) -> None:
        """Stop every queued, running or paused orbit (the block in progress is dropped)."""
        self._runs, self._paused, self._ended = [], [], []
        self.session.cancel("orbits")

    def remove(self, ident: int) -> None:
        """Stop one orbit, running or paused (undo)."""
        self._runs = [r for r in self._runs if r.ident != ident]
        self._paused = [r for r in self._paused if r.ident != ident]
        self._ended = [r for r in self._ended if r.ident != ident]

    def recount(self, settings, cut: Callable[[int, int], np.ndarray]) -> dict:
        """Every orbit at ``settings``, which differ only in the crossings per click K: one past K is cut to
        K (``cut(ident, K)`` returns its rows past K, kept in :attr:`OrbitRun.ahead`); one short of K gets
        its kept rows and continues, or reruns (``cut(ident, 0)``) if it stopped on its time budget (100 K).
        A block in progress is dropped.  Returns {ident: (crossings, status)}."""
        out: dict = {}
        groups = (self._runs, self._paused, self._ended)
        self._runs, self._paused, self._ended = [], [], []
        for paused, runs in zip((False, True, False), groups):
            for run in runs:
                run = self._recount(run, settings, cut)
                (self._ended if run.status != "running" else self._paused if paused else self._runs).append(run)
                out[run.ident] = (run.done, run.status)
        self._ensure_running()
        return out

    def _recount(self, run: OrbitRun, settings, cut) -> OrbitRun:
        k, run.settings = settings.crossings, settings
        if run.done > k:
            if not len(run.ahead):
                run.after = run.status
            run.ahead = np.concatenate([cut(run.ident, k), run.ahead])
            run.done, run.status = k, "done"
            return run
        end = run.after if len(run.ahead) else run.status      # the status at the end of its rows
        if end == STATUS_NAMES[STATUS_TMAX] and run.done + len(run.ahead) < k:   # (its time budget, 100 K, grows)
            cut(run.ident, 0)
            return settings.new_run(run.ident, run.p1, run.p2)
        rows, run.ahead = run.ahead[:k - run.done], run.ahead[k - run.done:]
        run.done += len(rows)
        run.status = "done" if len(run.ahead) else end
        if run.status in ("running", "done"):
            run.status = "done" if run.done >= k else "running"
            if run.status == "running" and run.finished:
                run.reopen()
                run.estimated = False
        if len(rows):
            self._on_block(run.ident, rows, run.done, run.status)
        return run

    def pause(self) -> list[int]:
        """Set every running orbit aside (the block in progress still applies); returns their ids."""
        moved, self._runs = self._runs, []
        self._paused = self._paused + moved
        return [r.ident for r in moved]

    def resume(self) -> list[int]:
        """Queue the paused orbits again, after the running ones; returns their ids."""
        moved, self._paused = self._paused, []
        self._runs = self._runs + moved
        self._ensure_running()
        return [r.ident for r in moved]

    def paused(self) -> list[int]:
        """The ids of the paused orbits."""
        return [r.ident for r in self._paused]

    def _estimate(self, run: OrbitRun) -> str | None:
        """(In the executor) the notice of an orbit expected to take more than STEP_BUDGET steps."""
        if run.finished:
            return None
        steps = step_estimate(run.settings, run.y0)
        if steps is None or steps <= STEP_BUDGET:
            return None
        s, rate = run.settings, run.step_rate
        took = f", about {_duration(steps / rate)} at {rate:.2g} steps/s" if rate > 0 else ""
        return (f"orbit {run.ident} needs about {steps:.2g} steps ({s.crossings} crossings of {s.method} "
                f"at dt = {s.dt:g}{took}); it runs until Clear, Undo, a new value or closing the tab "
                "stops it; a larger dt or fewer crossings is quicker")

    def _pick(self) -> OrbitRun | None:
        fresh = [r for r in self._runs if r.done == 0]
        if fresh:
            return fresh[0]
        if not self._runs:
            return None
        self._rr = (self._rr + 1) % len(self._runs)
        return self._runs[self._rr]

    def _queued(self, run: OrbitRun) -> bool:
        return any(r is run for r in self._runs + self._paused + self._ended)

    async def _loop(self) -> None:
        """The task: block after block until no orbit is queued; each on a copy of its run (_hand_out)."""
        session = self.session
        while (run := self._pick()) is not None:
            work = copy.copy(run)
            try:
                rows = await session.run(work.advance)
                notice = None
                if not work.estimated:
                    work.estimated = True
                    notice = await session.run(self._estimate, work)
            except Exception as exc:  # noqa: BLE001 - reported in the page; the server keeps serving
                if self._queued(run):
                    self.remove(run.ident)
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
                await session.apply(partial(self._on_indicators, run.ident, megno, mlce))

    def _hand_out(self, run: OrbitRun, work: OrbitRun, rows: np.ndarray, notice: str | None) -> None:
        """(On the loop) the block computed on ``work`` becomes ``run``'s, and goes to the page."""
        if not self._queued(run) or work.settings is not run.settings:   # removed or recounted meanwhile
            return
        run.__dict__.update(work.__dict__)
        if run.finished:
            self.remove(run.ident)
            self._ended.append(run)
        if notice is not None:
            self._on_notice(run.ident, notice)
        if len(rows) or run.finished:   # (a block cut at its steps before a crossing: nothing to show)
            self._on_block(run.ident, rows, run.done, run.status)
