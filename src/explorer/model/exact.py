"""Closed-form solutions of Chaplygin's equations (reference for tests).

This module is deliberately independent of the project's own physics code: it
takes only the layout of the packed parameter vector (the index constants ``A1 ..
ETA`` and ``N_PARAMS`` of :mod:`explorer.model.parameters`, the one table of the
parameters), none of its formulas (it does not import :mod:`explorer.model.equations`);
it is plain numpy and cites the verified equations of ``docs/model.md`` (labels
R1..R11).

Parameters are a packed float64 array ``P``,
``P = [a1, a2, b, lam, chi, zeta, mu, xi, eta]`` (indices ``A1 .. ETA``).
The reduced state (R3) is ``y = [p1, p2, M, g1, g2]`` with
``(g1, g2) = (sin phi, cos phi)``.

Public functions
----------------
uniform_rotation(P, c, t, phi0=pi)
    Relative equilibrium of the case mu = 0 (R3, R6 solution I): p constant,
    M = c, phi = phi0 + (c/b) t.
uniform_rotation_crossing_times(P, c, n)
    Its section crossing times t_k = 2 pi b k / c, k = 1..n.
homoclinic(P, c, t, sign=+1, t0=0.0, phi_at_t0=0.0)
    The homoclinic orbit R7 of solution I (mu = 0, chi = zeta = 0).
homoclinic_crossing_times(P, c, phi_section, t_min, t_max, ...)
    Times where the homoclinic phi(t) crosses phi_section (mod 2 pi).
chaplygin_F(P, y)
    Chaplygin's integral of the case mu = 0 (R5.1, R6).
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


# ---------------------------------------------------------------------------
# Uniform rotation (relative equilibrium) for mu = 0
# ---------------------------------------------------------------------------
def uniform_rotation(P, c, t, phi0=np.pi):
    """Uniform rotation of the body for mu = 0 (R3 with mu = 0; R6 solution I).

    With mu = 0 the reduced equations R3 read
    ``dp/dt = (M/b) J (p - s) - lam J A p``, ``dM/dt = (p - s, J A p)``,
    ``dphi/dt = M/b``.  For ``M = c`` constant, dp/dt = 0 requires
    ``(c/b)(p_i - s_i) = lam p_i / a_i``, i.e.

        p_i = c s_i / (c - lam b / a_i),     s = (chi, zeta),

    and then ``dM/dt = (lam b / c)(p1 p2 - p2 p1)/(a1 a2) = 0`` as well.  For
    chi = zeta = 0 this is p = 0 (solution I of R6).  If ``c = lam b / a_i``
    and ``s_i = 0`` the component is taken as 0; if ``c = lam = 0`` then
    p = s.  A singular case ``c = lam b / a_i`` with ``s_i != 0`` raises.

    Parameters
    ----------
    P : array (9,)
        Parameters; ``P[MU]`` must be 0.
    c : float
        The constant value of M.
    t : array_like
        Times.
    phi0 : float
        phi at t = 0 (default pi, the section of R9).

    Returns
    -------
    p1, p2, M, phi : ndarrays with the shape of ``t``;
        ``phi = phi0 + (c/b) t`` (not reduced mod 2 pi).
    """
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
    """Crossing times of the uniform rotation with its starting section.

    Starting on the section phi = phi0 at t = 0 (see :func:`uniform_rotation`),
    phi = phi0 + (c/b) t returns to phi0 (mod 2 pi) at

        t_k = 2 pi b k / |c|,   k = 1 .. n,

    crossing with phi increasing if c > 0 and decreasing if c < 0.
    """
    P = _params(P)
    if c == 0.0:
        raise ValueError("c must be nonzero for the body to turn")
    k = np.arange(1, int(n) + 1, dtype=np.float64)
    return TWO_PI * P[B] * k / abs(float(c))


# ---------------------------------------------------------------------------
# Homoclinic orbit R7
# ---------------------------------------------------------------------------
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
    """Homoclinic orbit of the uniform rotation I (R7), case R6.

    Valid for mu = 0, chi = zeta = 0, lam > 0, a1 > a2 and
    ``lam b/a1 < c < lam b/a2`` (the band where solution I, p = 0, M = c, is
    unstable); otherwise ``ValueError`` naming the offending parameter.
    (xi, eta do not enter since mu = 0.)

    With ``b1 = 2(c - lam b/a1)``, ``b2 = 2(lam b/a2 - c)``, ``B = b1 + b2``,
    ``d1^2 = b1/B``, ``d2^2 = b2/B``, ``tau = sqrt(b1 b2) (t - t0) / (2 b)``,
    ``E = cosh 2tau - d1^2 + d2^2`` (R7, corrected):

        M   = c - 2 B d1^2 d2^2 / E
        p1  = sign * sqrt(8 lam B) d1 d2^2 cosh(tau) / E
        p2  = sign * sqrt(8 lam B) d1^2 d2 sinh(tau) / E
        phi = phi_at_t0 + (c/b)(t - t0) - 2 arctan( (d1/d2) tanh(tau) )

    Note ``(1 + d1^2 - d2^2)/(2 d1 d2) = d1/d2`` since ``d1^2 + d2^2 = 1``.

    Conventions
    -----------
    * The orbit is centred at ``t0``: p2 = 0 and |p1|, the distance from
      solution I, are maximal and M is minimal (``M = 2 lam b/a1 - c``) at
      ``t = t0``.  ``p -> 0``, ``M -> c`` as ``|t| -> inf``.
    * phi's additive constant: ``phi(t0) = phi_at_t0`` exactly.  phi is not
      reduced mod 2 pi and is continuous (arctan of tanh stays in
      (-pi/2, pi/2)); ``dphi/dt = M/b`` (R1).  Asymptotically
      ``phi ~ phi_at_t0 + (c/b)(t - t0) -+ 2 arctan(d1/d2)`` as
      ``t -> +-inf``.
    * ``sign = +1`` / ``-1`` selects the two separatrices (p1 > 0 / p1 < 0);
      phi and M do not depend on it.  NOTE (erratum to R7): the sign multiplies
      p2 as well.  R6 is invariant under p -> -p, and the branch of R7 is
      itself invariant under the time reversal (p1, p2, M, t) ->
      (p1, -p2, M, -t), so flipping p1 alone (R7's "p1 = +-...") is not a
      solution of R6 (residual O(1)); the second separatrix is p -> -p,
      equivalently p1 -> -p1 together with t - t0 -> -(t - t0).

    The hyperbolic functions are evaluated in the overflow-free form
    ``v = exp(-|tau|)``, ``D = 1 + v^4 - 2 (d1^2 - d2^2) v^2``:
    ``cosh tau / E = v (1 + v^2)/D``, ``sinh tau / E = sgn(tau) v (1 - v^2)/D``,
    ``1/E = 2 v^2 / D``.

    Returns
    -------
    p1, p2, M, phi : ndarrays with the shape of ``t``.
    """
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
    ``phi_section`` (mod 2 pi) with phi increasing.

    Same orbit and conventions as :func:`homoclinic` (in particular
    ``phi(t0) = phi_at_t0``).  ``dphi/dt = M/b`` and along R7
    ``min M = M(t0) = 2 lam b/a1 - c``; this function checks that this is
    > 0, so that phi is strictly increasing along the whole orbit and every
    crossing is a crossing with phi increasing (M > 0).  If
    ``c >= 2 lam b/a1`` (M changes sign near t0) a ``ValueError`` is raised.

    Each target value ``phi_section + 2 pi k`` in ``[phi(t_min), phi(t_max)]``
    is bracketed on a fine grid, then solved by safeguarded Newton (exact
    derivative M/b) with bisection fallback, to about 1e-15 relative in t.
    ``sign`` does not change phi; it is only validated.

    Returns
    -------
    times : sorted 1-D ndarray (possibly empty).
    """
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

    # bracket on a fine grid (phi is increasing)
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
        # shrink the bracket
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


# ---------------------------------------------------------------------------
# Chaplygin's integral
# ---------------------------------------------------------------------------
def chaplygin_F(P, y):
    """Chaplygin's integral for mu = 0 (R5 case 1 divided by lam; R6).

        F = M + ((p1 - chi)^2 + (p2 - zeta)^2) / (2 lam)

    which for chi = zeta = 0 is ``F = M + (p1^2 + p2^2)/(2 lam)`` of R6
    (R5.1 writes ``lam F = |p - s|^2/2 + lam M``).  F is an integral only
    when mu = 0; it is evaluated for any P (e.g. to measure its drift).

    ``y`` is ``[p1, p2, M, ...]`` along its first axis (shape (5,) or (5, n)
    as ``solve_ivp(...).y``); returns a float or an array of shape ``y.shape[1:]``.
    """
    P = _params(P)
    if P[LAM] == 0.0:
        raise ValueError("chaplygin_F needs lam != 0")
    y = np.asarray(y, dtype=np.float64)
    p1, p2, M = y[0], y[1], y[2]
    return M + ((p1 - P[CHI]) ** 2 + (p2 - P[ZETA]) ** 2) / (2.0 * P[LAM])
