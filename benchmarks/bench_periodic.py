#!/usr/bin/env python
"""Search of all periodic orbits of periods K = 1..8 of the section map at Figure 4's scene
(mu = 0.03, h = 2, phi = pi), :func:`explorer.analysis.periodic.search_periodic_orbits` with its
defaults (grid 12, 96 start points per symmetry line, at most 60 Newton starts per K).

- serial: one process, one Numba thread, K = 1..8 in turn (wall per K);
- parallel: 2 joblib processes (loky) over K, one Numba thread each, K in decreasing order
  (the long searches first); the orbits found must be the same as the serial run's.

Prints a table (per K: orbits, elliptic, symmetric, wall) and, on a full run, writes the
PERIODIC section of benchmarks/RESULTS.md.

    python benchmarks/bench_periodic.py            # ~1 min on 2 cores
    python benchmarks/bench_periodic.py --quick    # K = 1..4, no RESULTS.md
"""
from __future__ import annotations

import argparse
import sys
import time

import _common as C

SECTION = "PERIODIC"
MU, H = 0.03, 2.0


def search(K):
    """(K, orbits as dicts, wall) of one search with one Numba thread (runs in a worker)."""
    from explorer import model
    from explorer._jit import set_num_threads
    from explorer.analysis import periodic

    set_num_threads(1)
    t0 = time.perf_counter()
    orbits = periodic.search_periodic_orbits(model.FIGURE4.with_(mu=MU), H, K, threads=1)
    return K, [o.as_dict() for o in orbits], time.perf_counter() - t0


def same_sets(a, b, tol=1e-6):
    import numpy as np

    def match(o, others):
        return any(np.min(np.linalg.norm(np.array(o["points"])[:, None] - np.array(p["points"])[None], axis=2)) < tol
                   for p in others)

    return len(a) == len(b) and all(match(o, b) for o in a)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="K = 1..4, no RESULTS.md")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes [2]")
    args = ap.parse_args(argv)
    from joblib import Parallel, delayed

    periods = list(range(1, 5 if args.quick else 9))
    command = C.command_line("bench_periodic.py", argv)
    started, load0, t_start = C.now(), C.loadavg(), time.perf_counter()
    search(1)   # compile / load the Numba caches outside the timings
    serial = {}
    t0 = time.perf_counter()
    for K in periods:
        k, orbits, wall = search(K)
        serial[k] = (orbits, wall)
        print(f"serial K = {K}: {len(orbits)} orbits in {wall:.2f} s", file=sys.stderr)
    serial_wall = time.perf_counter() - t0
    with Parallel(n_jobs=args.jobs, backend="loky") as par:
        par(delayed(search)(1) for _ in range(args.jobs))   # warm the workers
        t0 = time.perf_counter()
        res = par(delayed(search)(K) for K in sorted(periods, reverse=True))
        parallel_wall = time.perf_counter() - t0
    parallel = {k: (orbits, wall) for k, orbits, wall in res}
    agree = all(same_sets(serial[K][0], parallel[K][0]) for K in periods)
    seconds = time.perf_counter() - t_start
    lines, _ = C.header("Periodic orbits: search of K = 1..8 at Figure 4's scene", command, started, seconds, load0,
                        extra=[f"mu = {MU}, h = {H}, phi = pi; search_periodic_orbits defaults (grid 12, 96 points "
                               "per symmetry line, <= 60 Newton starts per K, 50 time units per return, Taylor "
                               "tol 1e-15); one Numba thread per process; warm caches.",
                               f"serial (1 process) and parallel ({args.jobs} joblib loky processes over K, "
                               f"largest K first) found the same orbits: {agree}."])
    lines += ["", "| K | orbits (minimal period K) | elliptic | hyperbolic | symmetric | serial wall (s) |",
              "|---:|---:|---:|---:|---:|---:|"]
    for K in periods:
        orbits, wall = serial[K]
        ell = sum(o["kind"] == "elliptic" for o in orbits)
        hyp = sum(o["kind"] == "hyperbolic" for o in orbits)
        sym = sum(o["symmetric"] for o in orbits)
        lines.append(f"| {K} | {len(orbits)} | {ell} | {hyp} | {sym} | {wall:.2f} |")
    total = sum(len(serial[K][0]) for K in periods)
    lines += ["", f"All {len(periods)} periods: {total} orbits; serial {serial_wall:.2f} s, "
              f"{args.jobs} processes {parallel_wall:.2f} s (speed-up {serial_wall / parallel_wall:.2f})."]
    print("\n".join(lines))
    if not args.quick:
        C.update_section(SECTION, lines)
        print(f"updated {C.RESULTS_MD}")
    return 0 if agree else 1


if __name__ == "__main__":
    sys.exit(main())
