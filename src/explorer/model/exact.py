"""Closed-form solutions of Chaplygin's equations, the tests' references (docs/model.md R3, R6,
R7).  Independent of the project's physics: plain numpy, only the layout of the packed ``P``
(index constants of :mod:`explorer.model.parameters`); states y = (p1, p2, M, g1, g2).
"""
from __future__ import annotations

import numpy as np

from explorer.model.parameters import A1, A2, CHI, ETA, LAM, MU, N_PARAMS, XI, ZETA, B

__all__ = [
    "A1", "A2", "B", "LAM", "CHI", "ZETA", "MU", "XI", "ETA",
    "uniform_rotation",
    "uniform_rotation_crossing_times",
    "homoclinic",
    "homoclinic_crossing_times",
    "chaplygin_F",
]

TWO_PI = 2.0 * np.pi


def _params(P):
    P = np.asarray(P, dtype=np.float64)
    if P.shape != (N_PARAMS,):
        raise ValueError(f"P must have shape ({N_PARAMS},), got {P.shape}")
    return P


# Uniform rotation (relative equilibrium) for mu = 0
def uniform_rotation(P, c, t, phi0=np.pi):
    """Uniform rotation of the body for mu = 0 (R3 with mu = 0; R6 solution I): M = c,
    p_i = c s_i / (c - lam b / a_i), phi = phi0 + (c/b) t.  Returns p1, p2, M, phi shaped as t."""
    P = _params(P)
    if P[MU] != 0.0:
        raise ValueError(f"uniform_rotation needs mu = 0, got mu = {P[MU]}")
    if P[B] <= 0.0:
        raise ValueError(f"b must be > 0, got b = {P[B]}")
    c = float(c)
    t = np.asarray(t, dtype=np.float64)
    p = []
    for ai, si, name in ((P[A1], P[CHI], "chi"), (P[A2], P[ZETA], "zeta")):
        den = c - P[LAM] * P[B] / ai
        if den != 0.0:
            p.append(c * si / den)
        elif si == 0.0:
            p.append(0.0)
        elif c == 0.0:  # lam = 0 and c = 0: everything is at rest, p = s
            p.append(si)
        else:
            raise ValueError(
                f"no uniform rotation with M = c = {c}: c = lam b/a_i while "
                f"{name} = {si} != 0")
    ones = np.ones_like(t)
    return p[0] * ones, p[1] * ones, c * ones, phi0 + (c / P[B]) * t


def uniform_rotation_crossing_times(P, c, n):
    """Crossing times t_k = 2 pi b k / |c| (k = 1..n) of the uniform rotation with its starting section."""
    P = _params(P)
    if c == 0.0:
        raise ValueError("c must be nonzero for the body to turn")
    k = np.arange(1, int(n) + 1, dtype=np.float64)
    return TWO_PI * P[B] * k / abs(float(c))


# Homoclinic orbit R7
def _homoclinic_constants(P, c):
    """Validate the range of R7 and return (b, lam, b1, b2, Bsum, d1, d2)."""
    P = _params(P)
    a1, a2, b, lam = P[A1], P[A2], P[B], P[LAM]
    if P[MU] != 0.0:
        raise ValueError(f"homoclinic (R7) needs mu = 0, got mu = {P[MU]}")
    if P[CHI] != 0.0:
        raise ValueError(f"homoclinic (R7) needs chi = 0, got chi = {P[CHI]}")
    if P[ZETA] != 0.0:
        raise ValueError(f"homoclinic (R7) needs zeta = 0, got zeta = {P[ZETA]}")
    if not b > 0.0:
        raise ValueError(f"homoclinic (R7) needs b > 0, got b = {b}")
    if not lam > 0.0:
        raise ValueError(f"homoclinic (R7) needs lam > 0, got lam = {lam}")
    if not a2 > 0.0:
        raise ValueError(f"homoclinic (R7) needs a2 > 0, got a2 = {a2}")
    if not a1 > a2:
        raise ValueError(f"homoclinic (R7) needs a1 > a2, got a1 = {a1}, a2 = {a2}")
    c = float(c)
    lo, hi = lam * b / a1, lam * b / a2
    if not (lo < c < hi):
        raise ValueError(
            f"homoclinic (R7) needs lam b/a1 < c < lam b/a2, i.e. "
            f"{lo} < c < {hi}; got c = {c}")
    b1 = 2.0 * (c - lo)
    b2 = 2.0 * (hi - c)
    Bs = b1 + b2
    d1 = np.sqrt(b1 / Bs)
    d2 = np.sqrt(b2 / Bs)
    return b, lam, b1, b2, Bs, d1, d2


def _homoclinic_phi(c, b, rate, d1, d2, t, t0, phi_at_t0):
    tau = rate * (t - t0)
    return phi_at_t0 + (c / b) * (t - t0) - 2.0 * np.arctan((d1 / d2) * np.tanh(tau))


def homoclinic(P, c, t, sign=+1, t0=0.0, phi_at_t0=0.0):
    """The homoclinic orbit R7 of solution I (docs/model.md R7, corrected), centred at t0 with
    phi(t0) = phi_at_t0; sign = +-1 the separatrices (p -> -p).  Needs mu = chi = zeta = 0, lam > 0,
    a1 > a2, lam b/a1 < c < lam b/a2 (else ValueError).  Returns p1, p2, M, phi shaped as t."""
    if sign not in (1, -1):
        raise ValueError(f"sign must be +1 or -1, got sign = {sign}")
    b, lam, b1, b2, Bs, d1, d2 = _homoclinic_constants(P, c)
    c = float(c)
    t = np.asarray(t, dtype=np.float64)
    rate = np.sqrt(b1 * b2) / (2.0 * b)
    tau = rate * (t - t0)
    v = np.exp(-np.abs(tau))
    v2 = v * v
    D = 1.0 + v2 * v2 - 2.0 * (d1 * d1 - d2 * d2) * v2
    inv_E = 2.0 * v2 / D
    cosh_over_E = v * (1.0 + v2) / D
    sinh_over_E = np.sign(tau) * v * (1.0 - v2) / D
    amp = np.sqrt(8.0 * lam * Bs)
    M = c - 2.0 * Bs * d1 * d1 * d2 * d2 * inv_E
    p1 = sign * amp * d1 * d2 * d2 * cosh_over_E
    p2 = sign * amp * d1 * d1 * d2 * sinh_over_E
    phi = _homoclinic_phi(c, b, rate, d1, d2, t, t0, phi_at_t0)
    return p1, p2, M, phi


def homoclinic_crossing_times(P, c, phi_section, t_min, t_max, sign=+1,
                              t0=0.0, phi_at_t0=0.0):
    """Times in [t_min, t_max] where the homoclinic phi(t) of R7 crosses
    ``phi_section`` (mod 2 pi) with phi increasing, sorted; ValueError unless M > 0 on the whole
    orbit (c < 2 lam b/a1)."""
    if sign not in (1, -1):
        raise ValueError(f"sign must be +1 or -1, got sign = {sign}")
    b, lam, b1, b2, Bs, d1, d2 = _homoclinic_constants(P, c)
    P = _params(P)
    c = float(c)
    M_min = 2.0 * lam * b / P[A1] - c
    if not M_min > 0.0:
        raise ValueError(
            f"M is not positive along the homoclinic orbit (min M = {M_min}, "
            f"needs c < 2 lam b/a1 = {2.0 * lam * b / P[A1]}); phi is not monotone")
    t_min = float(t_min)
    t_max = float(t_max)
    if not t_max >= t_min:
        raise ValueError(f"need t_min <= t_max, got {t_min}, {t_max}")
    rate = np.sqrt(b1 * b2) / (2.0 * b)

    def phi(t):
        return _homoclinic_phi(c, b, rate, d1, d2, t, t0, phi_at_t0)

    def dphi(t):
        return homoclinic(P, c, t, sign, t0, phi_at_t0)[2] / b

    ph_lo, ph_hi = phi(t_min), phi(t_max)
    k_lo = int(np.ceil((ph_lo - phi_section) / TWO_PI))
    k_hi = int(np.floor((ph_hi - phi_section) / TWO_PI))
    if k_hi < k_lo:
        return np.empty(0)
    targets = phi_section + TWO_PI * np.arange(k_lo, k_hi + 1, dtype=np.float64)

    n_grid = max(2001, 20 * targets.size + 1)
    grid = np.linspace(t_min, t_max, n_grid)
    phg = phi(grid)
    phg[0], phg[-1] = ph_lo, ph_hi
    j = np.clip(np.searchsorted(phg, targets, side="left"), 1, n_grid - 1)
    lo = grid[j - 1].copy()
    hi = grid[j].copy()
    t = 0.5 * (lo + hi)
    for _ in range(200):
        f = phi(t) - targets
        lo = np.where(f < 0.0, t, lo)
        hi = np.where(f > 0.0, t, hi)
        done = f == 0.0
        lo = np.where(done, t, lo)
        hi = np.where(done, t, hi)
        t_new = t - f / dphi(t)
        bad = ~((t_new >= lo) & (t_new <= hi))
        t_new = np.where(bad, 0.5 * (lo + hi), t_new)
        step = np.abs(t_new - t)
        t = t_new
        if np.all(step <= 1e-16 * np.maximum(1.0, np.abs(t))) or np.all(
                hi - lo <= 4e-16 * np.maximum(1.0, np.abs(t))):
            break
    t = np.clip(t, t_min, t_max)
    return np.sort(t)


def chaplygin_F(P, y):
    """Chaplygin's integral F = M + |p - s|^2/(2 lam) (R5 case 1 divided by lam; R6) of
    y = [p1, p2, M, ...] along its first axis."""
    P = _params(P)
    if P[LAM] == 0.0:
        raise ValueError("chaplygin_F needs lam != 0")
    y = np.asarray(y, dtype=np.float64)
    p1, p2, M = y[0], y[1], y[2]
    return M + ((p1 - P[CHI]) ** 2 + (p2 - P[ZETA]) ** 2) / (2.0 * P[LAM])
