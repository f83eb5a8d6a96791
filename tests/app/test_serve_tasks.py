"""The task helper of `explorer serve` (app/serve/tasks.py): a newer job supersedes the older one
(its budget cancelled, what it hands in afterwards dropped), results reach the page only through
the session's loop, and a timer keeps only its earliest due call.  No browser, no compiled code."""
from __future__ import annotations

import threading
import time

from explorer.analysis.budget import Budget
from explorer.app.serve import tasks
from explorer.app.serve.tasks import SessionLoop


def _until(cond, timeout=60.0):
    t0 = time.monotonic()
    while not cond():
        assert time.monotonic() - t0 < timeout, "timed out"
        time.sleep(0.005)


def test_a_newer_job_cancels_the_older_ones_budget_and_only_its_results_reach_the_loop():
    loop = SessionLoop()                  # (no document: what jobs hand in waits for poll)
    task = loop.task("t")
    shown: list = []
    started = threading.Event()

    def old(job):
        started.set()
        _until(lambda: job.budget.stopped)          # a long search, stopped by its switch
        job.post(lambda: shown.append("old"))       # handed in after it was superseded: dropped

    first = task.submit(old, budget=Budget())
    started.wait(60)
    second = task.submit(lambda job: job.post(lambda: shown.append("new")), budget=Budget())
    assert first.budget.cancelled and not first.current and second.current
    _until(lambda: (loop.poll() or True) and shown == ["new"])
    task.cancel()                                   # a cancel supersedes too: nothing current
    assert not second.current
    loop.close(wait=True)
    assert task.join(0)                             # no job of the task queued or running


def test_a_result_handed_in_before_a_cancel_is_dropped_on_the_loop():
    loop = SessionLoop()
    task = loop.task("t")
    shown: list = []
    posted = threading.Event()

    def work(job):
        job.post(lambda: shown.append(1))
        posted.set()

    job = task.submit(work)
    posted.wait(60)                                 # handed in, not yet on the page ...
    task.cancel()                                   # ... when the page cancels (on its loop)
    assert loop.poll() and shown == [] and not job.current
    loop.close()


def test_a_timer_keeps_its_earliest_due_call_only():
    loop = SessionLoop()
    fired: list = []
    timer = loop.timer(lambda: fired.append(time.monotonic()))
    now = time.monotonic()
    timer.at(now + 10.0)
    timer.at(now + 20.0)                            # later than the one due: nothing changes
    assert timer.due == now + 10.0
    timer.at(now - 1.0, reentrant=False)            # due now, on the next tick (a notebook: the next poll)
    # (a notebook's poll runs both calls handed in; the superseded one, due in 10 s, does nothing)
    assert fired == [] and loop.poll() and len(fired) == 1 and not timer.pending
    assert not loop.poll() and len(fired) == 1
    timer.at(now - 1.0)                             # due and reentrant: at once
    assert len(fired) == 2


class _SetOrderDoc:
    """A document whose next-tick callbacks start in an order of their own, as Bokeh starts those
    added before a session is attached (kept in a set): here the reverse of the order added."""

    def __init__(self):
        self.callbacks: list = []

    def add_next_tick_callback(self, f):
        self.callbacks.append(f)

    def run(self):
        todo, self.callbacks = self.callbacks[::-1], []
        for f in todo:
            f()


class _LosingDoc(_SetOrderDoc):
    """A document that refuses its first next-tick callback (torn down for a moment)."""

    def __init__(self):
        super().__init__()
        self.refused = 0

    def add_next_tick_callback(self, f):
        if not self.refused:
            self.refused += 1
            raise RuntimeError("no callbacks now")
        super().add_next_tick_callback(f)


def test_an_action_whose_callback_was_lost_is_not_stranded_behind_the_later_ones():
    doc = _LosingDoc()
    loop = SessionLoop(doc)
    shown: list = []
    for k in range(3):
        loop.post(lambda k=k: shown.append(k))
    while doc.callbacks:
        doc.run()
    assert doc.refused == 1 and shown == [0, 1, 2]


class _SilentlyLosingDoc(_SetOrderDoc):
    """A document that takes every callback and, while ``lose``, keeps some apart without running
    them and without an error (as Bokeh lost callbacks in the browser loops: docs/tests.md); its
    one periodic callback is the loop's watch."""

    def __init__(self):
        super().__init__()
        self.lose, self.lost, self.timeouts, self.periodic = False, [], [], []

    def add_next_tick_callback(self, f):
        (self.lost if self.lose else self.callbacks).append(f)

    def add_timeout_callback(self, f, ms):
        (self.lost if self.lose else self.timeouts).append(f)

    def add_periodic_callback(self, f, ms):
        self.periodic.append(f)
        return f

    def remove_periodic_callback(self, f):
        self.periodic.remove(f)


def test_a_callback_that_bokeh_silently_lost_is_made_up_by_the_watch_once_and_not_before(monkeypatch):
    monkeypatch.setattr(tasks, "LOST_AFTER_SECONDS", 0.05)
    doc = _SilentlyLosingDoc()
    loop = SessionLoop(doc)
    (watch,) = doc.periodic
    shown: list = []
    doc.lose = True
    loop.post(lambda: shown.append("a"))            # its next-tick callback lost ...
    doc.lose = False
    loop.post(lambda: shown.append("b"))            # ... so one callback runs "a", and "b" waits
    while doc.callbacks:
        doc.run()
    assert shown == ["a"]
    watch()                                         # not lost yet: a callback ran just now
    assert not doc.callbacks and loop.made_up == 0
    time.sleep(0.1)
    watch()                                         # none ran for LOST_AFTER_SECONDS: made up
    while doc.callbacks:
        doc.run()
    assert shown == ["a", "b"] and loop.made_up == 1

    fired: list = []
    timer = loop.timer(lambda: fired.append(1))
    doc.lose = True
    timer.at(time.monotonic() + 0.01)              # its timeout callback lost
    doc.lose = False
    watch()
    assert fired == []                              # not yet due
    time.sleep(0.1)
    watch()
    assert fired == [1] and not timer.pending and loop.made_up == 2
    for f in doc.lost:                              # the lost callbacks come after all: stale, nothing twice
        f()
    assert fired == [1] and shown == ["a", "b"]
    timer.at(time.monotonic() + 0.01)               # a timer whose callback runs is left alone
    time.sleep(0.1)
    doc.timeouts.pop()()
    watch()
    assert fired == [1, 1] and loop.made_up == 2
    loop.close()
    assert doc.periodic == []                       # the watch ends with the session


def test_actions_reach_the_loop_in_the_order_they_were_handed_in_whatever_order_bokeh_starts_callbacks():
    doc = _SetOrderDoc()
    loop = SessionLoop(doc)
    task = loop.task("t")
    shown: list = []

    def blocks(job):
        for k in range(5):                           # an orbit's blocks, the first one first
            job.post(lambda k=k: shown.append(k))

    task.submit(blocks)
    _until(lambda: len(doc.callbacks) == 5)
    doc.run()
    assert shown == [0, 1, 2, 3, 4]
    loop.close(wait=True)
