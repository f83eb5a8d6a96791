#!/usr/bin/env python
"""A/B of two revisions on the W4 workload (Figure 4 at mu = 0.5, h = 2, 64 orbits x 2000 crossings,
as benchmarks/bench_w4.py) for the explorer's own rows: taylor (tol 1e-12), dop853 (tol 1e-12),
split8 (dt 0.05), and the chaos indicators of 64 orbits over T = 1000 (taylor and dop853, tol 1e-12).

Each revision runs in its own processes with its own Numba cache (warm: one untimed call
first); the revisions alternate, ``--rounds`` times, and the best time per row is kept, so a
load change on the machine hits both.  Used when a refactor must not slow W4 down (issue 13:
at most 5 %).

``--cpu`` times each call by the process's CPU time with one Numba thread (NUMBA_NUM_THREADS=1):
on a virtual machine whose wall times move by 20-30 % between processes minutes apart (steal
time, a neighbour's load), this is the measurement that can resolve a few per cent.
``--repeat K`` times each row K times in each process (best kept): one call of a process can
take 30-40 % more CPU time than the next on such a machine, for either revision alike.
``--rows`` picks rows (split8 alone takes 35 s a call).

    git worktree add /tmp/base <rev>
    python benchmarks/bench_ab.py /tmp/base .            # prints the table
    python benchmarks/bench_ab.py /tmp/base . --write    # and records it in RESULTS.md
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import _common as C

SNIPPET = r"""
import json, os, sys, time
import numpy as np
clock = time.process_time if os.environ.get("EXPLORER_AB_CPU") else time.perf_counter
src = sys.argv[1]
sys.path.insert(0, src)
import explorer
assert explorer.__file__.startswith(src), explorer.__file__
from explorer import model
from explorer.analysis import lyapunov, sections
prm = model.FIGURE4.with_(mu=0.5)
c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
p1 = c1 + r1 * np.linspace(-0.95, 0.95, 64)
p2 = np.zeros(64)
rows = {"taylor": dict(method="taylor", tol=1e-12), "dop853": dict(method="dop853", tol=1e-12),
        "split8": dict(method="split8", dt=0.05)}
wanted, repeat = sys.argv[2].split(","), int(sys.argv[3])
out = {}
for name, kw in rows.items():
    if name not in wanted:
        continue
    sections.crossings(prm, 2.0, np.column_stack([p1[:2], p2[:2]]), n_crossings=5, **kw)   # load the compiled code
    for _ in range(repeat):
        t0 = clock()
        r = sections.crossings(prm, 2.0, np.column_stack([p1, p2]), n_crossings=2000, **kw)
        out[name] = min(out.get(name, (float("inf"),)), (clock() - t0, int(r.count.sum())))
y0 = model.section_state(prm, p1, p2, 2.0)
for m in ("taylor", "dop853"):
    if "megno_" + m not in wanted:
        continue
    lyapunov.indicators(prm, y0[:2], tmax=10.0, method=m, tol=1e-12)
    for _ in range(repeat):
        t0 = clock()
        lyapunov.indicators(prm, y0, tmax=1000.0, method=m, tol=1e-12)
        out["megno_" + m] = min(out.get("megno_" + m, (float("inf"),)), (clock() - t0, 64))
print(json.dumps(out))
"""


#: the rows, in the order each process runs them
ROWS = ("taylor", "dop853", "split8", "megno_taylor", "megno_dop853")


def run(rev: Path, cache: str, cpu: bool = False, rows=ROWS, repeat: int = 1) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    if cpu:
        env.update(NUMBA_NUM_THREADS="1", EXPLORER_AB_CPU="1")
    r = subprocess.run([sys.executable, "-c", SNIPPET, str(rev / "src"), ",".join(rows), str(repeat)],
                       capture_output=True, text=True, env=env, check=True)
    return json.loads(r.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--write", action="store_true", help="record the table in RESULTS.md")
    ap.add_argument("--cpu", action="store_true", help="CPU time of one Numba thread instead of wall time")
    ap.add_argument("--repeat", type=int, default=1, help="timed calls of each row per process (best kept)")
    ap.add_argument("--rows", default=",".join(ROWS), help=f"comma-separated rows (default: all, {','.join(ROWS)})")
    args = ap.parse_args(argv)
    rows = tuple(r for r in args.rows.split(",") if r)
    if not rows or set(rows) - set(ROWS) or args.repeat < 1 or args.rounds < 1:
        ap.error(f"--rows must name some of {', '.join(ROWS)}; --repeat and --rounds at least 1")
    base, new = args.base.resolve(), args.new.resolve()
    started, load0 = C.now(), C.loadavg()
    caches = {k: tempfile.mkdtemp(prefix=f"nc-ab-{k}-") for k in ("base", "new")}
    run(base, caches["base"], args.cpu, rows)  # compile both once (not timed)
    run(new, caches["new"], args.cpu, rows)
    best: dict = {"base": {}, "new": {}}
    for _ in range(args.rounds):
        for key, rev in (("base", base), ("new", new)):
            for row, (sec, n) in run(rev, caches[key], args.cpu, rows, args.repeat).items():
                if row not in best[key] or sec < best[key][row][0]:
                    best[key][row] = (sec, n)
    lines = ["| row | base (s) | new (s) | new / base | crossings (base = new) |", "|---|---|---|---|---|"]
    for row in best["base"]:
        b, n = best["base"][row], best["new"][row]
        lines.append(f"| {row} | {b[0]:.3f} | {n[0]:.3f} | {n[0] / b[0]:.3f} | {b[1]} = {n[1]} |")
    print("\n".join(lines))
    if args.write:
        rev = lambda p: subprocess.run(["git", "-C", str(p), "rev-parse", "--short", "HEAD"],  # noqa: E731
                                       capture_output=True, text=True).stdout.strip() or p.name
        seconds = (C.now() - started).total_seconds()
        head, _ = C.header("A/B of two revisions on W4 (explorer rows)", C.command_line("bench_ab.py", [
            "<worktree of base>", ".", "--rounds", str(args.rounds)] + (["--cpu"] if args.cpu else [])
            + (["--repeat", str(args.repeat)] if args.repeat > 1 else [])
            + (["--rows", ",".join(rows)] if rows != ROWS else [])), started,
            seconds, load0, extra=[f"base {rev(base)}, new {rev(new)}; best of {args.rounds} alternating rounds"
                                   + (f" x {args.repeat} calls" if args.repeat > 1 else "") + ", warm caches"
                                   + ("; CPU time of one Numba thread" if args.cpu else "; wall time")],
            numba_threads=1 if args.cpu else None)   # (--cpu: the timed processes run one thread)
        C.update_section("AB", head + [""] + lines)


if __name__ == "__main__":
    main()
