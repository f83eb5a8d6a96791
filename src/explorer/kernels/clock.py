"""The integration clock shared by every adaptive driver.

- :func:`clip_step`: the last step of a run is shortened to end exactly at ``tend``;
- :func:`advance_time`: compensated (Kahan) summation of the step sizes, so the clock does not
  drift over 1e7 steps (compare FMPy #106, preCICE #1933); the true time is ``t - tc``, and the
  last step lands exactly on ``tend``.
"""
from explorer._jit import njit


@njit
def clip_step(t, h, tend):
    """(h', last): h shortened to tend - t when t + h reaches tend."""
    if t + h >= tend:
        return tend - t, True
    return h, False


@njit
def advance_time(t, tc, h, last, tend):
    """Compensated t += h with its carried error tc; returns (t, tc)."""
    if last:
        return tend, 0.0
    yk = h - tc
    tn = t + yk
    return tn, (tn - t) - yk
