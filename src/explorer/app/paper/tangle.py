"""The homoclinic tangle of the central saddle with the turnstile's lobes shaded, and the flux
across the broken separatrix against the Melnikov prediction (docs/manifolds.md)."""
import numpy as np

from explorer import model
from explorer.app.paper._common import _FS, _SMALL, Drawn, Outcome, _new_figure, _rc, save

#: the figure's name (``explorer figures --only tangle``) and what it shows
NAME = "tangle"
DESCRIPTION = "the homoclinic tangle of the central saddle (mu = 0.03) with its lobes, and the flux against Melnikov"
#: the scene: Figure 4 (docs/model.md R9) at mu = 0.03, h = 2
MU, H = 0.03, 2.0
#: mu values of the flux curve (full run: from 1e-3 until the central saddle is lost,
#: transport.DEFAULT_FLUX_MUS; --quick)
FLUX_MUS = None
QUICK_MUS = (1e-3, 1e-2)


def tangle_figure(*, quick=False, dpi=200) -> Drawn:
    from explorer.analysis import fixedpoints, manifolds, transport
    from explorer.analysis.section_map import SectionMap

    smap = SectionMap(model.FIGURE4.with_(mu=MU), H)
    fp = fixedpoints.find_fixed_point(smap, (0.0, 0.0))
    sd = manifolds.saddle(smap, fp)
    # W^u_+ meets W^s_+ here (transport.turnstile finds the pair in general)
    draw = manifolds.manifolds(smap, fp, arclength=6.0 if quick else 10.0)
    hs = manifolds.homoclinic_points(draw[0], draw[2])
    t = {"lobes": transport.lobes(draw[0], draw[2], points=hs), "homoclinic_points": hs}
    rows = transport.flux_curve(model.FIGURE4, H, QUICK_MUS if quick else FLUX_MUS, max_arclength=24.0)
    # transit times through the resonance zone at this mu: the stickiness tail
    h0 = max((p for p in hs if abs(p.point[1]) < 1e-9), key=lambda p: abs(p.point[0]))
    tt = transport.exit_times(draw[0], draw[2], h0, samples=1000 if quick else 4000, max_iter=100 if quick else 1000)
    e = model.allowed_ellipse(model.FIGURE4.with_(mu=MU), H)
    data = {"lobes": [lb.as_dict() for lb in t["lobes"]], "flux": list(rows), "destruction": rows.destruction,
            "stop_reason": rows.stop_reason,
            "homoclinic_points": [h.point.tolist() for h in hs],
            "transit": {k: tt[k] for k in ("mean", "sem", "accessible_area", "accessible_sem", "entry", "capped")}}
    with _rc():
        fig = _new_figure((13.5, 3.6), dpi=dpi)
        axs = fig.subplots(1, 4, gridspec_kw={"width_ratios": [1.5, 1.0, 1.0, 1.0]})
        ax = axs[0]
        if e is not None:
            c1, c2, r1, r2 = e
            th = np.linspace(0, 2 * np.pi, 400)
            ax.plot(c1 + r1 * np.cos(th), c2 + r2 * np.sin(th), color="0.5", lw=0.6)
        for b in draw:
            col = "#b2182b" if b.kind == "unstable" else "#1f4e9c"
            ax.plot(b.points[:, 0], b.points[:, 1], color=col, lw=0.5 if b.sign < 0 else 0.8,
                    alpha=0.6 if b.sign < 0 else 1.0)
        for lb, col in zip(t["lobes"], ("#fdae61", "#abd9e9")):
            ax.fill(lb.boundary[:, 0], lb.boundary[:, 1], color=col, alpha=0.85, lw=0)
        hp = np.array(data["homoclinic_points"]).reshape(-1, 2)
        ax.plot(hp[:, 0], hp[:, 1], "o", ms=2.5, color="k")
        ax.plot(*sd.point, "+", ms=7, color="k")
        ax.set_xlabel("$p_1$")
        ax.set_ylabel("$p_2$")
        ax.set_aspect("equal", adjustable="datalim")
        area = abs(t["lobes"][0].area) if t["lobes"] else float("nan")
        ax.set_title(rf"(a) $W^u$ (red), $W^s$ (blue), $\mu = {MU:g}$: lobe area {area:.5f}", fontsize=_FS)
        ok = [r for r in rows if r["status"] == "ok"]
        mus = np.array([r["mu"] for r in ok])
        ax = axs[1]
        ax.loglog(mus, [r["flux"] for r in ok], "o", mfc="none", color="k", label="lobe area (Green)")
        eye = [r for r in rows if r["eye_flux"] is not None and r["eye_flux"] > 0]
        if eye:   # the entry set of the eye (Monte Carlo): torn or non-simple turnstiles too
            ax.errorbar([r["mu"] for r in eye], [r["eye_flux"] for r in eye], yerr=[r["eye_error"] for r in eye],
                        fmt="^", ms=3, color="#2166ac", lw=0.6, label="entry set of the eye (Monte Carlo)")
        every = [r["mu"] for r in rows]
        mm = np.geomspace(min(every), max(every), 50)
        slope = ok[0]["melnikov"] / ok[0]["mu"]
        ax.loglog(mm, slope * mm, color="#b2182b", lw=0.9, label=r"Melnikov $2\lambda\mu|J|$")
        torn = [r["mu"] for r in rows if r["reason"] == transport.REASON_TORN]
        if torn:
            ax.axvspan(min(torn), max(torn), color="0.9", lw=0, zorder=0, label="turnstile torn by the section edge")
        if rows.destruction is not None:
            ax.axvline(rows.destruction, color="0.3", lw=0.8, ls=":",
                       label=rf"saddle lost, $\mu = {rows.destruction:g}$")
        ax.set_xlabel(r"$\mu$")
        ax.set_ylabel("flux per iteration")
        ax.set_title("(b) flux across the broken separatrix", fontsize=_FS)
        ax.legend(loc="upper left", fontsize=_SMALL, frameon=False)
        ax = axs[2]
        dev = np.array([abs(r["ratio"] - 1.0) for r in ok])
        ax.loglog(mus, dev, "s", mfc="none", color="k", label="|area / Melnikov - 1|")
        k = np.median(dev / mus ** 2)
        ax.loglog(mm, k * mm ** 2, color="0.4", lw=0.8, ls="--", label=rf"${k:.3f}\,\mu^2$")
        ax.set_xlabel(r"$\mu$")
        ax.set_title("(c) the ratio tends to 1", fontsize=_FS)
        ax.legend(loc="upper left", fontsize=_SMALL, frameon=False)
        ax = axs[3]
        ts, surv = tt["survival"]
        ok_s = surv > 0
        ax.loglog(ts[ok_s], surv[ok_s], "-", drawstyle="steps-post", color="k", lw=0.9)
        phi = abs(t["lobes"][0].area) if t["lobes"] else float("nan")
        ax.set_xlabel("transit time $T$ (iterations)")
        ax.set_ylabel(r"$P(T > t)$ over the entry set")
        ax.set_title(rf"(d) transit times, $\mu = {MU:g}$", fontsize=_FS)
        ax.text(0.04, 0.04, rf"$\langle\min(T, N)\rangle = {tt['mean']:.2f} \pm {tt['sem']:.2f}$" "\n"
                rf"$A_{{acc}}/\Phi = {tt['accessible_area'] / phi:.2f}$, {tt['entry']} entries",
                transform=ax.transAxes, fontsize=_SMALL, va="bottom")
        fig.suptitle(rf"Homoclinic tangle and transport, Figure 4 scene, $h = {H:g}$", fontsize=_FS)
    return Drawn(fig, data)


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = tangle_figure(quick=quick)
    ratios = [r["ratio"] for r in d.data["flux"] if r["ratio"] is not None]
    msg = f"flux / Melnikov from {ratios[0]:.8f} to {ratios[-1]:.8f}" if ratios else "no lobes"
    if d.data["destruction"] is not None:
        msg += f"; the central saddle is lost at mu = {d.data['destruction']:g}"
    return Outcome(NAME, "written", save(d, out_dir, NAME), msg, d.data)
