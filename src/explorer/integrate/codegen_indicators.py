"""The chaos-indicator drivers appended to every generated module (:data:`explorer.integrate.codegen.TEMPLATES`):
``indicators_taylor_worker``, the adaptive Taylor method on the variational system of
:meth:`explorer.model.system.System.variational` with the indicators of :mod:`explorer.kernels.tangent`
(docs/systems.md, "Chaos indicators"), and ``indicators_lanes_worker``, the same for LANES orbits at once on
SIMD lanes (each lane the scalar driver bit for bit, as :mod:`explorer.integrate.codegen_lanes`), called by
:mod:`explorer.analysis.system_indicators`.

It is rendered into every module but compiled only when called, on the module of ``System.variational(nvec)``:
its rows are the state (n), then nvec deviation vectors (n each), so DIM = n (1 + nvec).
"""
from __future__ import annotations

__all__ = ["render"]

SOURCE = '''

# ---- chaos indicators along deviation vectors (explorer.analysis.system_indicators): generated here,
# beside the recurrence they call, so that numba's cache of them follows the recurrence (docs/systems.md)
from explorer.integrate.simd import atomic_fetch_add  # noqa: E402
from explorer.kernels import tangent as _tg  # noqa: E402
from explorer.kernels.checks import all_finite, is_finite  # noqa: E402
from explorer.kernels.clock import advance_time, clip_step, resolves  # noqa: E402
from explorer.kernels.status import (  # noqa: E402
    STATUS_CANCELLED, STATUS_DONE, STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW)
from explorer.kernels.taylor import evaluate, safety_factor, step_size  # noqa: E402


@njit(error_model="numpy")
def _indicator_history(acc, hist_t, hist, hpos, row):
    """The result rows at the history times the step end passed (as the engine's tangent loops)."""
    while hpos < hist_t.shape[0] and acc[_tg.ACC_T] >= hist_t[hpos]:
        _tg.result(acc, row)
        for c in range(_tg.N_RES):
            hist[hpos, c] = row[c]
        hpos += 1
    return hpos


@njit(error_model="numpy")
def _indicator_early(acc, v, w, n, nvec, sali_stop, megno_level, tmin, since):
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
def indicators_orbit(y0, v0, w0, n, nvec, P, T, order, max_steps, early_stop, sali_stop, megno_level, early_tmin,
                     hist_t, hist, res, ext, wout, yout, stop):
    """The orbit from y0 and nvec (1 or 2) deviation vectors from v0, w0 (made unit) over the time T
    by the adaptive Taylor method of ``order`` on the variational system (Jorba & Zou 2005; the step
    from the orbit's rows only, as the crossings' taylor step of the orbit, so the vectors do not change
    the orbit), the vectors renormalised after every step and the indicators accumulated by
    kernels.tangent (the engine's formulas and columns).  Returns (status, steps); res the result
    row, ext (SALI, GALI_2, early code; NaN without a second vector), wout the final unit vectors,
    yout the final state, hist the rows at the times hist_t; STATUS_CANCELLED before a step once the
    caller's switch ``stop[0]`` is set (analysis.budget)."""
    X = np.empty((DIM, order + 1))
    Wk = np.empty((max(N_WORK, 1), order + 1))
    z = np.empty(DIM)
    znew = np.empty(DIM)
    acc = np.zeros(_tg.N_ACC)
    row = np.empty(_tg.N_RES)
    factor = safety_factor(order)
    for i in range(n):
        z[i] = y0[i]
        z[n + i] = v0[i]
        if nvec == 2:
            z[2 * n + i] = w0[i]
    _tg.renormalize(z[n:2 * n], n)
    if nvec == 2:
        _tg.renormalize(z[2 * n:3 * n], n)
    t = 0.0
    tc = 0.0
    steps = 0
    hpos = 0
    since = -1.0
    early = _tg.EARLY_NONE
    status = STATUS_DONE
    while True:
        if not (t < T):
            break
        if steps >= max_steps:
            status = STATUS_MAX_STEPS
            break
        if stop[0] != 0:
            status = STATUS_CANCELLED
            break
        for i in range(DIM):
            X[i, 0] = z[i]
        st, h, last, steps = taylor_step(P, X, Wk, n, t, T, order, factor, steps, znew, False)
        if st != STEP_OK:
            status = st
            break
        start = t - tc
        t, tc = advance_time(t, tc, h, last, T)
        dlog = _tg.renormalize(znew[n:2 * n], n)
        _tg.accumulate(acc, start, t - tc, dlog)
        hpos = _indicator_history(acc, hist_t, hist, hpos, row)
        if nvec == 2:
            _tg.renormalize(znew[2 * n:3 * n], n)
        for i in range(DIM):
            z[i] = znew[i]
        if early_stop:
            early, since = _indicator_early(acc, z[n:2 * n], z[nvec * n:(nvec + 1) * n], n, nvec, sali_stop,
                                            megno_level, early_tmin, since)
            if early != _tg.EARLY_NONE:
                break
    _tg.result(acc, res)
    for i in range(n):
        yout[i] = z[i]
        wout[0, i] = z[n + i]
        if nvec == 2:
            wout[1, i] = z[2 * n + i]
    if nvec == 2:
        _tg.extra(z[n:2 * n], z[2 * n:3 * n], n, ext)
    else:
        for c in range(_tg.N_EXT):
            ext[c] = np.nan
    ext[_tg.EXT_EARLY] = early
    return status, steps


@njit(nogil=True, error_model="numpy")
def indicators_taylor_worker(next_orbit, Y0, V0, W0, n, nvec, P, T, order, max_steps, early_stop, sali_stop,
                             megno_level, early_tmin, hist_t, out_hist, out_res, out_ext, out_status, out_final,
                             out_steps, out_w, stop):
    """:func:`indicators_orbit` for the orbits (rows of Y0) of the queue ``next_orbit`` that threads share:
    each orbit is computed alone, so the result does not depend on the number of threads."""
    j = atomic_fetch_add(next_orbit, 0, 1)
    while j < Y0.shape[0]:
        s, k = indicators_orbit(Y0[j], V0[j], W0[j], n, nvec, P, T, order, max_steps, early_stop, sali_stop,
                                megno_level, early_tmin, hist_t, out_hist[j], out_res[j], out_ext[j], out_w[j],
                                out_final[j], stop)
        out_status[j] = s
        out_steps[j] = k
        j = atomic_fetch_add(next_orbit, 0, 1)


# ---- the indicators on SIMD lanes: each lane indicators_orbit bit for bit.  The recurrence, the step
# (its norms over the orbit's rows) and the Horner evaluation in vector form; the renormalisation and the
# accumulators after a step lane by lane with the scalar kernels (their cost is small beside the recurrence)
from explorer.integrate.simd import (  # noqa: E402
    next_bit, vbits, vmask, vmax_gt, vmin_lt, vradius_power_core, vselect)
from explorer.kernels.clock import compensated_add  # noqa: E402
from explorer.kernels.power import is_normal  # noqa: E402
from explorer.kernels.taylor import radius_min  # noqa: E402


@njit(error_model="numpy")
def _indicator_norms_lanes(X, order, n, e_p, e_q, NORM):
    """_norms_lanes over the orbit's rows :n only, as taylor_step (its finiteness test and
    kernels.taylor.step_size on X[:n]): NORM = (a, bm, s/a, s/bm, min((s/a)^e_p, (s/bm)^e_q)).
    Returns the bits of the finite lanes and of those with s/a, s/bm normal."""
    op = order * XS
    oq = (order - 1) * XS
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
def _unit_rows_lanes(Y, X, first, n, m, NRM):
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
def _indicator_ends_lanes(X, Y, hv, L_go, L_last, L_t, L_tc, L_steps, L_hnext, L_since, acc, NRM, n, nvec, T,
                          max_steps, early_stop, sali_stop, megno_level, tmin):
    """The end of indicators_orbit's step in vector form for the lanes whose step went on, is not the
    last, ends finite before T, the step cap and the next history time: the compensated clock, the
    renormalised vectors, kernels.tangent.accumulate and (``early_stop``) _indicator_early, lane-wise
    the scalar kernels' operations.  Returns (the bits of the other lanes whose step went on, their
    end taken per lane; the bits stopping by SALI; by MEGNO)."""
    zero = vzero()
    go = vbits(vload(L_go, 0) > 0.0)
    s = zero
    for i in range(DIM):
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
    _unit_rows_lanes(Y, X, n, n, m, NRM)
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
        _unit_rows_lanes(Y, X, 2 * n, n, m, NRM)
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
def _indicator_status(early, t, T, steps, max_steps):
    """Why indicators_orbit stops after a step (its checks in its order), or -1 to go on."""
    if early != _tg.EARLY_NONE or not (t < T):
        return STATUS_DONE
    if steps >= max_steps:
        return STATUS_MAX_STEPS
    return -1


@njit(error_model="numpy")
def _next_history_time(hist_t, hpos):
    """The next history time of a lane (inf after the last)."""
    return hist_t[hpos] if hpos < hist_t.shape[0] else math.inf


@njit(error_model="numpy")
def _indicator_lane_start(l, next_orbit, Y0, V0, W0, n, nvec, T, max_steps, X, z, orb, L_on, L_t, L_tc, L_steps,
                          L_early, L_hpos, L_hnext, L_since, hist_t, acc, out_hist, out_res, out_ext, out_status,
                          out_final, out_steps, out_w):
    """Lane l takes the next orbit of the queue ``next_orbit`` at its start, as indicators_orbit (an
    orbit stopped before its first step is written out and the next one taken).  Returns 1, or 0 when
    the queue is empty: the lane then idles on the zero state."""
    while True:
        j = atomic_fetch_add(next_orbit, 0, 1)
        if j >= Y0.shape[0]:
            orb[l] = -1
            L_on[l] = 0.0
            for i in range(DIM):
                X[0, i, l] = 0.0
            return 0
        for i in range(DIM):
            z[i] = 0.0
        for i in range(n):
            z[i] = Y0[j, i]
            z[n + i] = V0[j, i]
            if nvec == 2:
                z[2 * n + i] = W0[j, i]
        _tg.renormalize(z[n:2 * n], n)
        if nvec == 2:
            _tg.renormalize(z[2 * n:3 * n], n)
        for i in range(DIM):
            X[0, i, l] = z[i]
        orb[l] = j
        L_on[l] = 1.0
        L_t[l] = 0.0
        L_tc[l] = 0.0
        L_steps[l] = 0
        L_early[l] = _tg.EARLY_NONE
        L_hpos[l] = 0
        L_hnext[l] = _next_history_time(hist_t, 0)
        L_since[l] = -1.0
        for c in range(_tg.N_ACC):
            acc[c, l] = 0.0
        st = _indicator_status(_tg.EARLY_NONE, 0.0, T, 0, max_steps)
        if st < 0:
            return 1
        _indicator_lane_finish(l, st, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext, out_status,
                               out_final, out_steps, out_w)


@njit(error_model="numpy")
def _indicator_lane_finish(l, st, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext, out_status,
                           out_final, out_steps, out_w):
    """Write out lane l's orbit, stopped with status ``st`` (indicators_orbit's outputs)."""
    j = orb[l]
    for i in range(DIM):
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
def _indicator_cancel_lanes(next_orbit, N, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext, out_status,
                            out_final, out_steps, out_w):
    """The stop switch is set: the lanes' orbits end where they are, the queued ones before their start."""
    for l in range(LANES):
        if orb[l] >= 0:
            _indicator_lane_finish(l, STATUS_CANCELLED, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext,
                                   out_status, out_final, out_steps, out_w)
            orb[l] = -1
    j = atomic_fetch_add(next_orbit, 0, 1)
    while j < N:
        out_status[j] = STATUS_CANCELLED
        j = atomic_fetch_add(next_orbit, 0, 1)


@njit(nogil=True, error_model="numpy")
def indicators_lanes_worker(next_orbit, Y0, V0, W0, n, nvec, P, T, order, max_steps, early_stop, sali_stop,
                            megno_level, early_tmin, hist_t, out_hist, out_res, out_ext, out_status, out_final,
                            out_steps, out_w, stop):
    """One group of LANES lanes: orbits from the queue ``next_orbit`` until it is empty, each lane
    indicators_orbit's loop (its arguments and outputs); once ``stop[0]`` is set, before the next step, every
    orbit in a lane and every one still queued ends with STATUS_CANCELLED."""
    X = np.zeros((order + 1, DIM, LANES))
    Wk = np.zeros((order + 1, max(N_WORK, 1), LANES))
    Y = np.zeros((DIM, LANES))
    NORM = np.zeros((5, LANES))
    NRM = np.zeros(LANES)
    hv = np.zeros(LANES)
    L_t = np.zeros(LANES)
    L_tc = np.zeros(LANES)
    L_on = np.zeros(LANES)
    L_last = np.zeros(LANES)
    L_go = np.zeros(LANES)
    L_since = np.zeros(LANES)
    L_steps = np.zeros(LANES)
    L_hnext = np.zeros(LANES)
    L_early = np.zeros(LANES, np.int64)
    L_hpos = np.zeros(LANES, np.int64)
    orb = np.full(LANES, -1, np.int64)
    acc = np.zeros((_tg.N_ACC, LANES))
    z = np.zeros(DIM)
    row = np.empty(_tg.N_RES)
    factor = safety_factor(order)
    e_p = 1.0 / order
    e_q = 1.0 / (order - 1)
    active = 0
    for l in range(LANES):
        active += _indicator_lane_start(l, next_orbit, Y0, V0, W0, n, nvec, T, max_steps, X, z, orb, L_on, L_t,
                                        L_tc, L_steps, L_early, L_hpos, L_hnext, L_since, hist_t, acc, out_hist,
                                        out_res, out_ext, out_status, out_final, out_steps, out_w)
    while active > 0:
        if stop[0] != 0:
            _indicator_cancel_lanes(next_orbit, Y0.shape[0], n, nvec, X, z, orb, L_steps, L_early, acc, out_res,
                                    out_ext, out_status, out_final, out_steps, out_w)
            return
        taylor_coefficients_lanes(P, X, order, Wk)
        fin, normal = _indicator_norms_lanes(X, order, n, e_p, e_q, NORM)
        bits = _steps_lanes(NORM, fin, normal, L_on, L_t, T, factor, hv, L_last, L_go)
        while bits != 0:
            l, bits = next_bit(bits)
            st = _lane_step(l, fin, normal, NORM, e_p, e_q, factor, L_t, T, hv, L_last, L_go)
            if st >= 0:
                _indicator_lane_finish(l, st, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext,
                                       out_status, out_final, out_steps, out_w)
                active += _indicator_lane_start(l, next_orbit, Y0, V0, W0, n, nvec, T, max_steps, X, z, orb, L_on,
                                                L_t, L_tc, L_steps, L_early, L_hpos, L_hnext, L_since, hist_t, acc,
                                                out_hist, out_res, out_ext, out_status, out_final, out_steps,
                                                out_w) - 1
        _evaluate_lanes(X, order, hv, Y)
        bits, stop_sali, stop_megno = _indicator_ends_lanes(X, Y, hv, L_go, L_last, L_t, L_tc, L_steps, L_hnext,
                                                            L_since, acc, NRM, n, nvec, T, max_steps, early_stop,
                                                            sali_stop, megno_level, early_tmin)
        stops = stop_sali | stop_megno
        while stops != 0:
            l, stops = next_bit(stops)
            L_early[l] = _tg.EARLY_SALI if (stop_sali >> l) & 1 else _tg.EARLY_MEGNO
            _indicator_lane_finish(l, STATUS_DONE, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext,
                                   out_status, out_final, out_steps, out_w)
            active += _indicator_lane_start(l, next_orbit, Y0, V0, W0, n, nvec, T, max_steps, X, z, orb, L_on,
                                            L_t, L_tc, L_steps, L_early, L_hpos, L_hnext, L_since, hist_t, acc,
                                            out_hist, out_res, out_ext, out_status, out_final, out_steps, out_w) - 1
        while bits != 0:
            l, bits = next_bit(bits)
            L_steps[l] += 1.0
            for i in range(DIM):
                z[i] = Y[i, l]
            st = STATUS_NONFINITE
            if all_finite(z):
                al = acc[:, l]
                start = L_t[l] - L_tc[l]
                t, tc = advance_time(L_t[l], L_tc[l], hv[l], L_last[l] != 0.0, T)
                dlog = _tg.renormalize(z[n:2 * n], n)
                _tg.accumulate(al, start, t - tc, dlog)
                L_hpos[l] = _indicator_history(al, hist_t, out_hist[orb[l]], L_hpos[l], row)
                L_hnext[l] = _next_history_time(hist_t, L_hpos[l])
                if nvec == 2:
                    _tg.renormalize(z[2 * n:3 * n], n)
                L_t[l] = t
                L_tc[l] = tc
                for i in range(DIM):
                    X[0, i, l] = z[i]
                if early_stop:
                    early, L_since[l] = _indicator_early(al, z[n:2 * n], z[nvec * n:(nvec + 1) * n], n, nvec,
                                                         sali_stop, megno_level, early_tmin, L_since[l])
                    L_early[l] = early
                st = _indicator_status(L_early[l], t, T, L_steps[l], max_steps)
            if st >= 0:
                _indicator_lane_finish(l, st, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext,
                                       out_status, out_final, out_steps, out_w)
                active += _indicator_lane_start(l, next_orbit, Y0, V0, W0, n, nvec, T, max_steps, X, z, orb, L_on,
                                                L_t, L_tc, L_steps, L_early, L_hpos, L_hnext, L_since, hist_t, acc,
                                                out_hist, out_res, out_ext, out_status, out_final, out_steps,
                                                out_w) - 1
'''


def render(system) -> str:
    """The driver's source (the same for every system: its dimensions are DIM, n and nvec)."""
    return SOURCE
