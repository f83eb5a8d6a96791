"""Paper-style figures of Poincaré sections (the seed's Figure 4, docs/model.md R9).

Arrays in, figures out: the crossings ``(p1, p2)`` over the allowed region ``M^2 >= 0`` (white)
and the forbidden one (light gray).  matplotlib is imported lazily and figures are made with
:class:`matplotlib.figure.Figure`, not pyplot: no global figure list, no backend chosen.
"""
from __future__ import annotations

import math
import os
import re
import tempfile
from pathlib import Path

import numpy as np

from explorer import model

#: light gray of the forbidden region (M^2 < 0), as in the seed's Figure 4
FORBIDDEN_COLOR = "0.8"
#: colour and width of the boundary M^2 = 0 of the allowed region
BOUNDARY_COLOR = "0.15"
BOUNDARY_WIDTH = 0.6
#: colour of the section points
POINT_COLOR = "k"
#: style of the optional curves (separatrices)
CURVE_STYLE = {"color": "#b2182b", "linewidth": 0.7, "solid_capstyle": "round"}
#: [manifolds] of a scene: W^u and W^s in two colours (as in the tangle figure)
MANIFOLD_COLORS = {"unstable": "#b2182b", "stable": "#1f4e9c"}
MANIFOLD_STYLE = {"linewidth": 0.6, "solid_capstyle": "round"}
#: default width of one panel in inches
PANEL_WIDTH = 3.0
LAYOUTS = ("row", "grid")

_FONT_SIZE = 9
_TICK_SIZE = 8
_NOTE_SIZE = 7


def _matplotlib():
    """Import matplotlib lazily.  No backend is chosen: figures are saved by format or drawn on a
    canvas of their own, so a user's pyplot later in the process is unaffected."""
    import matplotlib

    return matplotlib


#: mathtext symbols: the model parameters' (model.PARAMETERS) and the other quantities labels name
_SYMBOLS = {
    **{p.name: p.latex for p in model.PARAMETERS}, "lambda": r"\lambda", "phi": r"\varphi",
    "phi0": r"\varphi_0", "h": "h", "c": "c", "p1": "p_1", "p2": "p_2", "M": "M", "t": "t",
    "tol": r"\mathrm{tol}", "dt": r"\Delta t",
}
_NUMBER = r"[-+\u2212]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?"
_VALUE = rf"(?:{_NUMBER}(?:\s*/\s*{_NUMBER})?|[-+]?\d*\s*\*?\s*pi(?:\s*/\s*\d+)?)"
_ASSIGN = re.compile(
    r"(?<![\w$\\])(" + "|".join(sorted(map(re.escape, _SYMBOLS), key=len, reverse=True)) + r")"
    r"\s*(=|<=|>=|<|>)\s*(" + _VALUE + r")(?![\w.])")
_RELATIONS = {"=": "=", "<=": r"\leq", ">=": r"\geq", "<": "<", ">": ">"}


def panel_axes(n, ncols, size, dpi):
    """A headless figure (constrained layout, Agg canvas) of ``size`` inches with ``n`` axes on
    ``ncols`` columns, unused cells removed; call inside its rc context.  Returns (fig, axes[:n])."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(-(-n // ncols), ncols, squeeze=False).ravel()
    for ax in axes[n:]:
        fig.delaxes(ax)
    return fig, axes[:n]


def _math_value(v: str) -> str:
    v = v.replace("\u2212", "-").replace(" ", "").replace("*", "")
    v = re.sub(r"pi", r"\\pi", v)
    m = re.fullmatch(r"([-+]?\d+(?:\.\d*)?)[eE]([-+]?\d+)", v)
    if m:  # 1e-05 -> 10^{-5}, 2.5e3 -> 2.5 \times 10^{3}
        mant, exp = m.group(1), int(m.group(2))
        if float(mant) == 1.0:
            return f"10^{{{exp}}}"
        if float(mant) == -1.0:
            return f"-10^{{{exp}}}"
        return f"{mant} \\times 10^{{{exp}}}"
    return v


def mathtext_label(text) -> str:
    """Each ``"name = value"`` piece of a label as mathtext: ``"mu = 0.5, h = 2"`` ->
    ``"$\\mu = 0.5$, $h = 2$"``; the rest of the text, unknown names and text with ``$`` are kept."""
    text = "" if text is None else str(text)
    if "$" in text:
        return text

    def sub(m):
        return f"${_SYMBOLS[m.group(1)]} {_RELATIONS[m.group(2)]} {_math_value(m.group(3))}$"

    return _ASSIGN.sub(sub, text)


def symbol_label(name) -> str:
    """The mathtext of a parameter name: ``"mu"`` -> ``"$\\mu$"``, ``"a1"`` -> ``"$a_1$"`` (the
    symbols of :func:`mathtext_label`); an unknown name is returned as it is."""
    name = str(name)
    return f"${_SYMBOLS[name]}$" if name in _SYMBOLS else name


def region_limits(params, h, phi0=math.pi, margin=0.05):
    """``((x0, x1), (y0, y1))``: the allowed region's bounding box plus ``margin`` on each side (a
    small box around a point region); None when it is empty."""
    e = model.allowed_ellipse(params, h, phi0)
    if e is None:
        return None
    c1, c2, r1, r2 = e
    floor = 1e-3 * max(1.0, abs(c1), abs(c2))
    r1, r2 = max(r1, floor), max(r2, floor)
    return ((c1 - r1 * (1 + 2 * margin), c1 + r1 * (1 + 2 * margin)),
            (c2 - r2 * (1 + 2 * margin), c2 + r2 * (1 + 2 * margin)))


def _union(boxes):
    boxes = [b for b in boxes if b is not None]
    if not boxes:
        return None
    return ((min(b[0][0] for b in boxes), max(b[0][1] for b in boxes)),
            (min(b[1][0] for b in boxes), max(b[1][1] for b in boxes)))


def _as_points(points, i):
    if points is None:
        return np.empty((0, 2))
    pts = np.asarray(points, dtype=np.float64)
    if pts.size == 0:
        return np.empty((0, 2))
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"panel {i}: points must be an (M, 2) array of (p1, p2), got shape {pts.shape}")
    return pts[np.isfinite(pts).all(axis=1)]


def _as_curves(curves, i):
    out = []
    for k, c in enumerate(curves or ()):
        arr = np.asarray(c, dtype=np.float64)
        if arr.size == 0:
            continue
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise ValueError(f"panel {i}: curve {k} must be a (K, 2) array of (p1, p2), got shape {arr.shape}")
        out.append(arr)
    return out


def _as_manifolds(branches, i):
    """[(kind, (K, 2) array)] with kind "unstable" or "stable"."""
    out = []
    for k, item in enumerate(branches or ()):
        if not (isinstance(item, (tuple, list)) and len(item) == 2 and item[0] in MANIFOLD_COLORS):
            raise ValueError(f"panel {i}: manifold {k} must be (kind, points) with kind 'unstable' or 'stable'")
        out += [(item[0], c) for c in _as_curves([item[1]], i)]
    return out


def _prepare(panels, separatrices):
    if isinstance(panels, dict):
        panels = [panels]
    panels = list(panels)
    if not panels:
        raise ValueError("section_panels needs at least one panel")
    n = len(panels)
    if separatrices is None:
        extra = [None] * n
    elif isinstance(separatrices, dict):
        extra = [separatrices.get(i, separatrices.get(i - n)) for i in range(n)]
    else:
        extra = list(separatrices)
        if len(extra) != n:
            raise ValueError(f"separatrices must have one entry per panel ({n}), got {len(extra)}")
    out = []
    for i, (p, sep) in enumerate(zip(panels, extra)):
        if not isinstance(p, dict):
            raise ValueError(f"panel {i} must be a dict with keys points, params, h (got {type(p).__name__})")
        for key in ("params", "h"):
            if key not in p:
                raise ValueError(f"panel {i}: missing key {key!r}")
        prm = p["params"]
        if not isinstance(prm, model.Params):
            prm = model.Params(**prm) if isinstance(prm, dict) else model.Params.from_array(prm)
        h = float(p["h"])
        phi0 = float(p.get("phi0", math.pi))
        if not (math.isfinite(h) and math.isfinite(phi0)):
            raise ValueError(f"panel {i}: h and phi0 must be finite, got h = {h!r}, phi0 = {phi0!r}")
        label = p.get("label")
        if label is None:
            label = f"mu = {prm.mu:g}"
        out.append(dict(points=_as_points(p.get("points"), i), params=prm, h=h, phi0=phi0,
                        label=mathtext_label(label), note=p.get("note"),
                        curves=_as_curves(p.get("curves"), i) + _as_curves(sep, i),
                        manifolds=_as_manifolds(p.get("manifolds"), i),
                        region=model.allowed_ellipse(prm, h, phi0)))
    return out


def _own_set(own_scale, n):
    own = set()
    for k in own_scale or ():
        k = int(k)
        if not -n <= k < n:
            raise ValueError(f"own_scale index {k} out of range for {n} panels")
        own.add(k % n)
    return own


def _limits(prepared, share_scale, own):
    boxes = [region_limits(p["params"], p["h"], p["phi0"]) if p["region"] is not None else None
             for p in prepared]
    shared = _union([b for i, b in enumerate(boxes) if i not in own]) if share_scale else None
    fallback = shared or _union(boxes)
    out = []
    for i, (p, box) in enumerate(zip(prepared, boxes)):
        if share_scale and i not in own and shared is not None:
            box = shared
        if box is None:  # empty region: borrow a scale, else fit the points, else a unit box
            box = fallback
            if box is None and len(p["points"]):
                lo, hi = p["points"].min(axis=0), p["points"].max(axis=0)
                pad = 0.05 * np.maximum(hi - lo, 1e-3)
                box = ((lo[0] - pad[0], hi[0] + pad[0]), (lo[1] - pad[1], hi[1] + pad[1]))
            if box is None:
                box = ((-1.0, 1.0), (-1.0, 1.0))
        out.append(box)
    return out


def _draw_panel(ax, p, box, marker_size):
    from matplotlib.patches import Ellipse

    (x0, x1), (y0, y1) = box
    ax.set_facecolor(FORBIDDEN_COLOR)
    notes = []
    if p["region"] is None:
        notes.append("no allowed region")
    else:
        c1, c2, r1, r2 = p["region"]
        ax.add_patch(Ellipse((c1, c2), 2 * r1, 2 * r2, facecolor="white", edgecolor="none", zorder=0.5))
        ax.add_patch(Ellipse((c1, c2), 2 * r1, 2 * r2, facecolor="none", edgecolor=BOUNDARY_COLOR,
                             linewidth=BOUNDARY_WIDTH, zorder=3))
    pts = p["points"]
    if len(pts):
        ax.plot(pts[:, 0], pts[:, 1], linestyle="none", marker="o", markersize=math.sqrt(max(marker_size, 0.0)),
                markeredgewidth=0, markerfacecolor=POINT_COLOR, color=POINT_COLOR, rasterized=True,
                zorder=2)
    for c in p["curves"]:
        ax.plot(c[:, 0], c[:, 1], zorder=2.5, **CURVE_STYLE)
    for kind, c in p["manifolds"]:
        ax.plot(c[:, 0], c[:, 1], zorder=2.6, color=MANIFOLD_COLORS[kind], gid=f"manifold-{kind}", **MANIFOLD_STYLE)
    if p["note"]:
        notes.append(str(p["note"]))
    if notes:
        ax.text(0.03, 0.03, mathtext_label("\n".join(notes)), transform=ax.transAxes, fontsize=_NOTE_SIZE,
                ha="left", va="bottom", zorder=4,
                bbox=dict(boxstyle="round,pad=0.25", facecolor="white", edgecolor="none", alpha=0.85))
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("$p_1$", fontsize=_FONT_SIZE, labelpad=1.5)
    ax.set_ylabel("$p_2$", fontsize=_FONT_SIZE, labelpad=1.5)
    ax.set_title(p["label"], fontsize=_FONT_SIZE, pad=4)
    ax.tick_params(direction="in", top=True, right=True, labelsize=_TICK_SIZE, width=0.5, length=2.5, pad=2)
    ax.minorticks_on()
    ax.tick_params(which="minor", direction="in", top=True, right=True, width=0.4, length=1.5)
    for s in ax.spines.values():
        s.set_linewidth(0.6)


def section_panels(panels, *, layout="row", columns=None, share_scale=True, own_scale=(), marker_size=0.25,
                   dpi=200, title=None, separatrices=None, panel_width=PANEL_WIDTH):
    """A paper-style figure of Poincaré sections, one panel per dict of ``panels``: ``points`` ((M, 2)
    or None), ``params``, ``h``, optional ``phi0`` [pi], ``label`` (through :func:`mathtext_label`),
    ``note``, ``curves`` (list of (K, 2), NaN rows break a curve), ``manifolds`` (list of (kind,
    (K, 2)), drawn in :data:`MANIFOLD_COLORS`).

    ``layout`` "row" or "grid" (``columns`` per row [3]); ``share_scale``: the panels not in
    ``own_scale`` share the union of their allowed regions (+5 %); ``marker_size`` in pt^2 (as
    scatter's ``s``); ``separatrices``: more curves per panel (list, or {index: curves});
    ``panel_width`` in inches.  Forbidden region light gray, allowed white, points rasterized;
    ``fig.axes[i]`` is the panel of ``panels[i]``."""
    mpl = _matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    prepared = _prepare(panels, separatrices)
    n = len(prepared)
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {LAYOUTS}, got {layout!r}")
    if layout == "row":
        ncols = n
    else:
        ncols = 3 if columns is None else int(columns)
        if ncols < 1:
            raise ValueError(f"columns must be >= 1, got {columns!r}")
        ncols = min(ncols, n)
    nrows = -(-n // ncols)
    own = _own_set(own_scale, n)
    boxes = _limits(prepared, bool(share_scale), own)
    if not (float(marker_size) >= 0.0):
        raise ValueError(f"marker_size must be >= 0, got {marker_size!r}")
    panel_width = float(panel_width)
    if not panel_width > 0:
        raise ValueError(f"panel_width must be > 0, got {panel_width!r}")

    # height of a row: the tallest panel (equal aspect) plus room for title and p1 label
    aspects = [(b[1][1] - b[1][0]) / (b[0][1] - b[0][0]) for b in boxes]
    inner = panel_width - 0.5
    height = sum(min(max(aspects[r * ncols:(r + 1) * ncols]), 3.0) * inner + 0.6 for r in range(nrows))
    if title:
        height += 0.3
    with mpl.rc_context({"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6,
                         "figure.constrained_layout.h_pad": 0.03, "figure.constrained_layout.w_pad": 0.03,
                         "figure.constrained_layout.wspace": 0.04, "figure.constrained_layout.hspace": 0.04}):
        fig = Figure(figsize=(panel_width * ncols, height), dpi=dpi, layout="constrained")
        FigureCanvasAgg(fig)  # a headless canvas: fig.canvas.draw() / buffer_rgba() work without pyplot
        axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
        for ax in axes[n:]:
            fig.delaxes(ax)
        for ax, p, box in zip(axes, prepared, boxes):
            _draw_panel(ax, p, box, float(marker_size))
        if title:
            fig.suptitle(mathtext_label(title), fontsize=_FONT_SIZE + 1)
        _trim_height(fig)
        _whole_pixels(fig)
    return fig


def _whole_pixels(fig):
    """Make the figure a whole number of pixels at its dpi (Agg truncates the size to
    whole pixels; a fractional height would shift the picture by part of a pixel)."""
    W, H = fig.get_size_inches()
    dpi = fig.dpi
    fig.set_size_inches(round(W * dpi) / dpi + 1e-7, round(H * dpi) / dpi + 1e-7)


def _trim_height(fig, keep=0.04):
    """Remove the empty height that constrained layout leaves below equal-aspect panels (more than
    ``keep`` inches of it).

    Draws nothing: the layout engine alone lays the figure out on its Agg renderer, as the layout
    pass of :meth:`~matplotlib.figure.Figure.draw_without_rendering` would, and the tight box is read
    from that layout (the rest of a draw would not change it).  The height is then new, so the
    figure is laid out again when it is drawn, e.g. by :func:`save_figure`.  A layout that fails
    is skipped as ``Figure.draw`` skips it; any other trouble (odd labels) keeps the estimate."""
    engine = fig.get_layout_engine()
    try:
        try:
            engine.execute(fig)
        except ValueError:  # as Figure.draw: no layout, the tight box of the figure as it is
            pass
        tight = fig.get_tightbbox()
    except Exception:  # layout trouble (e.g. odd labels): keep the estimate
        return
    W, H = fig.get_size_inches()
    pad = engine.get()["h_pad"]
    slack = H - tight.height - 2 * pad
    if slack > keep:
        fig.set_size_inches(W, H - slack + keep)


def _atomic_savefig(fig, path: Path, fmt: str, **kwargs):
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        fig.savefig(tmp, format=fmt, **kwargs)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _set_layout_engine(fig, engine):
    """``fig.set_layout_engine(engine)``, where None means no engine whatever the rcParams say."""
    with _matplotlib().rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
        fig.set_layout_engine(engine)


def _lay_out_as_pdf(fig):
    """Run ``fig``'s layout engine as ``savefig`` runs it before drawing a PDF: on a PDF canvas
    at the PDF's 72 dpi (so with the PDF renderer's text metrics).  Draws nothing; a layout that
    fails is skipped as ``Figure.draw`` skips it."""
    engine = fig.get_layout_engine()
    if engine is None or not fig.axes:
        return
    from matplotlib.backends.backend_pdf import FigureCanvasPdf

    canvas, dpi = fig.canvas, fig.dpi
    FigureCanvasPdf(fig)            # the canvas savefig switches to for a PDF
    try:
        fig.dpi = 72                # FigureCanvasPdf.print_pdf's: 72 points to the inch
        try:
            engine.execute(fig)
        except ValueError:
            pass
    finally:
        fig.dpi = dpi
        fig.set_canvas(canvas)


def save_figure(fig, stem, dpi=None, *, text=None):
    """Write ``<stem>.png`` and ``<stem>.pdf`` atomically (parents created; a ``.png``/``.pdf`` suffix
    of ``stem`` is dropped), at ``dpi`` [the figure's], the PDF without a creation date; ``text``:
    {key: value} chunks of the PNG (:func:`png_text`, docs/scenes.md "What a rerun recomputes"),
    written last.  Returns (png, pdf) paths.

    Each file is one draw of the figure (``explorer figures``, docs/commands/figures.md, writes
    every figure this way): the layout engine (constrained layout) lays the figure out once, as
    ``savefig`` would before drawing the PDF, then the figure has no layout engine while both
    files are written (restored after), so ``savefig`` neither lays it out again nor walks it
    before drawing it.  The PDF is the one ``fig.savefig`` writes; the PNG has the PDF's size and
    layout (a PNG saved alone may sit a pixel off: Agg's text metrics differ a little)."""
    _matplotlib()
    stem = os.fspath(stem)
    if stem.lower().endswith((".png", ".pdf")):
        stem = stem[:-4]
    base = Path(stem)
    if not base.name:
        raise ValueError(f"save_figure needs a file stem, got {stem!r}")
    base.parent.mkdir(parents=True, exist_ok=True)
    dpi = fig.dpi if dpi is None else float(dpi)
    png, pdf = Path(stem + ".png"), Path(stem + ".pdf")
    engine = fig.get_layout_engine()
    _lay_out_as_pdf(fig)
    _set_layout_engine(fig, None)     # laid out: neither file computes it again or draws it twice
    try:
        _atomic_savefig(fig, pdf, "pdf", dpi=dpi, facecolor="white", metadata={"CreationDate": None})
        _atomic_savefig(fig, png, "png", dpi=dpi, facecolor="white", metadata=dict(text or {}))
    finally:
        _set_layout_engine(fig, engine)
    return png, pdf


def png_text(path, key):
    """The text chunk ``key`` of the PNG at ``path`` (:func:`save_figure`'s ``text``), None if the
    file or the key is missing or the file is not a readable PNG."""
    from PIL import Image

    try:
        with Image.open(path) as im:
            return getattr(im, "text", {}).get(key)
    except (OSError, ValueError, SyntaxError):
        return None


def chaos_maps(maps, *, layout="row", columns=None, threshold=4.0, dpi=200, panel_width=PANEL_WIDTH):
    """Chaos maps: each seed coloured by its MEGNO <Y> (log scale), the forbidden region gray, one
    colour bar, each title with the chaotic fraction (<Y> > ``threshold``).  ``maps``: dicts of
    ``seeds``, ``megno``, optional ``valid``, ``params``, ``h``, ``phi0``, ``label``."""
    mpl = _matplotlib()
    from matplotlib.colors import LogNorm
    from matplotlib.patches import Ellipse

    n = len(maps)
    if n == 0:
        raise ValueError("chaos_maps needs at least one panel")
    ncols = n if layout == "row" else min(n, 3 if columns is None else int(columns))
    nrows = -(-n // ncols)
    vmax = max(10.0, max(float(np.nanmax(np.asarray(m["megno"]))) if len(m["megno"]) else 10.0 for m in maps))
    norm = LogNorm(vmin=0.5, vmax=vmax)
    with mpl.rc_context({"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6}):
        fig, axes = panel_axes(n, ncols, (panel_width * ncols + 0.8, 0.85 * panel_width * nrows + 0.3), dpi)
        sc = None
        for ax, m in zip(axes, maps):
            prm = m["params"] if isinstance(m["params"], model.Params) else model.Params(**m["params"])
            phi0 = m.get("phi0", math.pi)
            ax.set_facecolor(FORBIDDEN_COLOR)
            region = model.allowed_ellipse(prm, m["h"], phi0)
            if region is not None:
                c1, c2, r1, r2 = region
                ax.add_patch(Ellipse((c1, c2), 2 * r1, 2 * r2, facecolor="white", edgecolor=BOUNDARY_COLOR,
                                     linewidth=BOUNDARY_WIDTH, zorder=0.5))
                pad = 0.05
                ax.set_xlim(c1 - r1 * (1 + pad), c1 + r1 * (1 + pad))
                ax.set_ylim(c2 - r2 * (1 + pad), c2 + r2 * (1 + pad))
            seeds = np.asarray(m["seeds"], float)
            megno = np.clip(np.asarray(m["megno"], float), 0.5, None)
            valid = np.asarray(m.get("valid", np.ones(len(megno), bool)), bool) & np.isfinite(megno)
            # marker size from the seed spacing: the map looks continuous
            if region is not None and valid.sum():
                area = math.pi * r1 * r2 / max(1, len(seeds))
                size_pt = math.sqrt(area) / (2 * r1 * (1 + pad)) * panel_width * 72 * 1.05
            else:
                size_pt = 3.0
            sc = ax.scatter(seeds[valid, 0], seeds[valid, 1], c=megno[valid], norm=norm, cmap="inferno_r",
                            s=size_pt ** 2, marker="s", linewidths=0, rasterized=True, zorder=1)
            frac = float(np.mean(np.asarray(m["megno"])[valid] > threshold)) if valid.sum() else float("nan")
            ax.set_title(mathtext_label(m.get("label", "")) + f"   chaotic {frac:.0%}", fontsize=_FONT_SIZE, pad=4)
            ax.set_aspect("equal", adjustable="box")
            ax.set_xlabel("$p_1$", fontsize=_FONT_SIZE)
            ax.set_ylabel("$p_2$", fontsize=_FONT_SIZE)
            ax.tick_params(direction="in", top=True, right=True, labelsize=_TICK_SIZE)
        if sc is not None:
            cb = fig.colorbar(sc, ax=list(axes[:n]), shrink=0.9, pad=0.01)
            cb.set_label(r"mean MEGNO $\langle Y\rangle$", fontsize=_FONT_SIZE)
            cb.ax.tick_params(labelsize=_TICK_SIZE)
    return fig


def save_fraction_curve(fractions, scene, dpi, stem, text=None) -> list:
    """The chaotic fraction against the swept value (rows (value, fraction, error)) of ``scene``,
    saved as ``<stem>_fraction``: :func:`fraction_curve`, :func:`save_figure`."""
    fr = np.array(fractions)
    fig = fraction_curve(fr[:, 0], fr[:, 1], fr[:, 2], parameter=scene.sweep_parameter or "",
                         threshold=scene.lyapunov.threshold, dpi=dpi)
    return save_figure(fig, stem.with_name(stem.name + "_fraction"), text=text)


def fraction_curve(values, fraction, error, *, parameter="mu", threshold=4.0, dpi=200):
    """The chaotic fraction of the allowed section (seeds with <Y> > threshold) against the
    swept parameter, with binomial error bars."""
    mpl = _matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    values = np.asarray(values, float)
    fraction = np.asarray(fraction, float)
    error = np.asarray(error, float)
    order = np.argsort(values)
    with mpl.rc_context({"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6}):
        fig = Figure(figsize=(4.5, 3.0), dpi=dpi, layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.subplots()
        ax.errorbar(values[order], fraction[order], yerr=error[order], fmt="o-", color="k", ms=3, lw=0.8,
                    capsize=2, elinewidth=0.6)
        if np.all(values > 0) or (np.sum(values > 0) > 2 and values.max() / values[values > 0].min() > 100):
            ax.set_xscale("symlog", linthresh=max(values[values > 0].min(), 1e-12) if np.any(values > 0) else 1.0)
        ax.set_ylim(-0.03, 1.03)
        ax.set_xlabel(symbol_label(parameter) if parameter else "value", fontsize=_FONT_SIZE)
        ax.set_ylabel(f"chaotic fraction (MEGNO > {threshold:g})", fontsize=_FONT_SIZE)
        ax.tick_params(direction="in", top=True, right=True, labelsize=_TICK_SIZE)
        ax.grid(alpha=0.3, lw=0.4)
    return fig
