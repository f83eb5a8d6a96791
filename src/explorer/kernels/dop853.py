"""Model-agnostic adaptive DOP853 (Dormand & Prince; Hairer, Norsett & Wanner, Solving ODEs I,
II.4-II.6, and ``dop853.f``) as Numba kernels, one step in pieces; the arithmetic of
``scipy.integrate.DOP853`` up to summation order (docs/methods.md).

The caller owns f and evaluates it between the kernels (kernel contract,
explorer/kernels/__init__.py); ``K`` is the (16, n) stage array, ``K[0] = f(t, y)`` (FSAL).  One
attempt: ``stage_input`` and f for stages 1..11, :func:`step_solution`, :func:`error_norm`
(reads K[0..11]); accept if err < 1, then K[12] = f(t + h, y_new), optionally stages 13..15 and
:func:`dense_coefficients`; the next |h| is ``abs(h) * step_factor(err)`` (or
``step_factor_after_reject`` after a rejection).  Clamping and clipping of h are the caller's.
"""
import numpy as np

from explorer._jit import njit
from explorer.kernels.dop853_coefficients import (
    E3,
    E5,
    ERROR_ESTIMATOR_ORDER,
    INTERPOLATOR_POWER,
    N_STAGES,
    N_STAGES_EXTENDED,
    A,
    B,
    D,
)

# Step-size controller (Hairer-Norsett-Wanner II.4, values as in SciPy).
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
ERROR_EXPONENT = -1.0 / (ERROR_ESTIMATOR_ORDER + 1)

# Hairer's combined estimator: err = err5^2 / sqrt(err5^2 + E3_WEIGHT^2 err3^2)
E3_WEIGHT_SQUARED = 0.01

# Starting-step heuristic (Hairer-Norsett-Wanner II.4, "Starting step size").
INITIAL_SMALL_NORM = 1e-5
INITIAL_FALLBACK_STEP = 1e-6
INITIAL_STEP_FRACTION = 0.01  # h0 = 0.01 * d0 / d1, h1 from 0.01 / max(d1, d2)
INITIAL_TINY_DERIVATIVE = 1e-15  # d1, d2 both below: h1 = max(1e-6, 1e-3 h0)
INITIAL_TINY_SHRINK = 1e-3
INITIAL_MAX_GROWTH = 100.0


@njit
def stage_input(y, K, s, h, out):
    """Argument of stage ``s``: out = y + h * sum_{j<s} A[s, j] K[j]."""
    n = y.shape[0]
    for i in range(n):
        acc = 0.0
        for j in range(s):
            acc += A[s, j] * K[j, i]
        out[i] = y[i] + acc * h


@njit
def step_solution(y, K, h, y_new):
    """8th-order solution: y_new = y + h * sum_{j<12} B[j] K[j]."""
    n = y.shape[0]
    for i in range(n):
        acc = 0.0
        for j in range(N_STAGES):
            acc += B[j] * K[j, i]
        y_new[i] = y[i] + acc * h


@njit
def error_norm(y, y_new, K, h, rtol, atol):
    """Hairer's combined error norm of the step (SciPy's
    ``DOP853._estimate_error_norm``)."""
    n = y.shape[0]
    e5_sq = 0.0
    e3_sq = 0.0
    for i in range(n):
        a5 = 0.0
        a3 = 0.0
        for j in range(N_STAGES):
            a5 += E5[j] * K[j, i]
            a3 += E3[j] * K[j, i]
        sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
        r5 = a5 / sc
        r3 = a3 / sc
        e5_sq += r5 * r5
        e3_sq += r3 * r3
    if e5_sq == 0.0 and e3_sq == 0.0:
        return 0.0
    denom = e5_sq + E3_WEIGHT_SQUARED * e3_sq
    return abs(h) * e5_sq / np.sqrt(denom * n)


@njit
def step_factor(err_norm):
    """Factor for the next |h| (SciPy ``RungeKutta._step_impl``)."""
    if err_norm < 1.0:
        if err_norm == 0.0:
            return MAX_FACTOR
        f = SAFETY * err_norm ** ERROR_EXPONENT
        if f > MAX_FACTOR:
            return MAX_FACTOR
        return f
    f = SAFETY * err_norm ** ERROR_EXPONENT
    if f > MIN_FACTOR:
        return f
    return MIN_FACTOR


@njit
def step_factor_after_reject(err_norm):
    """Like :func:`step_factor`, for an attempt that follows a rejection of
    the same step: SciPy sets ``factor = min(1, factor)`` on acceptance, so
    the step never grows right after a rejection.  Rejections are unchanged."""
    f = step_factor(err_norm)
    if err_norm < 1.0 and f > 1.0:
        return 1.0
    return f


#: smallest step relative to the spacing of floats at t (scipy's min_step rule)
MIN_STEP_ULPS = 10.0


@njit
def step_too_small(t, h_abs):
    """True when |h| < 10 ulp(t): the step size has underflowed against the clock."""
    return h_abs < MIN_STEP_ULPS * abs(np.nextafter(t, np.inf) - t)


@njit
def accepted_factor(err_norm, rejected_before):
    """Factor for |h| after an accepted step (no growth right after a rejection)."""
    if rejected_before:
        return step_factor_after_reject(err_norm)
    return step_factor(err_norm)


@njit
def _rms_scaled(v, y, rtol, atol):
    """RMS norm of v / (atol + rtol |y|)."""
    n = y.shape[0]
    acc = 0.0
    for i in range(n):
        r = v[i] / (atol + abs(y[i]) * rtol)
        acc += r * r
    return np.sqrt(acc) / np.sqrt(n)


@njit
def initial_step_part1(y, f0, rtol, atol, h_max, direction, y1):
    """First half of SciPy's ``select_initial_step`` (HNW II.4)."""
    n = y.shape[0]
    if n == 0:
        return np.inf
    if h_max == 0.0:
        for i in range(n):
            y1[i] = y[i]
        return 0.0
    d0 = _rms_scaled(y, y, rtol, atol)
    d1 = _rms_scaled(f0, y, rtol, atol)
    if d0 < INITIAL_SMALL_NORM or d1 < INITIAL_SMALL_NORM:
        h0 = INITIAL_FALLBACK_STEP
    else:
        h0 = INITIAL_STEP_FRACTION * d0 / d1
    if h0 > h_max:
        h0 = h_max
    hd = h0 * direction
    for i in range(n):
        y1[i] = y[i] + hd * f0[i]
    return h0


@njit
def initial_step_part2(y, f0, f1, h0, rtol, atol, h_max,
                       order=ERROR_ESTIMATOR_ORDER):
    """Second half of SciPy's ``select_initial_step``: returns |h| for the
    first step."""
    n = y.shape[0]
    if n == 0:
        return np.inf
    if h0 == 0.0:
        return 0.0
    d1 = _rms_scaled(f0, y, rtol, atol)
    acc = 0.0
    for i in range(n):
        r = (f1[i] - f0[i]) / (atol + abs(y[i]) * rtol)
        acc += r * r
    d2 = np.sqrt(acc) / np.sqrt(n) / h0
    if d1 <= INITIAL_TINY_DERIVATIVE and d2 <= INITIAL_TINY_DERIVATIVE:
        h1 = max(INITIAL_FALLBACK_STEP, h0 * INITIAL_TINY_SHRINK)
    else:
        h1 = (INITIAL_STEP_FRACTION / max(d1, d2)) ** (1.0 / (order + 1))
    h = INITIAL_MAX_GROWTH * h0
    if h1 < h:
        h = h1
    if h_max < h:
        h = h_max
    return h


@njit
def dense_coefficients(y_old, y_new, K, h, F):
    """Coefficients F (7, n) of the continuous extension of an accepted step
    (SciPy ``DOP853._dense_output_impl``)."""
    n = y_old.shape[0]
    for i in range(n):
        dy = y_new[i] - y_old[i]
        f_old = K[0, i]
        F[0, i] = dy
        F[1, i] = h * f_old - dy
        F[2, i] = 2.0 * dy - h * (K[N_STAGES, i] + f_old)
        for r in range(INTERPOLATOR_POWER - 3):
            acc = 0.0
            for j in range(N_STAGES_EXTENDED):
                acc += D[r, j] * K[j, i]
            F[3 + r, i] = h * acc


@njit
def dense_eval(F, y_old, theta, out):
    """Evaluate the dense output at theta = (t - t_old) / h in [0, 1] (SciPy ``Dop853DenseOutput``):
    y = y_old + th (F0 + (1-th) (F1 + th (F2 + (1-th) (F3 + th (F4 + (1-th) (F5 + th F6))))))."""
    n = y_old.shape[0]
    m = 1.0 - theta
    for i in range(n):
        acc = 0.0
        for k in range(INTERPOLATOR_POWER):
            acc += F[INTERPOLATOR_POWER - 1 - k, i]
            if k % 2 == 0:
                acc *= theta
            else:
                acc *= m
        out[i] = acc + y_old[i]


@njit
def dense_eval_scalar(Fg, g_old, theta):
    """Dense output of one linear functional g = w . y:
    ``Fg = F @ w`` (7,), ``g_old = w . y_old``."""
    m = 1.0 - theta
    acc = 0.0
    for k in range(INTERPOLATOR_POWER):
        acc += Fg[INTERPOLATOR_POWER - 1 - k]
        if k % 2 == 0:
            acc *= theta
        else:
            acc *= m
    return acc + g_old


@njit
def dense_eval_scalar_derivative(Fg, h, theta):
    """d/dt of :func:`dense_eval_scalar` (i.e. d/dtheta divided by h)."""
    m = 1.0 - theta
    acc = 0.0
    dacc = 0.0
    for k in range(INTERPOLATOR_POWER):
        acc += Fg[INTERPOLATOR_POWER - 1 - k]
        if k % 2 == 0:  # multiply by theta, d/dtheta theta = 1
            dacc = dacc * theta + acc
            acc *= theta
        else:
            dacc = dacc * m - acc
            acc *= m
    return dacc / h
