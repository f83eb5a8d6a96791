"""Model-agnostic accumulators of chaos indicators along a tangent vector.

After every step the caller renormalises the deviation vector (:func:`renormalize`, which
returns ln of its norm, the log-stretch of the step) and hands the stretch to
:func:`accumulate`.  From ell(t) = ln |delta(t)| / |delta(0)| accumulated over the steps:

- maximal Lyapunov exponent, finite-time:  chi(t) = ell(t) / t  (Benettin et al. 1980);
- MEGNO (Cincotta & Simó 2000, A&AS 147, 205):  Y(t) = (2/t) int_0^t s dell(s),
  mean <Y>(t) = (1/t) int_0^t Y(s) ds; <Y> -> 2 for quasi-periodic orbits, ~ chi t / 2 for
  chaotic ones, -> 0 for stable periodic ones;
- FLI (Froeschlé, Lega & Gonczi 1997):  max_{s <= t} ell(s).

The integrals over a step use the trapezoid rule in time on the step's stretch; renormalising
every step keeps the vector O(1) (the tangent equations are linear, so this changes nothing
but round-off; Skokos 2010, Lect. Notes Phys. 790, 63).

With a second deviation vector (both renormalised every step, each to unit norm):

- SALI (Skokos 2001, J. Phys. A 34, 10029):  min(|w1 + w2|, |w1 - w2|) of the unit vectors;
  stays away from 0 on regular orbits of two degrees of freedom, -> 0 exponentially fast
  on chaotic ones (the two vectors align with the most unstable direction);
- GALI_2 (Skokos, Bountis & Antonopoulos 2007, Physica D 231, 30):  |w1 ^ w2|, the norm of the
  wedge product of the unit vectors, sqrt(sum_{i<j} (w1_i w2_j - w1_j w2_i)^2) (the area of
  their parallelogram); ~ SALI on chaotic orbits.

A new indicator: its columns and entry in :mod:`explorer.kernels.indicator_table`, its update
in :func:`accumulate` and :func:`result` (every scalar tangent loop calls these two; the tangent
lanes' vector step end calls accumulate's pieces, :func:`megno_weight` ..., on vectors, and
must learn a new accumulator too: tests/integrate/test_tangent_lanes.py compares them bit for bit),
or, for one of two deviation vectors, its value in :func:`extra` (called at the end of the
Taylor tangent loops, scalar and lanes).

Early classification (:func:`megno_early`): an orbit whose <Y> has stayed above a level at
every step end of [t/2, t], t >= tmin, is classified chaotic at t and stops.
"""
import math

from explorer._jit import njit

# the layout of the accumulator, result and extra rows: the indicator registry (pure Python),
# re-exported here for the compiled loops (tg.RES_*, tg.EXT_*)
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


# MEGNO's sums over a step, written with operators: :func:`accumulate` calls them on doubles, the
# tangent lanes (explorer.integrate.tangent_lanes) on vectors of lanes
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
    current run of step ends with <Y> > ``level`` (-1 when <Y> <= level at the last one).  Returns
    (stop, since): stop when <Y> has stayed above ``level`` at every step end of [t/2, t] (since
    <= t/2) and t >= ``tmin``."""
    t = acc[ACC_T]
    ym = acc[ACC_YINT] / t if t > 0.0 else 0.0
    if ym > level:
        if since < 0.0:
            since = t
    else:
        since = -1.0
    return since >= 0.0 and t >= tmin and 2.0 * since <= t, since
