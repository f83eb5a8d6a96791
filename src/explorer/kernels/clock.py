"""The integration clock shared by every adaptive driver.

- :func:`clip_step`: the last step of a run is shortened to end exactly at ``tend``;
- :func:`resolves`: a step too small to advance the clock (h <= eps |t|) is an underflow;
- :func:`advance_time`: compensated (Kahan) summation (:func:`compensated_add`) of the step sizes, so the clock does not
  drift over 1e7 steps (compare FMPy #106, preCICE #1933); the true time is ``t - tc``, and the
  last step lands exactly on ``tend``.
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
