"""Finiteness checks shared by every stepping loop (kernel contract: no exceptions, a status)."""
from explorer._jit import njit


@njit
def all_finite(y):
    """True when every entry of the vector ``y`` is finite: one sum, s - s == 0 only for finite s
    (no NaN test of its own, so it must never be compiled with fastmath)."""
    s = 0.0
    for i in range(y.shape[0]):
        s += y[i]
    return s - s == 0.0
