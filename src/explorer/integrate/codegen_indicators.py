"""The chaos-indicator driver appended to every generated module (:data:`explorer.integrate.codegen.TEMPLATES`):
``indicators_taylor``, the adaptive Taylor method on the variational system of
:meth:`explorer.model.system.System.variational` with the indicators of :mod:`explorer.kernels.tangent`
(docs/systems.md, "Chaos indicators"), called by :mod:`explorer.analysis.system_indicators`.

It is rendered into every module but compiled only when called, on the module of ``System.variational(nvec)``:
its rows are the state (n), then nvec deviation vectors (n each), so DIM = n (1 + nvec).
"""
from __future__ import annotations

__all__ = ["render"]

SOURCE = '''

# ---- chaos indicators along deviation vectors (explorer.analysis.system_indicators): generated here,
# beside the recurrence they call, so that numba's cache of them follows the recurrence (docs/systems.md)
from explorer._jit import prange  # noqa: E402
from explorer.kernels import tangent as _tg  # noqa: E402
from explorer.kernels.checks import all_finite, is_finite  # noqa: E402
from explorer.kernels.clock import clip_step, resolves  # noqa: E402
from explorer.kernels.status import (  # noqa: E402
    STATUS_DONE, STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW)
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
                     hist_t, hist, res, ext, wout, yout):
    """The orbit from y0 and nvec (1 or 2) deviation vectors from v0, w0 (made unit) over the time T
    by the adaptive Taylor method of ``order`` on the variational system (Jorba & Zou 2005; the step
    from the orbit's rows only, as explorer.integrate.systems.taylor_step, so the vectors do not
    change the orbit), the vectors renormalised after every step and the indicators accumulated by
    kernels.tangent (the engine's formulas and columns).  Returns (status, steps); res the result
    row, ext (SALI, GALI_2, early code; NaN without a second vector), wout the final unit vectors,
    yout the final state, hist the rows at the times hist_t."""
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
        for i in range(DIM):
            X[i, 0] = z[i]
        st, h, last, steps = taylor_step(P, X, Wk, n, t, T, order, factor, steps, znew)
        if st != STEP_OK:
            status = st
            break
        t_new = T if last else t + h
        dlog = _tg.renormalize(znew[n:2 * n], n)
        _tg.accumulate(acc, t, t_new, dlog)
        hpos = _indicator_history(acc, hist_t, hist, hpos, row)
        if nvec == 2:
            _tg.renormalize(znew[2 * n:3 * n], n)
        t = t_new
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


@njit(parallel=True, error_model="numpy")
def indicators_taylor(Y0, V0, W0, n, nvec, P, T, order, max_steps, early_stop, sali_stop, megno_level, early_tmin,
                      hist_t, out_hist, out_res, out_ext, out_status, out_final, out_steps, out_w):
    """:func:`indicators_orbit` for every orbit (row of Y0), in parallel over orbits: each orbit
    is computed alone, so the result does not depend on the number of threads."""
    for j in prange(Y0.shape[0]):
        s, k = indicators_orbit(Y0[j], V0[j], W0[j], n, nvec, P, T, order, max_steps, early_stop, sali_stop,
                                megno_level, early_tmin, hist_t, out_hist[j], out_res[j], out_ext[j], out_w[j],
                                out_final[j])
        out_status[j] = s
        out_steps[j] = k
'''


def render(system) -> str:
    """The driver's source (the same for every system: its dimensions are DIM, n and nvec)."""
    return SOURCE
