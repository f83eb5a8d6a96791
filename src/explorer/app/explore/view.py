"""The explorer's drawing: the section with its allowed region (docs/model.md R9: white inside the
ellipse M^2 >= 0, light gray outside, as in :mod:`explorer.app.figures`), the orbits' crossings,
the seeds, fixed points and separatrices, the MEGNO colour bar, the sliders, text box and buttons,
and the status line. It reads an :class:`~explorer.app.explore.state.ExplorerState` and never
changes it; the controller wires the widgets to the state's actions."""
from __future__ import annotations

import math
import os

import numpy as np

from explorer.app.explore.state import CHAOTIC_MEGNO, INDICATOR_TIME

#: top of the colour scale of the MEGNO (larger values get the top colour)
MEGNO_COLOR_MAX = 10.0
#: separatrix polylines are broken where two points are farther apart than this x the larger semi-axis
SEPARATRIX_GAP = 0.1
#: colour of separatrices and fixed-point markers
SEPARATRIX_COLOR = "k"
#: the window's size in inches
FIGSIZE = (11.0, 7.6)
DISPLAY_ERROR = "explore needs a display (set DISPLAY or use a GUI backend)"
#: the buttons: key -> label (the same actions as the keys)
BUTTONS = (("c", "clear  [c]"), ("r", "re-run seeds  [r]"), ("s", "save PNG  [s]"),
           ("w", "write HDF5  [w]"), ("x", "colour by MEGNO  [x]"), ("p", "separatrices  [p]"),
           ("o", "periodic orbits  [o]"))
#: colours of the periodic orbits by period (key o)
PERIOD_COLORS = ("k", "#1f4e9c", "#b2182b", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2")


def break_jumps(curve, gap):
    """A polyline with NaN rows inserted where consecutive points are more than ``gap`` apart
    (unresolved pieces of a manifold are not drawn as straight chords)."""
    c = np.asarray(curve, dtype=np.float64)
    if len(c) < 2:
        return c
    jumps = np.flatnonzero(np.hypot(*np.diff(c, axis=0).T) > gap)
    return np.insert(c, jumps + 1, np.nan, axis=0) if len(jumps) else c


class ExplorerView:
    """The window's artists and widgets for one state. ``fig`` None creates a pyplot figure
    (ParameterError naming the display problem if none can be opened)."""

    def __init__(self, state, fig=None):
        import matplotlib as mpl
        from matplotlib.patches import Ellipse
        from matplotlib.widgets import Button, Slider, TextBox

        from explorer.app.figures import BOUNDARY_COLOR, BOUNDARY_WIDTH, FORBIDDEN_COLOR
        from explorer.model import ParameterError

        self.state = state
        if fig is None:
            import matplotlib.pyplot as plt

            try:
                fig = plt.figure(figsize=FIGSIZE)
            except Exception as exc:  # noqa: BLE001 - e.g. TclError: the display cannot be opened
                raise ParameterError(f"{DISPLAY_ERROR}: {type(exc).__name__}: {exc}") from None
            try:
                fig.canvas.manager.set_window_title("explorer explore")
            except Exception:  # noqa: BLE001, S110 - some backends have no window title
                pass
        self.fig = fig
        ax = self.ax = fig.add_axes([0.07, 0.27, 0.56, 0.65])
        ax.set_facecolor(FORBIDDEN_COLOR)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("$p_1$")
        ax.set_ylabel("$p_2$")
        ax.tick_params(direction="in", top=True, right=True)
        self.region_patch = Ellipse((0, 0), 1, 1, facecolor="white", edgecolor="none", zorder=0.5)
        self.boundary_patch = Ellipse((0, 0), 1, 1, facecolor="none", edgecolor=BOUNDARY_COLOR,
                                      linewidth=BOUNDARY_WIDTH, zorder=3)
        ax.add_patch(self.region_patch)
        ax.add_patch(self.boundary_patch)
        self.region_note = ax.text(0.03, 0.03, "", transform=ax.transAxes, fontsize=9, zorder=5,
                                   bbox=dict(boxstyle="round,pad=0.25", facecolor="white", edgecolor="none",
                                             alpha=0.85))
        (self.seed_ok_line,) = ax.plot([], [], linestyle="none", marker="+", markersize=7, color="k",
                                       markeredgewidth=1.0, zorder=4)
        (self.seed_bad_line,) = ax.plot([], [], linestyle="none", marker="x", markersize=6, color="#b2182b",
                                        markeredgewidth=1.0, zorder=4)
        self.lines: dict[int, object] = {}   # orbit number -> Line2D of its crossings
        self.sep_artists: list = []
        self.periodic_artists: list = []

        # colour bar of the MEGNO (shown with 'x'); turbo: every colour is visible on white
        self.cmap = mpl.colormaps["turbo"]
        self.norm = mpl.colors.Normalize(vmin=0.0, vmax=MEGNO_COLOR_MAX, clip=True)
        self.cax = fig.add_axes([0.645, 0.27, 0.013, 0.65])
        sm = mpl.cm.ScalarMappable(norm=self.norm, cmap=self.cmap)
        self.colorbar = fig.colorbar(sm, cax=self.cax, extend="max")
        self.colorbar.set_label(f"MEGNO $\\langle Y\\rangle$ at t = {INDICATOR_TIME:g} (2: regular, larger: chaotic)",
                                fontsize=8)
        self.cax.tick_params(labelsize=7)
        self.cax.set_visible(False)

        # sliders and the parameter text box
        mu_max = max(10.0, 2.0 * state.params.mu)
        emin = state.energy_minimum()
        h_lo = min(state.h, emin) if emin is not None else min(state.h, 0.0)
        h_hi = max(state.h + 1.0, (emin if emin is not None else 0.0) + 3.0 * max(state.h - (emin or 0.0), 1.0))
        self.mu_slider = Slider(fig.add_axes([0.12, 0.175, 0.46, 0.025]), "$\\mu$", 0.0, mu_max,
                                valinit=state.params.mu, valfmt="%.4g")
        self.h_slider = Slider(fig.add_axes([0.12, 0.138, 0.46, 0.025]), "$h$", h_lo, h_hi,
                               valinit=state.h, valfmt="%.4g")
        self.textbox = TextBox(fig.add_axes([0.12, 0.088, 0.30, 0.034]), "set ", initial="")
        fig.text(0.43, 0.105, "e.g. a1=1.2  or  mu=0.03, h=2.5  (Enter)", fontsize=8, va="center", color="0.3")
        self.buttons = {}
        for i, (key, text) in enumerate(BUTTONS):
            b = Button(fig.add_axes([0.73, 0.86 - i * 0.058, 0.22, 0.046]), text)
            b.label.set_fontsize(9)
            self.buttons[key] = b
        help_text = ("click in the white region: start an orbit\n"
                     "there (M > 0 from the energy)\n\n"
                     "sliders / text: change a parameter;\n"
                     "the seeds (+) are kept, press r\n"
                     "to run them again\n\n"
                     f"x: colour by the MEGNO <Y> over\n"
                     f"t <= {INDICATOR_TIME:g} (2: quasi-periodic,\n"
                     f"0: stable periodic, > {CHAOTIC_MEGNO:g}: chaotic-like)\n\n"
                     "p: fixed points (o elliptic, x hyperbolic)\n"
                     "and separatrices\n\n"
                     "o: periodic orbits of periods 1..4\n"
                     "(number: period)\n\n"
                     "toolbar zoom/pan: clicks do not start orbits")
        fig.text(0.73, 0.47, help_text, fontsize=8, va="top", color="0.2", linespacing=1.3)
        self.status_text = fig.text(0.01, 0.006, "", fontsize=9, va="bottom", ha="left", family="monospace")

    # ------------------------------------------------------------ region, seeds, title
    def draw_region(self, reset_limits=False):
        """Region, title and seeds at the state's parameters."""
        from explorer.app.figures import mathtext_label, region_limits

        st = self.state
        e = st.region
        if e is None:
            self.region_patch.set_visible(False)
            self.boundary_patch.set_visible(False)
            emin = st.energy_minimum()
            extra = f" (h must exceed {emin:.6g})" if emin is not None else ""
            self.region_note.set_text(f"no allowed region at h = {st.h:g}{extra}")
            self.region_note.set_visible(True)
        else:
            c1, c2, r1, r2 = e
            for p in (self.region_patch, self.boundary_patch):
                p.set_center((c1, c2))
                p.set_width(2 * r1)
                p.set_height(2 * r2)
                p.set_visible(True)
            self.region_note.set_visible(False)
            if reset_limits:
                (x0, x1), (y0, y1) = region_limits(st.params, st.h, st.phi0)
                self.ax.set_xlim(x0, x1)
                self.ax.set_ylim(y0, y1)
        text = mathtext_label(", ".join(st.title_parts()))
        self.ax.set_title(f"{st.label}: {text}" if st.label else text, fontsize=10)
        self.draw_seeds()

    def draw_seeds(self):
        ok, bad = self.state.seeds_split()
        self.seed_ok_line.set_data(ok[:, 0], ok[:, 1])
        self.seed_bad_line.set_data(bad[:, 0], bad[:, 1])

    def sync_sliders(self):
        """Move the sliders to the state's mu and h (widening their range if needed)."""
        for slider, v in ((self.mu_slider, self.state.params.mu), (self.h_slider, self.state.h)):
            if v < slider.valmin or v > slider.valmax:
                lo, hi = min(slider.valmin, v), max(slider.valmax, v)
                slider.valmin, slider.valmax = lo, hi
                slider.ax.set_xlim(lo, hi)
            if slider.val != v:
                slider.set_val(v)

    # ------------------------------------------------------------ orbits
    def orbit_color(self, o):
        if not self.state.color_by_indicator:
            return o.color
        return "0.55" if o.megno is None else self.cmap(self.norm(o.megno))

    def update_orbit(self, o):
        """Draw (or redraw) the crossings of orbit ``o``."""
        line = self.lines.get(o.number)
        if line is None:
            (line,) = self.ax.plot([], [], linestyle="none", marker="o", markersize=1.8, markeredgewidth=0,
                                   color=o.color, zorder=2)
            self.lines[o.number] = line
        pts = o.crossings
        line.set_data(pts[:, 1], pts[:, 2])
        line.set_color(self.orbit_color(o))

    def sync_orbits(self):
        """Remove the artists of orbits the state no longer has; redraw the others."""
        alive = {o.number for o in self.state.orbits}
        for number in [n for n in self.lines if n not in alive]:
            self.lines.pop(number).remove()
        for o in self.state.orbits:
            self.update_orbit(o)
        self.cax.set_visible(self.state.color_by_indicator)

    # ------------------------------------------------------------ separatrices
    def clear_separatrices(self):
        for a in self.sep_artists:
            a.remove()
        self.sep_artists = []

    def draw_separatrices(self, points, curves):
        """Fixed points (o elliptic, x hyperbolic) and separatrix branches, in black."""
        from explorer.app.figures import CURVE_STYLE

        self.clear_separatrices()
        style = dict(CURVE_STYLE, color=SEPARATRIX_COLOR, linewidth=0.9)  # black: visible over any orbit colour
        region = self.state.region
        gap = SEPARATRIX_GAP * max(region[2], region[3]) if region else math.inf
        for c in curves or ():
            c = break_jumps(c, gap)
            (ln,) = self.ax.plot(c[:, 0], c[:, 1], zorder=3.5, **style)
            self.sep_artists.append(ln)
        for fp in points or ():
            (mk,) = self.ax.plot([fp.point[0]], [fp.point[1]], linestyle="none", zorder=4.5,
                                 marker="o" if fp.stable else "x", markersize=8, markeredgewidth=1.8,
                                 markerfacecolor="none", color=SEPARATRIX_COLOR)
            self.sep_artists.append(mk)

    def clear_periodic(self):
        for a in self.periodic_artists:
            a.remove()
        self.periodic_artists = []

    def draw_periodic(self, orbits):
        """Periodic orbits: o elliptic (filled), x hyperbolic, one colour per period, labelled K."""
        self.clear_periodic()
        for o in orbits or ():
            col = PERIOD_COLORS[(o.period - 1) % len(PERIOD_COLORS)]
            (mk,) = self.ax.plot(o.points[:, 0], o.points[:, 1], linestyle="none", zorder=4.6,
                                 marker="o" if o.stable else "x", markersize=5, markeredgewidth=1.2,
                                 color=col, markerfacecolor=col if o.stable else "none")
            self.periodic_artists.append(mk)
            for p in o.points:
                self.periodic_artists.append(self.ax.annotate(str(o.period), p, xytext=(3, 3),
                                                              textcoords="offset points", fontsize=6, color=col))

    # ------------------------------------------------------------ status, output
    def update_status(self):
        self.status_text.set_text(self.state.status_report())

    def redraw(self):
        self.fig.canvas.draw_idle()

    def _section_bbox(self):
        """The part of the figure holding the section (title, labels, colour bar if shown), in inches."""
        from matplotlib.transforms import Bbox

        renderer = self.fig.canvas.get_renderer()
        boxes = [self.ax.get_tightbbox(renderer)]
        if self.cax.get_visible():
            boxes.append(self.cax.get_tightbbox(renderer))
        return Bbox.union(boxes).transformed(self.fig.dpi_scale_trans.inverted()).padded(0.08)

    def save_png(self, path) -> str:
        """Write the section (axes with its orbits, not the widgets) as a PNG, atomically."""
        from explorer.io.store import atomic_path

        path = os.fspath(path)
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        self.fig.canvas.draw()
        bbox = self._section_bbox()
        with atomic_path(path) as tmp:
            self.fig.savefig(tmp, format="png", dpi=200, bbox_inches=bbox, facecolor="white")
        return path
