"""Model-agnostic adaptive DOP853 as Numba kernels (one step in pieces).

Explicit Runge-Kutta method of order 8 by Dormand & Prince with Hairer's
combined 5th/3rd-order error estimator, the standard step-size controller and
the 7th-degree continuous extension, following

    E. Hairer, S. P. Norsett, G. Wanner, "Solving Ordinary Differential
    Equations I: Nonstiff Problems", 2nd ed., Springer 1993,
    Sec. II.4 (step-size control, starting step) and II.6 (dense output),
    and Hairer's Fortran code ``dop853.f``.

The arithmetic reproduces ``scipy.integrate.DOP853`` (``scipy/integrate/_ivp/
rk.py``: ``rk_step``, ``RungeKutta._step_impl``, ``DOP853._estimate_error_norm``,
``DOP853._dense_output_impl``, ``Dop853DenseOutput``; ``common.py``:
``select_initial_step``).  Results agree with SciPy to rounding; the only
differences are summation orders inside dot products.  Note that the error
estimate sum_j E5[j] K[j] is a strong cancellation (condition numbers up to
~1e13 when err is tiny), so SciPy's np.dot and the loop here give error norms
that differ by up to cond * eps; since the step factor is err**(-1/8), free
runs agree in the number of steps and evaluations but their t grids only to
~1e-8 relative (the tests quantify this).

No kernel takes a function argument (that would defeat Numba's on-disk
cache).  The caller owns the right-hand side f(t, y) and evaluates it between
the kernels.  Every kernel works on C-contiguous float64 arrays, writes into
preallocated outputs, allocates nothing and raises nothing.  ``K`` is the
stage array of shape (16, n); output arrays must not alias ``y`` or ``K``
(except where stated).

Caller protocol for one attempt of a step of size ``h`` (signed) from (t, y),
with ``K[0] = f(t, y)`` already stored (FSAL: it is ``K[12]`` of the previous
accepted step)::

    for s in range(1, 12):
        stage_input(y, K, s, h, tmp);  K[s] = f(t + C[s] * h, tmp)
    step_solution(y, K, h, y_new)
    err = error_norm(y, y_new, K, h, rtol, atol)     # reads K[0..11] only
    if err < 1.0:                                    # accept (strictly < 1)
        K[12] = f(t + h, y_new)                      # FSAL stage = next K[0]
        # optional dense output of this step (needs K[12]):
        for s in (13, 14, 15):
            stage_input(y, K, s, h, tmp);  K[s] = f(t + C[s] * h, tmp)
        dense_coefficients(y, y_new, K, h, F)
        fac = step_factor_after_reject(err) if rejected_before else step_factor(err)
        h_abs = abs(h) * fac;  rejected_before = False
        t, y, K[0] = t + h, y_new, K[12]
    else:                                            # reject, retry from (t, y)
        h_abs = abs(h) * step_factor(err);  rejected_before = True

SciPy evaluates ``K[12] = f(t + h, y_new)`` before the error estimate, even
for rejected attempts.  Because ``E3[12] == E5[12] == 0`` that stage does not
enter the estimate, so ``error_norm`` does not read it and the caller may
defer the evaluation to acceptance (as ``dop853.f`` does) without changing a
single accepted step.  (Only difference: if f(y_new) is non-finite SciPy's
estimate becomes NaN and the attempt is rejected; a caller that defers must
check f(y_new) itself if it wants that behaviour.)

SciPy additionally clamps ``h_abs`` to ``[min_step, max_step]`` with
``min_step = 10 * |nextafter(t, direction*inf) - t|`` and clips the step at
``t_bound``; that is caller policy and not part of these kernels.
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
SAFETY = 0.9  # multiply the asymptotically optimal factor by this
MIN_FACTOR = 0.2  # largest allowed decrease of the step in one go
MAX_FACTOR = 10.0  # largest allowed increase of the step in one go
ERROR_EXPONENT = -1.0 / (ERROR_ESTIMATOR_ORDER + 1)  # = -1/8

# Hairer's combined estimator: err = err5^2 / sqrt(err5^2 + E3_WEIGHT^2 err3^2)
E3_WEIGHT_SQUARED = 0.01

# Starting-step heuristic (Hairer-Norsett-Wanner II.4, "Starting step size").
INITIAL_SMALL_NORM = 1e-5  # d0 or d1 below this: use INITIAL_FALLBACK_STEP
INITIAL_FALLBACK_STEP = 1e-6
INITIAL_STEP_FRACTION = 0.01  # h0 = 0.01 * d0 / d1, h1 from 0.01 / max(d1, d2)
INITIAL_TINY_DERIVATIVE = 1e-15  # d1, d2 both below: h1 = max(1e-6, 1e-3 h0)
INITIAL_TINY_SHRINK = 1e-3
INITIAL_MAX_GROWTH = 100.0  # h <= 100 * h0


@njit
def stage_input(y, K, s, h, out):
    """Argument of stage ``s``: out = y + h * sum_{j<s} A[s, j] K[j].

    Valid for s = 1..15 (11 main stages, and the extra dense-output stages
    13, 14, 15, which also use K[12] = f(y_new)).  The stage time is
    ``t + C[s] * h``.  ``out`` may alias ``y`` but not ``K``.
    """
    n = y.shape[0]
    for i in range(n):
        acc = 0.0
        for j in range(s):
            acc += A[s, j] * K[j, i]
        out[i] = y[i] + acc * h


@njit
def step_solution(y, K, h, y_new):
    """8th-order solution: y_new = y + h * sum_{j<12} B[j] K[j].

    ``y_new`` may alias ``y`` (each component is finished before the next)."""
    n = y.shape[0]
    for i in range(n):
        acc = 0.0
        for j in range(N_STAGES):
            acc += B[j] * K[j, i]
        y_new[i] = y[i] + acc * h


@njit
def error_norm(y, y_new, K, h, rtol, atol):
    """Hairer's combined error norm of the step (SciPy's
    ``DOP853._estimate_error_norm``).

    With scale_i = atol + rtol * max(|y_i|, |y_new_i|),
    e5_i = (K^T E5)_i / scale_i and e3_i = (K^T E3)_i / scale_i::

        err = |h| * ||e5||^2 / sqrt(n * (||e5||^2 + 0.01 ||e3||^2))

    (0 if both norms vanish).  Accept the step iff err < 1.  Only K[0..11]
    are read: the FSAL stage K[12] has zero weight in E3 and E5.
    """
    n = y.shape[0]
    e5_sq = 0.0
    e3_sq = 0.0
    for i in range(n):
        a5 = 0.0
        a3 = 0.0
        for j in range(N_STAGES):  # E3[12] == E5[12] == 0
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
    """Factor for the next |h| (SciPy ``RungeKutta._step_impl``).

    err_norm == 0      -> MAX_FACTOR
    0 < err_norm < 1   -> min(MAX_FACTOR, SAFETY * err_norm**(-1/8))  (accepted)
    err_norm >= 1      -> max(MIN_FACTOR, SAFETY * err_norm**(-1/8))  (rejected)
    NaN                -> MIN_FACTOR (treated as rejected, as SciPy does)

    After a rejection within the same step SciPy forbids growth on the
    eventual acceptance: use :func:`step_factor_after_reject` there.
    """
    if err_norm < 1.0:
        if err_norm == 0.0:
            return MAX_FACTOR
        f = SAFETY * err_norm ** ERROR_EXPONENT
        if f > MAX_FACTOR:
            return MAX_FACTOR
        return f
    f = SAFETY * err_norm ** ERROR_EXPONENT
    if f > MIN_FACTOR:  # False for NaN -> MIN_FACTOR
        return f
    return MIN_FACTOR


@njit
def step_factor_after_reject(err_norm):
    """Like :func:`step_factor`, for an attempt that follows a rejection of
    the same step: SciPy sets ``factor = min(1, factor)`` on acceptance, so
    the step never grows right after a rejection.  Rejections are unchanged.
    """
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
    """First half of SciPy's ``select_initial_step`` (HNW II.4).

    Returns the trial step h0 > 0 and fills y1 = y + (h0 * direction) * f0;
    the caller then evaluates f1 = f(t0 + h0 * direction, y1) and calls
    :func:`initial_step_part2`.

    ``h_max`` is SciPy's ``interval_length`` = |t_bound - t0| (for
    bitwise-identical behaviour do not fold ``max_step`` in here; it goes to
    part 2).  Degenerate cases as in SciPy: n == 0 -> inf, h_max == 0 -> 0
    (y1 = y is still filled).
    """
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
    first step.

    ``order`` is the *error-estimator* order; SciPy's DOP853 passes
    ``error_estimator_order = 7`` (so h1 = (0.01 / max(d1, d2))**(1/8)).
    ``h_max`` = min(|t_bound - t0|, max_step).  ``h0`` is the value returned
    by :func:`initial_step_part1`.
    """
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
    (SciPy ``DOP853._dense_output_impl``).

    Requires K[0..12] of the step (K[12] = f(t_old + h, y_new)) and the
    extra stages K[13..15]: for s in 13, 14, 15:
    ``stage_input(y_old, K, s, h, tmp); K[s] = f(t_old + C[s] * h, tmp)``.

    F[0] = y_new - y_old, F[1] = h K[0] - F[0],
    F[2] = 2 F[0] - h (K[12] + K[0]), F[3:7] = h * D @ K.
    """
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
    """Evaluate the dense output at theta = (t - t_old) / h in [0, 1]
    (SciPy ``Dop853DenseOutput``)::

        y(theta) = y_old + th (F0 + (1-th) (F1 + th (F2 + (1-th) (F3
                   + th (F4 + (1-th) (F5 + th F6))))))

    theta = 0 gives y_old exactly; theta = 1 gives y_old + (y_new - y_old).
    """
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
    ``Fg = F @ w`` (7,), ``g_old = w . y_old``.  Same nesting as
    :func:`dense_eval`."""
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
    """d/dt of :func:`dense_eval_scalar` (i.e. d/dtheta divided by h).

    Forward-mode differentiation of the nested product.  The interpolant is
    Hermite at the ends: the value at theta = 0 is w . f(t_old) and at
    theta = 1 it is w . f(t_old + h) (up to rounding).
    """
    m = 1.0 - theta
    acc = 0.0
    dacc = 0.0
    for k in range(INTERPOLATOR_POWER):
        acc += Fg[INTERPOLATOR_POWER - 1 - k]
        if k % 2 == 0:  # multiply by theta, d/dtheta theta = 1
            dacc = dacc * theta + acc
            acc *= theta
        else:  # multiply by (1 - theta), derivative -1
            dacc = dacc * m - acc
            acc *= m
    return dacc / h
