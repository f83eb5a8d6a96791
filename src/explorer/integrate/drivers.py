"""Compiled crossing loops of DOP853 and the splitting methods, many orbits in parallel, each until
it has crossed phi = phi0 K times or a budget runs out; and what every crossing loop shares
(:func:`start_carry`, :func:`keep_crossing`, :func:`save_carry`, :func:`store_orbit`).  No
validation (that is :mod:`explorer.analysis.sections`).

Arguments: Y0 (N, 5) states; P (9,) packed parameters; cphi, sphi of phi0; direction +1, -1 or
0 (both); tmax, max_steps per orbit and for the whole run.  ``carry`` (N, N_CARRY) and
``limits`` (N, 2) make blocks continue bit for bit (docs/architecture.md, Streaming).  Outputs:
out_cross (N, K, 5) rows (t, p1, p2, M, H - H0); out_count, out_status (kernels.STATUS_*);
out_final (N, 5); out_info (N, 3) final time, steps, Casimir error.
"""

import numpy as np

from explorer._jit import njit, prange
from explorer.integrate import _systems_generated as sg
from explorer.integrate.layout import (  # noqa: F401 (the carry and limits columns, re-exported)
    CARRY_G,
    CARRY_H0,
    CARRY_HABS,
    CARRY_STEPS,
    CARRY_T,
    CARRY_TC,
    LIMIT_ROOM,
    LIMIT_TARGET,
    MAX_ROOTS_PER_STEP,
    N_CARRY,
)
from explorer.integrate.systems import STEP_OK
from explorer.kernels import STATUS_DONE, STATUS_NONFINITE, STATUS_TMAX
from explorer.kernels import dop853 as dp
from explorer.kernels.checks import EPS, is_finite
from explorer.kernels.clock import advance_time
from explorer.kernels.events import (
    ROOT_MAX_ITER,
    ROOT_XTOL,
    dense_step_roots,
    newton_in_bracket,
    root_workspace,
    secant_start,
    sign_change,
    sin_diff,
    turns,
)
from explorer.model.equations import (
    G1,
    G2,
    energy,
    rhs,
    section_c,
    section_g,
    section_g_rate,
)
from explorer.model.parameters import B

#: A start point with |sin(phi - phi0)| below this is on the section (not a crossing).
ON_SECTION = 8.0 * EPS

@njit
def _record(cross, k, t, yc, H):
    s = t + yc[0] + yc[1] + yc[2] + H
    if not is_finite(s):
        return False
    cross[k, 0] = t
    cross[k, 1] = yc[0]
    cross[k, 2] = yc[1]
    cross[k, 3] = yc[2]
    cross[k, 4] = H
    return True


@njit
def keep_crossing(cross, count, t, yc, P, H0, cphi, sphi):
    """Record the root of sin(phi - phi0) at state yc, time t as crossing number ``count`` if it
    lies on the branch phi = phi0 (cos(phi - phi0) > 0; the root at phi0 + pi is not a crossing):
    the row (t, p1, p2, M, H - H0)."""
    if section_c(yc, cphi, sphi) <= 0.0:
        return count
    if not _record(cross, count, t, yc, energy(yc, P) - H0):
        return -1
    return count + 1


@njit
def _start_g(y, cphi, sphi):
    g = section_g(y, cphi, sphi)
    if abs(g) <= ON_SECTION:
        return 0.0
    return g


@njit
def start_carry(Y0, P, cphi, sphi, carry):
    """The carry of a first block: time 0, no steps, H0 = H(y0), sin(phi - phi0) at y0 (0 on the
    section: a start point is not a crossing), DOP853 not started."""
    for j in range(Y0.shape[0]):
        carry[j, CARRY_T] = 0.0
        carry[j, CARRY_TC] = 0.0
        carry[j, CARRY_G] = _start_g(Y0[j], cphi, sphi)
        carry[j, CARRY_STEPS] = 0.0
        carry[j, CARRY_H0] = energy(Y0[j], P)
        carry[j, CARRY_HABS] = 0.0


@njit
def read_carry(carry):
    """(t, tc, g, steps, H0): where one orbit's block starts, from its carry (the columns
    CARRY_*: time, its Kahan compensation, sin(phi - phi0) at the state, steps taken, and the
    energy the crossings' H - H0 refers to)."""
    return carry[CARRY_T], carry[CARRY_TC], carry[CARRY_G], int(carry[CARRY_STEPS]), carry[CARRY_H0]


@njit
def save_carry(carry, t, tc, g, steps):
    """The carry of one orbit at the end of its block (the columns CARRY_*: time, its Kahan
    compensation, sin(phi - phi0) at the final state, steps); DOP853 adds its next step."""
    carry[CARRY_T] = t
    carry[CARRY_TC] = tc
    carry[CARRY_G] = g
    carry[CARRY_STEPS] = steps


@njit
def store_orbit(j, count, status, t, steps, out_count, out_status, out_final, out_info):
    """The per-orbit outputs of every crossing driver (scalar and lanes): count, status and
    info = (time reached, steps, Casimir error g1^2 + g2^2 - 1 of the final state out_final[j])."""
    out_count[j] = count
    out_status[j] = status
    out_info[j, 0] = t
    out_info[j, 1] = steps
    out_info[j, 2] = out_final[j, 3] ** 2 + out_final[j, 4] ** 2 - 1.0


@njit
def split_step(y, P, dt, flow_ids, fracs):
    """One step of a composition of exact sub-flows (docs/model.md R4), in place
    (:func:`explorer.integrate._systems_generated.compose_reduced`)."""
    sg.compose_reduced(y, P, dt, flow_ids, fracs)


#: the functionals of the splitting root search: sin(phi - phi0), and M (the turn of phi)
_SPLIT_G = 0
_SPLIT_M = 1


@njit
def _split_value_rate(yc, P, which, cphi, sphi, f):
    """(value, d/dt) along the exact flow of the functional ``which`` at yc."""
    if which == _SPLIT_G:
        return section_g(yc, cphi, sphi), section_g_rate(yc, P, cphi, sphi)
    rhs(yc, P, f)
    return yc[2], f[2]  # docs/model.md (R3): dM/dt


@njit
def _split_root(y, P, dt, flow_ids, fracs, which, cphi, sphi, a, b, ga, gb, yc, f):
    if gb == 0.0:
        for i in range(5):
            yc[i] = y[i]
        split_step(yc, P, b, flow_ids, fracs)
        return b
    x = secant_start(a, b, ga, gb)
    tol = ROOT_XTOL * dt
    for _ in range(ROOT_MAX_ITER):
        for i in range(5):
            yc[i] = y[i]
        split_step(yc, P, x, flow_ids, fracs)
        g, d = _split_value_rate(yc, P, which, cphi, sphi, f)
        if g == 0.0:
            return x
        xn, a, b, ga = newton_in_bracket(x, g, d, a, b, ga)
        if abs(xn - x) <= tol or abs(b - a) <= tol:
            for i in range(5):
                yc[i] = y[i]
            split_step(yc, P, xn, flow_ids, fracs)
            return xn
        x = xn
    return x


@njit
def _split_step_roots(y, P, dt, flow_ids, fracs, cphi, sphi, gprev, gnew, mnew, direction,
                      roots, yc, f):
    if turns(y[2], mnew):
        tm = _split_root(y, P, dt, flow_ids, fracs, _SPLIT_M, cphi, sphi, 0.0, dt, y[2], mnew,
                         yc, f)
        gm = section_g(yc, cphi, sphi)
        n = 0
        if sign_change(gprev, gm, direction):
            roots[n] = _split_root(y, P, dt, flow_ids, fracs, _SPLIT_G, cphi, sphi, 0.0, tm,
                                   gprev, gm, yc, f)
            n += 1
        if sign_change(gm, gnew, direction):
            roots[n] = _split_root(y, P, dt, flow_ids, fracs, _SPLIT_G, cphi, sphi, tm, dt,
                                   gm, gnew, yc, f)
            n += 1
        return n
    if sign_change(gprev, gnew, direction):
        roots[0] = _split_root(y, P, dt, flow_ids, fracs, _SPLIT_G, cphi, sphi, 0.0, dt,
                               gprev, gnew, yc, f)
        return 1
    return 0


@njit
def orbit_split(y0, P, cphi, sphi, direction, tmax, dt, flow_ids, fracs, max_steps, cross, yout, carry, target,
                room):
    """One orbit with a fixed-step composition of exact flows (the step:
    :func:`explorer.integrate._systems_generated.split_step_reduced`); t_n = n dt (no summation
    error).  Returns (count, status, t, steps)."""
    ynew = np.empty(5)
    yc = np.empty(5)
    f = np.empty(5)
    roots = np.empty(2)
    for i in range(5):
        yout[i] = y0[i]
    _t, _tc, gprev, n, H0 = read_carry(carry)   # t_n = n dt: no time is carried
    count = 0
    status = STATUS_TMAX
    if target == 0:
        return 0, STATUS_DONE, n * dt, n
    while True:
        t = n * dt
        if t >= tmax:
            status = STATUS_TMAX
            break
        code, n = sg.split_step_reduced(yout, P, dt, flow_ids, fracs, n, max_steps, ynew)
        if code != STEP_OK:
            status = code
            break
        gnew = section_g(ynew, cphi, sphi)
        if sign_change(gprev, gnew, direction) or turns(yout[2], ynew[2]):
            nroots = _split_step_roots(yout, P, dt, flow_ids, fracs, cphi, sphi, gprev, gnew,
                                       ynew[2], direction, roots, yc, f)
            kept = count
            for r in range(nroots):
                tau = roots[r]
                if kept < 0 or kept >= room or t + tau > tmax:
                    break
                if nroots > 1:
                    for i in range(5):
                        yc[i] = yout[i]
                    split_step(yc, P, tau, flow_ids, fracs)
                kept = keep_crossing(cross, kept, t + tau, yc, P, H0, cphi, sphi)
            if kept < 0:
                status = STATUS_NONFINITE
                break
            count = kept
        for i in range(5):
            yout[i] = ynew[i]
        gprev = gnew
        if count >= target:
            status = STATUS_DONE
            break
    save_carry(carry, n * dt, 0.0, gprev, n)
    return count, status, n * dt, n


# nogil: the batch drivers Python calls release the GIL (docs/architecture.md, Parallelism)
@njit(parallel=True, nogil=True)
def run_split_batch(Y0, P, cphi, sphi, direction, tmax, dt, flow_ids, fracs, max_steps, carry, limits,
                    out_cross, out_count, out_status, out_final, out_info):
    """Batch twin of :func:`orbit_split`, parallel over orbits (prange)."""
    n = Y0.shape[0]
    for j in prange(n):
        count, status, t, steps = orbit_split(Y0[j], P, cphi, sphi, direction, tmax, dt,
                                              flow_ids, fracs, max_steps, out_cross[j], out_final[j],
                                              carry[j], limits[j, LIMIT_TARGET], limits[j, LIMIT_ROOM])
        store_orbit(j, count, status, t, steps, out_count, out_status, out_final, out_info)
    return 0


#: a DOP853 step whose ends are within NEAR_SECTION times the reach of the step (below) of
#: the section gets its dense output searched even without a sign change at its ends
NEAR_SECTION = 2.0


@njit
def _may_reach_section(y_old, y_new, K, P, h, g_old, g_new):
    if turns(y_old[2], y_new[2]):
        return True
    b = P[B]
    reach = (h * (abs(y_old[2]) + abs(y_new[2])) + h * h * (abs(K[0, 2]) + abs(K[12, 2]))) / b
    return min(abs(g_old), abs(g_new)) <= NEAR_SECTION * reach


@njit
def orbit_dop853(y0, P, cphi, sphi, direction, tmax, rtol, atol, max_steps, cross, yout, carry, target, room):
    """One orbit with adaptive DOP853 (Hairer-Nørsett-Wanner; controller and first step as
    scipy's)."""
    K = np.empty((16, 5))
    F = np.empty((7, 5))
    Fg = np.empty(7)
    coef, work, roots, brackets, stack = root_workspace(7)
    tmp = np.empty(5)
    ynew = np.empty(5)
    yc = np.empty(5)
    for i in range(5):
        yout[i] = y0[i]
    t, tc, gprev, steps, H0 = read_carry(carry)
    if target == 0:
        return 0, STATUS_DONE, t, steps
    h_abs = carry[CARRY_HABS]
    if h_abs > 0.0:
        sg.field_reduced(yout, P, K[0])
    else:
        h_abs = sg.dop853_first_step_reduced(yout, P, K, rtol, atol, tmax, tmp)
    count = 0
    while True:
        code, h, last, h_abs, steps = sg.dop853_step_reduced(yout, P, K, t, tmax, STATUS_TMAX, h_abs, steps,
                                                             max_steps, rtol, atol, tmp, ynew, True)
        if code != STEP_OK:
            break
        gnew = section_g(ynew, cphi, sphi)
        if sign_change(gprev, gnew, direction) or _may_reach_section(yout, ynew, K, P, h, gprev,
                                                                     gnew):
            sg.dop853_dense_stages_reduced(yout, P, K, h, tmp)
            dp.dense_coefficients(yout, ynew, K, h, F)
            g_old = section_g(yout, cphi, sphi)
            for k in range(7):
                Fg[k] = sin_diff(F[k, G1], F[k, G2], cphi, sphi)
            nroots = dense_step_roots(Fg, g_old, gprev, gnew, direction, roots, brackets, coef,
                                      work, stack)
            kept = count
            for r in range(nroots):
                if kept < 0 or kept >= room:
                    break
                theta = roots[r]
                dp.dense_eval(F, yout, theta, yc)
                kept = keep_crossing(cross, kept, (t - tc) + theta * h, yc, P, H0, cphi, sphi)
            if kept < 0:
                code = STATUS_NONFINITE
                break
            count = kept
        t, tc = advance_time(t, tc, h, last, tmax)
        for i in range(5):
            yout[i] = ynew[i]
            K[0, i] = K[12, i]
        gprev = gnew
        if count >= target:
            code = STATUS_DONE
            break
    save_carry(carry, t, tc, gprev, steps)
    carry[CARRY_HABS] = h_abs
    return count, code, t, steps


@njit(parallel=True, nogil=True)
def run_dop853_batch(Y0, P, cphi, sphi, direction, tmax, rtol, atol, max_steps, carry, limits,
                     out_cross, out_count, out_status, out_final, out_info):
    """Batch twin of :func:`orbit_dop853`, parallel over orbits (prange)."""
    n = Y0.shape[0]
    for j in prange(n):
        count, status, t, steps = orbit_dop853(Y0[j], P, cphi, sphi, direction, tmax, rtol, atol,
                                               max_steps, out_cross[j], out_final[j], carry[j],
                                               limits[j, LIMIT_TARGET], limits[j, LIMIT_ROOM])
        store_orbit(j, count, status, t, steps, out_count, out_status, out_final, out_info)
    return 0
