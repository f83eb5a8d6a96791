"""Lane (SIMD) batch driver of the Taylor method: LANES orbits advance in lockstep.

:func:`run_taylor_lanes_batch` has the signature and the outputs of
:func:`explorer.integrate.drivers.run_taylor_batch` and gives bit for bit the same results for every
orbit (crossings, final state, status, time, step count), whatever the grouping of orbits
into lanes and the number of threads:

* the Taylor coefficients, the step norms and the Horner evaluation of LANES orbits are
  computed together by the generated vector kernels of :mod:`explorer._lanes_generated`
  (one vector instruction per scalar instruction of ``equations.taylor_coefficients`` and
  ``kernels.taylor``: lane-wise the same IEEE operations in the same order);
* everything else - step size, time and step budgets, last step clipped to tmax, Kahan time
  sum, NaN and step-underflow checks, ``poly_step_roots`` on the lane's own
  polynomial, ``_keep`` (branch test and record) - is the control flow of
  :func:`explorer.integrate.drivers.orbit_taylor`, run per lane in scalar code.  The root isolation
  is skipped for a lane when a bound of the variation of sin(phi - phi0) over the step,
  computed for all lanes in one vectorised loop, proves it has no root there (then
  ``poly_step_roots`` would find none either: ``kernels.events.excluded_by_variation``).

Lanes never exchange values: a lane computes exactly what ``orbit_taylor`` computes for
its orbit, so which orbits share a vector, in which order they are taken and how many
threads run cannot change any result.  The work is therefore distributed dynamically:
one worker per thread (prange), each with up to LANES lanes; a lane whose orbit stops takes
the next unstarted orbit of the batch at once (an atomic counter), so lanes idle only when
the whole batch is handed out (then on the zero state: all its coefficients are 0, harmless,
and ignored), and a long orbit cannot leave a thread idle.

Step size: ``kernels.taylor.step_size`` takes the smaller of two ``pow``,
rho_p = (s/a)^(1/p) and rho_{p-1} = (s/bm)^(1/(p-1)).  The lanes compute d = log2 rho_{p-1} -
log2 rho_p with a cheap approximation (error <= (1/p + 1/(p-1)) LOG2_APPROX_ERR) and, when
|d| exceeds that bound by a wide margin, call ``pow`` for the smaller one only: ``pow`` is
accurate to < 1 ulp, so the other, larger by a factor > 1 + 1e-12, can never be the
minimum.  Otherwise (about 0.2 % of the steps) both are computed and compared as in
step_size.  The result is the same double.

Kernel contract: arrays are allocated per worker, never inside the step loop; no
exceptions (status codes); no fastmath.
"""
import math

import numpy as np

from explorer._jit import get_num_threads, njit, prange
from explorer.integrate._lanes_generated import (
    LANES,
    LOG2_APPROX_ERR,
    NVAR,
    atomic_fetch_add,
    evaluate_lanes,
    step_norms_lanes,
    taylor_coefficients_lanes,
    vabs,
    vadd,
    vload,
    vmul,
    vsplat,
    vstore,
    vsub,
    vzero,
)
from explorer.integrate.drivers import (
    CARRY_G,
    CARRY_H0,
    CARRY_STEPS,
    CARRY_T,
    CARRY_TC,
    EPS,
    LIMIT_ROOM,
    LIMIT_TARGET,
    _finite5,
    _keep,
    _save_carry,
    store_orbit,
)
from explorer.kernels import STATUS_DONE, STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW, STATUS_TMAX
from explorer.kernels import taylor as tk
from explorer.kernels.clock import advance_time, clip_step
from explorer.kernels.events import ISOLATE_STACK, MAX_STEP_ROOTS, excluded_by_variation, poly_step_roots
from explorer.model.equations import section_g

_IDLE = -1
#: positive normal doubles: the range where vlog2_approx is valid
_TINY = 2.2250738585072014e-308
_HUGE = 1.7976931348623157e308
#: rows of the step_norms_lanes output
_N_NORMS = 7
#: rows of sin(phi) = g1 and cos(phi) = g2 in the state (p1, p2, M, g1, g2)
_G1 = 3
_G2 = 4


@njit
def lane_step_size(a, bm, u, v, d, e_p, e_q, margin, factor):
    """kernels.taylor.step_size from its norms: a, bm (> 0 tested as there), u = s/a, v = s/bm,
    e_p = 1/p, e_q = 1/(p-1); d ~ e_q log2 v - e_p log2 u within ``margin`` (when u, v are
    normal).  Returns min(u^e_p, v^e_q) * factor as step_size does (inf if a = bm = 0),
    computing a single pow when d says which one is smaller."""
    if a > 0.0 and bm > 0.0 and u >= _TINY and u <= _HUGE and v >= _TINY and v <= _HUGE:
        if d > margin:        # v^e_q > u^e_p (1 + 1e-12): step_size keeps rho = u^e_p
            return u ** e_p * factor
        if d < -margin:       # v^e_q < u^e_p (1 - 1e-12): step_size takes r2 = v^e_q
            return v ** e_q * factor
    rho = math.inf
    if a > 0.0:
        rho = u ** e_p
    if bm > 0.0:
        r2 = v ** e_q
        if r2 < rho:
            rho = r2
    return rho * factor


@njit(inline="always")
def lane_step(l, norms, t, tend, e_p, e_q, margin, factor):
    """The checks and the step of :func:`explorer.integrate.systems.taylor_step` for lane l from
    its norms (step_norms_lanes): finiteness of the last two coefficients, the step size, clipped
    to ``tend``, and the underflow test.  Returns (code, h, last): code -1 (systems.STEP_OK) or
    STATUS_NONFINITE / STATUS_STEP_UNDERFLOW.  Shared by the crossing and the tangent lanes."""
    f = norms[0, l]
    g = norms[1, l]
    if not (f - f == 0.0 and g - g == 0.0):
        return STATUS_NONFINITE, 0.0, False
    h = lane_step_size(norms[2, l], norms[3, l], norms[4, l], norms[5, l], norms[6, l], e_p, e_q, margin, factor)
    h, last = clip_step(t, h, tend)
    if not (h > EPS * abs(t)):
        return STATUS_STEP_UNDERFLOW, 0.0, False
    return -1, h, last


@njit(inline="always")
def step_lanes(orb, norms, L_t, tend, e_p, e_q, margin, factor, hv, L_last, L_status, L_stop):
    """:func:`lane_step` for every lane that holds an orbit: its step in ``hv`` (0 for idle and
    stopped lanes) and ``L_last``, or its stop in ``L_status``/``L_stop``."""
    for l in range(LANES):
        hv[l] = 0.0
        L_stop[l] = False
        if orb[l] == _IDLE:
            continue
        code, h, last = lane_step(l, norms, L_t[l], tend, e_p, e_q, margin, factor)
        if code >= 0:
            L_status[l] = code
            L_stop[l] = True
            continue
        hv[l] = h
        L_last[l] = last


@njit
def variation_lanes(X, order, h, cphi, sphi, out):
    """out[l] = sum_{k>=1} |X[k, G1, l] cos phi0 - X[k, G2, l] sin phi0| h[l]^k for every lane
    in one vector chain (Horner): the bound of the variation of sin(phi - phi0) over the step
    that kernels.events.no_root_within uses (up to the rounding its slack covers)."""
    hv = vload(h, 0)
    cv = vsplat(cphi)
    sv = vsplat(sphi)
    acc = vzero()
    for k in range(order, 0, -1):
        o = k * (NVAR * LANES)
        ck = vsub(vmul(vload(X, o + _G1 * LANES), cv), vmul(vload(X, o + _G2 * LANES), sv))
        acc = vmul(vadd(acc, vabs(ck)), hv)
    vstore(out, 0, acc)


@njit
def _evaluate_lane(X, order, l, h, out):
    """out[i] = sum_k X[k, i, l] h^k: kernels.taylor.evaluate on lane l."""
    for i in range(NVAR):
        acc = X[order, i, l]
        for k in range(order - 1, -1, -1):
            acc = acc * h + X[k, i, l]
        out[i] = acc


@njit
def _finish(j, l, X, count, status, t, tc, gprev, steps, carry, out_count, out_status, out_final,
            out_info):
    """Write the outputs of orbit j from lane l (its state is X[0, :, l]) and its carry, as
    run_taylor_batch."""
    for i in range(NVAR):
        out_final[j, i] = X[0, i, l]
    _save_carry(carry[j], t, tc, gprev, steps)
    store_orbit(j, count, status, t, steps, out_count, out_status, out_final, out_info)


@njit(inline="always")
def next_lane_orbit(next_orbit, n, orb, l, X, nrows):
    """The next unstarted orbit of a batch of ``n`` (the shared counter ``next_orbit``) for lane
    l, or -1 when the batch is handed out: the lane then idles on the zero state (its ``nrows``
    rows of X[0] set to 0: all its coefficients are 0, harmless)."""
    j = atomic_fetch_add(next_orbit, 0, 1)
    if j >= n:
        orb[l] = _IDLE
        for i in range(nrows):
            X[0, i, l] = 0.0
        return -1
    return j


@njit
def _start_lane(l, X, orb, L_t, L_tc, L_gprev, L_H0, L_count, L_steps, L_target, L_room, next_orbit,
                Y0, tmax, max_steps, carry, limits, out_count, out_status, out_final, out_info):
    """Put the next unstarted orbit that needs a step on lane l (the start of orbit_taylor, from
    the orbit's carry; orbits that stop before their first step are written out at once).
    Returns 1 if the lane got an orbit, 0 if the batch is exhausted (the lane then idles on
    the zero state)."""
    while True:
        j = next_lane_orbit(next_orbit, Y0.shape[0], orb, l, X, NVAR)
        if j < 0:
            return 0
        for i in range(NVAR):
            X[0, i, l] = Y0[j, i]
        t = carry[j, CARRY_T]
        tc = carry[j, CARRY_TC]
        g = carry[j, CARRY_G]
        steps = int(carry[j, CARRY_STEPS])
        if limits[j, LIMIT_TARGET] == 0:
            _finish(j, l, X, 0, STATUS_DONE, t, tc, g, steps, carry, out_count, out_status, out_final,
                    out_info)
            continue
        if t >= tmax:
            _finish(j, l, X, 0, STATUS_TMAX, t, tc, g, steps, carry, out_count, out_status, out_final,
                    out_info)
            continue
        if steps >= max_steps:
            _finish(j, l, X, 0, STATUS_MAX_STEPS, t, tc, g, steps, carry, out_count, out_status, out_final,
                    out_info)
            continue
        orb[l] = j
        L_H0[l] = carry[j, CARRY_H0]
        L_gprev[l] = g
        L_t[l] = t
        L_tc[l] = tc
        L_count[l] = 0
        L_steps[l] = steps
        L_target[l] = limits[j, LIMIT_TARGET]
        L_room[l] = limits[j, LIMIT_ROOM]
        return 1


#: the lane worker's work arrays: five of several dimensions, given one by one, and the 1-D ones
#: that :func:`workspace_views` cuts from three flat buffers (float64, int64, bool); ``p`` is the
#: order
WORKSPACE_ND = (("X", "(p + 1, NVAR, LANES)"), ("norms", "(_N_NORMS, LANES)"), ("ynew", "(NVAR, LANES)"),
                ("brackets", "(MAX_STEP_ROOTS, 4)"), ("stack", "(ISOLATE_STACK, 5)"))
WORKSPACE_F = (("hv", "LANES"), ("vary", "LANES"), ("yl", "NVAR"), ("yc", "NVAR"), ("gc", "p + 1"),
               ("work", "p + 1"), ("roots", "MAX_STEP_ROOTS"), ("L_t", "LANES"), ("L_tc", "LANES"),
               ("L_gprev", "LANES"), ("L_H0", "LANES"))
WORKSPACE_I = ("orb", "L_count", "L_steps", "L_target", "L_room", "L_status")
WORKSPACE_B = ("L_last", "L_stop")
#: length of the output of :func:`workspace_sizes`
N_WORKSPACE = 8
#: alignment (bytes) of the float work arrays: one cache line, one vector of LANES doubles
ALIGN = 64


@njit
def workspace_sizes(order, out):
    """Sizes of the worker's work arrays for ``order``: out[0:5] the elements of WORKSPACE_ND
    (X, norms, ynew, brackets, stack), out[5:8] the lengths of the flat float64, int64 and bool
    buffers of :func:`workspace_views`."""
    p1 = order + 1
    out[0] = p1 * NVAR * LANES
    out[1] = _N_NORMS * LANES
    out[2] = NVAR * LANES
    out[3] = MAX_STEP_ROOTS * 4
    out[4] = ISOLATE_STACK * 5
    out[5] = 6 * LANES + 2 * NVAR + 2 * p1 + MAX_STEP_ROOTS
    out[6] = 6 * LANES
    out[7] = 2 * LANES


@njit
def workspace_views(order, wf, wi, wb):
    """The 1-D work arrays (WORKSPACE_F, WORKSPACE_I, WORKSPACE_B) as views of the flat buffers
    ``wf``, ``wi``, ``wb`` (slices: views that cost nothing)."""
    p1 = order + 1
    # six float and six int arrays of LANES each, then the float arrays of other lengths
    hv, vary, L_t, L_tc, L_gprev, L_H0 = (wf[0:LANES], wf[LANES:2 * LANES], wf[2 * LANES:3 * LANES],
                                          wf[3 * LANES:4 * LANES], wf[4 * LANES:5 * LANES], wf[5 * LANES:6 * LANES])
    orb, L_count, L_steps, L_target, L_room, L_status = (wi[0:LANES], wi[LANES:2 * LANES], wi[2 * LANES:3 * LANES],
                                                         wi[3 * LANES:4 * LANES], wi[4 * LANES:5 * LANES],
                                                         wi[5 * LANES:6 * LANES])
    a = 6 * LANES
    yl = wf[a:a + NVAR]
    yc = wf[a + NVAR:a + 2 * NVAR]
    a += 2 * NVAR
    gc = wf[a:a + p1]
    work = wf[a + p1:a + 2 * p1]
    a += 2 * p1
    roots = wf[a:a + MAX_STEP_ROOTS]
    L_last = wb[0:LANES]
    L_stop = wb[LANES:2 * LANES]
    return (hv, vary, yl, yc, gc, work, roots, L_t, L_tc, L_gprev, L_H0, orb, L_count, L_steps, L_target, L_room,
            L_status, L_last, L_stop)


@njit
def _run_worker(nlanes, next_orbit, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                out_cross, out_count, out_status, out_final, out_info):
    """:func:`run_worker` on work arrays of its own."""
    n = np.zeros(N_WORKSPACE, np.int64)
    workspace_sizes(order, n)
    return run_worker(nlanes, next_orbit, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                      out_cross, out_count, out_status, out_final, out_info,
                      aligned_zeros(n[0]).reshape((order + 1, NVAR, LANES)),
                      aligned_zeros(n[1]).reshape((_N_NORMS, LANES)), aligned_zeros(n[2]).reshape((NVAR, LANES)),
                      aligned_zeros(n[3]).reshape((MAX_STEP_ROOTS, 4)),
                      aligned_zeros(n[4]).reshape((ISOLATE_STACK, 5)), aligned_zeros(n[5]),
                      np.zeros(n[6], np.int64), np.zeros(n[7], np.bool_))


@njit
def aligned_zeros(n):
    """n float64 zeros starting on a cache line (ALIGN bytes).  The lanes load and store whole
    vectors of LANES doubles (64 bytes): a vector that straddles two lines costs two accesses,
    and numba's allocator aligns to 32 bytes only, so an unaligned X made a lone orbit up to 20 %
    slower in one run than in the next (benchmarks/RESULTS.md, LONGORBIT)."""
    buf = np.zeros(n + ALIGN // 8)
    skip = ((ALIGN - buf.ctypes.data % ALIGN) % ALIGN) // 8
    return buf[skip:skip + n]


@njit
def run_worker(nlanes, next_orbit, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
               out_cross, out_count, out_status, out_final, out_info, X, norms, ynew, brackets, stack, wf, wi, wb):
    """Integrate orbits taken from the shared counter ``next_orbit`` on up to ``nlanes`` lanes
    until none is left; each lane is drivers.orbit_taylor step for step.  The work arrays
    (WORKSPACE_ND, then the flat buffers of :func:`workspace_views`) come zeroed from the
    caller: nothing is allocated here."""
    (hv, vary, yl, yc, gc, work, roots, L_t, L_tc, L_gprev, L_H0, orb, L_count, L_steps, L_target, L_room,
     L_status, L_last, L_stop) = workspace_views(order, wf, wi, wb)
    for l in range(LANES):
        orb[l] = _IDLE
    factor = tk.safety_factor(order)
    e_p = 1.0 / order          # the exponents of kernels.taylor.step_size
    e_q = 1.0 / (order - 1)
    margin = (e_p + e_q) * LOG2_APPROX_ERR + 1e-12
    active = 0
    for l in range(LANES):
        if l < nlanes:
            active += _start_lane(l, X, orb, L_t, L_tc, L_gprev, L_H0, L_count, L_steps, L_target, L_room,
                                  next_orbit, Y0, tmax, max_steps, carry, limits,
                                  out_count, out_status, out_final, out_info)
        else:
            orb[l] = _IDLE

    while active > 0:
        taylor_coefficients_lanes(P, X, order)
        step_norms_lanes(X, order, e_p, e_q, norms)
        # ---- per lane: finiteness of the last two coefficients, step size, underflow
        step_lanes(orb, norms, L_t, tmax, e_p, e_q, margin, factor, hv, L_last, L_status, L_stop)
        evaluate_lanes(X, order, hv, ynew)
        # ---- all lanes at once (vectorised): a bound of the variation of sin(phi - phi0) over
        # the step, sum_{k>=1} |c_k| h^k, so that steps far from the section skip the root
        # isolation (kernels.events.excluded_by_variation)
        variation_lanes(X, order, hv, cphi, sphi, vary)
        # ---- per lane: the rest of the step of orbit_taylor
        for l in range(LANES):
            j = orb[l]
            if j == _IDLE:
                continue
            if not L_stop[l]:
                L_steps[l] += 1
                for i in range(NVAR):
                    yl[i] = ynew[i, l]
                if not _finite5(yl):
                    L_status[l] = STATUS_NONFINITE
                    L_stop[l] = True
            if not L_stop[l]:
                h = hv[l]
                t = L_t[l]
                tc = L_tc[l]
                gprev = L_gprev[l]
                count = L_count[l]
                gnew = section_g(yl, cphi, sphi)
                nroots = 0
                if not excluded_by_variation(X[0, 3, l] * cphi - X[0, 4, l] * sphi, vary[l]):
                    for k in range(order + 1):
                        gc[k] = X[k, 3, l] * cphi - X[k, 4, l] * sphi
                    nroots = poly_step_roots(gc, order, h, gprev, gnew, direction, roots,
                                             brackets, work, stack)
                for r in range(nroots):
                    if count >= L_room[l]:
                        break
                    tau = roots[r]
                    _evaluate_lane(X, order, l, tau, yc)
                    kept = _keep(out_cross[j], count, (t - tc) + tau, yc, P, L_H0[l], cphi, sphi)
                    if kept < 0:
                        L_status[l] = STATUS_NONFINITE
                        L_stop[l] = True
                        break
                    count = kept
                    L_count[l] = count
            if not L_stop[l]:
                # compensated t += h
                t, tc = advance_time(t, tc, h, L_last[l], tmax)
                L_t[l] = t
                L_tc[l] = tc
                for i in range(NVAR):
                    X[0, i, l] = yl[i]
                L_gprev[l] = gnew
                if count >= L_target[l]:
                    L_status[l] = STATUS_DONE
                    L_stop[l] = True
                elif t >= tmax:          # the checks at the top of orbit_taylor's loop
                    L_status[l] = STATUS_TMAX
                    L_stop[l] = True
                elif L_steps[l] >= max_steps:
                    L_status[l] = STATUS_MAX_STEPS
                    L_stop[l] = True
            if L_stop[l]:
                # orbit j stopped: write it out and refill the lane
                _finish(j, l, X, L_count[l], L_status[l], L_t[l], L_tc[l], L_gprev[l], L_steps[l], carry,
                        out_count, out_status, out_final, out_info)
                active += _start_lane(l, X, orb, L_t, L_tc, L_gprev, L_H0, L_count, L_steps, L_target, L_room,
                                      next_orbit, Y0, tmax, max_steps, carry, limits,
                                      out_count, out_status, out_final, out_info) - 1
    return 0


@njit(parallel=True)
def _run_lanes(nworkers, nlanes, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
               out_cross, out_count, out_status, out_final, out_info):
    """nworkers workers (prange) of nlanes lanes each, fed from one shared queue of orbits."""
    next_orbit = np.zeros(1, np.int64)
    for w in prange(nworkers):
        _run_worker(nlanes, next_orbit, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                    out_cross, out_count, out_status, out_final, out_info)
    return 0


def run_taylor_lanes_batch(Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                           out_cross, out_count, out_status, out_final, out_info, max_lanes=LANES):
    """Lane twin of :func:`explorer.integrate.drivers.run_taylor_batch` (same arguments and outputs, bit
    for bit the same results).  One worker per numba thread (at most one per orbit), each with
    min(max_lanes, LANES, ceil(N / workers)) lanes.  A Python function: the thread count is
    read here (numba's get_num_threads inside a kernel would defeat the on-disk cache)."""
    n = Y0.shape[0]
    # one orbit: one worker, run here without the parallel layer (numba's thread pool is neither
    # asked nor started: a lone orbit pays for no threads)
    nworkers = 1 if n <= 1 else max(1, min(get_num_threads(), n))
    nlanes = max(1, min(int(max_lanes), LANES, -(-n // nworkers)))
    if nworkers == 1:
        return _run_worker(nlanes, np.zeros(1, np.int64), Y0, P, cphi, sphi, int(direction), float(tmax), int(order),
                           int(max_steps), carry, limits, out_cross, out_count, out_status, out_final, out_info)
    return _run_lanes(nworkers, nlanes, Y0, P, cphi, sphi, int(direction), float(tmax), int(order),
                      int(max_steps), carry, limits, out_cross, out_count, out_status, out_final, out_info)
