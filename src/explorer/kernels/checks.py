"""Finiteness checks shared by every stepping loop (kernel contract: no exceptions, a status), and
the machine epsilon they and the step and root controls are written in."""
from explorer._jit import njit

#: the float64 machine epsilon 2**-52 (numpy.finfo(float).eps), written once for every kernel and
#: loop (a Numba global: a compile-time constant)
EPS = 2.220446049250313e-16


@njit
def all_finite(y):
    """True when every entry of the vector ``y`` is finite: one sum, s - s == 0 only for finite s
    (no NaN test of its own, so it must never be compiled with fastmath)."""
    s = 0.0
    for i in range(y.shape[0]):
        s += y[i]
    return s - s == 0.0
