"""The page of ``explorer serve``: one Bokeh figure of the section in a Panel layout, the fields
of the parameters, and the buttons.  One :class:`SectionPage` per browser session.

What the page holds, by Bokeh model name (``Bokeh.documents[0].get_model_by_name(NAME)`` in the
browser; the tests read them there):

``region``     ColumnDataSource of the allowed ellipse (x, y, width, height; empty: no region)
``crossings``  ColumnDataSource of every crossing on screen (a dot or in the density image):
               orbit, t, p1, p2, M, dH, the orbit's colour c (an index into COLORS) and its
               MEGNO (NaN until known); empty
               past density.THRESHOLD crossings (``SectionPage.crossings``, in the server
               only, holds them all; ``SectionPage.shown`` is this one)
``glyphs``     CustomJSFilter of the crossings drawn as glyphs: those of the orbits from
               ``args.first`` on (0: all), the newest, at most density.GLYPH_BUDGET crossings
``live``       ColumnDataSource of the crossings of a message that carried an orbit's first
               crossings (and of those sent in the FLUSH_SECONDS after it), drawn on Bokeh's
               overlay canvas (the older orbits are not repainted) until the flush then moves them
               to ``crossings`` (same columns; every row of the page is in exactly one of the two)
``density``    ColumnDataSource of the density image of the other crossings (n: how many):
               the older orbits past density.GLYPH_BUDGET, every orbit past the threshold
``starts``     ColumnDataSource of the clicked starts: orbit, p1, p2, c
``raster``     ColumnDataSource of the MEGNO layer: image, x, y, dw, dh (the window), n, complete
``fixed``      ColumnDataSource of the fixed points of the section map: p1, p2, kind, marker
``separatrices`` ColumnDataSource of the separatrix branches: xs, ys (one polyline per branch)
``periodic``   ColumnDataSource of the periodic orbits of periods 1..4: p1, p2, period, kind, marker
``overlay``    what the searches found
``readout``    the picked orbit's mLCE, mean MEGNO and rotation number
``section``    the figure (a click on it starts an orbit)
``message``    the last message (a refused value, an export, a click outside the region)
``status``     one line: orbits running and paused, crossings drawn

Values from the page are read by :func:`explorer.app.serve.settings.parse_fields`; a refused
value leaves everything as it was and says why in ``message``.  Crossings arrive from the
session's :class:`~explorer.app.serve.orbits.Worker` thread and are streamed onto the document
in its own event loop (``add_next_tick_callback``).
"""
from __future__ import annotations

import math
import threading
import time
from functools import partial

import numpy as np
import panel as pn
from bokeh.events import DoubleTap, RangesUpdate, Tap
from bokeh.models import CDSView, ColorBar, ColumnDataSource, CustomJSFilter, Div, LinearColorMapper, Range1d
from bokeh.plotting import figure

from explorer import model
from explorer.app.serve import export
from explorer.app.serve import raster as raster_mod
from explorer.app.serve import settings as settings_mod
from explorer.app.serve.orbits import CHAOTIC_MEGNO, COLORS, INDICATOR_TIME, Worker
from explorer.app.serve.overlays import PERIODIC_MAX
from explorer.app.serve.page_exports import ExportsMixin
from explorer.app.serve.page_layers import (  # noqa: F401
    CROSSING_COLUMNS,
    LayersMixin,
    _empty_crossings,
    _empty_density,
    _empty_manifolds,
    _empty_periodic,
    _empty_raster,
)
from explorer.app.serve.page_readout import ReadoutMixin
from explorer.app.serve.settings import (
    FIELDS,
    Settings,
    format_starts,
    format_window,
    parse_fields,
    parse_starts,
    parse_window,
)
from explorer.app.serve.style import (
    ALLOWED_COLOR,
    BOUNDARY_COLOR,
    FIELD_WIDTH,
    FIGURE_HEIGHT,
    FIGURE_WIDTH,
    FORBIDDEN_COLOR,
    MEGNO_HIGH,
    MEGNO_LOW,
    MEGNO_ORBIT_SKIP,
    MESSAGE_ERROR_COLOR,
    MESSAGE_OK_COLOR,
    PERIOD_COLORS,
    POINT_SIZE,
    SEPARATRIX_CASING,
    SEPARATRIX_COLOR,
    VIEW_MARGIN,
    megno_palette,
)
from explorer.model import ParameterError

#: a double tap within this many pixels of the click before it is that click again
SAME_SPOT_PX = 4.0
#: after an orbit's first block (sent at once, to the live layer), blocks go to the browser at most
#: this often (s): each message makes the browser redraw every dot on screen (benchmarks/bench_serve.py)
FLUSH_SECONDS = 0.25
#: a flush this close to the time the live rows are due to settle (s) settles them
SETTLE_SLACK = 0.01
#: rows sent before the live rows settle join them while the live layer stays within this many
#: (a short orbit's last block; the overlay repaints them all, about 5 us a dot); a larger block
#: took 50 ms or more to compute (orbits.BLOCK_SECONDS), the first rows are on screen by then,
#: and it settles at once with them (one repaint of everything instead of two)
LIVE_MAX_ROWS = 2_000
#: a click's new link (the URL's orbits) is written this long after the click (ms), off the path
#: from the click to its first crossings on screen; clicks meanwhile make one update
URL_DELAY_MS = 1000
#: what a click does: the choices of the page's switch (Shift + click always picks)
CLICK_MODES = ("start an orbit", "pick an orbit")
#: the check box: on, a new orbit pauses those still running (Resume continues them); off, they run together
PAUSE_LABEL = "a click pauses running orbits"
#: the browser's filter of the drawn crossings: the rows of the orbits from ``first`` on (their indices)
GLYPH_FILTER = ("const o = source.data.orbit, n = o.length, rows = [];\n"
                "for (let i = 0; i < n; i++) if (o[i] >= first) rows.push(i);\n"
                "return rows;")
#: labels of the fields
LABELS = {p.name: p.symbol for p in model.PARAMETERS} | {
    "h": "h", "method": "method", "tol": "tol (taylor, dop853)", "dt": "dt (split*)",
    "crossings": "crossings per click", "phi0": "φ0 (section φ = φ0)"}


def _empty_live() -> dict:
    return {c: [] for c in _empty_crossings()}


def _empty_starts() -> dict:
    return {"orbit": [], "p1": [], "p2": [], "c": []}


class SectionPage(ReadoutMixin, LayersMixin, ExportsMixin):
    """One browser session: settings, starts, orbits, the Bokeh models and their callbacks.

    ``base``: the settings before any URL argument or field (from the scene and the command
    line); ``args``: the request's URL arguments ({name: text}); ``export_dir``: where the
    export button writes (None: the page offers the scene as a download only); ``doc``: the
    session's Bokeh document (:meth:`attach`); ``seeds``: the scene's ``[seeds]`` (a SeedSpec)
    that *Scene seeds* starts (None: the default seeds of a scene); ``megno_resolution``,
    ``megno_time``: the MEGNO layer's finest raster and its integration time."""

    def __init__(self, base: Settings, args: dict | None = None, export_dir=None, label: str = "", doc=None,
                 seeds=None, megno_resolution: int = raster_mod.RESOLUTIONS[-1],
                 megno_time: float = raster_mod.RASTER_TIME):
        self.base = base
        self.seeds = seeds
        self.settings = base
        self.export_dir = export_dir
        self.label = label
        self.starts: list[tuple] = []          # (orbit id, p1, p2, colour) of every start, in click order
        self._unmarked: list[tuple] = []        # starts whose cross is not yet in start_source
        self._color = 0
        self._running: set = set()             # ids of the orbits still computing (or paused)
        self._doc = None
        self._pending: list = []               # blocks from the worker not yet on the page
        self._pending_lock = threading.Lock()
        self._flush_at: float | None = None     # when the scheduled flush of _pending runs (monotonic)
        self._flushed_at = -math.inf            # when the last one ran
        self._url_due = False                   # a deferred _push_url is scheduled
        self._inbox: list = []                 # notebook mode: what the workers handed in (poll)
        self.indicators: dict = {}             # orbit id -> (mean MEGNO, mLCE) over INDICATOR_TIME
        self.worker = Worker(self._on_block, self._on_error, self._on_indicators)
        self.raster = raster_mod.RasterWorker(self._on_image, self._on_raster_error,
                                              raster_mod.resolutions_up_to(megno_resolution), float(megno_time))
        self._raster_generation = 0
        self.window: raster_mod.Window | None = None
        self._overlay_generation = 0
        self._readout_generation = 0
        self.dense = False                      # the density image replaces the crossings' glyphs
        self.glyph_first = 0                    # orbits from this id on are glyphs, older ones in the image
        self._density_key: tuple | None = None  # what the density image on the page shows
        self._density_at = 0.0
        self.picked: int | None = None          # the orbit whose readout is shown
        self.readouts: dict = {}                # orbit id -> orbit_readout(...) of a picked orbit
        self._build()
        if doc is not None:
            self.attach(doc)
        self._load_url(args or {})

    # ------------------------------------------------------------ layout
    def _build(self):
        self.region = ColumnDataSource({"x": [], "y": [], "width": [], "height": []}, name="region")
        # every crossing of the session, in the server (never in the document: not sent to the browser) ...
        self.crossings = ColumnDataSource(_empty_crossings())
        # ... and what the browser draws: the same rows up to density.THRESHOLD, none past it
        self.shown = ColumnDataSource(_empty_crossings(), name="crossings")
        # ... and the rows of a message with an orbit's first crossings, until the next message
        # (:meth:`_flush`): self.live holds self.crossings' rows from self._settled on
        # (as lists: a few rows as JSON, one frame of the websocket, not a binary buffer per column)
        self.live = ColumnDataSource(_empty_live(), name="live")
        self._settled = 0
        self._settle_at = -math.inf             # (monotonic) the flush due then moves the live rows
        self.start_source = ColumnDataSource(_empty_starts(), name="starts")
        colors = {"field": "c", "transform": LinearColorMapper(palette=list(COLORS), low=-0.5,
                                                                high=len(COLORS) - 0.5)}
        # Range1d, set by the server (_fit_view): a DataRange1d kept the window it started with in the
        # browser (its initial start and end) whatever the server set later, and Reset went back to it
        fig = figure(name="section", width=FIGURE_WIDTH, height=FIGURE_HEIGHT,
                     x_range=Range1d(-1.0, 1.0), y_range=Range1d(-1.0, 1.0),
                     tools="pan,wheel_zoom,box_zoom,reset,save", active_scroll="wheel_zoom",
                     x_axis_label="p1", y_axis_label="p2", background_fill_color=FORBIDDEN_COLOR,
                     toolbar_location="above")
        fig.ellipse("x", "y", width="width", height="height", source=self.region, fill_color=ALLOWED_COLOR,
                    line_color=BOUNDARY_COLOR, line_width=1.0)
        self.raster_source = ColumnDataSource(_empty_raster(), name="raster")
        megno = LinearColorMapper(palette=megno_palette(), low=MEGNO_LOW, high=MEGNO_HIGH,
                                  nan_color=(0, 0, 0, 0))
        fig.image(image="image", x="x", y="y", dw="dw", dh="dh", source=self.raster_source, color_mapper=megno,
                  alpha=0.85)
        # the MEGNO layer's scale, shown with the layer
        self.colour_bar = ColorBar(color_mapper=megno, title="⟨Y⟩ (MEGNO)", visible=False, width=12,
                                   name="megno-colour-bar")
        fig.add_layout(self.colour_bar, "right")
        self.fixed = ColumnDataSource({"p1": [], "p2": [], "kind": [], "marker": []}, name="fixed")
        self.curves = ColumnDataSource({"xs": [], "ys": []}, name="separatrices")
        self.periodic = ColumnDataSource(_empty_periodic(), name="periodic")
        # a dark casing under a bright line: visible on white and on every colour of the MEGNO layer
        self.separatrix_lines = (
            fig.multi_line("xs", "ys", source=self.curves, line_color=SEPARATRIX_CASING, line_width=3.0),
            fig.multi_line("xs", "ys", source=self.curves, line_color=SEPARATRIX_COLOR, line_width=1.4))
        self.manifold_source = ColumnDataSource(_empty_manifolds(), name="manifolds")
        fig.multi_line("xs", "ys", source=self.manifold_source, line_color="color", line_width=1.2)
        self._by_orbit = colors
        self._by_megno = {"field": "megno", "transform": LinearColorMapper(
            palette=megno_palette(MEGNO_ORBIT_SKIP), low=MEGNO_LOW, high=MEGNO_HIGH, nan_color="#9e9e9e")}
        self.density = ColumnDataSource(_empty_density(), name="density")
        fig.image_rgba(image="image", x="x", y="y", dw="dw", dh="dh", source=self.density)
        # the glyphs: only the orbits from glyph_first on (the newest, at most density.GLYPH_BUDGET
        # crossings), filtered in the browser from the rows it holds: a change of glyph_first sends
        # one number, never the rows again; the older orbits are in the density image
        self.glyph_filter = CustomJSFilter(name="glyphs", args={"first": 0}, code=GLYPH_FILTER)
        self.points = fig.scatter("p1", "p2", source=self.shown, color=colors, size=POINT_SIZE, line_width=0,
                                  view=CDSView(filter=self.glyph_filter))
        # the newest rows on the overlay canvas: Bokeh repaints only that canvas when they change
        # (not the primary one with every older crossing and the images; benchmarks/bench_serve.py)
        self.live_points = fig.scatter("p1", "p2", source=self.live, color=colors, size=POINT_SIZE, line_width=0,
                                       level="overlay")
        self.start_marks = fig.scatter("p1", "p2", source=self.start_source, marker="cross", color=colors, size=9,
                                       line_width=2, level="overlay")   # (above the crossings and the images)
        fig.scatter("p1", "p2", source=self.periodic, marker="marker", size=8, line_color="black",
                    fill_color={"field": "period", "transform": LinearColorMapper(
                        palette=list(PERIOD_COLORS), low=0.5, high=len(PERIOD_COLORS) + 0.5)}, line_width=1.5)
        fig.scatter("p1", "p2", source=self.fixed, marker="marker", size=11, line_color="black",
                    fill_color="white", line_width=2)
        fig.grid.visible = False
        fig.on_event(Tap, self._on_tap)
        fig.on_event(DoubleTap, self._on_tap)   # a second click within 300 ms is a double tap
        fig.on_event(RangesUpdate, self._on_ranges)
        self.figure = fig
        s = self.settings.fields()
        self.inputs = {}
        for name in FIELDS:
            if name == "method":
                from explorer.analysis.sections import METHODS

                w = pn.widgets.Select(label=LABELS[name], options=list(METHODS), value=s[name], width=FIELD_WIDTH)
            else:
                w = pn.widgets.TextInput(label=LABELS[name], value=s[name], width=FIELD_WIDTH)
            w.param.watch(self._field_changed, "value")
            self.inputs[name] = w
        clear = pn.widgets.Button(label="Clear", color="warning", width=90)
        clear.on_click(lambda _e: self._later(self.clear))
        undo = pn.widgets.Button(label="Undo", width=90)
        undo.on_click(lambda _e: self._later(self.undo))
        resume = pn.widgets.Button(label="Resume", width=190)
        resume.on_click(lambda _e: self._later(self.resume))
        seeds = pn.widgets.Button(label="Scene seeds", width=190)
        seeds.on_click(lambda _e: self._later(self.run_seeds))
        buttons = [clear, undo, resume, seeds]
        self.layer = pn.widgets.Checkbox(label=f"MEGNO layer (T = {self.raster.time:g})", value=False)
        self.layer.param.watch(lambda _e: self._later(self._layer_changed), "value")
        self.overlay = pn.widgets.Checkbox(label="fixed points, separatrices", value=False)
        self.overlay.param.watch(lambda _e: self._later(self._overlay_changed), "value")
        self.colour_box = pn.widgets.Checkbox(label="colour orbits by MEGNO", value=False)
        self.colour_box.param.watch(lambda _e: self._later(self._colour_changed), "value")
        self.periodic_box = pn.widgets.Checkbox(label=f"periodic orbits, periods 1-{PERIODIC_MAX}", value=False)
        self.periodic_box.param.watch(lambda _e: self._later(self._overlay_changed), "value")
        self.starts_box = pn.widgets.Checkbox(label="start markers (+)", value=True)
        self.starts_box.param.watch(lambda _e: self._later(self._starts_box_changed), "value")
        self.pause_box = pn.widgets.Checkbox(label=PAUSE_LABEL, value=True)
        self.pause_box.param.watch(lambda _e: self._later(self._push_url), "value")
        download = pn.widgets.FileDownload(callback=self._scene_file, filename=f"{export.SCENE_NAME}.toml",
                                           label="Scene (TOML)", color="primary", width=190)
        buttons.append(download)
        buttons.append(pn.Row(*(pn.widgets.FileDownload(callback=partial(self._figure_file, fmt),
                                                        filename=f"{export.SCENE_NAME}.{fmt}",
                                                        label=f"Figure ({fmt.upper()})", width=92)
                                for fmt in ("png", "svg"))))
        if self.export_dir is not None:
            save = pn.widgets.Button(label="Export scene", width=190)
            save.on_click(lambda _e: self._later(self.export))
            buttons.append(save)
            figure_button = pn.widgets.Button(label="Export figure", width=190)
            figure_button.on_click(lambda _e: self._later(self.export_figure))
            buttons.append(figure_button)
        # text, never HTML: a message may quote what was typed into a field
        self.message = Div(name="message", text="", render_as_text=True, width=FIGURE_WIDTH,
                           styles={"color": MESSAGE_ERROR_COLOR, "min-height": "1.2em"})
        self.status = Div(name="status", text="click in the white region to start an orbit", render_as_text=True,
                          width=FIGURE_WIDTH)
        self.overlay_text = Div(name="overlay", text="", render_as_text=True, width=FIGURE_WIDTH)
        self.readout = Div(name="readout", text="", render_as_text=True, width=FIGURE_WIDTH,
                           styles={"font-family": "monospace"})
        self.click_mode = pn.widgets.RadioButtonGroup(options=list(CLICK_MODES),
                                                      value=CLICK_MODES[0], width=220)
        self.title = pn.pane.Markdown(self._title())
        controls = pn.Column(pn.pane.Markdown("a click (Shift + click: pick):", margin=(0, 5)), self.click_mode,
                             self.pause_box, pn.GridBox(*self.inputs.values(), ncols=2), self.colour_box, self.layer,
                             self.overlay, self.periodic_box, self.starts_box, pn.Row(*buttons[:2]), *buttons[2:],
                             width=230)
        self.layout = pn.Row(controls, pn.Column(self.title, pn.pane.Bokeh(fig),
                                                 pn.pane.Bokeh(self.status), pn.pane.Bokeh(self.readout),
                                                 pn.pane.Bokeh(self.message), pn.pane.Bokeh(self.overlay_text)))

    def attach(self, doc) -> None:
        """The session's document: blocks are streamed into it; the worker ends with it."""
        self._doc = doc
        doc.on_session_destroyed(lambda _ctx: self.close())

    _closed = False

    def close(self) -> None:
        """Stop the session's threads (the browser tab is gone)."""
        self._closed = True
        self.worker.stop(timeout=0)
        self.raster.stop()
        self._cancel_overlay()
        self._stop_readouts()
        self._stop_manifolds()

    # ------------------------------------------------------------ state in the URL
    def _load_url(self, args: dict):
        fields = {k: v for k, v in args.items() if k in FIELDS}
        try:
            self.settings = parse_fields(self.base, fields)
            starts = parse_starts(args.get("orbits", ""))
            full = settings_mod.room_for(len(starts), self.settings.crossings)
            if full:
                raise ParameterError(full)
        except ParameterError as exc:
            self.settings, starts = self.base, []
            self.say(f"link ignored: {exc}")
        self._show_fields()
        if self.settings.phi0 != self.base.phi0:
            self.title.object = self._title()
        self._draw_region()
        if args.get("view"):
            try:
                self._show_window(parse_window(args["view"]))
            except ParameterError as exc:
                self.say(f"link's view ignored: {exc}")
        self.layer.value = args.get("megno") == "1"
        self.overlay.value = args.get("separatrices") == "1"
        self.periodic_box.value = args.get("periodic") == "1"
        self.colour_box.value = args.get("colour") == "megno"
        self.pause_box.value = args.get("pause") != "0"
        for p1, p2 in starts:
            self._start(p1, p2)

    def url_query(self) -> dict:
        """The view as URL arguments: every field and the starts."""
        q = self.settings.fields()
        q["orbits"] = format_starts((p1, p2) for _i, p1, p2, _c in self.starts)
        q["megno"] = "1" if self.layer.value else "0"
        q["separatrices"] = "1" if self.overlay.value else "0"
        q["periodic"] = "1" if self.periodic_box.value else "0"
        q["colour"] = "megno" if self.colour_box.value else "orbit"
        q["pause"] = "1" if self.pause_box.value else "0"
        if self.window is not None:
            w = self.window
            q["view"] = format_window(w)
        return q

    def _push_url_soon(self):
        """:meth:`_push_url` URL_DELAY_MS from now (one update for the clicks meanwhile); at once
        without a served document."""
        if self._doc is None:
            self._push_url()
        elif not self._url_due:
            self._url_due = True
            self._doc.add_timeout_callback(self._push_url_due, URL_DELAY_MS)

    def _push_url_due(self):
        self._url_due = False
        self._push_url()

    def _push_url(self):
        loc = pn.state.location
        if loc is not None:
            loc.update_query(**self.url_query())

    def _show_fields(self):
        s = self.settings.fields()
        for name, w in self.inputs.items():
            if w.value != s[name]:
                self._quiet = True
                try:
                    w.value = s[name]
                finally:
                    self._quiet = False

    _quiet = False

    # ------------------------------------------------------------ actions
    def _title(self) -> str:
        phi0 = self.settings.phi0
        shown = "π" if phi0 == math.pi else f"{phi0:.6g}"
        return f"### explorer: Poincaré section φ = {shown}" + (f" ({self.label})" if self.label else "")

    def _starts_box_changed(self) -> None:
        """Show or hide the clicked starts' crosses."""
        self.start_marks.visible = bool(self.starts_box.value)

    def say(self, text: str, ok: bool = False) -> None:
        """The message under the figure: a refusal or a failure in the error colour, or (``ok``) what
        went well in the success colour (:meth:`tell`)."""
        self.message_ok = bool(ok)
        color = MESSAGE_OK_COLOR if ok else MESSAGE_ERROR_COLOR
        if self.message.styles.get("color") != color:
            self.message.styles = {**self.message.styles, "color": color}
        self.message.text = text

    def tell(self, text: str) -> None:
        """A success (an export written, seeds started) under the figure, in the success colour."""
        self.say(text, ok=True)

    message_ok = False

    def _draw_region(self):
        r = self.settings.region
        if r is None:
            self.region.data = {"x": [], "y": [], "width": [], "height": []}
            self.say(f"the allowed region is empty at h = {self.settings.h:g} (h is below the minimum of "
                     "the energy on the section)")
            return
        c1, c2, r1, r2 = r
        self.region.data = {"x": [c1], "y": [c2], "width": [2 * r1], "height": [2 * r2]}
        self._fit_view(c1, c2, (1 + VIEW_MARGIN) * r1, (1 + VIEW_MARGIN) * r2)

    def _show_window(self, w) -> None:
        """Show the window ``w`` (a link's zoom; Reset still goes to the region's view)."""
        self.figure.x_range.update(start=w.x0, end=w.x1)
        self.figure.y_range.update(start=w.y0, end=w.y1)
        self.window = w

    def _fit_view(self, c1: float, c2: float, m1: float, m2: float) -> None:
        """Show the box c1 +- m1, c2 +- m2, the same length per pixel along both axes (the frame's
        size as drawn; before that, the nominal size), and make it the view Reset goes back to."""
        px, py = self._frame_px()
        scale = max(2.0 * m1 / max(px, 1.0), 2.0 * m2 / max(py, 1.0))     # p-units per pixel
        h1, h2 = 0.5 * scale * max(px, 1.0), 0.5 * scale * max(py, 1.0)
        for rng, lo, hi in ((self.figure.x_range, c1 - h1, c1 + h1), (self.figure.y_range, c2 - h2, c2 + h2)):
            rng.update(start=lo, end=hi, reset_start=lo, reset_end=hi)
        self.window = raster_mod.Window(c1 - h1, c1 + h1, c2 - h2, c2 + h2)

    def _start(self, p1: float, p2: float, color: int | None = None, mark_later: bool = False):
        """Queue the orbit from (p1, p2) and mark its start (``mark_later``, a click on a served
        page: with its first crossings, :meth:`_mark_starts`); None outside the region."""
        if not self.settings.admissible(p1, p2):
            return None
        if color is None:
            color = self._color % len(COLORS)
            self._color += 1
        run = self.worker.submit(p1, p2, self.settings)
        self.starts.append((run.ident, p1, p2, color))
        self._unmarked.append((run.ident, p1, p2, color))
        self._running = self._running | {run.ident}
        if not mark_later or self._doc is None:
            self._mark_starts()
            self._update_status()            # (else with the first crossings, in their flush)
        return run

    def _mark_starts(self):
        """Stream the crosses of the starts not yet marked.  On a served page this waits for the
        next flush, which sends a click's cross just after its first crossings (the cross's
        redraw does not delay them)."""
        live = {i for i, *_ in self.starts}
        marks, self._unmarked = [m for m in self._unmarked if m[0] in live], []
        if marks:
            self.start_source.stream({k: [m[j] for m in marks] for j, k in enumerate(("orbit", "p1", "p2", "c"))})

    def click(self, p1: float, p2: float):
        """A click at (p1, p2): a new orbit, or a message saying why not."""
        if not (math.isfinite(p1) and math.isfinite(p2)):
            return None
        full = settings_mod.room_for(len(self.starts) + 1, self.settings.crossings)
        if full:
            self.say(full)
            return None
        if self.settings.region is None:
            self.say("nothing to do: the allowed region is empty at this energy")
            return None
        if not self.settings.admissible(p1, p2):
            self.say(f"({p1:.4g}, {p2:.4g}) is outside the allowed region (M^2 < 0 there): click in the white "
                     "ellipse")
            return None
        if self.pause_box.value:
            self.worker.pause()
        run = self._start(p1, p2, mark_later=True)
        self.say("")
        self._push_url_soon()
        return run

    def resume(self) -> int:
        """Continue the orbits a click paused, from where each stopped (its rows are those of an
        uninterrupted run); returns how many."""
        n = len(self.worker.resume())
        self._update_status()
        return n

    def _on_tap(self, event):
        """Tap or double tap: Bokeh reports a click that follows another within 300 ms as a double
        tap instead of a tap; one at the place of the previous click is that click again (ignored),
        one elsewhere is a new click."""
        here = (float(event.sx), float(event.sy))
        last, self._last_tap = self._last_tap, here
        if isinstance(event, DoubleTap) and last is not None and max(abs(here[0] - last[0]),
                                                                      abs(here[1] - last[1])) <= SAME_SPOT_PX:
            return
        shift = bool((getattr(event, "modifiers", None) or {}).get("shift"))
        if shift or self.click_mode.value == CLICK_MODES[1]:
            self.pick(float(event.x), float(event.y))
        else:
            self.click(float(event.x), float(event.y))

    _last_tap: tuple | None = None

    def _post(self, action) -> None:
        """From a worker thread: run ``action`` on the document's loop (a served page), or keep it
        for :meth:`poll` (a notebook, where no Bokeh server owns the document)."""
        if self._doc is not None:
            if self._closed:
                return                       # the session is gone: nothing to show it on
            try:
                self._doc.add_next_tick_callback(action)
            except (AttributeError, RuntimeError, ValueError):
                return                       # (destroyed meanwhile: Bokeh tore the document's callbacks down)
        else:
            with self._pending_lock:
                self._inbox.append(action)

    def poll(self) -> bool:
        """Run what the workers handed in since the last call (notebook mode: a periodic
        callback calls it); returns whether there was anything."""
        with self._pending_lock:
            actions, self._inbox = self._inbox, []
        for action in actions:
            action()
        return bool(actions)

    def _later(self, action) -> None:
        """Run ``action`` on the document's loop with its lock (Panel calls widget watchers
        outside it; the Bokeh models of the figure must be changed inside), or now without one."""
        if self._doc is None:
            action()
        else:
            self._doc.add_next_tick_callback(action)

    def _field_changed(self, event):
        if not self._quiet:           # (a change made by _show_fields is not the user's)
            name = next((n for n, w in self.inputs.items() if w is event.obj), None)
            self._later(partial(self._on_field, name))

    def _on_field(self, name: str | None = None):
        """The field ``name`` was edited: the applied settings with its text (every field's text
        when None), validated by :func:`~explorer.app.serve.settings.parse_fields` as the command
        line's values are.  A refused value changes nothing and is said in the message; it stays in
        its field, but a later edit of another field is read on top of the applied settings (it does
        not quote the refused one again) and puts every field back to the applied values."""
        if name is None:
            fields = {n: w.value for n, w in self.inputs.items()}
        else:
            fields = {**self.settings.fields(), name: self.inputs[name].value}
        try:
            new = parse_fields(self.base, fields)
            full = settings_mod.room_for(len(self.starts), new.crossings)
            if full:
                raise ParameterError(f"crossings: {full}")
        except ParameterError as exc:
            self.say(f"not applied: {exc}")
            return
        self.say("")
        self._show_fields()               # (a refused text in another field goes: the fields show what applies)
        self.apply(new)

    def apply(self, new: Settings) -> None:
        """New settings: the orbits stop, the region is redrawn, the starts inside it run again."""
        if new == self.settings:
            return
        old = self._drop_orbits()
        angle_changed = new.phi0 != self.settings.phi0
        self.settings = new
        if angle_changed:                 # (only then: a change of the title is a message of its own)
            self.title.object = self._title()
        # the kept starts' crosses go before the region and the view (one message each, in order): a
        # page that shows the new region shows the starts that run again in it
        kept = [self._start(p1, p2, color) for _i, p1, p2, color in old]
        self._draw_region()
        self._show_fields()
        self._restart_raster()
        self._restart_overlay()
        dropped = sum(r is None for r in kept)
        if dropped:
            self.say(f"{dropped} start(s) outside the new allowed region dropped")
        self._update_status()        # (the orbits and values now, also when every start was dropped)
        self._push_url()

    def _drop_orbits(self) -> list:
        """Stop every orbit and take them off the page; returns their starts."""
        self.worker.cancel()
        old, self.starts, self._running = self.starts, [], set()
        self.indicators = {}
        self.readouts, self.picked = {}, None
        self._readout_generation += 1
        self._cancel_readout()
        self.readout.text = ""
        self.crossings.data = _empty_crossings()
        self._show_all()
        self.start_source.data = _empty_starts()
        self._unmarked = []
        self._refresh_density(force=True)       # no image left of them
        return old

    def clear(self) -> None:
        self._drop_orbits()
        self._update_status()
        self._push_url()

    def undo(self) -> None:
        """Remove the last orbit (stopped if it runs or is paused)."""
        if not self.starts:
            return
        ident = self.starts.pop()[0]
        self.worker.remove(ident)
        self.indicators.pop(ident, None)
        self.readouts.pop(ident, None)
        if self.picked == ident:
            self.picked, self.readout.text = None, ""
        self._running = self._running - {ident}
        keep = np.asarray(self.crossings.data["orbit"]) != ident
        self.crossings.data = {k: np.asarray(v)[keep] for k, v in self.crossings.data.items()}
        self._show_all()
        keep = [o != ident for o in self.start_source.data["orbit"]]
        self.start_source.data = {k: [x for x, ok in zip(v, keep) if ok] for k, v in self.start_source.data.items()}
        self._update_status()
        self._push_url()

    def run_seeds(self) -> int:
        """Start an orbit at each seed point of the scene's ``[seeds]`` at the current settings
        (the starts ``explorer sweep`` runs for such a panel), as clicks there would; as many as
        the session has room for.  Returns how many were started."""
        try:
            starts = settings_mod.seed_starts(self.seeds or settings_mod.seeds_for(None), self.settings)
        except ParameterError as exc:
            self.say(f"scene seeds: {exc}")
            return 0
        n = 0
        for p1, p2 in starts:
            if settings_mod.room_for(len(self.starts) + 1, self.settings.crossings):
                break
            n += self._start(p1, p2) is not None
        if n < len(starts):
            why = settings_mod.room_for(len(self.starts) + 1, self.settings.crossings)
            self.say(f"scene seeds: {n} of {len(starts)} started ({why})")
        else:
            self.tell(f"scene seeds: {n} orbits started")
        self._push_url()
        return n

    # ------------------------------------------------------------ blocks from the worker
    def _on_block(self, ident, rows, done, status):
        """In the worker thread: queue the block for the document's loop.  An orbit's first block
        and its last go at once; others at most every FLUSH_SECONDS after the last flush (each
        message redraws every crossing in the browser).  Blocks queued meanwhile go to the page
        together (one stream of rows)."""
        urgent = done == len(rows) or status != "running"
        with self._pending_lock:
            self._pending.append((ident, rows, done, status))
            now = time.monotonic()
            at = now if urgent else max(now, self._flushed_at + FLUSH_SECONDS)
            if self._flush_at is not None and self._flush_at <= at:
                return                   # a flush is scheduled already, soon enough
            self._flush_at = at
        self._post(partial(self._flush_when, at))       # (add_timeout_callback is not thread-safe)

    def _flush_when(self, at: float) -> None:
        """On the document's loop: :meth:`_flush` at ``at`` (time.monotonic), now if it is past."""
        wait = at - time.monotonic()
        if self._doc is None or wait < 0.001:
            self._flush()
        else:
            self._doc.add_timeout_callback(self._flush, int(1000 * wait) + 1)

    def _flush(self):
        """The queued blocks onto the page.  Bokeh sends each change of a model as its own message,
        in order, all written before the next callback runs.  Not through Panel's ``unlocked`` (one
        message per flush): when the socket was busy it queued the message for a task that could
        return without sending it (panel 1.9), and an orbit's last rows never reached the browser
        (tests/app/test_serve.py, the slow-connection test).

        A flush that carries an orbit's first crossings sends them to ``live`` (drawn on the
        overlay canvas: the browser repaints that alone, not the older crossings and the images,
        about 5 us per dot in headless chromium), then the starts' crosses (also on the overlay),
        and nothing else: the status line and the density image, whose changes make the browser
        lay out the page or repaint everything, wait for the flush FLUSH_SECONDS later
        (:meth:`_settle_later`), which moves the live rows to ``crossings``.  A few rows that come
        before it (a short orbit's last block, sent at once; LIVE_MAX_ROWS) go to ``live`` too:
        otherwise the browser, taking both messages in one frame, would repaint everything for
        the first rows."""
        with self._pending_lock:
            blocks, self._pending = self._pending, []
            now = time.monotonic()
            self._flush_at, self._flushed_at = None, now
        live = {i: c for i, _a, _b, c in self.starts}
        blocks = [b for b in blocks if b[0] in live]          # undone or cancelled meanwhile: dropped
        first_rows = {b[0] for b in blocks if 0 < len(b[1]) == b[2]}   # orbits at their first block
        if first_rows and any(b[0] not in first_rows for b in blocks):
            with self._pending_lock:     # other orbits' blocks wait for the next flush: these go alone
                self._pending[:0] = [b for b in blocks if b[0] not in first_rows]
            blocks = [b for b in blocks if b[0] in first_rows]
        full = [b for b in blocks if len(b[1])]
        held = len(self.live.data["orbit"])
        # (SETTLE_SLACK: a timer is never early by more; a flush it runs must settle)
        to_live = bool(first_rows) or (0 < held and now < self._settle_at - SETTLE_SLACK
                                       and held + sum(len(b[1]) for b in full) <= LIVE_MAX_ROWS)
        if full:
            data = np.concatenate([b[1] for b in full])
            megno = [self.indicators.get(b[0], (math.nan,))[0] for b in full]
            new = {"orbit": np.concatenate([np.full(len(b[1]), b[0], np.int64) for b in full]),
                   "megno": np.concatenate([np.full(len(b[1]), m) for b, m in zip(full, megno)]),
                   "t": data[:, 0], "p1": data[:, 1], "p2": data[:, 2], "M": data[:, 3], "dH": data[:, 4],
                   "c": np.concatenate([np.full(len(b[1]), live[b[0]], np.int64) for b in full])}
            self.crossings.stream(new)
            if to_live:
                self.live.stream({k: v.tolist() for k, v in new.items()})   # drawn at once, alone
        moved = False if to_live else self._settle()
        self._mark_starts()              # (their starts' crosses in the next message)
        for ident, _rows, done, status in blocks:
            if status != "running":
                self._running = self._running - {ident}
                if status != "done":
                    self.say(f"orbit {ident} stopped after {done} crossings: {status}")
        if first_rows:
            self._settle_later()
        elif not to_live:
            self._update_status(force_density=self.dense and moved)

    def _settle(self) -> bool:
        """The live rows to ``crossings`` (past density.THRESHOLD, to the density image only: the
        caller redraws it at once), streamed before ``live`` empties (never a frame without them);
        returns whether there were live rows."""
        moved = bool(len(self.live.data["orbit"]))
        n = len(self.crossings.data["orbit"])
        if n > self._settled:
            if not self.dense:
                self.shown.stream({k: np.asarray(v)[self._settled:] for k, v in self.crossings.data.items()})
            self._settled = n
        if moved:
            self.live.data = _empty_live()
        return moved

    def _settle_later(self) -> None:
        """A flush FLUSH_SECONDS after this one, whether blocks come or not (it settles the live
        rows; blocks handed in meanwhile go with it); in a notebook, at the next :meth:`poll`."""
        if self._doc is None:
            with self._pending_lock:
                self._inbox.append(self._flush)
            return
        with self._pending_lock:
            at = self._flushed_at + FLUSH_SECONDS        # (the time _on_block gives a block)
            self._settle_at = at
            if self._flush_at is None or self._flush_at > at:
                self._flush_at = at
        self._flush_when(at)     # (always: a flush scheduled sooner runs before the rows are due)

    def _show_all(self) -> None:
        """The browser's rows anew: every crossing in ``crossings`` (none past density.THRESHOLD),
        none live (after an undo, a clear, a change of settings or of the threshold's side)."""
        self.shown.data = _empty_crossings() if self.dense else dict(self.crossings.data)
        if len(self.live.data["orbit"]):
            self.live.data = _empty_live()
        self._settled = len(self.crossings.data["orbit"])

    def _on_error(self, ident, exc):
        self._post(partial(self._fail, ident, f"orbit {ident} failed: {type(exc).__name__}: "
                                               f"{' '.join(str(exc).split())}"))

    def _fail(self, ident, msg):
        self._mark_starts()
        self._running = self._running - {ident}
        self.say(msg)
        self._update_status()

    def _update_status(self, force_density: bool = False):
        """The status line (and the density image, at once if ``force_density``)."""
        # the worker's paused orbits still running here (one paused as its last block came is done)
        paused = len(self._running.intersection(self.worker.paused()))
        running = len(self._running) - paused
        n = len(self.crossings.data["orbit"])
        self._refresh_density(force=force_density or not running)   # (at once when the last orbit is done)
        text = (f"{len(self.starts)} orbit(s), {running} running, "
                + (f"{paused} paused (Resume continues them), " if paused else "") + f"{n} crossings drawn"
                + (" (as a density image)" if self.dense else "") + "; "
                f"mu = {self.settings.params.mu:g}, h = {self.settings.h:g}, {self.settings.method}")
        known = [i for i, *_ in self.starts if i in self.indicators]
        if known:
            megno, mlce = self.indicators[known[-1]]
            kind = "chaotic-like" if megno > CHAOTIC_MEGNO else "regular-like"
            text += (f"; orbit {known[-1]}: <Y> = {megno:.3g}, mLCE = {mlce:.3g} over t <= {INDICATOR_TIME:g}"
                     + (f" ({kind})" if math.isfinite(megno) else " (unknown: the run stopped early)"))
        self.status.text = text


def session_app(base: Settings, export_dir=None, label: str = "", **page_options):
    """A Panel app function for ``pn.serve``: one :class:`SectionPage` per session, built from
    the session's URL arguments (``page_options``: seeds, megno_resolution, megno_time)."""
    def app():
        args = {k: v[0].decode("utf-8", "replace") for k, v in (pn.state.session_args or {}).items() if v}
        try:
            page = SectionPage(base, args, export_dir=export_dir, label=label, doc=pn.state.curdoc, **page_options)
        except Exception as exc:  # noqa: BLE001 - a link the checks let through: the page without it, and why
            page = SectionPage(base, {}, export_dir=export_dir, label=label, doc=pn.state.curdoc, **page_options)
            page.say(f"link ignored: {type(exc).__name__}: {' '.join(str(exc).split())}")
        return page.layout
    return app
