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
from explorer.app.serve.tasks import failure

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
#: the columns of a block's rows (orbits.OrbitRun.advance)
ROW_COLUMNS = ("t", "p1", "p2", "M", "dH")


def _empty_crossings() -> dict:
    """The page's crossings: a block's rows, the orbit's id, its MEGNO and c, its colour index."""
    return {c: np.zeros(0, np.int64 if c in ("orbit", "c") else float) for c in ("orbit", *ROW_COLUMNS, "megno", "c")}


def _empty_live() -> dict:
    return {c: [] for c in _empty_crossings()}


class OrbitsLayer:
    """The starts, crossings and status of a page; ``host``: the page."""

    def __init__(self, host, view, session):
        self.host, self.view, self.session = host, view, session
        self.starts: list[tuple] = []          # (orbit id, p1, p2, colour) of every start, in click order
        self._marked: set = set()              # the starts whose cross is drawn unless hidden
        self._color = 0
        self.indicators: dict = {}             # orbit id -> (mean MEGNO, mLCE) over INDICATOR_TIME
        self.progress: dict = {}               # orbit id -> (crossings on the page so far, status)
        self.hidden: dict = {}                 # orbit id -> its rows (columns of crossings), hidden: not in crossings
        self.on_status = lambda: None          # called after every update of the status line
        self._pending: list = []               # blocks handed in, not yet on the page
        self._flushed_at = -math.inf           # when the last flush ran (monotonic)
        self._settle_at = -math.inf            # the flush due then moves the live rows
        self._settled = 0                      # crossings' rows up to here are in shown, from here on in live
        self.flush_timer = session.timer(lambda: self._flush())   # (looked up when due: tests trace it)
        self.worker = Worker(session, self._on_block, self._on_error, self._on_indicators, on_notice=self._on_notice)
        # every crossing (server only); what the browser draws; a click's first rows (lists: one JSON frame)
        self.crossings = ColumnDataSource(_empty_crossings())
        self.shown = ColumnDataSource(_empty_crossings(), name="crossings")
        self.live = ColumnDataSource(_empty_live(), name="live")
        self.start_source = ColumnDataSource({"orbit": [], "p1": [], "p2": [], "c": []}, name="starts")
        self.by_orbit = {"field": "c", "transform": LinearColorMapper(palette=list(COLORS), low=-0.5,
                                                                       high=len(COLORS) - 0.5)}
        self.by_megno = {"field": "megno", "transform": LinearColorMapper(
            palette=megno_palette(MEGNO_ORBIT_SKIP), low=MEGNO_LOW, high=MEGNO_HIGH, nan_color="#9e9e9e")}
        self.status = Div(name="status", text="click in the white region to start an orbit", render_as_text=True)
        self.colour_box = Box(label="colour orbits by MEGNO", value=False)
        self.colour_box.param.watch(lambda _e: session.soon(self._colour_changed), "value")
        self.starts_box = Box(label="start markers (+)", value=True)
        self.starts_box.param.watch(lambda _e: session.soon(self._starts_box_changed), "value")
        self.pause_box = Box(label=PAUSE_LABEL, value=True)
        self.pause_box.param.watch(lambda _e: session.soon(host.push_url), "value")

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
    def start(self, p1: float, p2: float, color: int | None = None, mark_later: bool = False,
              ident: int | None = None, quiet: bool = False):
        """Queue the orbit from (p1, p2) and mark its start (``mark_later`` on a served page: with its
        first crossings; ``quiet``: when the caller calls :meth:`mark_starts`); None outside the region."""
        settings = self.host.settings
        if not settings.admissible(p1, p2):
            return None
        if color is None:
            color = self._color % len(COLORS)
            self._color += 1
        run = self.worker.submit(p1, p2, settings, ident)
        self.starts.append((run.ident, p1, p2, color))
        self.progress[run.ident] = (0, "running")
        if not quiet and (not mark_later or self.session.doc is None):
            self.mark_starts()               # (else with the first crossings, in their flush)
        return run

    def mark_starts(self) -> None:
        """Mark the starts not marked yet, and the status line (and the orbit list) anew."""
        self._draw_starts(mark=True)
        self.update_status()

    def _draw_starts(self, mark: bool = False):
        """The crosses of the marked starts that are not hidden (``mark``: every start marked)."""
        if mark:
            self._marked = {i for i, *_ in self.starts}
        marks = [m for m in self.starts if m[0] in self._marked and m[0] not in self.hidden]
        data = {k: [m[j] for m in marks] for j, k in enumerate(("orbit", "p1", "p2", "c"))}
        if data != self.start_source.data:
            self.start_source.data = data

    def drop_all(self) -> list:
        """Stop every orbit and take them off the page; returns their starts."""
        self.worker.cancel()
        self.flush_timer.cancel()
        old, self.starts, self._pending = self.starts, [], []
        self.indicators, self.progress, self.hidden = {}, {}, {}
        self.crossings.data = _empty_crossings()
        self.show_all()
        self._draw_starts(mark=True)
        return old

    def has(self, ident) -> bool:
        """Orbit ``ident`` is on the page (hidden or not)."""
        return any(i == ident for i, *_ in self.starts)

    def remove(self, ident: int) -> None:
        """Stop orbit ``ident`` (running or paused) and take it off the page."""
        self.starts = [s for s in self.starts if s[0] != ident]
        self.worker.remove(ident)
        self.indicators.pop(ident, None)
        self.progress.pop(ident, None)
        if self.hidden.pop(ident, None) is None:
            self._take(ident)
            self.show_all()
            self._draw_starts()

    def _take(self, ident: int, keep: int = 0) -> dict:
        """Orbit ``ident``'s rows past its first ``keep`` off ``crossings`` (or :attr:`hidden`); returns them."""
        data = self.hidden.get(ident, self.crossings.data)
        mine = np.asarray(data["orbit"]) == ident
        mine[np.flatnonzero(mine)[:keep]] = False
        taken = {k: np.asarray(v)[mine] for k, v in data.items()}
        if mine.any():
            rest = {k: np.asarray(v)[~mine] for k, v in data.items()}
            if ident in self.hidden:
                self.hidden[ident] = rest
            else:
                self.crossings.data = rest
        return taken

    def hide(self, ident: int) -> None:
        """Take orbit ``ident``'s crossings and start off the page, into :attr:`hidden`."""
        if ident in self.hidden or not self.has(ident):
            return
        self.hidden[ident] = self._take(ident)
        self.show_all()
        self._draw_starts()

    def show(self, ident: int) -> None:
        """Put a hidden orbit's crossings and start back on the page."""
        rows = self.hidden.pop(ident, None)
        if rows is None:
            return
        d = self.crossings.data
        self.crossings.data = {k: np.concatenate([np.asarray(d[k]), rows[k]]) for k in d}
        self.show_all()
        self._draw_starts()

    def recount(self, settings) -> None:
        """New ``settings`` that differ only in the crossings per click K (Worker.recount): each orbit
        past K is cut to its first K rows, each one short of K continues exactly, none reruns."""
        blocks, self._pending = self._pending, []
        self._apply(blocks)                    # (the rows the worker counted, on the page before the cut)
        now = self.worker.recount(settings, self._cut)
        self.progress.update({i: now[i] for i in self.progress if i in now})
        self.show_all()
        self.update_status(force_density=True)

    def _cut(self, ident: int, keep: int) -> np.ndarray:
        """Orbit ``ident``'s rows past its first ``keep`` off the page, (n, 5)."""
        rows = self._take(ident, keep)
        return np.column_stack([rows[k] for k in ROW_COLUMNS])

    def state(self, ident: int) -> str:
        """running, paused, done, or why the orbit stopped."""
        if ident in self.running:
            return "paused" if ident in self.worker.paused() else "running"
        return self.progress.get(ident, (0, "done"))[1]

    @property
    def running(self) -> set:
        """The ids of the orbits still computing (or paused)."""
        return {i for i, (_n, status) in self.progress.items() if status == "running"}

    # ------------------------------------------------------------ blocks from the worker
    def _on_block(self, ident, rows, done, status):
        """Queue the block: an orbit's first and last go at once, others at most every FLUSH_SECONDS."""
        urgent = done == len(rows) or status != "running"
        self._pending.append((ident, rows, done, status))
        now = time.monotonic()
        self.flush_timer.at(now if urgent else max(now, self._flushed_at + FLUSH_SECONDS))

    def _flush(self):
        """The queued blocks onto the page (docs/architecture.md, "Many crossings in the browser"): a click's first rows
        alone to ``live``, with its cross and the link; the flush FLUSH_SECONDS later settles them into ``shown``."""
        blocks = [b for b in self._pending if self.has(b[0])]
        self._pending = []
        first = {b[0] for b in blocks if 0 < len(b[1]) == b[2] and b[0] not in self.hidden}   # alone
        if first:
            self._pending[:0] = [b for b in blocks if b[0] not in first]
            blocks = [b for b in blocks if b[0] in first]
        now = self._flushed_at = time.monotonic()
        held = len(self.live.data["orbit"])
        to_live = bool(first) or (0 < held and now < self._settle_at - SETTLE_SLACK
                                  and held + sum(len(b[1]) for b in blocks) <= LIVE_MAX_ROWS)
        new = self._apply(blocks)
        if new and to_live:
            self.live.stream({k: v.tolist() for k, v in new.items()})   # drawn at once, alone
        moved = False if to_live else self._settle()
        self._draw_starts(mark=True)
        if first:
            self._settle_at = now + FLUSH_SECONDS if self.session.doc is not None else -math.inf
            self.host.push_url()
        elif not to_live:
            self.update_status(force_density=self.host.density_image.dense and moved)
        if self._pending or len(self.live.data["orbit"]):
            self.flush_timer.at(max(self._settle_at, now + (FLUSH_SECONDS if self._pending else 0.0)))

    def _apply(self, blocks) -> dict:
        """The blocks' rows onto ``crossings`` (a hidden orbit's into :attr:`hidden`), their progress; returns
        the rows added to ``crossings`` as columns ({} if none)."""
        colour = {i: c for i, _a, _b, c in self.starts}
        blocks = [b for b in blocks if b[0] in colour]
        for ident, rows, done, status in blocks:
            if ident in self.hidden and len(rows):
                new, old = _columns([(ident, rows)], colour, self.indicators), self.hidden[ident]
                self.hidden[ident] = {k: np.concatenate([old[k], new[k]]) for k in new}
            self.progress[ident] = (done, status)
            if status not in ("running", "done"):
                self.host.say(f"orbit {ident} stopped after {done} crossings: {status}")
        drawn = [b for b in blocks if len(b[1]) and b[0] not in self.hidden]
        new = _columns(drawn, colour, self.indicators) if drawn else {}
        if new:
            self.crossings.stream(new)
        return new

    def _settle(self) -> bool:
        """The live rows to ``crossings`` (streamed before ``live`` empties); returns whether there were any."""
        moved = bool(len(self.live.data["orbit"]))
        n = len(self.crossings.data["orbit"])
        if n > self._settled:
            if not self.host.density_image.dense:
                self.shown.stream({k: np.asarray(v)[self._settled:] for k, v in self.crossings.data.items()})
            self._settled = n
        if moved:
            self.live.data = _empty_live()
        return moved

    def show_all(self) -> None:
        """The browser's rows anew: every crossing (none past density.THRESHOLD), none live."""
        self.shown.data = _empty_crossings() if self.host.density_image.dense else dict(self.crossings.data)
        if len(self.live.data["orbit"]):
            self.live.data = _empty_live()
        self._settled = len(self.crossings.data["orbit"])

    def _on_notice(self, _ident, text):
        self._draw_starts(mark=True)
        self.host.say(text)

    def _on_error(self, ident, exc):
        self._draw_starts(mark=True)
        self.progress[ident] = (self.progress.get(ident, (0,))[0], "failed")
        self.host.say(f"orbit {ident} failed: {failure(exc)}")
        self.update_status()
        self.host.push_url()

    def update_status(self, force_density: bool = False):
        """The status line (and the density image, at once if ``force_density``)."""
        paused = len(self.running.intersection(self.worker.paused()))
        running = len(self.running) - paused
        n = len(self.crossings.data["orbit"])
        density = self.host.density_image
        density.refresh(force=force_density or not running)   # (at once when the last orbit is done)
        s = self.host.settings
        text = (f"{len(self.starts)} orbit(s), {running} running, "
                + (f"{paused} paused (Resume continues them), " if paused else "") + f"{n} crossings drawn"
                + (" (as a density image)" if density.dense else "") + "; " + s.describe())
        known = [i for i, *_ in self.starts if i in self.indicators]
        if known:
            megno, mlce = self.indicators[known[-1]]
            text += (f"; orbit {known[-1]}: <Y> = {megno:.3g}, mLCE = {mlce:.3g} over t <= {INDICATOR_TIME:g}"
                     f" ({style.megno_kind(megno)})")
        self.status.text = text
        self.on_status()

    # ------------------------------------------------------------ chaos indicators and colours
    def _on_indicators(self, ident, megno, mlce):
        if not self.has(ident):
            return
        self.indicators[ident] = (megno, mlce)
        for d in (self.hidden.get(ident), self.crossings.data):     # (server only: in place)
            if d is not None:
                d["megno"][np.asarray(d["orbit"]) == ident] = megno
        for src in (self.shown, self.live):        # the browser's rows streamed before the indicator was known
            rows = np.flatnonzero(np.asarray(src.data["orbit"]) == ident)
            if rows.size:
                src.patch(_megno_patch(rows, megno, as_list=src is self.live))
        self.update_status()

    def _colour_changed(self):
        spec = self.by_megno if self.colour_box.value else self.by_orbit
        for r in (self.points, self.live_points):
            r.glyph.fill_color = spec
            r.glyph.line_color = spec
        self.host.density_image.refresh(force=True)
        self.host.push_url()

    def load_url(self, args: dict) -> list:
        """The boxes from a link: ``colour`` ("megno": by MEGNO), ``pause`` ("0": off); nothing refused."""
        self.colour_box.value, self.pause_box.value = args.get("colour") == "megno", args.get("pause") != "0"
        return []

    def url_query(self) -> dict:
        return {"colour": "megno" if self.colour_box.value else "orbit", "pause": str(int(self.pause_box.value))}

    def view_fields(self) -> dict:
        """Its part of the exported view (image.View): the orbits shown (hidden ones left out), their starts."""
        orbit = np.asarray(self.crossings.data["orbit"])
        p = np.column_stack([np.asarray(self.crossings.data[k], float) for k in ("p1", "p2")])
        visible = [s for s in self.starts if s[0] not in self.hidden]
        return {"orbits": [(i, COLORS[c], p[orbit == i], self.indicators.get(i, (math.nan,))[0])
                           for i, _a, _b, c in visible],
                "starts": [(a, b, COLORS[c]) for _i, a, b, c in visible], "by_megno": bool(self.colour_box.value)}

    def case_dots(self, on: bool) -> None:
        """Each dot on a casing (:data:`~explorer.app.serve.style.DOT_CASING`), or not."""
        for r in self.casings:
            r.visible = bool(on)

    def _starts_box_changed(self) -> None:
        """Show or hide the clicked starts' crosses."""
        self.start_marks.visible = bool(self.starts_box.value)


def _columns(blocks, colour: dict, indicators: dict) -> dict:
    """The blocks' rows as the columns of ``crossings`` (``colour``: orbit id -> colour index;
    ``indicators``: orbit id -> (MEGNO, mLCE) where known)."""
    ids, n = [b[0] for b in blocks], [len(b[1]) for b in blocks]
    data = np.concatenate([b[1] for b in blocks])
    return {"orbit": np.repeat(np.array(ids, np.int64), n),
            "megno": np.repeat([indicators.get(i, (math.nan,))[0] for i in ids], n).astype(float),
            **{k: data[:, j] for j, k in enumerate(ROW_COLUMNS)},
            "c": np.repeat(np.array([colour[i] for i in ids], np.int64), n)}


def _megno_patch(rows, megno: float, as_list: bool = False) -> dict:
    """A patch of the column megno to ``megno`` at ``rows`` (sorted indices): one slice per run of
    them; values as arrays (binary in the message), or ``as_list`` (a column held as a list)."""
    runs = np.split(rows, np.flatnonzero(np.diff(rows) != 1) + 1)
    return {"megno": [(slice(int(r[0]), int(r[-1]) + 1), [megno] * len(r) if as_list else np.full(len(r), megno))
                      for r in runs]}

