"""The engine's Taylor crossings on SIMD lanes: those of every System
(:mod:`explorer.integrate.codegen_lanes`, rendered into :mod:`explorer.integrate._lanes_generated` for
``chaplygin.system()``): the section phi = phi0 is the hyperplane sin(phi - phi0) = g1 cos phi0 - g2 sin phi0
= 0, its half cos(phi - phi0) = g2 cos phi0 + g1 sin phi0 > 0 kept (docs/model.md; docs/architecture.md,
The system seam).  Each lane is bit for bit the scalar oracle tests/integrate/taylor_oracle.py, whatever
the thread count.  Kernel contract: explorer/kernels/__init__.py.
"""
import numpy as np

from explorer._jit import get_num_threads, njit, prange
from explorer.integrate import _lanes_generated as G
from explorer.integrate.layout import CARRY_T
from explorer.integrate.simd import LANES

#: the section phi = phi0 as every System's: s = a . y + b (sin(phi - phi0)), its half keep . (y, 1) > 0
#: (cos(phi - phi0)), the rows (t, p1, p2, M, H - H0)
ROW_STATES = np.array([0, 1, 2], np.int64)


def section_arrays(cphi, sphi):
    """(a, b, keep) of the section phi = phi0 (cphi, sphi = cos phi0, sin phi0) for the generated drivers."""
    return (np.array([0.0, 0.0, 0.0, cphi, -sphi]), 0.0, np.array([0.0, 0.0, 0.0, sphi, cphi, 0.0]))


# nogil: the batch drivers Python calls release the GIL (docs/architecture.md, Parallelism)
@njit(parallel=True, nogil=True)
def _run_lanes(nworkers, Y0, P, a, b, keep, direction, tmax, order, max_steps, carry, limits, out_cross, out_count,
               out_status, out_final, out_info):
    """nworkers groups of LANES lanes (prange), fed from one shared queue of orbits."""
    next_orbit = np.zeros(1, np.int64)
    for w in prange(nworkers):
        G.crossings_lanes_worker(next_orbit, Y0, P, a, b, keep, ROW_STATES, direction, tmax, order, max_steps, carry,
                                 limits, out_cross, out_count, out_status, out_final, out_info, False)
    return 0


def run_taylor_lanes_batch(Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                           out_cross, out_count, out_status, out_final, out_info):
    """Crossings of the section by the Taylor method of ``order`` for every orbit of Y0: the
    arguments and outputs of every batch driver (:mod:`explorer.integrate.drivers`: the carry, the
    limits of a block, the outputs; info's time the clock's sum t and its last column the Casimir
    error g1^2 + g2^2 - 1 of the final state)."""
    a, b, keep = section_arrays(cphi, sphi)
    nworkers = lane_workers(Y0.shape[0])
    args = (Y0, P, a, b, keep, int(direction), float(tmax), int(order), int(max_steps), carry, limits, out_cross,
            out_count, out_status, out_final, out_info)
    if nworkers == 1:
        G.crossings_lanes_worker(np.zeros(1, np.int64), *args[:5], ROW_STATES, *args[5:], False)
    else:
        _run_lanes(nworkers, *args)
    out_info[:, 0] = carry[:, CARRY_T]
    out_info[:, 2] = out_final[:, 3] ** 2 + out_final[:, 4] ** 2 - 1.0
    return 0


def lane_workers(n):
    """How many groups of LANES lanes a batch of ``n`` orbits runs on: one per numba thread, but no more
    than the batch fills (a group steps all its lanes whether they hold an orbit or not), and at least one."""
    return max(1, min(get_num_threads(), -(-int(n) // LANES)))
