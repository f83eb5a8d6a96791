#!/usr/bin/env python
"""Observed convergence order of every method on the real model (three parameter sets: the
Figure-4 scene at mu = 0.5 and two asymmetric sets with chi, zeta, xi, eta != 0, lam < 0 / > 0).

The error is that of the state at a fixed time T = 2 (orbit started on phi = pi) against a
reference: heyoka taylor_adaptive in extended precision (fp_type numpy.longdouble, tol = eps)
when heyoka is installed, else explorer dop853 tol 1e-16 for the Taylor rows and explorer taylor
tol 1e-16 for the others (never the method being measured).

- every splitting scheme (kernels.splitting.SCHEMES, n steps of drivers.split_step with
  dt = T/n, n = 1 .. 65536 in steps of sqrt 2, stopping below an error of 1e-12): the
  least-squares slope of log(error) against log(dt) over the points with errors in
  [1e-11, 1e-5] (the asymptotic range, away from round-off; at least 3 points) within 10 % of
  the nominal order;
- Taylor at a fixed step (the kernels of the taylor method, _lanes_generated.taylor_coefficients and
  kernels.taylor.evaluate) for orders p = 2, 3, 4, 6, 8, 10, same fit: within 10 % of p.
  (Orders >= 12 cannot be seen in double precision: an error above 1e-11 needs h / rho > 0.1,
  where the terms beyond h^(p+1) still count and the apparent order is p + 1 or more.);
- adaptive Taylor: error / tol in [1e-3, 10] for tol = 1e-8 .. 1e-14;
- DOP853 at a fixed step (kernels.dop853): within 10 % of 8;
- adaptive DOP853: slope of log(error) against log(tol) over tol = 1e-6 .. 1e-13 in [0.9, 1.1]
  (tolerance proportionality, which holds for an 8th-order method under scipy's controller; a
  7th-order one gives 7/8) and error / tol in [0.1, 30].

    python benchmarks/stress/stress_convergence.py            # ~1 min
    python benchmarks/stress/stress_convergence.py --quick    # one parameter set
"""
from __future__ import annotations

import argparse
import sys

import numpy as np
from _stress import C, Checks

T = 2.0


def param_sets():
    from explorer import model
    return {"figure4_mu0.5": model.FIGURE4.with_(mu=0.5),
            "asym_lam_neg": model.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=-0.15, mu=0.7, xi=0.3,
                                         eta=-0.25),
            "asym_lam_pos": model.Params(a1=0.8, a2=1.4, b=2.5, lam=1.6, chi=-0.3, zeta=0.25, mu=1.2, xi=-0.2,
                                         eta=0.4)}


def heyoka_state(P, y0, t):
    import bench_w4
    import heyoka as hy
    eqs, _ = bench_w4._hy_system(P)
    ta = hy.taylor_adaptive(eqs, np.array([np.longdouble(v) for v in y0]), fp_type=np.longdouble)
    ta.propagate_until(np.longdouble(t))
    return np.array([float(v) for v in ta.state])


def final(prm, y0, t, method, **kw):
    from explorer.analysis import sections
    r = sections.crossings(prm, states=y0, n_crossings=10**4, method=method, tmax=t, **kw)
    assert r.info[0, 0] == t
    return r.final[0]


NS = np.unique(np.round(2.0 ** (np.arange(0, 33) / 2)).astype(int))   # 1 .. 65536


def fitted_order(dts, errs, lo=1e-11, hi=1e-5):
    """Least-squares slope of log(err) vs log(dt) over the points with errors in [lo, hi];
    None if fewer than 3 such points."""
    dts, errs = np.asarray(dts, float), np.asarray(errs, float)
    sel = (errs >= lo) & (errs <= hi) & np.isfinite(errs)
    if sel.sum() < 3:
        return None, int(sel.sum())
    return float(np.polyfit(np.log(dts[sel]), np.log(errs[sel]), 1)[0]), int(sel.sum())


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    ck = Checks("stress_convergence", args.quick, argv)
    from explorer import model
    from explorer._jit import njit
    from explorer.integrate import drivers
    from explorer.integrate._lanes_generated import taylor_coefficients
    from explorer.kernels import dop853 as dp
    from explorer.kernels import splitting
    from explorer.kernels import taylor as tk
    from explorer.model.equations import N_FLOWS, rhs

    @njit
    def split_steps(y, P, dt, ids, fr, n):
        for _ in range(n):
            drivers.split_step(y, P, dt, ids, fr)

    use_heyoka = C.have("heyoka")
    ck.note("reference: " + ("heyoka taylor_adaptive fp_type=numpy.longdouble" if use_heyoka else
                             "explorer dop853 tol 1e-16 (taylor rows) / taylor tol 1e-16 (others)"))
    sets = param_sets()
    if args.quick:
        sets = {k: sets[k] for k in ("asym_lam_neg",)}
    for name, prm in sets.items():
        P = prm.as_array()
        c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
        y0 = model.section_state(prm, [c1 + 0.3 * r1], [c2 + 0.2 * r2], 2.0)[0]
        if use_heyoka:
            ref_all = ref_taylor = heyoka_state(P, y0, T)
            ck.note(f"{name}: |heyoka ldbl - taylor 1e-16| = {np.abs(ref_all - final(prm, y0, T, 'taylor', tol=1e-16)).max():.2e}")
        else:
            ref_all = final(prm, y0, T, "taylor", tol=1e-16)
            ref_taylor = final(prm, y0, T, "dop853", tol=1e-16)
        # ---- splitting: n steps of dt = T/n
        for method, (weights, order, _ref) in splitting.SCHEMES.items():
            ids, fr = splitting.flow_sequence(weights, N_FLOWS)
            ids, fr = np.ascontiguousarray(ids, np.int64), np.ascontiguousarray(fr, np.float64)
            errs = []
            for n in NS:
                y = y0.copy()
                split_steps(y, P, T / n, ids, fr, n)
                errs.append(np.abs(y - ref_all).max() if np.all(np.isfinite(y)) else np.inf)
                if errs[-1] < 1e-12:
                    break
            q, npts = fitted_order(T / NS[:len(errs)], errs)
            ck.check(f"{name}: {method} (nominal order {order}) fitted order", q is not None and abs(q - order) <= 0.1 * order,
                     None if q is None else round(q, 3), f"within 10 % of {order} ({npts} points in [1e-11, 1e-5])",
                     errors=[float(e) for e in errs])
        # ---- taylor at fixed steps
        for p in (2, 3, 4, 6, 8, 10):
            errs = []
            for n in NS:
                h = T / n
                y = y0.copy()
                X = np.zeros((5, p + 1))
                out = np.empty(5)
                for _ in range(n):
                    X[:, 0] = y
                    taylor_coefficients(P, X, p)
                    tk.evaluate(X, p, h, out)
                    y = out.copy()
                errs.append(np.abs(y - ref_taylor).max() if np.all(np.isfinite(y)) else np.inf)
                if errs[-1] < 1e-12:
                    break
            q, npts = fitted_order(T / NS[:len(errs)], errs)
            ck.check(f"{name}: taylor fixed step, order {p}: fitted order", q is not None and abs(q - p) <= 0.1 * p,
                     None if q is None else round(q, 3), f"within 10 % of {p} ({npts} points)",
                     errors=[float(e) for e in errs])
        # ---- adaptive taylor
        ratios = [float(np.abs(final(prm, y0, T, "taylor", tol=10.0 ** -k) - ref_taylor).max() / 10.0 ** -k)
                  for k in range(8, 15)]
        ck.check(f"{name}: adaptive taylor error/tol, tol 1e-8 .. 1e-14", all(1e-3 <= r <= 10 for r in ratios),
                 [float(f"{r:.2g}") for r in ratios], "in [1e-3, 10]")
        # ---- dop853 fixed step
        errs = []
        for n in NS:
            h = T / n
            y = y0.copy()
            K = np.empty((16, 5))
            tmp, ynew = np.empty(5), np.empty(5)
            for _ in range(n):
                rhs(y, P, K[0])
                for s in range(1, 12):
                    dp.stage_input(y, K, s, h, tmp)
                    rhs(tmp, P, K[s])
                dp.step_solution(y, K, h, ynew)
                y = ynew.copy()
            errs.append(np.abs(y - ref_all).max() if np.all(np.isfinite(y)) else np.inf)
            if errs[-1] < 1e-12:
                break
        q, npts = fitted_order(T / NS[:len(errs)], errs)
        ck.check(f"{name}: dop853 fixed step fitted order", q is not None and abs(q - 8) <= 0.8,
                 None if q is None else round(q, 3), f"within 10 % of 8 ({npts} points)", errors=[float(e) for e in errs])
        # ---- adaptive dop853
        tols = 10.0 ** -np.arange(6, 14)
        errs = np.array([np.abs(final(prm, y0, T, "dop853", tol=float(t)) - ref_all).max() for t in tols])
        slope = float(np.polyfit(np.log(tols), np.log(errs), 1)[0])
        ck.check(f"{name}: adaptive dop853 slope of log(error) vs log(tol)", 0.9 <= slope <= 1.1, round(slope, 3),
                 "in [0.9, 1.1]", errors=errs.tolist())
        ck.check(f"{name}: adaptive dop853 error/tol", bool(np.all((errs / tols >= 0.1) & (errs / tols <= 30))),
                 [float(f"{r:.2g}") for r in errs / tols], "in [0.1, 30]")
    fitted = [(c["check"], c["value"]) for c in ck.items if "fitted order" in c["check"]]
    return ck.finish(f"{sum(c['ok'] for c in ck.items)}/{len(ck.items)} passed; fitted orders: "
                     + "; ".join(f"{k.split(': ', 1)[1].replace(' fitted order', '')}: {v}" for k, v in fitted[:40]))


if __name__ == "__main__":
    sys.exit(main())
