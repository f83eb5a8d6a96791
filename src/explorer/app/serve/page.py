"""The page of ``explorer serve``: one :class:`SectionPage` per browser session, made of components that own
their models, widgets and state (docs/architecture.md, "The page"); it holds the settings, the fields and the
link, and routes clicks, buttons and values to the components."""
from __future__ import annotations

import math
from dataclasses import replace
from urllib.parse import urlencode

import panel as pn
from bokeh.events import ConnectionLost, DocumentReady, DoubleTap, PressUp, Tap
from bokeh.models import CustomJS, Div

from explorer.app.serve import export, style
from explorer.app.serve import raster as raster_mod
from explorer.app.serve import settings as settings_mod
from explorer.app.serve.image import View
from explorer.app.serve.page_fields import Fields
from explorer.app.serve.page_layers import ChaosLayer, DensityImage
from explorer.app.serve.page_orbit_list import OrbitList
from explorer.app.serve.page_orbits import OrbitsLayer
from explorer.app.serve.page_overlays import Overlays
from explorer.app.serve.settings import TOKEN_ARG, Settings
from explorer.app.serve.tasks import Session, failure
from explorer.app.serve.view import SectionView
from explorer.model import ParameterError

#: a double tap within this many pixels of the click before it is that click again
SAME_SPOT_PX = 4.0
#: what a click does: the choices of the page's switch (Shift + click always picks)
CLICK_MODES = ("start an orbit", "pick an orbit")
#: a served page's address: the text of its ``link`` as the query, the token kept, replacing the
#: address (no history entry), when the document is ready and at every change of the link
WRITE_LINK = """const token = new URLSearchParams(window.location.search).get("token");
const query = (token === null ? [] : ["token=" + encodeURIComponent(token)]).concat(link.text ? [link.text] : []);
window.history.replaceState(window.history.state, "", window.location.pathname + "?" + query.join("&"));"""


class SectionPage:
    """One browser session: ``base`` the settings before the URL arguments ``args`` ({name: text}); ``export_dir``
    where the export buttons write (None: downloads only); ``doc`` the session's Bokeh document (None: no server);
    ``seeds`` the scene's ``[seeds]``; ``megno_resolution``, ``megno_time``: the MEGNO layer's finest raster;
    ``loop`` the event loop of its work without a server (tasks.Session)."""

    def __init__(self, base: Settings, args: dict | None = None, export_dir=None, label: str = "", doc=None,
                 seeds=None, megno_resolution: int = raster_mod.RESOLUTIONS[-1],
                 megno_time: float = raster_mod.RASTER_TIME, loop=None):
        self.base = self.settings = base
        self.seeds = seeds
        self.suffix = f" ({label})" if label else ""      # (the label after the page's and an image's title)
        self.session = Session(doc, loop)
        # the message line under the figure: text, never HTML (a message may quote a field)
        self.message = Div(name="message", text="", render_as_text=True,
                           styles={"color": style.MESSAGE_ERROR_COLOR, "min-height": "1.2em"})
        # the link (push_url): sent by Bokeh's own dispatch, written into the address in the browser
        self.link = Div(name="link", text="", visible=False)
        self.section = SectionView()
        fig = self.section.figure
        fig.xaxis.axis_label, fig.yaxis.axis_label = base.axes
        self.orbits = OrbitsLayer(self, self.section, self.session)
        self.density_image = DensityImage(self.orbits, self.section)
        self.chaos = ChaosLayer(self.section, self.session, raster_mod.resolutions_up_to(megno_resolution),
                                megno_time, lambda: self.settings, self.say, self.push_url)
        self.overlays = Overlays(self.section, self.session, lambda: self.settings, self.push_url)
        self.orbit_list = OrbitList(self.orbits, self.overlays, self.section, self.session, lambda: self.settings,
                                    self.say, on_changed=self.push_url)
        # each reads and writes its own link arguments (load_url, url_query), in this order
        self.link_parts = (self.section, self.chaos, self.overlays, self.orbits, self.orbit_list)
        self.exports = export.Exports(self.session, export_dir, self.scene, self.view, self.say)
        self.section.on_window(self.push_url)       # (the browser sends one window per zoom or pan: view.py)
        for draw in (self.chaos.draw, self.overlays.draw_lines, self.density_image.draw, self.orbits.draw,
                     self.orbit_list.draw, self.overlays.draw_marks):      # (bottom to top)
            draw(fig)
        self.chaos.layer.param.watch(lambda e: self.session.soon(lambda: self.orbits.case_dots(e.new)), "value")
        for event in (Tap, DoubleTap, PressUp):     # a second click within 300 ms is a double tap, one held 300 ms
            fig.on_event(event, self._on_tap)       # or more a press: each a click
        self._build()
        if doc is not None:       # the tab is gone (or never connected): its work stops now
            doc.on_event(ConnectionLost, lambda _e: self.close())
            doc.on_session_destroyed(lambda _ctx: self.close())
        self._load_url(args or {})

    # ------------------------------------------------------------ layout
    def _build(self):
        self.fields = Fields(self.session, lambda: self.settings, self._on_field)
        self.inputs = self.fields.inputs
        # the buttons in rows above the figure: at 1280 x 720 every one is in view with the figure
        ol, ex, scene = self.orbit_list, self.exports, self.base.scene_export
        actions = [("Clear", ol.clear, 70), ("Undo", ol.undo, 70), ("Resume", ol.resume, 80),
                   ("Scene seeds", self.run_seeds, 100)]
        if ex.export_dir is not None:
            actions += [("Export scene", ex.export, 110)] * scene + [("Export figure", ex.export_figure, 110)]
        buttons = []
        for label, action, width in actions:
            b = pn.widgets.Button(label=label, width=width, color="warning" if label == "Clear" else "default")
            b.on_click(lambda _e, action=action: self.session.soon(action))
            buttons.append(b)
        downloads = [("Scene (TOML)", "toml")] * scene + [(f"Figure ({x.upper()})", x) for x in ("png", "svg")]
        buttons[4:4] = [pn.widgets.FileDownload(callback=lambda x=x: ex.download(x), label=label,
                                                filename=f"{export.SCENE_NAME}.{x}", width=110 if x == "toml" else 100,
                                                color="primary" if x == "toml" else "default")
                        for label, x in downloads]
        self.click_mode = pn.widgets.RadioButtonGroup(options=list(CLICK_MODES), value=CLICK_MODES[0], width=220)
        self.title = pn.pane.Markdown()         # (the settings' title: _show_section)
        o, ov = self.orbits, self.overlays
        controls = pn.Column(pn.pane.Markdown("a click (Shift + click: pick):", margin=(0, 5)), self.click_mode,
                             o.pause_box, self.fields.grid, o.colour_box, self.chaos.layer, self.chaos.indicator,
                             ov.overlay, ov.periodic_box, o.starts_box, width=230)
        texts = (o.status, self.orbit_list.text, self.message, self.overlays.text, self.link)
        for div in texts:
            div.sizing_mode = "stretch_width"
        bar = pn.FlexBox(*buttons, flex_wrap="wrap", sizing_mode="stretch_width")
        self.section.figure.styles = {"max-width": style.FIGURE_MAX_WIDTH}
        plot = pn.pane.Bokeh(self.section.figure, sizing_mode="stretch_width")
        self.layout = pn.Row(controls, pn.Column(self.title, bar, pn.Row(plot, self.orbit_list.panel,
                                                                         sizing_mode="stretch_width"),
                                                 *(pn.pane.Bokeh(d) for d in texts), sizing_mode="stretch_width"),
                             sizing_mode="stretch_width")

    def say(self, text: str, ok: bool = False) -> None:
        """``text`` on the message line, in the error colour or (``ok``) the success colour."""
        color = style.MESSAGE_OK_COLOR if ok else style.MESSAGE_ERROR_COLOR
        self.message.styles = {**self.message.styles, "color": color}     # (Bokeh sends no unchanged value)
        self.message.text = text

    def close(self) -> None:
        """Stop the session's work (the browser tab is gone)."""
        self.session.close()

    # ------------------------------------------------------------ state in the URL
    def _load_url(self, args: dict):
        args, refused = settings_mod.screen_link(args, (*self.url_query(), TOKEN_ARG))   # (what a link carries)
        fields = {k: v for k, v in args.items() if k in self.base.field_names}
        self.settings, wrong = settings_mod.parse_link_fields(self.base, fields)
        self.fields.show()
        self._show_section()
        refused += wrong
        for part in self.link_parts:
            refused += part.load_url(args)
        if refused:
            self.say(f"link ignored in part (the rest applies): {'; '.join(refused)}")
        self.push_url()

    def url_query(self) -> dict:
        """The view as URL arguments: the fields, the starts (which are hidden), the boxes and the window."""
        q = self.settings.fields()
        for part in self.link_parts:
            q.update(part.url_query())
        return q

    def push_url(self):
        """The link anew: ``link``'s text, the address's query on a served page (WRITE_LINK)."""
        self.link.text = urlencode(self.url_query())

    def overlays_on(self) -> tuple:
        """The names of the overlays that are on (the chaos layer by its indicator), for the scene."""
        on = tuple(name for name, value in self.overlays.url_query().items() if value == "1")
        return on + ((self.chaos.indicator.value,) if self.chaos.layer.value else ())

    def scene(self):
        """The session as a scene (export.session_scene)."""
        starts = [(a, b) for _i, a, b, _c in self.orbits.starts]
        return export.session_scene(self.settings, starts, overlays=self.overlays_on())

    def view(self):
        """What the page shows now, hidden orbits left out, copied (drawn in any thread): each component's part."""
        s, parts = self.settings, {}
        for part in (self.section, self.chaos, self.overlays, self.orbits):
            parts.update(part.view_fields())
        return View(region=s.region, region_mask=s.region_mask(), axes=s.axes,
                    title=s.describe() + self.suffix, **parts)

    # ------------------------------------------------------------ values
    def _on_field(self, name: str | None = None):
        """The field ``name`` (None: every field) was edited: applied if valid as on the command line (Fields.read),
        else said on the message line."""
        try:
            new = self.fields.read(self.base, len(self.orbits.runs), name)
        except ParameterError as exc:
            self.say(f"not applied: {exc}")
            return
        self.say("")
        self.apply(new)

    def apply(self, new: Settings) -> None:
        """New settings: the starts inside the new region run again, under their ids; a new crossings per click
        alone cuts or continues each orbit (OrbitsLayer.recount); the fields show what applies."""
        if new.crossings != self.settings.crossings and replace(self.settings, crossings=new.crossings) == new:
            self.settings = new           # (only the crossings per click: each orbit is cut or continues)
            self.orbits.recount(new)
        elif new != self.settings:
            self.orbit_list.forget()
            self.settings = new
            # the kept starts' crosses go before the region and the view, with the status line (the orbits and
            # values now, also when every start was dropped)
            dropped = self.orbits.rerun()
            self._show_section()
            self.chaos.restart()
            self.overlays.restart()
            if dropped:
                self.say(f"{dropped} start(s) outside the new allowed region dropped")
        self.fields.show()
        self.push_url()

    def _show_section(self):
        """The settings' title and allowed region (the view fitted to it; an empty one said)."""
        self.title.object = f"### explorer: {self.settings.title()}{self.suffix}"   # (param sends no unchanged value)
        region = self.settings.region
        self.section.draw_region(region, self.settings.region_mask())
        if region is None:
            self.say(self.settings.empty_region())

    # ------------------------------------------------------------ orbits
    def run_seeds(self) -> int:
        """An orbit at each of the scene's ``[seeds]`` (at the settings) there is room for; returns how many."""
        try:
            starts = self.settings.seed_starts(self.seeds)
        except ParameterError as exc:
            self.say(f"scene seeds: {exc}")
            return 0
        n, why = 0, "the map refuses the others"        # (start: None for a seed the map cannot lift)
        for p1, p2 in starts:
            if full := settings_mod.room_for(len(self.orbits.runs) + 1, self.settings.crossings):
                why = full
                break
            n += self.orbits.start(p1, p2) is not None
        self.orbits.mark_starts()                # (once for all: not a status line and list per seed)
        if n < len(starts):
            self.say(f"scene seeds: {n} of {len(starts)} started ({why})")
        else:
            self.say(f"scene seeds: {n} orbits started", ok=True)
        self.push_url()
        return n

    def click(self, p1: float, p2: float):
        """A click at (p1, p2): a new orbit, or a message saying why not (no room left, or the map refuses the
        place).  On a served page its cross waits for its first crossings (they go first: OrbitsLayer._flush)."""
        if not (math.isfinite(p1) and math.isfinite(p2)):
            return None
        why = (settings_mod.room_for(len(self.orbits.runs) + 1, self.settings.crossings)
               or self.settings.refusal(p1, p2))
        if why is not None:
            self.say(why)
            return None
        if self.orbits.pause_box.value:
            self.orbits.worker.pause()
        run = self.orbits.start(p1, p2)
        if self.session.doc is None:        # (without a server nothing is sent: marked at once)
            self.orbits.mark_starts()
        self.say("")
        return run

    def _on_tap(self, event):
        """Tap, double tap or the end of a press, each a click (docs/commands/serve.md); a double tap at the
        previous click's place is that click again."""
        here = (float(event.sx), float(event.sy))
        last, self._last_tap = self._last_tap, here
        if isinstance(event, DoubleTap) and last is not None and max(abs(here[0] - last[0]),
                                                                      abs(here[1] - last[1])) <= SAME_SPOT_PX:
            return
        shift = bool((getattr(event, "modifiers", None) or {}).get("shift"))
        if shift or self.click_mode.value == CLICK_MODES[1]:
            self.orbit_list.pick(float(event.x), float(event.y))
        else:
            self.click(float(event.x), float(event.y))

    _last_tap: tuple | None = None


def session_app(base: Settings, export_dir=None, label: str = "", **page_options):
    """The app function of ``pn.serve``: a :class:`SectionPage` per session from its URL arguments."""
    def app():
        args = {k: v[0].decode("utf-8", "replace") for k, v in (pn.state.session_args or {}).items() if v}
        try:
            page = SectionPage(base, args, export_dir=export_dir, label=label, doc=pn.state.curdoc, **page_options)
        except Exception as exc:  # noqa: BLE001 - a link the checks let through: the page without it, and why
            page = SectionPage(base, {}, export_dir=export_dir, label=label, doc=pn.state.curdoc, **page_options)
            page.say(f"link ignored: {failure(exc)}")
        write = CustomJS(args={"link": page.link}, code=WRITE_LINK)
        page.link.js_on_change("text", write)
        pn.state.curdoc.js_on_event(DocumentReady, write)
        return page.layout
    return app
