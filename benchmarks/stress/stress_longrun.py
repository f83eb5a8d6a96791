#!/usr/bin/env python
"""1e7 steps of every splitting method: energy error bounded without drift, Casimir kept.

8 orbits at once through the batch driver (4 chaotic at mu = 0.5, 4 regular at mu = 0.002;
Figure-4 scene, h = 2), dt = 0.05, run in chunks of at most 1e6 steps (the state carries over
exactly: t = n dt).  Per decade of steps (1e2..1e3, ..., 1e6..1e7) the maximum of |H - H0| over
the crossings and the chunk ends is recorded.

Checks (per method and regime):
- no drift: the log-log slope of the per-decade maximum of |H - H0| against the number of steps,
  from the decade 1e2..1e3 on (the first 100 steps, 5 time units, do not cover an orbit), is
  <= 0.6: a bounded error gives 0, the round-off random walk ~ sqrt(n) gives 0.5 (split8 at
  dt 0.05 is at round-off level), a drift ~ n gives 1;
- the energy error of the last decade is at most 3 sqrt(n_last / 1e5) x that of the decade
  1e4..1e5 steps (3 x the growth of a random walk; 30 for 1e7 steps);
- Casimir |g1^2 + g2^2 - 1| <= 5e-12 after 1e7 steps on every orbit.

    python benchmarks/stress/stress_longrun.py            # 1e7 steps, ~5 min on 2 cores
    python benchmarks/stress/stress_longrun.py --quick    # 1e5 steps
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from _stress import Checks

METHODS = ("split4", "split6", "split8")
DT = 0.05
MAX_CHUNK = 10**6


def run(prm, y0, method, n_total):
    from explorer import model
    from explorer.analysis import sections
    H0 = model.energy(prm, y0)
    y, n = y0.copy(), 0
    decades = {}
    ends = []
    e = 100
    while e <= n_total:
        ends.append(e)
        e *= 10
    bounds = []
    for end in ends:
        while end - (bounds[-1] if bounds else 0) > MAX_CHUNK:
            bounds.append((bounds[-1] if bounds else 0) + MAX_CHUNK)
        bounds.append(end)
    for b in bounds:
        steps = b - n
        tmax = steps * DT
        K = int(tmax * 2) + 20
        r = sections.crossings(prm, states=y, n_crossings=K, method=method, dt=DT, tmax=tmax)
        assert np.all(r.count < K) and np.all(r.status == 1), (r.count, r.status)   # ran to its time budget
        off = model.energy(prm, y) - H0
        dH = np.nanmax(np.abs(np.nan_to_num(r.data[..., 4], nan=0.0) + off[:, None]))
        y, n = r.final.copy(), b
        dH = max(float(dH), float(np.abs(model.energy(prm, y) - H0).max()))
        dec = int(np.ceil(np.log10(b)))
        decades[dec] = max(decades.get(dec, 0.0), dH)
    cas = np.abs(model.casimir(y) - 1.0)
    return decades, cas, y


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="1e5 steps instead of 1e7")
    ap.add_argument("--steps", type=int, default=None)
    args = ap.parse_args(argv)
    n_total = args.steps or (10**5 if args.quick else 10**7)
    ck = Checks("stress_longrun", args.quick, argv)
    from explorer import model
    lines = []
    for regime, mu in (("chaotic", 0.5), ("regular", 0.002)):
        prm = model.FIGURE4.with_(mu=mu)
        c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
        y0 = model.section_state(prm, c1 + r1 * np.array([-0.6, 0.2, 0.7, -0.2]),
                                 c2 + r2 * np.array([0.1, -0.3, 0.2, 0.5]), 2.0)
        for method in METHODS:
            t0 = time.perf_counter()
            dec, cas, _ = run(prm, y0, method, n_total)
            wall = time.perf_counter() - t0
            ks = [k for k in sorted(dec) if k >= 3]
            slope = float(np.polyfit(ks, np.log10([dec[k] for k in ks]), 1)[0])
            tag = f"{method} {regime} (mu = {mu}), {n_total:.0e} steps of dt {DT}"
            ck.check(f"{tag}: slope of the per-decade max |dH| vs steps (log-log)", slope <= 0.6, round(slope, 3),
                     "<= 0.6", per_decade={f"1e{k - 1}..1e{k}": dec[k] for k in sorted(dec)}, wall=wall)
            if 5 in dec and max(ks) > 5:
                ratio = dec[max(ks)] / dec[5]
                lim = 3.0 * 10 ** ((max(ks) - 5) / 2)
                ck.check(f"{tag}: max |dH| last decade / decade 1e4..1e5", ratio <= lim, round(ratio, 3), f"<= {lim:g}")
            ck.check(f"{tag}: Casimir error at the end (max over 4 orbits)", cas.max() <= 5e-12,
                     float(f"{cas.max():.3g}"), "<= 5e-12")
            lines.append(f"{tag}: max abs dH per decade " + ", ".join(f"{dec[k]:.2e}" for k in sorted(dec))
                         + f"; slope {slope:.2f}; Casimir {cas.max():.2e}; {wall:.0f} s")
    return ck.finish("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
