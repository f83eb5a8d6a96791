"""The Poincaré–Melnikov integral ur23/ur24 (docs/model.md R6, R7, R8) and the splitting of the
separatrices it predicts, measured on the section phi = pi; derivation, conventions and numbers
in docs/commands/melnikov.md.

H = H0 + mu H1 (R8), F0 = M + |p - s|^2/(2 lam) (R6).  ``g0`` is the angle phi at the centre of
the homoclinic orbit R7 (:func:`explorer.model.exact.homoclinic`), ``sign`` its branch (+1: p1 > 0
at the centre, -1: p -> -p).  Per unit mu, J_sign(g0) = int {F0, H1} dt along the orbit, taken as
the regularised integral of :func:`integrand`; F0(W^u) - F0(W^s) = mu J(g0) + O(mu^2)
(:func:`measured_splitting`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.integrate.methods import MAP_TOL
from explorer.model import ParameterError, exact, packed_params

#: mu values of the measured-splitting table
DEFAULT_MUS = (1e-4, 3e-4, 1e-3, 3e-3)
#: phases of the table's transversals: |sin g0| = 1, the extremes of J when xi = eta = 0
DEFAULT_G0S = (0.5 * math.pi,)
#: half-width of the quadrature window in units of tau = rate * t (integrand ~ exp(-|tau|))
DEFAULT_WINDOW = 40.0
#: Gauss-Legendre nodes per panel
GAUSS_NODES = 20
#: relative agreement of ur24 with the quadrature that counts as "holds"
UR24_RTOL = 1e-6


# ---------------------------------------------------------------- Chaplygin's integral (R6)
def F0(params, y):
    """Chaplygin's integral (R6) F0 = M + |p - s|^2/(2 lam) on states y (..., 5)."""
    P = packed_params(params)
    y = np.asarray(y, dtype=np.float64)
    return y[..., model.M] + ((y[..., model.P1] - P[model.CHI]) ** 2
                              + (y[..., model.P2] - P[model.ZETA]) ** 2) / (2.0 * P[model.LAM])


# ---------------------------------------------------------------- the homoclinic orbit R7
@dataclass(frozen=True)
class HomoclinicConstants:
    c: float
    b1: float
    b2: float
    B: float
    d1: float
    d2: float
    rate: float      # tau = rate * t, rate = sqrt(b1 b2)/(2b)
    S: float
    alpha: float     # cos alpha = d1, sin alpha = d2
    beta: float      # pi/2 - alpha = arctan(d1/d2)


def _params(params) -> model.Params:
    return params if isinstance(params, model.Params) else model.Params.from_array(params)


def c_of_h(params, h) -> float:
    """c = sqrt(2 b h): the value of F0 on solution I at energy h (R6, R9)."""
    prm = _params(params)
    try:
        h = float(h)
    except (TypeError, ValueError):
        raise ParameterError(f"h must be a real number, got {h!r}") from None
    if not math.isfinite(h) or not h > 0.0:
        raise ParameterError(f"h must be finite and > 0 (solution I has h = c^2/(2b)), got {h!r}")
    return math.sqrt(2.0 * prm.b * h)


def check_params(params, h=None, *, c=None) -> float:
    """Validate that the homoclinic orbit R7 exists and return c; ParameterError (one line) else."""
    prm = _params(params)
    if c is None:
        c = c_of_h(prm, h)
    c = float(c)
    if not prm.lam > 0.0:
        raise ParameterError(f"melnikov needs lam > 0 (the homoclinic orbit R7), got lam = {prm.lam!r}")
    if not prm.a1 > prm.a2:
        raise ParameterError(f"melnikov needs a1 > a2 (R7), got a1 = {prm.a1!r}, a2 = {prm.a2!r}")
    if prm.chi != 0.0 or prm.zeta != 0.0:
        raise ParameterError(f"melnikov needs chi = zeta = 0 (R6, R7), got chi = {prm.chi!r}, "
                             f"zeta = {prm.zeta!r}")
    lo, hi = prm.lam * prm.b / prm.a1, prm.lam * prm.b / prm.a2
    if not lo < c < hi:
        hs = "" if h is None else f" (h = {float(h)!r})"
        raise ParameterError(f"melnikov needs lam b/a1 < c < lam b/a2, i.e. {lo:.6g} < c < {hi:.6g} "
                             f"(h between {lo * lo / (2 * prm.b):.6g} and {hi * hi / (2 * prm.b):.6g}), "
                             f"where solution I is hyperbolic; got c = {c:.6g}{hs}")
    return c


def homoclinic_constants(params, c) -> HomoclinicConstants:
    prm = _params(params)
    c = check_params(prm, c=c)
    b, lam = prm.b, prm.lam
    b1 = 2.0 * (c - lam * b / prm.a1)
    b2 = 2.0 * (lam * b / prm.a2 - c)
    B = b1 + b2
    d1, d2 = math.sqrt(b1 / B), math.sqrt(b2 / B)
    rate = math.sqrt(b1 * b2) / (2.0 * b)
    S = 2.0 * c / math.sqrt(b1 * b2)
    alpha = math.atan2(d2, d1)
    return HomoclinicConstants(c, b1, b2, B, d1, d2, rate, S, alpha, math.atan2(d1, d2))


def _P0(prm: model.Params) -> np.ndarray:
    """Parameter vector with mu = 0 for :func:`exact.homoclinic`."""
    return prm.with_(mu=0.0).as_array()


def integrand(params, c, t, g0, sign=1):
    """The regularised Melnikov integrand -(p1 sin phi + p2 cos phi)/lam - (xi cos phi - eta sin phi)
    (1 - M/c) (docs/commands/melnikov.md, step 3) along the orbit (sign, g0) at times t (broadcast
    with g0)."""
    prm = _params(params)
    t, g0 = np.broadcast_arrays(np.asarray(t, float), np.asarray(g0, float))
    p1, p2, M, phi0 = exact.homoclinic(_P0(prm), c, t, sign, 0.0, 0.0)
    phi = phi0 + g0
    s, co = np.sin(phi), np.cos(phi)
    return -(p1 * s + p2 * co) / prm.lam - (prm.xi * co - prm.eta * s) * (1.0 - M / c)


def _gauss_grid(hc: HomoclinicConstants, window):
    """Composite Gauss-Legendre nodes/weights in t over |tau| <= window."""
    w = min(0.5, 0.5 * hc.alpha, 1.0 / hc.S)
    w = max(w, 1e-4)
    n_pan = int(math.ceil(window / w))
    x, wt = np.polynomial.legendre.leggauss(GAUSS_NODES)
    edges = np.linspace(-window, window, 2 * n_pan + 1)
    half = 0.5 * (edges[1:] - edges[:-1])
    mid = 0.5 * (edges[1:] + edges[:-1])
    u = (mid[:, None] + half[:, None] * x[None, :]).ravel()
    wu = (half[:, None] * wt[None, :]).ravel()
    return u / hc.rate, wu / hc.rate


def melnikov_integral(params, c, g0, sign=1, *, window=DEFAULT_WINDOW, method="gauss"):
    """J_sign(g0) by quadrature over |tau| <= window (tau = rate t)."""
    if sign not in (1, -1):
        raise ParameterError(f"sign must be +1 or -1, got {sign!r}")
    prm = _params(params)
    hc = homoclinic_constants(prm, c)
    g = np.asarray(g0, dtype=float)
    if method == "gauss":
        t, w = _gauss_grid(hc, float(window))
        vals = integrand(prm, hc.c, t[None, :], g.reshape(-1, 1), sign) @ w
    elif method == "quad":
        import warnings

        from scipy import integrate

        T = float(window) / hc.rate
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", integrate.IntegrationWarning)
            vals = np.array([integrate.quad(lambda tt: float(integrand(prm, hc.c, tt, gg, sign)), -T, T,
                                            limit=2000, epsabs=1e-14, epsrel=1e-13)[0]
                             for gg in g.ravel()])
    else:
        raise ParameterError(f"method must be gauss or quad, got {method!r}")
    vals = vals.reshape(g.shape)
    return float(vals) if vals.ndim == 0 else vals


def fit_harmonics(params, c, sign=1, n=16, *, window=DEFAULT_WINDOW, method="gauss"):
    """Least-squares fit J(g0) = A sin g0 + B cos g0 + C on n equispaced g0 (quadrature values).
    Returns (A, B, C, max |residual|); C and the residual vanish up to round-off."""
    g0 = 2.0 * math.pi * np.arange(n) / n
    J = melnikov_integral(params, c, g0, sign, window=window, method=method)
    X = np.stack([np.sin(g0), np.cos(g0), np.ones_like(g0)], axis=1)
    coef, *_ = np.linalg.lstsq(X, J, rcond=None)
    res = float(np.max(np.abs(X @ coef - J)))
    return float(coef[0]), float(coef[1]), float(coef[2]), res


def closed_form(params, c) -> dict:
    """The corrected residue formula (docs/commands/melnikov.md, step 6), per unit mu: J_sign(g0) =
    sin_plus|sin_minus * sin g0 + cos * cos g0 (sign = +1 | -1), with its parts J_Q, J_R."""
    prm = _params(params)
    hc = homoclinic_constants(prm, c)
    b, lam, S = prm.b, prm.lam, hc.S
    e = math.exp(hc.beta * S)
    AQ = 2.0 * math.pi * math.sqrt(2.0) * b / math.sqrt(lam * hc.B) * e / math.cosh(0.5 * math.pi * S)
    AR = 4.0 * math.pi * b / hc.B * e / math.sinh(0.5 * math.pi * S)
    return {"AQ": AQ, "AR": AR, "sin_plus": -AQ + AR * prm.eta + 0.0, "sin_minus": AQ + AR * prm.eta + 0.0,
            "cos": -AR * prm.xi + 0.0}


def ur24(params, c) -> dict:
    """ur24 exactly as printed, divided by mu: J = J_Q + J_R with S = 2c (b1 b2)^(-1/2),
    cos alpha = d1, sin alpha = d2."""
    prm = _params(params)
    hc = homoclinic_constants(prm, c)
    b, lam, S, al = prm.b, prm.lam, hc.S, hc.alpha
    pref = math.exp(0.5 * math.pi * S) / math.sinh(math.pi * S)
    AQ = 2.0 * math.pi * math.sqrt(2.0) * b / math.sqrt(lam * hc.B) * pref * math.sinh((0.5 * math.pi - al) * S)
    AR = 4.0 * math.pi * b / hc.B * pref * math.cosh((0.5 * math.pi - al) * S)
    return {"AQ": AQ, "AR": AR, "sin": -AQ + AR * prm.eta + 0.0, "cos": -AR * prm.xi + 0.0}


def _close(a, b, scale):
    return abs(a - b) <= UR24_RTOL * max(scale, 1e-300)


def amplitudes(params=None, h=None, *, window=DEFAULT_WINDOW) -> dict:
    """Everything ``python -m explorer melnikov`` reports (per unit mu; mu itself is ignored)."""
    prm = model.FIGURE4 if params is None else _params(params)
    h = model.FIGURE4_H if h is None else h
    c = check_params(prm, h)
    hc = homoclinic_constants(prm, c)
    fits = {s: fit_harmonics(prm, c, s, window=window) for s in (1, -1)}
    pure = prm.with_(xi=0.0, eta=0.0, mu=0.0)
    amp = {s: fit_harmonics(pure, c, s, window=window)[0] for s in (1, -1)}
    u = ur24(prm, c)
    cf = closed_form(prm, c)
    scale = max(abs(fits[1][0]), abs(fits[1][1]), abs(amp[1]))
    holds = any(_close(u["sin"], fits[s][0], scale) and _close(u["cos"], fits[s][1], scale) for s in (1, -1))
    out = {
        "c": c, "h": float(h), "params": prm.as_dict(),
        "b1": hc.b1, "b2": hc.b2, "B": hc.B, "S": hc.S, "alpha": hc.alpha,
        "amplitude_plus": amp[1], "amplitude_minus": amp[-1],
        "sin_plus": fits[1][0], "cos_plus": fits[1][1],
        "sin_minus": fits[-1][0], "cos_minus": fits[-1][1],
        "fit_residual": max(fits[1][3], fits[-1][3]),
        "ur24": -u["AQ"], "ur24_sin": u["sin"], "ur24_cos": u["cos"],
        "ur24_ratio": (-u["AQ"]) / amp[1],
        "ur24_holds": bool(holds),
        "closed_form_plus": -cf["AQ"], "closed_form_sin_plus": cf["sin_plus"],
        "closed_form_sin_minus": cf["sin_minus"], "closed_form_cos": cf["cos"],
        "g0": "phi at the centre of the homoclinic orbit (p2 = 0, |p1| max, M min)",
    }
    return out


def _psi(hc: HomoclinicConstants, b, t):
    """phi(t) - g0 along R7 (increasing when M > 0)."""
    return (hc.c / b) * t - 2.0 * math.atan((hc.d1 / hc.d2) * math.tanh(hc.rate * t))


def _psi_inverse(hc, b, target):
    from scipy.optimize import brentq

    w = hc.c / b
    lo, hi = (target - math.pi) / w - 1.0, (target + math.pi) / w + 1.0
    return brentq(lambda t: _psi(hc, b, t) - target, lo, hi, xtol=1e-15, rtol=1e-15, maxiter=200)


def _require_monotone(prm, c):
    if not c < 2.0 * prm.lam * prm.b / prm.a1:
        raise ParameterError(f"the section phi = pi needs M > 0 along the homoclinic orbit, i.e. "
                             f"c < 2 lam b/a1 = {2 * prm.lam * prm.b / prm.a1:.6g}; got c = {c:.6g}")


def _section_F0_normal(prm, h, x, phi0=math.pi):
    """Normal to the level curve of F0 on the section (M from the energy) at x."""
    y = model.section_state(prm, [x[0]], [x[1]], h, phi0)[0]
    P = prm.as_array()
    gH = np.array([x[0] / P[model.A1], x[1] / P[model.A2]])  # + mu terms: zero at mu = 0
    if prm.mu != 0.0:
        g1, g2 = model.section_gamma(phi0)
        gH = gH + (prm.mu / prm.lam) * np.array([-g2, g1])
    dM = -gH / (y[2] / prm.b)
    n = dM + np.asarray(x, float) / prm.lam
    return n / np.linalg.norm(n)


def separatrix_point(params, h, g0, sign=1, phi0=math.pi):
    """The crossing with phi = phi0 (mod 2 pi) of the unperturbed homoclinic orbit (sign, g0)
    nearest its centre (psi(t_c) = phi0 - g0 reduced to [-pi, pi))."""
    prm = _params(params).with_(mu=0.0)
    c = check_params(prm, h)
    _require_monotone(prm, c)
    hc = homoclinic_constants(prm, c)
    target = (phi0 - g0 + math.pi) % (2.0 * math.pi) - math.pi
    tc = _psi_inverse(hc, prm.b, target)
    p1, p2, _, _ = exact.homoclinic(_P0(prm), c, tc, sign, 0.0, g0)
    x = np.array([float(p1), float(p2)])
    return x, tc, _section_F0_normal(prm, h, x, phi0)


def measured_splitting(params, h, mu, g0, sign=1, *, s_local=1e-4, tol=MAP_TOL, J=None) -> dict:
    """Splitting of the separatrices measured in F0 on the section phi = pi at weight mu."""
    from scipy.optimize import brentq

    from explorer.analysis import fixedpoints
    from explorer.analysis.section_map import SectionMap

    prm0 = _params(params).with_(mu=0.0)
    c = check_params(prm0, h)
    _require_monotone(prm0, c)
    mu = float(mu)
    if not (math.isfinite(mu) and mu > 0.0):
        raise ParameterError(f"mu must be finite and > 0 for a measured splitting, got {mu!r}")
    hc = homoclinic_constants(prm0, c)
    prm = prm0.with_(mu=mu)
    fp = fixedpoints.follow(prm0, h, "mu", 0.0, mu, (0.0, 0.0), max_step=max(mu, 1e-12), tol=tol)
    if fp.stable:
        raise ParameterError(f"the fixed point is elliptic at mu = {mu:g}: no separatrices to split")
    smap = SectionMap(prm, h, tol=tol)
    w, V = np.linalg.eig(fp.jacobian)
    w, V = np.real(w), np.real(V)
    iu = int(np.argmax(np.abs(w)))
    lam_u = abs(w[iu])
    xc, tc, nrm = separatrix_point(prm0, h, g0, sign)
    tan = np.array([-nrm[1], nrm[0]])
    P0 = _P0(prm0)
    pts = {}
    iters = {}
    for stable in (False, True):
        idx = 1 - iu if stable else iu
        e = V[:, idx] / np.linalg.norm(V[:, idx])
        k = 0
        while True:
            k += 1
            tk = _psi_inverse(hc, prm0.b, _psi(hc, prm0.b, tc) + (2 if stable else -2) * math.pi * k)
            q1, q2, _, _ = exact.homoclinic(P0, c, tk, sign, 0.0, g0)
            q = np.array([float(q1), float(q2)])
            if np.linalg.norm(q) < s_local or k > 200:
                break
        if e @ q < 0:
            e = -e
        s0 = float(np.linalg.norm(q))

        def image(logs):
            x = fp.point + math.exp(logs) * e
            for _ in range(k):
                x = smap(x, backward=stable, jacobian=False).point
            return x

        def G(logs):
            return float((image(logs) - xc) @ tan)

        root = None
        for frac in (0.25, 0.5):
            f = frac * math.log(lam_u)
            lo, hi = math.log(s0) - f, math.log(s0) + f
            try:
                if G(lo) * G(hi) < 0:
                    root = brentq(G, lo, hi, xtol=1e-15, rtol=1e-15, maxiter=200)
                    break
            except ParameterError:
                continue
        if root is None:
            raise ParameterError(f"could not locate the {'stable' if stable else 'unstable'} manifold on "
                                 f"the transversal at g0 = {g0:g} (mu = {mu:g} too large?)")
        pts[stable] = image(root)
        iters[stable] = k

    def F0sec(x):
        y = model.section_state(prm, [x[0]], [x[1]], h)[0]
        return float(F0(prm, y))

    xu, xs = pts[False], pts[True]
    measured = F0sec(xu) - F0sec(xs)
    if J is None:
        J = melnikov_integral(prm0, c, g0, sign)
    predicted = mu * J
    return {"mu": mu, "g0": float(g0), "sign": int(sign), "measured": measured, "predicted": predicted,
            "ratio": measured / predicted if predicted != 0 else float("nan"),
            "J": J, "x_c": xc.tolist(), "x_u": xu.tolist(), "x_s": xs.tolist(),
            "fixed_point": fp.point.tolist(), "multiplier": float(lam_u),
            "iterations_u": iters[False], "iterations_s": iters[True]}


def melnikov_table(params=None, h=None, mus=DEFAULT_MUS, g0s=DEFAULT_G0S, signs=(1, -1), *, s_local=1e-4,
                   tol=MAP_TOL):
    """Rows (dicts) of :func:`measured_splitting` for every sign, g0 and mu (mu innermost)."""
    prm = model.FIGURE4 if params is None else _params(params)
    h = model.FIGURE4_H if h is None else h
    c = check_params(prm, h)
    rows = []
    for s in signs:
        for g in g0s:
            J = melnikov_integral(prm.with_(mu=0.0), c, g, s)
            for mu in mus:
                rows.append(measured_splitting(prm, h, mu, g, s, J=J, s_local=s_local, tol=tol))
    return rows


def format_table(rows) -> str:
    lines = ["sign,g0,mu,measured,mu*J,ratio"]
    for r in rows:
        lines.append(f"{r['sign']:+d},{r['g0']:.6f},{r['mu']:.3g},{r['measured']:.10e},"
                     f"{r['predicted']:.10e},{r['ratio']:.8f}")
    return "\n".join(lines)
