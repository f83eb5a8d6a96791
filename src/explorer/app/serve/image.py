"""The page's view as a PNG or SVG by matplotlib, each orbit's SVG id ``orbit-<id>`` (docs/commands/serve.md)."""
from __future__ import annotations

import io
import math
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
    window) on ``raster_scale`` (None: MEGNO's), ``fixed`` [(p1, p2, elliptic)], ``manifolds`` [(kind, curve)],
    ``periodic`` [(p1, p2, period, elliptic)]."""

    window: tuple
    region: tuple | None
    orbits: list = field(default_factory=list)
    starts: list = field(default_factory=list)
    raster: tuple | None = None
    raster_scale: tuple | None = None
    fixed: list = field(default_factory=list)
    separatrices: list = field(default_factory=list)
    manifolds: list = field(default_factory=list)
    periodic: list = field(default_factory=list)
    by_megno: bool = False
    title: str = ""
    region_mask: np.ndarray | None = None
    axes: tuple = ("p1", "p2")


def _megno_colormap(skip: int = 0):
    from matplotlib.colors import ListedColormap

    return ListedColormap(style.megno_palette(skip)).with_extremes(bad=(0, 0, 0, 0))


def figure(view: View):
    """The matplotlib Figure of ``view`` (not registered with pyplot)."""
    from explorer.app import figures

    figures._matplotlib()
    from matplotlib.figure import Figure
    from matplotlib.patches import Ellipse

    fig = Figure(figsize=FIGSIZE, dpi=DPI, layout="constrained")
    ax = fig.add_subplot()
    x0, x1, y0, y1 = view.window
    ax.set_facecolor(figures.FORBIDDEN_COLOR)
    if view.region is not None and view.region_mask is not None:
        c1, c2, r1, r2 = view.region
        white = np.zeros((*np.shape(view.region_mask), 4))
        white[np.asarray(view.region_mask, bool)] = 1.0
        ax.imshow(white, extent=(c1 - r1, c1 + r1, c2 - r2, c2 + r2), origin="lower", interpolation="nearest",
                  zorder=0.5)
    elif view.region is not None:
        c1, c2, r1, r2 = view.region
        ax.add_patch(Ellipse((c1, c2), 2 * r1, 2 * r2, facecolor="white", edgecolor="none", zorder=0.5))
        ax.add_patch(Ellipse((c1, c2), 2 * r1, 2 * r2, facecolor="none", edgecolor=figures.BOUNDARY_COLOR,
                             linewidth=figures.BOUNDARY_WIDTH, zorder=3))
    cmap = _megno_colormap()
    orbit_cmap = _megno_colormap(style.MEGNO_ORBIT_SKIP)
    if view.raster is not None:
        values, (a0, a1, b0, b1) = view.raster
        low, high = view.raster_scale or (style.MEGNO_LOW, style.MEGNO_HIGH)
        ax.imshow(np.asarray(values, float), extent=(a0, a1, b0, b1), origin="lower", cmap=cmap, vmin=low,
                  vmax=high, alpha=0.85, interpolation="nearest", zorder=1)
    total = sum(len(pts) for _i, _c, pts, _m in view.orbits)
    raster_points = total > SVG_VECTOR_MAX
    size = 4.0 if total < 20_000 else 1.0
    for ident, colour, pts, megno in view.orbits:
        pts = np.asarray(pts, float).reshape(-1, 2)
        if view.by_megno:
            u = (megno - style.MEGNO_LOW) / (style.MEGNO_HIGH - style.MEGNO_LOW)    # (outside [0, 1]: an end's colour)
            colour = orbit_cmap(u) if math.isfinite(megno) else "#9e9e9e"
        ax.scatter(pts[:, 0], pts[:, 1], s=size, c=[colour], linewidths=0, marker="o", zorder=2,
                   rasterized=raster_points, gid=f"orbit-{ident}")
    if view.starts:
        s = np.asarray([(a, b) for a, b, _c in view.starts], float)
        ax.scatter(s[:, 0], s[:, 1], s=40, marker="+", c=[c for _a, _b, c in view.starts], linewidths=1.5,
                   zorder=4, gid="starts")
    for n, curve in enumerate(view.separatrices):
        c = np.asarray(curve, float)
        ax.plot(c[:, 0], c[:, 1], color=style.SEPARATRIX_COLOR, linewidth=0.8, zorder=2.5, gid=f"separatrix-{n}")
    for n, (kind, curve) in enumerate(view.manifolds):
        c = np.asarray(curve, float)
        ax.plot(c[:, 0], c[:, 1], color=figures.MANIFOLD_COLORS[kind], linewidth=0.8, zorder=2.6,
                gid=f"manifold-{kind}-{n}")
    for p1, p2, period, elliptic in view.periodic:
        ax.scatter([p1], [p2], s=36, marker="o" if elliptic else "X", edgecolors="black", linewidths=1.0,
                   c=[style.PERIOD_COLORS[(int(period) - 1) % len(style.PERIOD_COLORS)]], zorder=5)
    for p1, p2, elliptic in view.fixed:
        ax.scatter([p1], [p2], s=60, marker="o" if elliptic else "X", edgecolors="black", facecolors="white",
                   linewidths=1.5, zorder=6)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel({"p1": "$p_1$"}.get(view.axes[0], view.axes[0]))
    ax.set_ylabel({"p2": "$p_2$"}.get(view.axes[1], view.axes[1]))
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
