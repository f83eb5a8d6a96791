"""Finiteness checks shared by every stepping loop (kernel contract: no exceptions, a status), and
the machine epsilon they and the step and root controls are written in."""
from explorer._jit import njit

#: the float64 machine epsilon 2**-52 (numpy.finfo(float).eps), written once for every kernel and
#: loop (a Numba global: a compile-time constant)
EPS = 2.220446049250313e-16


@njit(inline="always")
def is_finite(x):
    """True when x is finite: x - x == 0 only for finite x (inf - inf and NaN - NaN are NaN; no
    NaN test of its own, so it must never be compiled with fastmath).  Written with operators, so
    it is also the lane-wise test on a vector of lanes (explorer.integrate.simd)."""
    return x - x == 0.0


@njit
def all_finite(y):
    """True when every entry of the vector ``y`` is finite: one sum, finite only when every
    entry is (:func:`is_finite` of the sum)."""
    s = 0.0
    for i in range(y.shape[0]):
        s += y[i]
    return is_finite(s)
