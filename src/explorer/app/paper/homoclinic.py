"""The homoclinic figure: R7 against the integrated flow, with its crossings of phi = pi."""
import math

import numpy as np

from explorer.app.paper._common import _FS, _SMALL, CHAPLYGIN, Drawn, Outcome, _new_figure, _rc, save
from explorer.app.paper._dense import dense_orbits
from explorer.app.paper.chaplygin import check_chaplygin
from explorer.integrate.methods import MAP_TOL

#: the figure's name (``explorer figures --only homoclinic``) and what it shows
NAME = "homoclinic"
DESCRIPTION = "R7 against the integrated flow, with its crossings of phi = pi"


def homoclinic_figure(params=CHAPLYGIN, h=2.0, *, T0=20.0, dt=0.02, tol=MAP_TOL, dpi=200) -> Drawn:
    """R7 (both separatrices, sign = +-1) against the flow integrated from the exact state at
    t = -T0, in (p1, p2) and (t, M), with the crossing times of phi = pi exact and integrated.
    data[sign]: t_exact, t_integrated, max_dt, t, y, exact."""
    from explorer.analysis import sections
    from explorer.model import exact

    prm = check_chaplygin(params)
    P = prm.as_array()
    c = math.sqrt(2 * prm.b * h)
    data = {"c": c, "h": h, "T0": T0}
    starts = []
    for s in (1, -1):
        p1, p2, M, phi = exact.homoclinic(P, c, np.array([-T0]), sign=s)
        starts.append([p1[0], p2[0], M[0], math.sin(phi[0]), math.cos(phi[0])])
    Y0 = np.array(starts)
    t, Ys = dense_orbits(prm, Y0, 2 * T0, dt, tol=tol)
    t = t - T0
    for i, s in enumerate((1, -1)):
        expect = exact.homoclinic_crossing_times(P, c, math.pi, -T0, T0, sign=s)
        res = sections.crossings(prm, states=Y0[i], n_crossings=len(expect), tmax=2 * T0, tol=tol, threads=1)
        got = res.orbit(0)[:, 0] - T0
        n = min(len(got), len(expect))
        diff = np.abs(got[:n] - expect[:n]) if n else np.array([np.inf])
        p1, p2, M, _ = exact.homoclinic(P, c, t, sign=s)
        pts_exact = exact.homoclinic(P, c, expect, sign=s)
        data[s] = {"t_exact": expect, "t_integrated": got, "count_exact": len(expect), "count_integrated": len(got),
                   "max_dt": float(diff.max()), "t": t, "y": Ys[:, i, :], "exact": np.column_stack([p1, p2, M]),
                   "cross_exact": np.column_stack(pts_exact[:3]), "cross_integrated": res.orbit(0)[:, 1:4]}
    colours = {1: "#1f4e9c", -1: "#b2182b"}
    with _rc():
        fig = _new_figure((10.5, 3.4), dpi=dpi)
        axs = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1.0, 1.35, 1.0]})
        ax = axs[0]
        for s in (1, -1):
            d = data[s]
            ax.plot(d["exact"][:, 0], d["exact"][:, 1], color=colours[s], lw=1.4, alpha=0.55,
                    label=f"R7, sign {s:+d}")
            ax.plot(d["y"][::10, 0], d["y"][::10, 1], ".", color=colours[s], ms=1.8, label="integrated")
            ax.plot(d["cross_exact"][:, 0], d["cross_exact"][:, 1], "o", mfc="none", mec="k", ms=4, mew=0.6)
            ax.plot(d["cross_integrated"][:, 0], d["cross_integrated"][:, 1], "x", color="k", ms=3, mew=0.7)
        ax.plot([0], [0], "o", color="k", ms=3)
        ax.annotate("I", (0, 0), xytext=(4, 4), textcoords="offset points", fontsize=_SMALL)
        ax.set_xlabel("$p_1$")
        ax.set_ylabel("$p_2$")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title("(a) the two separatrices of I", fontsize=_FS)
        from matplotlib.lines import Line2D

        ax.legend(handles=[Line2D([], [], color=colours[1], lw=1.4, alpha=0.6, label="R7, sign +1"),
                           Line2D([], [], color=colours[-1], lw=1.4, alpha=0.6, label=r"R7, sign $-1$ ($p\to-p$)"),
                           Line2D([], [], ls="none", marker=".", ms=3, color="0.3", label="integrated (Taylor)"),
                           Line2D([], [], ls="none", marker="o", ms=4, mfc="none", mec="k",
                                  label=r"exact crossing $\varphi=\pi$"),
                           Line2D([], [], ls="none", marker="x", ms=3, color="k", label="integrator's crossing")],
                  loc="lower center", fontsize=6, frameon=False, ncol=2, bbox_to_anchor=(0.5, -0.02))
        ax.margins(0.05, 0.28)
        ax = axs[1]
        d = data[1]
        ax.plot(d["t"], d["exact"][:, 2], color="k", lw=1.4, alpha=0.5, label="R7 (both signs)")
        ax.plot(d["t"][::10], d["y"][::10, 2], ".", color=colours[1], ms=1.8, label="integrated, sign +1")
        ax.plot(data[-1]["t"][5::10], data[-1]["y"][5::10, 2], ".", color=colours[-1], ms=1.8,
                label=r"integrated, sign $-1$")
        Mx = exact.homoclinic(P, c, d["t_exact"])[2]
        ax.plot(d["t_exact"], Mx, "o", mfc="none", mec="k", ms=4.5, mew=0.7,
                label=r"exact crossings of $\varphi = \pi$")
        ax.plot(d["t_integrated"], d["cross_integrated"][:, 2], "x", color="k", ms=4, mew=0.8,
                label="integrator's crossings")
        ax.axhline(c, color="0.6", lw=0.6, ls=":")
        ax.set_xlabel("$t$")
        ax.set_ylabel("$M$")
        ax.set_xlim(-T0, T0)
        ax.set_title(rf"(b) $M(t)$, $c = \sqrt{{2bh}} = {c:.4g}$", fontsize=_FS)
        ax.legend(loc="lower left", fontsize=6, frameon=False)
        ax = axs[2]
        for s, mk, ms in ((1, "o", 6.0), (-1, "s", 3.0)):
            d = data[s]
            n = min(len(d["t_exact"]), len(d["t_integrated"]))
            err = np.abs(d["t_integrated"][:n] - d["t_exact"][:n])
            ax.semilogy(d["t_exact"][:n], np.maximum(err, 1e-17), mk, color=colours[s], ms=ms, mfc="none",
                        mew=0.9, label=f"sign {s:+d}: max {d['max_dt']:.1e}")
        ax.axhline(1e-8, color="0.4", lw=0.7, ls="--")
        ax.text(T0 * 0.97, 1.5e-8, "test bound $10^{-8}$", fontsize=6, color="0.3", ha="right", va="bottom")
        ax.text(T0 * 0.97, 1.6e-17, "(0 drawn at $10^{-17}$)", fontsize=5.5, color="0.4", ha="right", va="bottom")
        ax.set_ylim(1e-17, 1e-6)
        ax.set_xlabel(r"crossing time $t_k$ (exact)")
        ax.set_ylabel(r"$|t_k^{\rm integrated} - t_k^{\rm exact}|$")
        ax.set_title("(c) crossing times: integrator vs R7", fontsize=_FS)
        ax.legend(loc="upper left", fontsize=6, frameon=False)
        fig.suptitle(rf"Homoclinic orbits of solution I (R7) at $h = {h:g}$, $\mu = 0$; start $t = -{T0:g}$, "
                     rf"Taylor tol {tol:.0e}", fontsize=_FS)
    return Drawn(fig, data)


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = homoclinic_figure()
    worst = max(d.data[1]["max_dt"], d.data[-1]["max_dt"])
    return Outcome(NAME, "written", save(d, out_dir, NAME),
                   f"crossing times: integrator vs R7 within {worst:.1e}", d.data)
