"""Compiled physics of the reduced system (docs/model.md R3, R4): the vector field, the energy and
the exact sub-flows of the splitting (the Taylor recurrences are generated from
:mod:`explorer.model.chaplygin` by tools/gen_lanes.py); the numpy twin is
:mod:`explorer.model.parameters`.  y = (p1, p2, M, g1, g2); P packed, read by the index constants.
"""
import math

from explorer._jit import njit
from explorer.kernels.events import cos_diff, sin_diff
from explorer.model.parameters import A1, A2, CHI, ETA, LAM, MU, XI, ZETA, B

# Splitting H = U + H_2 + H_1 + H_M (docs/model.md R4). Flow ids, outermost first:
# the Strang base method applies U, H_2, H_1 half steps around a full H_M step,
# so the one flow that needs sin/cos (H_M) runs once per stage.
FLOW_U, FLOW_H2, FLOW_H1, FLOW_HM = 0, 1, 2, 3
N_FLOWS = 4


@njit
def rhs(y, P, dy):
    """docs/model.md R3 (ur12 corrected):
    dp/dt = (M/b) J (p - s) - mu g - lam J A p;  dM/dt = (p - s, J A p) - mu (r, J g);
    dg/dt = (M/b) J g, with J v = (v2, -v1)."""
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P[A1], P[A2], P[B], P[LAM], P[CHI], P[ZETA], P[MU], P[XI], P[ETA]
    p1, p2, m, g1, g2 = y[0], y[1], y[2], y[3], y[4]
    w = m / b
    dy[0] = w * (p2 - zeta) - mu * g1 - lam * p2 / a2
    dy[1] = -w * (p1 - chi) - mu * g2 + lam * p1 / a1
    # docs/model.md R3: dM/dt = (p - s, J A p) - mu (r, J g) = (p1-chi) p2/a2 - (p2-zeta) p1/a1 - mu (xi g2 - eta g1)
    dy[2] = (p1 - chi) * p2 / a2 - (p2 - zeta) * p1 / a1 - mu * (xi * g2 - eta * g1)
    dy[3] = w * g2
    dy[4] = -w * g1


@njit
def energy(y, P):
    """docs/model.md R3:
    H = 1/2(p1^2/a1 + p2^2/a2 + M^2/b) - (mu/lam)((p1-chi) g2 - (p2-zeta) g1) + mu (xi g1 + eta g2)."""
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P[A1], P[A2], P[B], P[LAM], P[CHI], P[ZETA], P[MU], P[XI], P[ETA]
    p1, p2, m, g1, g2 = y[0], y[1], y[2], y[3], y[4]
    kin = 0.5 * (p1 * p1 / a1 + p2 * p2 / a2 + m * m / b)
    return kin - (mu / lam) * ((p1 - chi) * g2 - (p2 - zeta) * g1) + mu * (xi * g1 + eta * g2)


# ------------------------------------------------------------------ exact sub-flows (R4)
@njit
def flow_hm(y, P, t):
    """docs/model.md R4, H_M = M^2/(2b): M fixed; p - s and g rotate rigidly by the angle (M/b) t
    (d q/dt = (M/b) J q, J q = (q2, -q1))."""
    chi, zeta = P[CHI], P[ZETA]
    th = y[2] / P[B] * t
    c = math.cos(th)
    s = math.sin(th)
    q1 = y[0] - chi
    q2 = y[1] - zeta
    y[0] = chi + c * q1 + s * q2
    y[1] = zeta - s * q1 + c * q2
    g1 = y[3]
    g2 = y[4]
    y[3] = c * g1 + s * g2
    y[4] = -s * g1 + c * g2


@njit(inline="always")
def _flow_shear(y, i, j, a, c, lam, s, t):
    """docs/model.md R4, the flow of H_1 (i, j = 0, 1, a = a1, c = zeta, s = 1) or H_2 (i, j = 1, 0,
    a = a2, c = chi, s = -1): u = p_i/a, p_j += s lam u t, M -= s u t ((p_j - c) + s lam u t / 2)."""
    u = y[i] / a
    d = s * lam * u * t
    y[2] -= s * u * t * ((y[j] - c) + 0.5 * d)
    y[j] += d


@njit
def flow_h1(y, P, t):
    """docs/model.md R4, H_1 = p1^2/(2 a1): p1, g fixed; p2(t) = p2 + (lam p1/a1) t;
    dM/dt = -(p2(t) - zeta) p1/a1, so M(t) = M - (p1/a1)((p2 - zeta) t + lam p1 t^2/(2 a1))."""
    _flow_shear(y, 0, 1, P[A1], P[ZETA], P[LAM], 1.0, t)


@njit
def flow_h2(y, P, t):
    """docs/model.md R4, H_2 = p2^2/(2 a2): p2, g fixed; p1(t) = p1 - (lam p2/a2) t;
    dM/dt = (p1(t) - chi) p2/a2, so M(t) = M + (p2/a2)((p1 - chi) t - lam p2 t^2/(2 a2))."""
    _flow_shear(y, 1, 0, P[A2], P[CHI], P[LAM], -1.0, t)


@njit
def flow_u(y, P, t):
    """docs/model.md R4, U = -(mu/lam)(p - s, J g) + mu (r, g): g fixed; p(t) = p - mu g t;
    dM/dt = -mu (r, J g) = -mu (xi g2 - eta g1) (constant)."""
    mu = P[MU]
    y[0] -= mu * y[3] * t
    y[1] -= mu * y[4] * t
    y[2] -= mu * (P[XI] * y[4] - P[ETA] * y[3]) * t


@njit
def apply_flow(k, y, P, t):
    """Apply exact sub-flow number k (FLOW_U, FLOW_H2, FLOW_H1, FLOW_HM) for time t."""
    if k == 0:
        flow_u(y, P, t)
    elif k == 1:
        flow_h2(y, P, t)
    elif k == 2:
        flow_h1(y, P, t)
    else:
        flow_hm(y, P, t)


# ------------------------------------------------------------------ the section phi = phi0
#: rows of g1 = sin phi and g2 = cos phi in the state (p1, p2, M, g1, g2) and in its Taylor
#: coefficients
G1 = 3
G2 = 4


@njit
def section_g(y, cphi, sphi):
    """Event function sin(phi - phi0) = g1 cos phi0 - g2 sin phi0 (linear in the state;
    kernels.events.sin_diff)."""
    return sin_diff(y[G1], y[G2], cphi, sphi)


@njit
def section_c(y, cphi, sphi):
    """cos(phi - phi0) = g2 cos phi0 + g1 sin phi0: > 0 on the branch phi = phi0 (not phi0 + pi)."""
    return cos_diff(y[G1], y[G2], cphi, sphi)


@njit
def section_g_rate(y, P, cphi, sphi):
    """d/dt sin(phi - phi0) = (M/b) cos(phi - phi0) (docs/model.md R3: dphi/dt = M/b)."""
    return y[2] / P[B] * cos_diff(y[G1], y[G2], cphi, sphi)


@njit
def rhs_tangent(y, v, P, dv):
    """Variational field of R3: dv/dt = Df(y) v (the linearisation of :func:`rhs`)."""
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P[A1], P[A2], P[B], P[LAM], P[CHI], P[ZETA], P[MU], P[XI], P[ETA]
    p1, p2, m, g1, g2 = y[0], y[1], y[2], y[3], y[4]
    v1, v2, vm, vg1, vg2 = v[0], v[1], v[2], v[3], v[4]
    w = m / b
    dw = vm / b
    dv[0] = dw * (p2 - zeta) + w * v2 - mu * vg1 - lam * v2 / a2
    dv[1] = -dw * (p1 - chi) - w * v1 - mu * vg2 + lam * v1 / a1
    dv[2] = (v1 * p2 + (p1 - chi) * v2) / a2 - (v2 * p1 + (p2 - zeta) * v1) / a1 - mu * (xi * vg2 - eta * vg1)
    dv[3] = dw * g2 + w * vg2
    dv[4] = -dw * g1 - w * vg1


@njit
def tangent_flow_hm(y, v, P, t):
    """Exact tangent map of the H_M flow (R4) at y (before the flow), applied to v in place:
    q' = R(theta) q with theta = (M/b) t, so dq' = R dq + R'(theta) q (t/b) dM."""
    chi, zeta = P[CHI], P[ZETA]
    th = y[2] / P[B] * t
    c = math.cos(th)
    s = math.sin(th)
    dth = v[2] / P[B] * t
    q1 = y[0] - chi
    q2 = y[1] - zeta
    v0 = c * v[0] + s * v[1] + (-s * q1 + c * q2) * dth
    v1 = -s * v[0] + c * v[1] + (-c * q1 - s * q2) * dth
    g1 = y[3]
    g2 = y[4]
    v3 = c * v[3] + s * v[4] + (-s * g1 + c * g2) * dth
    v4 = -s * v[3] + c * v[4] + (-c * g1 - s * g2) * dth
    v[0] = v0
    v[1] = v1
    v[3] = v3
    v[4] = v4


@njit(inline="always")
def _tangent_flow_shear(y, v, i, j, a, c, lam, s, t):
    """Tangent map of :func:`_flow_shear` at y applied to v in place: du = dv_i/a,
    dM' = dM - s t (p_j - c) du - s u t dp_j - lam u t^2 du, dp_j' = dp_j + s lam t du."""
    u = y[i] / a
    du = v[i] / a
    v[2] += -s * t * (y[j] - c) * du - s * u * t * v[j] - lam * u * t * t * du
    v[j] += s * lam * t * du


@njit
def tangent_flow_h1(y, v, P, t):
    """Tangent map of the H_1 flow: M' = M - u t (p2 - zeta) - lam u^2 t^2 / 2, p2' = p2 + lam u t,
    u = p1/a1."""
    _tangent_flow_shear(y, v, 0, 1, P[A1], P[ZETA], P[LAM], 1.0, t)


@njit
def tangent_flow_h2(y, v, P, t):
    """Tangent map of the H_2 flow: M' = M + w t (p1 - chi) - lam w^2 t^2 / 2, p1' = p1 - lam w t,
    w = p2/a2."""
    _tangent_flow_shear(y, v, 1, 0, P[A2], P[CHI], P[LAM], -1.0, t)


@njit
def tangent_flow_u(y, v, P, t):
    """Tangent map of the U flow: p' = p - mu g t, M' = M - mu (xi g2 - eta g1) t."""
    mu = P[MU]
    v[0] -= mu * t * v[3]
    v[1] -= mu * t * v[4]
    v[2] -= mu * t * (P[XI] * v[4] - P[ETA] * v[3])


@njit
def apply_flow_tangent(k, y, v, P, t):
    """Advance the tangent vector v by the tangent map of sub-flow k at y, then y by the flow."""
    if k == 0:
        tangent_flow_u(y, v, P, t)
        flow_u(y, P, t)
    elif k == 1:
        tangent_flow_h2(y, v, P, t)
        flow_h2(y, P, t)
    elif k == 2:
        tangent_flow_h1(y, v, P, t)
        flow_h1(y, P, t)
    else:
        tangent_flow_hm(y, v, P, t)
        flow_hm(y, P, t)


# ====================================================================== the full system R1
#: dimension of the full state (p1, p2, M, g1, g2, x, y): R3 plus the position (R1)
FULL_DIM = 7


@njit
def rhs_full(y, P, dy):
    """docs/model.md R1 in the polynomial form (g1, g2) = (sin phi, cos phi)."""
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P[A1], P[A2], P[B], P[LAM], P[CHI], P[ZETA], P[MU], P[XI], P[ETA]
    p1, p2, m, g1, g2 = y[0], y[1], y[2], y[3], y[4]
    w = m / b
    u1 = p1 / a1
    u2 = p2 / a2
    dy[0] = w * (p2 - zeta) - mu * g1 - lam * u2
    dy[1] = -w * (p1 - chi) - mu * g2 + lam * u1
    dy[2] = (p1 - chi) * u2 - (p2 - zeta) * u1 - mu * (xi * g2 - eta * g1)
    dy[3] = w * g2
    dy[4] = -w * g1
    dy[5] = u1 * g2 - u2 * g1
    dy[6] = u1 * g1 + u2 * g2


@njit
def energy_full(y, P):
    """docs/model.md R1: H = 1/2(p1^2/a1 + p2^2/a2 + M^2/b) + mu (y + xi g1 + eta g2)."""
    kin = 0.5 * (y[0] * y[0] / P[A1] + y[1] * y[1] / P[A2] + y[2] * y[2] / P[B])
    return kin + P[MU] * (y[6] + P[XI] * y[3] + P[ETA] * y[4])
