"""Compiled loops of the orbit and one deviation vector under the tangent dynamics of each
integrator (the Taylor variational series, DOP853 on (y, v), the exact tangent maps of the
sub-flows: Skokos & Gerlach 2010), the indicators of :mod:`explorer.kernels.tangent`, and the
section return map with its Jacobian (docs/commands/lyapunov.md, docs/architecture.md).
"""

import numpy as np

from explorer._jit import njit, prange
from explorer.integrate import _systems_generated as sg
from explorer.integrate._tangent_lanes_generated import (
    DEV2,
    N_WORK_TANGENT,
    NROWS,
    deviation_coefficients_into,
    tangent_coefficients,
)
from explorer.integrate.drivers import ON_SECTION
from explorer.integrate.systems import FIRST_STEP, STEP_OK, reverse_time
from explorer.kernels import STATUS_CANCELLED, STATUS_DONE, STATUS_NONFINITE
from explorer.kernels import STATUS_TMAX as STATUS_TMAX_CODE
from explorer.kernels import tangent as tg
from explorer.kernels import taylor as tk
from explorer.kernels.checks import all_finite
from explorer.kernels.events import poly_step_roots, root_workspace, sin_diff
from explorer.model.equations import (
    G1,
    G2,
    section_c,
    section_g,
)


@njit
def _history(acc, hist_t, hist, hpos, row):
    while hpos < hist_t.shape[0] and acc[tg.ACC_T] >= hist_t[hpos]:
        tg.result(acc, row)
        for c in range(tg.N_RES):
            hist[hpos, c] = row[c]
        hpos += 1
    return hpos


@njit
def _start(y0, v0, z):
    """z = (y0, v0 / |v0|): the state a tangent loop starts from."""
    for i in range(5):
        z[i] = y0[i]
        z[5 + i] = v0[i]
    tg.renormalize(z[5:], 5)


@njit
def _end(acc, res, z, yout):
    """The indicators (t, mLCE, <Y>, Y, FLI) from the accumulators, and the orbit's final state."""
    tg.result(acc, res)
    for i in range(5):
        yout[i] = z[i]


@njit
def _store(j, result, out_status, out_steps):
    """Orbit j's (status, steps) from its loop."""
    out_status[j] = result[0]
    out_steps[j] = result[1]


@njit
def _observe(acc, v, t_old, t_new, hist_t, hist, hpos, row):
    dlog = tg.renormalize(v, 5)
    tg.accumulate(acc, t_old, t_new, dlog)
    return _history(acc, hist_t, hist, hpos, row)


@njit
def orbit_tangent_taylor(y0, v0, P, T, order, max_steps, hist_t, hist, res, yout):
    """The orbit and one deviation vector by the Taylor series of R3 and its variational
    equations (the step: :func:`explorer.integrate._systems_generated.taylor_step_tangent`, chosen
    from the orbit's own coefficients): :func:`orbit_tangent_taylor_ext` with one vector and no
    early classification."""
    ext = np.empty(tg.N_EXT)
    wout = np.empty((2, 5))
    return orbit_tangent_taylor_ext(y0, v0, v0, 1, P, T, order, max_steps, False, 0.0, 0.0, 0.0, hist_t, hist, res,
                                    ext, wout, yout)

@njit
def _early(acc, v, w, nvec, sali_stop, megno_level, tmin, since):
    if nvec == 2 and sali_stop > 0.0 and tg.sali(v, w, 5) < sali_stop:
        return tg.EARLY_SALI, since
    if megno_level > 0.0:
        stop, since = tg.megno_early(acc, since, megno_level, tmin)
        if stop:
            return tg.EARLY_MEGNO, since
    return tg.EARLY_NONE, since


@njit
def _finish_ext(acc, v, w, nvec, early, res, ext, wout):
    """The result row, (SALI, GALI_2, early code) and the final unit deviation vectors."""
    tg.result(acc, res)
    for i in range(5):
        wout[0, i] = v[i]
        if nvec == 2:
            wout[1, i] = w[i]
    if nvec == 2:
        tg.extra(v, w, 5, ext)
    else:
        for c in range(tg.N_EXT):
            ext[c] = np.nan
    ext[tg.EXT_EARLY] = early


@njit
def orbit_tangent_taylor_ext(y0, v0, w0, nvec, P, T, order, max_steps, early_stop, sali_stop, megno_level,
                             early_tmin, hist_t, hist, res, ext, wout, yout):
    """:func:`orbit_tangent_taylor` with a second deviation vector ``w0`` (nvec = 2: SALI and
    GALI_2; its coefficients in rows DEV2.. of the lanes' 15-row array, from the orbit's, by the
    generated deviation_coefficients) and the early classification (``early_stop``: :func:`_early`
    after every step; the orbit stops with STATUS_DONE at the time reached and its EARLY_* code in
    ext).  With
    nvec = 1 and no early stop the orbit, steps and indicators are those of
    :func:`orbit_tangent_taylor` bit for bit.  The scalar reference of
    :mod:`explorer.integrate.tangent_lanes`."""
    n = 10
    Z3 = np.empty((NROWS, order + 1))   # the orbit, v and w, as in the lanes
    Z = Z3[:n]
    Wd = np.empty((N_WORK_TANGENT, order + 1))
    z = np.empty(n)
    znew = np.empty(n)
    w = np.zeros(5)
    wnew = np.empty(5)
    acc = np.zeros(tg.N_ACC)
    row = np.empty(tg.N_RES)
    factor = tk.safety_factor(order)
    for i in range(5):
        z[i] = y0[i]
        z[5 + i] = v0[i]
        w[i] = w0[i]
    tg.renormalize(z[5:], 5)
    if nvec == 2:
        tg.renormalize(w, 5)
    t = 0.0
    steps = 0
    hpos = 0
    since = -1.0
    early = tg.EARLY_NONE
    while True:
        for i in range(n):
            Z[i, 0] = z[i]
        code, h, last, steps = sg.taylor_step_tangent(Z, P, t, T, STATUS_DONE, order, factor, steps,
                                                      max_steps, znew)
        if code != STEP_OK:
            break
        if nvec == 2:
            for i in range(5):
                Z3[DEV2 + i, 0] = w[i]
            deviation_coefficients_into(P, Z3, order, Wd)
            tk.evaluate(Z3[DEV2:], order, h, wnew)
            if not all_finite(wnew):
                code = STATUS_NONFINITE
                break
        t_new = T if last else t + h
        hpos = _observe(acc, znew[5:], t, t_new, hist_t, hist, hpos, row)
        if nvec == 2:
            tg.renormalize(wnew, 5)
            for i in range(5):
                w[i] = wnew[i]
        t = t_new
        for i in range(n):
            z[i] = znew[i]
        if early_stop:
            early, since = _early(acc, z[5:], w, nvec, sali_stop, megno_level, early_tmin, since)
            if early != tg.EARLY_NONE:
                code = STATUS_DONE
                break
    _finish_ext(acc, z[5:], w, nvec, early, res, ext, wout)
    for i in range(5):
        yout[i] = z[i]
    return code, steps


@njit
def orbit_tangent_dop853(y0, v0, P, T, rtol, atol, max_steps, hist_t, hist, res, yout):
    n = 10
    K = np.empty((16, n))
    z = np.empty(n)
    znew = np.empty(n)
    tmp = np.empty(n)
    acc = np.zeros(tg.N_ACC)
    row = np.empty(tg.N_RES)
    t = 0.0
    steps = 0
    hpos = 0
    h_abs = FIRST_STEP
    _start(y0, v0, z)
    while True:
        code, h, last, h_abs, steps = sg.dop853_step_tangent(z, P, K, t, T, STATUS_DONE, h_abs, steps,
                                                             max_steps, rtol, atol, tmp, znew, False)
        if code != STEP_OK:
            break
        t_new = T if last else t + h
        hpos = _observe(acc, znew[5:], t, t_new, hist_t, hist, hpos, row)
        t = t_new
        for i in range(n):
            z[i] = znew[i]
        sg.field_tangent(z, P, K[0])
    _end(acc, res, z, yout)
    return code, steps


@njit
def orbit_tangent_split(y0, v0, P, T, dt, flow_ids, fracs, max_steps, hist_t, hist, res, yout):
    """The orbit and one deviation vector by the splitting method's own tangent map (the step:
    :func:`explorer.integrate._systems_generated.split_step_tangent`); t_n = n dt."""
    n = 10
    z = np.empty(n)
    znew = np.empty(n)
    acc = np.zeros(tg.N_ACC)
    row = np.empty(tg.N_RES)
    _start(y0, v0, z)
    steps = 0
    hpos = 0
    code = STATUS_DONE
    nsteps = int(np.ceil(T / dt - 1e-9))
    while steps < nsteps:
        code, steps = sg.split_step_tangent(z, P, dt, flow_ids, fracs, steps, max_steps, znew)
        if code != STEP_OK:
            break
        hpos = _observe(acc, znew[5:], (steps - 1) * dt, steps * dt, hist_t, hist, hpos, row)
        for i in range(n):
            z[i] = znew[i]
        code = STATUS_DONE
    _end(acc, res, z, yout)
    return code, steps


@njit(parallel=True, nogil=True)
def run_tangent_taylor_batch(Y0, V0, P, T, order, max_steps, hist_t, out_hist, out_res, out_status,
                             out_final, out_steps):
    for j in prange(Y0.shape[0]):
        _store(j, orbit_tangent_taylor(Y0[j], V0[j], P, T, order, max_steps, hist_t, out_hist[j], out_res[j],
                                       out_final[j]), out_status, out_steps)
    return 0


@njit(parallel=True, nogil=True)
def run_tangent_dop853_batch(Y0, V0, P, T, rtol, atol, max_steps, hist_t, out_hist, out_res, out_status,
                             out_final, out_steps):
    for j in prange(Y0.shape[0]):
        _store(j, orbit_tangent_dop853(Y0[j], V0[j], P, T, rtol, atol, max_steps, hist_t, out_hist[j],
                                       out_res[j], out_final[j]), out_status, out_steps)
    return 0


@njit(parallel=True, nogil=True)
def run_tangent_split_batch(Y0, V0, P, T, dt, flow_ids, fracs, max_steps, hist_t, out_hist, out_res,
                            out_status, out_final, out_steps):
    for j in prange(Y0.shape[0]):
        _store(j, orbit_tangent_split(Y0[j], V0[j], P, T, dt, flow_ids, fracs, max_steps, hist_t,
                                      out_hist[j], out_res[j], out_final[j]), out_status, out_steps)
    return 0


# nogil: the section map calls it from a page's thread while the server's event loop runs
@njit(nogil=True)
def return_map_taylor(y0, V0, P, cphi, sphi, tsign, tmax, order, max_steps, stop, yout, Vout):
    """The next crossing of the section phi = phi0 (phi increasing through phi0 in forward time)
    from y0, forward (tsign = +1) or backward (tsign = -1) in time, with the tangent map of the
    flow applied to the rows of V0 (m deviation vectors) up to the crossing time.  Stops on the
    switch ``stop[0]`` != 0 (STATUS_CANCELLED), ``tmax`` or ``max_steps``; returns (status, signed time)."""
    m = V0.shape[0]
    X = np.empty((5, order + 1))
    D = np.empty((m, 10, order + 1))   # per vector, the orbit and the vector (rows 5..9)
    y = np.empty(5)
    ynew = np.empty(5)
    gc, work, roots, brackets, stack = root_workspace(order)
    factor = tk.safety_factor(order)
    V = np.empty((m, 5))
    for i in range(5):
        y[i] = y0[i]
        for r in range(m):
            V[r, i] = V0[r, i]
    direction = 1 if tsign > 0 else -1
    g0 = section_g(y, cphi, sphi)
    gprev = 0.0 if abs(g0) <= ON_SECTION else g0
    s = 0.0
    steps = 0
    while True:
        if stop[0] != 0:
            return STATUS_CANCELLED, tsign * s
        for i in range(5):
            X[i, 0] = y[i]
        if tsign > 0:
            code, h, _last, steps = sg.taylor_step_reduced(X, P, s, tmax, STATUS_TMAX_CODE, order, factor, steps,
                                                           max_steps, ynew)
        else:   # the inverse map: R3 in reversed time
            code, h, _last, steps = sg.taylor_step_backward(X, P, s, tmax, STATUS_TMAX_CODE, order, factor, steps,
                                                            max_steps, ynew)
        if code != STEP_OK:
            return code, tsign * s
        for r in range(m):
            for i in range(5):
                D[r, i, 0] = y[i]
                D[r, 5 + i, 0] = V[r, i]
            tangent_coefficients(P, D[r], order)
            if tsign < 0:
                reverse_time(D[r], order)
        gnew = section_g(ynew, cphi, sphi)
        found = False
        tau = h
        for k in range(order + 1):
            gc[k] = sin_diff(X[G1, k], X[G2, k], cphi, sphi)
        nroots = poly_step_roots(gc, order, h, gprev, gnew, direction, roots, brackets, work,
                                 stack)
        for r in range(nroots):
            tau = roots[r]
            tk.evaluate(X, order, tau, yout)
            if section_c(yout, cphi, sphi) > 0.0:
                found = True
                break
        if found:
            for r in range(m):
                tk.evaluate(D[r, 5:], order, tau, Vout[r])
            return STATUS_DONE, tsign * (s + tau)
        for r in range(m):
            tk.evaluate(D[r, 5:], order, h, V[r])
        for i in range(5):
            y[i] = ynew[i]
        s += h
        gprev = gnew
