"""Model-agnostic numerical kernels.

The kernel contract (every function in this package keeps it):

1. Inputs are C-contiguous float64 arrays (int64 for index tables) and
   scalars; no Python objects, no callables (a jitted function passed as an
   argument defeats numba's on-disk cache).  A step that needs the vector
   field is split into pieces and the caller (``explorer.integrate.drivers``) evaluates
   the field between them.
2. Outputs go into preallocated arrays passed by the caller; kernels never
   allocate inside their loops.
3. Kernels never raise: success or failure is an integer status (the codes
   below); the user layer (``explorer.analysis.sections``) turns codes into messages.
4. Compiled with ``explorer._jit.njit`` (``cache=True``, never ``fastmath``:
   it breaks compensated sums and NaN checks).
5. Results do not depend on the number of threads: parallel loops run over
   independent orbits only, each orbit's arithmetic is sequential.

Modules: ``dop853_coefficients`` (tables), ``dop853`` (step pieces, error
norm, dense output), ``taylor`` (order and step-size control, Horner),
``splitting`` (composition weights and flow sequences), ``events`` (root
refinement of event functions), ``status`` (the per-orbit status codes).
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
