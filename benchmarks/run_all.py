#!/usr/bin/env python
"""Run every benchmark, one after the other, each in its own process (each also runs alone).

    python benchmarks/run_all.py             # full runs: update benchmarks/RESULTS.md (~35 min on 2 cores)
    python benchmarks/run_all.py --quick     # smoke test of every script (~3 min); RESULTS.md untouched
    python benchmarks/run_all.py --only work_precision longtime
    python benchmarks/run_all.py --skip w4 --stress    # also the stress scripts (benchmarks/stress/)

Benchmarks (script, RESULTS.md section):
  w4              bench_w4.py              W4 (explorer vs scipy vs heyoka at mu = 0.5)
  workflows       bench_workflows.py       WORKFLOWS (sweep, chaos map, continuation)
  work_precision  bench_work_precision.py  WORK-PRECISION (error and energy error vs wall time, 3 mu)
  longtime        bench_longtime.py        LONGTIME (energy / Casimir error over 1e6 time units)
  scaling         bench_scaling.py         SCALING (orbits, crossings, threads, sweep --jobs)
  startup         bench_startup.py         STARTUP (import, cold compile, warm start, CLI)
  long_orbit      bench_long_orbit.py      LONGORBIT (one long orbit vs heyoka scalar, start-up, memory)
  early_stop      bench_early_stop.py      EARLYSTOP (time saved by early classification)
  greene          bench_greene.py          GREENE (Greene's k_c of the standard map's golden curve)
  systems         bench_systems.py         SYSTEMS (a System's crossings vs heyoka: Hénon–Heiles sections)

With ``--quick`` it also runs, as a smoke test, the scripts a full run leaves to be run alone
(:data:`SMOKE`: each records its table itself, with ``--write`` or by hand): adaptive, chaos,
greene_section, periodic, roofline, store, manifolds and serve (the browser).

Each section of RESULTS.md carries its own command, date, machine and versions; a full run of
this script also writes the RUN-ALL section (what ran, exit status, wall time).  Benchmarks are
run sequentially: they time themselves and must not compete for the cores.  Exit status: the
number of failed scripts (0: all ran).
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import time

import _common as C

BENCHMARKS = {
    "w4": "bench_w4.py",
    "workflows": "bench_workflows.py",
    "work_precision": "bench_work_precision.py",
    "longtime": "bench_longtime.py",
    "scaling": "bench_scaling.py",
    "startup": "bench_startup.py",
    "long_orbit": "bench_long_orbit.py",
    "early_stop": "bench_early_stop.py",
    "greene": "bench_greene.py",
    "systems": "bench_systems.py",
}
#: the scripts that only ``--quick`` runs, with their arguments for a short run
SMOKE = {
    "adaptive": ["bench_adaptive.py", "--quick"],
    "chaos": ["bench_chaos.py", "--quick"],
    "greene_section": ["bench_greene_section.py", "--quick"],
    "periodic": ["bench_periodic.py", "--quick"],
    "roofline": ["bench_roofline.py", "--quick"],
    "store": ["bench_store.py", "--quick"],
    "manifolds": ["bench_manifolds.py"],
    "serve": ["bench_serve.py", "2"],
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="pass --quick to every script")
    ap.add_argument("--only", nargs="+", choices=sorted({**BENCHMARKS, **SMOKE}), help="run only these")
    ap.add_argument("--skip", nargs="+", choices=sorted({**BENCHMARKS, **SMOKE}), default=[],
                    help="do not run these")
    ap.add_argument("--stress", action="store_true", help="also run benchmarks/stress/run_stress.py")
    ap.add_argument("--timeout", type=float, default=3 * 3600, help="per script, seconds [3 h]")
    args = ap.parse_args(argv)
    alone = sorted(set(args.only or ()) & set(SMOKE)) if not args.quick else []
    if alone:
        ap.error(f"{', '.join(alone)} run(s) only with --quick here; a full run is the script's own "
                 f"(python benchmarks/{SMOKE[alone[0]][0]})")
    scripts = {n: [f, *(["--quick"] if args.quick else [])] for n, f in BENCHMARKS.items()}
    if args.quick:
        scripts.update(SMOKE)
    names = [n for n in (args.only or scripts) if n in scripts and n not in args.skip]
    started, load0, T0 = C.now(), C.loadavg(), time.perf_counter()
    report = []
    jobs = [(n, [sys.executable, str(C.HERE / scripts[n][0]), *scripts[n][1:]]) for n in names]
    if args.stress:
        jobs.append(("stress", [sys.executable, str(C.HERE / "stress" / "run_stress.py")]
                     + (["--quick"] if args.quick else [])))
    for name, cmd in jobs:
        print(f"==> {name}: {' '.join(cmd)}", flush=True)
        t0 = time.perf_counter()
        try:
            code = subprocess.run(cmd, cwd=C.ROOT, timeout=args.timeout).returncode
        except subprocess.TimeoutExpired:
            code = "timeout"
        wall = time.perf_counter() - t0
        report.append((name, " ".join(["python"] + [c.replace(str(C.ROOT) + "/", "") for c in cmd[1:]]), code, wall))
        print(f"<== {name}: exit {code}, {wall:.0f} s", flush=True)
    failed = [r for r in report if r[2] != 0]
    print("\nsummary:")
    for name, cmd, code, wall in report:
        print(f"  {name:<15} exit {code!s:<8} {wall:8.0f} s   {cmd}")
    if not args.quick:
        lines, _ = C.header("Run of benchmarks/run_all.py", C.command_line("run_all.py", argv), started,
                            time.perf_counter() - T0, load0)
        lines += ["", "| benchmark | command | exit status | wall (s) |", "|---|---|---:|---:|"]
        lines += [f"| {n} | `{c}` | {code} | {w:.0f} |" for n, c, code, w in report]
        C.update_section("RUN-ALL", lines)
    return len(failed)


if __name__ == "__main__":
    sys.exit(main())
