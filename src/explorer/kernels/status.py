"""Per-orbit status codes (kernel contract rule 3): int constants for compiled code, :class:`Status`
their typed view."""
from enum import IntEnum


class Status(IntEnum):
    """Why an orbit stopped. ``Status(code).description`` is the message the user layer prints."""

    DONE = 0            #: all requested crossings found (or the requested time reached)
    TMAX = 1            #: the time budget ran out first (fewer crossings)
    NONFINITE = 2       #: a non-finite state appeared; the orbit was stopped
    MAX_STEPS = 3       #: the step budget ran out first
    STEP_UNDERFLOW = 4  #: the adaptive step became negligible against t
    UNRESOLVED = 5      #: the fixed step does not resolve the orbit's motion: not integrated
    CANCELLED = 6       #: the caller's stop switch was set (a budget ran out, or the result is not wanted)

    @property
    def description(self) -> str:
        return _DESCRIPTIONS[self]


_DESCRIPTIONS = {
    Status.DONE: "done",
    Status.TMAX: "time budget exhausted",
    Status.NONFINITE: "non-finite state",
    Status.MAX_STEPS: "step budget exhausted",
    Status.STEP_UNDERFLOW: "step size underflow",
    Status.UNRESOLVED: "step does not resolve the motion (dt x model.max_rate > pi: lower dt or use taylor, dop853)",
    Status.CANCELLED: "cancelled (a wall-clock budget ran out or the result was no longer wanted)",
}

STATUS_DONE = int(Status.DONE)
STATUS_TMAX = int(Status.TMAX)
STATUS_NONFINITE = int(Status.NONFINITE)
STATUS_MAX_STEPS = int(Status.MAX_STEPS)
STATUS_STEP_UNDERFLOW = int(Status.STEP_UNDERFLOW)
STATUS_UNRESOLVED = int(Status.UNRESOLVED)
STATUS_CANCELLED = int(Status.CANCELLED)

#: {code: description}: stored with every panel of the HDF5 store (``status_names`` attribute)
STATUS_NAMES = {int(s): s.description for s in Status}
