#!/usr/bin/env python
"""Cost of committing a panel against the number of panels already stored (store format 2).

Commits ``--panels`` small panels (``--orbits`` orbits x ``--crossings`` crossings each, random
numbers: the store does not care) one after the other into a fresh store in a temporary
directory, and times each :func:`explorer.io.store.commit_panel` (wall time, fsyncs included).
Prints a table: for a few numbers of panels already stored, the median commit time of the commits
around that number, the bytes the commit wrote (the files it created or changed: the new panel's
file and the store file), the size of the store file (root attributes and one external link per
panel), and what format 1 copied at that commit (the whole store so far).  The commit time should
be flat against the panels stored; format 1 grew linearly.

    python benchmarks/bench_store.py                 # 200 panels of 20 x 100 rows, ~5 s
    python benchmarks/bench_store.py --quick         # 30 panels
    python benchmarks/bench_store.py --json out.json # also the per-commit numbers as JSON

RESULTS.md is not touched.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time

import numpy as np

from explorer.io import store

#: the numbers of panels already stored at which the table reports (those below --panels)
REPORT_AT = (0, 1, 10, 50, 100, 150, 199)
#: commits around each reported number whose times are pooled (median)
WINDOW = 10
COLUMNS = 5


def _panel(rng, n_orbits: int, n_crossings: int) -> tuple[dict, dict]:
    count = np.full(n_orbits, n_crossings, np.int64)
    arrays = {"seeds": rng.normal(size=(n_orbits, 2)), "y0": rng.normal(size=(n_orbits, 5)), "count": count,
              "status": np.zeros(n_orbits, np.int8), "final": rng.normal(size=(n_orbits, 5)),
              "info": rng.normal(size=(n_orbits, 3)),
              "offsets": np.arange(n_orbits + 1, dtype=np.int64) * n_crossings,
              "crossings": rng.normal(size=(n_orbits * n_crossings, COLUMNS))}
    attrs = {"label": "bench", "settings": {"orbits": n_orbits, "crossings": n_crossings}}
    return arrays, attrs


def _store_bytes(path: str) -> tuple[int, int]:
    """(bytes of the store file, bytes of its whole panel folder)."""
    folder = store.panels_dir(path)
    return os.path.getsize(path), sum(os.path.getsize(os.path.join(folder, n)) for n in os.listdir(folder))


def run(n_panels: int, n_orbits: int, n_crossings: int) -> list[dict]:
    """One row per commit: panels already stored, seconds, bytes written, store-file bytes, bytes of
    the whole store before the commit (what format 1 copied)."""
    rng = np.random.default_rng(2026)
    file_attrs = {"scene_name": "bench", "scene": "name = 'bench'\n", "provenance": {"bench": True}}
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-store-") as tmp:
        path = os.path.join(tmp, "s.h5")
        for i in range(n_panels):
            arrays, attrs = _panel(rng, n_orbits, n_crossings)
            stored = sum(_store_bytes(path)) if i else 0    # format 1 copied all of it
            t0 = time.perf_counter()
            store.commit_panel(path, i, arrays, attrs, file_attrs)
            seconds = time.perf_counter() - t0
            # the commit wrote the new panel's file and the store file (tests/io/test_store_scale.py checks
            # that nothing else changes)
            folder = store.panels_dir(path)
            panel = [n for n in os.listdir(folder) if n.startswith(f"{i:03d}-")]
            top = os.path.getsize(path)
            rows.append({"stored": i, "seconds": seconds, "written": top + os.path.getsize(os.path.join(folder, panel[0])),
                         "store_file": top, "format1_copied": stored})
        assert sorted(store.read_store(path).panels) == list(range(n_panels))
    return rows


def table(rows: list[dict]) -> list[str]:
    lines = ["| panels stored | commit (ms, median) | bytes written | store file (bytes) | format 1 copied (MB) |",
             "|---:|---:|---:|---:|---:|"]
    for k in REPORT_AT:
        if k >= len(rows):
            break
        pool = rows[max(1, k - WINDOW // 2): k + WINDOW // 2 + 1] if k else rows[:1]
        ms = 1e3 * statistics.median(r["seconds"] for r in pool)
        r = rows[k]
        lines.append(f"| {k} | {ms:.1f} | {r['written']:,} | {r['store_file']:,} | {r['format1_copied'] / 1e6:.2f} |")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--panels", type=int, default=200)
    ap.add_argument("--orbits", type=int, default=20)
    ap.add_argument("--crossings", type=int, default=100)
    ap.add_argument("--quick", action="store_true", help="30 panels")
    ap.add_argument("--json", help="also write the per-commit numbers here")
    a = ap.parse_args(argv)
    n = 30 if a.quick else a.panels
    t0 = time.perf_counter()
    rows = run(n, a.orbits, a.crossings)
    print(f"store format {store.FORMAT_VERSION}: {n} panels of {a.orbits} orbits x {a.crossings} crossings "
          f"({a.orbits * a.crossings * 8 * COLUMNS / 1e3:.0f} kB of rows each), {time.perf_counter() - t0:.1f} s")
    print(f"load average at the end {[round(v, 2) for v in os.getloadavg()]} (fsync times vary with other jobs)")
    print("\n".join(table(rows)))
    first, last = rows[:WINDOW], rows[-WINDOW:]
    ratio = statistics.median(r["seconds"] for r in last) / statistics.median(r["seconds"] for r in first)
    print(f"median commit time, last {WINDOW} / first {WINDOW} commits: {ratio:.2f}")
    if a.json:
        import json

        with open(a.json, "w") as f:
            json.dump({"panels": n, "orbits": a.orbits, "crossings": a.crossings, "commits": rows}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
