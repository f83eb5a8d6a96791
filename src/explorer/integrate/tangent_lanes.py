"""Tangent dynamics by the Taylor method on SIMD lanes (docs/methods.md, Parallelism): LANES
orbits with one or two deviation vectors in lockstep, each lane bit for bit what
:func:`explorer.integrate.tangent.orbit_tangent_taylor_ext` gives for its orbit, whatever the
order of the orbits and the thread count.  Kernel contract: explorer/kernels/__init__.py.
"""
import math

import numpy as np

from explorer._jit import njit, prange
from explorer.integrate._tangent_lanes_generated import (
    DEV1,
    DEV2,
    N_WORK_TANGENT,
    NROWS,
    deviation_coefficients_lanes,
    tangent_coefficients_lanes,
)
from explorer.integrate.lanes import (
    N_NORMS,
    aligned_zeros,
    count_step,
    evaluate_lanes,
    lane_workers,
    next_lane_orbit,
    step_constants,
    step_lanes,
    step_norms_lanes,
    stop_lane,
    stop_unless_finite,
    worker_lanes,
)
from explorer.integrate.simd import (
    LANES,
    next_bit,
    vadd,
    vand,
    vandnot,
    vbits,
    vdiv,
    vge,
    vgt,
    vload,
    vlt,
    vmask,
    vmax_gt,
    vmin_lt,
    vmul,
    vselect,
    vsplat,
    vsqrt,
    vstore,
    vsub,
    vzero,
)
from explorer.integrate.tangent import _early, _finish_ext, _history
from explorer.kernels import STATUS_DONE, STATUS_MAX_STEPS
from explorer.kernels import tangent as tg
from explorer.kernels.checks import is_finite

_IDLE = -1


@njit
def _finish(j, l, Z, acc, v, w, nvec, early, status, steps, out_res, out_ext, out_status, out_final,
            out_steps, out_w):
    """Write the outputs of orbit j from lane l (its state is Z[0, :, l])."""
    for i in range(5):
        v[i] = Z[0, DEV1 + i, l]
        w[i] = Z[0, DEV2 + i, l]
        out_final[j, i] = Z[0, i, l]
    _finish_ext(acc[:, l], v, w, nvec, early, out_res[j], out_ext[j], out_w[j])
    out_status[j] = status
    out_steps[j] = int(steps)


@njit
def _start_lane(l, Z, orb, L_on, acc, L_t, L_steps, L_hpos, L_hnext, L_since, hist_t, next_orbit, Y0, V0, W0, nvec, T,
                max_steps, v, w, out_res, out_ext, out_status, out_final, out_steps, out_w):
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
        tg.reset(acc[:, l])
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
        L_steps[l] = 0.0
        L_hpos[l] = 0
        L_hnext[l] = _next_history_time(hist_t, 0)
        L_since[l] = -1.0
        L_on[l] = 1.0
        return 1


@njit(inline="always")
def _next_history_time(hist_t, hpos):
    return hist_t[hpos] if hpos < hist_t.shape[0] else math.inf


@njit(inline="always")
def _unit_lanes(znew, first, c, nl):
    x0 = vload(znew, first * nl + c)
    x1 = vload(znew, (first + 1) * nl + c)
    x2 = vload(znew, (first + 2) * nl + c)
    x3 = vload(znew, (first + 3) * nl + c)
    x4 = vload(znew, (first + 4) * nl + c)
    s = vadd(vadd(vadd(vadd(vadd(vzero(), vmul(x0, x0)), vmul(x1, x1)), vmul(x2, x2)), vmul(x3, x3)), vmul(x4, x4))
    norm = vsqrt(s)
    inv = vdiv(vsplat(1.0), norm)
    return vmul(x0, inv), vmul(x1, inv), vmul(x2, inv), vmul(x3, inv), vmul(x4, inv), norm


@njit(inline="always")
def _keep(Z, row, ok, x):
    """Z[0, row] = x in the lanes of ok (the group's offset in ``row``)."""
    vstore(Z, row, vselect(ok, x, vload(Z, row)))


@njit(inline="always")
def end_steps_tangent_lanes(Z, znew, hv, nrm, acc, L_t, L_steps, L_hnext, L_on, L_fast, L_last, nvec, T, max_steps,
                            c, nl):
    """The end of the tangent step, in vector form, for the lanes of the group at ``c`` whose step
    needs only bookkeeping (taken in vector form, not the last, finite, no history row): step
    count, time, renormalised deviation vectors and kernels.tangent.accumulate, lane-wise as the
    scalar loop.  Returns the bits of the other lanes holding an orbit (lane c + i bit i)."""
    zero = vzero()
    live = vgt(vload(L_on, c), zero)
    ok = vandnot(vgt(vload(L_fast, c), zero), vgt(vload(L_last, c), zero))
    s = zero
    for i in range(DEV1 + 5):
        s = vadd(s, vload(znew, i * nl + c))
    ok = vand(ok, is_finite(s))
    if nvec == 2:
        s = zero
        for i in range(DEV2, DEV2 + 5):
            s = vadd(s, vload(znew, i * nl + c))
        ok = vand(ok, is_finite(s))
    t = vload(L_t, c)
    tn = vadd(t, vload(hv, c))
    steps = vload(L_steps, c)
    sn = vadd(steps, vsplat(1.0))
    ok = vand(ok, vand(vand(vlt(tn, vsplat(T)), vlt(sn, vsplat(max_steps))), vlt(tn, vload(L_hnext, c))))
    v0, v1, v2, v3, v4, norm = _unit_lanes(znew, DEV1, c, nl)
    vstore(nrm, c, norm)
    for l in range(c, c + LANES):
        if L_on[l] != 0.0:
            nrm[l] = math.log(nrm[l])
    dlog = vload(nrm, c)
    lg = vadd(vload(acc, tg.ACC_LOG * nl + c), dlog)
    wv = tg.megno_weight(vload(acc, tg.ACC_W * nl + c), t, tn, dlog)
    y1 = vselect(vgt(tn, zero), tg.megno_y(wv, tn), zero)
    yint = tg.megno_mean_integral(vload(acc, tg.ACC_YINT * nl + c), vload(acc, tg.ACC_Y * nl + c), y1, t, tn)
    _keep(acc, tg.ACC_LOG * nl + c, ok, lg)
    _keep(acc, tg.ACC_W * nl + c, ok, wv)
    _keep(acc, tg.ACC_YINT * nl + c, ok, yint)
    _keep(acc, tg.ACC_Y * nl + c, ok, y1)
    _keep(acc, tg.ACC_T * nl + c, ok, tn)
    _keep(acc, tg.ACC_FLI * nl + c, ok, vmax_gt(lg, vload(acc, tg.ACC_FLI * nl + c)))
    vstore(L_t, c, vselect(ok, tn, t))
    vstore(L_steps, c, vselect(ok, sn, steps))
    for i in range(5):
        _keep(Z, i * nl + c, ok, vload(znew, i * nl + c))
    _keep(Z, DEV1 * nl + c, ok, v0)
    _keep(Z, (DEV1 + 1) * nl + c, ok, v1)
    _keep(Z, (DEV1 + 2) * nl + c, ok, v2)
    _keep(Z, (DEV1 + 3) * nl + c, ok, v3)
    _keep(Z, (DEV1 + 4) * nl + c, ok, v4)
    if nvec == 2:
        w0, w1, w2, w3, w4, _ = _unit_lanes(znew, DEV2, c, nl)
        _keep(Z, DEV2 * nl + c, ok, w0)
        _keep(Z, (DEV2 + 1) * nl + c, ok, w1)
        _keep(Z, (DEV2 + 2) * nl + c, ok, w2)
        _keep(Z, (DEV2 + 3) * nl + c, ok, w3)
        _keep(Z, (DEV2 + 4) * nl + c, ok, w4)
    else:
        for i in range(DEV2, DEV2 + 5):
            _keep(Z, i * nl + c, ok, zero)
    return vbits(vandnot(live, ok))


@njit(inline="always")
def early_lanes(Z, acc, L_since, L_on, bits, nvec, sali_stop, megno_level, tmin, c, nl):
    """The early classification (integrate.tangent._early) in vector form for the lanes that
    :func:`end_steps_tangent_lanes` ended: SALI below ``sali_stop`` (nvec == 2), else the MEGNO rule
    (kernels.tangent.megno_early).  Returns (bits stopping by SALI, bits stopping by MEGNO)."""
    zero = vzero()
    m = vandnot(vgt(vload(L_on, c), zero), vmask(bits))
    stop_sali = 0
    if nvec == 2 and sali_stop > 0.0:
        sp = zero
        sm = zero
        for i in range(5):
            v = vload(Z, (DEV1 + i) * nl + c)
            w = vload(Z, (DEV2 + i) * nl + c)
            a = vadd(v, w)
            b = vsub(v, w)
            sp = vadd(sp, vmul(a, a))
            sm = vadd(sm, vmul(b, b))
        low = vand(m, vlt(vsqrt(vmin_lt(sm, sp)), vsplat(sali_stop)))
        stop_sali = vbits(low)
        m = vandnot(m, low)
    stop_megno = 0
    if megno_level > 0.0:
        t = vload(acc, tg.ACC_T * nl + c)
        ym = vselect(vgt(t, zero), vdiv(vload(acc, tg.ACC_YINT * nl + c), t), zero)
        since = vload(L_since, c)
        since = vselect(vgt(ym, vsplat(megno_level)), vselect(vlt(since, zero), t, since), vsplat(-1.0))
        _keep(L_since, c, m, since)
        stop = vand(vand(vge(since, zero), vge(t, vsplat(tmin))), vge(t, vmul(vsplat(2.0), since)))
        stop_megno = vbits(vand(m, stop))
    return stop_sali, stop_megno


# nogil: the batch drivers Python calls release the GIL (docs/architecture.md, Parallelism)
@njit(nogil=True)
def _run_worker(nlanes, next_orbit, Y0, V0, W0, nvec, P, T, order, max_steps, early_stop, sali_stop,
                megno_level, early_tmin, hist_t, out_hist, out_res, out_ext, out_status, out_final, out_steps, out_w):
    nl = LANES
    Z = aligned_zeros((order + 1) * NROWS * nl).reshape((order + 1, NROWS, nl))
    # the recurrences' work array (explorer.integrate.codegen: rows of the nodes whose past they read)
    WT = aligned_zeros((order + 1) * N_WORK_TANGENT * nl).reshape((order + 1, N_WORK_TANGENT, nl))
    znew = aligned_zeros(NROWS * nl).reshape((NROWS, nl))
    norms = aligned_zeros(N_NORMS * nl).reshape((N_NORMS, nl))
    hv = aligned_zeros(nl)
    nrm = aligned_zeros(nl)
    acc = aligned_zeros(tg.N_ACC * nl).reshape((tg.N_ACC, nl))
    v = np.empty(5)
    w = np.zeros(5)
    row = np.empty(tg.N_RES)
    orb = np.full(nl, _IDLE, np.int64)
    L_t = aligned_zeros(nl)
    L_steps = aligned_zeros(nl)
    L_hnext = aligned_zeros(nl)
    L_on = aligned_zeros(nl)
    L_fast = aligned_zeros(nl)
    L_last = aligned_zeros(nl)
    L_hpos = np.zeros(nl, np.int64)
    L_since = aligned_zeros(nl)
    L_status = np.zeros(nl, np.int64)
    L_early = np.zeros(nl, np.int64)
    L_stop = np.zeros(nl, np.bool_)
    factor, e_p, e_q = step_constants(order)
    active = 0
    for l in range(nlanes):
        active += _start_lane(l, Z, orb, L_on, acc, L_t, L_steps, L_hpos, L_hnext, L_since, hist_t, next_orbit, Y0,
                              V0, W0, nvec, T, max_steps, v, w, out_res, out_ext, out_status, out_final, out_steps,
                              out_w)

    while active > 0:
        tangent_coefficients_lanes(P, Z, order, WT)
        if nvec == 2:
            deviation_coefficients_lanes(P, Z, order, WT)
        step_norms_lanes(Z, order, e_p, e_q, norms)
        step_lanes(L_on, norms, L_t, T, e_p, e_q, factor, hv, L_last, L_fast, L_status, L_stop, nl)
        evaluate_lanes(Z, order, hv, znew, 0)
        evaluate_lanes(Z, order, hv, znew, DEV1)
        if nvec == 2:
            evaluate_lanes(Z, order, hv, znew, DEV2)
        for c in range(0, nl, LANES):
            bits = end_steps_tangent_lanes(Z, znew, hv, nrm, acc, L_t, L_steps, L_hnext, L_on, L_fast, L_last,
                                           nvec, T, max_steps, c, nl)
            if early_stop:
                stop_sali, stop_megno = early_lanes(Z, acc, L_since, L_on, bits, nvec, sali_stop, megno_level,
                                                    early_tmin, c, nl)
                stops = stop_sali | stop_megno
                while stops != 0:
                    ib, stops = next_bit(stops)
                    l = c + ib
                    early = tg.EARLY_SALI if stop_sali >> ib & 1 else tg.EARLY_MEGNO
                    _finish(orb[l], l, Z, acc, v, w, nvec, early, STATUS_DONE, L_steps[l], out_res, out_ext,
                            out_status, out_final, out_steps, out_w)
                    active += _start_lane(l, Z, orb, L_on, acc, L_t, L_steps, L_hpos, L_hnext, L_since, hist_t,
                                          next_orbit, Y0, V0, W0, nvec, T, max_steps, v, w, out_res, out_ext,
                                          out_status, out_final, out_steps, out_w) - 1
            while bits != 0:
                ib, bits = next_bit(bits)
                l = c + ib
                j = orb[l]
                L_early[l] = tg.EARLY_NONE
                count_step(l, znew, 0, DEV1 + 5, L_steps, L_status, L_stop)
                if nvec == 2 and not L_stop[l]:
                    stop_unless_finite(l, znew, DEV2, DEV2 + 5, L_status, L_stop)
                if not L_stop[l]:
                    al = acc[:, l]
                    t = L_t[l]
                    t_new = T if L_last[l] != 0.0 else t + hv[l]
                    for i in range(5):
                        v[i] = znew[DEV1 + i, l]
                    dlog = tg.renormalize(v, 5)
                    tg.accumulate(al, t, t_new, dlog)
                    L_hpos[l] = _history(al, hist_t, out_hist[j], L_hpos[l], row)
                    L_hnext[l] = _next_history_time(hist_t, L_hpos[l])
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
                        early, L_since[l] = _early(al, v, w, nvec, sali_stop, megno_level, early_tmin, L_since[l])
                    if early != tg.EARLY_NONE:
                        L_early[l] = early
                        stop_lane(l, STATUS_DONE, L_status, L_stop)
                    elif not (t_new < T):
                        stop_lane(l, STATUS_DONE, L_status, L_stop)
                    elif L_steps[l] >= max_steps:
                        stop_lane(l, STATUS_MAX_STEPS, L_status, L_stop)
                if L_stop[l]:
                    _finish(j, l, Z, acc, v, w, nvec, L_early[l], L_status[l], L_steps[l], out_res, out_ext,
                            out_status, out_final, out_steps, out_w)
                    active += _start_lane(l, Z, orb, L_on, acc, L_t, L_steps, L_hpos, L_hnext, L_since, hist_t,
                                          next_orbit, Y0, V0, W0, nvec, T, max_steps, v, w, out_res, out_ext,
                                          out_status, out_final, out_steps, out_w) - 1
    return 0


@njit(parallel=True, nogil=True)
def _run_lanes(nworkers, nlanes, Y0, V0, W0, nvec, P, T, order, max_steps, early_stop, sali_stop,
               megno_level, early_tmin, hist_t, out_hist, out_res, out_ext, out_status, out_final, out_steps, out_w):
    next_orbit = np.zeros(1, np.int64)
    for _w in prange(nworkers):
        _run_worker(nlanes, next_orbit, Y0, V0, W0, nvec, P, T, order, max_steps, early_stop, sali_stop,
                    megno_level, early_tmin, hist_t, out_hist, out_res, out_ext, out_status, out_final, out_steps,
                    out_w)
    return 0


def run_tangent_lanes_batch(Y0, V0, W0, nvec, P, T, order, max_steps, early_stop, sali_stop, megno_level,
                            early_tmin, hist_t, out_hist, out_res, out_ext, out_status, out_final, out_steps, out_w,
                            max_lanes=None):
    """Lane twin of :func:`explorer.integrate.tangent.orbit_tangent_taylor_ext` over the orbits:
    out_*[j] is what it gives for orbit j (out_status, out_steps its return), bit for bit."""
    n = Y0.shape[0]
    if n == 0:
        return 0
    nworkers = lane_workers(n, max_lanes)
    nlanes = worker_lanes(n, nworkers, max_lanes)
    return _run_lanes(nworkers, nlanes, Y0, V0, W0, int(nvec), P, float(T), int(order), int(max_steps),
                      bool(early_stop), float(sali_stop), float(megno_level), float(early_tmin), hist_t, out_hist,
                      out_res, out_ext, out_status, out_final, out_steps, out_w)
