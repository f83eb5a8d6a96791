#!/usr/bin/env python
"""A/B of two revisions on the W4 workload (Figure 4 at mu = 0.5, h = 2, 64 orbits x 2000 crossings,
as benchmarks/bench_w4.py) for the explorer's own rows: taylor (tol 1e-12), dop853 (tol 1e-12),
split8 (dt 0.05), and the chaos indicators of 64 orbits over T = 1000 (taylor and dop853, tol 1e-12).

Each revision runs in its own processes with its own Numba cache (warm: one untimed call
first); the revisions alternate, ``--rounds`` times, and the best time per row is kept, so a
load change on the machine hits both.  Used when a refactor must not slow W4 down.

``--cpu`` times each call by the process's CPU time with one Numba thread (NUMBA_NUM_THREADS=1):
on a virtual machine whose wall times move by 20-30 % between processes minutes apart (steal
time, a neighbour's load), this is the measurement that can resolve a few per cent.
``--repeat K`` times each row K times in each process (best kept): one call of a process can
take 30-40 % more CPU time than the next on such a machine, for either revision alike.
``--rows`` picks rows (split8 alone takes 35 s a call).  Every round is kept: the table gives the
best time of each side, the median ratio new/base over the rounds and its spread, and below it how
far apart the two sides' results are (the W4 taylor crossings per orbit, MEGNO; each side's first,
untimed call)::

    git worktree add /tmp/base <rev>
    python benchmarks/bench_ab.py /tmp/base .            # prints the table
    python benchmarks/bench_ab.py /tmp/base . --write    # and records it in RESULTS.md (section AB)
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
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
    if os.environ.get("EXPLORER_AB_SAVE"):
        np.save(os.path.join(os.environ["EXPLORER_AB_SAVE"], name + ".npy"), r.data)
y0 = model.section_state(prm, p1, p2, 2.0)
for m in ("taylor", "dop853"):
    if "megno_" + m not in wanted:
        continue
    lyapunov.indicators(prm, states=y0[:2], tmax=10.0, method=m, tol=1e-12)
    for _ in range(repeat):
        t0 = clock()
        res = lyapunov.indicators(prm, states=y0, tmax=1000.0, method=m, tol=1e-12)
        out["megno_" + m] = min(out.get("megno_" + m, (float("inf"),)), (clock() - t0, 64))
    if os.environ.get("EXPLORER_AB_SAVE"):
        np.save(os.path.join(os.environ["EXPLORER_AB_SAVE"], "megno_" + m + ".npy"), res.values["megno"])
print(json.dumps(out))
"""


#: the rows, in the order each process runs them
ROWS = ("taylor", "dop853", "split8", "megno_taylor", "megno_dop853")


def run(rev: Path, cache: str, cpu: bool = False, rows=ROWS, repeat: int = 1, env_extra=None) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, **(env_extra or {}))
    if cpu:
        env.update(NUMBA_NUM_THREADS="1", EXPLORER_AB_CPU="1")
    r = subprocess.run([sys.executable, "-c", SNIPPET, str(rev / "src"), ",".join(rows), str(repeat)],
                       capture_output=True, text=True, env=env)
    if r.returncode:
        raise SystemExit(f"the measured process of {rev} failed:\n{r.stderr}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def compare_saved(base_dir: str, new_dir: str) -> list:
    """Lines on the difference of the saved results: the W4 taylor crossings (per orbit, the largest
    difference over its crossings; the orbits within 1e-13; the first crossing beyond it) and MEGNO."""
    import numpy as np
    lines = []
    for name in ("taylor", "megno_taylor"):
        fb, fn = Path(base_dir) / f"{name}.npy", Path(new_dir) / f"{name}.npy"
        if not (fb.exists() and fn.exists()):
            continue
        a, b = np.load(fb), np.load(fn)
        if name == "taylor":
            d = np.abs(a - b)
            d = np.where(np.isnan(a) & np.isnan(b), 0.0, d).reshape(a.shape[0], a.shape[1], -1).max(axis=2)
            per_orbit = d.max(axis=1)
            close = per_orbit <= 1e-13
            first = [int(np.argmax(row > 1e-13)) for row in d[~close]]
            lines.append(f"W4 taylor crossings: {int(close.sum())} of {len(close)} orbits within 1e-13 over all "
                         f"{a.shape[1]} crossings (largest {per_orbit[close].max() if close.any() else 0:.1e}); "
                         f"the others first differ by > 1e-13 at crossing {sorted(first)}")
        else:
            lines.append(f"MEGNO, T = 1000: largest |difference| {np.max(np.abs(a - b)):.1e} "
                         f"(values {np.min(a):.3g}..{np.max(a):.3g})")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--write", action="store_true", help="record the table in RESULTS.md")
    ap.add_argument("--section", default="AB", help="with --write: the section of RESULTS.md (default AB)")
    ap.add_argument("--title", default="A/B of two revisions on W4 (explorer rows)", help="with --write: its title")
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
    saved = {k: tempfile.mkdtemp(prefix=f"ab-out-{k}-") for k in ("base", "new")}
    for key, rev in (("base", base), ("new", new)):   # compile both once (not timed); keep the results
        run(rev, caches[key], args.cpu, rows, env_extra={"EXPLORER_AB_SAVE": saved[key]})
    best: dict = {"base": {}, "new": {}}
    ratios: dict = {}
    for _ in range(args.rounds):
        got = {key: run(rev, caches[key], args.cpu, rows, args.repeat)
               for key, rev in (("base", base), ("new", new))}
        for key in got:
            for row, (sec, n) in got[key].items():
                if row not in best[key] or sec < best[key][row][0]:
                    best[key][row] = (sec, n)
        for row in got["base"]:
            ratios.setdefault(row, []).append(got["new"][row][0] / got["base"][row][0])
    lines = ["| row | base (s) | new (s) | new / base (best) | new / base (median of rounds) | spread "
             "(min..max) | crossings (base = new) |", "|---|---|---|---|---|---|---|"]
    for row in best["base"]:
        b, n = best["base"][row], best["new"][row]
        r = ratios[row]
        lines.append(f"| {row} | {b[0]:.3f} | {n[0]:.3f} | {n[0] / b[0]:.3f} | {statistics.median(r):.3f} | "
                     f"{min(r):.3f}..{max(r):.3f} | {b[1]} = {n[1]} |")
    lines += [""] + [f"- {line}" for line in compare_saved(saved["base"], saved["new"])]
    print("\n".join(lines))
    if args.write:
        rev = lambda p: subprocess.run(["git", "-C", str(p), "rev-parse", "--short", "HEAD"],  # noqa: E731
                                       capture_output=True, text=True).stdout.strip() or p.name
        seconds = (C.now() - started).total_seconds()
        head, _ = C.header(args.title, C.command_line("bench_ab.py", (
                               ["<worktree of base>", "."] + ["--rounds", str(args.rounds)]
                               + (["--cpu"] if args.cpu else [])
                               + (["--repeat", str(args.repeat)] if args.repeat > 1 else [])
                               + (["--rows", ",".join(rows)] if rows != ROWS else []))), started,
            seconds, load0, extra=[f"base {rev(base)}, new {rev(new)}; {args.rounds} alternating rounds"
                                   + (f" x {args.repeat} calls" if args.repeat > 1 else "") + ", warm caches"
                                   + ("; CPU time of one Numba thread" if args.cpu else "; wall time")],
            numba_threads=1 if args.cpu else None)   # (--cpu: the timed processes run one thread)
        C.update_section(args.section, head + [""] + lines)


if __name__ == "__main__":
    main()
