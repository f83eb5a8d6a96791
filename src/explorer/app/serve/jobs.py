"""The page's background work: one daemon thread per kind of job that computes only the latest
request (a pick's readout, a saddle's manifolds, the MEGNO rasters of a window), so rapid
requests queue nothing and start no thread each.  No web library here."""
from __future__ import annotations

import threading


class LatestJob:
    """One daemon thread that runs ``work(*job)`` for the latest job :meth:`put` (a job put while
    another runs replaces any job still waiting)."""

    def __init__(self, work, name: str):
        self._work = work
        self._cond = threading.Condition()
        self._job: tuple | None = None
        self._stopped = False
        self.thread = threading.Thread(target=self._loop, name=name, daemon=True)
        self.thread.start()

    @classmethod
    def of(cls, owner, attr: str, work, name: str) -> LatestJob:
        """``owner``'s LatestJob kept in its attribute ``attr``, made (and its thread started) at
        the first call: a page starts a thread only for what its user asks for."""
        jobs = owner.__dict__.get(attr)
        if jobs is None:
            jobs = owner.__dict__[attr] = cls(work, name)
        return jobs

    @staticmethod
    def stop_of(owner, attr: str) -> None:
        """Stop ``owner``'s LatestJob in ``attr``, if it was ever made."""
        jobs = owner.__dict__.get(attr)
        if jobs is not None:
            jobs.stop()

    def put(self, job: tuple) -> None:
        with self._cond:
            self._job = job
            self._cond.notify()

    def drop(self) -> None:
        """Forget the job still waiting, if any (the one running goes on)."""
        with self._cond:
            self._job = None

    def stop(self) -> None:
        with self._cond:
            self._stopped, self._job = True, None
            self._cond.notify()

    def _loop(self) -> None:
        while True:
            with self._cond:
                while not self._stopped and self._job is None:
                    self._cond.wait()
                if self._stopped:
                    return
                job, self._job = self._job, None
            if job is not None:      # (always: the wait ends on a job or a stop; said for the type checker)
                self._work(*job)
