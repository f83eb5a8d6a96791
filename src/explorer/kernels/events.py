"""Root refinement of event functions inside one step.

An event function linear in the state (such as sin(phi - phi0) =
g1 cos phi0 - g2 sin phi0) evaluated on the step's interpolant is a scalar
polynomial in the step fraction, so the crossing is located to the order of
the integrator, never by linear interpolation.  The root finder is a
safeguarded Newton iteration on a sign-changing bracket (Newton step when it
stays inside the bracket, bisection otherwise), stopped at ROOT_XTOL of the
step length.  Compare scipy's event handling (brentq, xtol = 4 eps).

A step in which the event's rate changes sign can hold two roots while the
end values keep one sign: for the section phi = phi0 the body passes phi0
and turns back inside the step (dphi/dt = M/b changes sign).  The step
searches (:func:`poly_step_roots`, :func:`dense_step_roots`) therefore split a
step at the root of M when M changes sign between its ends, and test each
half, where phi is monotone, on its own.  (M vanishing twice inside one step,
with one sign at both ends, is not searched: it needs a step longer than the
time M takes to turn back twice, which the error control does not produce on
the orbits of the stress suite - benchmarks/stress/stress_crossings.py.)
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
def turns(m_old, m_new):
    """True if the rate m (here M, dphi/dt = M/b) changes sign strictly inside the step:
    one end < 0 and the other > 0."""
    return (m_old < 0.0 and m_new > 0.0) or (m_old > 0.0 and m_new < 0.0)


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
def poly_root_in(c, order, a, b, ga, gb):
    """Root in (a, b] of the polynomial sum_k c_k x^k, given its values ga at a and gb at b of
    opposite signs (or gb == 0).  Safeguarded Newton on the bracket; stops at ROOT_XTOL of
    max(|a|, |b|) (the step length for a = 0)."""
    if gb == 0.0:
        return b
    x = a - ga * (b - a) / (gb - ga)  # secant start
    if not (x > a and x < b):
        x = 0.5 * (a + b)
    tol = ROOT_XTOL * max(abs(a), abs(b))
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
def poly_root(c, order, h, g_lo, g_hi):
    """Root in (0, h] of the polynomial sum_k c_k x^k, given g(0) = g_lo and g(h) = g_hi of
    opposite signs (or g_hi == 0).  Safeguarded Newton; returns x."""
    return poly_root_in(c, order, 0.0, h, g_lo, g_hi)


@njit
def poly_step_roots(gc, mc, order, h, g_old, g_new, m_old, m_new, direction, roots):
    """Crossings in (0, h] of the event polynomial gc in the given direction (as
    :func:`sign_change`), where mc is the polynomial of the rate's sign carrier M
    (dg/dt has the sign of M near the root).  If M changes sign in the step the step is
    split at the root of M and each part, where g is monotone, is tested and searched.
    Writes the roots in increasing order to roots[0:n] and returns n (0, 1 or 2)."""
    if turns(m_old, m_new):
        tm = poly_root_in(mc, order, 0.0, h, m_old, m_new)
        gm, _ = poly_value_derivative(gc, order, tm)
        n = 0
        if sign_change(g_old, gm, direction):
            roots[n] = poly_root_in(gc, order, 0.0, tm, g_old, gm)
            n += 1
        if sign_change(gm, g_new, direction):
            roots[n] = poly_root_in(gc, order, tm, h, gm, g_new)
            n += 1
        return n
    if sign_change(g_old, g_new, direction):
        roots[0] = poly_root_in(gc, order, 0.0, h, g_old, g_new)
        return 1
    return 0


@njit
def dense_root_in(Fg, g_old, a, b, ga, gb):
    """Root theta in (a, b] of the DOP853 continuous extension of a linear event functional
    (Fg = F @ w, g_old = w . y_old), given its values ga at a and gb at b of opposite signs
    (or gb == 0), 0 <= a < b <= 1.  Safeguarded Newton on the 7th-order interpolant."""
    if gb == 0.0:
        return b
    x = a - ga * (b - a) / (gb - ga)
    if not (x > a and x < b):
        x = 0.5 * (a + b)
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


@njit
def dense_root(Fg, g_old, g_new):
    """Root theta in (0, 1] of the DOP853 continuous extension of a linear event
    functional (Fg = F @ w, g_old = w . y_old), given its end values of opposite signs
    (or g_new == 0).  Safeguarded Newton on the 7th-order interpolant."""
    return dense_root_in(Fg, g_old, 0.0, 1.0, g_old, g_new)


@njit
def dense_step_roots(Fg, g_old, g_new, Fm, m_old, m_new, direction, roots):
    """:func:`poly_step_roots` on the DOP853 continuous extension: crossings theta in (0, 1]
    of the event functional (Fg, g_old) in the given direction, the step split at the root
    of the interpolant (Fm, m_old) of M when M changes sign.  Returns n, roots[0:n]."""
    if turns(m_old, m_new):
        tm = dense_root_in(Fm, m_old, 0.0, 1.0, m_old, m_new)
        gm = dense_eval_scalar(Fg, g_old, tm)
        n = 0
        if sign_change(g_old, gm, direction):
            roots[n] = dense_root_in(Fg, g_old, 0.0, tm, g_old, gm)
            n += 1
        if sign_change(gm, g_new, direction):
            roots[n] = dense_root_in(Fg, g_old, tm, 1.0, gm, g_new)
            n += 1
        return n
    if sign_change(g_old, g_new, direction):
        roots[0] = dense_root_in(Fg, g_old, 0.0, 1.0, g_old, g_new)
        return 1
    return 0
