"""The parts of the generated drivers that do not depend on the system (docs/systems.md, "The
cache"): a lane's start, finish and status, the step size in vector form, the chaos indicators'
bookkeeping and step end.  The templates of :mod:`explorer.integrate.codegen_lanes`,
:mod:`~explorer.integrate.codegen_indicators` and :mod:`~explorer.integrate.codegen_flow` call them,
so numba compiles them once for every system instead of once per generated module.  What depends on
the system stays generated: the recurrence, the norms, the Horner evaluation and the section written
out row by row, the energy, and the crossings' and the flow's step ends, whose state rows are copied
at a compile-time dimension (with the dimension read at run time the W4 crossings ran about 10 %
slower).  Here the dimension is read off the arrays (X has the shape (order + 1, rows, LANES), Y
(rows, LANES)) and every loop keeps the generated order of operations, so each lane is still the
scalar driver bit for bit.  A change of this file gives every generated module a new key
(:func:`explorer.integrate.codegen.module_key`).
"""
import math

import numpy as np

from explorer._jit import njit
from explorer.integrate.layout import CARRY_G, CARRY_H0, CARRY_STEPS, CARRY_T, CARRY_TC
from explorer.integrate.simd import (
    LANES,
    atomic_fetch_add,
    next_bit,
    vbits,
    vload,
    vmask,
    vmax_gt,
    vmin_lt,
    vradius_power_core,
    vselect,
    vsplat,
    vsqrt,
    vstore,
    vzero,
)
from explorer.kernels import tangent as _tg
from explorer.kernels.checks import is_finite
from explorer.kernels.clock import clip_step, compensated_add, resolves
from explorer.kernels.power import is_normal
from explorer.kernels.status import (
    STATUS_CANCELLED,
    STATUS_DONE,
    STATUS_MAX_STEPS,
    STATUS_NONFINITE,
    STATUS_STEP_UNDERFLOW,
    STATUS_TMAX,
)
from explorer.kernels.taylor import radius_min


# ---- the crossings' and the flow's lanes (codegen_lanes, codegen_flow)
@njit(error_model="numpy")
def lane_step(l, fin, normal, NORM, e_p, e_q, factor, L_t, tmax, hv, L_last, L_go):
    """The step of lane ``l`` that steps_lanes left to the scalar code (kernels.taylor.step_size's
    radius from NORM, clipped onto ``tmax``): -1 with hv, L_last and L_go set, else the lane's stop
    status (non-finite coefficients, a step below the clock's resolution)."""
    if not (fin >> l) & 1:
        return STATUS_NONFINITE
    if (normal >> l) & 1:
        h = NORM[4, l] * factor
    else:
        h = radius_min(NORM[0, l], NORM[1, l], NORM[2, l], NORM[3, l], e_p, e_q) * factor
    h, last = clip_step(L_t[l], h, tmax)
    if not resolves(L_t[l], h):
        return STATUS_STEP_UNDERFLOW
    hv[l] = h
    L_last[l] = 1.0 if last else 0.0
    L_go[l] = 1.0
    return -1


@njit(error_model="numpy")
def steps_lanes(NORM, fin, normal, L_on, L_t, tmax, factor, hv, L_last, L_go):
    """crossings_orbit's step (step_size, clip_step, resolves) in vector form for the lanes holding an orbit
    whose norms are finite and normal: their hv, L_last and L_go (1.0: the step goes on; 0.0 and hv = 0 for
    the others).  Returns the bits of the other lanes holding an orbit: their step is taken per lane."""
    t = vload(L_t, 0)
    tv = vsplat(tmax)
    h = vload(NORM, 4 * LANES) * factor
    last = (t + h) >= tv
    h = vselect(last, tv - t, h)
    live = vbits(vload(L_on, 0) > 0.0)
    ok = live & fin & normal & vbits(resolves(t, h))
    go = vmask(ok)
    zero = vzero()
    one = vsplat(1.0)
    vstore(hv, 0, vselect(go, h, zero))
    vstore(L_last, 0, vselect(last, one, zero))
    vstore(L_go, 0, vselect(go, one, zero))
    return live & ~ok


@njit(error_model="numpy")
def lane_status(n, limit, t, tmax, steps, max_steps):
    """Why crossings_orbit stops after a step (its checks in its order), or -1 to go on."""
    if n >= limit:
        return STATUS_DONE
    if not (t < tmax):
        return STATUS_TMAX
    if steps >= max_steps:
        return STATUS_MAX_STEPS
    return -1


@njit(error_model="numpy")
def lane_take(l, next_orbit, N, X, orb, L_on):
    """The next orbit j < N of the queue ``next_orbit`` for lane l, or -1 when it is empty: the lane then
    idles on the zero state (its coefficients all 0, orb[l] = -1, L_on[l] = 0)."""
    j = atomic_fetch_add(next_orbit, 0, 1)
    if j >= N:
        orb[l] = -1
        L_on[l] = 0.0
        for i in range(X.shape[1]):
            X[0, i, l] = 0.0
        return -1
    return j


@njit(error_model="numpy")
def lane_start(l, next_orbit, Y0, tmax, max_steps, carry, limits, X, orb, L_on, L_t, L_tc, L_g, L_E0, L_n, L_steps,
                L_target, L_room, count, status, final, info):
    """Lane l takes the next orbit of the queue ``next_orbit`` where its carry left it, as crossings_orbit
    does (an orbit stopped before its first step is written out and the next one taken).  Returns 1, or 0
    when the queue is empty: the lane then idles on the zero state (its coefficients all 0)."""
    dim = X.shape[1]
    while True:
        j = lane_take(l, next_orbit, Y0.shape[0], X, orb, L_on)
        if j < 0:
            return 0
        for i in range(dim):
            X[0, i, l] = Y0[j, i]
        orb[l] = j
        L_on[l] = 1.0
        L_t[l] = carry[j, CARRY_T]
        L_tc[l] = carry[j, CARRY_TC]
        L_g[l] = carry[j, CARRY_G]
        L_steps[l] = carry[j, CARRY_STEPS]
        L_E0[l] = carry[j, CARRY_H0]
        L_n[l] = 0
        L_target[l] = limits[j, 0]
        L_room[l] = limits[j, 1]
        st = lane_status(0, L_target[l], L_t[l], tmax, L_steps[l], max_steps)
        if st < 0:
            return 1
        lane_finish(l, st, X, orb, L_t, L_tc, L_g, L_n, L_steps, carry, count, status, final, info)


@njit(error_model="numpy")
def lane_finish(l, st, X, orb, L_t, L_tc, L_g, L_n, L_steps, carry, count, status, final, info):
    """Write out lane l's orbit, stopped with status ``st`` (crossings_orbit's final, info, count, carry)."""
    j = orb[l]
    for i in range(X.shape[1]):
        final[j, i] = X[0, i, l]
    carry[j, CARRY_T] = L_t[l]
    carry[j, CARRY_TC] = L_tc[l]
    carry[j, CARRY_G] = L_g[l]
    carry[j, CARRY_STEPS] = L_steps[l]
    info[j, 0] = L_t[l] - L_tc[l]
    info[j, 1] = L_steps[l]
    info[j, 2] = np.nan
    count[j] = L_n[l]
    status[j] = st


@njit(error_model="numpy")
def flow_lane_finish(l, st, orb, L_t, L_tc, L_steps, status, info):
    """Write out lane l's orbit, stopped with status ``st`` (flow_orbit's info and status)."""
    j = orb[l]
    info[j, 0] = L_t[l] - L_tc[l]
    info[j, 1] = L_steps[l]
    status[j] = st


# ---- the chaos indicators (codegen_indicators): the scalar driver's bookkeeping and its lanes'
@njit(error_model="numpy")
def indicator_history(acc, hist_t, hist, hpos, row):
    """The result rows at the history times the step end passed (as the engine's tangent loops)."""
    while hpos < hist_t.shape[0] and acc[_tg.ACC_T] >= hist_t[hpos]:
        _tg.result(acc, row)
        for c in range(_tg.N_RES):
            hist[hpos, c] = row[c]
        hpos += 1
    return hpos


@njit(error_model="numpy")
def indicator_early(acc, v, w, n, nvec, sali_stop, megno_level, tmin, since):
    """The engine's early classification after a step: SALI below sali_stop, or <Y> above
    megno_level for the last half of the time (kernels.tangent.megno_early)."""
    if nvec == 2 and sali_stop > 0.0 and _tg.sali(v, w, n) < sali_stop:
        return _tg.EARLY_SALI, since
    if megno_level > 0.0:
        stop, since = _tg.megno_early(acc, since, megno_level, tmin)
        if stop:
            return _tg.EARLY_MEGNO, since
    return _tg.EARLY_NONE, since


@njit(error_model="numpy")
def norms_lanes(X, order, n, e_p, e_q, NORM):
    """kernels.taylor.step_size per lane over the rows :n of X (the orbit's rows), with taylor_step's
    finiteness test of the last two orders: NORM = (a, bm, s/a, s/bm, min((s/a)^e_p, (s/bm)^e_q)).
    Returns the bits of the finite lanes and of those with s/a, s/bm normal."""
    xs = X.shape[1] * LANES
    op = order * xs
    oq = (order - 1) * xs
    s = vsplat(1.0)
    a = vzero()
    bm = vzero()
    fin = is_finite(s)
    for i in range(n):
        p = vload(X, op + i * LANES)
        q = vload(X, oq + i * LANES)
        s = vmax_gt(abs(vload(X, i * LANES)), s)
        a = vmax_gt(abs(p), a)
        bm = vmax_gt(abs(q), bm)
        fin = fin & is_finite(p) & is_finite(q)
    u = s / a
    v = s / bm
    vstore(NORM, 0, a)
    vstore(NORM, LANES, bm)
    vstore(NORM, 2 * LANES, u)
    vstore(NORM, 3 * LANES, v)
    vstore(NORM, 4 * LANES, vmin_lt(vradius_power_core(v, e_q), vradius_power_core(u, e_p)))
    return vbits(fin), vbits(is_normal(u) & is_normal(v))


@njit(error_model="numpy")
def unit_rows_lanes(Y, X, first, n, m, NRM):
    """kernels.tangent.renormalize of rows first..first+n-1 of Y per lane, written to X[0] in the lanes
    of the mask m: the same operations in the same order; NRM the former norms."""
    s = vzero()
    for i in range(first, first + n):
        v = vload(Y, i * LANES)
        s = s + v * v
    norm = vsqrt(s)
    inv = vsplat(1.0) / norm
    for i in range(first, first + n):
        vstore(X, i * LANES, vselect(m, vload(Y, i * LANES) * inv, vload(X, i * LANES)))
    vstore(NRM, 0, norm)


@njit(error_model="numpy")
def indicator_ends_lanes(X, Y, hv, L_go, L_last, L_t, L_tc, L_steps, L_hnext, L_since, acc, NRM, n, nvec, T,
                          max_steps, early_stop, sali_stop, megno_level, tmin):
    """The end of indicators_orbit's step in vector form for the lanes whose step went on, is not the
    last, ends finite before T, the step cap and the next history time: the compensated clock, the
    renormalised vectors, kernels.tangent.accumulate and (``early_stop``) indicator_early, lane-wise
    the scalar kernels' operations.  Returns (the bits of the other lanes whose step went on, their
    end taken per lane; the bits stopping by SALI; by MEGNO)."""
    zero = vzero()
    go = vbits(vload(L_go, 0) > 0.0)
    s = zero
    for i in range(Y.shape[0]):
        s = s + vload(Y, i * LANES)
    start = vload(L_t, 0) - vload(L_tc, 0)
    t, tc = compensated_add(vload(L_t, 0), vload(L_tc, 0), vload(hv, 0))
    t1 = t - tc
    steps = vload(L_steps, 0) + 1.0
    ok = (go & vbits(is_finite(s)) & ~vbits(vload(L_last, 0) > 0.0)
          & vbits((t < T) & (steps < float(max_steps)) & (t1 < vload(L_hnext, 0))))
    if ok == 0:
        return go, 0, 0
    m = vmask(ok)
    vstore(L_t, 0, vselect(m, t, vload(L_t, 0)))
    vstore(L_tc, 0, vselect(m, tc, vload(L_tc, 0)))
    vstore(L_steps, 0, vselect(m, steps, vload(L_steps, 0)))
    for i in range(n):
        vstore(X, i * LANES, vselect(m, vload(Y, i * LANES), vload(X, i * LANES)))
    unit_rows_lanes(Y, X, n, n, m, NRM)
    bits = ok
    while bits != 0:   # libm's log per lane (kernels.tangent.renormalize's)
        l, bits = next_bit(bits)
        NRM[l] = math.log(NRM[l])
    dlog = vload(NRM, 0)
    lg = vload(acc, _tg.ACC_LOG * LANES) + dlog
    w = _tg.megno_weight(vload(acc, _tg.ACC_W * LANES), start, t1, dlog)
    y1 = vselect(t1 > zero, _tg.megno_y(w, t1), zero)
    yint = _tg.megno_mean_integral(vload(acc, _tg.ACC_YINT * LANES), vload(acc, _tg.ACC_Y * LANES), y1, start, t1)
    fli = vmax_gt(lg, vload(acc, _tg.ACC_FLI * LANES))
    vstore(acc, _tg.ACC_LOG * LANES, vselect(m, lg, vload(acc, _tg.ACC_LOG * LANES)))
    vstore(acc, _tg.ACC_W * LANES, vselect(m, w, vload(acc, _tg.ACC_W * LANES)))
    vstore(acc, _tg.ACC_YINT * LANES, vselect(m, yint, vload(acc, _tg.ACC_YINT * LANES)))
    vstore(acc, _tg.ACC_Y * LANES, vselect(m, y1, vload(acc, _tg.ACC_Y * LANES)))
    vstore(acc, _tg.ACC_T * LANES, vselect(m, t1, vload(acc, _tg.ACC_T * LANES)))
    vstore(acc, _tg.ACC_FLI * LANES, vselect(m, fli, vload(acc, _tg.ACC_FLI * LANES)))
    if nvec == 2:
        unit_rows_lanes(Y, X, 2 * n, n, m, NRM)
    stop_sali = 0
    stop_megno = 0
    if early_stop:
        if nvec == 2 and sali_stop > 0.0:
            sp = zero
            sm = zero
            for i in range(n):
                v = vload(X, (n + i) * LANES)
                u = vload(X, (2 * n + i) * LANES)
                a = v + u
                b = v - u
                sp = sp + a * a
                sm = sm + b * b
            stop_sali = ok & vbits(vsqrt(vmin_lt(sm, sp)) < vsplat(sali_stop))
        if megno_level > 0.0:
            rest = vmask(ok & ~stop_sali)
            ym = vselect(t1 > zero, yint / t1, zero)
            since = vload(L_since, 0)
            since = vselect(ym > vsplat(megno_level), vselect(since < zero, t1, since), vsplat(-1.0))
            vstore(L_since, 0, vselect(rest, since, vload(L_since, 0)))
            stop = (since >= zero) & (t1 >= vsplat(tmin)) & (vsplat(2.0) * since <= t1)
            stop_megno = vbits(rest & stop)
    return go & ~ok, stop_sali, stop_megno


@njit(error_model="numpy")
def indicator_status(early, t, T, steps, max_steps):
    """Why indicators_orbit stops after a step (its checks in its order), or -1 to go on."""
    if early != _tg.EARLY_NONE or not (t < T):
        return STATUS_DONE
    if steps >= max_steps:
        return STATUS_MAX_STEPS
    return -1


@njit(error_model="numpy")
def next_history_time(hist_t, hpos):
    """The next history time of a lane (inf after the last)."""
    return hist_t[hpos] if hpos < hist_t.shape[0] else math.inf


@njit(error_model="numpy")
def indicator_lane_start(l, next_orbit, Y0, V0, W0, n, nvec, T, max_steps, X, z, orb, L_on, L_t, L_tc, L_steps,
                          L_early, L_hpos, L_hnext, L_since, hist_t, acc, out_hist, out_res, out_ext, out_status,
                          out_final, out_steps, out_w):
    """Lane l takes the next orbit of the queue ``next_orbit`` at its start, as indicators_orbit (an
    orbit stopped before its first step is written out and the next one taken).  Returns 1, or 0 when
    the queue is empty: the lane then idles on the zero state."""
    dim = X.shape[1]
    while True:
        j = lane_take(l, next_orbit, Y0.shape[0], X, orb, L_on)
        if j < 0:
            return 0
        for i in range(dim):
            z[i] = 0.0
        for i in range(n):
            z[i] = Y0[j, i]
            z[n + i] = V0[j, i]
            if nvec == 2:
                z[2 * n + i] = W0[j, i]
        _tg.renormalize(z[n:2 * n], n)
        if nvec == 2:
            _tg.renormalize(z[2 * n:3 * n], n)
        for i in range(dim):
            X[0, i, l] = z[i]
        orb[l] = j
        L_on[l] = 1.0
        L_t[l] = 0.0
        L_tc[l] = 0.0
        L_steps[l] = 0
        L_early[l] = _tg.EARLY_NONE
        L_hpos[l] = 0
        L_hnext[l] = next_history_time(hist_t, 0)
        L_since[l] = -1.0
        for c in range(_tg.N_ACC):
            acc[c, l] = 0.0
        st = indicator_status(_tg.EARLY_NONE, 0.0, T, 0, max_steps)
        if st < 0:
            return 1
        indicator_lane_finish(l, st, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext, out_status,
                               out_final, out_steps, out_w)


@njit(error_model="numpy")
def indicator_lane_finish(l, st, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext, out_status,
                           out_final, out_steps, out_w):
    """Write out lane l's orbit, stopped with status ``st`` (indicators_orbit's outputs)."""
    j = orb[l]
    for i in range(X.shape[1]):
        z[i] = X[0, i, l]
    _tg.result(acc[:, l], out_res[j])
    for i in range(n):
        out_final[j, i] = z[i]
        out_w[j, 0, i] = z[n + i]
        if nvec == 2:
            out_w[j, 1, i] = z[2 * n + i]
    if nvec == 2:
        _tg.extra(z[n:2 * n], z[2 * n:3 * n], n, out_ext[j])
    else:
        for c in range(_tg.N_EXT):
            out_ext[j, c] = np.nan
    out_ext[j, _tg.EXT_EARLY] = L_early[l]
    out_status[j] = st
    out_steps[j] = int(L_steps[l])


@njit(error_model="numpy")
def indicator_cancel_lanes(next_orbit, N, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext, out_status,
                            out_final, out_steps, out_w):
    """The stop switch is set: the lanes' orbits end where they are, the queued ones before their start."""
    for l in range(LANES):
        if orb[l] >= 0:
            indicator_lane_finish(l, STATUS_CANCELLED, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext,
                                   out_status, out_final, out_steps, out_w)
            orb[l] = -1
    j = atomic_fetch_add(next_orbit, 0, 1)
    while j < N:
        out_status[j] = STATUS_CANCELLED
        j = atomic_fetch_add(next_orbit, 0, 1)
