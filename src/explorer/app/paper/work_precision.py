"""One-step error against throughput, from ``benchmarks/results_w4.json``."""
import json
from pathlib import Path

import numpy as np

from explorer.app.paper._common import Drawn, FigureUnavailable, Outcome, _new_figure, _rc, save

#: the figure's name (``explorer figures --only work_precision``) and what it shows
NAME = "work_precision"
DESCRIPTION = "one-step error against throughput (benchmarks/results_w4.json)"


def _method_group(row):
    m = row["method"]
    setting = row.get("setting", "")
    if "1 thread" in setting:
        return m + " (1 thread)"
    if "heyoka" in m and "batch" in m:
        return "heyoka batch, " + ("2 processes" if "2 proc" in setting else "1 process")
    if "heyoka" in m:
        return "heyoka scalar, 1 process"
    if "scipy" in m:
        return "scipy solve_ivp DOP853"
    return m


def _short_setting(s):
    s = s.split(",")[0].replace("rtol=atol ", "").replace("tol ", "").replace("dt ", "dt = ")
    return s


#: marker, colour, line style of each method group of the work-precision figure
WP_STYLE = {
    "explorer taylor": ("o", "#1f4e9c", "-"), "explorer taylor (1 thread)": ("o", "#7fa6d9", ":"),
    "explorer dop853": ("s", "#2a9d4b", "-"), "explorer split8": ("D", "#8e44ad", "-"),
    "explorer split6": ("v", "#c27ba0", "-"), "explorer split4": ("^", "#e08e0b", "-"),
    "scipy solve_ivp DOP853": ("P", "0.3", "-"),
    "heyoka batch, 2 processes": ("h", "#b2182b", "-"), "heyoka batch, 1 process": ("h", "#e88f85", ":"),
    "heyoka scalar, 1 process": ("X", "#7b241c", "-"),
}


def work_precision_figure(path, *, dpi=200) -> Drawn:
    """One-step error of the section map against throughput for every method of the W4 benchmark
    (log-log).  data: groups, n_rows, points {name: [(rate, median, max, setting)]}."""
    path = Path(path)
    doc = json.loads(path.read_text())
    rows = doc["rows"]
    groups = {}
    for r in rows:
        groups.setdefault(_method_group(r), []).append(r)
    points = {}
    with _rc():
        fig = _new_figure((6.6, 4.7), dpi=dpi)
        ax = fig.subplots()
        for g, rs in groups.items():
            mk, col, ls = WP_STYLE.get(g, ("o", "0.5", "-"))
            rs = sorted(rs, key=lambda r: -r["err_median"])
            x = np.array([r["rate"] for r in rs])
            y = np.array([r["err_median"] for r in rs])
            ymax = np.array([r["err_max"] for r in rs])
            extra = any(r.get("extrapolated") for r in rs)
            points[g] = [(r["rate"], r["err_median"], r["err_max"], r["setting"]) for r in rs]
            ax.vlines(x, y, ymax, color=col, lw=0.6, alpha=0.6, zorder=1)
            ax.plot(x, ymax, ls="none", marker="_", color=col, ms=5, mew=0.8, zorder=2)
            label = g.replace("explorer ", "explorer: ") + (" (rate extrapolated)" if extra else "")
            ax.plot(x, y, ls=ls, lw=0.8, marker=mk, color=col, ms=4, mfc="white" if extra else col,
                    mec=col, mew=0.8, zorder=3, label=label)
            below = g.startswith("explorer") or g.startswith("scipy")
            for r in rs:
                ax.annotate(_short_setting(r["setting"]), (r["rate"], r["err_median"]),
                            xytext=(3, -6) if below else (-3, 4), textcoords="offset points", fontsize=4.5,
                            color=col, ha="left" if below else "right")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("throughput (section crossings per second)")
        ax.set_ylabel("one-step error of the section map\n(median; bar up to the maximum)")
        meta = doc.get("meta", {})
        wl = meta.get("workload", {})
        mach = meta.get("machine", {})
        mu = wl.get("params", {}).get("mu", "?")
        ax.set_title(f"W4: Figure-4 section, $\\mu = {mu}$, $h = {wl.get('h', '?')}$, {wl.get('n_orbits', '?')} orbits "
                     f"$\\times$ {wl.get('n_crossings', '?')} crossings, {mach.get('cpus', '?')} cores "
                     f"({str(meta.get('date', ''))[:10]})", fontsize=8)
        ax.legend(fontsize=5.5, loc="upper left", frameon=True, framealpha=0.95, edgecolor="none", ncol=2,
                  handlelength=2.2)
        ax.grid(which="major", color="0.92", lw=0.4)
        ref = doc.get("reference", {}).get("reference", "")
        if ref:
            ax.text(0.01, 0.01, "one-step error against " + ref, transform=ax.transAxes, ha="left", va="bottom",
                    fontsize=4.5, color="0.4")
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi * 30)   # room for the legend
    return Drawn(fig, {"groups": {g: len(rs) for g, rs in groups.items()}, "n_rows": len(rows), "points": points})


def find_benchmark(path=None):
    """benchmarks/results_w4.json: the given path, else in the current directory, else next to
    the package's repository root; None when absent."""
    cands = [Path(path)] if path else [Path("benchmarks") / "results_w4.json",
                                       Path(__file__).resolve().parents[2] / "benchmarks" / "results_w4.json"]
    for p in cands:
        if p.is_file():
            return p
    return None


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    p = find_benchmark(benchmark)
    if p is None:
        raise FigureUnavailable("benchmarks/results_w4.json not found (run benchmarks/bench_w4.py)")
    d = work_precision_figure(p)
    return Outcome(NAME, "written", save(d, out_dir, NAME), f"from {p}", d.data)
