"""The central fixed point of the section map continued in mu, with its trace and the
values where its stability changes."""

import numpy as np

from explorer import model
from explorer.app.paper._common import _FS, _SMALL, Drawn, Outcome, _new_figure, _rc, save

#: the figure's name (``explorer figures --only continuation``) and what it shows
NAME = "continuation"
DESCRIPTION = "the central fixed point continued in mu, its trace and stability changes"


def continuation_figure(params=None, h=None, *, start=0.0, stop=8.0, step=0.1, dpi=200,
                        marks=(0.002, 0.01, 0.03, 4.0, 8.0), refine_min=True) -> Drawn:
    """The central fixed point of the section map phi = pi at h = 2 continued in mu
    (:func:`explorer.analysis.fixedpoints.continue_branch`): its p1 and the monodromy trace against mu,
    the lines trace = +-2, the value where it turns stable; the analytic trace of solution I at
    mu = 0 (:func:`fixedpoints.analytic_eigenvalues_solution_I`); ticks at Figure 4's mu."""
    from explorer.analysis import fixedpoints

    prm = model.FIGURE4 if params is None else params
    h = model.FIGURE4_H if h is None else h
    br = fixedpoints.continue_branch(prm, h, "mu", start, stop, step)
    mu = np.asarray(br.values, float)
    p1 = np.array([fp.point[0] for fp in br.orbits])
    p2 = np.array([fp.point[1] for fp in br.orbits])
    tr = np.array([fp.trace for fp in br.orbits])
    _ev, tr0 = fixedpoints.analytic_eigenvalues_solution_I(prm.with_(mu=0.0), h)
    stable = np.abs(tr) < 2
    # the continuation's one bifurcation detector: crossings of |trace| = 2 (vertical lines) and
    # touches of -2 (annotated), as `fixedpoint --continue` and `periodic -K 1 --continue` print them
    changes = [b["value"] for b in br.bifurcations if not b["type"].startswith("touch")]
    touches = [(b["value"], b["trace"]) for b in br.bifurcations if b["type"] == "touch -2"]
    tmin = touches[0] if (refine_min and touches) else None
    with _rc():
        fig = _new_figure((5.0, 4.6), dpi=dpi)
        ax1, ax2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [1, 1.3]})
        for ax in (ax1, ax2):
            for b in changes:
                ax.axvline(b, color="0.45", lw=0.8, ls="--", zorder=1)
        c1s = np.array([model.allowed_ellipse(prm.with_(mu=m), h)[0] for m in mu])
        ax1.plot(mu, c1s, color="0.6", lw=0.8, ls=":", label=r"centre of the allowed region, $-a_1\mu/\lambda$")
        ax1.plot(mu[~stable], p1[~stable], "o", color="#b2182b", ms=2.6, label="hyperbolic (unstable)")
        ax1.plot(mu[stable], p1[stable], "o", color="#1f4e9c", ms=2.6, label="elliptic (stable)")
        ax1.set_ylabel("$p_1$ of the fixed point")
        ax1.legend(fontsize=6, frameon=False, loc="lower left")
        ax1.text(0.98, 0.94, rf"$p_2 = 0$ (max $|p_2|$ = {np.max(np.abs(p2)):.0e})", transform=ax1.transAxes,
                 ha="right", va="top", fontsize=6)
        ax2.axhspan(-2, 2, color="0.9", lw=0, zorder=0)
        ax2.axhline(2, color="0.3", lw=0.7)
        ax2.axhline(-2, color="0.3", lw=0.7)
        ax2.plot(mu, tr, "-", color="k", lw=1.0, zorder=2)
        ax2.plot(mu[~stable], tr[~stable], "o", color="#b2182b", ms=2.6, zorder=3)
        ax2.plot(mu[stable], tr[stable], "o", color="#1f4e9c", ms=2.6, zorder=3)
        ax2.plot([0.0], [tr0], "*", color="k", ms=9, mfc="none", zorder=4, clip_on=False,
                 label=rf"solution I, linearised R6: $2\cosh(\sqrt{{-\alpha\beta}}\,T)$ = {tr0:.5g}")
        for b in changes:
            ax2.annotate(rf"$\mu^* = {b:.6g}$", xy=(b, 2), xytext=(b + 0.25, 5.0), fontsize=_SMALL,
                         arrowprops=dict(arrowstyle="->", lw=0.6))
        ax2.text(stop * 0.98, 1.55, "stable: $|\\mathrm{tr}| < 2$", ha="right", va="center", fontsize=_SMALL,
                 color="0.3")
        ax2.set_ylabel("trace of the monodromy")
        ax2.set_xlabel(r"$\mu$")
        ax2.legend(fontsize=6, frameon=False, loc="upper right")
        ax2.set_xlim(start, stop)
        for ax in (ax1, ax2):
            ax.minorticks_on()
        ax1.plot(list(marks), [1.0] * len(marks), "v", color="#b2182b", ms=4, clip_on=False, zorder=5,
                 transform=ax1.get_xaxis_transform(), label=r"the $\mu$ of Figure 4's panels")
        ax1.legend(fontsize=6, frameon=False, loc="lower left")
        if tmin is not None:
            ax2.annotate(f"least trace at $\\mu = {tmin[0]:.4f}$: tr + 2 = {tmin[1] + 2:.0e},\n"
                         "touches $-2$ to round-off, no crossing (1:2 resonance)", xy=(tmin[0], tmin[1]),
                         xytext=(6.35, -0.55), fontsize=6, ha="center", va="center",
                         arrowprops=dict(arrowstyle="->", lw=0.5))
        ax1.set_title(rf"central fixed point of $\varphi = \pi$, $h = {h:g}$ (Figure 4's scene)", fontsize=_FS)
    data = {"mu": mu, "p1": p1, "p2": p2, "trace": tr, "bifurcations": changes, "trace_mu0": tr0,
            "trace_min": tmin}
    return Drawn(fig, data)


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = continuation_figure(step=0.2 if quick else 0.1)
    b = ", ".join(f"{v:.8g}" for v in d.data["bifurcations"])
    return Outcome(NAME, "written", save(d, out_dir, NAME), f"stability changes at mu = {b}", d.data)
