"""Model-agnostic numerical kernels.  The kernel contract, kept by every function here:

1. C-contiguous float64 (int64 index) arrays and scalars in; no callables (they defeat the
   on-disk cache): the caller evaluates the field between the pieces of a step.
2. Outputs in preallocated arrays; no allocation inside loops.
3. No exceptions: an integer status per orbit.
4. ``explorer._jit.njit`` (cache=True, never fastmath).
5. Results independent of the thread count: parallel over independent orbits only.
"""

from explorer.kernels.status import (
                                     STATUS_CANCELLED,
                                     STATUS_DONE,
                                     STATUS_MAX_STEPS,
                                     STATUS_NAMES,
                                     STATUS_NONFINITE,
                                     STATUS_STEP_UNDERFLOW,
                                     STATUS_TMAX,
                                     STATUS_UNRESOLVED,
                                     Status,
)

__all__ = ["Status", "STATUS_DONE", "STATUS_TMAX", "STATUS_NONFINITE", "STATUS_MAX_STEPS",
           "STATUS_STEP_UNDERFLOW", "STATUS_UNRESOLVED", "STATUS_CANCELLED", "STATUS_NAMES"]
