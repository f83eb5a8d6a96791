"""The system seam: which compiled vector field a stepping loop advances, and the one step of
each method (DOP853, Taylor, splitting) that does not depend on what is observed along the way.

A *system* is an integer id (no callables cross a compiled boundary: a jitted function passed
as an argument defeats Numba's on-disk cache, kernel contract rule 1); :func:`field` dispatches
on it.  The loops that use it -- crossings of the section (:mod:`explorer.integrate.drivers`,
DOP853 and splitting), tangent dynamics (:mod:`explorer.integrate.tangent`) and the body in the plane
(:mod:`explorer.integrate.full`) -- differ only in what they observe after an accepted step;
the step itself is written once here, per method:

- :func:`dop853_step` (the first step, the twelve stages, the solution, the error norm, the budget
  and non-finite checks, retries; :func:`dop853_dense_stages` the three dense-output stages);
- :func:`taylor_step` (the budgets, the Taylor coefficients of the system by its recurrence,
  their finiteness, the Jorba-Zou step from the orbit's own coefficients, the step clipped to
  the end of the span, the Horner evaluation, the non-finite check);
- :func:`split_step` (the step budget, one composition of the exact sub-flows of R4 -- with
  their exact tangent maps for ``TANGENT`` -- and the non-finite check).

A loop is then: take a step, observe it (crossings, tangent accumulators, samples), advance.

====================  ===  =================================================================
system                 n   state and field
====================  ===  =================================================================
``REDUCED``            5   (p1, p2, M, g1, g2), docs/model.md R3 (:func:`explorer.model.equations.rhs`)
``TANGENT``           10   R3 and one deviation vector, the variational equations of R3
``FULL``               7   R3 and the position (x, y), docs/model.md R1
``REDUCED_BACKWARD``   5   R3 in reversed time s = -t: the field -f, Taylor coefficients (-1)^k X_k
====================  ===  =================================================================

DOP853: Hairer, Nørsett & Wanner, *Solving ODEs I*, II.10 (tableau and continuous extension
in :mod:`explorer.kernels.dop853`; controller and first step as scipy's ``DOP853``).
Taylor: Jorba & Zou, Exp. Math. 14 (2005) 99 (order and step rules in
:mod:`explorer.kernels.taylor`).  Splitting: compositions of :mod:`explorer.kernels.splitting`
(Yoshida 1990; Kahan & Li 1997), tangent maps of the sub-flows as Skokos & Gerlach, Phys. Rev.
E 82 (2010) 036704.

The Taylor crossing loop runs on SIMD lanes (:mod:`explorer.integrate.lanes`): :func:`taylor_step`
of ``REDUCED`` with its arithmetic vectorised (the recurrence translated by ``tools/gen_lanes.py``)
and its control flow per lane; the scalar loop over :func:`taylor_step` of ``REDUCED`` is its
oracle in the tests (tests/integrate/taylor_oracle.py, bit for bit the same steps).
"""
from explorer._jit import njit
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
    taylor_coefficients,
    taylor_coefficients_tangent,
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


@njit(inline="always")  # inlined at Numba IR level: the tangent loop ~10 % faster (bench_ab.py)
def field(system, y, P, dy):
    """dy = f(y) of ``system``."""
    if system == REDUCED:
        rhs(y, P, dy)                          # docs/model.md R3
    elif system == TANGENT:
        _rhs_augmented(y, P, dy)
    elif system == FULL:
        rhs_full(y, P, dy)                     # docs/model.md R1
    else:
        rhs(y, P, dy)                          # d/ds y(t0 - s) = -f
        for i in range(dy.shape[0]):
            dy[i] = -dy[i]


@njit
def _rhs_augmented(z, P, dz):
    """R3 for z[:5] and its variational equations for the deviation z[5:] (the views are made
    here, not in :func:`field`, so that the other systems' steps carry no view bookkeeping)."""
    rhs(z[:5], P, dz[:5])
    rhs_tangent(z[:5], z[5:], P, dz[5:])


@njit
def dop853_first_step(system, y, P, K, rtol, atol, span, tmp):
    """K[0] = f(y) and scipy's initial step for an integration over ``span``."""
    field(system, y, P, K[0])
    h0 = dp.initial_step_part1(y, K[0], rtol, atol, span, 1.0, tmp)
    field(system, tmp, P, K[1])
    return dp.initial_step_part2(y, K[0], K[1], h0, rtol, atol, span)


@njit(inline="always")  # inlined into each loop (a call costs ~10 % of a tangent step)
def dop853_step(system, y, P, K, t, tend, end_code, h_abs, steps, max_steps, rtol, atol, tmp, ynew, fsal):
    """One accepted step from ``y`` at time ``t`` towards ``tend`` (K[0] = f(y) on entry), with
    rejected attempts retried at the smaller step the controller proposes; ``end_code`` (with
    h = 0) when ``t`` has reached ``tend``.

    Each attempt: the budget checks, the step clipped to ``tend``, the eleven stages, the solution
    and the error norm.  Returns (code, h, last, h_abs, steps): ``code`` is ``STEP_OK`` (``ynew``
    holds the solution at t + h; ``last``: the step reaches ``tend``; ``h_abs`` is the next step
    proposed), ``STATUS_MAX_STEPS`` or ``STATUS_STEP_UNDERFLOW`` (a budget ran out before an
    attempt) or ``STATUS_NONFINITE`` (the error or the solution is not finite).  ``steps`` counts
    attempts.  With ``fsal`` an accepted step also sets K[12] = f(ynew) (first same as last; the
    tangent loop renormalises first, so it computes f itself).  With ``h_abs`` = FIRST_STEP
    (a loop's first call) it starts the integration: K[0] = f(y) and scipy's initial step for
    the span to ``tend`` (:func:`dop853_first_step`)."""
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


# ====================================================================== Taylor
@njit(inline="always")
def taylor_coefficients_of(system, P, X, order):
    """The normalised Taylor coefficients X[i, k] = y_i^(k)/k!, k = 0..order, of ``system`` from
    X[:, 0] by its recurrence: R3 (``REDUCED``), or R3 and its variational equations
    (``TANGENT``: rows 5..9 the deviation vector), or R3's in reversed time
    (``REDUCED_BACKWARD``: y(t0 - s) has the coefficients (-1)^k X_k, exactly)."""
    if system == REDUCED:
        taylor_coefficients(P, X, order)
    elif system == TANGENT:
        taylor_coefficients_tangent(P, X[:N_ORBIT], X[N_ORBIT:], order)
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


@njit(inline="always")  # inlined into each loop, as dop853_step
def taylor_step(system, X, P, t, tend, end_code, order, factor, steps, max_steps, ynew):
    """One step of the adaptive Taylor method of ``order`` from the state X[:, 0] at time ``t``
    towards ``tend``; ``end_code`` (with h = 0) when ``t`` has reached ``tend``.

    The budget check, the coefficients (:func:`taylor_coefficients_of`), the finiteness of the
    orbit's last two coefficients, the step rho * ``factor`` from the orbit's own coefficients
    (Jorba & Zou 2005; rows 0..4 only: a deviation vector does not choose the step), clipped to
    ``tend``, the Horner sum into ``ynew`` and its finiteness.  Returns (code, h, last, steps):
    ``code`` is ``STEP_OK`` (X holds the step's coefficients, ``ynew`` the state at t + h,
    ``last``: the step reaches ``tend``), ``STATUS_MAX_STEPS``, ``STATUS_NONFINITE`` or
    ``STATUS_STEP_UNDERFLOW`` (h <= eps |t|: time no longer advances)."""
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


# ====================================================================== splitting
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
    ends: t_n = n dt is never summed).  Returns (code, steps): ``STEP_OK``,
    ``STATUS_MAX_STEPS`` (before the step) or ``STATUS_NONFINITE``."""
    if steps >= max_steps:
        return STATUS_MAX_STEPS, steps
    for i in range(y.shape[0]):
        ynew[i] = y[i]
    compose(system, ynew, P, dt, flow_ids, fracs)
    steps += 1
    if not all_finite(ynew):
        return STATUS_NONFINITE, steps
    return STEP_OK, steps
