"""Model-agnostic pieces of the adaptive Taylor method (Jorba & Zou, Exp. Math. 14 (2005) 99):
order from the tolerance, step from the last two normalised coefficients X[i, k] = y_i^(k)/k!,
Horner evaluation.
"""
import math

from explorer._jit import njit
from explorer.kernels.power import radius_power
from explorer.kernels.taylor_order import MAX_ORDER, MIN_ORDER, order_for_tolerance  # noqa: F401 (re-exported)

#: Jorba-Zou safety factor exp(-0.7/(p-1))/e^2 is applied to the radius estimate.
RHO_EXPONENT = -0.7


@njit
def safety_factor(order):
    """Jorba-Zou safety factor exp(-0.7/(p-1)) / e^2 applied to the radius estimate (the one
    place it is written: every Taylor loop, scalar, tangent and vectorised, calls this)."""
    return math.exp(RHO_EXPONENT / (order - 1) - 2.0)


@njit
def step_size(X, order, factor):
    """Step from the radius-of-convergence estimate (Jorba-Zou 2005, Sec. 3.2.1):
    rho_m = (s / ||x^[m]||_inf)^(1/m) for m = p-1, p with s = max(1, ||x_0||_inf),
    h = min(rho_{p-1}, rho_p) * factor, factor = :func:`safety_factor` (p), the powers by
    kernels.power.radius_power (:func:`radius_min`).  Returns +inf when the last two coefficients
    vanish (polynomial solution)."""
    n = X.shape[0]
    s = 1.0
    a = 0.0
    bm = 0.0
    for i in range(n):
        v = abs(X[i, 0])
        if v > s:
            s = v
        v = abs(X[i, order])
        if v > a:
            a = v
        v = abs(X[i, order - 1])
        if v > bm:
            bm = v
    return radius_min(a, bm, s / a if a > 0.0 else math.inf, s / bm if bm > 0.0 else math.inf,
                      1.0 / order, 1.0 / (order - 1)) * factor


@njit
def radius_min(a, bm, u, v, e_p, e_q):
    """min(rho_p, rho_{p-1}) of :func:`step_size` from its norms a, bm, u = s/a, v = s/bm (for
    a, bm > 0) and e_p = 1/p, e_q = 1/(p-1): +inf for a vanishing norm."""
    rho = math.inf
    if a > 0.0:
        rho = radius_power(u, e_p)
    if bm > 0.0:
        r2 = radius_power(v, e_q)
        if r2 < rho:
            rho = r2
    return rho


@njit
def evaluate(X, order, h, out):
    """out[i] = sum_k X[i, k] h^k (Horner)."""
    n = X.shape[0]
    for i in range(n):
        acc = X[i, order]
        for k in range(order - 1, -1, -1):
            acc = acc * h + X[i, k]
        out[i] = acc

