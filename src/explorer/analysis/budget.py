"""A wall-clock budget and stop switch for the section-map analyses of one thread
(docs/commands/serve.md, Budgets): inside ``with Budget(...)``, every
:class:`~explorer.analysis.section_map.SectionMap` passes the switch to the compiled return, which
stops within one step, and raises :class:`BudgetExceeded`; outside a budget nothing changes.
"""
from __future__ import annotations

import heapq
import itertools
import math
import threading
import time

import numpy as np

from explorer.kernels.status import STATUS_CANCELLED

__all__ = ["Budget", "BudgetExceeded", "checkpoint", "current", "raise_if_cancelled", "step_cap", "stop_switch"]


class BudgetExceeded(RuntimeError):
    """The current :class:`Budget` ran out or was cancelled: the search stops here."""


class Budget:
    """``seconds`` of wall-clock time (None: no limit, only :meth:`cancel`) for what runs in the
    ``with`` block of the thread that enters it; ``max_steps``: at most this many steps per orbit in
    a crossing batch run inside it (None: the batch's own)."""

    def __init__(self, seconds: float | None = None, max_steps: int | None = None):
        self.seconds = None if seconds is None else float(seconds)
        self.max_steps = max_steps
        self.switch = np.zeros(1, np.int64)
        self.cancelled = False
        self._inner: list[Budget] = []
        self.started = math.nan

    def cancel(self) -> None:
        """Stop the search now (any thread): the compiled loop returns at its next step."""
        self.cancelled = True
        self._expire()

    def _expire(self) -> None:
        self.switch[0] = 1
        for b in list(self._inner):
            b._expire()

    @property
    def stopped(self) -> bool:
        """The switch is set (cancelled or out of time)."""
        return bool(self.switch[0])

    def check(self) -> None:
        """Raise :class:`BudgetExceeded` when the switch is set."""
        if self.switch[0]:
            raise BudgetExceeded(self.reason())

    def reason(self) -> str:
        if self.cancelled:
            return "cancelled: a newer request replaced it"
        if self.seconds is None:
            return "stopped by an outer budget"
        return f"stopped at its budget of {self.seconds:g} s"

    def __enter__(self) -> Budget:
        self.started = time.monotonic()
        if self.seconds is not None:
            _watchdog.add(self.started + self.seconds, self)
        outer = current()
        if outer is not None:
            outer._inner.append(self)
            if outer.stopped:
                self.switch[0] = 1
        _stack().append(self)
        return self

    def __exit__(self, *exc) -> None:
        _stack().remove(self)
        outer = current()
        if outer is not None and self in outer._inner:
            outer._inner.remove(self)
        _watchdog.drop(self)


class _Watchdog:

    def __init__(self):
        self._cond = threading.Condition()
        self._heap: list = []
        self._live: set = set()
        self._count = itertools.count()
        self._thread: threading.Thread | None = None

    def add(self, deadline: float, budget: Budget) -> None:
        with self._cond:
            self._live.add(budget)
            heapq.heappush(self._heap, (deadline, next(self._count), budget))
            if self._thread is None:
                self._thread = threading.Thread(target=self._loop, name="explorer-budget-watchdog", daemon=True)
                self._thread.start()
            self._cond.notify()

    def drop(self, budget: Budget) -> None:
        with self._cond:
            self._live.discard(budget)
            while self._heap and self._heap[0][2] not in self._live:
                heapq.heappop(self._heap)

    def _loop(self) -> None:
        with self._cond:
            while True:
                now = time.monotonic()
                while self._heap and self._heap[0][0] <= now:
                    _deadline, _n, b = heapq.heappop(self._heap)
                    if b in self._live:
                        b._expire()
                self._cond.wait(None if not self._heap else self._heap[0][0] - now)


_watchdog = _Watchdog()
_local = threading.local()
#: the switch of a thread with no budget (never set)
_NEVER = np.zeros(1, np.int64)


def _stack() -> list:
    s = getattr(_local, "stack", None)
    if s is None:
        s = _local.stack = []
    return s


def current() -> Budget | None:
    """The innermost budget entered in this thread, or None."""
    s = _stack()
    return s[-1] if s else None


def stop_switch() -> np.ndarray:
    """The stop switch the compiled loops of this thread read: the current budget's, else one never
    set.  Raises :class:`BudgetExceeded` when the current budget has already stopped."""
    b = current()
    if b is None:
        return _NEVER
    b.check()
    return b.switch


def checkpoint() -> None:
    """Raise :class:`BudgetExceeded` when this thread's current budget has stopped (called before
    a compiled batch that reads no switch, e.g. :func:`explorer.analysis.sections.crossings`)."""
    b = current()
    if b is not None:
        b.check()


def raise_if_cancelled(status) -> None:
    """Raise :class:`BudgetExceeded` when a compiled batch that read :func:`stop_switch` ended an orbit
    with STATUS_CANCELLED (its outputs are then incomplete)."""
    if np.any(np.asarray(status) == STATUS_CANCELLED):
        b = current()
        raise BudgetExceeded("stopped" if b is None else b.reason())


def step_cap(max_steps: int) -> int:
    """``max_steps`` bounded by the step caps of this thread's budgets."""
    for b in _stack():
        if b.max_steps is not None:
            max_steps = min(max_steps, int(b.max_steps))
    return max_steps
