#!/usr/bin/env python
"""A/B of the lane groups (issue 24): the same workloads with G = 1, 2 groups of LANES lanes
per worker (``EXPLORER_LANE_GROUPS``, read at each call), alternated in one process so that a
load change on a shared machine hits every G alike; prints the median wall time of each G over
the rounds and its ratio to G = 1.  The results are bit for bit the same for every G (checked
here on every row, and by tests/integrate/test_lanes.py, test_tangent_lanes.py).

Rows: W4 (mu = 0.5, h = 2, 64 orbits x 2000 crossings, taylor tol 1e-12, 2 threads) and the
400-orbit chaos map of benchmarks/bench_chaos.py (mu = 1, T = 1000, MEGNO, tol 1e-12, 2 threads).

    python benchmarks/bench_lane_groups.py              # 5 rounds, G = 1 2
    python benchmarks/bench_lane_groups.py --rounds 3 --groups 1 2 --quick
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402
from bench_chaos import polar_seeds  # noqa: E402


def workloads(quick):
    """name -> (callable returning the arrays whose bits must agree across G)."""
    from explorer import model
    from explorer.analysis import lyapunov, sections

    prm4 = model.FIGURE4.with_(mu=0.5)
    c1, c2, r1, r2 = model.allowed_ellipse(prm4, 2.0)
    p1 = c1 + r1 * np.linspace(-0.95, 0.95, 64)
    p2 = np.zeros(64)
    K = 200 if quick else 2000
    prm1 = model.FIGURE4.with_(mu=1.0)
    Y1 = polar_seeds(prm1)
    T = 100.0 if quick else 1000.0

    def w4():
        r = sections.crossings(prm4, 2.0, np.column_stack([p1, p2]), n_crossings=K, method="taylor", tol=1e-12)
        return (r.data, r.count, r.final)

    def chaos():
        r = lyapunov.indicators(prm1, states=Y1, tmax=T, tol=1e-12, threads=2)
        return (r.megno, r.mlce, r.fli)

    return {f"W4 taylor 64 x {K}": w4, f"chaos map 400 orbits T = {T:g}": chaos}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--groups", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--quick", action="store_true", help="W4 with 200 crossings, the map with T = 100")
    ap.add_argument("--write", action="store_true", help="record the tables in RESULTS.md (section LANEGROUPS)")
    args = ap.parse_args(argv)
    started, load0 = C.now(), C.loadavg()
    emit = C.Emitter()
    lines = emit.lines
    from explorer._jit import set_num_threads
    set_num_threads(2)
    rows = workloads(args.quick)
    env = os.environ.get("EXPLORER_LANE_GROUPS")
    times = {(name, g): [] for name in rows for g in args.groups}
    ref = {}
    for name, fn in rows.items():             # load or compile every G first (untimed)
        for g in args.groups:
            os.environ["EXPLORER_LANE_GROUPS"] = str(g)
            out = fn()
            bits = [np.ascontiguousarray(a).view(np.uint8) for a in out]
            if name in ref:
                assert all(np.array_equal(a, b) for a, b in zip(ref[name], bits)), f"{name}: G = {g} differs"
            ref[name] = bits
    for r in range(args.rounds):
        for name, fn in rows.items():
            order = args.groups if r % 2 == 0 else args.groups[::-1]
            for g in order:
                os.environ["EXPLORER_LANE_GROUPS"] = str(g)
                t0 = time.perf_counter()
                fn()
                times[(name, g)].append(time.perf_counter() - t0)
    if env is None:       # the machine line names the G of the environment, not the last one tried
        os.environ.pop("EXPLORER_LANE_GROUPS", None)
    else:
        os.environ["EXPLORER_LANE_GROUPS"] = env
    emit(f"# lane groups A/B on {C.machine_line(C.machine())}; load average at the end {os.getloadavg()}")
    emit(f"# {args.rounds} rounds, G alternated; median (min-max) seconds, ratio of medians to G = {args.groups[0]}")
    emit("| workload | " + " | ".join(f"G = {g}" for g in args.groups) + " | "
          + " | ".join(f"G{g}/G{args.groups[0]}" for g in args.groups[1:]) + " |")
    emit("|---|" + "---:|" * (2 * len(args.groups) - 1))
    for name in rows:
        med = {g: float(np.median(times[(name, g)])) for g in args.groups}
        cells = [f"{med[g]:.3f} ({min(times[(name, g)]):.3f}-{max(times[(name, g)]):.3f})" for g in args.groups]
        ratios = [f"{med[g] / med[args.groups[0]]:.3f}" for g in args.groups[1:]]
        emit(f"| {name} | " + " | ".join(cells) + " | " + " | ".join(ratios) + " |")
    if args.write:
        head, _ = C.header("Lane groups A/B (issue 24)", C.command_line("bench_lane_groups.py", argv), started,
                           (C.now() - started).total_seconds(), load0)
        C.update_section("LANEGROUPS", head + [""] + [x for x in lines if not x.startswith("# ")])
    return 0


if __name__ == "__main__":
    sys.exit(main())
