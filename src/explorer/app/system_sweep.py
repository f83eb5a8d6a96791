"""The figures of a System's sweep (docs/scenes.md, "A scene of your own system"), drawn from the
store: the section points of each panel with the axes named by the map's coords, with the
separatrices and [manifolds] branches computed when drawn, the chaos map
(:func:`explorer.app.chaos_raster.chaos_rasters`) and the chaotic fraction against the swept value.
The sweep itself is :func:`explorer.app.runner.run_sweep`'s."""
from __future__ import annotations

import math

import numpy as np

from explorer.analysis.classification import class_text
from explorer.analysis.sweep import panel_class
from explorer.app import figures
from explorer.app.chaos_raster import axis_label, chaos_rasters
from explorer.io import store
from explorer.model import ParameterError


def system_section_panels(panels, *, axes, layout="row", columns=None, share_scale=True, own_scale=(),
                          marker_size=0.25, dpi=200, window=None):
    """One panel per dict of ``panels`` (``points`` (M, 2), ``label``, optional ``curves``,
    ``manifolds`` and ``note`` as :func:`explorer.app.figures.section_panels` has them): the
    section points, the axes named by ``axes`` (the coords); limits ``window`` (a_lo, a_hi, b_lo,
    b_hi) or the extent of the points and curves (+5 %), shared unless ``share_scale`` is false or
    the panel is in ``own_scale``."""
    mpl = figures._matplotlib()
    n = len(panels)
    ncols = n if layout == "row" else min(n, 3 if columns is None else int(columns))
    boxes = [_box(np.concatenate([np.asarray(p["points"], np.float64).reshape(-1, 2), *p.get("curves", ()),
                                  *(c for _kind, c in p.get("manifolds", ()))]), window) for p in panels]
    shared = _union([b for i, b in enumerate(boxes) if i not in own_scale and b is not None])
    xlabel, ylabel = (axis_label(a) for a in axes)
    with mpl.rc_context({"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6}):
        size = (figures.PANEL_WIDTH * ncols, figures.PANEL_WIDTH * -(-n // ncols))
        fig, axs = figures.panel_axes(n, ncols, size, dpi)
        for i, (ax, p) in enumerate(zip(axs, panels)):
            pts = np.asarray(p["points"], dtype=np.float64).reshape(-1, 2)
            if len(pts):
                ax.plot(pts[:, 0], pts[:, 1], linestyle="none", marker="o", markersize=math.sqrt(marker_size),
                        markeredgewidth=0, color=figures.POINT_COLOR, rasterized=True)
            for c in figures._as_curves(p.get("curves"), i):
                ax.plot(c[:, 0], c[:, 1], zorder=2.5, **figures.CURVE_STYLE)
            for kind, c in figures._as_manifolds(p.get("manifolds"), i):
                ax.plot(c[:, 0], c[:, 1], zorder=2.6, color=figures.MANIFOLD_COLORS[kind], gid=f"manifold-{kind}",
                        **figures.MANIFOLD_STYLE)
            if p.get("note"):
                ax.text(0.03, 0.03, figures.mathtext_label(p["note"]), transform=ax.transAxes,
                        fontsize=figures._NOTE_SIZE, ha="left", va="bottom", zorder=4,
                        bbox=dict(boxstyle="round,pad=0.25", facecolor="white", edgecolor="none", alpha=0.85))
            box = shared if share_scale and i not in own_scale and shared is not None else boxes[i]
            if box is not None:
                ax.set_xlim(*box[0])
                ax.set_ylim(*box[1])
            ax.set_title(figures.mathtext_label(p.get("label", "")), fontsize=figures._FONT_SIZE, pad=4)
            ax.set_xlabel(xlabel, fontsize=figures._FONT_SIZE)
            ax.set_ylabel(ylabel, fontsize=figures._FONT_SIZE)
            ax.tick_params(direction="in", top=True, right=True, labelsize=figures._TICK_SIZE)
    return fig


def _box(points, window):
    if window is not None:
        return (window[0], window[1]), (window[2], window[3])
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if not len(pts):
        return None
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.05 * np.maximum(hi - lo, 1e-3)
    return (lo[0] - pad[0], hi[0] + pad[0]), (lo[1] - pad[1], hi[1] + pad[1])


def _union(boxes):
    if not boxes:
        return None
    return ((min(b[0][0] for b in boxes), max(b[0][1] for b in boxes)),
            (min(b[1][0] for b in boxes), max(b[1][1] for b in boxes)))


def panel_curves(scene, i) -> dict:
    """What panel i of a System's ``scene`` draws over its points, computed now, never stored:
    ``curves``, the separatrices of its map's hyperbolic fixed points ([compute] separatrices,
    :func:`explorer.analysis.system_scene.separatrix_curves`), ``manifolds``, the branches of the
    [manifolds] orbit, and a ``note`` saying why either is missing."""
    from explorer.analysis.system_scene import orbit_branches, separatrix_curves

    out: dict = {}
    notes = []
    smap = scene.section_map(i) if scene.separatrices or scene.manifolds.draw else None
    if scene.separatrices:
        try:
            points, out["curves"] = separatrix_curves(smap)
            if not points:
                notes.append("no hyperbolic fixed point found")
        except ParameterError as exc:
            notes.append(_why("no separatrices", exc))
    if scene.manifolds.draw:
        try:
            out["manifolds"] = orbit_branches(smap, scene.manifolds)
        except ParameterError as exc:
            notes.append(_why("no manifolds", exc))
    if notes:
        out["note"] = "\n".join(notes)
    return out


def _why(what: str, exc: Exception) -> str:
    """A panel's note: ``what``, then the refusal's first clause in at most 60 characters."""
    msg = str(exc).split(" (")[0]
    return f"{what}: " + (msg if len(msg) <= 60 else msg[:57] + "...")


def draw_system_figure(scene, out_path, stem, text=None):
    """Read the store of a System's scene and draw its figures (PNG and PDF, ``text`` chunks in the
    PNG): ``stem`` (sections), ``stem``_map (the map of ``map_indicator`` on a ``map_resolution`` grid) and
    ``stem``_fraction (the stored chaotic fractions of more than one panel).  Returns the paths."""
    data = store.read_store(out_path)
    fs = scene.figure
    paths: list = []
    if "sections" in scene.compute:
        panels = []
        for i in range(scene.n_panels):
            pd = data.panels.get(i)
            pts = pd.crossings[:, 1:3] if pd is not None and len(pd.crossings) else np.zeros((0, 2))
            panels.append({"points": pts, "label": scene.panel(i)[2] or scene.system.name})
            panels[-1].update(panel_curves(scene, i))
        fig = system_section_panels(panels, axes=scene.coords, layout=fs.layout, columns=fs.columns,
                                    share_scale=fs.share_scale, own_scale=tuple(fs.own_scale),
                                    marker_size=fs.marker_size, dpi=fs.dpi, window=scene.seeds.window)
        paths += figures.save_figure(fig, stem, text=text)
    if "lyapunov" in scene.compute:
        ind = scene.lyapunov.map_indicator
        rasters, fractions = [], []
        for i, pd in sorted(data.panels.items()):
            if i >= scene.n_panels or "megno" not in pd.extra:
                continue
            a = pd.attrs
            fraction = (float(a["chaotic_fraction"]), float(a["chaotic_fraction_error"]))
            fractions.append((scene.sweep_values[i] if scene.sweep_values else 0.0, *fraction))
            if "map_resolution" in a:
                grid = (int(a["map_resolution"]), *(float(v) for v in a["map_p1"]), *(float(v) for v in a["map_p2"]))
                values = pd.extra[ind] if ind in pd.extra else pd.extra["megno"]
                rasters.append({"seeds": pd.extra.get("lyapunov_seeds", pd.seeds), "values": values,
                                "grid": grid, "params": None, "h": scene.panel(i)[1], "axes": scene.coords,
                                "label": scene.panel(i)[2] or scene.system.name, "fraction": fraction[0],
                                "computed": float(np.mean(pd.extra.get("map_computed", True))),
                                "classified": class_text(*panel_class(scene.lyapunov, True))})
        if rasters:
            fig = chaos_rasters(rasters, indicator=ind, threshold=scene.lyapunov.threshold, columns=fs.columns,
                                dpi=fs.dpi)
            paths += figures.save_figure(fig, stem.with_name(stem.name + "_map"), text=text)
        if len(fractions) > 1:
            paths += figures.save_fraction_curve(fractions, scene, fs.dpi, stem, text)
    return paths
