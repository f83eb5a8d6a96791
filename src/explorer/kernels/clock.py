"""The integration clock of every adaptive driver: the last step clipped to ``tend``, the
underflow test, and Kahan-compensated time (the true time is t - tc).
"""
from explorer._jit import njit
from explorer.kernels.checks import EPS


@njit
def clip_step(t, h, tend):
    """(h', last): h shortened to tend - t when t + h reaches tend."""
    if t + h >= tend:
        return tend - t, True
    return h, False


@njit(inline="always")
def resolves(t, h):
    """True when a step h from time t is resolved: h > eps |t| (else t + h does not advance the
    clock: a step underflow).  Written with operators: also lane-wise on vectors of lanes."""
    return h > EPS * abs(t)


@njit(inline="always")
def compensated_add(t, tc, h):
    """Kahan's compensated t += h with the carried error tc: returns (t', tc').  Written with
    operators: also lane-wise on vectors of lanes (explorer.integrate.lanes.end_steps_lanes)."""
    yk = h - tc
    tn = t + yk
    return tn, (tn - t) - yk


@njit
def advance_time(t, tc, h, last, tend):
    """Compensated t += h with its carried error tc (:func:`compensated_add`), the last step
    landing exactly on tend; returns (t, tc)."""
    if last:
        return tend, 0.0
    return compensated_add(t, tc, h)
