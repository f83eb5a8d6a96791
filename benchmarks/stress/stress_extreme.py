#!/usr/bin/env python
"""Extreme parameters: correct numbers or a clear refusal, never NaN stored as data.

Cases (Figure-4 scene changed as named): mu up to 50; |lam| down to 1e-3 (both signs); a1 = a2
(1 +- 1e-12); h = 1e3, 1e6 and h just above the minimum of the energy on the section (and
exactly at it, an equilibrium); combinations; the asymmetric terms chi, zeta, xi, eta at large
mu.  Each case: 6 start points across the allowed ellipse, 20 crossings (time budget 200, step
budget 1e6), every method: taylor tol 1e-13, dop853 tol 1e-12, split8 and split4 at dt = the
mean Taylor step / 10 (a step resolving the orbit's time scale; a fixed dt chosen for h = 2
does not resolve h = 1e6 and gives meaningless energies: see the note printed at the end).

Checks per case and method: a ParameterError, or: every stored crossing finite, no orbit with
status 'non-finite state', final states finite, and the energy error relative to the size of
the terms of H within the method's error (taylor 1e-11, dop853 1e-9, split8 1e-8, split4 1e-4).

Beyond the stated ranges (lam = 1e-6, mu = 1e3, h = 1e12, a1 = 1e-8, b = 1e8): only that nothing
non-finite is stored and that the status says why an orbit stopped.

    python benchmarks/stress/stress_extreme.py            # ~1 min
    python benchmarks/stress/stress_extreme.py --quick
"""
from __future__ import annotations

import argparse
import sys

import numpy as np
from _stress import Checks

BOUNDS = {"taylor": 1e-11, "dop853": 1e-9, "split8": 1e-8, "split4": 1e-4}


def cases(quick):
    from explorer import model
    F = model.FIGURE4
    c = {
        "mu=50": (F.with_(mu=50.0), 2.0),
        "mu=20": (F.with_(mu=20.0), 2.0),
        "lam=1e-3,mu=0.5": (F.with_(lam=1e-3, mu=0.5), 2.0),
        "lam=-1e-3,mu=0.5": (F.with_(lam=-1e-3, mu=0.5), 2.0),
        "lam=1e-3,mu=0": (F.with_(lam=1e-3), 2.0),
        "lam=1e-2,mu=50": (F.with_(lam=1e-2, mu=50.0), 2.0),
        "a1=a2(1+1e-12),mu=0.5": (F.with_(a1=0.5 * (1 + 1e-12), mu=0.5), 2.0),
        "a1=a2(1-1e-12),mu=0.5": (F.with_(a1=0.5 * (1 - 1e-12), mu=0.5), 2.0),
        "a1=a2(1+1e-12),mu=0": (F.with_(a1=0.5 * (1 + 1e-12)), 2.0),
        "h=1e3,mu=0.5": (F.with_(mu=0.5), 1e3),
        "h=1e6,mu=0.5": (F.with_(mu=0.5), 1e6),
        "h=1e6,mu=50": (F.with_(mu=50.0), 1e6),
        "h=1e6,lam=1e-3": (F.with_(mu=0.5, lam=1e-3), 1e6),
        "h=hmin+1e-12,mu=2": (F.with_(mu=2.0), -2.0 + 1e-12),
        "h=hmin+1e-8,mu=0.5": (F.with_(mu=0.5), -0.125 + 1e-8),
        "h=hmin+1e-12,mu=50": (F.with_(mu=50.0), -1250.0 + 1e-9),
        "asym,mu=50": (model.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=-0.15, mu=50.0, xi=0.3,
                                    eta=-0.25), 2.0),
        "asym,lam=1e-3": (model.Params(a1=1.3, a2=0.6, b=1.7, lam=1e-3, chi=0.2, zeta=-0.15, mu=0.7, xi=0.3,
                                       eta=-0.25), 2.0),
    }
    if quick:
        c = {k: c[k] for k in ("mu=50", "lam=-1e-3,mu=0.5", "a1=a2(1+1e-12),mu=0.5", "h=1e6,mu=0.5",
                               "h=hmin+1e-12,mu=2")}
    beyond = {
        "lam=1e-6,mu=0.5": (F.with_(lam=1e-6, mu=0.5), 2.0),
        "mu=1e3": (F.with_(mu=1e3), 2.0),
        "h=1e12": (F.with_(mu=0.5), 1e12),
        "a1=1e-8": (F.with_(a1=1e-8, mu=0.5), 2.0),
        "b=1e8": (F.with_(b=1e8, mu=0.5), 2.0),
    }
    return c, beyond


def energy_scale(prm, y):
    P = prm.as_array()
    p1, p2, m, g1, g2 = np.moveaxis(np.asarray(y, float), -1, 0)
    kin = 0.5 * (p1 * p1 / P[0] + p2 * p2 / P[1] + m * m / P[2])
    return kin + abs(P[6] / P[3]) * np.abs((p1 - P[4]) * g2 - (p2 - P[5]) * g1) + P[6] * np.abs(P[7] * g1 + P[8] * g2)


def run_case(prm, h):
    from explorer import model
    from explorer.analysis import sections
    from explorer.model import ParameterError
    u = np.array([-0.9, -0.3, 0.0, 0.5, 0.95, 0.2])
    v = np.array([0.1, -0.4, 0.0, 0.2, 0.0, 0.9])
    try:
        c1, c2, r1, r2 = model.allowed_ellipse(prm, h)
        y0 = model.section_state(prm, c1 + r1 * u, c2 + r2 * v, h)
    except (TypeError, ParameterError) as exc:
        return {"refused": f"start: {exc}"}, None, None
    out = {}
    tay = sections.crossings(prm, states=y0, n_crossings=20, method="taylor", tol=1e-13, tmax=200.0, max_steps=10**6)
    out["taylor"] = tay
    dt = float(np.min(tay.info[:, 0] / np.maximum(tay.info[:, 1], 1))) / 10
    for method, kw in (("dop853", dict(tol=1e-12)), ("split8", dict(dt=dt)), ("split4", dict(dt=dt))):
        try:
            out[method] = sections.crossings(prm, states=y0, n_crossings=20, method=method, tmax=200.0, max_steps=10**6, **kw)
        except ParameterError as exc:
            out[method] = f"refused: {exc}"
    return out, y0, dt


def assess(res, y0, prm):
    """(finite_ok, worst relative energy error, statuses)"""
    from explorer.kernels import STATUS_NONFINITE
    finite = all(np.all(np.isfinite(res.orbit(i))) for i in range(len(y0))) and np.all(np.isfinite(res.final))
    nonfinite = int(np.sum(res.status == STATUS_NONFINITE))
    scale = energy_scale(prm, y0)
    rel = 0.0
    for i in range(len(y0)):
        rows = res.orbit(i)
        if len(rows):
            rel = max(rel, float(np.abs(rows[:, 4]).max() / scale[i]))
    return finite, nonfinite, rel, sorted({res.status_name(i) for i in range(len(y0))})


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    ck = Checks("stress_extreme", args.quick, argv)
    from explorer.analysis import sections
    main_cases, beyond = cases(args.quick)
    worst, refused = {}, 0
    for name, (prm, h) in main_cases.items():
        out, y0, dt = run_case(prm, h)
        if "refused" in out:
            ck.check(f"{name}: refused", True, out["refused"], "ParameterError or correct numbers")
            refused += 1
            continue
        for method, res in out.items():
            if isinstance(res, str):
                ck.check(f"{name} {method}: refused", True, res, "ParameterError or correct numbers")
                continue
            finite, nonfinite, rel, st = assess(res, y0, prm)
            worst[method] = max(worst.get(method, 0.0), rel)
            ok = finite and nonfinite == 0 and rel <= BOUNDS[method]
            ck.check(f"{name} {method}{f' dt {dt:.3g}' if method.startswith('split') else ''}: rel. energy error "
                     f"(statuses {st}, {int(res.count.sum())} crossings)", ok, float(f"{rel:.3g}"),
                     f"<= {BOUNDS[method]:g}, all finite, no non-finite status")
    for name, (prm, h) in beyond.items():
        out, y0, dt = run_case(prm, h)
        if "refused" in out:
            ck.check(f"beyond: {name}: refused", True, out["refused"], "nothing non-finite stored")
            continue
        for method, res in out.items():
            if isinstance(res, str):
                ck.check(f"beyond: {name} {method}: refused", True, res, "nothing non-finite stored")
                continue
            finite, nonfinite, rel, st = assess(res, y0, prm)
            ck.check(f"beyond: {name} {method}: stored crossings finite (statuses {st}, rel. energy error "
                     f"{rel:.2g})", finite, finite, "all finite")
    # the note on fixed steps that do not resolve the orbit
    from explorer import model
    prm = model.FIGURE4.with_(mu=0.5)
    y0 = model.section_state(prm, [0.0, 500.0], [0.0, 300.0], 1e6)
    r = sections.crossings(prm, states=y0, n_crossings=20, method="split8", dt=0.05, tmax=10.0)
    rel = float(np.nanmax(np.abs(r.data[..., 4])) / energy_scale(prm, y0).min())
    ck.note(f"split8 with the default dt = 0.05 at h = 1e6 (the orbit's time scale is ~1e-3): relative energy "
            f"error {rel:.2g}, statuses {[r.status_name(i) for i in range(2)]}: no warning that dt does not resolve "
            "the orbit (a fixed-step method has no error control)")
    return ck.finish(f"{len(main_cases)} cases x 4 methods ({refused} refused): worst energy error relative to the "
                     "size of H's terms: " + ", ".join(f"{m} {v:.1e} (bound {BOUNDS[m]:g})" for m, v in worst.items())
                     + f"; {len(beyond)} cases beyond the ranges: nothing non-finite stored")


if __name__ == "__main__":
    sys.exit(main())
