"""Chaos benchmark (issue 10): the explorer's tangent SIMD lanes on chaos maps.

Rows: a 20 x 20 raster map (the 316 cells inside the allowed region, mu = 1, h = 2, T = 1000, tol 1e-12,
2 threads) and MEGNO orbits per second at mu = 0.03 and mu = 1.  The heyoka comparator
(taylor_adaptive_batch with the variational equations in 2 processes) is not written yet:
this script says so instead of inventing a ratio.

    python benchmarks/bench_chaos.py [--append]   # --append: add the rows to benchmarks/RESULTS.md
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

from explorer import model
from explorer.analysis import lyapunov
from explorer.analysis.sweep import map_seeds


def run_map(mu, resolution, T=1000.0, tol=1e-12, threads=2, repeats=3):
    prm = model.FIGURE4.with_(mu=mu)
    p1, p2, _grid = map_seeds(prm, 2.0, np.pi, resolution)
    y0 = model.section_state(prm, p1, p2, 2.0)
    lyapunov.indicators(prm, y0[:8], 1.0, tol=tol, threads=threads)      # compile / load the cache
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        r = lyapunov.indicators(prm, y0, T, tol=tol, threads=threads)
        best = min(best, time.perf_counter() - t0)
    return len(y0), best, float(np.mean(r.megno > 4.0))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--append", action="store_true")
    args = ap.parse_args(argv)
    rows = []
    n, t, f = run_map(1.0, 20)
    rows.append(f"| 20x20 raster map (cells inside the allowed region), mu = 1, T = 1000, 2 threads | {n} orbits | {t:.2f} s | "
                f"chaotic {f:.3f} |")
    for mu in (0.03, 1.0):
        n, t, f = run_map(mu, 32)
        rows.append(f"| MEGNO, mu = {mu:g}, T = 1000, 2 threads | {n / t:.0f} orbits/s | {t:.2f} s for {n} | "
                    f"chaotic {f:.3f} |")
    print("heyoka comparator: not implemented in this script yet (no ratio reported)", file=sys.stderr)
    text = "\n".join(rows)
    print(text)
    if args.append:
        with open(Path(__file__).with_name("RESULTS.md"), "a") as fh:
            fh.write("\n## Chaos maps on tangent SIMD lanes (issue 10)\n\n`python benchmarks/bench_chaos.py --append`"
                     f" ({time.strftime('%Y-%m-%d')}, 2 cores shared with other jobs)\n\n"
                     "| run | rate | time | result |\n|---|---|---|---|\n" + text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
