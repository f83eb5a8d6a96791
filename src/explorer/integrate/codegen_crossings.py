"""The crossings driver appended to every generated module (:data:`explorer.integrate.codegen.TEMPLATES`):
``crossings_taylor_worker``, the adaptive Taylor method with the crossings of a section a . x + b = 0 on its
half keep . (x, 1) > 0, a block of each orbit continued from its carry (docs/systems.md, "Crossings"), called
by :mod:`explorer.analysis.system_sections`; rendered for ``chaplygin.system()`` into
:mod:`explorer.integrate._lanes_generated`, the engine's section phi = phi0 (:mod:`explorer.integrate.lanes`)."""
from __future__ import annotations

__all__ = ["render"]

SOURCE = '''

# ---- crossings of a section a . x + b = 0 (explorer.analysis.system_sections): generated here, beside
# the recurrence they call, so that numba's cache of them follows the recurrence (docs/systems.md)
from explorer.integrate.layout import CARRY_G, CARRY_H0, CARRY_STEPS, CARRY_T, CARRY_TC  # noqa: E402
from explorer.integrate.simd import atomic_fetch_add  # noqa: E402
from explorer.kernels.checks import all_finite, is_finite  # noqa: E402
from explorer.kernels.clock import advance_time, clip_step, resolves  # noqa: E402
from explorer.kernels.events import poly_step_roots, root_workspace  # noqa: E402
from explorer.kernels.status import (  # noqa: E402
    STATUS_DONE, STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW, STATUS_TMAX)
from explorer.kernels.taylor import evaluate, safety_factor, step_size  # noqa: E402

#: a crossing row ends with E - E0 when the system has an energy
HAS_ENERGY = {has_energy}


@njit(error_model="numpy")
def _section_value(a, b, y):
    """s(y) = a . y + b."""
    s = b
    for i in range(DIM):
        s += a[i] * y[i]
    return s


@njit(error_model="numpy")
def crossings_start(Y0, P, a, b, carry):
    """The carry of a run's first block (explorer.integrate.layout): time 0, no steps, s(y0), E0 = E(y0)."""
    for j in range(Y0.shape[0]):
        carry[j, CARRY_T] = 0.0
        carry[j, CARRY_TC] = 0.0
        carry[j, CARRY_G] = _section_value(a, b, Y0[j])
        carry[j, CARRY_STEPS] = 0.0
        carry[j, CARRY_H0] = {energy_of_y0}


@njit(error_model="numpy")
def _record(data, j, n, tr, yc, P, E0, keep, cols):
    """Crossing n of orbit j at time tr, state yc, if keep . (yc, 1) > 0 (a half of the hyperplane; a
    NaN is not refused here): the row data[j, n] = (tr, yc[cols], E - E0).  Returns n + 1, n (the other
    half), or -1 when the row is not finite."""
    side = keep[DIM]
    for i in range(DIM):
        side += keep[i] * yc[i]
    if side <= 0.0:
        return n
    s = tr
    for i in range(cols.shape[0]):
        s += yc[cols[i]]
{energy_value}
    if not is_finite(s):
        return -1
    data[j, n, 0] = tr
    for i in range(cols.shape[0]):
        data[j, n, 1 + i] = yc[cols[i]]
{energy_column}
    return n + 1


@njit(error_model="numpy")
def crossings_orbit(j, y0, P, a, b, keep, cols, direction, tmax, order, max_steps, carry, target, room, data, final,
                    info, backward):
    """Orbit j from y0 with the adaptive Taylor method of ``order`` (Jorba & Zou 2005: the order
    from the tolerance, the step from the last two coefficients, kernels.taylor.step_size), a block
    continued from ``carry[j]`` (explorer.integrate.layout: t, its compensation, s(y0), steps, E0;
    written back at the end), until ``target`` crossings of s = a . y + b = 0 in ``direction``
    (+1: ds/dt > 0, -1: < 0, 0: both), the time ``tmax`` or ``max_steps`` steps.  Each step's
    polynomial s(t + tau) = a . X[:, k] tau^k (+ b) has its roots in (0, h] isolated and refined by
    kernels.events.poly_step_roots; those with keep . (y, 1) > 0 are the crossings, at most ``room``,
    rows :func:`_record`.  Returns (count, status); final[j] the state and info[j] = (t, steps, nan)
    where the orbit stopped.  ``backward``: backward in time (taylor_step), t the time elapsed
    backward, ``direction`` the sign of ds/dt along it."""
    X = np.empty((DIM, order + 1))
    W = np.empty((max(N_WORK, 1), order + 1))
    ynew = np.empty(DIM)
    yc = np.empty(DIM)
    gc, work, roots, brackets, stack = root_workspace(order)
    factor = safety_factor(order)
    for i in range(DIM):
        X[i, 0] = y0[i]
    t = carry[j, CARRY_T]
    tc = carry[j, CARRY_TC]
    gprev = carry[j, CARRY_G]
    steps = int(carry[j, CARRY_STEPS])
    E0 = carry[j, CARRY_H0]
    n = 0
    status = STATUS_DONE
    while n < target:
        if not (t < tmax):
            status = STATUS_TMAX
            break
        if steps >= max_steps:
            status = STATUS_MAX_STEPS
            break
        st, h, last, steps = taylor_step(P, X, W, DIM, t, tmax, order, factor, steps, ynew, backward)
        if st != STEP_OK:
            status = st
            break
        gnew = _section_value(a, b, ynew)
        for k in range(order + 1):
            s = 0.0
            for i in range(DIM):
                s += a[i] * X[i, k]
            gc[k] = s
        gc[0] += b
        nroots = poly_step_roots(gc, order, h, gprev, gnew, direction, roots, brackets, work, stack)
        for r in range(nroots):
            if n >= room:
                break
            tau = roots[r]
            evaluate(X, order, tau, yc)
            kept = _record(data, j, n, (t - tc) + tau, yc, P, E0, keep, cols)
            if kept < 0:
                status = STATUS_NONFINITE
                break
            n = kept
        if status == STATUS_NONFINITE:
            break
        t, tc = advance_time(t, tc, h, last, tmax)
        for i in range(DIM):
            X[i, 0] = ynew[i]
        gprev = gnew
    for i in range(DIM):
        final[j, i] = X[i, 0]
    carry[j, CARRY_T] = t
    carry[j, CARRY_TC] = tc
    carry[j, CARRY_G] = gprev
    carry[j, CARRY_STEPS] = steps
    info[j, 0] = t - tc
    info[j, 1] = steps
    info[j, 2] = np.nan
    return n, status


@njit(nogil=True, error_model="numpy")
def crossings_taylor_worker(next_orbit, Y0, P, a, b, keep, cols, direction, tmax, order, max_steps, carry, limits,
                            data, count, status, final, info, backward):
    """:func:`crossings_orbit` for the orbits (rows of Y0) of the queue ``next_orbit`` that threads share
    (analysis.system_sections.run_driver), orbit j's block up to limits[j] = (target, room): each orbit
    is computed alone, so the result does not depend on the number of threads."""
    j = atomic_fetch_add(next_orbit, 0, 1)
    while j < Y0.shape[0]:
        c, s = crossings_orbit(j, Y0[j], P, a, b, keep, cols, direction, tmax, order, max_steps, carry,
                               limits[j, 0], limits[j, 1], data, final, info, backward)
        count[j] = c
        status[j] = s
        j = atomic_fetch_add(next_orbit, 0, 1)
'''


def render(system) -> str:
    """The driver's source for ``system`` (its energy column when it has an energy)."""
    has_energy = system.energy is not None
    return SOURCE.format(
        has_energy=has_energy,
        energy_of_y0="energy(Y0[j], P)" if has_energy else "0.0",
        energy_value="    e = energy(yc, P) - E0\n    s += e" if has_energy else "",
        energy_column="    data[j, n, 1 + cols.shape[0]] = e" if has_energy else "")
