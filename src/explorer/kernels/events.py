"""Roots of event functions inside one step (docs/methods.md, crossing rules): every root of the
step's polynomial of sin(phi - phi0) is isolated (exclusion and monotonicity tests on Taylor
expansions, bisection otherwise) and refined by safeguarded Newton to ROOT_XTOL of the step.
The tests a step end makes are written with operators only, so the SIMD lanes compile the same
definitions (docs/architecture.md, Scalar and vector forms from one definition).
"""

import numpy as np

from explorer._jit import njit
from explorer.kernels.checks import EPS
from explorer.kernels.dop853 import dense_eval_scalar, dense_eval_scalar_derivative

#: stop when the Newton correction falls below this fraction of the step
ROOT_XTOL = 4.0 * EPS
ROOT_MAX_ITER = 100
#: deepest bisection of a step in the root isolation (intervals of 2**-24 of the step); an
#: interval that is still undecided there (a tangency to rounding) is tested by its end values
ISOLATE_MAX_DEPTH = 24
#: rows of the isolation stack (depth first, left half first: MAX_DEPTH + 1 live entries)
ISOLATE_STACK = ISOLATE_MAX_DEPTH + 2
#: roots a step search can return (more than 2 needs several turns inside one step)
MAX_STEP_ROOTS = 8
#: relative slack of the exclusion and monotonicity bounds, for the rounding of the sums
BOUND_SLACK = 64.0 * EPS


@njit(inline="always")
def sin_diff(s, c, cphi, sphi):
    """sin(phi - phi0) = sin phi cos phi0 - cos phi sin phi0 from s = sin phi, c = cos phi and
    cphi, sphi = cos phi0, sin phi0: the event function of the section phi = phi0, written once."""
    return s * cphi - c * sphi


@njit(inline="always")
def cos_diff(s, c, cphi, sphi):
    """cos(phi - phi0) = cos phi cos phi0 + sin phi sin phi0 (> 0 on the branch phi = phi0 of a
    root of :func:`sin_diff`, < 0 on phi = phi0 + pi)."""
    return c * cphi + s * sphi


@njit
def sign_change(g_prev, g_new, direction):
    """Half-open crossing test on (t_prev, t_new]: +1 means g goes from < 0 to >= 0,
    -1 from > 0 to <= 0, 0 either."""
    up = (g_prev < 0.0) & (g_new >= 0.0)
    down = (g_prev > 0.0) & (g_new <= 0.0)
    if direction > 0:
        return up
    if direction < 0:
        return down
    return up | down


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
def root_workspace(degree):
    """The work arrays of the root search in one step, for an event polynomial of ``degree``
    (allocated once per orbit, kernel contract rule 2): (coefficients, work, roots, brackets,
    bisection stack)."""
    return (np.empty(degree + 1), np.empty(degree + 1), np.empty(MAX_STEP_ROOTS),
            np.empty((MAX_STEP_ROOTS, 4)), np.empty((ISOLATE_STACK, 5)))


@njit
def secant_start(a, b, ga, gb):
    """The first iterate of a bracketed root search on [a, b] (values ga, gb of opposite signs):
    the secant root, or the midpoint when the secant leaves the bracket."""
    x = a - ga * (b - a) / (gb - ga)
    if not (x > a and x < b):
        x = 0.5 * (a + b)
    return x


@njit
def newton_in_bracket(x, g, d, a, b, ga):
    """One safeguarded Newton step (Press et al., Numerical Recipes, rtsafe): the bracket [a, b]
    (ga = g(a)) shrinks to the side of the sign change at x, then the Newton iterate x - g/d if it
    falls inside, else the midpoint.  Returns (next x, a, b, ga)."""
    if (g < 0.0) == (ga < 0.0):
        a = x
        ga = g
    else:
        b = x
    xn = x - g / d if d != 0.0 else 0.5 * (a + b)
    if not (xn > a and xn < b):
        xn = 0.5 * (a + b)
    return xn, a, b, ga


@njit
def poly_root_in(c, order, a, b, ga, gb):
    """Root in (a, b] of the polynomial sum_k c_k x^k, given its values ga at a and gb at b of
    opposite signs (or gb == 0)."""
    if gb == 0.0:
        return b
    x = secant_start(a, b, ga, gb)
    tol = ROOT_XTOL * max(abs(a), abs(b))
    for _ in range(ROOT_MAX_ITER):
        g, d = poly_value_derivative(c, order, x)
        if g == 0.0:
            return x
        xn, a, b, ga = newton_in_bracket(x, g, d, a, b, ga)
        if abs(xn - x) <= tol or abs(b - a) <= tol:
            return xn
        x = xn
    return x


@njit
def taylor_shift(c, order, m, out):
    """out[k] = coefficients of p(m + x) = sum_k out[k] x^k for p(x) = sum_k c[k] x^k
    (repeated synthetic division, order^2 / 2 multiply-adds)."""
    for k in range(order + 1):
        out[k] = c[k]
    for i in range(order):
        for j in range(order - 1, i - 1, -1):
            out[j] += m * out[j + 1]


@njit
def excluded_by_variation(g0, variation):
    """True if g cannot vanish where g = g0 + (terms whose sum is at most ``variation`` in
    size): |g0| > variation, with BOUND_SLACK."""
    return abs(g0) > variation + BOUND_SLACK * (abs(g0) + variation)


@njit(inline="always")
def tail_term(s, rk, r, weight, dk):
    """One term of :func:`_tail_bound`'s sum: (s + weight |dk| rk r, rk r)."""
    rk = rk * r
    return s + weight * abs(dk) * rk, rk


@njit
def _tail_bound(d, order, r, derivative):
    s = 0.0
    rk = 1.0
    for k in range(2 if derivative else 1, order + 1):
        s, rk = tail_term(s, rk, r, float(k) if derivative else 1.0, d[k])
    return s


@njit
def no_root_within(d, order, r):
    """True if p(x) = sum_k d[k] x^k has no root for |x| <= r: |d0| > sum_{k>=1} |d_k| r^k."""
    return excluded_by_variation(d[0], _tail_bound(d, order, r, False))


@njit
def monotone_within(d, order, r):
    """True if p'(x) has no root for |x| <= r: |d1| > sum_{k>=2} k |d_k| r^(k-1)."""
    s = _tail_bound(d, order, r, True)
    return excluded_by_variation(d[1], s)


@njit
def identically_zero(c, order):
    """True if every coefficient c[0..order] is 0."""
    for k in range(order + 1):
        if c[k] != 0.0:
            return False
    return True


@njit
def isolate_crossings(gc, order, h, g_old, g_new, direction, brackets, work, stack):
    """Brackets (a, b, g(a), g(b)) of every crossing in (0, h] of g(x) = sum_k gc[k] x^k in the given
    direction (:func:`sign_change`; g_old, g_new the caller's end values), increasing, in
    ``brackets``; returns their number.  work (order + 1,), stack (ISOLATE_STACK, 5): scratch."""
    if no_root_within(gc, order, h):
        return 0
    if monotone_within(gc, order, h):
        if sign_change(g_old, g_new, direction):
            brackets[0, 0] = 0.0
            brackets[0, 1] = h
            brackets[0, 2] = g_old
            brackets[0, 3] = g_new
            return 1
        return 0
    if identically_zero(gc, order):
        return 0
    n = 0
    top = 1
    stack[0, 0] = 0.0
    stack[0, 1] = h
    stack[0, 2] = g_old
    stack[0, 3] = g_new
    stack[0, 4] = 0.0
    while top > 0:
        top -= 1
        a = stack[top, 0]
        b = stack[top, 1]
        ga = stack[top, 2]
        gb = stack[top, 3]
        depth = stack[top, 4]
        m = 0.5 * (a + b)
        r = 0.5 * (b - a)
        taylor_shift(gc, order, m, work)
        if no_root_within(work, order, r):
            continue
        if depth >= ISOLATE_MAX_DEPTH or monotone_within(work, order, r):
            if sign_change(ga, gb, direction) and n < brackets.shape[0]:
                brackets[n, 0] = a
                brackets[n, 1] = b
                brackets[n, 2] = ga
                brackets[n, 3] = gb
                n += 1
            continue
        gm = work[0]
        stack[top, 0] = m
        stack[top, 1] = b
        stack[top, 2] = gm
        stack[top, 3] = gb
        stack[top, 4] = depth + 1.0
        stack[top + 1, 0] = a
        stack[top + 1, 1] = m
        stack[top + 1, 2] = ga
        stack[top + 1, 3] = gm
        stack[top + 1, 4] = depth + 1.0
        top += 2
    return n


@njit
def poly_step_roots(gc, order, h, g_old, g_new, direction, roots, brackets, work, stack):
    """Every crossing in (0, h] of the polynomial g(x) = sum_k gc[k] x^k in the given
    direction: :func:`isolate_crossings`, each bracket refined by :func:`poly_root_in`.
    brackets: (MAX_STEP_ROOTS, 4) scratch.  Writes roots[0:n] increasing, returns n."""
    n = isolate_crossings(gc, order, h, g_old, g_new, direction, brackets, work, stack)
    for i in range(n):
        roots[i] = poly_root_in(gc, order, brackets[i, 0], brackets[i, 1], brackets[i, 2],
                                brackets[i, 3])
    return n


@njit
def dense_root_in(Fg, g_old, a, b, ga, gb):
    """Root theta in (a, b] (0 <= a < b <= 1) of the DOP853 continuous extension of a linear event
    functional (Fg = F @ w, g_old = w . y_old), ga, gb of opposite signs: safeguarded Newton."""
    if gb == 0.0:
        return b
    x = secant_start(a, b, ga, gb)
    for _ in range(ROOT_MAX_ITER):
        g = dense_eval_scalar(Fg, g_old, x)
        if g == 0.0:
            return x
        d = dense_eval_scalar_derivative(Fg, 1.0, x)
        xn, a, b, ga = newton_in_bracket(x, g, d, a, b, ga)
        if abs(xn - x) <= ROOT_XTOL or b - a <= ROOT_XTOL:
            return xn
        x = xn
    return x


@njit
def dense_root(Fg, g_old, g_new):
    """:func:`dense_root_in` on (0, 1], given end values of opposite signs (or g_new == 0)."""
    return dense_root_in(Fg, g_old, 0.0, 1.0, g_old, g_new)


@njit
def dense_power_basis(Fg, g_old, out):
    """Coefficients out[0:8] in powers of theta of the DOP853 continuous extension of a linear
    functional (the nesting of :func:`dense_eval_scalar`)."""
    npow = Fg.shape[0]
    for k in range(npow + 1):
        out[k] = 0.0
    out[0] = Fg[npow - 1]
    deg = 0
    for k in range(1, npow):
        if k % 2 == 1:
            for j in range(deg + 1, 0, -1):
                out[j] = out[j - 1]
            out[0] = 0.0
        else:
            for j in range(deg + 1, 0, -1):
                out[j] = out[j] - out[j - 1]
        deg += 1
        out[0] += Fg[npow - 1 - k]
    for j in range(deg + 1, 0, -1):
        out[j] = out[j - 1]
    out[0] = g_old


@njit
def dense_step_roots(Fg, g_old, g_prev, g_new, direction, roots, brackets, coef, work, stack):
    """:func:`poly_step_roots` on the DOP853 continuous extension of a linear event functional
    (Fg = F @ w, g_old = w . y_old): every crossing theta in (0, 1] in the given direction
    (g_prev = 0, a start on the section, never fires).  coef, work: (8,) scratch.  Returns n."""
    dense_power_basis(Fg, g_old, coef)
    n = isolate_crossings(coef, Fg.shape[0], 1.0, g_prev, g_new, direction, brackets, work, stack)
    for i in range(n):
        roots[i] = dense_root_in(Fg, g_old, brackets[i, 0], brackets[i, 1], brackets[i, 2],
                                 brackets[i, 3])
    return n
