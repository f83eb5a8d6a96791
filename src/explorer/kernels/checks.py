"""Finiteness checks of the stepping loops and the machine epsilon of their controls."""
from explorer._jit import njit

#: the float64 machine epsilon 2**-52 (numpy.finfo(float).eps), written once for every kernel and
#: loop (a Numba global: a compile-time constant)
EPS = 2.220446049250313e-16


@njit(inline="always")
def is_finite(x):
    """True when x is finite: x - x == 0 only for finite x (inf - inf and NaN - NaN are NaN; no
    NaN test of its own, so it must never be compiled with fastmath)."""
    return x - x == 0.0


@njit
def all_finite(y):
    """True when every entry of the vector ``y`` is finite: one sum, finite only when every
    entry is (:func:`is_finite` of the sum)."""
    s = 0.0
    for i in range(y.shape[0]):
        s += y[i]
    return is_finite(s)
