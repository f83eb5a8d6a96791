"""Ctrl-C during a long run: the first SIGINT sets a flag that the run checks between chunks,
blocks and commits (:meth:`deferred_interrupt.check`), so it stops with :class:`Interrupted` after
a whole commit, never inside a Numba call's cleanup; a second SIGINT raises at once."""
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
