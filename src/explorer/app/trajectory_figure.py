"""Figures of the body in the plane (full system R1, drift ur25, Kozlov's falling body): the
numbers come from :mod:`explorer.analysis.trajectory`, this module only draws them."""
from __future__ import annotations

import math

import numpy as np

from explorer.analysis.trajectory import drift, full_params
from explorer.app.figures import _matplotlib, mathtext_label


def _param_title(prm) -> str:
    parts = [f"{n} = {prm[n]:g}" for n in ("a1", "a2", "b", "lam", "mu")]
    parts += [f"{n} = {prm[n]:g}" for n in ("chi", "zeta", "xi", "eta") if prm[n] != 0.0]
    return mathtext_label(", ".join(parts))


def path_figure(result, params=None, *, glyphs=40, band=None, title=None, dpi=200, width=7.0):
    """The path (x, y) of the body, coloured by time, with ``glyphs`` orientation glyphs (an ellipse
    of semi-axes ~ sqrt(a2) along e1 and sqrt(a1) along e2, at the true angle phi, not to scale), the
    orbit band shaded, the energy band dashed and the measured y range dotted.  ``result``: a
    :func:`trajectory` result; ``band``: the ``band`` of :func:`drift` (computed when lam != 0)."""
    mpl = _matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import EllipseCollection, LineCollection
    from matplotlib.figure import Figure

    prm = full_params(result["params"] if params is None else params)
    ok = np.isfinite(result["x"]) & np.isfinite(result["phi"])
    t, x, y, phi = result["t"][ok], result["x"][ok], result["y"][ok], result["phi"][ok]
    if t.size < 2:
        raise ValueError("path_figure needs at least two finite samples")
    if band is None and prm["lam"] != 0.0:
        band = drift(prm, result["y0"], result["t"][-1], result=result)["band"]
    ylo, yhi = float(y.min()), float(y.max())
    if band is not None:
        ylo = min(ylo, band["centre"] - band["halfwidth_orbit"])
        yhi = max(yhi, band["centre"] + band["halfwidth_orbit"])
        if math.isfinite(band.get("halfwidth_energy", math.inf)):
            ylo = min(ylo, band["centre"] - band["halfwidth_energy"])
            yhi = max(yhi, band["centre"] + band["halfwidth_energy"])
    xr = max(float(x.max() - x.min()), 1e-12)
    yr = max(yhi - ylo, 1e-12)
    to_scale = 0.25 <= yr / xr <= 4.0
    # equal aspect: a figure whose height fits the data (axes width ~ width - 1.7 in)
    height = 0.55 * width if not to_scale else min(max((width - 1.7) * (1.24 * yr) / (1.08 * xr) + 1.2, 2.5), 9.0)
    with mpl.rc_context({"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6}):
        fig = Figure(figsize=(width, height), dpi=dpi, layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.subplots()
        ax.plot(x, y, color="0.25", lw=0.6, zorder=2)
        ax.plot(x[0], y[0], "o", color="tab:green", ms=4, zorder=4, label="start")
        ax.plot(x[-1], y[-1], "s", color="tab:red", ms=4, zorder=4, label="end")
        if band is not None:
            c, hw = band["centre"], band["halfwidth_orbit"]
            ax.axhspan(c - hw, c + hw, color="tab:blue", alpha=0.12, lw=0, zorder=0,
                       label=r"band $c_1/\lambda \pm \max|p-s|/|\lambda|$")
            he = band.get("halfwidth_energy", math.inf)
            if math.isfinite(he):
                for s in (-1, 1):
                    ax.axhline(c + s * he, color="tab:blue", lw=0.7, ls="--", zorder=1,
                               label="energy bound" if s < 0 else None)
            for v in (band["y_min"], band["y_max"]):
                ax.axhline(v, color="0.3", lw=0.6, ls=":", zorder=1,
                           label="measured range of y" if v == band["y_min"] else None)
        ax.set_xlim(x.min() - 0.04 * xr, x.max() + 0.04 * xr)
        ax.set_ylim(ylo - 0.12 * yr, yhi + 0.12 * yr)
        if to_scale:
            ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("$x$")
        ax.set_ylabel("$y$")
        ax.tick_params(direction="in", top=True, right=True, labelsize=8)
        # everything that changes the layout (colour bar, title) comes before measuring the
        # data-to-screen scale used for the e1 segments
        cmap = mpl.colormaps["viridis"]
        norm = mpl.colors.Normalize(vmin=float(t[0]), vmax=float(t[-1]))
        cb = fig.colorbar(mpl.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, pad=0.01, shrink=0.9)
        cb.set_label("$t$")
        head = title if title is not None else "path of the body (R1), orientation glyphs: axis $e_1$"
        if not to_scale:
            head += " (axes not to scale; glyphs at the true angle)"
        ax.set_title(head + "\n" + _param_title(prm), fontsize=9)
        fig.draw_without_rendering()
        fig.set_layout_engine("none")  # freeze the layout: the scale measured here stays valid
        bb = ax.get_window_extent()
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        sx = (x1 - x0) / bb.width   # data units per pixel
        sy = (y1 - y0) / bb.height
        n_gl = max(1, min(int(glyphs), t.size))
        idx = np.unique(np.linspace(0, t.size - 1, n_gl).round().astype(int))
        ang = np.degrees(phi[idx])  # screen angle of e1 = the body's true angle (x right, y up)
        size = 0.16  # inches, longer glyph axis
        r1, r2 = math.sqrt(prm["a2"]), math.sqrt(prm["a1"])
        wd = size * r1 / max(r1, r2)
        ht = size * r2 / max(r1, r2)
        offs = np.column_stack([x[idx], y[idx]])
        ec = EllipseCollection(np.full(idx.size, 2 * wd), np.full(idx.size, 2 * ht), ang, units="inches",
                               offsets=offs, offset_transform=ax.transData, facecolors="none",
                               edgecolors=cmap(norm(t[idx])), linewidths=0.8, zorder=3)
        ax.add_collection(ec)
        # segment along e1 (screen direction), half-length wd inches
        ppi = fig.dpi
        ux, uy = np.cos(np.radians(ang)), np.sin(np.radians(ang))
        dx, dy = ux * wd * ppi * sx, uy * wd * ppi * sy
        segs = np.stack([np.column_stack([x[idx] - dx, y[idx] - dy]),
                         np.column_stack([x[idx] + dx, y[idx] + dy])], axis=1)
        ax.add_collection(LineCollection(segs, colors=cmap(norm(t[idx])), linewidths=1.0, zorder=3))
        ax.legend(fontsize=7, loc="best", framealpha=0.8)
    return fig


def kozlov_figure(kres, params=None, *, title=None, dpi=200):
    """Two panels for lam = 0 (:func:`kozlov` result): the half-amplitude of the oscillation of
    phi about phi_inf vs t and its frequency vs t, log-log, with the fitted power laws (slopes)
    and Kozlov's exponents -1/2 and 1 for comparison; the fit window is marked."""
    mpl = _matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    prm = full_params(kres["result"]["params"] if params is None else params)
    tm, amp, freq, w = kres["t_mid"], kres["amplitude"], kres["frequency"], kres["fit_mask"]
    with mpl.rc_context({"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6}):
        fig = Figure(figsize=(8.0, 3.4), dpi=dpi, layout="constrained")
        FigureCanvasAgg(fig)
        axa, axf = fig.subplots(1, 2)
        tf = np.array([tm[w].min(), tm[w].max()])
        for ax, data, expo, pref, expect, lab in (
                (axa, amp, kres["amplitude_exponent"], kres["amplitude_prefactor"], -0.5,
                 r"half-amplitude of $\varphi - \varphi_\infty$"),
                (axf, freq, kres["frequency_exponent"], kres["frequency_prefactor"], 1.0, "frequency")):
            ax.loglog(tm[~w], data[~w], ".", color="0.6", ms=2, rasterized=True)
            ax.loglog(tm[w], data[w], ".", color="k", ms=2, rasterized=True, label="turning points")
            ax.loglog(tf, pref * tf ** expo, "-", color="tab:red", lw=1.2, label=f"fit: slope {expo:.4f}")
            ref = pref * tf[0] ** expo * (tf / tf[0]) ** expect
            ax.loglog(tf, ref, "--", color="tab:blue", lw=0.9, label=f"Kozlov: slope {expect:g}")
            ax.axvspan(tf[0], tf[1], color="tab:orange", alpha=0.08, lw=0)
            ax.set_xlabel("$t$")
            ax.set_ylabel(lab)
            ax.tick_params(direction="in", which="both", top=True, right=True, labelsize=8)
            ax.legend(fontsize=7)
        head = title if title is not None else (r"falling body ($\lambda = 0$): $\varphi_\infty$ = "
                                                f"{kres['phi_inf_mod_pi']:.4f} (mod $\\pi$)")
        fig.suptitle(head + "\n" + _param_title(prm), fontsize=9)
    return fig
