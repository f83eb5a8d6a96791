"""Chaos maps drawn as rasters on their grid: one image cell per seed of a ``[lyapunov]
map_resolution`` scene, coloured by the chosen indicator, redrawn from the store alone."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.analysis.sweep import map_raster
from explorer.app.figures import (
    _FONT_SIZE,
    _TICK_SIZE,
    BOUNDARY_COLOR,
    BOUNDARY_WIDTH,
    FORBIDDEN_COLOR,
    PANEL_WIDTH,
    _matplotlib,
    mathtext_label,
    panel_axes,
    symbol_label,
)


@dataclass(frozen=True)
class Style:
    """How a chaos indicator is drawn: its colour bar's label (matplotlib mathtext), colour
    scale (logarithmic?, lower end, upper end or None for the data's maximum) and colour map
    (chaotic orbits dark: ``inferno_r`` when the indicator grows with chaos)."""

    label: str
    log: bool
    vmin: float
    vmax: float | None
    cmap: str


#: the style of each indicator of the registry (explorer.kernels.indicator_table, by name;
#: tests/app/test_indicator_registry.py checks every name has one)
STYLES = {
    "mlce": Style(r"finite-time mLCE $\chi(T)$", True, 1e-4, None, "inferno_r"),
    "megno": Style(r"mean MEGNO $\langle Y\rangle$", True, 0.5, None, "inferno_r"),
    "fli": Style("FLI", False, 0.0, None, "inferno_r"),
    "sali": Style("SALI", True, 1e-16, 2.0, "inferno"),
    "gali2": Style(r"GALI$_2$", True, 1e-16, 1.0, "inferno"),
    # log10 |nu1 - nu2|: tori below -10 (round-off of the weighted Birkhoff average), chaos -5 to 0
    "frequency_diffusion": Style(r"frequency diffusion $\log_{10}|\nu_1 - \nu_2|$", False, -14.0, 0.0, "inferno_r"),
}
#: colour scale of each indicator: (label, log scale, vmin, vmax or None for the data's max)
SCALES = {name: (s.label, s.log, s.vmin, s.vmax) for name, s in STYLES.items()}
SEPARATRIX_COLOR = "#1f77b4"


def axis_label(name) -> str:
    """The mathtext of a coordinate's name: the model's symbols (``p1`` -> ``$p_1$``), else the name
    in italics with a trailing number, or the letter after a momentum's ``p``, as subscript (``q2`` ->
    ``$q_{2}$``, ``py`` -> ``$p_{y}$``)."""
    label = symbol_label(name)
    if label != str(name):
        return label
    if len(str(name)) == 2 and str(name)[0] == "p" and str(name).isalpha():
        return f"$p_{{{name[1]}}}$"
    head = str(name).rstrip("0123456789")
    tail = str(name)[len(head):]
    return f"${head}_{{{tail}}}$" if head and tail and head.isalpha() else \
        (f"${name}$" if str(name).isalpha() else str(name))


#: the colour bar's ticks of a MEGNO scale saturated at an early stop's level
SATURATED_TICKS = (0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 15.0, 20.0)


def _stopped(m) -> np.ndarray:
    """Per seed: did its orbit stop early as chaotic (the map's ``stopped``, False when absent)?"""
    values = np.asarray(m["values"], float)
    s = m.get("stopped")
    return np.zeros(values.shape, bool) if s is None else np.asarray(s, bool).reshape(values.shape)


def _unstopped(m) -> np.ndarray:
    """The map's values with its early-stopped orbits left out (NaN)."""
    return np.where(_stopped(m), np.nan, np.asarray(m["values"], float))


def chaos_rasters(maps, *, indicator="megno", threshold=4.0, columns=None, dpi=200, panel_width=PANEL_WIDTH):
    """One raster per map: dicts with ``seeds`` (N, 2), ``values`` (N,) of ``indicator``,
    ``grid`` (resolution, p1_lo, p1_hi, p2_lo, p2_hi), ``params``, ``h``, ``phi0``, ``label``,
    optional ``curves`` (separatrix polylines (p1, p2)), ``fraction`` (chaotic fraction; ``classified``
    says by what, default MEGNO > ``threshold``) and
    ``computed`` (the fraction of cells computed, not filled, of an adaptive map: written in a corner).
    Cells without a seed (outside the allowed region) are drawn gray.  A System's map (docs/systems.md):
    ``params`` None (no ellipse of Chaplygin's model) and ``axes``, the names of its coords."""
    mpl = _matplotlib()
    from matplotlib.colors import LogNorm, Normalize
    from matplotlib.patches import Ellipse

    if indicator not in SCALES:
        raise ValueError(f"indicator must be one of {', '.join(SCALES)}; got {indicator!r}")
    n = len(maps)
    if n == 0:
        raise ValueError("chaos_rasters needs at least one map")
    label, log, vmin, vmax = SCALES[indicator]
    free = [_unstopped(m) for m in maps]
    if vmax is None:
        finite = [float(np.nanmax(v)) for v in free if np.isfinite(v).any()]
        vmax = max([vmin * 20 if log else 1.0] + finite)
    # MEGNO maps whose chaotic orbits stopped early at <Y> > level: the scale saturates at the level, so the
    # stopped orbits and the cells filled from them are drawn alike (their <Y> at the stop is not <Y>(T))
    levels = [m["stop_level"] for m in maps if m.get("stop_level") and _stopped(m).any()]
    saturated = indicator == "megno" and bool(levels)
    if saturated:
        vmax = min(levels)
    # an orbit stopped early is chaotic (docs/scenes.md, early classification): its value at the stop
    # is not its value at T, so it is drawn at the scale's chaotic end (the dark end of the colour map)
    chaotic_end = vmax if STYLES[indicator].cmap.endswith("_r") else vmin
    norm = LogNorm(vmin=vmin, vmax=vmax) if log else Normalize(vmin=vmin, vmax=vmax)
    cmap = mpl.colormaps[STYLES[indicator].cmap].with_extremes(
        bad=FORBIDDEN_COLOR)
    ncols = min(n, 3 if columns is None else int(columns))
    nrows = -(-n // ncols)
    with mpl.rc_context({"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6}):
        fig, axes = panel_axes(n, ncols, (panel_width * ncols + 0.9, 0.9 * panel_width * nrows + 0.3), dpi)
        im = None
        for ax, m in zip(axes, maps):
            res, a1, b1, a2, b2 = m["grid"]
            stopped = _stopped(m)
            vals = np.where(stopped, chaotic_end, np.asarray(m["values"], float))
            if log:
                vals = np.clip(vals, vmin, None)
            img = map_raster(np.asarray(m["seeds"], float), vals, m["grid"])
            ax.set_facecolor(FORBIDDEN_COLOR)
            im = ax.imshow(np.ma.masked_invalid(img), origin="lower", extent=(a1, b1, a2, b2), cmap=cmap, norm=norm,
                           interpolation="nearest", aspect="equal", zorder=1)
            prm = m.get("params")
            if isinstance(prm, dict):
                prm = model.Params(**prm)
            region = None if prm is None else model.allowed_ellipse(prm, m["h"], m.get("phi0", math.pi))
            if region is not None:
                c1, c2, r1, r2 = region
                ax.add_patch(Ellipse((c1, c2), 2 * r1, 2 * r2, facecolor="none", edgecolor=BOUNDARY_COLOR,
                                     linewidth=BOUNDARY_WIDTH, zorder=3))
            for c in m.get("curves", ()) or ():
                c = np.asarray(c, float)
                if len(c):
                    ax.plot(c[:, 0], c[:, 1], color=SEPARATRIX_COLOR, linewidth=0.5, zorder=2)
            ax.set_xlim(a1, b1)
            ax.set_ylim(a2, b2)
            title = mathtext_label(m.get("label", ""))
            if m.get("fraction") is not None and math.isfinite(m["fraction"]):
                title += f"   chaotic {m['fraction']:.1%} ({m.get('classified') or f'MEGNO > {threshold:g}'})"
            ax.set_title(title, fontsize=_FONT_SIZE, pad=4)
            xlabel, ylabel = (axis_label(a) for a in m.get("axes", ("p1", "p2")))
            ax.set_xlabel(xlabel, fontsize=_FONT_SIZE)
            ax.set_ylabel(ylabel, fontsize=_FONT_SIZE)
            ax.tick_params(direction="in", top=True, right=True, labelsize=_TICK_SIZE)
            size = f"{int(res)}$\\times${int(res)}"
            if m.get("computed") is not None and m["computed"] < 1.0:
                size += f", {m['computed']:.1%} of cells computed (adaptive)"
            if stopped.any():
                size += f"\n{stopped.mean():.1%} stopped early (chaotic)"
                if saturated:
                    size += rf", $\langle Y\rangle$ > {vmax:g}: the scale's top"
            ax.text(0.01, 0.01, size, transform=ax.transAxes, fontsize=_TICK_SIZE - 1, va="bottom", ha="left", zorder=4,
                    in_layout=False)
        if im is not None:
            cb = fig.colorbar(im, ax=list(axes[:n]), shrink=0.9, pad=0.01, extend="max" if saturated else "neither")
            cb.set_label(label, fontsize=_FONT_SIZE)
            if saturated:   # a short log scale: plain ticks, not powers of ten
                cb.ax.minorticks_off()
                ticks = [v for v in SATURATED_TICKS if vmin <= v <= vmax]
                cb.set_ticks(ticks, labels=[f"{v:g}" for v in ticks])
            cb.ax.tick_params(labelsize=_TICK_SIZE)
    return fig
