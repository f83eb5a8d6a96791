"""The scalar Taylor crossing loop: the oracle of the lane driver (explorer.integrate.lanes).

One orbit at a time, written as plainly as the method reads: take the step of
``_systems_generated.taylor_step_reduced`` (budgets, coefficients of R3, finiteness, the Jorba-Zou step clipped to
tmax, Horner), find every root of the step's Taylor polynomial of sin(phi - phi0)
(``kernels.events.poly_step_roots``), keep those on the branch phi = phi0
(``drivers.keep_crossing``), advance the compensated clock, stop at the block's target or a
budget.  The lanes vectorise the arithmetic and run the control flow per lane; the tests hold
them to this loop bit for bit (tests/integrate/test_lanes.py).  Arguments and outputs: those of
``lanes.run_taylor_lanes_batch`` (``explorer.integrate.drivers`` documents them); sequential, for
small test batches.
"""
import numpy as np

from explorer._jit import njit
from explorer.integrate import drivers
from explorer.integrate._systems_generated import taylor_step_reduced
from explorer.integrate.systems import STEP_OK
from explorer.kernels import STATUS_DONE, STATUS_NONFINITE, STATUS_TMAX
from explorer.kernels import taylor as tk
from explorer.kernels.clock import advance_time
from explorer.kernels.events import poly_step_roots, root_workspace
from explorer.model.equations import section_g


@njit
def orbit_taylor(y0, P, cphi, sphi, direction, tmax, order, max_steps, cross, yout, carry, target, room):
    """One orbit from y0 and its carry; returns (count, status, t, steps)."""
    X = np.empty((5, order + 1))
    ynew = np.empty(5)
    yc = np.empty(5)
    gc, work, roots, brackets, stack = root_workspace(order)
    factor = tk.safety_factor(order)
    for i in range(5):
        yout[i] = y0[i]
    t, tc, gprev, steps, H0 = drivers.read_carry(carry)  # tc: Kahan compensation of the time sum
    count = 0
    status = STATUS_TMAX
    if target == 0:
        return 0, STATUS_DONE, t, steps
    while True:
        for i in range(5):
            X[i, 0] = yout[i]
        code, h, last, steps = taylor_step_reduced(X, P, t, tmax, STATUS_TMAX, order, factor, steps, max_steps,
                                                   ynew)
        if code != STEP_OK:
            status = code
            break
        gnew = section_g(ynew, cphi, sphi)
        for k in range(order + 1):
            gc[k] = X[3, k] * cphi - X[4, k] * sphi
        nroots = poly_step_roots(gc, order, h, gprev, gnew, direction, roots, brackets, work, stack)
        kept = count
        for r in range(nroots):
            if kept < 0 or kept >= room:
                break
            tau = roots[r]
            tk.evaluate(X, order, tau, yc)
            kept = drivers.keep_crossing(cross, kept, (t - tc) + tau, yc, P, H0, cphi, sphi)
        if kept < 0:
            status = STATUS_NONFINITE
            break
        count = kept
        t, tc = advance_time(t, tc, h, last, tmax)
        for i in range(5):
            yout[i] = ynew[i]
        gprev = gnew
        if count >= target:
            status = STATUS_DONE
            break
    drivers.save_carry(carry, t, tc, gprev, steps)
    return count, status, t, steps


@njit
def run_taylor_batch(Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                     out_cross, out_count, out_status, out_final, out_info):
    """:func:`orbit_taylor` for every orbit, one after the other."""
    for j in range(Y0.shape[0]):
        count, status, t, steps = orbit_taylor(Y0[j], P, cphi, sphi, direction, tmax, order,
                                               max_steps, out_cross[j], out_final[j], carry[j],
                                               limits[j, drivers.LIMIT_TARGET], limits[j, drivers.LIMIT_ROOM])
        drivers.store_orbit(j, count, status, t, steps, out_count, out_status, out_final, out_info)
    return 0
