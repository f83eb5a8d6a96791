#!/usr/bin/env python
"""Long-time behaviour: energy error and Casimir error against time over 1e6 time units.

Two regimes of the Figure-4 scene at h = 2 (regular mu = 0.002 and chaotic mu = 0.5), two orbits
each, every method at one typical setting (split4 dt 0.02, split6 and split8 dt 0.05, dop853 tol
1e-12, taylor tol 1e-13).  Each orbit is integrated in chunks ending on a log grid of times
(4 per decade, chunks at most 2e4 long); the state carries over from chunk to chunk, so the run
is one continuous integration.  Recorded at every chunk end: |H - H0| (end of chunk and the
maximum over the chunk's crossings) and |g1^2 + g2^2 - 1|.

Growth law: the running maximum E(t) = max_{s <= t} |H(s) - H0| is fitted as E ~ t^alpha over
the last three decades (least squares in log-log); the splitting methods should be bounded
(alpha ~ 0, at most 1/2 once the round-off random walk dominates), the adaptive methods drift
(alpha ~ 1: a systematic error per unit time, or 1/2 for a random walk of the local errors).
The Casimir error is fitted the same way.

Writes benchmarks/results/longtime.json and .png (quick: *_quick.*) and the LONGTIME section of
benchmarks/RESULTS.md (full run only).

    python benchmarks/bench_longtime.py            # T = 1e6, ~4 min on 2 cores
    python benchmarks/bench_longtime.py --quick    # T = 1e3, seconds
"""
from __future__ import annotations

import argparse
import sys
import time

import _common as C
import numpy as np

SECTION = "LONGTIME"
H = 2.0
REGIMES = (("regular", 0.002), ("chaotic", 0.5))
METHODS = (("split4", dict(dt=0.02)), ("split6", dict(dt=0.05)), ("split8", dict(dt=0.05)),
           ("dop853", dict(tol=1e-12)), ("taylor", dict(tol=1e-13)))
MAX_CHUNK = 2e4


def sample_times(T_end, per_decade=4):
    k = int(round(np.log10(T_end) * per_decade))
    ts = np.unique(np.concatenate([10.0 ** (np.arange(0, k + 1) / per_decade), [T_end]]))
    return ts[ts <= T_end]


def run_method(prm, y0, method, kw, T_end):
    """Continuous run in chunks; returns per-chunk-end rows (t, max |dH| over orbits at the end,
    max |dH| over the chunk's crossings, max |Casimir - 1|) and per-orbit end values."""
    from explorer import model
    from explorer.analysis import sections
    H0 = model.energy(prm, y0)
    y = y0.copy()
    dt = kw.get("dt")
    ends = []
    for t in sample_times(T_end):
        last = ends[-1] if ends else 0.0
        while t - last > MAX_CHUNK * 1.000001:
            last += MAX_CHUNK
            ends.append(last)
        ends.append(float(t))
    if dt:   # chunk ends on multiples of dt: the splitting driver's t = n dt carries over exactly
        ends = sorted(set(max(1, int(round(e / dt))) for e in ends))
    rows, t_now, n_now = [], 0.0, 0
    env = 0.0
    steps_total = np.zeros(len(y0), np.int64)
    for e in ends:
        if dt:
            steps = e - n_now
            tmax = steps * dt
        else:
            tmax = e - t_now
        K = int(tmax * 2) + 20            # more than the crossings a chunk can have (period > 0.5)
        r = sections.crossings(prm, states=y, n_crossings=K, method=method, tmax=tmax, **kw)
        assert np.all(r.count < K), "chunk stopped on its crossing count"
        off = model.energy(prm, y) - H0
        dHc = np.nanmax(np.abs(np.nan_to_num(r.data[..., 4], nan=0.0) + off[:, None])) if r.data.size else 0.0
        y = r.final.copy()
        steps_total += r.info[:, 1].astype(np.int64)
        if dt:
            n_now = e
            t_now = n_now * dt
        else:
            t_now = e
        dH_end = np.abs(model.energy(prm, y) - H0)
        cas = np.abs(model.casimir(y) - 1.0)
        env = max(env, float(dHc), float(dH_end.max()))
        rows.append(dict(t=t_now, dH_end=float(dH_end.max()), dH_chunk=float(dHc), envelope=env,
                         casimir=float(cas.max()), steps=int(steps_total.max())))
    return rows


def fit_growth(rows, key, t_min):
    t = np.array([r["t"] for r in rows])
    v = np.array([r[key] for r in rows])
    sel = (t >= t_min) & (v > 0)
    if sel.sum() < 3:
        return None
    return float(np.polyfit(np.log10(t[sel]), np.log10(v[sel]), 1)[0])


def running_max(values):
    out, m = [], 0.0
    for v in values:
        m = max(m, v)
        out.append(m)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="T = 1e3 instead of 1e6; RESULTS.md untouched")
    ap.add_argument("--time", type=float, default=None, help="final time (default 1e6; quick 1e3)")
    args = ap.parse_args(argv)
    quick = args.quick
    T_end = args.time or (1e3 if quick else 1e6)
    command = C.command_line("bench_longtime.py", argv)
    started, load0, T0 = C.now(), C.loadavg(), time.perf_counter()
    from explorer import model
    from explorer.analysis import sections

    results = []
    for regime, mu in REGIMES:
        prm = model.FIGURE4.with_(mu=mu)
        c1, c2, r1, r2 = model.allowed_ellipse(prm, H)
        y0 = model.section_state(prm, c1 + r1 * np.array([-0.6, 0.5]), c2 + 0.1 * r2 * np.ones(2), H)
        for method, kw in METHODS:
            sections.crossings(prm, states=y0, n_crossings=2, method=method, **kw)     # compile / load the cache
            t0 = time.perf_counter()
            rows = run_method(prm, y0, method, kw, T_end)
            wall = time.perf_counter() - t0
            t_fit = T_end / 1e3 if T_end >= 1e4 else max(1.0, T_end / 1e2)
            res = dict(regime=regime, mu=mu, method=method, setting=kw, wall=wall, rows=rows,
                       alpha_energy=fit_growth(rows, "envelope", t_fit),
                       alpha_casimir=fit_growth([dict(r, cm=m) for r, m in
                                                 zip(rows, running_max([r["casimir"] for r in rows]))], "cm", t_fit),
                       fit_from=t_fit, final_dH=rows[-1]["dH_end"], max_dH=rows[-1]["envelope"],
                       final_casimir=rows[-1]["casimir"], steps=rows[-1]["steps"])
            results.append(res)
            print(f"[{regime} mu={mu}] {method:<7} {str(kw):<16} T={T_end:g}: max|dH| {C.fmt_e(res['max_dH'])}, "
                  f"growth t^{res['alpha_energy']:.2f} (t >= {t_fit:g}); Casimir {C.fmt_e(res['final_casimir'])} "
                  f"(t^{res['alpha_casimir'] if res['alpha_casimir'] is None else round(res['alpha_casimir'], 2)}); "
                  f"{wall:.1f} s", flush=True)

    seconds = time.perf_counter() - T0
    stem = C.OUT_DIR / ("longtime_quick" if quick else "longtime")
    png = plot(results, stem.with_suffix(".png"), T_end)
    doc = dict(benchmark="longtime", quick=quick, command=command, date=started.isoformat(timespec="seconds"),
               seconds=seconds, T=T_end, h=H, machine=C.machine(), versions=C.versions(), load_start=load0,
               load_end=C.loadavg(), results=results, figure=str(png.relative_to(C.ROOT)))
    js = C.write_json(stem.with_suffix(".json"), doc)
    lines, _ = C.header(f"Long-time energy and Casimir errors (T = {T_end:g})", command, started, seconds, load0, extra=[
        f"Figure-4 scene, h = {H}; two orbits per regime (p1 = c1 + r1 (-0.6, 0.5), p2 = c2 + 0.1 r2); chunks "
        "ending on a log grid (4 per decade), state carried over; values = max over the two orbits.",
        "alpha = exponent of the fit E(t) ~ t^alpha of the running maximum of |H - H0| (resp. of the Casimir "
        "error) over the last three decades; bounded: alpha ~ 0 (at most 1/2 from the round-off random walk); "
        "drift: alpha ~ 1.",
        f"Plot: `{png.relative_to(C.ROOT)}` (top: |H - H0| at the chunk ends and running maximum; bottom: "
        "Casimir error; log-log)."])
    lines += ["", "| regime | method | setting | max abs dH up to T | growth alpha (energy) | Casimir error at T "
                  "| growth alpha (Casimir) | steps per orbit | wall (s) |",
              "|---|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in results:
        a, ac = r["alpha_energy"], r["alpha_casimir"]
        lines.append(f"| {r['regime']} (mu = {r['mu']}) | {r['method']} | "
                     f"{', '.join(f'{k} {v:g}' for k, v in r['setting'].items())} | {C.fmt_e(r['max_dH'])} | "
                     f"{'-' if a is None else f'{a:.2f}'} | {C.fmt_e(r['final_casimir'])} | "
                     f"{'-' if ac is None else f'{ac:.2f}'} | {r['steps']:,} | {r['wall']:.1f} |")
    return C.report(SECTION, lines, not quick, (js, png))


def plot(results, path, T_end):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    regimes = list(dict.fromkeys(r["regime"] for r in results))
    methods = list(dict.fromkeys(r["method"] for r in results))
    colors = {m: plt.cm.tab10(i) for i, m in enumerate(methods)}
    fig, axes = plt.subplots(2, len(regimes), figsize=(6.2 * len(regimes), 8.4), squeeze=False)
    for j, reg in enumerate(regimes):
        for r in [r for r in results if r["regime"] == reg]:
            t = [x["t"] for x in r["rows"]]
            col = colors[r["method"]]
            a = r["alpha_energy"]
            lab = f"{r['method']} {', '.join(f'{k} {v:g}' for k, v in r['setting'].items())}" + \
                  ("" if a is None else f" (t^{a:.2f})")
            axes[0, j].plot(t, [max(x["dH_end"], 1e-18) for x in r["rows"]], ".", color=col, alpha=0.5, ms=4)
            axes[0, j].plot(t, [max(x["envelope"], 1e-18) for x in r["rows"]], "-", color=col, label=lab)
            axes[1, j].plot(t, [max(x["casimir"], 1e-18) for x in r["rows"]], "-", color=col, label=r["method"])
        mu = next(r["mu"] for r in results if r["regime"] == reg)
        axes[0, j].set_title(f"{reg}: $\\mu$ = {mu}, h = {H}")
        axes[0, j].set_ylabel(r"$|H - H_0|$ (dots: at chunk ends; line: running max)")
        axes[1, j].set_ylabel(r"$|g_1^2 + g_2^2 - 1|$")
        for ax in axes[:, j]:
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("t")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
    return C.savefig(fig, path, f"Energy and Casimir errors over T = {T_end:g} (benchmarks/bench_longtime.py)")


if __name__ == "__main__":
    sys.exit(main())
