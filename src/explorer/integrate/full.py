"""The body in the plane (docs/model.md R1, docs/commands/trajectory.md): adaptive DOP853 of R1
(:func:`explorer.integrate._systems_generated.dop853_step_full`) with samples at requested times and
the turning points of phi from the continuous extension.
"""
import math

import numpy as np

from explorer._jit import njit
from explorer.integrate._systems_generated import dop853_dense_stages_full, dop853_step_full
from explorer.integrate.systems import FIRST_STEP, STEP_OK
from explorer.kernels import STATUS_DONE
from explorer.kernels import dop853 as dp
from explorer.kernels.clock import advance_time
from explorer.kernels.events import dense_root
from explorer.model.equations import FULL_DIM
from explorer.model.parameters import B

TWO_PI = 2.0 * math.pi


@njit
def _branch(phi_guess, g1, g2):
    """atan2(g1, g2) + 2 pi k, the branch closest to phi_guess."""
    a = math.atan2(g1, g2)
    k = math.floor((phi_guess - a) / TWO_PI + 0.5)
    return a + TWO_PI * k


@njit
def integrate_full(y0, phi0, P, t_samples, rtol, atol, max_steps, out, out_phi, turns):
    """Adaptive DOP853 of R1 from t = 0 to t_samples[-1] (sorted, >= 0)."""
    n = FULL_DIM
    ns = t_samples.shape[0]
    cap = turns.shape[0]
    K = np.empty((16, n))
    F = np.empty((7, n))
    Fg = np.empty(7)
    tmp = np.empty(n)
    yc = np.empty(n)
    ynew = np.empty(n)
    ycur = np.empty(n)
    for i in range(n):
        ycur[i] = y0[i]
    b = P[B]
    phi = phi0
    tmax = t_samples[ns - 1]
    j = 0
    while j < ns and t_samples[j] <= 0.0:
        for i in range(n):
            out[j, i] = ycur[i]
        out_phi[j] = phi
        j += 1
    nturn = 0
    steps = 0
    if j >= ns:
        return STATUS_DONE, j, nturn, steps, 0.0
    t = 0.0
    tc = 0.0
    h_abs = FIRST_STEP
    while True:
        code, h, last, h_abs, steps = dop853_step_full(ycur, P, K, t, tmax, STATUS_DONE, h_abs, steps,
                                                       max_steps, rtol, atol, tmp, ynew, True)
        if code != STEP_OK:
            break
        t_old = t - tc
        t_new = tmax if last else t_old + h
        m_old = ycur[2]
        m_new = ynew[2]
        sign_m = (m_old < 0.0 and m_new >= 0.0) or (m_old > 0.0 and m_new <= 0.0)
        need_dense = sign_m or (j < ns and t_samples[j] <= t_new)
        if need_dense:
            dop853_dense_stages_full(ycur, P, K, h, tmp)
            dp.dense_coefficients(ycur, ynew, K, h, F)
            if sign_m:
                for k in range(7):
                    Fg[k] = F[k, 2]
                theta = dense_root(Fg, m_old, m_new)
                dp.dense_eval(F, ycur, theta, yc)
                if nturn < cap:
                    turns[nturn, 0] = t_old + theta * h
                    turns[nturn, 1] = _branch(phi + theta * h * (m_old + yc[2]) / (2.0 * b), yc[3], yc[4])
                    turns[nturn, 2] = 1.0 if m_new > m_old else -1.0
                nturn += 1
            while j < ns and t_samples[j] <= t_new:
                theta = (t_samples[j] - t_old) / h
                if theta > 1.0:
                    theta = 1.0
                if theta < 0.0:
                    theta = 0.0
                dp.dense_eval(F, ycur, theta, yc)
                for i in range(n):
                    out[j, i] = yc[i]
                out_phi[j] = _branch(phi + theta * h * (m_old + yc[2]) / (2.0 * b), yc[3], yc[4])
                j += 1
        phi = _branch(phi + h * (m_old + m_new) / (2.0 * b), ynew[3], ynew[4])
        t, tc = advance_time(t, tc, h, last, tmax)
        for i in range(n):
            ycur[i] = ynew[i]
            K[0, i] = K[12, i]
    return code, j, nturn, steps, t - tc
