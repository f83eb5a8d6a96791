"""Ctrl-C during a long run: stop at the next safe point, never in the middle of anything.

Python's own SIGINT handler raises ``KeyboardInterrupt`` at whatever bytecode runs next, which
after a long Numba call may be a weakref callback of numba's caches: the exception is then
printed as "Exception ignored in: <function WeakValueDictionary...>" and lost, and the run goes
on.  Inside :class:`deferred_interrupt` the first SIGINT only sets a flag; the run calls
:meth:`deferred_interrupt.check` between chunks, blocks and commits (each kernel call is bounded,
see :data:`explorer.analysis.sweep.CHUNK_ORBITS_THREADS`) and stops there with
:class:`Interrupted`, after the last commit is whole.  A second SIGINT raises at once.  Outside
the main thread, or when SIGINT is ignored (a background job), nothing is changed.
"""
from __future__ import annotations

import signal
import threading


class Interrupted(KeyboardInterrupt):
    """A run stopped by SIGINT at a safe point; the message says what is kept (the CLI prints it on
    one line and exits with status 130)."""


class deferred_interrupt:
    """Context manager: SIGINT sets a flag that :meth:`check` turns into :class:`Interrupted`."""

    def __init__(self):
        self.requested = False
        self._old = None

    def _handler(self, signum, frame):
        if self.requested:          # the second Ctrl-C: the user insists
            raise Interrupted("stopped at once by a second SIGINT")
        self.requested = True

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            old = signal.getsignal(signal.SIGINT)
            if old is not signal.SIG_IGN:
                self._old = old
                signal.signal(signal.SIGINT, self._handler)
        return self

    def __exit__(self, *exc):
        if self._old is not None:
            signal.signal(signal.SIGINT, self._old)
            self._old = None
        return False

    def check(self) -> None:
        """Raise :class:`Interrupted` if SIGINT arrived (call it where stopping loses nothing)."""
        if self.requested:
            raise Interrupted()
