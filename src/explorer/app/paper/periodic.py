"""A Figure 4 panel (mu = 0.03, h = 2) with its island chains marked by period, and the
rotation-number profile from the elliptic fixed point beside it."""
import numpy as np

from explorer import model
from explorer.app.paper._common import _FS, _SMALL, Drawn, Outcome, _new_figure, _rc, save
from explorer.integrate.methods import DEFAULT_TOL

#: the figure's name (``explorer figures --only periodic``) and what it shows
NAME = "periodic"
DESCRIPTION = "Figure 4 at mu = 0.03: periodic orbits of periods 1..8 marked, rotation-number profile"

#: the elliptic fixed point of the scene (Newton refines it) and the end of the profile segment
CENTER_GUESS = (1.5822, 0.0)
PROFILE_END = (0.9, 0.0)
#: the profile starts this far from the elliptic point towards PROFILE_END: at the point itself the
#: angle around it is undefined (no rotation number: docs/commands/rotation.md), next to it the
#: rotation number is the linear one, arccos(trace / 2) / 2 pi
PROFILE_START = 1e-6


#: the figure's size (inches) and its panels' widths: the section, the rotation profile
FIGSIZE = (9.0, 4.7)
WIDTH_RATIOS = (1.35, 1)
#: one colour per period K (cycled)
PERIOD_COLOURS = ("#000000", "#1f4e9c", "#b2182b", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
                  "#17becf", "#7f7f7f")

#: how an orbit's kind is drawn (:attr:`explorer.analysis.periodic.PeriodicOrbit.kind`, or degenerate:
#: not isolated at the map's accuracy): elliptic filled circles, hyperbolic crosses, parabolic
#: plus signs, degenerate open squares; the colour is the period's
_KINDS = {
    "elliptic": dict(marker="o", ms=3.2, mew=0.7, filled=True, label="elliptic"),
    "hyperbolic": dict(marker="x", ms=2.8, mew=0.7, filled=False, label="hyperbolic"),
    "parabolic": dict(marker="+", ms=3.4, mew=0.7, filled=False, label="parabolic"),
    "degenerate": dict(marker="s", ms=3.4, mew=0.5, filled=False, label="degenerate (not isolated)"),
}


#: the kinds' markers in the legend: grey, a colour no period has (K = 1 is black)
_KIND_GREY = "0.5"


def period_legend(ax, colours, kinds):
    """The left panel's legend, below the axes so that it hides no orbit: one colour per period
    (``colours``: {K: colour}) and one marker, in grey, per kind drawn (``kinds``, keys of
    :data:`_KINDS`, listed in that table's order)."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], ls="none", marker="o", ms=4, color=col, label=f"K = {K}")
               for K, col in colours.items()]
    handles += [Line2D([], [], ls="none", marker=st["marker"], ms=st["ms"] + 0.8, mew=st["mew"], color=_KIND_GREY,
                       mfc=_KIND_GREY if st["filled"] else "none", label=st["label"])
                for kind, st in _KINDS.items() if kind in kinds]
    return ax.legend(handles=handles, fontsize=6, frameon=False, loc="upper center", bbox_to_anchor=(0.5, -0.13),
                     ncol=6, title="period (colour) and kind (marker)", title_fontsize=6, handletextpad=0.2,
                     columnspacing=1.0)


def periodic_figure(params=None, h=None, *, periods=range(1, 9), seeds=40, crossings=400, profile_n=120,
                    iterates=2000, grid=12, dpi=200) -> Drawn:
    """Left: the crossings of ``seeds`` orbits and the periodic orbits of each period in ``periods``
    (one colour per period, one marker per kind).  Right: the rotation number along p2 = 0 from the
    elliptic fixed point, with the levels m/K of the elliptic orbits found."""
    from explorer.analysis import periodic, rotation, sections
    from explorer.analysis.fixedpoints import find_fixed_point

    prm = model.FIGURE4.with_(mu=0.03) if params is None else params
    h = model.FIGURE4_H if h is None else h
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h)
    p1s = c1 + r1 * np.linspace(-0.97, 0.97, seeds)
    cr = sections.crossings(prm, h, np.column_stack([p1s, np.zeros_like(p1s)]), n_crossings=crossings,
                            tol=DEFAULT_TOL)
    pts = cr.data[..., 1:3].reshape(-1, 2)
    pts = pts[np.isfinite(pts[:, 0])]
    orbits = {K: periodic.search_periodic_orbits(prm, h, K, grid=grid) for K in periods}
    center = find_fixed_point(prm, h, CENTER_GUESS)
    out = np.asarray(PROFILE_END) - center.point
    start = center.point + PROFILE_START * out / np.linalg.norm(out)
    prof = rotation.rotation_profile(prm, h, start, PROFILE_END, n=profile_n, center=center.point,
                                     iterates=iterates)
    levels = {}   # m/K of the elliptic orbits found whose level the profile reaches (a plateau)
    reached = prof.rotation[prof.converged]
    for K, obs in orbits.items():
        for o in obs:
            if o.kind == "elliptic" and not o.degenerate:
                r = rotation.orbit_rotation(o.points, center.point)
                if np.any(np.abs(reached - r) < 1e-8):
                    levels.setdefault(round(r * K) / K, (round(r * K), K))
    colour = {K: PERIOD_COLOURS[(K - 1) % len(PERIOD_COLOURS)] for K in orbits}   # the levels' K are among them
    with _rc():
        fig = _new_figure(FIGSIZE, dpi=dpi)
        ax, bx = fig.subplots(1, 2, gridspec_kw={"width_ratios": WIDTH_RATIOS})
        t = np.linspace(0, 2 * np.pi, 400)
        ax.set_facecolor("0.85")            # outside the allowed region: gray (as in Figure 4)
        ax.fill(c1 + r1 * np.cos(t), c2 + r2 * np.sin(t), color="white", lw=0, zorder=0)
        ax.plot(pts[:, 0], pts[:, 1], ",", color="0.55", zorder=1, rasterized=True)
        kinds = set()
        for K, obs in orbits.items():
            col = colour[K]
            for o in obs:
                # degenerate: not isolated at the map's accuracy (a point of a resonant curve)
                kind = "degenerate" if o.degenerate else o.kind
                kinds.add(kind)
                style = _KINDS[kind]
                ax.plot(o.points[:, 0], o.points[:, 1], style["marker"], ms=style["ms"], color=col,
                        mfc=col if style["filled"] else "none", mew=style["mew"], zorder=3)
        ax.plot(*np.array([center.point, PROFILE_END]).T, "-", color="k", lw=0.5, zorder=2)
        ax.set_xlim(c1 - 1.05 * r1, c1 + 1.05 * r1)
        ax.set_ylim(c2 - 1.05 * r2, c2 + 1.05 * r2)
        ax.set_xlabel("$p_1$")
        ax.set_ylabel("$p_2$")
        period_legend(ax, colour, kinds)
        ax.set_title(rf"$\varphi = \pi$, $\mu = {prm.mu:g}$, $h = {h:g}$: periodic orbits", fontsize=_FS)
        conv = prof.converged
        x = prof.points[:, 0]
        # not converged: chaotic, or a regular orbit that needs more returns
        bx.plot(x[~conv], prof.rotation[~conv], ".", color="0.7", ms=2.5,
                label=f"not converged in {iterates} returns (chaotic, or too few returns)")
        bx.plot(x[conv], prof.rotation[conv], ".", color="k", ms=2.5, label="converged to 1e-10")
        for lev, (m, K) in sorted(levels.items()):
            bx.axhline(lev, color=colour[K], lw=0.6, ls="--")
            # at the left edge, where the profile lies above every plateau
            bx.text(0.01, lev, f"{m:d}/{K}: island chain of period {K}", fontsize=_SMALL, va="top", ha="left",
                    color=colour[K], transform=bx.get_yaxis_transform())
        bx.set_xlabel("$p_1$ on $p_2 = 0$ (from the elliptic fixed point)")
        bx.set_ylabel("rotation number (turns per return)")
        bx.invert_xaxis()
        bx.legend(fontsize=6, frameon=False, loc="lower left")
        bx.set_title("weighted Birkhoff rotation number", fontsize=_FS)
    data = {"orbits": {K: [o.as_dict() for o in obs] for K, obs in orbits.items()},
            "counts": {K: len(obs) for K, obs in orbits.items()}, "levels": levels,
            "center": center.point.tolist(), "rotation": prof.rotation, "converged": prof.converged}
    return Drawn(fig, data)


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    # quick: fewer profile orbits and returns (those near the island's edge cost the most)
    kw = dict(periods=range(1, 4), seeds=16, crossings=150, profile_n=16, iterates=300, grid=6) if quick else {}
    d = periodic_figure(**kw)
    counts = ", ".join(f"K={K}: {n}" for K, n in d.data["counts"].items())
    return Outcome(NAME, "written", save(d, out_dir, NAME), f"orbits {counts}", d.data)
