"""Model-agnostic accumulators of chaos indicators along deviation vectors renormalised every step
(docs/commands/lyapunov.md): mLCE (Benettin et al. 1980), MEGNO (Cincotta & Simo 2000), FLI
(Froeschle, Lega & Gonczi 1997) from the log-stretches; SALI (Skokos 2001) and GALI_2 (Skokos,
Bountis & Antonopoulos 2007) from two vectors; the early classification.  A new indicator:
docs/contributing.md.
"""
import math

from explorer._jit import njit
from explorer.kernels.indicator_table import (  # noqa: F401
    ACC_FLI,
    ACC_LOG,
    ACC_T,
    ACC_W,
    ACC_Y,
    ACC_YINT,
    EXT_EARLY,
    EXT_GALI2,
    EXT_SALI,
    N_ACC,
    N_EXT,
    N_RES,
    RES_FLI,
    RES_MEGNO,
    RES_MLCE,
    RES_T,
    RES_Y,
)


@njit
def renormalize(v, n):
    """Scale v[:n] to unit Euclidean norm in place and return ln of its former norm."""
    s = 0.0
    for i in range(n):
        s += v[i] * v[i]
    norm = math.sqrt(s)
    inv = 1.0 / norm
    for i in range(n):
        v[i] *= inv
    return math.log(norm)


@njit
def reset(acc):
    for i in range(N_ACC):
        acc[i] = 0.0


@njit(inline="always")
def megno_weight(w, t0, t1, dlog):
    """W = int_0^t s dell(s) after the step [t0, t1] of stretch dlog (trapezoid in time)."""
    return w + 0.5 * (t0 + t1) * dlog


@njit(inline="always")
def megno_y(w, t1):
    """Y(t1) = 2 W / t1 (for t1 > 0)."""
    return 2.0 * w / t1


@njit(inline="always")
def megno_mean_integral(yint, y0, y1, t0, t1):
    """int_0^t Y(s) ds after the step [t0, t1] (trapezoid: Y = y0 at t0, y1 at t1)."""
    return yint + 0.5 * (y0 + y1) * (t1 - t0)


@njit
def accumulate(acc, t0, t1, dlog):
    """Add one step [t0, t1] with log-stretch dlog."""
    acc[ACC_LOG] += dlog
    acc[ACC_W] = megno_weight(acc[ACC_W], t0, t1, dlog)
    y1 = megno_y(acc[ACC_W], t1) if t1 > 0.0 else 0.0
    acc[ACC_YINT] = megno_mean_integral(acc[ACC_YINT], acc[ACC_Y], y1, t0, t1)
    acc[ACC_Y] = y1
    acc[ACC_T] = t1
    if acc[ACC_LOG] > acc[ACC_FLI]:
        acc[ACC_FLI] = acc[ACC_LOG]


@njit
def result(acc, out):
    """out = (t, mLCE, mean MEGNO <Y>, Y, FLI)."""
    t = acc[ACC_T]
    out[RES_T] = t
    out[RES_MLCE] = acc[ACC_LOG] / t if t > 0.0 else 0.0
    out[RES_MEGNO] = acc[ACC_YINT] / t if t > 0.0 else 0.0
    out[RES_Y] = acc[ACC_Y]
    out[RES_FLI] = acc[ACC_FLI]


#: why an orbit stopped before T (EXT_EARLY): it did not, SALI fell below its level, <Y> stayed high
EARLY_NONE, EARLY_SALI, EARLY_MEGNO = 0, 1, 2


@njit
def sali(v, w, n):
    """SALI = min(|v + w|, |v - w|) of unit vectors v[:n], w[:n] (Skokos 2001)."""
    sp = 0.0
    sm = 0.0
    for i in range(n):
        a = v[i] + w[i]
        b = v[i] - w[i]
        sp += a * a
        sm += b * b
    return math.sqrt(min(sp, sm))


@njit
def gali2(v, w, n):
    """GALI_2 = |v ^ w| = sqrt(sum_{i<j} (v_i w_j - v_j w_i)^2) of unit vectors v[:n], w[:n]
    (Skokos, Bountis & Antonopoulos 2007; the wedge product's norm, accurate when they align)."""
    s = 0.0
    for i in range(n):
        for j in range(i + 1, n):
            m = v[i] * w[j] - v[j] * w[i]
            s += m * m
    return math.sqrt(s)


@njit
def extra(v, w, n, ext):
    """The indicators of two unit deviation vectors v[:n], w[:n] into their columns of the extra
    row (EXT_SALI, EXT_GALI2; EXT_EARLY is the caller's)."""
    ext[EXT_SALI] = sali(v, w, n)
    ext[EXT_GALI2] = gali2(v, w, n)


@njit
def megno_early(acc, since, level, tmin):
    """The MEGNO rule of early classification after a step: ``since`` is the first step end of the
    current run of step ends with <Y> > ``level`` (-1 when <Y> <= level at the last one)."""
    t = acc[ACC_T]
    ym = acc[ACC_YINT] / t if t > 0.0 else 0.0
    if ym > level:
        if since < 0.0:
            since = t
    else:
        since = -1.0
    return since >= 0.0 and t >= tmin and 2.0 * since <= t, since
