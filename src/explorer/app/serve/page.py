"""The page of ``explorer serve``: one :class:`SectionPage` per browser session, made of components
that each own their Bokeh models, widgets and state (docs/architecture.md, "The page"):

=====================  ==============================================================================
:class:`~explorer.app.serve.view.SectionView`               the figure, the allowed region, the window
:class:`~explorer.app.serve.page_orbits.OrbitsLayer`        starts, crossings, live layer, status
:class:`~explorer.app.serve.page_layers.DensityImage`       many crossings as an image
:class:`~explorer.app.serve.page_layers.ChaosLayer`         the chaos raster (MEGNO or frequency diffusion)
:class:`~explorer.app.serve.page_overlays.Overlays`         fixed points, separatrices, periodic orbits
:class:`~explorer.app.serve.page_readout.Readout`           a picked orbit's mLCE, MEGNO, rotation
:class:`~explorer.app.serve.page_orbit_list.OrbitList`      the orbit list: select, hide, delete
:class:`~explorer.app.serve.page_exports.Exports`           scene, store, figure files
:class:`~explorer.app.serve.page_message.Message`           the message line (refusals, successes)
:class:`UrlState`                                           the link (``pn.state.location.sync``)
=====================  ==============================================================================

Every background job runs through the session's task helper (:mod:`explorer.app.serve.tasks`).
This class holds the settings and the fields, and routes a click, the buttons and a change of a
value to the components.  The Bokeh models are found in the browser by name
(``Bokeh.documents[0].get_model_by_name(NAME)``; the tests read them there): ``message`` is the
last message (a refused value, an export, a click outside the region), ``section`` the figure, and
each component's docstring lists its own.

Values from the page are read by :func:`explorer.app.serve.settings.parse_fields`; a refused value
leaves everything as it was and says why in ``message``.
"""
from __future__ import annotations

import contextlib
import math
import time
from urllib.parse import parse_qsl, urlsplit

import panel as pn
import param
from bokeh.events import ConnectionLost, DoubleTap, PressUp, Tap

from explorer.app.serve import export
from explorer.app.serve import raster as raster_mod
from explorer.app.serve import settings as settings_mod
from explorer.app.serve.page_exports import Exports
from explorer.app.serve.page_fields import LABELS, Fields  # noqa: F401
from explorer.app.serve.page_layers import ChaosLayer, DensityImage
from explorer.app.serve.page_message import Message
from explorer.app.serve.page_orbit_list import OrbitList
from explorer.app.serve.page_orbits import (  # noqa: F401  (the page's constants)
    FLUSH_SECONDS,
    LIVE_MAX_ROWS,
    PAUSE_LABEL,
    SETTLE_SLACK,
    OrbitsLayer,
)
from explorer.app.serve.page_overlays import Overlays
from explorer.app.serve.page_readout import Readout
from explorer.app.serve.settings import FIELDS, Settings, format_window
from explorer.app.serve.style import (
    FIGURE_CHROME_PX,
    FIGURE_HEIGHT,
    FIGURE_MIN_WIDTH,
    FIGURE_WIDTH,
)
from explorer.app.serve.tasks import SessionLoop
from explorer.app.serve.view import SectionView
from explorer.model import ParameterError

#: a double tap within this many pixels of the click before it is that click again
SAME_SPOT_PX = 4.0
#: a zoom or pan reaches the link this long after the view stopped moving (s): one update per gesture
URL_DELAY_SECONDS = 0.5
#: what a click does: the choices of the page's switch (Shift + click always picks)
CLICK_MODES = ("start an orbit", "pick an orbit")
#: the URL's arguments besides the fields (what url_query writes)
URL_EXTRAS = ("orbits", "hidden", "megno", "indicator", "separatrices", "periodic", "colour", "pause", "view")
#: attributes of the page that are its components' (page.crossings is page.orbits.crossings, ...)
FACADE = {"orbits": ("crossings", "shown", "live", "start_source", "points", "live_points", "start_marks",
                     "glyph_filter", "colour_box", "starts_box", "pause_box", "status", "worker", "starts",
                     "indicators", "_running", "_flush", "_on_block", "_on_indicators", "update_status"),
          "section": ("figure", "region", "window", "_on_ranges"),
          "density_image": ("density", "dense"), "chaos": ("layer", "colour_bar", "raster_source"),
          "overlays": ("fixed", "curves", "periodic", "manifold_source", "overlay", "periodic_box",
                       "separatrix_lines", "show_manifolds", "saddle_near"),
          "readout_": ("pick", "select", "picked", "readouts"), "orbit_list": ("clear", "undo", "resume"),
          "messages": ("message", "message_ok", "say", "tell"),
          "exports": ("view", "figure_bytes", "export_figure", "export", "scene_text", "_scene_text")}
_FACADE = {a: c for c, names in FACADE.items() for a in names}


class UrlState(param.Parameterized):
    """The link of a page: every field and :data:`URL_EXTRAS`, as text, kept in the browser's
    address by ``pn.state.location.sync`` once :meth:`attach` ed (a notebook's page has none).

    The page's link is the truth, and the address heals to it: Panel's location is written from
    both ends, so a write can be overtaken by an older value.  Whenever the location reports an
    address (``search``, or ``href``: what the browser shows) that lacks a value of the link, the
    link is written again (:meth:`_heal`)."""

    def attach(self, location, loop) -> None:
        """Keep the browser's address (Panel's ``location``) this link from now on; ``loop``: the
        session's :class:`~explorer.app.serve.tasks.SessionLoop`, where a stale address is healed."""
        # (the address first: sync reads it into the link, and a link the page ignored is not the page's)
        location.update_query(**{n: getattr(self, n) for n in FIELDS + URL_EXTRAS})
        location.sync(self, on_error=lambda _values: None)
        self._location, self._loop = location, loop
        location.param.watch(self._on_address, ["search", "href"])

    def write(self, link: dict) -> None:
        """The link anew ({name: text}).  The address holds the whole link: when the page loads,
        the browser gives Panel's location the address it was opened at (a bare address: no query
        at all), and ``sync`` writes only the values that change after that, so the address would
        hold only those (``?orbits=...`` without the fields); it is written whole when any
        non-empty value of the link is missing from it."""
        self._link = dict(link)
        with self._sent_by_bokeh():
            self.param.update(**link)
            if self._location is not None and self._lacks(self._location.search):
                self._location.update_query(**link)

    def _sent_by_bokeh(self):
        """The address's changes sent by Bokeh, not by Panel's own writer, which loses one now and
        then (SessionLoop.bokeh_sends); no hold before attach (a notebook, a page being built)."""
        return self._loop.bokeh_sends() if self._loop is not None else contextlib.nullcontext()

    def _lacks(self, query: str) -> bool:
        """Whether the address's query text lacks a non-empty value of the page's link (compared as
        text: Panel's query_params turns numbers into floats and drops empty values, which its own
        updates leave out too, and which mean "none")."""
        have = dict(parse_qsl(query.lstrip("?"), keep_blank_values=True))
        return any(v and have.get(k) != v for k, v in self._link.items())

    def _on_address(self, event) -> None:
        """A watcher of the location's ``search`` and ``href``: a changed address that lacks the
        link is healed on the session's loop (not inside Panel's own update that reported it)."""
        if event.new != event.old and self._lacks(self._query(event.name, event.new)):
            self._loop.soon(self._heal)

    @staticmethod
    def _query(name: str, address: str) -> str:
        return urlsplit(address).query if name == "href" else address

    def _heal(self) -> None:
        """The link written again, whole: into Panel's location when its ``search`` lacks it (the
        link and the address both take it, as :meth:`write` does), else sent to the browser again
        (``param.trigger``: Panel updates its model with the value it holds, which reaches the
        browser only when the model held another, an older write that landed last).  Once the
        browser shows the link, its ``href`` matches and nothing more is sent."""
        location = self._location
        if self._lacks(location.search):
            self.write(self._link)
        elif self._lacks(self._query("href", location.href or "")):
            with self._sent_by_bokeh():
                location.param.trigger("search")

    _location = None            # Panel's location of a served page (attach), else None
    _loop = None                # the session's loop (attach)
    _link: dict = {}            # the page's link as last written ({name: text})


for _name in FIELDS + URL_EXTRAS:
    UrlState.param.add_parameter(_name, param.String(default=""))


class SectionPage:
    """One browser session (module docstring).  ``base``: the settings before any URL argument or
    field; ``args``: the request's URL arguments ({name: text}); ``export_dir``: where the export
    buttons write (None: downloads only); ``doc``: the session's Bokeh document (None: a notebook,
    :meth:`poll`); ``seeds``: the scene's ``[seeds]`` that *Scene seeds* starts;
    ``megno_resolution``, ``megno_time``: the MEGNO layer's finest raster and its integration time."""

    def __init__(self, base: Settings, args: dict | None = None, export_dir=None, label: str = "", doc=None,
                 seeds=None, megno_resolution: int = raster_mod.RESOLUTIONS[-1],
                 megno_time: float = raster_mod.RASTER_TIME):
        self.base = self.settings = base
        self.seeds, self.export_dir, self.label = seeds, export_dir, label
        self.loop = SessionLoop(doc)
        self.messages = Message()
        self.url_state = UrlState()
        self.section = SectionView()
        self.orbits = OrbitsLayer(self, self.section, self.loop)
        self.density_image = DensityImage(self.orbits, self.section)
        self.chaos = ChaosLayer(self, self.section, self.loop, raster_mod.resolutions_up_to(megno_resolution),
                                megno_time)
        self.overlays = Overlays(self, self.section, self.loop)
        self.readout_ = Readout(self, self.section, self.orbits, self.overlays, self.loop)
        self.orbit_list = OrbitList(self.orbits, self.readout_, self.loop, on_changed=self.push_url)
        self.exports = Exports(self, self.loop, export_dir, label)
        self.readout, self.overlay_text = self.readout_.text, self.overlays.text
        self._url_timer = self.loop.timer(self.push_url)
        self.section.on_window(lambda: self._url_timer.at(time.monotonic() + URL_DELAY_SECONDS))
        fig = self.section.figure
        self.chaos.draw(fig)
        self.overlays.draw_lines(fig)
        self.density_image.draw(fig)
        self.orbits.draw(fig)
        self.orbit_list.draw(fig)
        self.overlays.draw_marks(fig)
        fig.on_event(Tap, self._on_tap)
        fig.on_event(DoubleTap, self._on_tap)   # a second click within 300 ms is a double tap
        fig.on_event(PressUp, self._on_tap)     # a click held 300 ms or more is a press
        self._build()
        if doc is not None:
            # the tab is gone (its websocket closed, or a page never connected expired): its jobs
            # stop now, not when Bokeh discards the session
            doc.on_event(ConnectionLost, lambda _e: self.close())
            doc.on_session_destroyed(lambda _ctx: self.close())
        self._load_url(args or {})

    def __getattr__(self, name):
        owner = _FACADE.get(name)
        if owner is None:
            raise AttributeError(name)
        return getattr(self.__dict__[owner], name)

    def __setattr__(self, name, value):
        owner = _FACADE.get(name)
        object.__setattr__(self.__dict__[owner] if owner else self, name, value)

    # ------------------------------------------------------------ layout
    def _build(self):
        self.fields = Fields(self.loop, self.settings, self._on_field)
        self.inputs = self.fields.inputs
        # the buttons in rows above the figure: at 1280 x 720 every one is in view with the figure
        # (in the controls' column, below the fields, the export buttons were below the fold)
        buttons = []
        ol = self.orbit_list
        for label, action, width in (("Clear", ol.clear, 70), ("Undo", ol.undo, 70), ("Resume", ol.resume, 80),
                                     ("Scene seeds", self.run_seeds, 100)):
            b = pn.widgets.Button(label=label, width=width, color="warning" if label == "Clear" else "default")
            b.on_click(lambda _e, action=action: self.loop.soon(action))
            buttons.append(b)
        buttons.append(pn.widgets.FileDownload(callback=self.exports.scene_file, filename=f"{export.SCENE_NAME}.toml",
                                               label="Scene (TOML)", color="primary", width=110))
        buttons += [pn.widgets.FileDownload(callback=lambda fmt=fmt: self.exports.figure_file(fmt),
                                            filename=f"{export.SCENE_NAME}.{fmt}", label=f"Figure ({fmt.upper()})",
                                            width=100) for fmt in ("png", "svg")]
        if self.export_dir is not None:
            for label, action in (("Export scene", self.exports.export), ("Export figure", self.exports.export_figure)):
                b = pn.widgets.Button(label=label, width=110)
                b.on_click(lambda _e, action=action: self.loop.soon(action))
                buttons.append(b)
        self.click_mode = pn.widgets.RadioButtonGroup(options=list(CLICK_MODES), value=CLICK_MODES[0], width=220)
        self.title = pn.pane.Markdown(self._title())
        o, ov = self.orbits, self.overlays
        controls = pn.Column(pn.pane.Markdown("a click (Shift + click: pick):", margin=(0, 5)), self.click_mode,
                             o.pause_box, self.fields.grid, o.colour_box, self.chaos.layer, self.chaos.indicator,
                             ov.overlay, ov.periodic_box, o.starts_box, width=230)
        texts = (o.status, self.readout, self.message, self.overlay_text)
        for div in texts:
            div.sizing_mode = "stretch_width"
        bar = pn.FlexBox(*buttons, flex_wrap="wrap", sizing_mode="stretch_width")
        # the figure as wide as the window leaves it, and no taller than the window less the lines
        # above and below it (a CSS bound on its width: the figure keeps its aspect, view.py)
        aspect = FIGURE_WIDTH / FIGURE_HEIGHT
        self.section.figure.styles = {"max-width": f"max({FIGURE_MIN_WIDTH}px, calc((100vh - {FIGURE_CHROME_PX}px)"
                                                   f" * {aspect:.6f}))"}
        plot = pn.pane.Bokeh(self.section.figure, sizing_mode="stretch_width")
        self.layout = pn.Row(controls, pn.Column(self.title, bar, plot, *(pn.pane.Bokeh(d) for d in texts),
                                                 self.orbit_list.panel, sizing_mode="stretch_width"),
                             sizing_mode="stretch_width")

    _closed = False

    def close(self) -> None:
        """Stop the session's jobs (the browser tab is gone)."""
        self._closed = True
        self._url_timer.cancel()
        self.orbits.close()
        self.loop.close()

    def poll(self) -> bool:
        """Run what the jobs handed in since the last call (notebook mode: a periodic callback
        calls it); returns whether there was anything."""
        return self.loop.poll()

    # ------------------------------------------------------------ state in the URL
    def _load_url(self, args: dict):
        fields = {k: v for k, v in args.items() if k in FIELDS}
        self.settings, refused = settings_mod.parse_link_fields(self.base, fields)
        try:
            starts = settings_mod.parse_starts(args.get("orbits", ""))
            full = settings_mod.room_for(len(starts), self.settings.crossings)
            if full:
                raise ParameterError(full)
        except ParameterError as exc:
            # (no starts: their ``hidden`` goes with them)
            starts, args = [], {k: v for k, v in args.items() if k != "hidden"}
            refused.append(str(exc))
        if refused:
            self.say(f"link ignored in part (the rest applies): {'; '.join(refused)}")
        self._show_fields()
        if self.settings.phi0 != self.base.phi0:
            self.title.object = self._title()
        self._draw_region()
        if args.get("view"):
            try:
                self.section.show_window(settings_mod.parse_window(args["view"]))
            except ParameterError as exc:
                self.say(f"link's view ignored: {exc}")
        self.chaos.load_url(args)                 # (its indicator, then its box)
        self.overlays.overlay.value = args.get("separatrices") == "1"
        self.overlays.periodic_box.value = args.get("periodic") == "1"
        self.orbits.colour_box.value = args.get("colour") == "megno"
        self.orbits.pause_box.value = args.get("pause") != "0"
        self.orbit_list.load_url(starts, args.get("hidden", ""))
        self.push_url()

    def url_query(self) -> dict:
        """The view as URL arguments: every field, the starts (and which are hidden), the boxes and
        the window."""
        q = self.settings.fields()
        q.update(self.orbit_list.url_query())
        for name, box in (("separatrices", self.overlays.overlay), ("periodic", self.overlays.periodic_box),
                          ("pause", self.orbits.pause_box)):
            q[name] = "1" if box.value else "0"
        q.update(self.chaos.url_query())
        q["colour"] = "megno" if self.orbits.colour_box.value else "orbit"
        w = self.section.window
        q["view"] = "" if w is None else format_window(w)
        return q

    def push_url(self):
        """The link anew (UrlState.write; the browser's address follows it once attached)."""
        self._url_timer.cancel()
        self.url_state.write(self.url_query())

    def overlays_on(self) -> tuple:
        """The names of the overlays that are on (separatrices, periodic, and the chaos layer by its
        indicator: megno or frequency_diffusion), for the exported scene's description."""
        return self.overlays.on() + ((self.chaos.indicator.value,) if self.chaos.layer.value else ())

    def _show_fields(self):
        self.fields.show(self.settings)

    # ------------------------------------------------------------ values
    def _on_field(self, name: str | None = None):
        """The field ``name`` was edited: the applied settings with its text (every field's text
        when None), validated as the command line's values are (Fields.read).  A refused value
        changes nothing and is said in the message; it stays in its field, but a later edit of
        another field is read on top of the applied settings (it does not quote the refused one
        again) and puts every field back to the applied values."""
        try:
            new = self.fields.read(self.base, self.settings, len(self.orbits.starts), name)
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
        hidden = set(self.orbits.hidden)
        old = self._drop_orbits()
        angle_changed = new.phi0 != self.settings.phi0
        self.settings = new
        if angle_changed:                 # (only then: a change of the title is a message of its own)
            self.title.object = self._title()
        # the kept starts' crosses go before the region and the view (one message each, in order): a
        # page that shows the new region shows the starts that run again in it
        kept = [self.orbits.start(p1, p2, color, ident=i) for i, p1, p2, color in old]   # (their ids kept)
        for run, (i, *_s) in zip(kept, old):
            if run is not None and i in hidden:
                self.orbits.hide(run.ident)           # (a hidden orbit stays hidden)
        self._draw_region()
        self._show_fields()
        self.chaos.restart()
        self.overlays.restart()
        dropped = sum(r is None for r in kept)
        if dropped:
            self.say(f"{dropped} start(s) outside the new allowed region dropped")
        self.orbits.update_status()   # (the orbits and values now, also when every start was dropped)
        self.push_url()

    def _draw_region(self):
        self.section.draw_region(self.settings.region)
        if self.settings.region is None:
            self.say(f"the allowed region is empty at h = {self.settings.h:g} (h is below the minimum of "
                     "the energy on the section)")

    def _title(self) -> str:
        phi0 = self.settings.phi0
        shown = "π" if phi0 == math.pi else f"{phi0:.6g}"
        return f"### explorer: Poincaré section φ = {shown}" + (f" ({self.label})" if self.label else "")

    # ------------------------------------------------------------ orbits
    def _drop_orbits(self) -> list:
        """Stop every orbit and take them off the page; returns their starts."""
        self.readout_.forget()
        old = self.orbits.drop_all()
        self.density_image.refresh(force=True)       # no image left of them
        return old

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
            if settings_mod.room_for(len(self.orbits.starts) + 1, self.settings.crossings):
                break
            n += self.orbits.start(p1, p2) is not None
        if n < len(starts):
            why = settings_mod.room_for(len(self.orbits.starts) + 1, self.settings.crossings)
            self.say(f"scene seeds: {n} of {len(starts)} started ({why})")
        else:
            self.tell(f"scene seeds: {n} orbits started")
        self.push_url()
        return n

    def click(self, p1: float, p2: float):
        """A click at (p1, p2): a new orbit (its start reaches the link with its first crossings,
        OrbitsLayer._flush), or a message saying why not."""
        if not (math.isfinite(p1) and math.isfinite(p2)):
            return None
        full = settings_mod.room_for(len(self.orbits.starts) + 1, self.settings.crossings)
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
        if self.orbits.pause_box.value:
            self.orbits.worker.pause()
        run = self.orbits.start(p1, p2, mark_later=True)
        self.say("")
        if self.loop.doc is None:
            self.push_url()
        return run

    def _on_tap(self, event):
        """Tap, double tap or the end of a press: Bokeh reports a click that follows another within
        300 ms as a double tap instead of a tap; one at the place of the previous click is that
        click again (ignored), one elsewhere is a new click.  A button held 300 ms or more without
        moving is a press, and its release a click too (a slow click, or a quick one whose button
        up reaches a busy browser late: Bokeh's press timer fires first, and the click was lost)."""
        here = (float(event.sx), float(event.sy))
        last, self._last_tap = self._last_tap, here
        if isinstance(event, DoubleTap) and last is not None and max(abs(here[0] - last[0]),
                                                                      abs(here[1] - last[1])) <= SAME_SPOT_PX:
            return
        shift = bool((getattr(event, "modifiers", None) or {}).get("shift"))
        if shift or self.click_mode.value == CLICK_MODES[1]:
            self.readout_.pick(float(event.x), float(event.y))
        else:
            self.click(float(event.x), float(event.y))

    _last_tap: tuple | None = None


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
        if pn.state.location is not None:
            page.url_state.attach(pn.state.location, page.loop)
        return page.layout
    return app
