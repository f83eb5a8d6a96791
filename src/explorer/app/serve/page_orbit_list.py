"""The page's orbit list and the picked orbit (docs/commands/serve.md, "Orbit list"): a table of every
orbit, a chooser, *hide*/*show*, *delete*, the link's ``orbits`` and ``hidden``; the picked orbit's
readout (mLCE, MEGNO, rotation number), or near a hyperbolic mark that mark's manifolds."""
from __future__ import annotations

import html
from functools import partial

import panel as pn
from bokeh.models import CDSView, Div, GroupFilter

from explorer.app.serve import overlays as search
from explorer.app.serve import settings as settings_mod
from explorer.app.serve.orbits import COLORS
from explorer.app.serve.page_overlays import show_search
from explorer.app.serve.style import LIST_WIDTH
from explorer.model import ParameterError

#: a pick selects the orbit with a crossing within this many pixels of the click
PICK_PX = 6.0

#: the chooser's entry for "no orbit selected" (orbit ids start at 1)
NONE_LABEL = "(none)"
#: the selected orbit's markers: this size (pixels; the dots are 2), outlined in this colour
SELECTED_SIZE = 6.0
SELECTED_LINE = "#000000"
#: the table's height at most (then it scrolls) and the selected row's background
LIST_MAX_HEIGHT = "calc(100vh - 300px)"
SELECTED_BACKGROUND = "#fff3b0"
#: the legend under the list, and each column's tooltip
LEGEND = ("white: the allowed region at h (M² ≥ 0), gray: forbidden; +: a start; a dot: a crossing, in its "
          "orbit's colour, or by its ⟨Y⟩ when orbits are coloured by MEGNO (light 0-2: regular, dark: chaotic). "
          "⟨Y⟩ (MEGNO, t ≤ 1000) tends to 2 on a torus and to 0 on a stable periodic orbit (a little below 0 "
          "there is no error); above 3: chaotic-like. A field's ? says what it sets.")
COLUMNS = (("", "the orbit's colour on the section"), ("orbit", "its id (choose it above, or Shift + click a dot)"),
           ("start (p1, p2)", "where it was clicked"), ("crossings", "crossings of the section so far"),
           ("state", "running, paused (Resume continues it), done, or why it stopped"))


class OrbitList:
    """The list and the picked orbit (``picked``, its readout ``text``); ``settings()``: the page's,
    ``say(text)``: its message line, ``on_changed()`` after a hide, show, delete or clear (the link)."""

    def __init__(self, orbits, overlays, view, session, settings, say, on_changed):
        self.orbits, self.overlays, self.view, self.session = orbits, overlays, view, session
        self.settings, self.say, self.on_changed = settings, say, on_changed
        self.text = Div(name="readout", text="", render_as_text=True, styles={"font-family": "monospace"})
        self.picked: int | None = None          # the orbit whose readout is shown
        self.filter = GroupFilter(name="selected-orbit", column_name="orbit", group=0)   # the highlighted rows
        self.table = Div(name="orbit-list", text="", styles={"max-height": LIST_MAX_HEIGHT, "overflow-y": "auto"},
                         width=LIST_WIDTH)
        self.choice = pn.widgets.Select(label="orbit", options={NONE_LABEL: 0}, value=0, width=LIST_WIDTH - 170)
        self.choice.param.watch(lambda e: session.soon(lambda: self.choose(e.new)), "value")
        self.hide_button = pn.widgets.Button(label="hide", width=50, disabled=True, align="end")
        self.hide_button.on_click(lambda _e: session.soon(lambda: self.toggle(self.picked)))
        self.delete_button = pn.widgets.Button(label="delete", width=50, disabled=True, align="end")
        self.delete_button.on_click(lambda _e: session.soon(lambda: self.delete(self.picked)))
        self.panel = pn.Column(pn.Row(self.choice, self.hide_button, self.delete_button), pn.pane.Bokeh(self.table),
                               pn.pane.HTML(LEGEND, width=LIST_WIDTH, styles={"font-size": "11px", "color": "#444"}),
                               width=LIST_WIDTH)
        orbits.on_status = self.refresh

    def draw(self, fig) -> None:
        """The selected orbit's markers (call after OrbitsLayer.draw), filtered from the browser's rows."""
        self.marks = fig.scatter("p1", "p2", source=self.orbits.shown, view=CDSView(filter=self.filter),
                                 fill_color=self.orbits.by_orbit, line_color=SELECTED_LINE, line_width=1.0,
                                 size=SELECTED_SIZE)

    # ------------------------------------------------------------ actions
    def choose(self, ident) -> None:
        """Select orbit ``ident`` (0 or None: none), as a pick of it does: its readout and highlight."""
        if (ident or None) != self.picked:      # (not when refresh set the chooser to the selection)
            self.select(ident)

    def toggle(self, ident: int | None) -> None:
        """Hide orbit ``ident`` (None: none), or show it again if hidden."""
        if ident in self.orbits.runs:
            self.orbits.hide(ident, not self.orbits.runs[ident].hidden)
            self._changed()

    def clear(self) -> None:
        """Remove every orbit (running and paused ones stopped)."""
        self.forget()
        self.orbits.drop_all()
        self._changed()

    def undo(self) -> None:
        """Remove the newest orbit (stopped if it runs or is paused)."""
        self.delete(next(reversed(self.orbits.runs), None))

    def resume(self) -> int:
        """Continue the orbits a click paused, from where each stopped; returns how many."""
        n = len(self.orbits.worker.resume())
        self.orbits.update_status()
        return n

    def delete(self, ident: int | None) -> None:
        """Stop orbit ``ident`` (running or paused) and remove it from the page and the session."""
        if ident not in self.orbits.runs:
            return
        self.forget(ident)
        self.orbits.remove(ident)
        self._changed()

    def _changed(self) -> None:
        """The orbits shown changed: the status line, the density image at once, the link."""
        self.orbits.update_status(force_density=True)
        self.on_changed()

    # ------------------------------------------------------------ the link
    def load_url(self, args: dict) -> list:
        """Start a link's ``orbits`` (none when they do not fit), hide those its ``hidden`` names and mark the starts
        (OrbitsLayer.mark_starts); returns what it refused."""
        try:
            starts = settings_mod.parse_starts(args.get("orbits", ""))
        except ParameterError as exc:
            return [str(exc)]                   # (no starts: their ``hidden`` goes with them)
        full = settings_mod.room_for(len(starts), self.settings().crossings)
        if full:
            return [full]
        try:
            positions, refused = settings_mod.parse_hidden(args.get("hidden", ""), len(starts)), []
        except ParameterError as exc:
            positions, refused = set(), [str(exc)]
        for k, (p1, p2) in enumerate(starts, 1):
            self.orbits.start(p1, p2, hidden=k in positions)
        if self.orbits.runs:                    # their crosses and the status line at once
            self.orbits.mark_starts()
        return refused

    def url_query(self) -> dict:
        """The link's ``orbits`` (every start) and ``hidden`` (the positions of the hidden ones)."""
        runs = list(self.orbits.runs.values())
        return {"orbits": settings_mod.format_starts((r.p1, r.p2) for r in runs),
                "hidden": settings_mod.format_hidden(k for k, r in enumerate(runs, 1) if r.hidden)}

    # ------------------------------------------------------------ what is shown
    def refresh(self) -> None:
        """The table, the chooser and the highlight anew (after a status update or a selection)."""
        starts, picked = self.orbits.starts, self.picked
        # (a value equal to the one there is not sent again: param and Bokeh compare them)
        self.choice.options = {NONE_LABEL: 0} | {f"{i}: ({p1:.4g}, {p2:.4g})": i for i, p1, p2, _c in starts}
        self.choice.value = picked if picked in self.orbits.runs else 0
        self.hide_button.label = "show" if getattr(self.orbits.runs.get(picked), "hidden", False) else "hide"
        self.hide_button.disabled = self.delete_button.disabled = picked is None
        self.filter.group = picked or 0
        self.table.text = _table(self.orbits, picked)

    # ------------------------------------------------------------ the picked orbit
    def pick(self, p1: float, p2: float, radius_px: float = PICK_PX) -> int | None:
        """A pick at (p1, p2): near a hyperbolic mark its manifolds (None), else selects the orbit with the
        nearest crossing within ``radius_px`` pixels and returns its id."""
        if self.overlays.pick(p1, p2, radius_px):
            return None
        d = self.orbits.columns(keys=("orbit", "p1", "p2"))
        k = self.view.nearest(d["p1"], d["p2"], p1, p2, radius_px)
        if k is None:
            self.say(f"pick: no crossing within {radius_px:g} pixels of ({p1:.4g}, {p2:.4g})" if len(d["orbit"])
                     else "pick: no orbit on the page yet")
            return None
        ident = int(d["orbit"][k])
        self.select(ident)
        return ident

    def select(self, ident) -> None:
        """Select orbit ``ident`` (None, or not an orbit of the page: none) and show its readout (computed once
        per orbit and settings, the latest pick; it stays on the orbit's run)."""
        run = self.orbits.runs.get(ident)
        self.session.cancel("readout")
        self.picked = None if run is None else run.ident
        self.refresh()
        if run is None:
            self.text.text = ""
            return
        self.say("")
        if run.readout:
            self.text.text = run.readout[1]
            return
        head = f"orbit {run.ident} from ({run.p1:.6g}, {run.p2:.6g}): "
        self.text.text = head + "computing mLCE, MEGNO, rotation ..."
        self.session.start("readout", show_search(self.session, "readout", partial(self._keep, run.ident, head),
                                                  search.orbit_readout, self.settings(), (run.p1, run.p2)),
                           budget=search.search_budget(search.READOUT_SECONDS))

    def forget(self, ident: int | None = None) -> None:
        """Before orbit ``ident`` (None: every orbit) leaves: stop computing its readout, unselect it."""
        if ident is None or self.picked == ident:
            self.select(None)

    def _keep(self, ident, head, values, text):
        if (run := self.orbits.runs.get(ident)) is not None:      # (not when the orbit went meanwhile)
            run.readout = (values, head + text)
            self.text.text = run.readout[1]


def _table(orbits, picked) -> str:
    """The list of ``orbits`` (an OrbitsLayer) as an HTML table (numbers and fixed words, escaped all the same)."""
    if not orbits.runs:
        return ""
    head = "".join(f"<th style='text-align:left;padding:0 3px' title='{tip}'>{h}</th>" for h, tip in COLUMNS)
    body = []
    for i, r in orbits.runs.items():
        style = "font-weight:bold;background:" + SELECTED_BACKGROUND if i == picked else ""
        if r.hidden:
            style += ";color:#808080"
        cells = (f"<span style='display:inline-block;width:10px;height:10px;background:{COLORS[r.colour]}'></span>",
                 str(i), f"({r.p1:.6g}, {r.p2:.6g})", str(r.done),
                 html.escape(r.phase) + (", hidden" if r.hidden else ""))
        body.append(f"<tr data-orbit='{i}' style='{style}'>"
                    + "".join(f"<td style='padding:0 3px'>{c}</td>" for c in cells) + "</tr>")
    return f"<table style='border-collapse:collapse;font-size:12px'><tr>{head}</tr>{''.join(body)}</table>"
