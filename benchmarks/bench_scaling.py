#!/usr/bin/env python
"""Scaling: throughput against the number of orbits, the number of crossings, numba threads
(1 -> 2) and sweep worker processes (`python -m explorer sweep --jobs 1, 2`).

Workload: Figure-4 scene at mu = 0.5 (chaotic), h = 2, orbits started on phi = pi across the
allowed ellipse; methods taylor (tol 1e-13), dop853 (tol 1e-12), split8 (dt 0.05).

- orbits N = 8 .. 512 at K = 200 crossings: wall and crossings/s (expect constant crossings/s,
  i.e. wall linear in N, once every thread has work: the taylor lanes take 8 orbits per thread);
- crossings K = 100 .. 4000 at N = 32: wall (expect linear in K); fitted exponents of wall ~ N^b
  (N >= 32) and wall ~ K^b;
- threads: N = 64, K = 500 with numba threads 1 and 2 (speed-up);
- the whole `python -m explorer sweep` of a small scene (3 panels x ~100 seeds x 200 crossings,
  taylor) with --jobs 1 and --jobs 2 (fresh processes, --force, warm cache; process wall time).

Writes benchmarks/results/scaling.json and .png (quick: *_quick.*) and the SCALING section of
benchmarks/RESULTS.md (full run only).

    python benchmarks/bench_scaling.py            # ~5 min on 2 cores
    python benchmarks/bench_scaling.py --quick    # ~30 s
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _common as C
import numpy as np

SECTION = "SCALING"
H = 2.0
MU = 0.5
METHODS = (("taylor", dict(tol=1e-13)), ("dop853", dict(tol=1e-12)), ("split8", dict(dt=0.05)))

SCENE = """name = "scaling"
[model]
mu = 0.5
[energy]
h = 2.0
[sweep]
parameter = "mu"
values = [0.3, 0.5, 0.7]
[seeds]
kind = "grid"
n = {n}
[integration]
method = "taylor"
tol = 1e-13
crossings = {k}
"""


def fit_exponent(x, y):
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small sizes; RESULTS.md untouched")
    ap.add_argument("--repeats", type=int, default=None, help="timing runs per point (default 2; quick 1)")
    args = ap.parse_args(argv)
    quick = args.quick
    repeats = args.repeats or (1 if quick else 2)
    Ns = (8, 32, 64) if quick else (8, 16, 32, 64, 128, 256, 512)
    K_N = 20 if quick else 200
    Ks = (20, 50, 100) if quick else (100, 250, 500, 1000, 2000, 4000)
    N_K = 16 if quick else 32
    N_T, K_T = (32, 50) if quick else (64, 500)
    sweep_n, sweep_k = (16, 20) if quick else (100, 200)
    command = C.command_line("bench_scaling.py", argv)
    started, load0, T0 = C.now(), C.loadavg(), time.perf_counter()
    from explorer import model
    from explorer._jit import get_num_threads
    from explorer.analysis import sections
    prm = model.FIGURE4.with_(mu=MU)
    Ymax = C.section_seeds(prm, H, max(max(Ns), N_K, N_T))
    nthreads = get_num_threads()
    out = dict(orbits={}, crossings={}, threads={}, sweep={})

    def timed(method, kw, Y, K, threads=None):
        best, times, res = C.best_of(lambda: sections.crossings(prm, states=Y, n_crossings=K, method=method, threads=threads, **kw),
                                     repeats, budget=60.0)
        n = int(res.count.sum())
        return dict(wall=best, times=times, crossings=n, rate=n / best, t_integrated=float(res.info[:, 0].sum()))

    for method, kw in METHODS:
        sections.crossings(prm, states=Ymax[:2], n_crossings=2, method=method, **kw)   # compile / load the cache
        # Orbits from the same seed set, spread over the ellipse: Y[:N] would take the left end only,
        # so every N uses an evenly spaced subset of the largest set.
        out["orbits"][method] = []
        for N in Ns:
            idx = np.linspace(0, len(Ymax) - 1, N).round().astype(int)
            r = timed(method, kw, Ymax[idx], K_N)
            out["orbits"][method].append(dict(N=N, K=K_N, **r))
            print(f"{method:<7} N={N:<4} K={K_N:<5} wall {r['wall']:7.3f} s  {r['rate']:10,.0f} crossings/s",
                  flush=True)
        out["crossings"][method] = []
        idx = np.linspace(0, len(Ymax) - 1, N_K).round().astype(int)
        for K in Ks:
            r = timed(method, kw, Ymax[idx], K)
            out["crossings"][method].append(dict(N=N_K, K=K, **r))
            print(f"{method:<7} N={N_K:<4} K={K:<5} wall {r['wall']:7.3f} s  {r['rate']:10,.0f} crossings/s",
                  flush=True)
        idx = np.linspace(0, len(Ymax) - 1, N_T).round().astype(int)
        out["threads"][method] = {}
        for th in sorted({1, nthreads}):
            r = timed(method, kw, Ymax[idx], K_T, threads=th)
            out["threads"][method][th] = dict(N=N_T, K=K_T, **r)
            print(f"{method:<7} threads={th} N={N_T} K={K_T} wall {r['wall']:7.3f} s", flush=True)

    # ---- the sweep command, --jobs 1 and 2
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "scaling.toml"
        scene.write_text(SCENE.format(n=sweep_n, k=sweep_k))
        base = [sys.executable, "-m", "explorer", "sweep", str(scene), "--no-figure", "--quiet", "--force"]
        subprocess.run(base + ["--out", str(Path(tmp) / "warm.h5")], check=True, capture_output=True, timeout=1800)
        for jobs in (1, 2):
            cmd = base + ["--jobs", str(jobs), "--out", str(Path(tmp) / f"j{jobs}.h5")]
            times, summary = [], ""
            for _ in range(repeats):
                t0 = time.perf_counter()
                p = subprocess.run(cmd, check=True, capture_output=True, text=True, timeout=1800)
                times.append(time.perf_counter() - t0)
                summary = p.stdout
            m = re.search(r"orbits (\d+), crossings (\d+)", summary)
            out["sweep"][jobs] = dict(wall=min(times), times=times, orbits=int(m.group(1)) if m else None,
                                      crossings=int(m.group(2)) if m else None)
            print(f"sweep --jobs {jobs}: {min(times):.2f} s ({summary.strip().splitlines()[-1] if summary else ''})",
                  flush=True)

    # ---- analysis
    analysis = {}
    for method, _ in METHODS:
        o = [r for r in out["orbits"][method] if r["N"] >= 32]
        k = out["crossings"][method]
        th = out["threads"][method]
        analysis[method] = dict(
            exponent_N=fit_exponent([r["N"] for r in o], [r["wall"] for r in o]) if len(o) >= 2 else None,
            exponent_K=fit_exponent([r["K"] for r in k], [r["wall"] for r in k]),
            speedup_threads=(th[1]["wall"] / th[nthreads]["wall"]) if nthreads > 1 else None)
    sw = out["sweep"]
    analysis["sweep_speedup_jobs2"] = sw[1]["wall"] / sw[2]["wall"]
    seconds = time.perf_counter() - T0
    stem = C.OUT_DIR / ("scaling_quick" if quick else "scaling")
    png = plot(out, analysis, stem.with_suffix(".png"), nthreads)
    doc = dict(benchmark="scaling", quick=quick, command=command, date=started.isoformat(timespec="seconds"),
               seconds=seconds, mu=MU, h=H, numba_threads=nthreads, machine=C.machine(), versions=C.versions(),
               load_start=load0, load_end=C.loadavg(), results=out, analysis=analysis,
               sweep_scene=SCENE.format(n=sweep_n, k=sweep_k), figure=str(png.relative_to(C.ROOT)))
    js = C.write_json(stem.with_suffix(".json"), doc)
    lines, _ = C.header("Scaling: orbits, crossings, threads, sweep jobs", command, started, seconds, load0, extra=[
        f"Figure-4 scene, mu = {MU}, h = {H}; taylor tol 1e-13, dop853 tol 1e-12, split8 dt 0.05; best of "
        f"{repeats} runs; orbits evenly spread over the allowed ellipse at p2 = c2.",
        f"Plot: `{png.relative_to(C.ROOT)}`."])
    lines += ["", f"Throughput against the number of orbits (K = {K_N} crossings each), crossings/s:", "",
              "| method | " + " | ".join(f"N = {N}" for N in Ns) + " | wall ~ N^b (N >= 32) |",
              "|---|" + "---:|" * (len(Ns) + 1)]
    for method, _ in METHODS:
        lines.append(f"| {method} | " + " | ".join(f"{r['rate']:,.0f}" for r in out["orbits"][method])
                     + f" | b = {analysis[method]['exponent_N']:.2f} |")
    lines += ["", f"Wall time (s) against the number of crossings (N = {N_K} orbits):", "",
              "| method | " + " | ".join(f"K = {K}" for K in Ks) + " | wall ~ K^b |", "|---|" + "---:|" * (len(Ks) + 1)]
    for method, _ in METHODS:
        lines.append(f"| {method} | " + " | ".join(f"{r['wall']:.3f}" for r in out["crossings"][method])
                     + f" | b = {analysis[method]['exponent_K']:.2f} |")
    lines += ["", f"Threads (N = {N_T}, K = {K_T}):", "", "| method | wall 1 thread (s) | wall "
              f"{nthreads} threads (s) | speed-up |", "|---|---:|---:|---:|"]
    for method, _ in METHODS:
        th = out["threads"][method]
        sp = analysis[method]["speedup_threads"]
        lines.append(f"| {method} | {th[1]['wall']:.3f} | {th[nthreads]['wall']:.3f} | "
                     f"{'-' if sp is None else f'{sp:.2f}'} |")
    lines += ["", f"`python -m explorer sweep` of a small scene (3 panels, grid of about {sweep_n} seeds, "
              f"{sweep_k} crossings, taylor tol 1e-13; --force --no-figure, warm cache, process wall time):", "",
              "| --jobs | wall (s) | orbits | crossings |", "|---:|---:|---:|---:|"]
    for jobs in (1, 2):
        s = sw[jobs]
        lines.append(f"| {jobs} | {s['wall']:.2f} | {s['orbits']} | {s['crossings']} |")
    lines += ["", f"--jobs 2 / --jobs 1 speed-up: {analysis['sweep_speedup_jobs2']:.2f} (--jobs 1 already uses "
              f"{nthreads} numba threads over orbits; --jobs N runs N processes of one thread each)."]
    return C.report(SECTION, lines, not quick, (js, png))


def plot(out, analysis, path, nthreads):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    for i, method in enumerate(out["orbits"]):
        col = plt.cm.tab10(i)
        o = out["orbits"][method]
        axes[0].plot([r["N"] for r in o], [r["rate"] for r in o], "o-", color=col,
                     label=f"{method} (wall ~ N^{analysis[method]['exponent_N']:.2f})")
        k = out["crossings"][method]
        axes[1].plot([r["K"] for r in k], [r["wall"] for r in k], "o-", color=col,
                     label=f"{method} (wall ~ K^{analysis[method]['exponent_K']:.2f})")
    axes[0].set_xscale("log", base=2)
    axes[0].set_yscale("log")
    axes[0].set_xlabel(f"orbits N (K = {out['orbits']['taylor'][0]['K']})")
    axes[0].set_ylabel("crossings per second")
    axes[1].set_xscale("log")
    axes[1].set_yscale("log")
    axes[1].set_xlabel(f"crossings per orbit K (N = {out['crossings']['taylor'][0]['N']})")
    axes[1].set_ylabel("wall time (s)")
    labels, vals = [], []
    for method in out["threads"]:
        if analysis[method]["speedup_threads"] is not None:
            labels.append(f"{method}\n1 -> {nthreads} threads")
            vals.append(analysis[method]["speedup_threads"])
    labels.append("sweep\n--jobs 1 -> 2")
    vals.append(analysis["sweep_speedup_jobs2"])
    axes[2].bar(range(len(vals)), vals, color="tab:gray")
    axes[2].axhline(1.0, color="k", lw=0.8)
    axes[2].axhline(float(nthreads), color="k", lw=0.8, ls="--")
    axes[2].set_xticks(range(len(vals)), labels, fontsize=8)
    axes[2].set_ylabel("speed-up")
    for ax in axes[:2]:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    return C.savefig(fig, path, "Scaling (benchmarks/bench_scaling.py)")


if __name__ == "__main__":
    sys.exit(main())
