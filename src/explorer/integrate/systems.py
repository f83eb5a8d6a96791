"""The system seam: which compiled vector field a stepping loop advances, and the parts of
the DOP853 loop that do not depend on what is observed along the way.

A *system* is an integer id (no callables cross a compiled boundary: a jitted function passed
as an argument defeats Numba's on-disk cache, kernel contract rule 1); :func:`field` dispatches
on it.  The loops that use it -- crossings of the section (:mod:`explorer.integrate.drivers`),
tangent dynamics (:mod:`explorer.integrate.tangent`) and the body in the plane
(:mod:`explorer.integrate.full`) -- differ only in what they observe after an accepted step;
the step itself (first step, the twelve stages, the solution, the error norm, the budget and
non-finite checks, the three dense-output stages) is written once here.

=============  ===  ========================================================================
system          n   state and field
=============  ===  ========================================================================
``REDUCED``     5   (p1, p2, M, g1, g2), MODEL.md R3 (:func:`explorer.model.equations.rhs`)
``TANGENT``    10   R3 and one deviation vector, the variational equations of R3
``FULL``        7   R3 and the position (x, y), MODEL.md R1
=============  ===  ========================================================================

DOP853: Hairer, Nørsett & Wanner, *Solving ODEs I*, II.10 (tableau and continuous extension
in :mod:`explorer.kernels.dop853`; controller and first step as scipy's ``DOP853``).
"""
from explorer._jit import njit
from explorer.kernels import STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW
from explorer.kernels import dop853 as dp
from explorer.kernels.checks import all_finite
from explorer.kernels.clock import clip_step
from explorer.model.equations import FULL_DIM, rhs, rhs_full, rhs_tangent

REDUCED = 0
TANGENT = 1
FULL = 2
#: state dimension of each system
DIMENSION = {REDUCED: 5, TANGENT: 10, FULL: FULL_DIM}
#: an accepted step (not a kernel status)
STEP_OK = -1


@njit(inline="always")  # inlined at Numba IR level: the tangent loop ~10 % faster (bench_ab.py)
def field(system, y, P, dy):
    """dy = f(y) of ``system``."""
    if system == REDUCED:
        rhs(y, P, dy)                          # MODEL.md R3
    elif system == TANGENT:
        _rhs_augmented(y, P, dy)
    else:
        rhs_full(y, P, dy)                     # MODEL.md R1


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
    tangent loop renormalises first, so it computes f itself)."""
    if not (t < tend):
        return end_code, 0.0, False, h_abs, steps
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
