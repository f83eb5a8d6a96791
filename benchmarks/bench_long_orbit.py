#!/usr/bin/env python
"""One long orbit, side by side in one run (issue 11): whole-process time against heyoka's scalar
integrator, single-orbit throughput, the start-up breakdown, and peak memory against the number of
crossings.

Workload: ``model.FIGURE4`` with mu = 0.5, h = 2, the orbit started on the section phi = pi at
(p1, p2) = (0.5, 0), crossings with dphi/dt > 0, tolerance 1e-12 (explorer ``taylor``; heyoka
``taylor_adaptive`` with the terminal event of benchmarks/bench_w4.py).

A. Whole process, warm caches (best of --repeats fresh processes each):
   ``python -m explorer orbit --p1 0.5 --p2 0 --mu 0.5 --crossings 30000 --tol 1e-12 --json`` against
   a fresh Python process that imports heyoka, builds the integrator, follows the same orbit to its
   30000th crossing and prints the same JSON rows.  Both print to a pipe that is read and dropped.
   (explorer's start-up is numba's with its on-disk cache: the ahead-of-time native library of
   issue 11 was removed in issue 21, being built on numba's private internals.)
B. Single-orbit throughput in one process (after a warm-up): crossings per second of explorer's
   ``sections.crossings`` for one orbit and of heyoka's scalar integrator; the first 20 crossings
   of the two are compared (max |p1, p2 difference|) to show they follow the same orbit.
C. Start-up breakdown of a small ``explorer orbit`` (5 crossings), each step in fresh processes:
   bare interpreter, ``import numpy``, ``import numba``, the command's imports, the whole command.
D. Peak resident memory (ru_maxrss of the child) of ``explorer orbit --out`` against the crossings
   per orbit (1e4 ... 1e7; --quick: up to 1e5), and of a 2-orbit sweep scene with the same counts.

Writes benchmarks/results/long_orbit.json (quick: long_orbit_quick.json) and the LONGORBIT section
of benchmarks/RESULTS.md (full run only).

    python benchmarks/bench_long_orbit.py            # ~10 min on 2 cores (the 1e7 rows dominate)
    python benchmarks/bench_long_orbit.py --quick    # ~1 min
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _common as C
import numpy as np

SECTION = "LONGORBIT"
HERE = Path(__file__).resolve().parent
MU, H, P1, P2, TOL = 0.5, 2.0, 0.5, 0.0, 1e-12
#: crossings compared between explorer and heyoka (the orbit may be chaotic: later ones diverge)
AGREE_CROSSINGS = 20
ORBIT_ARGS = ["orbit", "--p1", str(P1), "--p2", str(P2), "--mu", str(MU), "--tol", str(TOL)]

HEYOKA_SCRIPT = r"""
import json, sys
sys.path.insert(0, sys.argv[1])
import numpy as np
from bench_w4 import HeyokaSections
P = np.array(json.loads(sys.argv[2])); y0 = np.array(json.loads(sys.argv[3])); K = int(sys.argv[4])
hs = HeyokaSections(P, float(sys.argv[5]), 1)
out = hs.run(y0[None, :], K)
rows = np.column_stack([out["ts"][0], out["ys"][0][:, :3]])[: out["count"][0]]
print(json.dumps({"crossings": rows.tolist(), "status": "done" if out["count"][0] == K else "stopped"}))
"""

TWO_ORBIT_SCENE = """name = "two_orbits"
[model]
mu = 0.5
[energy]
h = 2.0
[seeds]
kind = "points"
points = [[0.5, 0.0], [-0.3, 0.1]]
[integration]
method = "taylor"
tol = 1e-12
crossings = {K}
"""


def _run(cmd, env=None, cwd=None, timeout=7200):
    """(wall seconds, stdout, peak RSS in MB of the child) of one fresh process."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, env=env, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    out, err = p.communicate(timeout=timeout)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{err}")
    return wall, out, None


#: measures a command's peak RSS from a small fresh process: a child forked from this (large)
#: process would count this process's pages until its exec
_RSS_WRAPPER = r"""
import json, os, subprocess, sys, time
t0 = time.perf_counter()
p = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
_pid, status, usage = os.wait4(p.pid, 0)
print(json.dumps({"rss_kb": usage.ru_maxrss, "wall": time.perf_counter() - t0, "status": status,
                  "err": p.stderr.read().decode()[-2000:]}))
"""


def _peak_rss(cmd, cwd=None):
    """Peak resident memory (MB) and wall time of a command (os.wait4's rusage: ru_maxrss, kB on
    Linux), measured from a small wrapper process."""
    out = subprocess.run([sys.executable, "-c", _RSS_WRAPPER] + list(cmd), cwd=cwd, capture_output=True,
                         text=True, check=True)
    r = json.loads(out.stdout)
    if r["status"] != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed: {r['err']}")
    return r["rss_kb"] / 1024.0, r["wall"]


def whole_process(repeats, K):
    from explorer import model

    prm = model.FIGURE4.with_(mu=MU)
    y0 = model.section_state(prm, [P1], [P2], H)[0]
    ex_cmd = [sys.executable, "-m", "explorer"] + ORBIT_ARGS + ["--crossings", str(K), "--json"]
    hy_cmd = [sys.executable, "-c", HEYOKA_SCRIPT, str(HERE), json.dumps(prm.as_array().tolist()),
              json.dumps(y0.tolist()), str(K), str(TOL)]
    _run(ex_cmd)                            # warm the Numba cache
    rows = {}
    rows["explorer"] = min(_run(ex_cmd)[0] for _ in range(repeats))
    ex_rows = np.array(json.loads(_run(ex_cmd)[1])["crossings"])
    if C.have("heyoka"):
        rows["heyoka scalar"] = min(_run(hy_cmd)[0] for _ in range(repeats))
        hy_rows = np.array(json.loads(_run(hy_cmd)[1])["crossings"])
        n = min(AGREE_CROSSINGS, len(hy_rows), len(ex_rows))
        agree = float(np.max(np.abs(hy_rows[:n, 1:3] - ex_rows[:n, 1:3])))
    else:
        agree = None
    return rows, agree


def throughput(K):
    """Crossings per second of one orbit in one process (explorer; heyoka scalar)."""
    from explorer import model
    from explorer.analysis import sections

    prm = model.FIGURE4.with_(mu=MU)
    y0 = model.section_state(prm, [P1], [P2], H)
    sections.crossings(prm, states=y0, n_crossings=10, tol=TOL)
    best = C.best_of(lambda: sections.crossings(prm, states=y0, n_crossings=K, tol=TOL), repeats=3)[0]
    out = {"explorer": K / best}
    if C.have("heyoka"):
        sys.path.insert(0, str(HERE))
        from bench_w4 import HeyokaSections

        hs = HeyokaSections(prm.as_array(), TOL, 1)
        hs.run(y0, 10)
        t = C.best_of(lambda: hs.run(y0, K), repeats=3)[0]
        out["heyoka scalar"] = K / t
    return out


def startup(repeats):
    steps = [("python -c pass", [sys.executable, "-c", "pass"]),
             ("import numpy", [sys.executable, "-c", "import numpy"]),
             ("import numba", [sys.executable, "-c", "import numba"]),
             ("the command's imports (no numba)", [sys.executable, "-c",
                                                   "import explorer.app.cli, explorer.app.orbit, "
                                                   "explorer.analysis.sections"]),
             ("+ numba's Taylor lanes", [sys.executable, "-c",
                                         "import explorer.app.cli, explorer.app.orbit, "
                                         "explorer.analysis.sections, explorer.integrate.lanes"]),
             ("explorer orbit -K 5 (whole command)", [sys.executable, "-m", "explorer"] + ORBIT_ARGS
              + ["--crossings", "5"])]
    _run(steps[-1][1])
    return {name: min(_run(cmd)[0] for _ in range(repeats)) for name, cmd in steps}


def memory(counts):
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for K in counts:
            path = os.path.join(tmp, f"o{K}.h5")
            rss, wall = _peak_rss([sys.executable, "-m", "explorer"] + ORBIT_ARGS + ["--crossings", str(K),
                                                                                     "--out", path])
            size = os.path.getsize(path) / 1e6
            os.remove(path)
            scene = os.path.join(tmp, "two.toml")
            Path(scene).write_text(TWO_ORBIT_SCENE.format(K=K))
            srss, swall = _peak_rss([sys.executable, "-m", "explorer", "sweep", scene, "--out",
                                     os.path.join(tmp, f"s{K}.h5"), "--no-figure", "--quiet"])
            os.remove(os.path.join(tmp, f"s{K}.h5"))
            out.append({"crossings": K, "orbit_rss_mb": rss, "orbit_wall": wall, "store_mb": size,
                        "sweep_rss_mb": srss, "sweep_wall": swall})
            print(f"  K = {K:.0e}: orbit --out peak {rss:.0f} MB ({wall:.1f} s, store {size:.1f} MB); "
                  f"2-orbit sweep peak {srss:.0f} MB ({swall:.1f} s)", flush=True)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small counts, one repeat; RESULTS.md untouched")
    args = ap.parse_args(argv)
    started = C.now()
    t_start = time.perf_counter()
    load_start = C.loadavg()
    repeats = 1 if args.quick else 3
    K = 3000 if args.quick else 30000
    print("A. whole process ...", flush=True)
    procs, agree = whole_process(repeats, K)
    print("B. single-orbit throughput ...", flush=True)
    rates = throughput(K)
    print("C. start-up ...", flush=True)
    st = startup(repeats)
    print("D. peak memory ...", flush=True)
    counts = [10**4, 10**5] if args.quick else [10**4, 10**5, 10**6, 10**7]
    mem = memory(counts)
    seconds = time.perf_counter() - t_start
    doc = {"whole_process": procs, "agreement_first_200": agree, "throughput": rates, "startup": st,
           "memory": mem, "crossings": K, "machine": C.machine(), "versions": C.versions(),
           "load_end": C.loadavg()}
    C.write_json(C.OUT_DIR / ("long_orbit_quick.json" if args.quick else "long_orbit.json"), doc)
    lines, _ = C.header("One long orbit: whole process, throughput, start-up, memory", C.command_line(
        "bench_long_orbit.py", argv), started, seconds, load_start,
        extra=[f"Orbit: Figure 4 at mu = {MU}, h = {H}, start (p1, p2) = ({P1}, {P2}), tol {TOL:g}, "
               "crossings with dphi/dt > 0; explorer `taylor` (one orbit: the lane worker without the parallel "
               "layer), heyoka `taylor_adaptive` with the terminal event of bench_w4.py"])
    ex = procs["explorer"]
    lines += ["", f"### A. Whole process, {K} crossings, warm caches (best of {repeats})", "",
              "| run | wall (s) | ratio heyoka / explorer |", "|---|---:|---:|"]
    for name, t in procs.items():
        ratio = procs.get("heyoka scalar", float("nan")) / t
        lines.append(f"| {name} | {t:.3f} | {ratio:.2f} |")
    if agree is not None:
        lines += ["", f"First {AGREE_CROSSINGS} crossings of the two: max |difference in (p1, p2)| = {agree:.1e}."]
    lines += ["", f"### B. One orbit in one process, {K} crossings", "", "| integrator | crossings/s |",
              "|---|---:|"]
    lines += [f"| {name} | {r:,.0f} |" for name, r in rates.items()]
    lines += ["", "### C. Start-up of `explorer orbit -K 5` (fresh processes, warm cache, best of "
              f"{repeats})", "", "| step | wall (s) |", "|---|---:|"]
    lines += [f"| {name} | {t:.3f} |" for name, t in st.items()]
    lines += ["", "### D. Peak resident memory against crossings per orbit", "",
              "| crossings per orbit | `orbit --out` peak (MB) | wall (s) | store (MB) | 2-orbit sweep peak (MB) | "
              "wall (s) |", "|---:|---:|---:|---:|---:|---:|"]
    lines += [f"| {m['crossings']:.0e} | {m['orbit_rss_mb']:.0f} | {m['orbit_wall']:.1f} | {m['store_mb']:.1f} | "
              f"{m['sweep_rss_mb']:.0f} | {m['sweep_wall']:.1f} |" for m in mem]
    print("\n".join(lines))
    if ex and not args.quick:
        C.update_section(SECTION, lines)
        print(f"recorded in {C.RESULTS_MD}")


if __name__ == "__main__":
    main()
