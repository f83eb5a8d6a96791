# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from its templates STEPS and its list SYSTEMS.
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""Each method's one step for each system of the scalar drivers (docs/architecture.md, "The system
seam"): the step written once, in a template, and rendered with each system's field, recurrence and
sub-flows, so a loop calls its system's step by name:

- ``*_reduced``: R3 (docs/model.md), 5 variables
- ``*_tangent``: R3 and one deviation vector (rows 5..9), 10 variables
- ``*_full``: R1 (docs/model.md) with the position, FULL_DIM variables
- ``*_backward``: R3 in reversed time, y(t0 - s) of s
"""
from explorer._jit import njit
from explorer.integrate._lanes_generated import taylor_coefficients
from explorer.integrate.systems import FIRST_STEP, N_ORBIT, STEP_OK, finite_column, reverse_time, rhs_augmented
from explorer.kernels import STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW
from explorer.kernels import dop853 as dp
from explorer.kernels import taylor as tk
from explorer.kernels.checks import all_finite
from explorer.kernels.clock import clip_step, resolves
from explorer.model.equations import apply_flow, apply_flow_tangent, rhs, rhs_full


@njit(inline="always")
def field_reduced(y, P, dy):
    """dy = f(y) of R3 (docs/model.md), 5 variables."""
    rhs(y, P, dy)


@njit
def dop853_first_step_reduced(y, P, K, rtol, atol, span, tmp):
    """K[0] = f(y) and scipy's initial step for an integration over ``span``."""
    field_reduced(y, P, K[0])
    h0 = dp.initial_step_part1(y, K[0], rtol, atol, span, 1.0, tmp)
    field_reduced(tmp, P, K[1])
    return dp.initial_step_part2(y, K[0], K[1], h0, rtol, atol, span)


@njit(inline="always")
def dop853_step_reduced(y, P, K, t, tend, end_code, h_abs, steps, max_steps, rtol, atol, tmp, ynew, fsal):
    """One accepted DOP853 step (Hairer, Nørsett & Wanner) from ``y`` at time ``t`` towards ``tend``
    (K[0] = f(y) on entry), rejected attempts retried at the controller's smaller step; ``end_code``
    (h = 0) when ``t`` has reached ``tend``.  Returns (code, h, last, h_abs, steps)."""
    if not (t < tend):
        return end_code, 0.0, False, h_abs, steps
    if h_abs == FIRST_STEP:
        h_abs = dop853_first_step_reduced(y, P, K, rtol, atol, tend - t, tmp)
    rejected = False
    while True:
        if steps >= max_steps:
            return STATUS_MAX_STEPS, 0.0, False, h_abs, steps
        if dp.step_too_small(t, h_abs):
            return STATUS_STEP_UNDERFLOW, 0.0, False, h_abs, steps
        h, last = clip_step(t, h_abs, tend)
        for s in range(1, 12):
            dp.stage_input(y, K, s, h, tmp)
            field_reduced(tmp, P, K[s])
        dp.step_solution(y, K, h, ynew)
        err = dp.error_norm(y, ynew, K, h, rtol, atol)
        steps += 1
        if not (err == err) or not all_finite(ynew):
            return STATUS_NONFINITE, h, last, h_abs, steps
        if err < 1.0:
            if fsal:
                field_reduced(ynew, P, K[12])
            return STEP_OK, h, last, h_abs * dp.accepted_factor(err, rejected), steps
        h_abs *= dp.step_factor(err)
        rejected = True


@njit
def dop853_dense_stages_reduced(y, P, K, h, tmp):
    """The three extra stages K[13..15] of the 7th-order continuous extension."""
    for s in range(13, 16):
        dp.stage_input(y, K, s, h, tmp)
        field_reduced(tmp, P, K[s])


@njit(inline="always")
def taylor_coefficients_reduced(P, X, order):
    """X[i, k] = y_i^(k)/k!, k = 0..order, from X[:, 0]: R3 (docs/model.md), 5 variables."""
    taylor_coefficients(P, X, order)


@njit(inline="always")
def taylor_step_reduced(X, P, t, tend, end_code, order, factor, steps, max_steps, ynew):
    """One step of the adaptive Taylor method of ``order`` (Jorba & Zou 2005) from X[:, 0] at time ``t``
    towards ``tend``, its size from the orbit's rows; ``end_code`` (h = 0) when ``t`` has reached ``tend``.
    Returns (code, h, last, steps)."""
    if not (t < tend):
        return end_code, 0.0, False, steps
    if steps >= max_steps:
        return STATUS_MAX_STEPS, 0.0, False, steps
    taylor_coefficients_reduced(P, X, order)
    if not (finite_column(X, order, N_ORBIT) and finite_column(X, order - 1, N_ORBIT)):
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
def compose_reduced(y, P, dt, flow_ids, fracs):
    """One step ``dt`` of the composition (flow_ids, fracs) of the exact sub-flows of R4 (docs/model.md),
    in place, for R3 (docs/model.md), 5 variables."""
    for i in range(flow_ids.shape[0]):
        apply_flow(flow_ids[i], y, P, fracs[i] * dt)


@njit(inline="always")
def split_step_reduced(y, P, dt, flow_ids, fracs, steps, max_steps, ynew):
    """One step of a splitting method from ``y`` into ``ynew`` (the loop decides when its span ends:
    t_n = n dt is never summed).  Returns (code, steps)."""
    if steps >= max_steps:
        return STATUS_MAX_STEPS, steps
    for i in range(y.shape[0]):
        ynew[i] = y[i]
    compose_reduced(ynew, P, dt, flow_ids, fracs)
    steps += 1
    if not all_finite(ynew):
        return STATUS_NONFINITE, steps
    return STEP_OK, steps


@njit(inline="always")
def field_tangent(y, P, dy):
    """dy = f(y) of R3 and one deviation vector (rows 5..9), 10 variables."""
    rhs_augmented(y, P, dy)


@njit
def dop853_first_step_tangent(y, P, K, rtol, atol, span, tmp):
    """K[0] = f(y) and scipy's initial step for an integration over ``span``."""
    field_tangent(y, P, K[0])
    h0 = dp.initial_step_part1(y, K[0], rtol, atol, span, 1.0, tmp)
    field_tangent(tmp, P, K[1])
    return dp.initial_step_part2(y, K[0], K[1], h0, rtol, atol, span)


@njit(inline="always")
def dop853_step_tangent(y, P, K, t, tend, end_code, h_abs, steps, max_steps, rtol, atol, tmp, ynew, fsal):
    """One accepted DOP853 step (Hairer, Nørsett & Wanner) from ``y`` at time ``t`` towards ``tend``
    (K[0] = f(y) on entry), rejected attempts retried at the controller's smaller step; ``end_code``
    (h = 0) when ``t`` has reached ``tend``.  Returns (code, h, last, h_abs, steps)."""
    if not (t < tend):
        return end_code, 0.0, False, h_abs, steps
    if h_abs == FIRST_STEP:
        h_abs = dop853_first_step_tangent(y, P, K, rtol, atol, tend - t, tmp)
    rejected = False
    while True:
        if steps >= max_steps:
            return STATUS_MAX_STEPS, 0.0, False, h_abs, steps
        if dp.step_too_small(t, h_abs):
            return STATUS_STEP_UNDERFLOW, 0.0, False, h_abs, steps
        h, last = clip_step(t, h_abs, tend)
        for s in range(1, 12):
            dp.stage_input(y, K, s, h, tmp)
            field_tangent(tmp, P, K[s])
        dp.step_solution(y, K, h, ynew)
        err = dp.error_norm(y, ynew, K, h, rtol, atol)
        steps += 1
        if not (err == err) or not all_finite(ynew):
            return STATUS_NONFINITE, h, last, h_abs, steps
        if err < 1.0:
            if fsal:
                field_tangent(ynew, P, K[12])
            return STEP_OK, h, last, h_abs * dp.accepted_factor(err, rejected), steps
        h_abs *= dp.step_factor(err)
        rejected = True


@njit
def dop853_dense_stages_tangent(y, P, K, h, tmp):
    """The three extra stages K[13..15] of the 7th-order continuous extension."""
    for s in range(13, 16):
        dp.stage_input(y, K, s, h, tmp)
        field_tangent(tmp, P, K[s])


@njit(inline="always")
def compose_tangent(y, P, dt, flow_ids, fracs):
    """One step ``dt`` of the composition (flow_ids, fracs) of the exact sub-flows of R4 (docs/model.md),
    in place, for R3 and one deviation vector (rows 5..9), 10 variables."""
    for i in range(flow_ids.shape[0]):
        apply_flow_tangent(flow_ids[i], y[:N_ORBIT], y[N_ORBIT:], P, fracs[i] * dt)


@njit(inline="always")
def split_step_tangent(y, P, dt, flow_ids, fracs, steps, max_steps, ynew):
    """One step of a splitting method from ``y`` into ``ynew`` (the loop decides when its span ends:
    t_n = n dt is never summed).  Returns (code, steps)."""
    if steps >= max_steps:
        return STATUS_MAX_STEPS, steps
    for i in range(y.shape[0]):
        ynew[i] = y[i]
    compose_tangent(ynew, P, dt, flow_ids, fracs)
    steps += 1
    if not all_finite(ynew):
        return STATUS_NONFINITE, steps
    return STEP_OK, steps


@njit(inline="always")
def field_full(y, P, dy):
    """dy = f(y) of R1 (docs/model.md) with the position, FULL_DIM variables."""
    rhs_full(y, P, dy)


@njit
def dop853_first_step_full(y, P, K, rtol, atol, span, tmp):
    """K[0] = f(y) and scipy's initial step for an integration over ``span``."""
    field_full(y, P, K[0])
    h0 = dp.initial_step_part1(y, K[0], rtol, atol, span, 1.0, tmp)
    field_full(tmp, P, K[1])
    return dp.initial_step_part2(y, K[0], K[1], h0, rtol, atol, span)


@njit(inline="always")
def dop853_step_full(y, P, K, t, tend, end_code, h_abs, steps, max_steps, rtol, atol, tmp, ynew, fsal):
    """One accepted DOP853 step (Hairer, Nørsett & Wanner) from ``y`` at time ``t`` towards ``tend``
    (K[0] = f(y) on entry), rejected attempts retried at the controller's smaller step; ``end_code``
    (h = 0) when ``t`` has reached ``tend``.  Returns (code, h, last, h_abs, steps)."""
    if not (t < tend):
        return end_code, 0.0, False, h_abs, steps
    if h_abs == FIRST_STEP:
        h_abs = dop853_first_step_full(y, P, K, rtol, atol, tend - t, tmp)
    rejected = False
    while True:
        if steps >= max_steps:
            return STATUS_MAX_STEPS, 0.0, False, h_abs, steps
        if dp.step_too_small(t, h_abs):
            return STATUS_STEP_UNDERFLOW, 0.0, False, h_abs, steps
        h, last = clip_step(t, h_abs, tend)
        for s in range(1, 12):
            dp.stage_input(y, K, s, h, tmp)
            field_full(tmp, P, K[s])
        dp.step_solution(y, K, h, ynew)
        err = dp.error_norm(y, ynew, K, h, rtol, atol)
        steps += 1
        if not (err == err) or not all_finite(ynew):
            return STATUS_NONFINITE, h, last, h_abs, steps
        if err < 1.0:
            if fsal:
                field_full(ynew, P, K[12])
            return STEP_OK, h, last, h_abs * dp.accepted_factor(err, rejected), steps
        h_abs *= dp.step_factor(err)
        rejected = True


@njit
def dop853_dense_stages_full(y, P, K, h, tmp):
    """The three extra stages K[13..15] of the 7th-order continuous extension."""
    for s in range(13, 16):
        dp.stage_input(y, K, s, h, tmp)
        field_full(tmp, P, K[s])


@njit(inline="always")
def taylor_coefficients_backward(P, X, order):
    """X[i, k] = y_i^(k)/k!, k = 0..order, from X[:, 0]: R3 in reversed time, y(t0 - s) of s."""
    taylor_coefficients(P, X, order)
    reverse_time(X, order)


@njit(inline="always")
def taylor_step_backward(X, P, t, tend, end_code, order, factor, steps, max_steps, ynew):
    """One step of the adaptive Taylor method of ``order`` (Jorba & Zou 2005) from X[:, 0] at time ``t``
    towards ``tend``, its size from the orbit's rows; ``end_code`` (h = 0) when ``t`` has reached ``tend``.
    Returns (code, h, last, steps)."""
    if not (t < tend):
        return end_code, 0.0, False, steps
    if steps >= max_steps:
        return STATUS_MAX_STEPS, 0.0, False, steps
    taylor_coefficients_backward(P, X, order)
    if not (finite_column(X, order, N_ORBIT) and finite_column(X, order - 1, N_ORBIT)):
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
