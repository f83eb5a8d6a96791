"""Lane (SIMD) batch driver of tangent dynamics by the Taylor method: LANES orbits, each with
one or two deviation vectors, advance in lockstep.

:func:`run_tangent_lanes_batch` has the signature and the outputs of
:func:`explorer.integrate.tangent.run_tangent_taylor_ext_batch` (the scalar reference; with one
deviation vector and no early stop that is :func:`explorer.integrate.tangent.orbit_tangent_taylor`,
the step of ``systems.taylor_step`` of ``TANGENT``) and gives bit for bit the same results for
every orbit (indicators, history, SALI, GALI_2, final state and vectors, status, step count),
whatever the grouping of orbits into lanes and the number of threads:

* the Taylor coefficients of the orbit and its deviation vectors of LANES orbits are computed
  together by the generated vector kernels of :mod:`explorer.integrate._tangent_lanes_generated`
  (translated by ``tools/gen_lanes.py`` from ``equations.taylor_coefficients_tangent``: lane-wise
  the same IEEE operations in the same order; the second vector by the same recurrence's
  statements for the deviation only), the step norms and the Horner sums by those of the
  crossing lanes (``lanes.step_norms_lanes``, ``lanes.evaluate_lanes``);
* the step sizes of all lanes from the orbit's rows (``lanes.step_norms_lanes``: the powers
  vectorized, the same doubles as ``kernels.taylor.step_size``);
* everything else - the clip to T, the step budget, the finiteness and
  underflow checks, the renormalisation and the accumulators of ``kernels.tangent``, the
  history rows and the early classification - is the control flow of the scalar loop, run per
  lane in scalar code.

Lanes never exchange values, so the work is distributed dynamically as in
:mod:`explorer.integrate.lanes`: one worker per thread, a lane whose orbit stops takes the next
unstarted orbit of the batch at once (an atomic counter); idle lanes run on the zero state.  A
worker advances G groups of LANES lanes (``lanes.lane_groups``, the generated kernels of G
groups), bit for bit the same results for every G.

Kernel contract: arrays are allocated per worker, never inside the step loop; no exceptions
(status codes); no fastmath.
"""
import numpy as np

from explorer._jit import get_num_threads, njit, prange
from explorer.integrate._tangent_lanes_generated import (
    DEV1,
    DEV2,
    NROWS,
    deviation_coefficients_lanes,
    tangent_coefficients_lanes,
)
from explorer.integrate.lanes import (
    N_NORMS,
    aligned_zeros,
    count_step,
    evaluate_lanes,
    next_lane_orbit,
    step_constants,
    step_lanes,
    step_norms_lanes,
    stop_lane,
    stop_unless_finite,
    worker_lanes,
)
from explorer.integrate.simd import LANES
from explorer.integrate.tangent import _early, _finish_ext, _history
from explorer.kernels import STATUS_DONE, STATUS_MAX_STEPS
from explorer.kernels import tangent as tg

_IDLE = -1


@njit
def _finish(j, l, Z, acc, v, w, nvec, early, status, steps, out_res, out_ext, out_status, out_final,
            out_steps, out_w):
    """Write the outputs of orbit j from lane l (its state is Z[0, :, l])."""
    for i in range(5):
        v[i] = Z[0, DEV1 + i, l]
        w[i] = Z[0, DEV2 + i, l]
        out_final[j, i] = Z[0, i, l]
    _finish_ext(acc[l], v, w, nvec, early, out_res[j], out_ext[j], out_w[j])
    out_status[j] = status
    out_steps[j] = steps


@njit
def _start_lane(l, Z, orb, L_on, acc, L_t, L_steps, L_hpos, L_since, next_orbit, Y0, V0, W0, nvec, T, max_steps,
                v, w, out_res, out_ext, out_status, out_final, out_steps, out_w):
    """Put the next unstarted orbit on lane l (the start of the scalar loop: the deviation
    vectors renormalised; orbits that stop before their first step are written out at once).
    Returns 1 if the lane got an orbit (``L_on[l]`` = 1.0), 0 if the batch is exhausted (the lane
    idles on 0, ``L_on[l]`` = 0.0)."""
    while True:
        j = next_lane_orbit(next_orbit, Y0.shape[0], orb, l, Z, NROWS)
        if j < 0:
            L_on[l] = 0.0
            return 0
        for i in range(5):
            Z[0, i, l] = Y0[j, i]
            v[i] = V0[j, i]
            w[i] = W0[j, i] if nvec == 2 else 0.0
        tg.renormalize(v, 5)
        if nvec == 2:
            tg.renormalize(w, 5)
        for i in range(5):
            Z[0, DEV1 + i, l] = v[i]
            Z[0, DEV2 + i, l] = w[i]
        tg.reset(acc[l])
        if not (0.0 < T):
            _finish(j, l, Z, acc, v, w, nvec, tg.EARLY_NONE, STATUS_DONE, 0, out_res, out_ext, out_status,
                    out_final, out_steps, out_w)
            continue
        if 0 >= max_steps:
            _finish(j, l, Z, acc, v, w, nvec, tg.EARLY_NONE, STATUS_MAX_STEPS, 0, out_res, out_ext, out_status,
                    out_final, out_steps, out_w)
            continue
        orb[l] = j
        L_t[l] = 0.0
        L_steps[l] = 0
        L_hpos[l] = 0
        L_since[l] = -1.0
        L_on[l] = 1.0
        return 1


# nogil: the batch drivers Python calls release the GIL (docs/architecture.md, Parallelism)
@njit(nogil=True)
def _run_worker(nlanes, groups, next_orbit, Y0, V0, W0, nvec, P, T, order, max_steps, early_stop, sali_stop,
                megno_level, early_tmin, hist_t, out_hist, out_res, out_ext, out_status, out_final, out_steps, out_w):
    """Integrate orbits taken from the shared counter ``next_orbit`` on up to ``nlanes`` lanes,
    in G = len(groups) groups of LANES lanes, until none is left; each lane is
    tangent.orbit_tangent_taylor_ext step for step."""
    nl = len(groups) * LANES
    # the vector operands on cache lines (lanes.aligned_zeros: a straddling vector costs two accesses)
    Z = aligned_zeros((order + 1) * NROWS * nl).reshape((order + 1, NROWS, nl))
    znew = aligned_zeros(NROWS * nl).reshape((NROWS, nl))
    norms = aligned_zeros(N_NORMS * nl).reshape((N_NORMS, nl))
    hv = aligned_zeros(nl)
    v = np.empty(5)
    w = np.zeros(5)
    row = np.empty(tg.N_RES)
    acc = np.zeros((nl, tg.N_ACC))
    orb = np.full(nl, _IDLE, np.int64)
    L_t = np.zeros(nl)
    L_steps = np.zeros(nl, np.int64)
    L_hpos = np.zeros(nl, np.int64)
    L_since = np.zeros(nl)
    L_status = np.zeros(nl, np.int64)
    L_early = np.zeros(nl, np.int64)
    L_on = np.zeros(nl)
    L_fast = np.zeros(nl)
    L_last = np.zeros(nl)
    L_stop = np.zeros(nl, np.bool_)
    factor, e_p, e_q = step_constants(order)
    active = 0
    for l in range(nlanes):
        active += _start_lane(l, Z, orb, L_on, acc, L_t, L_steps, L_hpos, L_since, next_orbit, Y0, V0, W0, nvec, T,
                              max_steps, v, w, out_res, out_ext, out_status, out_final, out_steps, out_w)

    while active > 0:
        tangent_coefficients_lanes(P, Z, order, DEV1, groups)
        if nvec == 2:
            deviation_coefficients_lanes(P, Z, order, DEV2, groups)
        step_norms_lanes(Z, order, e_p, e_q, norms, groups)
        # ---- per lane: systems.taylor_step's checks and step size
        for l in range(nl):
            L_early[l] = tg.EARLY_NONE
        step_lanes(L_on, norms, L_t, T, e_p, e_q, factor, hv, L_last, L_fast, L_status, L_stop, nl)
        evaluate_lanes(Z, order, hv, znew, 0, groups)
        evaluate_lanes(Z, order, hv, znew, DEV1, groups)
        if nvec == 2:
            evaluate_lanes(Z, order, hv, znew, DEV2, groups)
        # ---- per lane: the rest of the step of the scalar loop
        for l in range(nl):
            j = orb[l]
            if j == _IDLE:
                continue
            count_step(l, znew, 0, DEV1 + 5, L_steps, L_status, L_stop)   # the orbit and the first vector
            if nvec == 2 and not L_stop[l]:
                stop_unless_finite(l, znew, DEV2, DEV2 + 5, L_status, L_stop)
            if not L_stop[l]:
                t = L_t[l]
                t_new = T if L_last[l] != 0.0 else t + hv[l]
                for i in range(5):
                    v[i] = znew[DEV1 + i, l]
                dlog = tg.renormalize(v, 5)
                tg.accumulate(acc[l], t, t_new, dlog)
                L_hpos[l] = _history(acc[l], hist_t, out_hist[j], L_hpos[l], row)
                if nvec == 2:
                    for i in range(5):
                        w[i] = znew[DEV2 + i, l]
                    tg.renormalize(w, 5)
                L_t[l] = t_new
                for i in range(5):
                    Z[0, i, l] = znew[i, l]
                    Z[0, DEV1 + i, l] = v[i]
                    Z[0, DEV2 + i, l] = w[i] if nvec == 2 else 0.0
                early = tg.EARLY_NONE
                if early_stop:
                    early, L_since[l] = _early(acc[l], v, w, nvec, sali_stop, megno_level, early_tmin, L_since[l])
                if early != tg.EARLY_NONE:
                    L_early[l] = early
                    stop_lane(l, STATUS_DONE, L_status, L_stop)
                elif not (t_new < T):        # the checks at the top of systems.taylor_step
                    stop_lane(l, STATUS_DONE, L_status, L_stop)
                elif L_steps[l] >= max_steps:
                    stop_lane(l, STATUS_MAX_STEPS, L_status, L_stop)
            if L_stop[l]:
                _finish(j, l, Z, acc, v, w, nvec, L_early[l], L_status[l], L_steps[l], out_res, out_ext,
                        out_status, out_final, out_steps, out_w)
                active += _start_lane(l, Z, orb, L_on, acc, L_t, L_steps, L_hpos, L_since, next_orbit, Y0, V0, W0, nvec,
                                      T, max_steps, v, w, out_res, out_ext, out_status, out_final, out_steps,
                                      out_w) - 1
    return 0


@njit(parallel=True, nogil=True)
def _run_lanes(nworkers, nlanes, groups, Y0, V0, W0, nvec, P, T, order, max_steps, early_stop, sali_stop,
               megno_level, early_tmin, hist_t, out_hist, out_res, out_ext, out_status, out_final, out_steps, out_w):
    next_orbit = np.zeros(1, np.int64)
    for _w in prange(nworkers):
        _run_worker(nlanes, groups, next_orbit, Y0, V0, W0, nvec, P, T, order, max_steps, early_stop, sali_stop,
                    megno_level, early_tmin, hist_t, out_hist, out_res, out_ext, out_status, out_final, out_steps,
                    out_w)
    return 0


def run_tangent_lanes_batch(Y0, V0, W0, nvec, P, T, order, max_steps, early_stop, sali_stop, megno_level,
                            early_tmin, hist_t, out_hist, out_res, out_ext, out_status, out_final, out_steps, out_w,
                            max_lanes=None, groups=None):
    """Lane twin of :func:`explorer.integrate.tangent.run_tangent_taylor_ext_batch` (same
    arguments and outputs, bit for bit the same results).  One worker per numba thread (at
    most one per orbit), each with up to ``groups`` groups of LANES lanes
    (:func:`explorer.integrate.lanes.worker_lanes`); the thread count is read here, in Python
    (inside a kernel it would defeat the on-disk cache)."""
    n = Y0.shape[0]
    if n == 0:
        return 0
    nworkers = max(1, min(get_num_threads(), n))
    nlanes, g = worker_lanes(n, nworkers, max_lanes, groups)
    return _run_lanes(nworkers, nlanes, g, Y0, V0, W0, int(nvec), P, float(T), int(order), int(max_steps),
                      bool(early_stop), float(sali_stop), float(megno_level), float(early_tmin), hist_t, out_hist,
                      out_res, out_ext, out_status, out_final, out_steps, out_w)
