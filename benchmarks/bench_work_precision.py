#!/usr/bin/env python
"""Work-precision: one-step section-map error and energy error against wall time, every method,
three regimes (regular mu = 0.002, mixed mu = 0.03, chaotic mu = 0.5; Figure-4 scene, h = 2).

For each mu and each row (explorer taylor at several tol, dop853 at several tol, split4/6/8 at
several dt, scipy solve_ivp DOP853 with events (1 process), heyoka taylor_adaptive_batch in one
process per core when installed; explorer uses numba threads on every core):

- wall time of a workload of N orbits x K crossings (started on phi = pi across the allowed
  ellipse at p2 = c2), best of a few runs, warm (compile / cache load done before);
  scipy is too slow for the workload: it is timed on a few orbits and extrapolated (marked);
- one-step section-map error: N_pts section points (crossings 1..k of the workload orbits from
  explorer taylor tol 1e-15, put exactly on the section), each integrated to its next crossing;
  error = max abs difference of (t, p1, p2, M) against the reference; median and max;
- energy error: max |H - H0| over all crossings of the workload run.

Reference of the one-step errors: heyoka taylor_adaptive in extended precision
(fp_type numpy.longdouble, tol = its epsilon; benchmarks/bench_w4.heyoka_reference) when heyoka
is installed, checked against explorer taylor tol 1e-16 and dop853 tol 1e-15; otherwise
explorer dop853 tol 1e-15 (checked against taylor tol 1e-16), and for the dop853 rows taylor
tol 1e-16 (a row is never measured against its own method).

Writes benchmarks/results/work_precision.json and .png (quick: *_quick.*), and the
WORK-PRECISION section of benchmarks/RESULTS.md (full run only).

    python benchmarks/bench_work_precision.py            # ~10 min on 2 cores
    python benchmarks/bench_work_precision.py --quick    # smoke test, ~1 min
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

import _common as C
import numpy as np

MUS = (("regular", 0.002), ("mixed", 0.03), ("chaotic", 0.5))
H = 2.0
SECTION = "WORK-PRECISION"
#: heyoka processes: one per core, as explorer runs numba threads on every core (2 here)
N_PROC = os.cpu_count() or 1


def rows_config(quick):
    if quick:
        return dict(taylor=(1e-8, 1e-12), dop853=(1e-8, 1e-12), split4=(0.02,), split6=(0.05,), split8=(0.1,),
                    scipy=(1e-10,), heyoka=(1e-12,))
    return dict(taylor=(1e-8, 1e-10, 1e-12, 1e-14, 1e-16), dop853=(1e-8, 1e-10, 1e-12, 1e-14),
                split4=(0.04, 0.02, 0.01, 0.005), split6=(0.1, 0.05, 0.025), split8=(0.2, 0.1, 0.05, 0.025),
                scipy=(1e-8, 1e-10, 1e-12), heyoka=(1e-8, 1e-12, 1e-15))


def one_step_points(prm, Y0, per_orbit):
    from explorer.analysis import sections
    r = sections.crossings(prm, states=Y0, n_crossings=per_orbit, method="taylor", tol=1e-15)
    ok = r.count == per_orbit
    rows = r.data[ok, :per_orbit, :].reshape(-1, 5)
    pts = np.zeros((rows.shape[0], 5))
    pts[:, :3] = rows[:, 1:4]
    pts[:, 3], pts[:, 4] = 0.0, -1.0          # exactly on phi = pi
    return pts


def errors(rows4, ref):
    e = np.max(np.abs(rows4 - ref), axis=1)
    e[~np.isfinite(e)] = np.inf
    return e


def stats(e):
    e = np.asarray(e)
    return dict(median=float(np.median(e)), max=float(np.max(e)), n=int(e.size),
                missing=int(np.sum(~np.isfinite(e))))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small workload, few rows; RESULTS.md untouched")
    ap.add_argument("--repeats", type=int, default=None, help="timing runs per row (default 3; quick 1)")
    ap.add_argument("--no-heyoka", action="store_true", help="do not use heyoka even when installed")
    ap.add_argument("--render", metavar="JSON", help="only re-render the WORK-PRECISION section of "
                    "RESULTS.md from a full run's JSON (e.g. benchmarks/results/work_precision.json)")
    args = ap.parse_args(argv)
    if args.render:
        return render(Path(args.render))
    quick = args.quick
    N, K = (8, 40) if quick else (32, 500)
    per_orbit = 4 if quick else 8
    repeats = args.repeats or (1 if quick else 3)
    cfg = rows_config(quick)
    use_heyoka = C.have("heyoka") and not args.no_heyoka
    have_scipy = C.have("scipy")
    command = C.command_line("bench_work_precision.py", argv)
    started, load0, T0 = C.now(), C.loadavg(), time.perf_counter()
    log = lambda *a: print(*a, flush=True)  # noqa: E731

    import bench_w4 as w4

    from explorer import model
    from explorer.analysis import sections

    results = []
    for regime, mu in MUS:
        prm = model.FIGURE4.with_(mu=mu)
        P = prm.as_array()
        Y0 = C.section_seeds(prm, H, N)
        pts = one_step_points(prm, Y0, per_orbit)
        # ---- reference
        t0 = time.perf_counter()
        ex_t16 = sections.crossings(prm, states=pts, n_crossings=1, method="taylor", tol=1e-16).data[:, 0, :4]
        ex_d15 = sections.crossings(prm, states=pts, n_crossings=1, method="dop853", tol=1e-15).data[:, 0, :4]
        if use_heyoka:
            ref, ref_tol, ref_order = w4.heyoka_reference(P, pts, "longdouble")
            keep = np.all(np.isfinite(ref), axis=1)
            refs = {"all": ref}
            ref_name = f"heyoka taylor_adaptive fp_type=numpy.longdouble, tol {ref_tol:.3g}, order {ref_order}"
            check = {"explorer taylor 1e-16": stats(errors(ex_t16[keep], ref[keep])),
                     "explorer dop853 1e-15": stats(errors(ex_d15[keep], ref[keep]))}
        else:
            keep = np.all(np.isfinite(ex_d15), axis=1) & np.all(np.isfinite(ex_t16), axis=1)
            refs = {"all": ex_d15, "dop853": ex_t16}
            ref_name = "explorer dop853 tol 1e-15 (for the dop853 rows: explorer taylor tol 1e-16)"
            check = {"dop853 1e-15 vs taylor 1e-16": stats(errors(ex_d15[keep], ex_t16[keep]))}
        pts, refs = pts[keep], {k: v[keep] for k, v in refs.items()}
        t_ref = time.perf_counter() - t0
        log(f"[{regime} mu={mu}] {len(pts)} one-step points; reference {ref_name} ({t_ref:.1f} s); check {check}")

        def ref_for(method):
            return refs.get(method, refs["all"])

        # ---- explorer rows
        rows = []
        specs = ([("taylor", dict(tol=t), f"tol {t:.0e}") for t in cfg["taylor"]]
                 + [("dop853", dict(tol=t), f"tol {t:.0e}") for t in cfg["dop853"]]
                 + [(m, dict(dt=d), f"dt {d:g}") for m in ("split4", "split6", "split8") for d in cfg[m]])
        for method, kw, setting in specs:
            sections.crossings(prm, states=Y0[:2], n_crossings=2, method=method, **kw)          # compile / load the cache
            best, times, res = C.best_of(lambda: sections.crossings(prm, states=Y0, n_crossings=K, method=method, **kw), repeats,
                                         budget=30.0)
            one = sections.crossings(prm, states=pts, n_crossings=1, method=method, **kw).data[:, 0, :4]
            es = stats(errors(one, ref_for(method)))
            ncross = int(res.count.sum())
            row = dict(family=f"explorer {method}", method=method, setting=setting, wall=best, times=times,
                       crossings=ncross, rate=ncross / best, err_median=es["median"], err_max=es["max"],
                       err_missing=es["missing"], max_dH=float(np.nanmax(np.abs(res.data[..., 4]))),
                       extrapolated=False, order=res.settings.get("order"))
            rows.append(row)
            log(f"  {row['family']:<16} {setting:<10} wall {best:7.3f} s  1-step med {C.fmt_e(es['median'])} "
                f"max {C.fmt_e(es['max'])}  max|dH| {C.fmt_e(row['max_dH'])}")
        # ---- scipy
        if have_scipy:
            sp_idx = np.linspace(0, N - 1, 2 if quick else 4).round().astype(int)
            sp_K = 10 if quick else 40
            sub = np.arange(0, len(pts), 1 if quick else 4)
            for rtol in cfg["scipy"]:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    best, times, sp = C.best_of(lambda: w4.scipy_sections(prm, Y0[sp_idx], sp_K, rtol), 1, 1e9)
                    sp1 = w4.scipy_sections(prm, pts[sub], 1, rtol, chunk=10.0)
                one = np.concatenate([sp1["ts"][:, :1], sp1["ys"][:, 0, :3]], axis=1)
                es = stats(errors(one, ref_for("scipy")[sub]))
                rate = int(sp["count"].sum()) / best
                dH = model.energy(prm, sp["ys"]) - model.energy(prm, Y0[sp_idx])[:, None]
                row = dict(family="scipy DOP853", method="scipy", setting=f"rtol=atol {rtol:.0e}",
                           wall=N * K / rate, times=times, crossings=int(sp["count"].sum()), rate=rate,
                           err_median=es["median"], err_max=es["max"], err_missing=es["missing"],
                           max_dH=float(np.nanmax(np.abs(dH))), extrapolated=True,
                           measured=f"{len(sp_idx)} orbits x {sp_K} crossings in {best:.2f} s; one-step on "
                                    f"{len(sub)} points")
                rows.append(row)
                log(f"  scipy DOP853     rtol {rtol:.0e} wall* {row['wall']:7.2f} s  1-step med "
                    f"{C.fmt_e(es['median'])} max {C.fmt_e(es['max'])}")
        # ---- heyoka: batch mode in one process per core (as explorer uses every core with its
        # threads), wall = integration after a barrier (bench_w4.heyoka_processes)
        if use_heyoka:
            import heyoka
            simd = int(heyoka.recommended_simd_size())
            for tol in cfg["heyoka"]:
                runner = w4.HeyokaSections(P, tol, simd)

                def hy_run():
                    out = w4.heyoka_processes(P, Y0, K, tol, simd, min(N_PROC, N))
                    return out["wall"], out
                times, r = [], None
                for _ in range(repeats):
                    wall_i, r = hy_run()
                    times.append(wall_i)
                best = min(times)
                o1 = runner.run(pts, 1, w4.TMAX_PER_CROSSING)
                one = np.concatenate([o1["ts"], o1["ys"][:, 0, :3]], axis=1)
                es = stats(errors(one, ref_for("heyoka")))
                dH = model.energy(prm, r["ys"]) - model.energy(prm, Y0)[:, None]
                ncross = int(r["count"].sum())
                rows.append(dict(family=f"heyoka batch {simd}, {N_PROC} proc", method="heyoka",
                                 setting=f"tol {tol:.0e}",
                                 wall=best, times=times, crossings=ncross, rate=ncross / best,
                                 err_median=es["median"], err_max=es["max"], err_missing=es["missing"],
                                 max_dH=float(np.nanmax(np.abs(dH))), extrapolated=False, order=runner.order))
                log(f"  heyoka batch     tol {tol:.0e} wall {best:7.3f} s  1-step med {C.fmt_e(es['median'])} "
                    f"max {C.fmt_e(es['max'])}")
        results.append(dict(regime=regime, mu=mu, n_points=int(len(pts)), reference=ref_name,
                            reference_seconds=t_ref, reference_check=check, rows=rows))

    seconds = time.perf_counter() - T0
    stem = C.OUT_DIR / ("work_precision_quick" if quick else "work_precision")
    png = plot(results, stem.with_suffix(".png"), N, K)
    doc = dict(benchmark="work_precision", quick=quick, command=command, date=started.isoformat(timespec="seconds"),
               seconds=seconds, workload=dict(orbits=N, crossings=K, h=H, one_step_per_orbit=per_orbit,
                                              start="phi = pi, p2 = c2, p1 = c1 + r1 linspace(-0.95, 0.95, N)"),
               machine=C.machine(), versions=C.versions(), load_start=load0, load_end=C.loadavg(),
               results=results, figure=str(png.relative_to(C.ROOT)))
    js = C.write_json(stem.with_suffix(".json"), doc)
    lines = markdown(results, doc, N, K, seconds, started, load0, png)
    return C.report(SECTION, lines, not quick, (js, png))


def plot(results, path, N, K):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fams = []
    for res in results:
        for r in res["rows"]:
            if r["family"] not in fams:
                fams.append(r["family"])
    colors = {f: plt.cm.tab10(i % 10) for i, f in enumerate(fams)}
    fig, axes = plt.subplots(2, len(results), figsize=(5.2 * len(results), 8.4), squeeze=False)
    for j, res in enumerate(results):
        ax1, ax2 = axes[0, j], axes[1, j]
        for fam in fams:
            rr = sorted([r for r in res["rows"] if r["family"] == fam], key=lambda r: r["wall"])
            if not rr:
                continue
            x = [r["wall"] for r in rr]
            mk = "s" if rr[0]["extrapolated"] else "o"
            face = "none" if rr[0]["extrapolated"] else colors[fam]
            ax1.plot(x, [max(r["err_median"], 1e-17) for r in rr], "-", marker=mk, color=colors[fam],
                     mfc=face, label=fam + (" (wall extrapolated)" if rr[0]["extrapolated"] else ""))
            ax1.plot(x, [max(r["err_max"], 1e-17) for r in rr], "--", marker=mk, color=colors[fam], mfc="none",
                     alpha=0.6)
            ax2.plot(x, [max(r["max_dH"], 1e-17) for r in rr], "-", marker=mk, color=colors[fam], mfc=face,
                     label=fam)
        for ax in (ax1, ax2):
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.grid(True, which="both", alpha=0.3)
            ax.set_xlabel(f"wall time for {N} orbits x {K} crossings (s)")
        ax1.set_title(f"{res['regime']}: $\\mu$ = {res['mu']}")
        ax1.set_ylabel("one-step section-map error\n(solid: median, dashed: max)")
        ax2.set_ylabel(r"max $|H - H_0|$ over the crossings")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    for ax in axes[0, 1:]:
        for h_, l_ in zip(*ax.get_legend_handles_labels()):
            if l_ not in labels:
                handles.append(h_)
                labels.append(l_)
    fig.legend(handles, labels, loc="lower center", ncol=min(4, len(labels)), fontsize=8)
    return C.savefig(fig, path, "Work-precision on the Figure-4 scene, h = 2 (benchmarks/bench_work_precision.py)",
                     rect=(0, 0.07, 1, 1))


#: an explorer row matches a comparator's accuracy when its median one-step error is at most
#: MATCH_FACTOR times the comparator's
MATCH_FACTOR = 2.0


def matched_accuracy(rows):
    """For each comparator row (heyoka, scipy): the fastest explorer row, and the fastest of each
    explorer method, whose median one-step error is at most MATCH_FACTOR times the
    comparator's; their throughput ratios.  Returns (lines, verdicts), verdicts a list of
    (comparator setting, ratio of the fastest matching explorer row or None)."""
    ours = [r for r in rows if r["family"].startswith("explorer") and np.isfinite(r["err_median"])]
    lines, verdicts = [], []
    for c in rows:
        if c["family"].startswith("explorer") or not np.isfinite(c["err_median"]):
            continue
        target = MATCH_FACTOR * c["err_median"]
        ok = [r for r in ours if r["err_median"] <= target]
        name = f"{c['family']} {c['setting']}"
        if not ok:
            lines.append(f"- {name} (median {C.fmt_e(c['err_median'])}, {c['rate']:,.0f} crossings/s): "
                         "no explorer setting tried reaches its accuracy")
            verdicts.append((name, None))
            continue
        best = max(ok, key=lambda r: r["rate"])
        per = []
        for fam in sorted({r["family"] for r in ours}):
            cand = [r for r in ok if r["family"] == fam]
            if cand:
                b = max(cand, key=lambda r: r["rate"])
                per.append(f"{fam.replace('explorer ', '')} {b['setting']} {b['rate'] / c['rate']:.2f}x")
            else:
                per.append(f"{fam.replace('explorer ', '')}: none of the settings tried")
        lines.append(f"- {name} (median {C.fmt_e(c['err_median'])}, {c['rate']:,.0f} crossings/s): fastest "
                     f"row at matched accuracy: {best['family']} {best['setting']} (median "
                     f"{C.fmt_e(best['err_median'])}, {best['rate']:,.0f}/s) = **{best['rate'] / c['rate']:.2f}x**; "
                     "per method: " + "; ".join(per))
        verdicts.append((name, best["rate"] / c["rate"]))
    return lines, verdicts


def render(path):
    """Re-render the WORK-PRECISION section from a full run's JSON document."""
    import datetime as _dt
    doc = json.loads(path.read_text())
    if doc.get("quick"):
        raise SystemExit(f"{path}: a --quick run; only full runs go into RESULTS.md")
    w = doc["workload"]
    lines = markdown(doc["results"], doc, w["orbits"], w["crossings"], doc["seconds"],
                     _dt.datetime.fromisoformat(doc["date"]), doc["load_start"], C.ROOT / doc["figure"],
                     stored=doc)
    C.update_section(SECTION, lines)
    print(f"updated {C.RESULTS_MD} from {path}")
    return 0


def markdown(results, doc, N, K, seconds, started, load0, png, stored=None):
    lines, _ = C.header("Work-precision: one-step error and energy error against wall time", doc["command"],
                        started, seconds, load0, stored=stored, extra=[
                            f"Workload per mu: Figure-4 scene, h = {H}, {N} orbits x {K} crossings from phi = pi "
                            "across the allowed ellipse (p2 = c2); wall = best of up to 3 runs (warm); explorer "
                            f"on numba threads over all cores, heyoka batch mode in {N_PROC} processes (one per "
                            "core; integration wall after a barrier, spawn and JIT excluded), scipy in 1 process, "
                            "timed on a few orbits and extrapolated (marked *).",
                            "One-step error: section points = crossings of the workload orbits (taylor tol 1e-15), "
                            "each integrated to its next crossing; max abs difference of (t, p1, p2, M) to the "
                            "reference; energy error = max |H - H0| over the workload's crossings.",
                            f"Plot: `{png.relative_to(C.ROOT)}` (one column per mu; top: one-step error median "
                            "solid, max dashed; bottom: energy error; log-log)."])
    for res in results:
        lines += ["", f"### {res['regime']}: mu = {res['mu']} ({res['n_points']} one-step points)", "",
                  f"Reference: {res['reference']} ({res['reference_seconds']:.1f} s). Check: "
                  + "; ".join(f"{k}: median {C.fmt_e(v['median'])}, max {C.fmt_e(v['max'])}"
                              for k, v in res["reference_check"].items()), "",
                  "| method | setting | wall (s) | crossings/s | 1-step err median | 1-step err max | max abs dH |",
                  "|---|---|---:|---:|---:|---:|---:|"]
        for r in res["rows"]:
            setting = r["setting"] + (f", order {r['order']}" if r.get("order") and "taylor" in r["family"] else "")
            wall = f"{r['wall']:.3f}" + ("*" if r["extrapolated"] else "")
            lines.append(f"| {r['family']} | {setting} | {wall} | {r['rate']:,.0f} | {C.fmt_e(r['err_median'])} | "
                         f"{C.fmt_e(r['err_max'])} | {C.fmt_e(r['max_dH'])} |")
        comp, verdicts = matched_accuracy(res["rows"])
        if comp:
            lines += ["", f"At matched accuracy (explorer median one-step error at most {MATCH_FACTOR:g}x the "
                      "comparator's; throughput ratio explorer / comparator, computed by the script):", ""] + comp
            behind = [n for n, ratio in verdicts if ratio is None or ratio < 1.0]
            lines += ["", "Verdict: explorer is ahead of every comparator row at matched accuracy." if not behind
                      else "Verdict: explorer is NOT ahead of: " + ", ".join(behind) + "."]
    return lines


if __name__ == "__main__":
    sys.exit(main())
