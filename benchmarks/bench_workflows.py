"""Wall times of the user-level workflows, recorded in benchmarks/RESULTS.md.

- the default sweep (`python -m explorer sweep`, Figure 4), first run (kernels compiled, store
  empty) and second run with nothing changed;
- a chaos map of 10,000 orbits on one panel (MEGNO, T = 1000, Taylor tol 1e-12);
- the fixed-point continuation over 0 <= mu <= 4 (step 0.1, bifurcation located by bisection).

Usage: python benchmarks/bench_workflows.py [--quick]
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
BEGIN, END = "<!-- BEGIN WORKFLOWS -->", "<!-- END WORKFLOWS -->"


def run(cmd, cwd):
    t0 = time.perf_counter()
    out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=True)
    return time.perf_counter() - t0, out.stdout


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    from explorer import model
    from explorer.analysis import fixedpoints, lyapunov

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        # warm the cache for the sweep's kernels in a throw-away run of another scene
        scene = Path(tmp) / "warm.toml"
        scene.write_text('name = "warm"\n[seeds]\nn = 4\n[integration]\ncrossings = 2\n'
                         '[compute]\nseparatrices = true\n')
        run([sys.executable, "-m", "explorer", "sweep", str(scene), "--quiet"], tmp)
        if not args.quick:
            t1, out1 = run([sys.executable, "-m", "explorer", "sweep", "--quiet"], tmp)
            t2, out2 = run([sys.executable, "-m", "explorer", "sweep", "--quiet"], tmp)
            m = re.search(r"orbits (\d+), crossings (\d+)", out1)
            rows.append(("default sweep (figure4), first run", t1,
                         f"{m.group(1)} orbits, {m.group(2)} crossings, separatrices of 3 panels; target < 60 s"))
            rows.append(("default sweep, second run (nothing changed)", t2, "target < 3 s"))

    n = 1000 if args.quick else 10000
    prm = model.FIGURE4.with_(mu=0.03)
    c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
    side = int(np.ceil(np.sqrt(n * 4 / np.pi) / 0.98)) + 2
    u, v = np.meshgrid(np.linspace(-0.98, 0.98, side), np.linspace(-0.98, 0.98, side))
    inside = u ** 2 + v ** 2 < 0.98 ** 2
    p1, p2 = (c1 + r1 * u[inside])[:n], (c2 + r2 * v[inside])[:n]
    y0 = model.section_state(prm, p1, p2, 2.0)
    lyapunov.indicators(prm, states=y0[:2], tmax=10.0)  # compile
    t0 = time.perf_counter()
    ind = lyapunov.indicators(prm, states=y0, tmax=1000.0, method="taylor", tol=1e-12)
    t_map = time.perf_counter() - t0
    frac = float(np.mean(ind.megno > 4.0))
    rows.append((f"chaos map: {len(y0)} orbits, mu = 0.03, T = 1000 (MEGNO, mLCE, FLI)", t_map,
                 f"chaotic fraction {frac:.3f}; 2 threads"))

    fixedpoints.continue_branch(model.FIGURE4, 2.0, "mu", 0.0, 0.2, 0.1)  # compile
    t0 = time.perf_counter()
    br = fixedpoints.continue_branch(model.FIGURE4, 2.0, "mu", 0.0, 4.0, 0.1)
    t_cont = time.perf_counter() - t0
    rows.append(("fixed-point continuation, 0 <= mu <= 4, step 0.1", t_cont,
                 f"{len(br.values)} points, stability change at mu = {br.bifurcations[0]['value']:.8f}"))

    lines = [BEGIN, "## Workflows", "",
             f"- Date: {time.strftime('%Y-%m-%dT%H:%M:%S%z')}",
             f"- Command (from the repository root): `python benchmarks/bench_workflows.py{' --quick' if args.quick else ''}`",
             f"- Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs; Python {platform.python_version()}",
             "",
             "| workflow | wall (s) | notes |", "|---|---:|---|"]
    lines += [f"| {a} | {b:.2f} | {c} |" for a, b, c in rows]
    lines += ["", END]
    block = "\n".join(lines)
    print(block)
    res = HERE / "RESULTS.md"
    text = res.read_text() if res.exists() else "# Benchmark results\n"
    if BEGIN in text:
        text = text[:text.index(BEGIN)] + block + text[text.index(END) + len(END):]
    else:
        text = text.rstrip() + "\n\n" + block + "\n"
    if not args.quick:
        res.write_text(text)
        (HERE / "results_workflows.json").write_text(json.dumps(
            [{"workflow": a, "wall_s": b, "notes": c} for a, b, c in rows], indent=1))


if __name__ == "__main__":
    main()
