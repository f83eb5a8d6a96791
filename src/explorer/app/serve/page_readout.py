"""The readout of a picked orbit (docs/commands/serve.md): its mLCE, MEGNO and rotation number (a task
under a budget), or near a hyperbolic mark that mark's manifolds."""
from __future__ import annotations

import math

import numpy as np
from bokeh.models import Div

from explorer.app.serve import overlays as search
from explorer.app.serve.orbits import INDICATOR_TIME
from explorer.app.serve.style import megno_kind

#: a pick selects the orbit with a crossing within this many pixels of the click
PICK_PX = 6.0


class Readout:
    """The picked orbit (``picked``), its readout text, and the readouts computed so far."""

    def __init__(self, host, view, orbits, overlays, session):
        self.host, self.view, self.orbits, self.overlays = host, view, orbits, overlays
        self.session = session
        self.text = Div(name="readout", text="", render_as_text=True, styles={"font-family": "monospace"})
        self.picked: int | None = None          # the orbit whose readout is shown
        self.readouts: dict = {}                # orbit id -> orbit_readout(...) of a picked orbit
        self._listeners: list = []

    def on_select(self, listener) -> None:
        """``listener(ident)`` when the picked orbit changes (None: no orbit picked any more)."""
        self._listeners.append(listener)

    def _picked(self, ident) -> None:
        self.picked = ident
        for listener in self._listeners:
            listener(ident)

    def pick(self, p1: float, p2: float, radius_px: float = PICK_PX) -> int | None:
        """A pick at (p1, p2): near a hyperbolic mark its manifolds (None), else selects the orbit with the
        nearest crossing within ``radius_px`` pixels and returns its id."""
        finite = math.isfinite(p1) and math.isfinite(p2)
        saddle = self.overlays.saddle_near(p1, p2, radius_px) if finite else None
        if saddle is not None:
            self.overlays.show_manifolds(*saddle)
            return None
        d = self.orbits.crossings.data
        if not finite or not len(d["orbit"]):
            self.host.say("pick: no orbit on the page yet")
            return None
        px, py = self.view.pixel()
        dist = np.hypot((np.asarray(d["p1"]) - p1) / (px or 1.0), (np.asarray(d["p2"]) - p2) / (py or 1.0))
        k = int(np.argmin(dist))
        if not dist[k] <= radius_px:
            self.host.say(f"pick: no crossing within {radius_px:g} pixels of ({p1:.4g}, {p2:.4g})")
            return None
        ident = int(np.asarray(d["orbit"])[k])
        self.select(ident)
        return ident

    def select(self, ident: int) -> None:
        """Show orbit ``ident``'s readout (computed once per orbit and settings, the latest pick)."""
        start = next(((a, b) for i, a, b, _c in self.orbits.starts if i == ident), None)
        if start is None:
            return
        self._picked(ident)
        self.host.say("")
        if ident in self.readouts:
            self.session.cancel("readout")
            self._show(ident, self.readouts[ident])
            return
        self.text.text = f"orbit {ident} from ({start[0]:.6g}, {start[1]:.6g}): computing mLCE, MEGNO, rotation ..."
        self.session.start("readout", self._compute(ident, start, self.host.settings),
                           budget=search.search_budget(search.READOUT_SECONDS))

    def unpick(self) -> None:
        """No orbit picked (its readout stays known: picked again, it shows at once)."""
        self.session.cancel("readout")
        self.text.text = ""
        self._picked(None)

    def forget(self, ident: int | None = None) -> None:
        """Drop the readout of orbit ``ident`` (None: of every orbit) and stop computing it."""
        if ident is None:
            self.readouts = {}
        else:
            self.readouts.pop(ident, None)
        if ident is None or self.picked == ident:
            self.unpick()

    async def _compute(self, ident, start, settings):
        try:
            r = await self.session.run(search.orbit_readout, settings, start)
        except Exception as exc:  # noqa: BLE001 - reported in the page
            r = {"error": f"{type(exc).__name__}: {' '.join(str(exc).split())}"}
        r["start"] = start
        await self.session.apply(lambda: self._keep(ident, r))

    def _keep(self, ident, r):
        if not any(i == ident for i, *_ in self.orbits.starts):
            return                           # the orbit went meanwhile
        self.readouts[ident] = r
        self._show(ident, r)

    def _show(self, ident, r):
        p1, p2 = r["start"]
        head = f"orbit {ident} from ({p1:.6g}, {p2:.6g}): "
        if "error" in r:
            self.text.text = head + f"failed: {r['error']}"
            return
        text = (head + f"mLCE = {r['mlce']:.4g}, <Y> = {r['megno']:.4g} over t <= {INDICATOR_TIME:g}"
                f" ({megno_kind(r['megno'])})")
        rot, fp = r["rotation"], r["center"]
        if rot is None:
            text += f"; rotation number: none ({r['rotation_error']})"
        elif not math.isfinite(rot.value):
            text += f"; rotation number: none ({rot.status})"
        else:
            text += (f"; rotation number {rot.value:.10g} around ({fp.point[0]:.6g}, {fp.point[1]:.6g}) over "
                     f"{rot.iterates} returns, " + ("converged" if rot.converged else
                                                        f"not converged (|WB_N - WB_2N| = {rot.difference:.2g})"))
        self.text.text = text
