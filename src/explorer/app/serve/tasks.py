"""The one way a page's work runs in the background and comes back: the session's loop
(:class:`SessionLoop`) and its latest-only tasks (:class:`LatestTask`) and timers (:class:`Timer`).

Every background job of a page is a :class:`LatestTask`: the orbits' worker loop, the MEGNO
raster, the overlay searches, a pick's readout, a saddle's manifolds, the figure and store
exports.  :meth:`LatestTask.submit` runs ``work(job, *args)`` on the task's executor (one daemon thread,
made at the first submit); a newer submit (or :meth:`LatestTask.cancel`) supersedes the older job:
its :class:`~explorer.analysis.budget.Budget` is cancelled, so its compiled loops stop within a
step, and whatever it still hands in (:meth:`Job.post`) is dropped on the loop.  Results reach the
page only on the session's event loop, through Bokeh's ``Document.add_next_tick_callback`` and
``add_timeout_callback`` (the document's lock held, as Panel's own callbacks run), in the order
they were handed in (:meth:`SessionLoop.post`); in a notebook,
where no server owns the document, they wait in an inbox for :meth:`SessionLoop.poll`.  The
generation counters of every job and timer are here, and only here.
"""
from __future__ import annotations

import queue
import threading
import time
from functools import partial

from explorer.analysis.budget import Budget, BudgetExceeded


class Executor:
    """One daemon thread that runs the calls :meth:`submit` hands it, in order.  (Not a
    ``concurrent.futures.ThreadPoolExecutor``: the interpreter joins its threads at exit, so a
    search no one waits for any more would hold the exit up.)"""

    def __init__(self, name: str):
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self.thread = threading.Thread(target=self._loop, name=name, daemon=True)
        self.thread.start()

    def submit(self, fn, *args) -> None:
        self._queue.put((fn, args))

    def shutdown(self, wait: bool = False) -> None:
        """End the thread after the calls already handed in (``wait``: join it)."""
        self._queue.put(None)
        if wait and threading.current_thread() is not self.thread:
            self.thread.join()

    def _loop(self) -> None:
        while (item := self._queue.get()) is not None:
            fn, args = item
            fn(*args)


class SessionLoop:
    """A session's event loop: ``doc``, its Bokeh document (None: a notebook, :meth:`poll`)."""

    def __init__(self, doc=None):
        self.doc = doc
        self.closed = False
        self._inbox: list = []
        self._scheduled = 0             # next-tick callbacks added and not yet run
        self._lock = threading.Lock()
        self._tasks: list[LatestTask] = []

    def post(self, action) -> None:
        """From any thread: run ``action()`` on the loop (dropped once the session is closed), after
        every action posted before it.  The order is kept here, in the inbox: each next-tick
        callback runs the oldest action waiting, one per callback (one per tick, as before).
        Bokeh's own order is not enough: the callbacks added before the session is attached (the
        blocks of a link's orbits, computed while the page is being built) are kept in a set and
        started in its order, and an orbit's first block reached the page after its last one
        (tests/app/test_serve_orbit_list.py, a hidden orbit's reload)."""
        if self.closed:
            return
        with self._lock:
            self._inbox.append(action)
        if self.doc is not None:        # (a notebook: poll runs them)
            self._schedule()

    def _schedule(self) -> None:
        """One next-tick callback more, unless as many are waiting as actions: a callback lost
        (a document torn down meanwhile, or actions handed in before the document was there)
        is made up by the next one, so no action is ever stranded behind the others.  Each
        callback is a callable of its own (Bokeh files callbacks by their callable)."""
        with self._lock:
            if self._scheduled >= len(self._inbox):
                return
            self._scheduled += 1
        try:
            self.doc.add_next_tick_callback(lambda: self._run_oldest())
        except (AttributeError, RuntimeError, ValueError):
            with self._lock:            # (destroyed meanwhile: Bokeh tore the document's callbacks down)
                self._scheduled -= 1

    def _run_oldest(self) -> None:
        with self._lock:
            self._scheduled = max(self._scheduled - 1, 0)
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

    def poll(self) -> bool:
        """Run what was handed in since the last call (a notebook's periodic callback); returns
        whether there was anything."""
        with self._lock:
            actions, self._inbox = self._inbox, []
        for action in actions:
            action()
        return bool(actions)

    def pending(self) -> int:
        """How many handed-in actions wait for :meth:`poll`."""
        with self._lock:
            return len(self._inbox)

    def task(self, name: str) -> LatestTask:
        t = LatestTask(self, name)
        self._tasks.append(t)
        return t

    def timer(self, action) -> Timer:
        return Timer(self, action)

    def close(self, wait: bool = False) -> None:
        """The session is gone: every task cancelled and its thread ended (``wait``: joined)."""
        self.closed = True
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
    """One kind of background job of a session: the latest request only (module docstring)."""

    def __init__(self, loop: SessionLoop, name: str):
        self.loop, self.name = loop, name
        self.generation = 0
        self._lock = threading.Lock()
        self._budget: Budget | None = None
        self._executor: Executor | None = None
        self._stopped = False

    def submit(self, work, *args, budget: Budget | None = None, on_error=None) -> Job:
        """Supersede the current job and run ``work(job, *args)`` on the executor, inside ``budget``
        if given.  An exception of a current job goes to ``on_error(exc)`` on the loop; a budget
        that ran out or was cancelled ends the job quietly."""
        with self._lock:
            self._supersede()
            self._budget = budget
            return self._start(work, args, budget, on_error)

    def run(self, work, *args, on_error=None) -> Job:
        """Run ``work(job, *args)`` on the executor as a job of the current generation: it goes with
        the jobs already running (after them: one thread), and a cancel stops them all."""
        with self._lock:
            return self._start(work, args, None, on_error)

    def _start(self, work, args, budget, on_error) -> Job:
        job = Job(self, self.generation, budget)
        if not self._stopped:
            if self._executor is None:
                self._executor = Executor(f"explorer-serve-{self.name}")
            self._executor.submit(self._run, job, work, args, on_error)
        return job

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
        with self._lock:
            self._stopped = True
            self._supersede()
            executor = self._executor
        if executor is not None:
            executor.shutdown(wait)           # (the jobs still queued are superseded: they return at once)

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
        if wait < 0.001 and reentrant:
            self._fire(g)
        elif doc is None or wait < 0.001:
            self.loop.post(lambda: self._fire(g))
        else:
            doc.add_timeout_callback(lambda: self._fire(g), max(int(1000 * wait) + 1, 1))

    def cancel(self) -> None:
        self.generation += 1
        self.due = None

    def _fire(self, g: int) -> None:
        if g == self.generation:
            self.due = None
            self.action()
