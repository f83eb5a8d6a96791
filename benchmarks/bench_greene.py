#!/usr/bin/env python
"""Greene's residue criterion on the standard map: the critical k of the golden-mean curve.

:func:`explorer.greene` on ``StandardMap`` for the Fibonacci convergents up to q = 233 and up to
q = 987 (half-orbit method, docs/greene.md): the critical k, its uncertainty and its distance to
the published k_c = 0.971635406 (Greene 1979; MacKay 1983), the residues at the critical k
against MacKay's R* = 0.2500888, and the wall time (cold: compiling or loading the Numba cache
included; warm: a second run).

    python benchmarks/bench_greene.py           # a few seconds; writes the GREENE section of RESULTS.md
    python benchmarks/bench_greene.py --quick   # no RESULTS.md
"""
from __future__ import annotations

import argparse
import time

import _common as C

SECTION = "GREENE"
K_C = 0.971635406        # Greene 1979 (J. Math. Phys. 20, 1183), MacKay 1983 (Physica D 7, 283)
R_STAR = 0.2500888       # MacKay 1983


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="do not write RESULTS.md")
    args = ap.parse_args(argv)
    command = C.command_line("bench_greene.py", argv)
    started, load0, t_start = C.now(), C.loadavg(), time.perf_counter()
    t0 = time.perf_counter()
    import explorer as ex

    first = ex.greene(ex.StandardMap(0.9), "golden", qmax=233)
    cold = time.perf_counter() - t0
    rows = []
    for qmax in (233, 987):
        t0 = time.perf_counter()
        r = ex.greene(ex.StandardMap(0.9), "golden", qmax=qmax)
        rows.append((qmax, r, time.perf_counter() - t0))
    assert first.critical == rows[0][1].critical
    seconds = time.perf_counter() - t_start
    lines, _ = C.header("Greene's residue criterion: the golden-mean curve of the standard map", command, started,
                        seconds, load0, extra=[f"cold run (q <= 233, compiling or loading the Numba cache "
                                               f"included): {cold:.2f} s"])
    lines += ["", "| q max | critical k | uncertainty | critical k - 0.971635406 | last ratio | wall (s) |",
              "|---:|---:|---:|---:|---:|---:|"]
    for qmax, r, wall in rows:
        lines.append(f"| {qmax} | {r.critical:.12f} | {r.uncertainty:.1e} | {r.critical - K_C:+.1e} | "
                     f"{r.ratio:.4f} | {wall:.3f} |")
    r = rows[-1][1]
    lines += ["", "| p/q | k_n (R_n = R*) | residue at the critical k | minus R* = 0.2500888 |", "|---|---:|---:|---:|"]
    for c in r.convergents:
        lines.append(f"| {c['p']}/{c['q']} | {c['param_n']:.12f} | {c['residue_at_critical']:.9f} | "
                     f"{c['residue_at_critical'] - R_STAR:+.2e} |")
    return C.report(SECTION, lines, not args.quick)


if __name__ == "__main__":
    raise SystemExit(main())
