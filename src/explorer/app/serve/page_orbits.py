"""The orbits on the page (docs/commands/serve.md, "How it works"): starts, crossings from the session's
:class:`~explorer.app.serve.orbits.Worker`, a click's first crossings on the live layer, the status line.
Bokeh model names: ``crossings`` (none past density.THRESHOLD), ``glyphs``, ``live``, ``starts``, ``status``."""
from __future__ import annotations

import math
import time

import numpy as np
from bokeh.models import CDSView, ColumnDataSource, CustomJSFilter, Div, LinearColorMapper

from explorer.app.serve import style
from explorer.app.serve.box import Box
from explorer.app.serve.orbits import COLORS, INDICATOR_TIME, Worker
from explorer.app.serve.style import MEGNO_HIGH, MEGNO_LOW, MEGNO_ORBIT_SKIP, POINT_SIZE, megno_palette
from explorer.app.serve.tasks import Timer, failure

#: blocks after an orbit's first go to the browser at most this often (s): each message redraws every dot
FLUSH_SECONDS = 0.25
#: a flush this close to the time the live rows are due to settle (s) settles them
SETTLE_SLACK = 0.01
#: rows sent before the live rows settle join them up to this many (a short orbit's last block)
LIVE_MAX_ROWS = 2_000
PAUSE_LABEL = "a click pauses running orbits"
#: the browser's filter of the drawn crossings: the rows of the orbits from ``first`` on
GLYPH_FILTER = ("const o = source.data.orbit, n = o.length, rows = [];\n"
                "for (let i = 0; i < n; i++) if (o[i] >= first) rows.push(i);\n"
                "return rows;")
#: the columns of a block's rows (orbits.OrbitRun.advance), and of the browser's sources
ROW_COLUMNS = ("t", "p1", "p2", "M", "dH")
COLUMNS = ("orbit", *ROW_COLUMNS, "megno", "c")


class OrbitsLayer:
    """The starts, crossings and status of a page; ``host``: the page.  The one store of the orbits is
    ``runs`` (the worker's {orbit id: OrbitRun}, click order), which the browser's ``shown`` and ``live`` are
    written from (a hidden run: OrbitRun.hidden)."""

    def __init__(self, host, view, session):
        self.host, self.view, self.session = host, view, session
        self.on_status = lambda: None          # called after every update of the status line
        self._flushed_at = -math.inf           # when the last flush ran (monotonic)
        self._settle_at = -math.inf            # the flush due then moves the live rows
        self.flush_timer = Timer(session, lambda: self._flush())   # (looked up when due: tests trace it)
        self.worker = Worker(session, self._on_block, self._on_error, self._on_indicators,
                             on_notice=lambda _i, text: host.say(text))
        self.runs = self.worker.runs
        # what the browser draws; a click's first rows (lists: one JSON frame)
        self.shown = ColumnDataSource(self.columns([]), name="crossings")
        self.live = ColumnDataSource({k: [] for k in COLUMNS}, name="live")
        self.start_source = ColumnDataSource({"orbit": [], "p1": [], "p2": [], "c": []}, name="starts")
        self.by_orbit = {"field": "c", "transform": LinearColorMapper(palette=list(COLORS), low=-0.5,
                                                                       high=len(COLORS) - 0.5)}
        self.by_megno = {"field": "megno", "transform": LinearColorMapper(
            palette=megno_palette(MEGNO_ORBIT_SKIP), low=MEGNO_LOW, high=MEGNO_HIGH,
            nan_color=style.UNKNOWN_MEGNO_COLOR)}
        self.status = Div(name="status", text="click in the white region to start an orbit", render_as_text=True)
        self.colour_box = Box(label="colour orbits by MEGNO", value=False)
        self.colour_box.param.watch(lambda _e: session.soon(self._colour_changed), "value")
        self.starts_box = Box(label="start markers (+)", value=True)
        self.starts_box.param.watch(lambda e: session.soon(lambda: self.start_marks.update(visible=e.new)), "value")
        self.pause_box = Box(label=PAUSE_LABEL, value=True)
        self.pause_box.param.watch(lambda _e: session.soon(host.push_url), "value")

    def columns(self, runs=None, keys=COLUMNS, unsent: bool = False) -> dict:
        """The rows of ``runs`` (None: every orbit not hidden) as ``keys`` of the browser's columns: a row, its
        orbit's id, MEGNO and colour index; each orbit's first ``done`` rows (``unsent``: those past ``sent``)."""
        if runs is None:
            runs = [r for r in self.runs.values() if not r.hidden]
        parts = [r.rows[r.sent if unsent else 0:r.done] for r in runs]
        n = [len(rows) for rows in parts]
        each = {"orbit": [r.ident for r in runs], "c": [r.colour for r in runs],
                "megno": [r.megno for r in runs]}
        out = {}
        for k in keys:
            if k in ROW_COLUMNS:
                out[k] = np.concatenate([rows[:, ROW_COLUMNS.index(k)] for rows in parts] or [np.zeros(0)])
            else:
                out[k] = np.repeat(np.array(each[k], float if k == "megno" else np.int64), n)
        return out

    def draw(self, fig) -> None:
        """The crossings' glyphs (call after the images) and the starts' crosses."""
        # the newest orbits (density.GLYPH_BUDGET) as dots: one number moves them between dots and image
        self.glyph_filter = CustomJSFilter(name="glyphs", args={"first": 0}, code=GLYPH_FILTER)
        # under each dot, while the chaos layer is on, a white disc with a dark edge: seen on its every colour
        size, fill, edge, width = style.DOT_CASING
        self.casings = [fig.scatter("p1", "p2", source=src, size=size, fill_color=fill, line_color=edge,
                                    line_width=width, visible=False, **kw)
                        for src, kw in ((self.shown, {"view": CDSView(filter=self.glyph_filter)}),
                                        (self.live, {"level": "overlay"}))]
        self.points = fig.scatter("p1", "p2", source=self.shown, color=self.by_orbit, size=POINT_SIZE, line_width=0,
                                  view=CDSView(filter=self.glyph_filter))
        # the newest rows on the overlay canvas, which Bokeh repaints alone (docs/architecture.md)
        self.live_points = fig.scatter("p1", "p2", source=self.live, color=self.by_orbit, size=POINT_SIZE,
                                       line_width=0, level="overlay")
        self.start_marks = fig.scatter("p1", "p2", source=self.start_source, marker="cross", color=self.by_orbit,
                                       size=9, line_width=2, level="overlay")   # (above the crossings and images)

    # ------------------------------------------------------------ starts
    @property
    def starts(self) -> list:
        """(orbit id, p1, p2, colour index) of every start, in click order."""
        return [(r.ident, r.p1, r.p2, r.colour) for r in self.runs.values()]

    def start(self, p1: float, p2: float, ident: int | None = None, hidden: bool = False):
        """Queue the orbit from (p1, p2) as orbit ``ident`` (None: a new id), ``hidden`` or not; None outside the
        region.  It draws nothing: its cross comes with its first crossings, or before them from :meth:`mark_starts`."""
        settings = self.host.settings
        if not settings.admissible(p1, p2):
            return None
        run = self.worker.submit(p1, p2, settings, ident)
        run.marked, run.hidden = False, hidden
        return run

    def mark_starts(self) -> None:
        """Every start marked: the crosses and the status line (and the orbit list) anew, once for the starts
        queued together (a link's, the scene's seeds, those a new value reruns)."""
        for r in self.runs.values():
            r.marked = True
        self._draw_starts()
        self.update_status()

    def _draw_starts(self):
        """The crosses of the starts not hidden that are marked (OrbitRun.marked), have crossings in the browser
        or stopped running."""
        marks = [(r.ident, r.p1, r.p2, r.colour) for r in self.runs.values()
                 if not r.hidden and (r.marked or r.sent or r.phase != "running")]
        data = {k: [m[j] for m in marks] for j, k in enumerate(("orbit", "p1", "p2", "c"))}
        if data != self.start_source.data:
            self.start_source.data = data

    def drop_all(self) -> None:
        """Stop every orbit and take them off the page."""
        self.worker.cancel()
        self.flush_timer.cancel()
        self.show_all()

    def rerun(self) -> int:
        """Every orbit anew at the page's settings, under its id (its colour kept), a hidden one still hidden, its
        cross and the status line at once; returns how many were dropped (outside the new region)."""
        old = list(self.runs.values())
        self.drop_all()
        for r in old:
            self.start(r.p1, r.p2, r.ident, r.hidden)
        self.mark_starts()
        return len(old) - len(self.runs)

    def remove(self, ident: int) -> None:
        """Stop orbit ``ident`` (running or paused) and take it off the page."""
        self.runs.pop(ident, None)
        self.show_all()

    def hide(self, ident: int, hidden: bool = True) -> None:
        """Take orbit ``ident``'s crossings and start off the page (it keeps computing), or (``hidden`` false)
        put them back."""
        if ident in self.runs:
            self.runs[ident].hidden = hidden
            self.show_all()

    def recount(self, settings) -> None:
        """New ``settings`` that differ only in the crossings per click K (Worker.recount): each orbit
        past K is cut to its first K rows, each one short of K continues exactly, none reruns."""
        self.worker.recount(settings)
        self.show_all()
        self.update_status(force_density=True)

    # ------------------------------------------------------------ blocks from the worker
    def _on_block(self, ident, rows, done, status):
        """An orbit's block is in ``runs``: its first and last go to the browser at once, others at most every
        FLUSH_SECONDS."""
        if status not in ("running", "done"):
            self.host.say(f"orbit {ident} stopped after {done} crossings: {status}")
        urgent = done == len(rows) or status != "running"
        now = time.monotonic()
        self.flush_timer.at(now if urgent else max(now, self._flushed_at + FLUSH_SECONDS))

    def _flush(self):
        """The rows not sent yet onto the page (docs/architecture.md, "Many crossings in the browser"): a click's
        first rows alone to ``live``, with its cross and the link; the flush FLUSH_SECONDS later settles them into
        ``shown``."""
        due = [r for r in self.runs.values() if not r.hidden and r.sent < r.done]
        first = [r for r in due if r.sent == 0]
        now = self._flushed_at = time.monotonic()
        held = len(self.live.data["orbit"])
        to_live = bool(first) or (0 < held and now < self._settle_at - SETTLE_SLACK
                                  and held + sum(r.done - r.sent for r in due) <= LIVE_MAX_ROWS)
        new = self.columns(first or due, unsent=True)
        for r in first or due:
            r.sent = r.done
        if to_live and len(new["orbit"]):
            self.live.stream({k: v.tolist() for k, v in new.items()})   # drawn at once, alone
        elif not to_live and (held or len(new["orbit"])):
            if not self.host.density_image.dense:     # (the live rows and the new ones, one message)
                live = self.live.data
                self.shown.stream({k: np.concatenate([np.asarray(live[k], v.dtype), v]) for k, v in new.items()})
            if held:
                self.live.data = {k: [] for k in COLUMNS}
        self._draw_starts()
        if first:
            self._settle_at = now + FLUSH_SECONDS if self.session.doc is not None else -math.inf
            self.host.push_url()
        elif not to_live:
            self.update_status(force_density=self.host.density_image.dense and held > 0)
        later = bool(first) and len(first) < len(due)       # (the other orbits' rows)
        if later or len(self.live.data["orbit"]):
            self.flush_timer.at(max(self._settle_at, now + (FLUSH_SECONDS if later else 0.0)))

    def show_all(self) -> None:
        """The browser's rows anew: every crossing of the orbits not hidden (none past density.THRESHOLD), none
        live; and their starts' crosses."""
        self.shown.data = self.columns([]) if self.host.density_image.dense else self.columns()
        if len(self.live.data["orbit"]):
            self.live.data = {k: [] for k in COLUMNS}
        for r in self.runs.values():
            r.sent = r.done
        self._draw_starts()

    def _on_error(self, ident, exc):
        self._draw_starts()
        self.host.say(f"orbit {ident} failed: {failure(exc)}")
        self.update_status()
        self.host.push_url()

    def update_status(self, force_density: bool = False):
        """The status line (and the density image, at once if ``force_density``)."""
        phases = [r.phase for r in self.runs.values()]
        paused, running = phases.count("paused"), phases.count("running")
        n = sum(r.done for r in self.runs.values() if not r.hidden)
        density = self.host.density_image
        density.refresh(force=force_density or not running)   # (at once when the last orbit is done)
        s = self.host.settings
        text = (f"{len(self.runs)} orbit(s), {running} running, "
                + (f"{paused} paused (Resume continues them), " if paused else "") + f"{n} crossings drawn"
                + (" (as a density image)" if density.dense else "") + "; " + s.describe())
        known = [r for r in self.runs.values() if r.indicators]
        if known:
            megno, mlce = known[-1].indicators
            text += (f"; orbit {known[-1].ident}: <Y> = {megno:.3g}, mLCE = {mlce:.3g} over t <= {INDICATOR_TIME:g}"
                     f" ({style.megno_kind(megno)})")
        self.status.text = text
        self.on_status()

    # ------------------------------------------------------------ chaos indicators and colours
    def _on_indicators(self, ident, megno, mlce):
        for src in (self.shown, self.live):        # the browser's rows streamed before the indicator was known
            rows = np.flatnonzero(np.asarray(src.data["orbit"]) == ident)
            if rows.size:
                src.patch(_megno_patch(rows, megno, as_list=src is self.live))
        self.update_status()

    def _colour_changed(self):
        spec = self.by_megno if self.colour_box.value else self.by_orbit
        for r in (self.points, self.live_points):
            r.glyph.update(fill_color=spec, line_color=spec)
        self.host.density_image.refresh()       # (at once: how it is coloured is part of what it shows)
        self.host.push_url()

    def load_url(self, args: dict) -> list:
        """The boxes from a link: ``colour`` ("megno": by MEGNO), ``pause`` ("0": off); nothing refused."""
        self.colour_box.value, self.pause_box.value = args.get("colour") == "megno", args.get("pause") != "0"
        return []

    def url_query(self) -> dict:
        return {"colour": "megno" if self.colour_box.value else "orbit", "pause": str(int(self.pause_box.value))}

    def view_fields(self) -> dict:
        """Its part of the exported view (image.View): the orbits shown (hidden ones left out), their starts."""
        visible = [r for r in self.runs.values() if not r.hidden]
        return {"orbits": [(r.ident, COLORS[r.colour], r.rows[:r.done, 1:3], r.megno) for r in visible],
                "starts": [(r.p1, r.p2, COLORS[r.colour]) for r in visible], "by_megno": bool(self.colour_box.value)}

    def case_dots(self, on: bool) -> None:
        """Each dot on a casing (:data:`~explorer.app.serve.style.DOT_CASING`), or not."""
        for r in self.casings:
            r.visible = bool(on)


def _megno_patch(rows, megno: float, as_list: bool = False) -> dict:
    """A patch of the column megno to ``megno`` at ``rows`` (sorted indices): one slice per run of
    them; values as arrays (binary in the message), or ``as_list`` (a column held as a list)."""
    runs = np.split(rows, np.flatnonzero(np.diff(rows) != 1) + 1)
    return {"megno": [(slice(int(r[0]), int(r[-1]) + 1), [megno] * len(r) if as_list else np.full(len(r), megno))
                      for r in runs]}

