"""The page's overlays (docs/commands/serve.md): fixed points with their separatrices, periodic orbits
(one task under a budget) and a picked saddle's manifolds (another), searched by :mod:`.overlays`."""
from __future__ import annotations

import numpy as np
from bokeh.models import ColumnDataSource, Div, LinearColorMapper

from explorer.app.serve import overlays as search
from explorer.app.serve.box import Box
from explorer.app.serve.style import MANIFOLD_COLORS, PERIOD_COLORS, SEPARATRIX_CASING, SEPARATRIX_COLOR
from explorer.app.serve.tasks import failure

#: the columns of each overlay's source
COLUMNS = {"fixed": ("p1", "p2", "kind", "marker"), "separatrices": ("xs", "ys"),
           "manifolds": ("xs", "ys", "color", "kind"), "periodic": ("p1", "p2", "period", "kind", "marker")}


def _empty(name: str) -> dict:
    return {k: [] for k in COLUMNS[name]}


def _marks(points, stable) -> dict:
    return {"p1": [float(p[0]) for p in points], "p2": [float(p[1]) for p in points],
            "kind": ["elliptic" if s else "hyperbolic" for s in stable],
            "marker": ["circle" if s else "x" for s in stable]}


class Overlays:
    """Fixed points, separatrices, periodic orbits and a saddle's manifolds of ``settings()``;
    ``on_changed()`` after a box changed."""

    def __init__(self, view, session, settings, on_changed):
        self.view, self.session, self.settings, self.on_changed = view, session, settings, on_changed
        self.fixed = ColumnDataSource(_empty("fixed"), name="fixed")
        self.curves = ColumnDataSource(_empty("separatrices"), name="separatrices")
        self.periodic = ColumnDataSource(_empty("periodic"), name="periodic")
        self.manifold_source = ColumnDataSource(_empty("manifolds"), name="manifolds")
        self.text = Div(name="overlay", text="", render_as_text=True)
        self.overlay = Box(label="fixed points, separatrices", value=False)
        self.periodic_box = Box(label=f"periodic orbits, periods 1-{search.PERIODIC_MAX}", value=False)
        for box in (self.overlay, self.periodic_box):
            box.param.watch(lambda _e: session.soon(self._boxes_changed), "value")

    def draw_lines(self, fig) -> None:
        """The separatrices and manifolds (under the crossings)."""
        # a dark casing under a bright line: visible on white and on every colour of the MEGNO layer
        self.separatrix_lines = (
            fig.multi_line("xs", "ys", source=self.curves, line_color=SEPARATRIX_CASING, line_width=3.0),
            fig.multi_line("xs", "ys", source=self.curves, line_color=SEPARATRIX_COLOR, line_width=1.4))
        fig.multi_line("xs", "ys", source=self.manifold_source, line_color="color", line_width=1.2)

    def draw_marks(self, fig) -> None:
        """The marks of the periodic orbits and fixed points (over the crossings)."""
        fig.scatter("p1", "p2", source=self.periodic, marker="marker", size=8, line_color="black",
                    fill_color={"field": "period", "transform": LinearColorMapper(
                        palette=list(PERIOD_COLORS), low=0.5, high=len(PERIOD_COLORS) + 0.5)}, line_width=1.5)
        fig.scatter("p1", "p2", source=self.fixed, marker="marker", size=11, line_color="black",
                    fill_color="white", line_width=2)

    def on(self) -> tuple:
        """The names of the overlays that are on, as in the URL."""
        return tuple(n for n, box in (("separatrices", self.overlay), ("periodic", self.periodic_box)) if box.value)

    def _boxes_changed(self):
        self.restart()
        self.on_changed()

    def restart(self):
        """Search what the boxes ask for at the current settings, under a budget; latest wins."""
        self.clear_manifolds()
        self.fixed.data = _empty("fixed")
        self.curves.data = _empty("separatrices")
        self.periodic.data = _empty("periodic")
        self.text.text = ""
        wanted = (self.overlay.value, self.periodic_box.value)
        if not any(wanted) or self.settings().region is None:
            self.session.cancel("overlay")
            return
        self.text.text = "searching ..."
        budget = search.search_budget(search.FIXED_SECONDS * wanted[0] + search.PERIODIC_SECONDS * wanted[1])
        self.session.start("overlay", self._compute(self.settings(), *wanted), budget=budget)

    async def _compute(self, settings, fixed, periodic):
        run, apply = self.session.run, self.session.apply
        text = ""
        if fixed:
            try:
                points, text = await run(search.fixed_points, settings)
                growing = "; growing the separatrices ..." if any(not p.stable for p in points) else ""
                await apply(lambda: self._show_fixed(points, [], text + growing))
                curves, text = await run(search.separatrices, settings, points, text)
            except Exception as exc:  # noqa: BLE001 - reported in the page
                points, curves, text = [], [], f"fixed points: failed ({failure(exc)})"
            await apply(lambda: self._show_fixed(points, curves, text))
        if periodic:
            if fixed:
                await apply(lambda: setattr(self.text, "text", f"{text}; searching the periodic orbits ..."))
            try:
                orbits, found = await run(search.periodic_orbits, settings, search.PERIODIC_MAX)
            except Exception as exc:  # noqa: BLE001 - reported in the page
                orbits, found = [], f"periodic orbits: failed ({failure(exc)})"
            await apply(lambda: self._show_periodic(orbits, "; ".join(t for t in (text, found) if t)))

    def _show_periodic(self, orbits, text):
        rows = [(p, int(o.period), o.stable) for o in orbits for p in np.asarray(o.points)]
        self.periodic.data = {**_marks([r[0] for r in rows], [r[2] for r in rows]), "period": [r[1] for r in rows]}
        self.text.text = text

    def _show_fixed(self, points, curves, text):
        self.fixed.data = _marks([fp.point for fp in points], [fp.stable for fp in points])
        self.curves.data = {"xs": [c[:, 0] for c in curves], "ys": [c[:, 1] for c in curves]}
        self.text.text = text

    # ------------------------------------------------------------ manifolds of a picked saddle
    def saddle_near(self, p1: float, p2: float, radius_px: float) -> tuple | None:
        """(point, period) of the nearest hyperbolic mark within ``radius_px`` pixels of (p1, p2), or None."""
        px, py = self.view.pixel()
        best = None
        for src, fixed in ((self.fixed.data, True), (self.periodic.data, False)):
            for i, (a, b, kind) in enumerate(zip(src["p1"], src["p2"], src["kind"])):
                if kind != "hyperbolic":
                    continue
                d = float(np.hypot((a - p1) / (px or 1.0), (b - p2) / (py or 1.0)))
                k = 1 if fixed else int(src["period"][i])
                if d <= radius_px and (best is None or d < best[0]):
                    best = (d, (float(a), float(b)), k)
        return None if best is None else best[1:]

    def show_manifolds(self, point, period: int = 1) -> None:
        """Grow and draw W^u and W^s of the hyperbolic orbit of ``period`` through ``point`` (latest wins)."""
        self.manifold_source.data = _empty("manifolds")
        self.text.text = (f"growing the manifolds of the period-{period} orbit at "
                          f"({point[0]:.6g}, {point[1]:.6g}) ...")
        self.session.start("manifolds", self._compute_manifolds(tuple(point), int(period), self.settings()),
                           budget=search.search_budget(search.MANIFOLD_SECONDS))

    def clear_manifolds(self) -> None:
        self.session.cancel("manifolds")
        self.manifold_source.data = _empty("manifolds")

    async def _compute_manifolds(self, point, period, settings):
        try:
            branches, text = await self.session.run(search.saddle_manifolds, settings, point, period)
        except Exception as exc:  # noqa: BLE001 - reported in the page
            branches, text = [], f"manifolds: failed ({failure(exc)})"
        await self.session.apply(lambda: self._show_manifolds(branches, text))

    def _show_manifolds(self, branches, text):
        pts = [np.asarray(b.points, float) for b in branches]
        self.manifold_source.data = {"xs": [p[:, 0] for p in pts], "ys": [p[:, 1] for p in pts],
                                     "color": [MANIFOLD_COLORS[b.kind] for b in branches],
                                     "kind": [b.kind for b in branches]}
        self.text.text = text
