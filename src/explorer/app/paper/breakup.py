"""Figure ``breakup``: mu_c of the noble curves of Figure 4's right island, and its section at 0.99 and
1.01 mu_c of the last curve to break (docs/greene.md, "The noble curves of the right island")."""

import numpy as np

from explorer import model
from explorer.app.paper._common import _FS, _SMALL, Drawn, Outcome, _new_figure, _rc, save

NAME = "breakup"
DESCRIPTION = "mu_c of the noble curves of the right island (Greene's criterion), sections at 0.99 and 1.01 mu_c"
NOBLES = ("4", "5,2", "5", "6,2", "6")
QUICK_NOBLES = ("6",)
AROUND = (1.58, 0.0)
MU0 = 0.025
QMAX = 150


def _window(panel, margin=0.05):
    """((p1 min, max), (p2 min, max)) of a panel's points, widened by ``margin`` of each span."""
    _, _, _, pts, conv_pts = panel
    xy = np.concatenate([*pts, conv_pts])
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    pad = margin * (hi - lo)
    return tuple((float(a), float(b)) for a, b in zip(lo - pad, hi + pad))


def breakup_figure(*, nobles=NOBLES, qmax=QMAX, starts=40, crossings=600, dpi=200) -> Drawn:
    """mu_c(nu) of each noble curve (convergents up to ``qmax``); the sections at 0.99 and 1.01 mu_c of
    the last to break (``starts`` orbits on p2 = 0, ``crossings`` each), both in the window of the first."""
    import explorer as ex
    from explorer.analysis import greene_section as gs

    h = model.FIGURE4_H
    smap = ex.SectionMap(model.FIGURE4.with_(mu=MU0), h)
    results = [ex.greene(smap, f"noble:{a}", qmax=qmax, around=AROUND) for a in nobles]
    last = max(results, key=lambda r: r.critical)
    panels = []
    for factor in (0.99, 1.01):
        m = smap.with_parameter(factor * last.critical)
        c = gs.island_centre(m, AROUND)
        cv = last.convergents[-1]
        orb = gs.section_symmetric_orbit(m, cv["q"], cv["point_at_critical"][0])
        # starts on p2 = 0 from the centre across the curve's far crossing (where the curves are spread)
        p1 = np.linspace(c[0] - 0.01, orb.points[:, 0].min() - 0.2 * (c[0] - orb.points[:, 0].min()), starts)
        ok = np.array([model.is_admissible(m.params, x, 0.0, h) for x in p1])
        res = ex.crossings(m, np.column_stack([p1[ok], np.zeros(int(ok.sum()))]), n_crossings=crossings)
        pts = [res.data[i, :res.count[i], 1:3] for i in range(len(res.count))]
        panels.append((factor, m.parameter_value, c, pts, orb.points))
    with _rc():
        fig = _new_figure((11.0, 3.6), dpi=dpi)
        axes = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1, 1.2, 1.2]})
        nu = np.array([r.nu for r in results])
        mc = np.array([r.critical for r in results])
        err = np.array([r.uncertainty for r in results])
        axes[0].errorbar(nu, mc, yerr=err, fmt="o", color="#1f4e9c", ms=4, capsize=2)
        for a, r in zip(nobles, results):
            axes[0].annotate(f"[0; {a.replace(',', ', ')}, 1, 1, ...]", (r.nu, r.critical), textcoords="offset points",
                             xytext=(4, 4), fontsize=_SMALL)
        axes[0].set_xlabel(r"rotation number $\nu$ around the centre (turns per return)")
        axes[0].set_ylabel(r"$\mu_c(\nu)$")
        axes[0].set_title("Greene's criterion, right island", fontsize=_FS)
        window = _window(panels[0])
        for ax, (factor, mu, c, pts, conv_pts) in zip(axes[1:], panels):
            for p in pts:
                ax.plot(p[:, 0], p[:, 1], ",", color="k", alpha=0.6, rasterized=True)
            ax.plot(conv_pts[:, 0], conv_pts[:, 1], "o", color="#b2182b", ms=2.5,
                    label=rf"{last.convergents[-1]['p']}/{last.convergents[-1]['q']} orbit (convergent)")
            ax.plot([c[0]], [c[1]], "+", color="#1f4e9c", ms=7)
            ax.set_title(rf"$\mu = {factor:g}\,\mu_c = {mu:.6f}$, $\nu = {last.nu:.5f}$", fontsize=_FS)
            ax.set_xlabel("$p_1$")
            ax.set_ylabel("$p_2$")
            ax.legend(fontsize=6, frameon=False, loc="upper left")
            ax.set_xlim(window[0])
            ax.set_ylim(window[1])
    data = {"nu": nu, "mu_c": mc, "uncertainty": err, "last": last.as_dict(), "window": window,
            "section_limits": [(ax.get_xlim(), ax.get_ylim()) for ax in axes[1:]],
            "curves": [r.as_dict() for r in results]}
    return Drawn(fig, data)


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = breakup_figure(nobles=QUICK_NOBLES if quick else NOBLES, qmax=20 if quick else QMAX,
                       starts=12 if quick else 40, crossings=150 if quick else 600)
    line = ", ".join(f"nu = {n:.5f}: mu_c = {m:.7f}" for n, m in zip(d.data["nu"], d.data["mu_c"]))
    return Outcome(NAME, "written", save(d, out_dir, NAME), line, d.data)
