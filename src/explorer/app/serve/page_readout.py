"""The orbits' chaos information on the page: each orbit's indicators (mean MEGNO, mLCE) as they
arrive from the worker, colouring the orbits by them, and the pick of an orbit (Shift + click or
the click switch) with its readout (mLCE, MEGNO, rotation number: :func:`explorer.app.serve.overlays.orbit_readout`,
computed in a thread).  A part of :class:`~explorer.app.serve.page.SectionPage` (a mixin: it uses
the page's models and :meth:`~explorer.app.serve.page.SectionPage._post`)."""
from __future__ import annotations

import math
from functools import partial

import numpy as np

from explorer.app.serve.jobs import LatestJob
from explorer.app.serve.orbits import CHAOTIC_MEGNO, INDICATOR_TIME
from explorer.app.serve.style import FIGURE_HEIGHT, FIGURE_WIDTH

#: a pick selects the orbit with a crossing within this many pixels of the click
PICK_PX = 6.0


class ReadoutMixin:
    """Indicators, colour by MEGNO, pick and readout of :class:`~explorer.app.serve.page.SectionPage`."""

    def _frame_px(self) -> tuple:
        """Width and height of the plot's frame in screen pixels (as drawn in the browser; before
        that, the figure's nominal size less its axes)."""
        try:
            return float(self.figure.inner_width), float(self.figure.inner_height)
        except Exception:  # noqa: BLE001 - not drawn in a browser yet: the figure's nominal size
            return FIGURE_WIDTH - 60.0, FIGURE_HEIGHT - 60.0

    def _pixel(self) -> tuple:
        """The size of a screen pixel in p1 and p2 (from the visible window and the plot's frame)."""
        w = self.window
        if w is None:
            return 0.0, 0.0
        width, height = self._frame_px()
        return (w.x1 - w.x0) / max(width, 1.0), (w.y1 - w.y0) / max(height, 1.0)

    def pick(self, p1: float, p2: float, radius_px: float = PICK_PX) -> int | None:
        """A pick at (p1, p2).  Near a hyperbolic mark of the overlays (× of a fixed point or of a
        periodic orbit, within ``radius_px`` screen pixels): its stable and unstable manifolds are
        grown and drawn (:meth:`show_manifolds`) and None is returned.  Else the orbit with the
        crossing nearest to it (within ``radius_px`` screen pixels) is selected and its readout
        (mLCE, mean MEGNO, rotation number: :func:`explorer.app.serve.overlays.orbit_readout`) is
        computed in a thread and shown in
        ``readout``; returns the orbit's id (None: no crossing near)."""
        saddle = self.saddle_near(p1, p2, radius_px) if math.isfinite(p1) and math.isfinite(p2) else None
        if saddle is not None:           # a hyperbolic mark of the overlays: its manifolds
            self.show_manifolds(*saddle)
            return None
        d = self.crossings.data
        if not (math.isfinite(p1) and math.isfinite(p2)) or not len(d["orbit"]):
            self.say("pick: no orbit on the page yet")
            return None
        px, py = self._pixel()
        dist = np.hypot((np.asarray(d["p1"]) - p1) / (px or 1.0), (np.asarray(d["p2"]) - p2) / (py or 1.0))
        k = int(np.argmin(dist))
        if not dist[k] <= radius_px:
            self.say(f"pick: no crossing within {radius_px:g} pixels of ({p1:.4g}, {p2:.4g})")
            return None
        ident = int(np.asarray(d["orbit"])[k])
        self.select(ident)
        return ident

    def select(self, ident: int) -> None:
        """Show orbit ``ident``'s readout (computed once per orbit and settings, in a thread)."""
        start = next(((a, b) for i, a, b, _c in self.starts if i == ident), None)
        if start is None:
            return
        self.picked = ident
        self._readout_generation += 1
        self._cancel_readout()
        self.say("")
        if ident in self.readouts:
            self._show_readout(self._readout_generation, ident, self.readouts[ident])
            return
        self.readout.text = f"orbit {ident} from ({start[0]:.6g}, {start[1]:.6g}): computing mLCE, MEGNO, rotation ..."
        self._readout_jobs.put((self._readout_generation, ident, start, self.settings))

    @property
    def _readout_jobs(self) -> LatestJob:
        """The session's one readout thread (made at the first pick): it computes the latest pick
        only, so rapid picks queue nothing and start no thread each."""
        return LatestJob.of(self, "_readout_worker", self._compute_readout, "explorer-serve-readout")

    def _stop_readouts(self) -> None:
        self._cancel_readout()
        LatestJob.stop_of(self, "_readout_worker")

    _readout_budget = None

    def _cancel_readout(self) -> None:
        """Stop the readout being computed, if any (a newer pick or value replaces it)."""
        if self._readout_budget is not None:
            self._readout_budget.cancel()

    def _compute_readout(self, generation, ident, start, settings):
        from explorer.app.serve.overlays import READOUT_SECONDS, orbit_readout, search_budget

        budget = search_budget(READOUT_SECONDS)
        self._readout_budget = budget
        if generation != self._readout_generation:
            return                           # a newer pick or a new value came meanwhile
        try:
            with budget:
                r = orbit_readout(settings, start)
        except Exception as exc:  # noqa: BLE001 - reported in the page
            if budget.cancelled:
                return                       # replaced: nothing to show, nothing to keep
            r = {"error": f"{type(exc).__name__}: {' '.join(str(exc).split())}"}
        r["start"], r["settings"] = start, settings
        self._post(partial(self._show_readout, generation, ident, r))

    def _show_readout(self, generation, ident, r):
        if r.get("settings") is not self.settings or not any(i == ident for i, *_ in self.starts):
            return                           # the orbit or the values changed meanwhile
        self.readouts[ident] = r
        if generation != self._readout_generation:
            return
        p1, p2 = r["start"]
        head = f"orbit {ident} from ({p1:.6g}, {p2:.6g}): "
        if "error" in r:
            self.readout.text = head + f"failed: {r['error']}"
            return
        kind = "chaotic-like" if r["megno"] > CHAOTIC_MEGNO else "regular-like"
        text = (head + f"mLCE = {r['mlce']:.4g}, <Y> = {r['megno']:.4g} over t <= {INDICATOR_TIME:g}"
                + (f" ({kind})" if math.isfinite(r["megno"]) else " (unknown: the run stopped early)"))
        rot, fp = r["rotation"], r["center"]
        if rot is None:
            text += f"; rotation number: none ({r['rotation_error']})"
        elif not math.isfinite(rot.value):
            text += f"; rotation number: none ({rot.status})"
        else:
            text += (f"; rotation number {rot.value:.10g} around ({fp.point[0]:.6g}, {fp.point[1]:.6g}) over "
                     f"{rot.iterates} returns, " + ("converged" if rot.converged else
                                                        f"not converged (|WB_N - WB_2N| = {rot.difference:.2g})"))
        self.readout.text = text

    # ------------------------------------------------------------ chaos indicators of the orbits
    def _on_indicators(self, ident, megno, mlce):
        self._post(partial(self._show_indicators, ident, megno, mlce))

    def _show_indicators(self, ident, megno, mlce):
        if not any(i == ident for i, *_ in self.starts):
            return
        self.indicators[ident] = (megno, mlce)
        rows = np.flatnonzero(np.asarray(self.crossings.data["orbit"]) == ident)
        if rows.size:      # the rows streamed before the indicator was known
            self.crossings.patch(_megno_patch(rows, megno))
            settled = self._settled        # (the browser's: crossings up to it, live from it on)
            if not self.dense and rows[0] < settled:
                self.shown.patch(_megno_patch(rows[rows < settled], megno))
            if rows[-1] >= settled:
                self.live.patch(_megno_patch(rows[rows >= settled] - settled, megno, as_list=True))
        self._update_status()

    def _colour_changed(self):
        spec = self._by_megno if self.colour_box.value else self._by_orbit
        for r in (self.points, self.live_points):
            r.glyph.fill_color = spec
            r.glyph.line_color = spec
        self._refresh_density(force=True)
        self._push_url()


def _megno_patch(rows, megno: float, as_list: bool = False) -> dict:
    """A patch of the column megno to ``megno`` at ``rows`` (sorted indices): one slice per run of
    them; values as arrays (binary in the message), or ``as_list`` (a column held as a list)."""
    runs = np.split(rows, np.flatnonzero(np.diff(rows) != 1) + 1)
    return {"megno": [(slice(int(r[0]), int(r[-1]) + 1), [megno] * len(r) if as_list else np.full(len(r), megno))
                      for r in runs]}
