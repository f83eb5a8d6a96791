"""The system seam (docs/architecture.md): a system is an integer id (``REDUCED`` R3, ``TANGENT``
R3 and one deviation vector, ``FULL`` R1, ``REDUCED_BACKWARD`` R3 in reversed time) that
:func:`field` dispatches on, and the one step of each method -- :func:`dop853_step`,
:func:`taylor_step`, :func:`split_step` -- that every loop takes before observing it.
"""
from explorer._jit import njit
from explorer.integrate._lanes_generated import taylor_coefficients
from explorer.integrate._tangent_lanes_generated import tangent_coefficients
from explorer.kernels import STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW
from explorer.kernels import dop853 as dp
from explorer.kernels import taylor as tk
from explorer.kernels.checks import all_finite, is_finite
from explorer.kernels.clock import clip_step, resolves
from explorer.model.equations import (
    FULL_DIM,
    apply_flow,
    apply_flow_tangent,
    rhs,
    rhs_full,
    rhs_tangent,
)

REDUCED = 0
TANGENT = 1
FULL = 2
#: R3 backward in time, y(t0 - s) as a function of s (the section map's inverse,
#: :func:`explorer.integrate.tangent.return_map_taylor`)
REDUCED_BACKWARD = 3
#: state dimension of each system
DIMENSION = {REDUCED: 5, TANGENT: 10, FULL: FULL_DIM, REDUCED_BACKWARD: 5}
#: an accepted step (not a kernel status)
STEP_OK = -1
#: the ``h_abs`` a loop gives :func:`dop853_step` before its first step (no step proposed yet)
FIRST_STEP = -1.0
#: rows of the orbit itself in every system's state (the rest: deviation vector, position)
N_ORBIT = 5


@njit(inline="always")
def field(system, y, P, dy):
    """dy = f(y) of ``system``."""
    if system == REDUCED:
        rhs(y, P, dy)                          # docs/model.md R3
    elif system == TANGENT:
        _rhs_augmented(y, P, dy)
    elif system == FULL:
        rhs_full(y, P, dy)                     # docs/model.md R1
    else:
        rhs(y, P, dy)
        for i in range(dy.shape[0]):
            dy[i] = -dy[i]


@njit
def _rhs_augmented(z, P, dz):
    rhs(z[:5], P, dz[:5])
    rhs_tangent(z[:5], z[5:], P, dz[5:])


@njit
def dop853_first_step(system, y, P, K, rtol, atol, span, tmp):
    """K[0] = f(y) and scipy's initial step for an integration over ``span``."""
    field(system, y, P, K[0])
    h0 = dp.initial_step_part1(y, K[0], rtol, atol, span, 1.0, tmp)
    field(system, tmp, P, K[1])
    return dp.initial_step_part2(y, K[0], K[1], h0, rtol, atol, span)


@njit(inline="always")
def dop853_step(system, y, P, K, t, tend, end_code, h_abs, steps, max_steps, rtol, atol, tmp, ynew, fsal):
    """One accepted step from ``y`` at time ``t`` towards ``tend`` (K[0] = f(y) on entry), with
    rejected attempts retried at the smaller step the controller proposes; ``end_code`` (with
    h = 0) when ``t`` has reached ``tend``."""
    if not (t < tend):
        return end_code, 0.0, False, h_abs, steps
    if h_abs == FIRST_STEP:
        h_abs = dop853_first_step(system, y, P, K, rtol, atol, tend - t, tmp)
    rejected = False
    while True:
        if steps >= max_steps:
            return STATUS_MAX_STEPS, 0.0, False, h_abs, steps
        if dp.step_too_small(t, h_abs):
            return STATUS_STEP_UNDERFLOW, 0.0, False, h_abs, steps
        h, last = clip_step(t, h_abs, tend)
        for s in range(1, 12):
            dp.stage_input(y, K, s, h, tmp)
            field(system, tmp, P, K[s])
        dp.step_solution(y, K, h, ynew)
        err = dp.error_norm(y, ynew, K, h, rtol, atol)
        steps += 1
        if not (err == err) or not all_finite(ynew):
            return STATUS_NONFINITE, h, last, h_abs, steps
        if err < 1.0:
            if fsal:
                field(system, ynew, P, K[12])
            return STEP_OK, h, last, h_abs * dp.accepted_factor(err, rejected), steps
        h_abs *= dp.step_factor(err)
        rejected = True


@njit
def dop853_dense_stages(system, y, P, K, h, tmp):
    """The three extra stages K[13..15] of the 7th-order continuous extension (computed only in
    steps whose dense output is used)."""
    for s in range(13, 16):
        dp.stage_input(y, K, s, h, tmp)
        field(system, tmp, P, K[s])


@njit(inline="always")
def taylor_coefficients_of(system, P, X, order):
    """The normalised Taylor coefficients X[i, k] = y_i^(k)/k!, k = 0..order, of ``system`` from
    X[:, 0] by its recurrence, generated from explorer.model.chaplygin (tools/gen_lanes.py): R3
    (``REDUCED``), or R3 and its variational equations (``TANGENT``: rows 5..9 the deviation
    vector), or R3's in reversed time
    (``REDUCED_BACKWARD``: y(t0 - s) has the coefficients (-1)^k X_k, exactly)."""
    if system == REDUCED:
        taylor_coefficients(P, X, order)
    elif system == TANGENT:
        tangent_coefficients(P, X, order)
    else:
        taylor_coefficients(P, X, order)
        reverse_time(X, order)


@njit
def reverse_time(X, order):
    """The Taylor coefficients of y(t0 - s) from those of y(t0 + t): X[i, k] -> (-1)^k X[i, k]."""
    for k in range(1, order + 1, 2):
        for i in range(X.shape[0]):
            X[i, k] = -X[i, k]


@njit
def _finite_column(X, k, n):
    s = 0.0
    for i in range(n):
        s += X[i, k]
    return is_finite(s)


@njit(inline="always")
def taylor_step(system, X, P, t, tend, end_code, order, factor, steps, max_steps, ynew):
    """One step of the adaptive Taylor method of ``order`` from the state X[:, 0] at time ``t``
    towards ``tend``; ``end_code`` (with h = 0) when ``t`` has reached ``tend``."""
    if not (t < tend):
        return end_code, 0.0, False, steps
    if steps >= max_steps:
        return STATUS_MAX_STEPS, 0.0, False, steps
    taylor_coefficients_of(system, P, X, order)
    if not (_finite_column(X, order, N_ORBIT) and _finite_column(X, order - 1, N_ORBIT)):
        return STATUS_NONFINITE, 0.0, False, steps
    h = tk.step_size(X[:N_ORBIT], order, factor)
    h, last = clip_step(t, h, tend)
    if not resolves(t, h):
        return STATUS_STEP_UNDERFLOW, 0.0, False, steps
    tk.evaluate(X, order, h, ynew)
    steps += 1
    if not all_finite(ynew):
        return STATUS_NONFINITE, h, last, steps
    return STEP_OK, h, last, steps


@njit(inline="always")
def compose(system, y, P, dt, flow_ids, fracs):
    """One step ``dt`` of the composition (flow_ids, fracs) of the exact sub-flows of R4, in
    place: the orbit (``REDUCED``), or the orbit and its deviation vector by the sub-flows'
    exact tangent maps (``TANGENT``)."""
    for i in range(flow_ids.shape[0]):
        if system == REDUCED:
            apply_flow(flow_ids[i], y, P, fracs[i] * dt)
        else:
            apply_flow_tangent(flow_ids[i], y[:N_ORBIT], y[N_ORBIT:], P, fracs[i] * dt)


@njit(inline="always")
def split_step(system, y, P, dt, flow_ids, fracs, steps, max_steps, ynew):
    """One step of a splitting method from ``y`` into ``ynew`` (the loop decides when its span
    ends: t_n = n dt is never summed)."""
    if steps >= max_steps:
        return STATUS_MAX_STEPS, steps
    for i in range(y.shape[0]):
        ynew[i] = y[i]
    compose(system, ynew, P, dt, flow_ids, fracs)
    steps += 1
    if not all_finite(ynew):
        return STATUS_NONFINITE, steps
    return STEP_OK, steps
