#!/usr/bin/env python
"""Invariant manifolds of the central saddle of Figure 4 (mu = 0.03, h = 2, phi = pi; issue 23).

- grow: the four branches (W^u +-, W^s +-) of the central hyperbolic fixed point near
  (-0.011, 0) to arclength 50 each (:func:`explorer.analysis.manifolds.manifolds`, defaults:
  start_tol 1e-12, max_gap 0.02, max_angle 0.2, max_gap_angle 2e-4); wall time, points and
  map evaluations per branch;
- flux (``--flux``): :func:`explorer.analysis.transport.flux_curve` at mu = 1e-3, 3e-3, 1e-2,
  3e-2, 0.1 (the Melnikov table of docs/manifolds.md), wall time.

Prints the numbers (and writes them as JSON with ``--json PATH``); RESULTS.md is left to the lead.

    python benchmarks/bench_manifolds.py            # ~10 s on 2 idle cores
    python benchmarks/bench_manifolds.py --flux     # + the flux curve (~30 s)
"""
from __future__ import annotations

import argparse
import json
import time

import _common as C

MU, H, ARCLENGTH = 0.03, 2.0, 50.0
FLUX_MUS = (1e-3, 3e-3, 1e-2, 3e-2, 0.1)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--flux", action="store_true", help="also time the flux curve")
    ap.add_argument("--json", default=None, help="write the numbers to this JSON file")
    args = ap.parse_args(argv)
    from explorer import model
    from explorer.analysis import fixedpoints, manifolds, transport

    prm = model.FIGURE4.with_(mu=MU)
    fp = fixedpoints.find_fixed_point(prm, H, (0.0, 0.0))
    manifolds.manifolds(prm, H, fp, arclength=0.5)        # compile / load the Numba caches outside the timing
    load0 = C.loadavg()
    t0, c0 = time.perf_counter(), time.process_time()
    branches = manifolds.manifolds(prm, H, fp, arclength=ARCLENGTH)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    out = {"started": C.now().isoformat(), "load": load0, "mu": MU, "h": H, "arclength": ARCLENGTH,
           "grow_seconds": wall, "grow_cpu_seconds": cpu,
           "branches": [{"kind": b.kind, "sign": b.sign, "points": len(b.points), "evaluations": b.evaluations,
                         "arclength": b.arclength, "status": b.status, "seconds": b.seconds} for b in branches]}
    print(f"grow 4 branches to arclength {ARCLENGTH:g} at mu = {MU:g}: {wall:.2f} s wall, {cpu:.2f} s CPU "
          f"(load {load0})")
    for b in out["branches"]:
        print(f"  {b['kind']:8s} {b['sign']:+d}: {b['points']:6d} points, {b['evaluations']:6d} evaluations, "
              f"{b['seconds']:.2f} s, {b['status']}")
    if args.flux:
        t0 = time.perf_counter()
        rows = transport.flux_curve(model.FIGURE4, H, FLUX_MUS)
        out["flux_seconds"] = time.perf_counter() - t0
        out["flux"] = [{k: r[k] for k in ("mu", "flux", "error", "melnikov", "ratio", "status")} for r in rows]
        print(f"flux curve at {len(FLUX_MUS)} values of mu: {out['flux_seconds']:.2f} s")
        for r in out["flux"]:
            print(f"  mu = {r['mu']:g}: flux {r['flux']!r} +- {r['error']!r}, ratio to Melnikov {r['ratio']!r}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
