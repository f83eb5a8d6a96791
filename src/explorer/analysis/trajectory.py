"""The body in the plane: the full system R1 with the position (x, y), any lam including 0
(docs/model.md R1, R2; docs/commands/trajectory.md has the equations, the drift +mu/lam and the
band (ur25 corrected), the falling body of Kozlov, and the API).
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np

from explorer import model
from explorer.integrate.full import integrate_full
from explorer.integrate.methods import TRAJECTORY_TOL
from explorer.kernels import STATUS_NAMES
from explorer.model import validation
from explorer.model.equations import FULL_DIM, energy_full

#: layout of the full state (docs/model.md R1, polynomial form)
P1, P2, M, G1, G2, X, Y = range(7)
STATE_DIM = FULL_DIM
TWO_PI = 2.0 * math.pi
#: the CLI's default scene: Figure 4 (docs/model.md R9) with mu = 0.5
DEFAULT_PARAMS = dict(model.FIGURE4.as_dict(), mu=0.5)
DEFAULT_TOL = TRAJECTORY_TOL
DEFAULT_MAX_STEPS = 10 ** 8
#: bytes per sample of a :func:`trajectory` result and its conservation check: about 20 float64
#: arrays of n_samples (the state, phi, H, p_x, p_y, kinetic energy, masks, temporaries)
SAMPLE_BYTES = 160


@dataclass(frozen=True)
class Trajectory:
    """The body in the plane sampled at equally spaced times (:func:`trajectory`)."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    phi: np.ndarray
    p1: np.ndarray
    p2: np.ndarray
    M: np.ndarray
    g1: np.ndarray
    g2: np.ndarray
    H: np.ndarray
    px: np.ndarray
    py: np.ndarray
    turn_t: np.ndarray
    turn_phi: np.ndarray
    turn_dir: np.ndarray
    status: str
    steps: int
    t_reached: float
    n_filled: int
    params: dict
    P: np.ndarray
    tol: float
    y0: np.ndarray

    def __getitem__(self, name):
        if name not in self.keys():
            raise KeyError(name)
        return getattr(self, name)

    def keys(self):
        return tuple(f.name for f in fields(self))

    def __iter__(self):
        return iter(self.keys())


def full_params(params=None, **changes) -> dict:
    """Validated parameters of the full system R1 as a dict (keys ``model.PARAM_NAMES``)."""
    if params is None:
        d = dict(DEFAULT_PARAMS)
    elif isinstance(params, model.Params):
        d = params.as_dict()
    elif isinstance(params, Mapping):
        unknown = sorted(set(params) - set(model.PARAM_NAMES))
        if unknown:
            raise model.ParameterError(f"unknown parameter(s) {', '.join(unknown)}; "
                                       f"allowed: {', '.join(model.PARAM_NAMES)}")
        d = dict(DEFAULT_PARAMS, **params)
    else:
        arr = np.asarray(params, dtype=np.float64).ravel()
        if arr.shape != (len(model.PARAM_NAMES),):
            raise model.ParameterError(f"packed parameters need {len(model.PARAM_NAMES)} numbers "
                                       f"({', '.join(model.PARAM_NAMES)}), got {arr.size}")
        d = dict(zip(model.PARAM_NAMES, arr.tolist()))
    unknown = sorted(set(changes) - set(model.PARAM_NAMES))
    if unknown:
        raise model.ParameterError(f"unknown parameter(s) {', '.join(unknown)}")
    d.update(changes)
    lam = validation.magnitude("lam", d["lam"])
    # model.Params validates every other parameter; lam = 0 is legal for R1, so it is replaced by 1 here.
    checked = model.Params(**dict(d, lam=1.0)).as_dict()
    checked["lam"] = lam
    return checked


def initial_state(params, p1, p2, M, phi, x=0.0, y=0.0) -> np.ndarray:
    """The full state (p1, p2, M, sin phi, cos phi, x, y) (docs/model.md R1); ``params`` is only
    validated (the state does not depend on it)."""
    full_params(params)
    vals = [validation.magnitude(n, v) if n != "phi" else validation.real(n, v)
            for n, v in (("p1", p1), ("p2", p2), ("M", M), ("phi", phi), ("x", x), ("y", y))]
    p1, p2, M_, phi, x, y = vals
    return np.array([p1, p2, M_, math.sin(phi), math.cos(phi), x, y], dtype=np.float64)


def _check_run(tmax, n_samples, tol):
    tmax = validation.real("tmax", tmax)
    if not tmax > 0.0:
        raise model.ParameterError(f"tmax (the time the orbit runs) must be > 0, got {tmax!r}")
    try:
        ns = int(n_samples)
    except (TypeError, ValueError):
        raise model.ParameterError(f"samples must be an integer >= 2, got {n_samples!r}") from None
    if ns != n_samples or ns < 2:
        raise model.ParameterError(f"samples must be an integer >= 2, got {n_samples!r}")
    validation.fits_in_memory("samples", ns, SAMPLE_BYTES, "the arrays of the result", lo=2)
    tol = validation.real("tol", tol)
    if not (0.0 < tol < 1.0):
        raise model.ParameterError(f"tol must be in (0, 1), got {tol!r}")
    return tmax, ns, tol


def momentum_integrals(P, t, p1, p2, g1, g2, x, y):
    """docs/model.md R2: (p_x, p_y); p_x = c1, p_y = c2 - mu t along orbits."""
    lam, chi, zeta = P[model.LAM], P[model.CHI], P[model.ZETA]
    px = p1 * g2 - p2 * g1 + lam * y + zeta * g1 - chi * g2
    py = p1 * g1 + p2 * g2 - lam * x - zeta * g2 - chi * g1
    return px, py


def trajectory(params, y0_full, tmax, n_samples=2001, tol=DEFAULT_TOL, *, phi_start=None,
               max_steps=DEFAULT_MAX_STEPS, max_turns=None) -> Trajectory:
    """Integrate R1 from ``y0_full`` (:func:`initial_state`) over [0, tmax] and sample it at
    ``n_samples`` equally spaced times (both ends included)."""
    prm = full_params(params)
    P = np.array([prm[n] for n in model.PARAM_NAMES], dtype=np.float64)
    tmax, ns, tol = _check_run(tmax, n_samples, tol)
    y0 = np.ascontiguousarray(np.asarray(y0_full, dtype=np.float64).ravel())
    if y0.shape != (STATE_DIM,):
        raise model.ParameterError(f"the full state has {STATE_DIM} components (p1, p2, M, g1, g2, x, y), "
                                   f"got {y0.size}")
    if not np.all(np.isfinite(y0)):
        raise model.ParameterError("the initial state must be finite")
    if abs(y0[G1] ** 2 + y0[G2] ** 2 - 1.0) > 1e-12:
        raise model.ParameterError("the initial state needs g1^2 + g2^2 = 1 (g = (sin phi, cos phi)); "
                                   "use initial_state()")
    phi0 = math.atan2(y0[G1], y0[G2])
    if phi_start is not None:
        ps = validation.real("phi", phi_start)
        phi0 = phi0 + TWO_PI * math.floor((ps - phi0) / TWO_PI + 0.5)
    t = np.linspace(0.0, tmax, ns)
    out = np.full((ns, STATE_DIM), np.nan)
    out_phi = np.full(ns, np.nan)
    cap = 1024 if max_turns is None else int(max_turns)
    while True:
        turns = np.empty((cap, 3))
        status, filled, nturn, steps, t_reached = integrate_full(
            y0, phi0, P, t, tol, tol, int(max_steps), out, out_phi, turns)
        if nturn <= cap or max_turns is not None:
            break
        cap = nturn
    nturn = min(nturn, cap)
    p1, p2, m, g1, g2, x, y = (out[:, i] for i in range(STATE_DIM))
    H = model.energy_full(P, out)
    px, py = momentum_integrals(P, t, p1, p2, g1, g2, x, y)
    return Trajectory(
        t=t, x=x, y=y, phi=out_phi, p1=p1, p2=p2, M=m, g1=g1, g2=g2, H=H, px=px, py=py,
        turn_t=turns[:nturn, 0].copy(), turn_phi=turns[:nturn, 1].copy(),
        turn_dir=turns[:nturn, 2].copy(),
        status=STATUS_NAMES.get(int(status), f"status {status}"), steps=int(steps),
        t_reached=float(t_reached), n_filled=int(filled),
        params=prm, P=P, tol=tol, y0=y0.copy(),
    )


def conservation(result) -> dict:
    """Errors of the integrals along a :func:`trajectory` result (finite samples only)."""
    P = result["P"]
    ok = np.isfinite(result["x"])
    t = result["t"][ok]
    g = {k: result[k][ok] for k in ("p1", "p2", "M", "g1", "g2", "x", "y", "H", "px", "py")}
    mu, lam = P[model.MU], P[model.LAM]
    pn = np.hypot(g["p1"], g["p2"])
    s = math.hypot(P[model.CHI], P[model.ZETA])
    kin = 0.5 * (g["p1"] ** 2 / P[model.A1] + g["p2"] ** 2 / P[model.A2] + g["M"] ** 2 / P[model.B])
    scale_H = np.max(kin + mu * (np.abs(g["y"]) + np.abs(P[model.XI] * g["g1"] + P[model.ETA] * g["g2"])))
    scale_px = np.max(pn + s + abs(lam) * np.abs(g["y"]))
    scale_py = np.max(pn + s + abs(lam) * np.abs(g["x"]) + mu * t)
    eH = float(np.max(np.abs(g["H"] - g["H"][0])))
    ex = float(np.max(np.abs(g["px"] - g["px"][0])))
    ey = float(np.max(np.abs(g["py"] + mu * t - g["py"][0])))
    tiny = np.finfo(float).tiny
    return {"H": eH, "px": ex, "py": ey,
            "H_rel": eH / max(scale_H, tiny), "px_rel": ex / max(scale_px, tiny),
            "py_rel": ey / max(scale_py, tiny),
            "casimir": float(np.max(np.abs(g["g1"] ** 2 + g["g2"] ** 2 - 1.0))),
            "samples": int(ok.sum())}


# ====================================================================== drift and band (ur25)
def energy_band_halfwidth(params, y0_full) -> float:
    """A priori bound on |p - s|/|lam| from the energy (lam != 0), hence on |y - c1/lam|."""
    prm = full_params(params)
    P = np.array([prm[n] for n in model.PARAM_NAMES])
    lam = P[model.LAM]
    if lam == 0.0:
        return math.inf
    y0 = np.asarray(y0_full, dtype=np.float64)
    H = float(energy_full(y0, P))
    px, _ = momentum_integrals(P, 0.0, y0[P1], y0[P2], y0[G1], y0[G2], y0[X], y0[Y])
    mu = P[model.MU]
    hr = H - mu * px / lam
    a = max(P[model.A1], P[model.A2])
    s = math.hypot(P[model.CHI], P[model.ZETA])
    r = math.hypot(P[model.XI], P[model.ETA])
    k = a * mu / abs(lam)
    q = k + math.sqrt(k * k + 2.0 * a * max(hr + mu * s / abs(lam) + mu * r, 0.0))
    return float((q + s) / abs(lam))


def drift(params, y0_full, T, n_samples=20001, tol=DEFAULT_TOL, *, result=None, phi_start=None) -> dict:
    """Mean horizontal velocity over [0, T] vs the prediction +mu/lam (R2, ur25), and the band
    in y.  Needs lam != 0."""
    prm = full_params(params)
    if prm["lam"] == 0.0:
        raise model.ParameterError("drift needs lam != 0 (for lam = 0 the body falls: use kozlov())")
    res = trajectory(prm, y0_full, T, n_samples, tol, phi_start=phi_start) if result is None else result
    P = res["P"]
    lam, mu = P[model.LAM], P[model.MU]
    ok = np.isfinite(res["x"])
    t, x, y = res["t"][ok], res["x"][ok], res["y"][ok]
    slope = float(np.polyfit(t, x, 1)[0])
    T_ = float(t[-1])
    endpoint = float((x[-1] - x[0]) / T_)
    ps = np.hypot(res["p1"][ok] - P[model.CHI], res["p2"][ok] - P[model.ZETA])
    pred = float(mu / lam)
    c1 = float(res["px"][0])
    half = float(np.max(ps) / abs(lam))
    centre = float(c1 / lam)
    dev = np.abs(y - centre)
    return {
        "measured": slope, "endpoint": endpoint, "predicted": pred, "seed": -pred,
        "rel_error": (slope - pred) / abs(pred) if pred != 0 else math.nan,
        "endpoint_rel_error": (endpoint - pred) / abs(pred) if pred != 0 else math.nan,
        "abs_error": slope - pred,
        "remainder_bound": 2.0 * half / T_,
        "T": T_, "status": res["status"],
        "band": {"y_min": float(y.min()), "y_max": float(y.max()), "centre": centre,
                 "halfwidth_orbit": half, "halfwidth_energy": energy_band_halfwidth(prm, res["y0"]),
                 "max_deviation": float(dev.max()),
                 "inside": bool(np.all(dev <= np.max(ps) / abs(lam) * (1 + 1e-9) + 1e-12))},
        "result": res,
    }


# ====================================================================== the falling body (lam = 0)
def kozlov_omega_rate(params) -> float:
    """d Omega/dt of the linearised ur17 (lam = 0): Omega(t) = mu t sqrt(|1/a2 - 1/a1|/b)."""
    prm = full_params(params)
    return prm["mu"] * math.sqrt(abs(1.0 / prm["a2"] - 1.0 / prm["a1"]) / prm["b"])


def kozlov(params, y0_full, T, tol=DEFAULT_TOL, *, fit_from=0.3, n_samples=4001, result=None,
           phi_start=None) -> dict:
    """lam = 0: fit amplitude ~ t^alpha and frequency ~ t^beta of the oscillation of phi about
    phi_inf (Kozlov: alpha = -1/2, beta = 1) over t in [fit_from T, T]."""
    prm = full_params(params)
    if prm["lam"] != 0.0:
        raise model.ParameterError("kozlov needs lam = 0 (the falling body without circulation)")
    if not prm["mu"] > 0.0:
        raise model.ParameterError("kozlov needs mu > 0 (a heavy body)")
    if prm["a1"] == prm["a2"]:
        raise model.ParameterError("kozlov needs a1 != a2 (no restoring torque when a1 = a2)")
    fit_from = float(fit_from)
    if not 0.0 <= fit_from < 1.0:
        raise model.ParameterError(f"fit_from must be in [0, 1), got {fit_from!r}")
    res = trajectory(prm, y0_full, T, n_samples, tol, phi_start=phi_start) if result is None else result
    tt, ph = res["turn_t"], res["turn_phi"]
    if tt.size < 3:
        raise model.ParameterError(f"only {tt.size} turning points of phi up to T = {T}: the body has not "
                                   "started to oscillate; use a longer time")
    tm = 0.5 * (tt[1:] + tt[:-1])
    amp = 0.5 * np.abs(ph[1:] - ph[:-1])
    freq = 0.5 / np.diff(tt)
    mid = 0.5 * (ph[1:] + ph[:-1])
    T_ = float(res["t_reached"])
    w = tm >= fit_from * T_
    if w.sum() < 10:
        raise model.ParameterError(f"only {int(w.sum())} half-periods in the fit window t >= {fit_from * T_:g}; "
                                   "use a longer time")
    la, lf, lt = np.log(amp[w]), np.log(freq[w]), np.log(tm[w])
    alpha, ca = np.polyfit(lt, la, 1)
    beta, cf = np.polyfit(lt, lf, 1)
    phi_inf = float(np.mean(mid[-20:]))
    a1_gt = prm["a1"] > prm["a2"]
    period = math.pi
    base = 0.5 * math.pi if a1_gt else 0.0
    phi_inf_mod = float((phi_inf - base + 0.5 * period) % period - 0.5 * period + base)
    return {
        "amplitude_exponent": float(alpha), "frequency_exponent": float(beta),
        "amplitude_prefactor": float(math.exp(ca)), "frequency_prefactor": float(math.exp(cf)),
        "expected_amplitude_exponent": -0.5, "expected_frequency_exponent": 1.0,
        "freq_rate": float(np.median(freq[w] / tm[w])),
        "freq_rate_predicted": kozlov_omega_rate(prm) / TWO_PI,
        "phi_inf": phi_inf, "phi_inf_mod_pi": phi_inf_mod,
        "phi_inf_predicted_mod_pi": base,
        "fit_window": [float(fit_from * T_), T_], "n_half_periods": int(w.sum()),
        "n_turns": int(tt.size), "T": T_, "status": res["status"],
        "t_mid": tm, "amplitude": amp, "frequency": freq, "fit_mask": w,
        "result": res,
    }


def summary(res_drift=None, res_kozlov=None, cons=None) -> dict:
    """JSON-ready numbers of a run (arrays dropped)."""
    out = {}
    if res_drift is not None:
        out["drift"] = {k: v for k, v in res_drift.items() if k != "result"}
    if res_kozlov is not None:
        out["kozlov"] = {k: v for k, v in res_kozlov.items()
                         if k not in ("result", "t_mid", "amplitude", "frequency", "fit_mask")}
    if cons is not None:
        out["conservation"] = cons
    return out
