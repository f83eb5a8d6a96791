"""A page's background work on asyncio (docs/architecture.md, "The page"): :class:`Session` runs each kind of
work as one latest-wins task on the session's loop, its numba work in the shared :data:`EXECUTOR`
(``Session.run``: the kernels release the GIL), its results applied with the document locked (``Session.apply``).
"""
from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
from concurrent.futures import ThreadPoolExecutor
from functools import partial

from explorer.analysis.budget import Budget, BudgetExceeded

#: the threads of every session's numba work, shared: a server holds as many as calls run at once
WORKERS = 32
EXECUTOR = ThreadPoolExecutor(max_workers=WORKERS, thread_name_prefix="explorer-serve")

_log = logging.getLogger("explorer.serve")


def failure(exc: BaseException) -> str:
    """A failure as the page says it: the exception's type and its message on one line."""
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"


def _in_budget(budget: Budget | None, fn, *args):
    with contextlib.nullcontext() if budget is None else budget:
        return fn(*args)


class Session:
    """The event loop of a page: a server's (``doc``, the page's Bokeh document, in a server session), else
    ``loop`` (a notebook's kernel's), else a new one that its caller runs (without a document, results apply
    at once)."""

    def __init__(self, doc=None, loop=None):
        self.doc, self.closed, self.loop = doc, False, loop
        if loop is None and getattr(doc, "session_context", None) is not None:
            with contextlib.suppress(RuntimeError):
                self.loop = asyncio.get_running_loop()
        if self.loop is None:
            self.loop = asyncio.new_event_loop()
        self._tasks: dict[object, tuple[asyncio.Task, Budget | None]] = {}

    def start(self, name, coro, budget: Budget | None = None, on_error=None) -> None:
        """Task ``name`` (a kind of work, or a :class:`Timer`) anew, latest wins: ``coro`` replaces the running
        one, its :meth:`run` calls in ``budget``; an exception goes to ``on_error(exc)`` (a spent budget: none).
        On a closed session nothing starts."""
        self.cancel(name)
        if self.closed:
            coro.close()
            return
        task = self.loop.create_task(coro)
        task.add_done_callback(partial(self._ended, name, on_error))
        self._tasks[name] = (task, budget)

    def _ended(self, name, on_error, task) -> None:
        if self._tasks.get(name, (None,))[0] is task:
            del self._tasks[name]
        exc = None if task.cancelled() else task.exception()
        if exc is None or isinstance(exc, BudgetExceeded):
            return
        if on_error is None:
            _log.error("explorer serve: a page's work failed", exc_info=exc)
        else:
            self.soon(partial(on_error, exc))

    def running(self, name) -> bool:
        t = self._tasks.get(name)
        return t is not None and not t[0].done()

    def release(self, name) -> None:
        """Task ``name`` is no longer the session's: it runs on, and a new task ``name`` does not cancel it."""
        self._tasks.pop(name, None)

    def cancel(self, name) -> None:
        """Task ``name`` stops (at its next await; its budget's compiled loops at their next step)."""
        task, budget = self._tasks.pop(name, (None, None))
        if task is not None:
            task.cancel()
        if budget is not None:
            budget.cancel()

    async def run(self, fn, *args):
        """``fn(*args)`` in :data:`EXECUTOR`, inside the budget of the task that awaits it."""
        me = asyncio.current_task()
        budget = next((b for t, b in self._tasks.values() if t is me), None)
        return await self.loop.run_in_executor(EXECUTOR, partial(_in_budget, budget, fn, *args))

    async def apply(self, fn) -> None:
        """``fn()`` on the loop with the document locked (Bokeh's ``with_locked_document``)."""
        context = getattr(self.doc, "session_context", None)
        if context is None:
            fn()
        else:
            async def locked(doc):
                import panel as pn

                pn.state.curdoc = doc       # (as in Bokeh's callbacks: Panel writes its widgets' changes at once)
                fn()
            await context.with_locked_document(locked)

    def soon(self, fn) -> None:
        """From a widget watcher (Panel calls them outside the document's lock): ``fn()`` on the loop with the
        lock; at once without a document."""
        if self.doc is None:
            fn()
        else:
            self.start(object(), self.apply(fn))        # (a task of its own: none replaces it)

    def busy(self) -> bool:
        """A task, a timer or a watcher call is pending."""
        return any(not t.done() for t, _b in self._tasks.values())

    def close(self) -> None:
        """The session is gone: every task and timer cancelled (a loop of its own, not running: closed)."""
        self.closed = True
        for name in list(self._tasks):
            self.cancel(name)
        if not (self.loop.is_running() or self.loop.is_closed()):
            # its cancelled tasks end first, in a thread of their own (this one may have a loop marked running)
            end = threading.Thread(target=self.loop.run_until_complete, args=(asyncio.sleep(0),))
            end.start()
            end.join()
            self.loop.close()


class Timer:
    """``action()`` with the document locked at a loop time (:meth:`at`; the loop's clock is time.monotonic), a
    task of its session: an earlier request supersedes a later one, a later one leaves an earlier one be."""

    def __init__(self, session: Session, action):
        self.session, self.action = session, action
        self._due: float | None = None

    @property
    def due(self) -> float | None:
        """When the pending call is due (None: no call is pending)."""
        return self._due if self.session.running(self) else None

    def at(self, when: float) -> None:
        if self.due is None or when < self.due:
            self._due = when
            self.session.start(self, self._fire(when))

    def cancel(self) -> None:
        self.session.cancel(self)

    async def _fire(self, when: float) -> None:
        await asyncio.sleep(when - self.session.loop.time())
        await self.session.apply(self._act)

    def _act(self) -> None:
        # due no more: the action may cancel the timer or ask for its next call, and this call still ends
        # (Bokeh sends the action's changes after it returns)
        self.session.release(self)
        self.action()
