"""Root refinement of event functions inside one step.

An event function linear in the state (such as sin(phi - phi0) =
g1 cos phi0 - g2 sin phi0) evaluated on the step's interpolant is a scalar
polynomial in the step fraction, so the crossing is located to the order of
the integrator, never by linear interpolation.  The root finder is a
safeguarded Newton iteration on a sign-changing bracket (Newton step when it
stays inside the bracket, bisection otherwise), stopped at ROOT_XTOL of the
step length.  Compare scipy's event handling (brentq, xtol = 4 eps).
"""
import math

from .._jit import njit
from .dop853 import dense_eval_scalar, dense_eval_scalar_derivative

EPS = 2.220446049250313e-16
#: stop when the Newton correction falls below this fraction of the step
ROOT_XTOL = 4.0 * EPS
ROOT_MAX_ITER = 100


@njit
def sign_change(g_prev, g_new, direction):
    """Half-open crossing test on (t_prev, t_new]: +1 means g goes from < 0 to >= 0,
    -1 from > 0 to <= 0, 0 either.  A root exactly at a step end fires once (in the
    step that ends on it) and a start exactly on the section (g_prev = 0) never fires."""
    if direction >= 0 and g_prev < 0.0 and g_new >= 0.0:
        return True
    if direction <= 0 and g_prev > 0.0 and g_new <= 0.0:
        return True
    return False


@njit
def poly_value_derivative(c, order, x):
    """(sum_k c_k x^k, sum_k k c_k x^(k-1))."""
    v = c[order]
    d = 0.0
    for k in range(order - 1, -1, -1):
        d = d * x + v
        v = v * x + c[k]
    return v, d


@njit
def poly_root(c, order, h, g_lo, g_hi):
    """Root in (0, h] of the polynomial sum_k c_k x^k, given g(0) = g_lo and g(h) = g_hi of
    opposite signs (or g_hi == 0).  Safeguarded Newton; returns x."""
    if g_hi == 0.0:
        return h
    a = 0.0
    b = h
    ga = g_lo
    x = a - ga * (b - a) / (g_hi - ga)  # secant start
    if not (x > a and x < b):
        x = 0.5 * (a + b)
    tol = ROOT_XTOL * abs(h)
    for _ in range(ROOT_MAX_ITER):
        g, d = poly_value_derivative(c, order, x)
        if g == 0.0:
            return x
        if (g < 0.0) == (ga < 0.0):
            a = x
            ga = g
        else:
            b = x
        xn = x - g / d if d != 0.0 else 0.5 * (a + b)
        if not (xn > a and xn < b):
            xn = 0.5 * (a + b)
        if abs(xn - x) <= tol or abs(b - a) <= tol:
            return xn
        x = xn
    return x


@njit
def dense_root(Fg, g_old, g_new):
    """Root theta in (0, 1] of the DOP853 continuous extension of a linear event
    functional (Fg = F @ w, g_old = w . y_old), given its end values of opposite signs
    (or g_new == 0).  Safeguarded Newton on the 7th-order interpolant."""
    if g_new == 0.0:
        return 1.0
    a = 0.0
    b = 1.0
    ga = g_old
    x = -ga / (g_new - ga)
    if not (x > a and x < b):
        x = 0.5
    for _ in range(ROOT_MAX_ITER):
        g = dense_eval_scalar(Fg, g_old, x)
        if g == 0.0:
            return x
        if (g < 0.0) == (ga < 0.0):
            a = x
            ga = g
        else:
            b = x
        d = dense_eval_scalar_derivative(Fg, 1.0, x)
        xn = x - g / d if d != 0.0 else 0.5 * (a + b)
        if not (xn > a and xn < b):
            xn = 0.5 * (a + b)
        if abs(xn - x) <= ROOT_XTOL or b - a <= ROOT_XTOL:
            return xn
        x = xn
    return x
