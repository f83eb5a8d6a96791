"""How a page's work runs in the background and comes back: the session's loop
(:class:`SessionLoop`), its latest-only tasks (:class:`LatestTask`) and timers (:class:`Timer`).

Every background job of a page (orbits, raster, searches, readout, manifolds, exports) is a
:class:`LatestTask` job on a thread shared by every session (:class:`_Threads`).  A newer submit or
a cancel supersedes the older job: its :class:`~explorer.analysis.budget.Budget` is cancelled and
what it still hands in (:meth:`Job.post`) is dropped.  Results reach the page on the session's
loop (Bokeh's next-tick and timeout callbacks, the document's lock held) in the order handed in;
in a notebook they wait for :meth:`SessionLoop.poll`.  A served session's watch makes up a Bokeh
callback that never ran (:meth:`SessionLoop._look_for_lost`; docs/commands/serve.md, "Lost
callbacks").
"""
from __future__ import annotations

import collections
import contextlib
import logging
import threading
import time
from functools import partial

from explorer.analysis.budget import Budget, BudgetExceeded

#: a Bokeh callback not run this long after it was due is taken as lost (s): the watch runs after
#: every callback ready before it (Bokeh's lock serves its waiters in order)
LOST_AFTER_SECONDS = 2.0
#: how often a served session looks for lost callbacks (ms; a Bokeh periodic callback)
WATCH_MS = 1000

_log = logging.getLogger("explorer.serve")


class _Threads:
    """The background threads of every session, shared: a call takes an idle thread or starts one,
    and a thread idle for IDLE_SECONDS ends.  So a server holds as many threads as calls run at
    once (a session's orbits, its raster, a search), never one per kind of task and session.
    Daemon threads (not ``ThreadPoolExecutor``'s, which the interpreter joins at exit: a search no
    one waits for would hold the exit up)."""

    def __init__(self):
        self._cond = threading.Condition()
        self._calls: collections.deque = collections.deque()
        self._idle = 0

    def submit(self, fn) -> None:
        with self._cond:
            self._calls.append(fn)
            if self._idle >= len(self._calls):
                self._cond.notify()
                return
        threading.Thread(target=self._loop, name="explorer-serve-worker", daemon=True).start()

    def _loop(self) -> None:
        while True:
            with self._cond:
                self._idle += 1
                while not self._calls:
                    if not self._cond.wait(IDLE_SECONDS) and not self._calls:
                        self._idle -= 1
                        return
                fn = self._calls.popleft()
                self._idle -= 1
            fn()


#: a shared background thread with nothing to run this long ends (s)
IDLE_SECONDS = 10.0
_threads = _Threads()


class SessionLoop:
    """A session's event loop: ``doc``, its Bokeh document (None: a notebook, :meth:`poll`)."""

    def __init__(self, doc=None):
        self.doc = doc
        self.closed = False
        self._inbox: list = []
        self._scheduled = 0             # next-tick callbacks added and not yet run
        self._ran_at = time.monotonic()  # when the last of them ran (or the first was added)
        self._lock = threading.Lock()
        self._tasks: list[LatestTask] = []
        self._timers: list[Timer] = []
        self.made_up = 0                # lost callbacks made up by the watch (_watch)
        self._watch = None
        if doc is not None:
            try:
                self._watch = doc.add_periodic_callback(self._look_for_lost, WATCH_MS)
            except (AttributeError, RuntimeError, ValueError):
                pass                    # (a document torn down already)

    def post(self, action) -> None:
        """From any thread: run ``action()`` on the loop after every action posted before it
        (dropped once the session is closed).  The order is kept in the inbox, one action per
        next-tick callback: Bokeh starts the callbacks added before a session is attached in a
        set's order."""
        if self.closed:
            return
        with self._lock:
            self._inbox.append(action)
        if self.doc is not None:        # (a notebook: poll runs them)
            self._schedule()

    def _schedule(self) -> None:
        """One next-tick callback more, unless as many wait as actions (a refused one is made up
        by the next)."""
        with self._lock:
            if self._scheduled >= len(self._inbox):
                return
            if not self._scheduled:
                self._ran_at = time.monotonic()
            self._scheduled += 1
        try:
            self.doc.add_next_tick_callback(lambda: self._run_oldest())
        except (AttributeError, RuntimeError, ValueError):
            with self._lock:            # (destroyed meanwhile: Bokeh tore the document's callbacks down)
                self._scheduled -= 1

    @contextlib.contextmanager
    def bokeh_sends(self):
        """On the loop: the changes made within go to the browser through Bokeh's own dispatch
        (the document held, ``Document.hold("collect")``, until the block ends), not Panel's
        writer, which may leave a message queued for a busy socket unsent (panel 1.9;
        tests/app/test_serve.py, a Panel that loses its own writes).  Not for a block that
        replaces a source's data and then streams to it (the rows would arrive twice).  Without
        a document, or within a hold, the block just runs."""
        doc = self.doc
        if doc is None or doc.callbacks.hold_value is not None:
            yield
            return
        doc.hold("collect")
        try:
            yield
        finally:
            doc.unhold()

    def _run_oldest(self) -> None:
        with self._lock:
            self._scheduled = max(self._scheduled - 1, 0)
            self._ran_at = time.monotonic()
            action = self._inbox.pop(0) if self._inbox else None
        if action is not None:
            action()
        if self.doc is not None and not self.closed:
            self._schedule()

    def soon(self, action) -> None:
        """From a widget watcher (Panel calls them outside the document's lock): ``action()`` on the
        loop with the lock; at once when no server owns the document."""
        if self.doc is None:
            action()
        else:
            self.post(action)

    def _look_for_lost(self) -> None:
        """The watch (every WATCH_MS): a next-tick callback waiting while none has run for
        LOST_AFTER_SECONDS, or a timer that long past due, was lost and is made up now, with a
        warning in the server's log."""
        if self.closed:
            return
        now = time.monotonic()
        with self._lock:
            stranded = bool(self._inbox) and self._scheduled > 0 and now - self._ran_at > LOST_AFTER_SECONDS
            if stranded:
                lost, self._scheduled = self._scheduled, 0
        if stranded:
            self.made_up += 1
            _log.warning("explorer serve: %d next-tick callback(s) lost; made up", lost)
            self._schedule()
        for timer in list(self._timers):
            late = timer.make_up_if_lost(now)
            if late is not None:
                self.made_up += 1
                _log.warning("explorer serve: a timer's callback lost (%.1f s past due); made up", late)

    def poll(self) -> bool:
        """Run what was handed in since the last call (a notebook's periodic callback); returns
        whether there was anything."""
        with self._lock:
            actions, self._inbox = self._inbox, []
        for action in actions:
            action()
        return bool(actions)

    def task(self, name: str) -> LatestTask:
        t = LatestTask(self, name)
        self._tasks.append(t)
        return t

    def timer(self, action) -> Timer:
        t = Timer(self, action)
        self._timers.append(t)
        return t

    def close(self, wait: bool = False) -> None:
        """The session is gone: every task cancelled and its thread ended (``wait``: joined)."""
        self.closed = True
        if self._watch is not None:
            try:
                self.doc.remove_periodic_callback(self._watch)
            except (AttributeError, RuntimeError, ValueError):
                pass                    # (Bokeh removed it with the session)
            self._watch = None
        for t in self._tasks:
            t.stop(wait)


class Job:
    """What a running job sees of its task: its ``generation`` and ``budget``."""

    def __init__(self, task: LatestTask, generation: int, budget: Budget | None):
        self.task, self.generation, self.budget = task, generation, budget

    @property
    def current(self) -> bool:
        """No newer job (nor a cancel) superseded this one."""
        return self.generation == self.task.generation

    def post(self, action) -> None:
        """``action()`` on the loop, if this job is still the current one when it gets there."""
        if self.current:
            self.task.loop.post(lambda: action() if self.current else None)


class LatestTask:
    """One kind of background job of a session: the latest request only (module docstring).  Its
    jobs run one after the other, each on a shared thread (:class:`_Threads`)."""

    def __init__(self, loop: SessionLoop, name: str):
        self.loop, self.name = loop, name
        self.generation = 0
        self._lock = threading.Lock()
        self._budget: Budget | None = None
        self._queue: collections.deque = collections.deque()
        self._idle = threading.Event()        # no job queued or running
        self._idle.set()
        self._stopped = False

    def submit(self, work, *args, budget: Budget | None = None, on_error=None) -> Job:
        """Supersede the current job and run ``work(job, *args)`` in the background, inside ``budget``
        if given.  An exception of a current job goes to ``on_error(exc)`` on the loop; a budget
        that ran out or was cancelled ends the job quietly."""
        with self._lock:
            self._supersede()
            self._budget = budget
            return self._start(work, args, budget, on_error)

    def run(self, work, *args, on_error=None) -> Job:
        """Run ``work(job, *args)`` as a job of the current generation, after the jobs already
        queued; a cancel stops them all."""
        with self._lock:
            return self._start(work, args, None, on_error)

    def _start(self, work, args, budget, on_error) -> Job:
        job = Job(self, self.generation, budget)
        if not self._stopped:
            self._queue.append((job, work, args, on_error))
            if self._idle.is_set():
                self._idle.clear()
                _threads.submit(self._drain)
        return job

    def _drain(self) -> None:
        while True:
            with self._lock:
                if not self._queue:
                    self._idle.set()
                    return
                item = self._queue.popleft()
            self._run(*item)

    def _supersede(self) -> None:
        self.generation += 1
        if self._budget is not None:
            self._budget.cancel()
            self._budget = None

    def cancel(self) -> int:
        """No current job any more (the running one stops); returns the new generation."""
        with self._lock:
            self._supersede()
            return self.generation

    def stop(self, wait: bool = False) -> None:
        """No job any more (the queued ones return at once); ``wait``: until the running one has."""
        with self._lock:
            self._stopped = True
            self._supersede()
        if wait:
            self.join()

    def join(self, timeout: float | None = None) -> bool:
        """Wait until no job of this task is queued or running; returns whether none is."""
        return self._idle.wait(timeout)

    @staticmethod
    def _run(job: Job, work, args, on_error) -> None:
        if not job.current:
            return                      # superseded while it waited
        try:
            if job.budget is None:
                work(job, *args)
            else:
                with job.budget:
                    work(job, *args)
        except BudgetExceeded:
            return
        except Exception as exc:  # noqa: BLE001 - reported in the page; the server keeps serving
            if on_error is not None:
                job.post(partial(on_error, exc))


class Timer:
    """``action()`` on the loop at a time (:meth:`at`), at most one due: an earlier request
    supersedes a later one, a later one leaves an earlier one be."""

    def __init__(self, loop: SessionLoop, action):
        self.loop, self.action = loop, action
        self.due: float | None = None         # (monotonic) when the pending call runs
        self.generation = 0
        self._bokeh_timeout = False           # the pending call is a Bokeh timeout callback

    @property
    def pending(self) -> bool:
        return self.due is not None

    def at(self, when: float, reentrant: bool = True) -> None:
        """On the loop: run the action at ``when`` (time.monotonic): now if it is due and
        ``reentrant``, else at the next tick once it is due (in a notebook: at the next poll)."""
        if self.due is not None and self.due <= when:
            return
        self.generation += 1
        g, self.due = self.generation, when
        wait = when - time.monotonic()
        doc = self.loop.doc
        self._bokeh_timeout = False
        if wait < 0.001 and reentrant:
            self._fire(g)
        elif doc is None or wait < 0.001:
            self.loop.post(lambda: self._fire(g))     # (the loop's watch covers a post: SessionLoop)
        else:
            self._bokeh_timeout = True
            doc.add_timeout_callback(lambda: self._fire(g), max(int(1000 * wait) + 1, 1))

    def make_up_if_lost(self, now: float) -> float | None:
        """On the loop (SessionLoop's watch): if the pending Bokeh timeout callback is more than
        LOST_AFTER_SECONDS past due, it was lost: run the action now and return how late it was
        (the lost callback, should it come after all, is stale); else None."""
        if self.due is None or not self._bokeh_timeout or now - self.due <= LOST_AFTER_SECONDS:
            return None
        late = now - self.due
        self.generation += 1
        self._fire(self.generation)
        return late

    def cancel(self) -> None:
        self.generation += 1
        self.due = None

    def _fire(self, g: int) -> None:
        if g == self.generation:
            self.due = None
            self.action()
