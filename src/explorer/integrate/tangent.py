"""Compiled loops of the orbit and one deviation vector under the tangent dynamics of each
integrator (the Taylor variational series, DOP853 on (y, v), the exact tangent maps of the
sub-flows: Skokos & Gerlach 2010), the indicators of :mod:`explorer.kernels.tangent`, and the
section return map with its Jacobian (docs/commands/lyapunov.md, docs/architecture.md).
The Taylor indicators of :func:`explorer.analysis.lyapunov.indicators` (one or two vectors, early
stops, on SIMD lanes) run on the drivers of every System (:func:`indicators_module`).
"""
import functools

import numpy as np

from explorer._jit import njit, prange
from explorer.integrate import _systems_generated as sg
from explorer.integrate._tangent_lanes_generated import tangent_coefficients
from explorer.integrate.drivers import ON_SECTION
from explorer.integrate.lane_parts import indicator_history
from explorer.integrate.systems import FIRST_STEP, STEP_OK, reverse_time
from explorer.kernels import STATUS_CANCELLED, STATUS_DONE
from explorer.kernels import STATUS_TMAX as STATUS_TMAX_CODE
from explorer.kernels import tangent as tg
from explorer.kernels import taylor as tk
from explorer.kernels.events import poly_step_roots, root_workspace, sin_diff
from explorer.model.equations import (
    G1,
    G2,
    section_c,
    section_g,
)


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
    return indicator_history(acc, hist_t, hist, hpos, row)


@functools.cache
def indicators_module(nvec: int):
    """The generated module of Chaplygin's variational system of ``nvec`` deviation vectors
    (:func:`explorer.model.chaplygin.variational`) whose orbit rows are R3's recurrence bit for bit
    (:func:`explorer.integrate.codegen.decompose_extending`): its indicator drivers are a System's
    (:mod:`explorer.integrate.codegen_indicators`, docs/systems.md "Chaos indicators")."""
    from explorer.integrate import codegen
    from explorer.model import chaplygin

    return codegen.load(chaplygin.variational(vectors=nvec), orbit=chaplygin.system())


@njit
def orbit_tangent_dop853(y0, v0, P, T, rtol, atol, max_steps, hist_t, hist, res, yout, stop):
    """The orbit and one deviation vector by DOP853 on (y, v) (the step:
    :func:`explorer.integrate._systems_generated.dop853_step_tangent`); STATUS_CANCELLED before a step once
    the caller's switch ``stop[0]`` is set (analysis.budget)."""
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
        if stop[0] != 0:
            code = STATUS_CANCELLED
            break
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
def orbit_tangent_split(y0, v0, P, T, dt, flow_ids, fracs, max_steps, hist_t, hist, res, yout, stop):
    """The orbit and one deviation vector by the splitting method's own tangent map (the step:
    :func:`explorer.integrate._systems_generated.split_step_tangent`); t_n = n dt; STATUS_CANCELLED before
    a step once ``stop[0]`` is set."""
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
        if stop[0] != 0:
            code = STATUS_CANCELLED
            break
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
def run_tangent_dop853_batch(Y0, V0, P, T, rtol, atol, max_steps, hist_t, out_hist, out_res, out_status,
                             out_final, out_steps, stop):
    for j in prange(Y0.shape[0]):
        _store(j, orbit_tangent_dop853(Y0[j], V0[j], P, T, rtol, atol, max_steps, hist_t, out_hist[j],
                                       out_res[j], out_final[j], stop), out_status, out_steps)
    return 0


@njit(parallel=True, nogil=True)
def run_tangent_split_batch(Y0, V0, P, T, dt, flow_ids, fracs, max_steps, hist_t, out_hist, out_res,
                            out_status, out_final, out_steps, stop):
    for j in prange(Y0.shape[0]):
        _store(j, orbit_tangent_split(Y0[j], V0[j], P, T, dt, flow_ids, fracs, max_steps, hist_t,
                                      out_hist[j], out_res[j], out_final[j], stop), out_status, out_steps)
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
