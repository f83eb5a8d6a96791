"""The chaos-indicator drivers appended to every generated module (:data:`explorer.integrate.codegen.TEMPLATES`):
``indicators_taylor_worker``, the adaptive Taylor method on the variational system of
:meth:`explorer.model.system.System.variational` with the indicators of :mod:`explorer.kernels.tangent`
(docs/systems.md, "Chaos indicators"), and ``indicators_lanes_worker``, the same for LANES orbits at once on
SIMD lanes (each lane the scalar driver bit for bit, as :mod:`explorer.integrate.codegen_lanes`), called by
:mod:`explorer.analysis.system_indicators`.

It is rendered into every module but compiled only when called, on the module of ``System.variational(nvec)``:
its rows are the state (n), then nvec deviation vectors (n each), so DIM = n (1 + nvec).  What does not
depend on the system (the bookkeeping, the lanes' start, finish and step end) is in
:mod:`explorer.integrate.lane_parts`, compiled once for all systems.
"""
from __future__ import annotations

__all__ = ["render"]

SOURCE = '''

# ---- chaos indicators along deviation vectors (explorer.analysis.system_indicators): generated here,
# beside the recurrence they call, so that numba's cache of them follows the recurrence (docs/systems.md)
from explorer.integrate.lane_parts import indicator_early, indicator_history  # noqa: E402
from explorer.integrate.simd import atomic_fetch_add  # noqa: E402
from explorer.kernels import tangent as _tg  # noqa: E402
from explorer.kernels.checks import all_finite  # noqa: E402
from explorer.kernels.clock import advance_time  # noqa: E402
from explorer.kernels.status import STATUS_CANCELLED, STATUS_DONE, STATUS_MAX_STEPS, STATUS_NONFINITE  # noqa: E402
from explorer.kernels.taylor import safety_factor  # noqa: E402


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
        hpos = indicator_history(acc, hist_t, hist, hpos, row)
        if nvec == 2:
            _tg.renormalize(znew[2 * n:3 * n], n)
        for i in range(DIM):
            z[i] = znew[i]
        if early_stop:
            early, since = indicator_early(acc, z[n:2 * n], z[nvec * n:(nvec + 1) * n], n, nvec, sali_stop,
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
from explorer.integrate.lane_parts import (  # noqa: E402
    indicator_cancel_lanes, indicator_ends_lanes, indicator_lane_finish, indicator_lane_start,
    indicator_status, lane_step, next_history_time, norms_lanes, steps_lanes)
from explorer.integrate.simd import next_bit  # noqa: E402


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
        active += indicator_lane_start(l, next_orbit, Y0, V0, W0, n, nvec, T, max_steps, X, z, orb, L_on, L_t,
                                        L_tc, L_steps, L_early, L_hpos, L_hnext, L_since, hist_t, acc, out_hist,
                                        out_res, out_ext, out_status, out_final, out_steps, out_w)
    while active > 0:
        if stop[0] != 0:
            indicator_cancel_lanes(next_orbit, Y0.shape[0], n, nvec, X, z, orb, L_steps, L_early, acc, out_res,
                                    out_ext, out_status, out_final, out_steps, out_w)
            return
        taylor_coefficients_lanes(P, X, order, Wk)
        fin, normal = norms_lanes(X, order, n, e_p, e_q, NORM)
        bits = steps_lanes(NORM, fin, normal, L_on, L_t, T, factor, hv, L_last, L_go)
        while bits != 0:
            l, bits = next_bit(bits)
            st = lane_step(l, fin, normal, NORM, e_p, e_q, factor, L_t, T, hv, L_last, L_go)
            if st >= 0:
                indicator_lane_finish(l, st, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext,
                                       out_status, out_final, out_steps, out_w)
                active += indicator_lane_start(l, next_orbit, Y0, V0, W0, n, nvec, T, max_steps, X, z, orb, L_on,
                                                L_t, L_tc, L_steps, L_early, L_hpos, L_hnext, L_since, hist_t, acc,
                                                out_hist, out_res, out_ext, out_status, out_final, out_steps,
                                                out_w) - 1
        _evaluate_lanes(X, order, hv, Y)
        bits, stop_sali, stop_megno = indicator_ends_lanes(X, Y, hv, L_go, L_last, L_t, L_tc, L_steps, L_hnext,
                                                            L_since, acc, NRM, n, nvec, T, max_steps, early_stop,
                                                            sali_stop, megno_level, early_tmin)
        stops = stop_sali | stop_megno
        while stops != 0:
            l, stops = next_bit(stops)
            L_early[l] = _tg.EARLY_SALI if (stop_sali >> l) & 1 else _tg.EARLY_MEGNO
            indicator_lane_finish(l, STATUS_DONE, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext,
                                   out_status, out_final, out_steps, out_w)
            active += indicator_lane_start(l, next_orbit, Y0, V0, W0, n, nvec, T, max_steps, X, z, orb, L_on,
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
                L_hpos[l] = indicator_history(al, hist_t, out_hist[orb[l]], L_hpos[l], row)
                L_hnext[l] = next_history_time(hist_t, L_hpos[l])
                if nvec == 2:
                    _tg.renormalize(z[2 * n:3 * n], n)
                L_t[l] = t
                L_tc[l] = tc
                for i in range(DIM):
                    X[0, i, l] = z[i]
                if early_stop:
                    early, L_since[l] = indicator_early(al, z[n:2 * n], z[nvec * n:(nvec + 1) * n], n, nvec,
                                                         sali_stop, megno_level, early_tmin, L_since[l])
                    L_early[l] = early
                st = indicator_status(L_early[l], t, T, L_steps[l], max_steps)
            if st >= 0:
                indicator_lane_finish(l, st, n, nvec, X, z, orb, L_steps, L_early, acc, out_res, out_ext,
                                       out_status, out_final, out_steps, out_w)
                active += indicator_lane_start(l, next_orbit, Y0, V0, W0, n, nvec, T, max_steps, X, z, orb, L_on,
                                                L_t, L_tc, L_steps, L_early, L_hpos, L_hnext, L_since, hist_t, acc,
                                                out_hist, out_res, out_ext, out_status, out_final, out_steps,
                                                out_w) - 1
'''


def render(system) -> str:
    """The driver's source (the same for every system: its dimensions are DIM, n and nvec)."""
    return SOURCE
