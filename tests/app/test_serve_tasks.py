"""A page's background work on asyncio (app/serve/tasks.py): a newer task of a kind cancels the
older one and its budget, its numba work runs in the shared executor inside that budget, results
apply with the document locked, a timer keeps only its earliest due call, and closing the session
ends everything.  No browser, no compiled code."""
from __future__ import annotations

import asyncio
import threading
import time

from page_loop import poll, settle

from explorer.analysis import budget as budget_mod
from explorer.analysis.budget import Budget
from explorer.app.serve.tasks import Session, Timer


def _until_stopped(started: threading.Event):
    started.set()
    b = budget_mod.current()
    while not b.stopped:                        # a long search, stopped by its switch
        time.sleep(0.001)
    return "old"


def test_a_newer_job_cancels_the_older_ones_budget_and_only_its_results_reach_the_loop():
    session = Session()                         # (no running loop: a loop of its own, run by settle)
    shown: list = []
    started = threading.Event()

    async def work(fn, *args):
        value = await session.run(fn, *args)
        await session.apply(lambda: shown.append(value))

    first = Budget()
    session.start("t", work(_until_stopped, started), budget=first)
    while not started.is_set():
        poll(session)
    session.start("t", work(lambda: "new"), budget=Budget())
    assert first.cancelled                      # its compiled loops stop at their next step
    settle(session, 60)
    assert shown == ["new"] and not session.busy()
    session.close()


def test_a_result_handed_in_before_a_cancel_is_dropped_on_the_loop():
    session = Session()
    shown: list = []
    started, release, finished = threading.Event(), threading.Event(), threading.Event()

    def work():
        started.set()
        release.wait(60)
        finished.set()
        return 1

    async def task():
        value = await session.run(work)
        await session.apply(lambda: shown.append(value))

    session.start("t", task())
    while not started.is_set():
        poll(session)
    release.set()
    finished.wait(60)                           # computed, not yet on the page ...
    session.cancel("t")                         # ... when the page cancels (on its loop)
    settle(session, 60)
    assert shown == [] and not session.busy()
    session.close()


def test_a_tasks_work_runs_in_the_shared_executor_inside_the_tasks_budget():
    session = Session()
    seen: list = []
    b = Budget(max_steps=7)

    async def work():
        seen.append(await session.run(lambda: (threading.current_thread().name, budget_mod.current())))

    session.start("t", work(), budget=b)
    settle(session, 60)
    (name, inside), = seen
    assert name.startswith("explorer-serve") and inside is b
    session.close()


def test_an_exception_of_a_task_goes_to_its_error_callback_on_the_loop():
    session = Session()
    errors: list = []

    async def fails():
        await session.run(lambda: 1 / 0)

    session.start("t", fails(), on_error=errors.append)
    settle(session, 60)
    assert len(errors) == 1 and isinstance(errors[0], ZeroDivisionError)
    session.close()


class _Context:
    """A session context whose ``with_locked_document`` records that the document was locked and, as
    Bokeh's, awaits the sending of the changes after ``func``; ``calls``: the calls that ended so."""

    def __init__(self):
        self.locked = False
        self.calls = 0

    async def with_locked_document(self, func):
        self.locked = True
        try:
            await func(None)
        finally:
            self.locked = False
        await asyncio.sleep(0)                  # (Bokeh: its pending writes)
        self.calls += 1


class _Doc:
    def __init__(self):
        self.session_context = _Context()


def test_actions_reach_the_loop_in_the_order_they_were_handed_in_whatever_order_bokeh_starts_callbacks():
    """Results apply in the order a task computes them, each with the document locked (no Bokeh
    callback carries them: their order is the coroutine's)."""
    doc = _Doc()
    session = Session(doc)
    shown: list = []

    async def blocks():
        for k in range(5):                       # an orbit's blocks, the first one first
            await session.run(time.sleep, 0.001 * (5 - k))
            await session.apply(lambda k=k: shown.append((k, doc.session_context.locked)))

    session.start("t", blocks())
    settle(session, 60)
    assert shown == [(k, True) for k in range(5)] and doc.session_context.calls == 5
    session.close()


def test_a_timer_keeps_its_earliest_due_call_only():
    session = Session()
    fired: list = []
    timer = Timer(session, lambda: fired.append(time.monotonic()))
    now = time.monotonic()
    timer.at(now + 10.0)
    timer.at(now + 20.0)                        # later than the one due: nothing changes
    assert timer.due == now + 10.0
    timer.at(now - 1.0)                         # due now: it replaces the one in 10 s
    settle(session, 60)
    assert len(fired) == 1 and timer.due is None and not session.busy()
    session.close()


def test_a_timers_action_that_asks_for_its_next_call_or_cancels_it_still_has_its_changes_sent():
    doc = _Doc()
    session = Session(doc)
    fired: list = []

    def action():
        fired.append(time.monotonic())
        if len(fired) == 1:
            timer.at(time.monotonic())          # the next call, asked for by the action
        else:
            timer.cancel()

    timer = Timer(session, action)
    timer.at(time.monotonic())
    settle(session, 60)
    assert len(fired) == 2 and doc.session_context.calls == 2 and timer.due is None
    session.close()


def test_closing_the_session_cancels_every_task_budget_and_timer():
    session = Session()
    b, started = Budget(), threading.Event()

    async def work():
        await session.run(_until_stopped, started)

    session.start("t", work(), budget=b)
    timer = Timer(session, lambda: None)
    timer.at(time.monotonic() + 60.0)
    while not started.is_set():
        poll(session)
    session.close()
    assert b.cancelled and timer.due is None and session.loop.is_closed()
    session.start("t", work())
    assert not session.busy()                   # nothing starts on a closed session

