"""The page's view as a PNG or SVG by matplotlib, each orbit's SVG id ``orbit-<id>`` (docs/commands/serve.md)."""
from __future__ import annotations

import io
from dataclasses import dataclass, field

import numpy as np

from explorer.app.serve import style

#: size of the picture (inches) and the PNG's resolution
FIGSIZE = (7.0, 5.6)
DPI = 150
#: above this many crossings in all, the orbits are rasterized in the SVG (~100 bytes a vector point)
SVG_VECTOR_MAX = 200_000
FORMATS = ("png", "svg")


@dataclass
class View:
    """What the page shows: ``orbits`` [(id, colour, points (n, 2), megno)], ``starts`` [(p1, p2, colour)], ``region``
    (c1, c2, r1, r2) or None, drawn as ``region_mask`` over its box if given (else an ellipse), ``raster`` (values,
    window) on ``raster_scale``, ``manifolds`` [(kind, curve)], the marks of the ``periodic`` orbits and of the
    ``fixed`` points (period 1), each [(p1, p2, period, elliptic)]."""

    window: tuple
    region: tuple | None
    orbits: list = field(default_factory=list)
    starts: list = field(default_factory=list)
    raster: tuple | None = None
    raster_scale: tuple = (style.MEGNO_LOW, style.MEGNO_HIGH)
    fixed: list = field(default_factory=list)
    separatrices: list = field(default_factory=list)
    manifolds: list = field(default_factory=list)
    periodic: list = field(default_factory=list)
    by_megno: bool = False
    title: str = ""
    region_mask: np.ndarray | None = None
    axes: tuple = ("p1", "p2")


def figure(view: View):
    """The matplotlib Figure of ``view`` (not registered with pyplot)."""
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.patches import Ellipse

    from explorer.app import figures

    fig = Figure(figsize=FIGSIZE, dpi=DPI, layout="constrained")
    ax = fig.add_subplot()
    ax.set_facecolor(figures.FORBIDDEN_COLOR)
    if view.region is not None:
        c1, c2, r1, r2 = view.region
        if view.region_mask is None:
            ax.add_patch(Ellipse((c1, c2), 2 * r1, 2 * r2, facecolor="white", edgecolor="none", zorder=0.5))
            ax.add_patch(Ellipse((c1, c2), 2 * r1, 2 * r2, facecolor="none", edgecolor=figures.BOUNDARY_COLOR,
                                 linewidth=figures.BOUNDARY_WIDTH, zorder=3))
        else:
            white = np.zeros((*np.shape(view.region_mask), 4))
            white[np.asarray(view.region_mask, bool)] = 1.0
            ax.imshow(white, extent=(c1 - r1, c1 + r1, c2 - r2, c2 + r2), origin="lower", interpolation="nearest",
                      zorder=0.5)
    if view.raster is not None:
        values, extent = view.raster
        cmap = ListedColormap(style.megno_palette()).with_extremes(bad=(0, 0, 0, 0))
        ax.imshow(np.asarray(values, float), extent=extent, origin="lower", cmap=cmap, vmin=view.raster_scale[0],
                  vmax=view.raster_scale[1], alpha=0.85, interpolation="nearest", zorder=1)
    # by MEGNO as on the page: NaN (unknown) gray, outside the scale an end's colour
    orbit_cmap = ListedColormap(style.megno_palette(style.MEGNO_ORBIT_SKIP)).with_extremes(
        bad=style.UNKNOWN_MEGNO_COLOR)
    total = sum(len(pts) for _i, _c, pts, _m in view.orbits)
    raster_points = total > SVG_VECTOR_MAX
    size = 4.0 if total < 20_000 else 1.0
    for ident, colour, pts, megno in view.orbits:
        pts = np.asarray(pts, float).reshape(-1, 2)
        if view.by_megno:
            colour = orbit_cmap((megno - style.MEGNO_LOW) / (style.MEGNO_HIGH - style.MEGNO_LOW))
        ax.scatter(pts[:, 0], pts[:, 1], s=size, c=[colour], linewidths=0, marker="o", zorder=2,
                   rasterized=raster_points, gid=f"orbit-{ident}")
    if view.starts:
        p1, p2, colours = zip(*view.starts)
        ax.scatter(p1, p2, s=40, marker="+", c=list(colours), linewidths=1.5, zorder=4, gid="starts")
    curves = [(f"separatrix-{n}", style.SEPARATRIX_COLOR, c) for n, c in enumerate(view.separatrices)]
    curves += [(f"manifold-{k}-{n}", figures.MANIFOLD_COLORS[k], c) for n, (k, c) in enumerate(view.manifolds)]
    for gid, colour, curve in curves:       # (the manifolds drawn over the separatrices)
        c = np.asarray(curve, float)
        ax.plot(c[:, 0], c[:, 1], color=colour, linewidth=0.8, zorder=2.5, gid=gid)
    for marks, size, width in ((view.periodic, 36, 1.0), (view.fixed, 60, 1.5)):     # (the fixed points larger, over)
        for p1, p2, period, elliptic in marks:
            ax.scatter([p1], [p2], s=size, marker="o" if elliptic else "X", edgecolors="black", linewidths=width,
                       c=[style.PERIOD_COLORS[(int(period) - 1) % len(style.PERIOD_COLORS)]], zorder=5)
    ax.set(xlim=view.window[:2], ylim=view.window[2:], xlabel=figures.symbol_label(view.axes[0]),
           ylabel=figures.symbol_label(view.axes[1]))
    ax.set_aspect("equal", adjustable="box")
    if view.title:
        ax.set_title(figures.mathtext_label(view.title), fontsize=9)
    ax.tick_params(direction="in", top=True, right=True)
    return fig


def render(view: View, fmt: str) -> bytes:
    """``view`` as a PNG or SVG file's bytes (SVG without a date: the same view, the same bytes)."""
    if fmt not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}, got {fmt!r}")
    fig = figure(view)
    buf = io.BytesIO()
    meta = {"Date": None} if fmt == "svg" else {"Software": "explorer serve"}
    fig.savefig(buf, format=fmt, dpi=DPI, facecolor="white", metadata=meta)
    return buf.getvalue()
