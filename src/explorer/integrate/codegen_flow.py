"""The flow driver appended to every generated module (:data:`explorer.integrate.codegen.TEMPLATES`):
``flow_taylor``, the states of orbits at given times read off each adaptive Taylor step's polynomial
(docs/systems.md, "The flow at given times"), called by :mod:`explorer.analysis.system_flow`."""
from __future__ import annotations

__all__ = ["render"]

SOURCE = '''

# ---- the flow at given times (explorer.analysis.system_flow): generated here, beside the recurrence it
# calls, so that numba's cache of it follows the recurrence (docs/systems.md)
from explorer._jit import prange  # noqa: E402
from explorer.kernels.checks import all_finite, is_finite  # noqa: E402
from explorer.kernels.clock import advance_time, clip_step, resolves  # noqa: E402
from explorer.kernels.status import (  # noqa: E402
    STATUS_DONE, STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW)
from explorer.kernels.taylor import evaluate, safety_factor, step_size  # noqa: E402


@njit(error_model="numpy")
def _flow_finite_column(X, k):
    for i in range(DIM):
        if not is_finite(X[i, k]):
            return False
    return True


@njit(error_model="numpy")
def _flow_sample(j, m, y, P, E0, states, energy_error):
    for i in range(DIM):
        states[j, m, i] = y[i]
{energy_sample}


@njit(error_model="numpy")
def flow_orbit(j, y0, P, times, order, max_steps, states, energy_error, info):
    """Orbit j from y0 with the adaptive Taylor method of ``order`` (Jorba & Zou 2005, as
    ``crossings_orbit``) to the last of the sorted ``times``, its last step clipped onto it.  The
    samples do not change the steps: a time inside a step is the step's polynomial there
    (kernels.taylor.evaluate), the last time the end of the clipped step, t = 0 the start.
    states[j, m] and energy_error[j, m] = |E - E0| for each time reached; info[j] = (t, steps).
    Returns the status."""
    X = np.empty((DIM, order + 1))
    W = np.empty((max(N_WORK, 1), order + 1))
    ynew = np.empty(DIM)
    ys = np.empty(DIM)
    factor = safety_factor(order)
    for i in range(DIM):
        X[i, 0] = y0[i]
    E0 = {energy_start}
    M = times.shape[0]
    tend = times[M - 1]
    m = 0
    while m < M and times[m] <= 0.0:
        _flow_sample(j, m, y0, P, E0, states, energy_error)
        m += 1
    t = 0.0
    tc = 0.0
    steps = 0
    status = STATUS_DONE
    while m < M:
        if steps >= max_steps:
            status = STATUS_MAX_STEPS
            break
        taylor_coefficients_into(P, X, order, W)
        if not (_flow_finite_column(X, order) and _flow_finite_column(X, order - 1)):
            status = STATUS_NONFINITE
            break
        h = step_size(X, order, factor)
        h, last = clip_step(t, h, tend)
        if not resolves(t, h):
            status = STATUS_STEP_UNDERFLOW
            break
        evaluate(X, order, h, ynew)
        steps += 1
        if not all_finite(ynew):
            status = STATUS_NONFINITE
            break
        start = t - tc
        t, tc = advance_time(t, tc, h, last, tend)
        end = t - tc
        while m < M and (last or times[m] <= end):
            if last and times[m] == tend:
                _flow_sample(j, m, ynew, P, E0, states, energy_error)
            else:
                tau = min(max(times[m] - start, 0.0), h)
                evaluate(X, order, tau, ys)
                _flow_sample(j, m, ys, P, E0, states, energy_error)
            m += 1
        for i in range(DIM):
            X[i, 0] = ynew[i]
    info[j, 0] = t - tc
    info[j, 1] = steps
    return status


@njit(parallel=True, error_model="numpy")
def flow_taylor(Y0, P, times, order, max_steps, states, energy_error, status, info):
    """:func:`flow_orbit` for every orbit (row of Y0), in parallel over orbits: each orbit is
    computed alone, so the result does not depend on the number of threads."""
    for j in prange(Y0.shape[0]):
        status[j] = flow_orbit(j, Y0[j], P, times, order, max_steps, states, energy_error, info)
'''


def render(system) -> str:
    """The driver's source for ``system`` (|E - E0| at each sample when it has an energy)."""
    has_energy = system.energy is not None
    return SOURCE.format(
        energy_start="energy(y0, P)" if has_energy else "np.nan",
        energy_sample="    energy_error[j, m] = abs(energy(y, P) - E0)" if has_energy else "    return")
