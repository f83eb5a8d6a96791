"""Figure 3: the bifurcation diagram in the (c, h) plane, admissible region in gray, unstable
branches dashed, checked numerically (:func:`explorer.app.paper.chaplygin.figure3_check`)."""

import numpy as np

from explorer.app.paper import _common as cm
from explorer.app.paper import chaplygin as ch

#: the figure's name (``explorer figures --only figure3``) and what it shows
NAME = "figure3"
DESCRIPTION = "the bifurcation diagram in the (c, h) plane, checked numerically"


def figure3_figure(params=cm.CHAPLYGIN, *, check=True, c_range=(-1.5, 6.6), h_max=8.0, energies=cm.FIGURE2_ENERGIES,
            dpi=200) -> cm.Drawn:
    """The seed's Figure 3: the bifurcation diagram of Chaplygin's case in the (c, h) plane, unstable
    parts dashed, the admissible region gray (docs/errata.md), the energies of Figure 2 and the points
    of :func:`~explorer.app.paper.chaplygin.figure3_check` (filled: stable).  Artists' gids:
    "admissible", "I-stable", "I-unstable", "II", "III", "checked"; data: segments, checks."""
    prm = ch.check_chaplygin(params)
    c1, c2 = ch.critical_c(prm)
    hc1, hc2 = ch.critical_h(prm)
    c0, cE = c_range
    records = ch.figure3_check(prm) if check else []
    cc = np.linspace(c0, cE, 1601)
    segs = {}

    def seg(gid, lo, hi, branch, dashed):
        c = np.linspace(lo, hi, 400)
        segs.setdefault(gid, []).append((c, ch.branch_h(branch, c, prm), dashed))

    seg("I-stable", c0, c1, "I", False)
    seg("I-unstable", c1, c2, "I", True)
    seg("I-stable", c2, cE, "I", False)
    seg("II", c1, cE, "II", False)
    seg("III", c2, cE, "III", True)
    styles = {"I": dict(color="k"), "II": dict(color="#1f4e9c"), "III": dict(color="#b2182b")}
    with cm._rc():
        fig = cm._new_figure((5.2, 4.0), dpi=dpi)
        ax = fig.subplots()
        hmin = ch.admissible_hmin(cc, prm)
        ax.fill_between(cc, hmin, h_max + 1.0, color="0.86", lw=0, zorder=0, gid="admissible",
                        label="admissible $(c, h)$")
        for gid, parts in segs.items():
            base = styles[gid.split("-")[0]]
            for j, (c, hh, dashed) in enumerate(parts):
                ax.plot(c, hh, ls=(0, (5, 3)) if dashed else "-", lw=1.3, gid=gid, zorder=3, **base)
        # tangency marks
        for cj, hj, lab in ((c1, hc1, "1"), (c2, hc2, "2")):
            ax.plot([cj, cj], [0, hj], ls=":", color="0.4", lw=0.7, zorder=1)
            ax.plot([c0, cj], [hj, hj], ls=":", color="0.4", lw=0.7, zorder=1)
            ax.plot([cj], [hj], "o", ms=3, color="k", zorder=4)
        # labels of the branches
        def lab(x, branch, text, dy, ha="left"):
            y = float(ch.branch_h(branch, x, prm))
            ax.text(x, y + dy, text, fontsize=cm._SMALL, ha=ha, va="center", color=styles[branch]["color"],
                    zorder=5, bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
        lab(-0.9, "I", r"I: $h = c^2/2b$", 0.75)
        lab(5.0, "II", r"II: $h = \frac{\lambda}{a_1}c - \frac{\lambda^2 b}{2a_1^2}$", -0.75)
        ax.annotate(r"III: $h = \frac{\lambda}{a_2}c - \frac{\lambda^2 b}{2a_2^2}$",
                    xy=(4.9, float(ch.branch_h("III", 4.9, prm))), xytext=(4.45, 6.4), fontsize=cm._SMALL, ha="right",
                    va="center", color=styles["III"]["color"], zorder=5,
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8),
                    arrowprops=dict(arrowstyle="-", lw=0.5, color=styles["III"]["color"], shrinkA=0, shrinkB=1))
        # checked points
        for r in records:
            if r["method"] == "jacobian" and r["branch"] == "I" and r["c"] > 0:
                continue    # shown by the monodromy check
            if r["agree"] is None:
                continue
            ax.plot([r["c"]], [r["h"]], marker="o" if r["method"] == "monodromy" else "s", ms=4.2,
                    mfc="k" if r["stable"] else "white", mec="k", mew=0.8, ls="none", zorder=6, gid="checked")
        # energies of Figure 2
        for k, h in enumerate(energies):
            if h < h_max:
                ax.annotate(f"Fig. 2({'abc'[k]})", xy=(cE, h), xytext=(cE - 0.08, h), fontsize=6, ha="right",
                            va="center", color="0.3")
                ax.plot([cE - 0.06, cE], [h, h], color="0.3", lw=0.8, zorder=2)
        ax.set_xlim(c0, cE)
        ax.set_ylim(0, h_max)
        ax.set_xlabel("$c$ (value of $F$)")
        ax.set_ylabel("$h$ (value of $H$)")
        ax.minorticks_on()
        top = ax.secondary_xaxis("top")
        top.set_xticks([c1, c2], [r"$\lambda b/a_1$", r"$\lambda b/a_2$"])
        top.tick_params(labelsize=cm._TS, direction="in", length=3)
        right = ax.secondary_yaxis("right")
        right.set_yticks([hc1, hc2], [r"$\frac{b\lambda^2}{2a_1^2}$", r"$\frac{b\lambda^2}{2a_2^2}$"])
        right.tick_params(labelsize=cm._TS, direction="in", length=3)
        from matplotlib.lines import Line2D
        from matplotlib.patches import Patch

        handles = [Line2D([], [], color="k", lw=1.3, label="stable"),
                   Line2D([], [], color="k", lw=1.3, ls=(0, (5, 3)), label="unstable"),
                   Line2D([], [], marker="o", ls="none", mfc="k", mec="k", ms=4,
                          label="checked: monodromy of the orbit I"),
                   Line2D([], [], marker="s", ls="none", mfc="k", mec="k", ms=4,
                          label="checked: eigenvalues of R6 (II, III; I at c < 0)"),
                   Line2D([], [], marker="o", ls="none", mfc="white", mec="k", ms=4,
                          label="open marker: numerically unstable"),
                   Patch(color="0.86", label="admissible region")]
        ax.legend(handles=handles, loc="upper left", frameon=True, framealpha=0.9, edgecolor="none",
                  borderpad=0.4, handlelength=2.4)
        ax.set_title(rf"$a_1 > a_2$:  $\lambda = {prm.lam:g}$, $b = {prm.b:g}$, $a_1 = {prm.a1:g}$, "
                     rf"$a_2 = {prm.a2:g}$", fontsize=cm._FS)
    data = {"segments": {g: [(c, hh, d) for c, hh, d in parts] for g, parts in segs.items()}, "checks": records,
            "critical_c": (c1, c2), "critical_h": (hc1, hc2)}
    return cm.Drawn(fig, data)


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> cm.Outcome:
    d = figure3_figure()
    n = sum(1 for r in d.data["checks"] if r["agree"])
    return cm.Outcome(NAME, "written", cm.save(d, out_dir, NAME), f"stability checked at {n} points, all agree", d.data)
