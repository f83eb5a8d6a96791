#!/usr/bin/env python
"""Adaptive against exact chaos maps (ex.chaos_map, docs/chaos_map.md): MEGNO over T = 1000 on a
resolution^2 raster of Figure 4's mu = 0.03 panel (the megno_map preset: h = 2, Taylor tol 1e-12),
of mu = 1, and of the standard map at k = 0.97, each computed adaptively and exactly (every cell)
in one run, the adaptive map first: wall and CPU time of each, their ratio, the share of cells
computed, the share of cells of the same class, the chaotic fractions, and whether every computed
cell equals the exact map's bit for bit; then the mu = 0.03 panel adaptively at --large (1024^2;
exactly too with --exact-large).  CPU time is this process's (all threads): prefer it on a
shared machine; the load average is read before each map.

    python benchmarks/bench_adaptive.py --no-record     # the table; without --no-record: RESULTS.md's ADAPTIVE
    python benchmarks/bench_adaptive.py --resolution 256 --large 0 --png benchmarks/results/adaptive.png
    python benchmarks/bench_adaptive.py --quick         # 64^2, RESULTS.md untouched
"""
from __future__ import annotations

import argparse
import time

import _common as C
import numpy as np


def maps():
    import explorer as ex

    return [("Figure 4, mu = 0.03 (megno_map)", ex.SectionMap(ex.FIGURE4.with_(mu=0.03), 2.0, tol=1e-12)),
            ("Figure 4, mu = 1", ex.SectionMap(ex.FIGURE4.with_(mu=1.0), 2.0, tol=1e-12)),
            ("standard map, k = 0.97", ex.StandardMap(0.97))]


def timed(fn):
    w, c = time.perf_counter(), time.process_time()
    r = fn()
    return r, time.perf_counter() - w, time.process_time() - c


def compare(label, smap, n, tmax, exact=True):
    """One row: the adaptive map, then (``exact``) the exact one, and how they agree."""
    import explorer as ex

    load = C.loadavg()
    a, aw, ac = timed(lambda: ex.chaos_map(smap, n, tmax=tmax))
    row = dict(map=label, resolution=n, load=load, adaptive_wall=aw, adaptive_cpu=ac, computed=a.computed_fraction,
               adaptive_fraction=a.chaotic_fraction)
    e = None
    if exact:
        e, ew, ec = timed(lambda: ex.chaos_map(smap, n, tmax=tmax, exact=True))
        ok = e.allowed
        row.update(exact_wall=ew, exact_cpu=ec, same_class=float(np.mean(a.chaotic[ok] == e.chaotic[ok])),
                   exact_fraction=e.chaotic_fraction,
                   identical=bool(np.array_equal(a.values[a.computed], e.values[a.computed])))
    print(row, flush=True)
    return row, e, a


def _cells(r, key, fmt):
    return fmt.format(r[key]) if key in r else "-"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--resolution", type=int, default=512)
    ap.add_argument("--large", type=int, default=1024, help="the mu = 0.03 panel adaptively at this side too (0: not)")
    ap.add_argument("--exact-large", action="store_true", help="and exactly at --large")
    ap.add_argument("--tmax", type=float, default=1000.0)
    ap.add_argument("--quick", action="store_true", help="64^2, RESULTS.md untouched")
    ap.add_argument("--png", help="write the exact map, the computed cells and the class differences here")
    ap.add_argument("--no-record", action="store_true")
    args = ap.parse_args(argv)
    import explorer as ex

    n = 64 if args.quick else args.resolution
    started, t_start, load_start = C.now(), time.perf_counter(), C.loadavg()
    rows, images = [], []
    for label, smap in maps():
        ex.chaos_map(smap, 8, tmax=10.0, exact=True)     # kernels loaded: warm timings
        row, e, a = compare(label, smap, n, args.tmax)
        rows.append(row)
        images.append((label, e, a))
    if args.large and not args.quick:
        label, smap = maps()[0]
        rows.append(compare(label, smap, args.large, args.tmax, exact=args.exact_large)[0])
    seconds = time.perf_counter() - t_start
    lines, meta = C.header(f"Adaptive chaos maps against exact (MEGNO, T = {args.tmax:g})",
                           C.command_line("bench_adaptive.py", argv), started, seconds, load_start,
                           extra=["ex.chaos_map defaults: coarse lattice about 64 cells a side, tolerance e^2 "
                                  "(natural log of <Y>, clipped at the threshold 4), boundary growth, threads: all; "
                                  "warm kernels; each map adaptive first, then exact"])
    lines += ["", "| map | cells | load | adaptive wall (s) | adaptive CPU (s) | exact wall (s) | exact CPU (s) | "
              "CPU ratio | cells computed | same class | chaotic fraction exact | adaptive | computed cells "
              "bit-identical |", "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        ratio = f"{r['exact_cpu'] / r['adaptive_cpu']:.2f}" if "exact_cpu" in r else "-"
        same = "-" if "identical" not in r else ("yes" if r["identical"] else "NO")
        lines.append(f"| {r['map']} | {r['resolution']}^2 | {r['load']} | {r['adaptive_wall']:.1f} | "
                     f"{r['adaptive_cpu']:.1f} | {_cells(r, 'exact_wall', '{:.1f}')} | "
                     f"{_cells(r, 'exact_cpu', '{:.1f}')} | {ratio} | {r['computed']:.1%} | "
                     f"{_cells(r, 'same_class', '{:.2%}')} | {_cells(r, 'exact_fraction', '{:.4f}')} | "
                     f"{r['adaptive_fraction']:.4f} | {same} |")
    record = not (args.quick or args.no_record)
    written = [C.write_json(C.OUT_DIR / "adaptive.json", dict(meta, rows=rows, resolution=n, tmax=args.tmax,
                                                              load_end=C.loadavg()))] if record else []
    if args.png:
        written.append(_png(args.png, images))
    return C.report("ADAPTIVE", lines, record, written)


def _png(path, images):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(images), 3, figsize=(11, 3.6 * len(images)), squeeze=False)
    for row, (label, e, a) in zip(axes, images):
        ext = e.window
        kw = dict(origin="lower", extent=ext, aspect="auto", interpolation="nearest")
        row[0].imshow(np.log10(np.clip(e.values, 0.5, 100.0)), cmap="inferno_r", **kw)
        row[0].set_title(f"{label}: exact MEGNO", fontsize=8)
        row[1].imshow(np.where(e.allowed, a.computed, np.nan), cmap="gray_r", vmin=0, vmax=1, **kw)
        row[1].set_title(f"computed cells (black) {a.computed_fraction:.1%}", fontsize=8)
        diff = np.where(e.allowed, (a.chaotic != e.chaotic).astype(float), np.nan)
        row[2].imshow(diff, cmap="Reds", vmin=0, vmax=1, **kw)
        row[2].set_title(f"class differs (red) {np.nanmean(diff):.2%}", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return path


if __name__ == "__main__":
    raise SystemExit(main())
