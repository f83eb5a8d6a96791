# Written to this file by tools/gen_lanes.py from explorer.model.chaplygin.system().
# Regenerate:  python tools/gen_lanes.py     (check: --check)
# ruff: noqa  (the text of every System's module: its imports repeat, template by template)
# GENERATED FILE - DO NOT EDIT. Written by explorer.integrate.codegen (generator version 12)
# from the system 'chaplygin'; the key  is of its content (explorer.model.system.System.flow_hash).
#
#   dp1/dt = M*p2/b - M*zeta/b - g1*mu - lam*p2/a2
#   dp2/dt = M*chi/b - M*p1/b - g2*mu + lam*p1/a1
#   dM/dt = eta*g1*mu - g2*mu*xi - chi*p2/a2 + p1*zeta/a1 + p1*p2*(a1 - a2)/(a1*a2)
#   dg1/dt = M*g2/b
#   dg2/dt = -M*g1/b
#   parameters: a1, a2, b, lam, chi, zeta, mu, xi, eta
"""The Taylor recurrence, right-hand side and energy of the system 'chaplygin' (explorer.integrate.codegen)."""
import math

import numpy as np

from explorer._jit import njit
from explorer.kernels.checks import all_finite, is_finite
from explorer.kernels.clock import clip_step, resolves
from explorer.kernels.status import STATUS_NONFINITE, STATUS_STEP_UNDERFLOW
from explorer.kernels.taylor import evaluate, step_size

#: state dimension, number of parameters, rows of the work array of taylor_coefficients_into
DIM = 5
N_PARAMS = 9
N_WORK = 0


# error_model="numpy": a division by zero gives inf/nan (the integrators' non-finite status), not an exception
@njit(error_model="numpy")
def taylor_coefficients_into(P, X, order, W):
    """X[i, k] = x_i^(k)(0)/k! for k = 0..order (order >= 1) from X[:, 0], with the parameters P and the
    work array W[N_WORK, >= order] (automatic differentiation, Jorba & Zou 2005)."""
    s1 = P[6]
    s3 = 1.0
    s4 = P[2]
    s5 = s3 / s4
    s9 = P[1]
    s14 = P[0]
    s19 = P[3]
    s20 = s19 / s9
    s23 = P[5]
    s24 = s5 * s23
    s27 = P[4]
    s28 = s27 * s5
    s30 = s19 / s14
    s37 = P[8]
    s38 = s37 * s1
    s40 = s23 / s14
    s44 = s9 * s14
    s45 = s14 - s9
    s46 = s45 / s44
    s49 = s27 / s9
    s52 = P[7]
    s53 = s1 * s52
    u16 = X[2, 0] * X[1, 0]
    u18 = (s5 * u16) - (s1 * X[3, 0])
    u22 = u18 - (s20 * X[1, 0])
    u26 = u22 - (s24 * X[2, 0])
    u32 = (s28 * X[2, 0]) + (s30 * X[0, 0])
    u33 = u32 - (s1 * X[4, 0])
    u34 = X[0, 0] * X[2, 0]
    u36 = u33 - (s5 * u34)
    u42 = (s38 * X[3, 0]) + (s40 * X[0, 0])
    u43 = X[1, 0] * X[0, 0]
    u48 = u42 + (s46 * u43)
    u51 = u48 - (s49 * X[1, 0])
    u55 = u51 - (s53 * X[4, 0])
    u56 = X[4, 0] * X[2, 0]
    u58 = X[3, 0] * X[2, 0]
    u60 = -(s5 * u58)
    X[0, 1] = u26
    X[1, 1] = u36
    X[2, 1] = u55
    X[3, 1] = (s5 * u56)
    X[4, 1] = u60
    for k in range(1, order):
        m16 = 0.0
        m34 = 0.0
        m43 = 0.0
        m56 = 0.0
        m58 = 0.0
        for j in range(k + 1):
            m16 = m16 + X[2, j] * X[1, k - j]
            m34 = m34 + X[0, j] * X[2, k - j]
            m43 = m43 + X[1, j] * X[0, k - j]
            m56 = m56 + X[4, j] * X[2, k - j]
            m58 = m58 + X[3, j] * X[2, k - j]
        v16 = m16
        v34 = m34
        v43 = m43
        v56 = m56
        v58 = m58
        v32 = (s28 * X[2, k]) + (s30 * X[0, k])
        v42 = (s38 * X[3, k]) + (s40 * X[0, k])
        v18 = (s5 * v16) - (s1 * X[3, k])
        v33 = v32 - (s1 * X[4, k])
        v48 = v42 + (s46 * v43)
        v60 = -(s5 * v58)
        v22 = v18 - (s20 * X[1, k])
        v36 = v33 - (s5 * v34)
        v51 = v48 - (s49 * X[1, k])
        v26 = v22 - (s24 * X[2, k])
        v55 = v51 - (s53 * X[4, k])
        r = 1.0 / (k + 1)
        X[0, k + 1] = v26 * r
        X[1, k + 1] = v36 * r
        X[2, k + 1] = v55 * r
        X[3, k + 1] = (s5 * v56) * r
        X[4, k + 1] = v60 * r


@njit(error_model="numpy")
def taylor_coefficients(P, X, order):
    """:func:`taylor_coefficients_into` with its own work array."""
    W = np.empty((max(N_WORK, 1), order + 1))
    taylor_coefficients_into(P, X, order, W)


#: taylor_step's status of a step taken
STEP_OK = -1


@njit(error_model="numpy")
def _rows_finite(X, k, n):
    for i in range(n):
        if not is_finite(X[i, k]):
            return False
    return True


@njit(error_model="numpy")
def taylor_step(P, X, W, n, t, tend, order, factor, steps, ynew, backward):
    """One step of the adaptive Taylor method of ``order`` (Jorba & Zou 2005) from X[:, 0] at time
    t towards tend: the coefficients, the step from rows :n (the orbit's) clipped onto tend, ynew
    the state at its end.  ``backward``: t is the time elapsed backward, the coefficients those of
    y(t0 - t), (-1)^k X[:, k] (exactly the flow of -f's).  Returns (status, h, last, steps): STEP_OK,
    or why no step was taken (h = 0) or why its end is not finite."""
    taylor_coefficients_into(P, X, order, W)
    if backward:
        for k in range(1, order + 1, 2):
            for i in range(DIM):
                X[i, k] = -X[i, k]
    if not (_rows_finite(X, order, n) and _rows_finite(X, order - 1, n)):
        return STATUS_NONFINITE, 0.0, False, steps
    h = step_size(X[:n], order, factor)
    h, last = clip_step(t, h, tend)
    if not resolves(t, h):
        return STATUS_STEP_UNDERFLOW, 0.0, False, steps
    evaluate(X, order, h, ynew)
    steps += 1
    if not all_finite(ynew):
        return STATUS_NONFINITE, h, last, steps
    return STEP_OK, h, last, steps


@njit(error_model="numpy")
def rhs(y, P, dy):
    """dy = f(y) (the order-0 part of the recurrence)."""
    X = np.empty((DIM, 1))
    for i in range(DIM):
        X[i, 0] = y[i]
    W = np.empty((max(N_WORK, 1), 1))
    s1 = P[6]
    s3 = 1.0
    s4 = P[2]
    s5 = s3 / s4
    s9 = P[1]
    s14 = P[0]
    s19 = P[3]
    s20 = s19 / s9
    s23 = P[5]
    s24 = s5 * s23
    s27 = P[4]
    s28 = s27 * s5
    s30 = s19 / s14
    s37 = P[8]
    s38 = s37 * s1
    s40 = s23 / s14
    s44 = s9 * s14
    s45 = s14 - s9
    s46 = s45 / s44
    s49 = s27 / s9
    s52 = P[7]
    s53 = s1 * s52
    u16 = X[2, 0] * X[1, 0]
    u18 = (s5 * u16) - (s1 * X[3, 0])
    u22 = u18 - (s20 * X[1, 0])
    u26 = u22 - (s24 * X[2, 0])
    u32 = (s28 * X[2, 0]) + (s30 * X[0, 0])
    u33 = u32 - (s1 * X[4, 0])
    u34 = X[0, 0] * X[2, 0]
    u36 = u33 - (s5 * u34)
    u42 = (s38 * X[3, 0]) + (s40 * X[0, 0])
    u43 = X[1, 0] * X[0, 0]
    u48 = u42 + (s46 * u43)
    u51 = u48 - (s49 * X[1, 0])
    u55 = u51 - (s53 * X[4, 0])
    u56 = X[4, 0] * X[2, 0]
    u58 = X[3, 0] * X[2, 0]
    u60 = -(s5 * u58)
    dy[0] = u26
    dy[1] = u36
    dy[2] = u55
    dy[3] = (s5 * u56)
    dy[4] = u60


# ---- the SIMD form (explorer.integrate.simd): LANES orbits at once
from explorer.integrate.simd import (  # noqa: E402
    LANES, vadd, vdiv, vget, vload, vmul, vneg, vset, vsplat, vsqrt, vstore, vsub, vzero)

#: the flat stride of one order in the lane array X[k, i, l] (the drivers' helpers; the recurrence
#: addresses X and W by vget and vset)
XS = DIM * LANES


@njit(error_model='numpy')
def taylor_coefficients_lanes(P, X, order, W):
    """LANES orbits at once: X[k, i, l] for k = 1..order from X[0] (X of shape (order + 1, DIM, LANES),
    W of shape (order + 1, max(N_WORK, 1), LANES), both C-contiguous).  Each lane equals
    taylor_coefficients_into bit for bit (the same operations in the same order)."""
    s1 = P[6]
    s3 = 1.0
    s4 = P[2]
    s5 = s3 / s4
    s9 = P[1]
    s14 = P[0]
    s19 = P[3]
    s20 = s19 / s9
    s23 = P[5]
    s24 = s5 * s23
    s27 = P[4]
    s28 = s27 * s5
    s30 = s19 / s14
    s37 = P[8]
    s38 = s37 * s1
    s40 = s23 / s14
    s44 = s9 * s14
    s45 = s14 - s9
    s46 = s45 / s44
    s49 = s27 / s9
    s52 = P[7]
    s53 = s1 * s52
    u16 = vmul(vget(X, 0, 2), vget(X, 0, 1))
    u18 = vsub(vmul(vsplat(s5), u16), vmul(vsplat(s1), vget(X, 0, 3)))
    u22 = vsub(u18, vmul(vsplat(s20), vget(X, 0, 1)))
    u26 = vsub(u22, vmul(vsplat(s24), vget(X, 0, 2)))
    u32 = vadd(vmul(vsplat(s28), vget(X, 0, 2)), vmul(vsplat(s30), vget(X, 0, 0)))
    u33 = vsub(u32, vmul(vsplat(s1), vget(X, 0, 4)))
    u34 = vmul(vget(X, 0, 0), vget(X, 0, 2))
    u36 = vsub(u33, vmul(vsplat(s5), u34))
    u42 = vadd(vmul(vsplat(s38), vget(X, 0, 3)), vmul(vsplat(s40), vget(X, 0, 0)))
    u43 = vmul(vget(X, 0, 1), vget(X, 0, 0))
    u48 = vadd(u42, vmul(vsplat(s46), u43))
    u51 = vsub(u48, vmul(vsplat(s49), vget(X, 0, 1)))
    u55 = vsub(u51, vmul(vsplat(s53), vget(X, 0, 4)))
    u56 = vmul(vget(X, 0, 4), vget(X, 0, 2))
    u58 = vmul(vget(X, 0, 3), vget(X, 0, 2))
    u60 = vneg(vmul(vsplat(s5), u58))
    vset(X, 1, 0, u26)
    vset(X, 1, 1, u36)
    vset(X, 1, 2, u55)
    vset(X, 1, 3, vmul(vsplat(s5), u56))
    vset(X, 1, 4, u60)
    for k in range(1, order):
        m16 = vzero()
        m34 = vzero()
        m43 = vzero()
        m56 = vzero()
        m58 = vzero()
        for j in range(k + 1):
            m16 = vadd(m16, vmul(vget(X, j, 2), vget(X, k - j, 1)))
            m34 = vadd(m34, vmul(vget(X, j, 0), vget(X, k - j, 2)))
            m43 = vadd(m43, vmul(vget(X, j, 1), vget(X, k - j, 0)))
            m56 = vadd(m56, vmul(vget(X, j, 4), vget(X, k - j, 2)))
            m58 = vadd(m58, vmul(vget(X, j, 3), vget(X, k - j, 2)))
        v16 = m16
        v34 = m34
        v43 = m43
        v56 = m56
        v58 = m58
        v32 = vadd(vmul(vsplat(s28), vget(X, k, 2)), vmul(vsplat(s30), vget(X, k, 0)))
        v42 = vadd(vmul(vsplat(s38), vget(X, k, 3)), vmul(vsplat(s40), vget(X, k, 0)))
        v18 = vsub(vmul(vsplat(s5), v16), vmul(vsplat(s1), vget(X, k, 3)))
        v33 = vsub(v32, vmul(vsplat(s1), vget(X, k, 4)))
        v48 = vadd(v42, vmul(vsplat(s46), v43))
        v60 = vneg(vmul(vsplat(s5), v58))
        v22 = vsub(v18, vmul(vsplat(s20), vget(X, k, 1)))
        v36 = vsub(v33, vmul(vsplat(s5), v34))
        v51 = vsub(v48, vmul(vsplat(s49), vget(X, k, 1)))
        v26 = vsub(v22, vmul(vsplat(s24), vget(X, k, 2)))
        v55 = vsub(v51, vmul(vsplat(s53), vget(X, k, 4)))
        r = 1.0 / (k + 1)
        vset(X, k + 1, 0, vmul(v26, vsplat(r)))
        vset(X, k + 1, 1, vmul(v36, vsplat(r)))
        vset(X, k + 1, 2, vmul(v55, vsplat(r)))
        vset(X, k + 1, 3, vmul(vmul(vsplat(s5), v56), vsplat(r)))
        vset(X, k + 1, 4, vmul(v60, vsplat(r)))


@njit(error_model="numpy")
def energy(y, P):
    """The energy at the state y."""
    X = np.empty((DIM, 1))
    for i in range(DIM):
        X[i, 0] = y[i]
    W = np.empty((max(N_ENERGY_WORK, 1), 1))
    s0 = P[6]
    s1 = P[8]
    s5 = P[7]
    s11 = 2.0
    s12 = P[2]
    s13 = s11 * s12
    s18 = P[0]
    s19 = s11 * s18
    s24 = P[1]
    s25 = s11 * s24
    s28 = P[4]
    s31 = P[5]
    s36 = P[3]
    u7 = (s1 * X[4, 0]) + (s5 * X[3, 0])
    W[0, 0] = X[2, 0] * X[2, 0]
    u15 = (s0 * u7) + (W[0, 0] / s13)
    W[1, 0] = X[0, 0] * X[0, 0]
    u21 = u15 + (W[1, 0] / s19)
    W[2, 0] = X[1, 0] * X[1, 0]
    u27 = u21 + (W[2, 0] / s25)
    W[3, 0] = X[0, 0] - s28
    u30 = X[4, 0] * W[3, 0]
    W[4, 0] = X[1, 0] - s31
    u33 = X[3, 0] * W[4, 0]
    u35 = s0 * (u30 - u33)
    u38 = u27 - (u35 / s36)
    return u38


N_ENERGY_WORK = 5


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
HAS_ENERGY = True


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
        carry[j, CARRY_H0] = energy(Y0[j], P)


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
    e = energy(yc, P) - E0
    s += e
    if not is_finite(s):
        return -1
    data[j, n, 0] = tr
    for i in range(cols.shape[0]):
        data[j, n, 1 + i] = yc[cols[i]]
    data[j, n, 1 + cols.shape[0]] = e
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


# ---- crossings on SIMD lanes (explorer.analysis.system_sections): each lane crossings_orbit bit for bit
from explorer.integrate.simd import next_bit, vbits, vmask, vselect  # noqa: E402
from explorer.kernels.clock import compensated_add  # noqa: E402
from explorer.kernels.events import excluded_by_variation, sign_change, tail_term  # noqa: E402
from explorer.integrate.lane_parts import (  # noqa: E402
    lane_finish, lane_start, lane_status, lane_step, norms_lanes, steps_lanes)

#: all lanes' bits
_ALL_LANES = (1 << LANES) - 1


@njit(error_model="numpy")
def _evaluate_lanes(X, order, hv, Y):
    """Y[i, l] = sum_k X[k, i, l] hv[l]^k: kernels.taylor.evaluate (Horner) per lane."""
    h = vload(hv, 0)
    o = order * XS
    y0 = vload(X, o + 0 * LANES)
    y1 = vload(X, o + 1 * LANES)
    y2 = vload(X, o + 2 * LANES)
    y3 = vload(X, o + 3 * LANES)
    y4 = vload(X, o + 4 * LANES)
    for k in range(order - 1, -1, -1):
        o = k * XS
        y0 = y0 * h + vload(X, o + 0 * LANES)
        y1 = y1 * h + vload(X, o + 1 * LANES)
        y2 = y2 * h + vload(X, o + 2 * LANES)
        y3 = y3 * h + vload(X, o + 3 * LANES)
        y4 = y4 * h + vload(X, o + 4 * LANES)
    vstore(Y, 0 * LANES, y0)
    vstore(Y, 1 * LANES, y1)
    vstore(Y, 2 * LANES, y2)
    vstore(Y, 3 * LANES, y3)
    vstore(Y, 4 * LANES, y4)


@njit(error_model="numpy")
def _section_lanes(X, order, hv, Y, a, b, direction, L_g, GC, G):
    """Per lane, as crossings_orbit: G = _section_value(a, b, y) of the new state y = Y, GC[k] = a . X[k]
    (+ b at k = 0).  Returns the bits of the lanes whose new state is finite (kernels.checks.all_finite)
    and of those where kernels.events.isolate_crossings(GC, order, h, L_g, G, direction, ...) may find a
    root: its first two tests (no_root_within; monotone_within without a sign change) in vector form."""
    h = vload(hv, 0)
    sy = vzero()
    g = vsplat(b)
    y0 = vload(Y, 0 * LANES)
    sy = sy + y0
    g = g + a[0] * y0
    y1 = vload(Y, 1 * LANES)
    sy = sy + y1
    g = g + a[1] * y1
    y2 = vload(Y, 2 * LANES)
    sy = sy + y2
    g = g + a[2] * y2
    y3 = vload(Y, 3 * LANES)
    sy = sy + y3
    g = g + a[3] * y3
    y4 = vload(Y, 4 * LANES)
    sy = sy + y4
    g = g + a[4] * y4
    vstore(G, 0, g)
    tail = vzero()
    rk = vsplat(1.0)
    dtail = vzero()
    drk = vsplat(1.0)
    for k in range(order + 1):
        o = k * XS
        c = vzero()
        c = c + a[0] * vload(X, o + 0 * LANES)
        c = c + a[1] * vload(X, o + 1 * LANES)
        c = c + a[2] * vload(X, o + 2 * LANES)
        c = c + a[3] * vload(X, o + 3 * LANES)
        c = c + a[4] * vload(X, o + 4 * LANES)
        if k == 0:
            c = c + b
        else:
            tail, rk = tail_term(tail, rk, h, 1.0, c)
            if k >= 2:
                dtail, drk = tail_term(dtail, drk, h, float(k), c)
        vstore(GC, k * LANES, c)
    excluded = vbits(excluded_by_variation(vload(GC, 0), tail))
    monotone = vbits(excluded_by_variation(vload(GC, LANES), dtail))
    cross = vbits(sign_change(vload(L_g, 0), g, direction))
    return vbits(is_finite(sy)), _ALL_LANES & ~excluded & (~monotone | cross)


@njit(error_model="numpy")
def _ends_lanes(X, Y, G, hv, L_go, L_last, finite, maybe, L_t, L_tc, L_steps, L_g, tmax, max_steps):
    """The end of crossings_orbit's step in vector form for the lanes whose step went on, is not the last,
    ends finite, cannot hold a root and leaves the orbit running: the compensated clock
    (kernels.clock.compensated_add), the step count, the state and the section's value.  Returns the bits
    of the other lanes whose step went on: their end is taken per lane."""
    go = vbits(vload(L_go, 0) > 0.0)
    t, tc = compensated_add(vload(L_t, 0), vload(L_tc, 0), vload(hv, 0))
    steps = vload(L_steps, 0) + 1.0
    ok = go & finite & ~maybe & ~vbits(vload(L_last, 0) > 0.0) & vbits((t < tmax) & (steps < float(max_steps)))
    m = vmask(ok)
    vstore(L_t, 0, vselect(m, t, vload(L_t, 0)))
    vstore(L_tc, 0, vselect(m, tc, vload(L_tc, 0)))
    vstore(L_steps, 0, vselect(m, steps, vload(L_steps, 0)))
    vstore(L_g, 0, vselect(m, vload(G, 0), vload(L_g, 0)))
    for i in range(DIM):
        vstore(X, i * LANES, vselect(m, vload(Y, i * LANES), vload(X, i * LANES)))
    return go & ~ok


@njit(nogil=True, error_model="numpy")
def crossings_lanes_worker(next_orbit, Y0, P, a, b, keep, cols, direction, tmax, order, max_steps, carry, limits,
                           data, count, status, final, info, backward):
    """One group of LANES lanes: orbits from the queue ``next_orbit`` until it is empty, each lane
    crossings_orbit's loop (the arguments and outputs of crossings_taylor_worker, ``backward`` its
    (-1)^k X[k])."""
    X = np.zeros((order + 1, DIM, LANES))
    W = np.zeros((order + 1, max(N_WORK, 1), LANES))
    Y = np.zeros((DIM, LANES))
    GC = np.zeros((order + 1, LANES))
    NORM = np.zeros((5, LANES))
    # per lane: the step, the clock, the section's values, E0, the step count, and flags as 1.0 / 0.0
    hv = np.zeros(LANES)
    G = np.zeros(LANES)
    L_t = np.zeros(LANES)
    L_tc = np.zeros(LANES)
    L_g = np.zeros(LANES)
    L_E0 = np.zeros(LANES)
    L_steps = np.zeros(LANES)
    L_on = np.zeros(LANES)
    L_last = np.zeros(LANES)
    L_go = np.zeros(LANES)
    orb = np.full(LANES, -1, np.int64)
    L_n = np.zeros(LANES, np.int64)
    L_target = np.zeros(LANES, np.int64)
    L_room = np.zeros(LANES, np.int64)
    yc = np.empty(DIM)
    gc, work, roots, brackets, stack = root_workspace(order)
    factor = safety_factor(order)
    e_p = 1.0 / order
    e_q = 1.0 / (order - 1)
    active = 0
    for l in range(LANES):
        active += lane_start(l, next_orbit, Y0, tmax, max_steps, carry, limits, X, orb, L_on, L_t, L_tc, L_g,
                              L_E0, L_n, L_steps, L_target, L_room, count, status, final, info)
    while active > 0:
        taylor_coefficients_lanes(P, X, order, W)
        if backward:
            for k in range(1, order + 1, 2):
                for i in range(DIM):
                    for l in range(LANES):
                        X[k, i, l] = -X[k, i, l]
        fin, normal = norms_lanes(X, order, DIM, e_p, e_q, NORM)
        bits = steps_lanes(NORM, fin, normal, L_on, L_t, tmax, factor, hv, L_last, L_go)
        while bits != 0:
            l, bits = next_bit(bits)
            st = lane_step(l, fin, normal, NORM, e_p, e_q, factor, L_t, tmax, hv, L_last, L_go)
            if st >= 0:
                lane_finish(l, st, X, orb, L_t, L_tc, L_g, L_n, L_steps, carry, count, status, final, info)
                active += lane_start(l, next_orbit, Y0, tmax, max_steps, carry, limits, X, orb, L_on, L_t,
                                      L_tc, L_g, L_E0, L_n, L_steps, L_target, L_room, count, status, final,
                                      info) - 1
        _evaluate_lanes(X, order, hv, Y)
        finite, maybe = _section_lanes(X, order, hv, Y, a, b, direction, L_g, GC, G)
        bits = _ends_lanes(X, Y, G, hv, L_go, L_last, finite, maybe, L_t, L_tc, L_steps, L_g, tmax, max_steps)
        while bits != 0:
            l, bits = next_bit(bits)
            L_steps[l] += 1.0
            st = STATUS_NONFINITE
            if (finite >> l) & 1:
                j = orb[l]
                t = L_t[l]
                tc = L_tc[l]
                h = hv[l]
                n = L_n[l]
                nroots = 0
                if (maybe >> l) & 1:
                    for k in range(order + 1):
                        gc[k] = GC[k, l]
                    nroots = poly_step_roots(gc, order, h, L_g[l], G[l], direction, roots, brackets, work, stack)
                kept = n
                for r in range(nroots):
                    if n >= L_room[l]:
                        break
                    tau = roots[r]
                    evaluate(X[:, :, l].T, order, tau, yc)
                    kept = _record(data, j, n, (t - tc) + tau, yc, P, L_E0[l], keep, cols)
                    if kept < 0:
                        break
                    n = kept
                L_n[l] = n
                if kept >= 0:
                    t, tc = advance_time(t, tc, h, L_last[l] != 0.0, tmax)
                    L_t[l] = t
                    L_tc[l] = tc
                    for i in range(DIM):
                        X[0, i, l] = Y[i, l]
                    L_g[l] = G[l]
                    st = lane_status(n, L_target[l], t, tmax, L_steps[l], max_steps)
            if st >= 0:
                lane_finish(l, st, X, orb, L_t, L_tc, L_g, L_n, L_steps, carry, count, status, final, info)
                active += lane_start(l, next_orbit, Y0, tmax, max_steps, carry, limits, X, orb, L_on, L_t,
                                      L_tc, L_g, L_E0, L_n, L_steps, L_target, L_room, count, status, final,
                                      info) - 1


# ---- the engine's names: its state's rows, and its H (explorer.model.equations.energy, docs/model.md R3)
# in the rows' H - H0, of which explorer.integrate.drivers.start_carry takes H0 for every method
from explorer.model.equations import energy  # noqa: E402, F811

#: state variables (p1, p2, M, g1, g2): the rows of X
NVAR = DIM
