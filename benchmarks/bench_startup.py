#!/usr/bin/env python
"""Start-up costs, each measured in fresh processes:

- import time of explorer (python -c "import explorer.analysis.sections", in-process perf_counter around
  the import) and the bare interpreter start (python -c pass) for comparison;
- cold compile per method: a fresh process with NUMBA_CACHE_DIR = an empty directory of its own
  times the first small call of one method (taylor, dop853, split4, split6, split8: each alone,
  so kernels shared between methods are counted in each);
- warm start per method: a fresh process with that (now filled) cache directory times the same
  first call (loading the compiled code from the cache);
- the command line, cold (empty cache directory) and warm (the same directory filled by the cold
  run): `python -m explorer orbit --p1 0.1 --p2 0 -K 5` and `python -m explorer sweep` of a tiny
  scene (one panel, 16 seeds, 5 crossings, no figure), process wall time.

Writes benchmarks/results/startup.json (quick: startup_quick.json) and the STARTUP section of
benchmarks/RESULTS.md (full run only).

    python benchmarks/bench_startup.py            # ~3 min on 2 cores (cold compiles)
    python benchmarks/bench_startup.py --quick    # taylor and split8 only, one run each
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _common as C

SECTION = "STARTUP"
METHODS = (("taylor", "tol=1e-13"), ("dop853", "tol=1e-12"), ("split4", "dt=0.05"), ("split6", "dt=0.05"),
           ("split8", "dt=0.05"))

IMPORT_SCRIPT = r"""
import time
t0 = time.perf_counter()
import explorer.analysis.sections
print(time.perf_counter() - t0)
"""

FIRST_CALL = r"""
import json, time
t0 = time.perf_counter()
import numpy as np
from explorer import model
from explorer.analysis import sections
t_import = time.perf_counter() - t0
prm = model.FIGURE4.with_(mu=0.5)
Y0 = model.section_state(prm, [0.0, 0.3], [0.0, 0.0], 2.0)
t1 = time.perf_counter()
r = sections.crossings(prm, states=Y0, n_crossings=3, method=METHOD, KW)
t_call = time.perf_counter() - t1
assert r.count.min() == 3
print(json.dumps({"import": t_import, "first_call": t_call}))
"""

TINY_SCENE = 'name = "tiny"\n[model]\nmu = 0.5\n[seeds]\nn = 16\n[integration]\ncrossings = 5\n'


def run(cmd, env=None, cwd=None):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True, timeout=3600)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"{cmd} failed:\n{p.stderr}")
    return wall, p.stdout


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="taylor and split8 only, one run each; RESULTS.md untouched")
    ap.add_argument("--repeats", type=int, default=None, help="warm runs (best of; default 3, quick 1)")
    args = ap.parse_args(argv)
    quick = args.quick
    repeats = args.repeats or (1 if quick else 3)
    methods = [m for m in METHODS if m[0] in ("taylor", "split8")] if quick else list(METHODS)
    command = C.command_line("bench_startup.py", argv)
    started, load0, T0 = C.now(), C.loadavg(), time.perf_counter()
    py = sys.executable
    res = dict(interpreter=None, imports=None, methods={}, cli={})

    res["interpreter"] = min(run([py, "-c", "pass"])[0] for _ in range(repeats))
    walls, inner = [], []
    for _ in range(repeats):
        w, out = run([py, "-c", IMPORT_SCRIPT])
        walls.append(w)
        inner.append(float(out.strip().splitlines()[-1]))
    res["imports"] = dict(process_wall=min(walls), in_process=min(inner))
    print(f"interpreter {res['interpreter']:.3f} s; import explorer.analysis.sections {min(inner):.3f} s in process, "
          f"{min(walls):.3f} s process", flush=True)

    tmp_root = Path(tempfile.mkdtemp(prefix="explorer_startup_"))
    try:
        for method, kw in methods:
            cache = tmp_root / f"cache_{method}"
            cache.mkdir()
            env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
            script = FIRST_CALL.replace("METHOD", repr(method)).replace("KW", kw)
            w_cold, out = run([py, "-c", script], env=env)
            cold = json.loads(out.strip().splitlines()[-1])
            warm = []
            for _ in range(repeats):
                w, out = run([py, "-c", script], env=env)
                warm.append(dict(json.loads(out.strip().splitlines()[-1]), process_wall=w))
            best = min(warm, key=lambda d: d["process_wall"])
            res["methods"][method] = dict(setting=kw, cold_first_call=cold["first_call"], cold_process_wall=w_cold,
                                          warm_first_call=min(d["first_call"] for d in warm),
                                          warm_process_wall=best["process_wall"], warm_runs=len(warm))
            print(f"{method:<7} cold: first call {cold['first_call']:.2f} s (process {w_cold:.2f} s); warm: first "
                  f"call {res['methods'][method]['warm_first_call']:.3f} s (process {best['process_wall']:.2f} s)",
                  flush=True)
        # ---- command line
        work = tmp_root / "work"
        work.mkdir()
        (work / "tiny.toml").write_text(TINY_SCENE)
        clis = {"orbit": [py, "-m", "explorer", "orbit", "--p1", "0.1", "--p2", "0", "-K", "5"],
                "sweep": [py, "-m", "explorer", "sweep", "tiny.toml", "--no-figure", "--quiet", "--force",
                          "--out", "tiny.h5"]}
        for name, cmd in clis.items():
            cache = tmp_root / f"cache_cli_{name}"
            cache.mkdir()
            env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
            w_cold, _ = run(cmd, env=env, cwd=work)
            warm = [run(cmd, env=env, cwd=work)[0] for _ in range(repeats)]
            res["cli"][name] = dict(command=" ".join(["python"] + cmd[1:]), cold=w_cold, warm=min(warm),
                                    warm_runs=len(warm))
            print(f"CLI {name}: cold {w_cold:.2f} s, warm {min(warm):.2f} s", flush=True)
    finally:
        shutil.rmtree(tmp_root, ignore_errors=True)

    seconds = time.perf_counter() - T0
    out = C.OUT_DIR / ("startup_quick.json" if quick else "startup.json")
    doc = dict(benchmark="startup", quick=quick, command=command, date=started.isoformat(timespec="seconds"),
               seconds=seconds, machine=C.machine(), versions=C.versions(), load_start=load0, load_end=C.loadavg(),
               results=res)
    C.write_json(out, doc)
    lines, _ = C.header("Start-up: import, cold compile, warm start, command line", command, started, seconds, load0,
                        extra=["Every number is measured in fresh processes. Cold: NUMBA_CACHE_DIR = an empty "
                               "directory of its own (each method alone: kernels shared between methods are "
                               "counted in each); warm: a fresh process with that directory filled by the cold "
                               f"run; best of {repeats} warm runs."])
    lines += ["", "| measurement | seconds |", "|---|---:|",
              f"| interpreter start (`python -c pass`, process) | {res['interpreter']:.3f} |",
              f"| `import explorer.analysis.sections` (in process) | {res['imports']['in_process']:.3f} |",
              f"| `python -c 'import explorer.analysis.sections'` (process) | {res['imports']['process_wall']:.3f} |"]
    lines += ["", "| method | setting | cold: first call (compile) | cold: process | warm: first call (cache load) "
              "| warm: process |", "|---|---|---:|---:|---:|---:|"]
    for m, d in res["methods"].items():
        lines.append(f"| {m} | {d['setting']} | {d['cold_first_call']:.2f} | {d['cold_process_wall']:.2f} | "
                     f"{d['warm_first_call']:.3f} | {d['warm_process_wall']:.2f} |")
    lines += ["", "| command | cold (s) | warm (s) |", "|---|---:|---:|"]
    for name, d in res["cli"].items():
        lines.append(f"| `{d['command']}` | {d['cold']:.2f} | {d['warm']:.2f} |")
    return C.report(SECTION, lines, not quick, (out,))


if __name__ == "__main__":
    sys.exit(main())
