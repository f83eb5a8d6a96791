"""The page's overlays, searched by :mod:`.overlays` in a task under a budget (docs/commands/serve.md)."""
from __future__ import annotations

from functools import partial

import numpy as np
from bokeh.models import ColumnDataSource, Div
from bokeh.transform import factor_mark, linear_cmap

from explorer.app.figures import MANIFOLD_COLORS
from explorer.app.serve import overlays as search
from explorer.app.serve.box import Box
from explorer.app.serve.style import PERIOD_COLORS, SEPARATRIX_CASING, SEPARATRIX_COLOR
from explorer.app.serve.tasks import failure

#: the columns of each overlay's source (by its name); the fixed points' and periodic orbits' marks (_marks)
MARKS = ("p1", "p2", "period", "kind")
COLUMNS = {"fixed": MARKS, "separatrices": ("xs", "ys"), "periodic": MARKS, "manifolds": ("xs", "ys", "color", "kind")}


async def show_search(session, what: str, show, fn, *args):
    """What the search ``fn(*args)`` run by ``session`` found, applied with its message by ``show(found, message)``;
    one that raises gives ``([], "<what>: failed (why)")``."""
    try:
        found, text = await session.run(fn, *args)
    except Exception as exc:  # noqa: BLE001 - reported in the page
        found, text = [], f"{what}: failed ({failure(exc)})"
    await session.apply(lambda: show(found, text))
    return found


def _clear(*sources) -> None:
    for src in sources:
        src.data = {k: [] for k in COLUMNS[src.name]}


def _marks(orbits) -> dict:
    """The columns (MARKS) of a mark at each point of each periodic orbit of ``orbits`` (a fixed point: period 1)."""
    rows = [(float(p[0]), float(p[1]), int(o.period), "elliptic" if o.stable else "hyperbolic")
            for o in orbits for p in np.asarray(o.points)]
    return {k: [r[j] for r in rows] for j, k in enumerate(MARKS)}


def _marked(data) -> list:
    """(p1, p2, period, elliptic) of each mark of the columns ``data`` (:func:`_marks`)."""
    return [(a, b, k, e == "elliptic") for a, b, k, e in zip(data["p1"], data["p2"], data["period"], data["kind"])]


def _lines(curves) -> dict:
    return {"xs": [c[:, 0] for c in curves], "ys": [c[:, 1] for c in curves]}


def _branches(branches) -> dict:
    """The columns (COLUMNS["manifolds"]) of manifold ``branches``."""
    return {**_lines([np.asarray(b.points, float) for b in branches]),
            "color": [MANIFOLD_COLORS[b.kind] for b in branches], "kind": [b.kind for b in branches]}


class Overlays:
    """Fixed points, separatrices, periodic orbits and a saddle's manifolds of ``settings()``;
    ``on_changed()`` after a box changed."""

    def __init__(self, view, session, settings, on_changed):
        self.view, self.session, self.settings, self.on_changed = view, session, settings, on_changed
        self.fixed, self.curves, self.periodic, self.manifold_source = (
            ColumnDataSource({k: [] for k in columns}, name=name) for name, columns in COLUMNS.items())
        self.text = Div(name="overlay", text="", render_as_text=True)
        self.overlay = Box(label="fixed points, separatrices", value=False)
        self.periodic_box = Box(label=f"periodic orbits, periods 1-{search.PERIODIC_MAX}", value=False)
        for box in (self.overlay, self.periodic_box):
            box.param.watch(lambda _e: session.soon(self._boxes_changed), "value")

    def draw_lines(self, fig) -> None:
        """The separatrices and manifolds (under the crossings)."""
        self.separatrix_lines = (
            fig.multi_line("xs", "ys", source=self.curves, line_color=SEPARATRIX_CASING, line_width=3.0),
            fig.multi_line("xs", "ys", source=self.curves, line_color=SEPARATRIX_COLOR, line_width=1.4))
        fig.multi_line("xs", "ys", source=self.manifold_source, line_color="color", line_width=1.2)

    def draw_marks(self, fig) -> None:
        """The marks of the periodic orbits, then larger the fixed points (period 1), over the crossings, each filled
        with the colour of its period."""
        by_period = linear_cmap("period", list(PERIOD_COLORS), 0.5, len(PERIOD_COLORS) + 0.5)
        shape = factor_mark("kind", ["circle", "x"], ["elliptic", "hyperbolic"])
        for source, size, width in ((self.periodic, 8, 1.5), (self.fixed, 11, 2.0)):
            fig.scatter("p1", "p2", source=source, marker=shape, size=size, line_color="black",
                        fill_color=by_period, line_width=width)

    def load_url(self, args: dict) -> list:
        """The boxes from a link (``separatrices``, ``periodic``: "1" ticked); nothing refused."""
        self.overlay.value, self.periodic_box.value = args.get("separatrices") == "1", args.get("periodic") == "1"
        return []

    def url_query(self) -> dict:
        return {"separatrices": str(int(self.overlay.value)), "periodic": str(int(self.periodic_box.value))}

    def view_fields(self) -> dict:
        """Its part of the exported view (image.View): the marks and curves shown."""
        c, m = self.curves.data, self.manifold_source.data
        return {"fixed": _marked(self.fixed.data),
                "separatrices": [np.column_stack([x, y]) for x, y in zip(c["xs"], c["ys"])],
                "manifolds": [(k, np.column_stack([x, y])) for k, x, y in zip(m["kind"], m["xs"], m["ys"])],
                "periodic": _marked(self.periodic.data)}

    def _boxes_changed(self):
        self.restart()
        self.on_changed()

    def restart(self):
        """Search what the boxes ask for at the current settings, under a budget; latest wins."""
        self.session.cancel("manifolds")
        self.session.cancel("overlay")
        _clear(self.fixed, self.curves, self.periodic, self.manifold_source)
        fixed, periodic = self.overlay.value, self.periodic_box.value
        searching = (fixed or periodic) and self.settings().region is not None
        self.text.text = "searching ..." if searching else ""
        if searching:
            budget = search.search_budget(search.FIXED_SECONDS * fixed + search.PERIODIC_SECONDS * periodic)
            self.session.start("overlay", self._compute(self.settings(), fixed, periodic), budget=budget)

    async def _compute(self, settings, fixed, periodic):
        show, session = partial(self._show, []), self.session      # (one list of what the searches said)
        if fixed:
            points = await show_search(session, "fixed points", partial(
                show, self.fixed, _marks, "growing the separatrices ..."), search.fixed_points, settings)
            then = "searching the periodic orbits ..." if periodic else ""
            await show_search(session, "separatrices", partial(show, self.curves, _lines, then), search.separatrices,
                              settings, points)
        if periodic:
            await show_search(session, "periodic orbits", partial(show, self.periodic, _marks, ""),
                              search.periodic_orbits, settings)

    def _show(self, said, source, columns, then, found, text):
        """A search's result: ``columns(found)`` in ``source``, its ``text`` after what the searches before it
        ``said`` (a list), then ``then`` (what is searched next)."""
        source.data = columns(found)
        said.append(text)
        self.text.text = "; ".join(t for t in (*said, then) if t)

    def pick(self, p1: float, p2: float, radius_px: float) -> bool:
        """A pick at (p1, p2): W^u and W^s of the orbit of the nearest hyperbolic mark within ``radius_px`` pixels
        grown and drawn (latest wins), True; False when there is no such mark."""
        marks = [m for src in (self.fixed, self.periodic) for m in _marked(src.data) if not m[3]]
        i = self.view.nearest([m[0] for m in marks], [m[1] for m in marks], p1, p2, radius_px)
        if i is None:
            return False
        a, b, period, _e = marks[i]
        _clear(self.manifold_source)
        self.text.text = f"growing the manifolds of the period-{period} orbit at ({a:.6g}, {b:.6g}) ..."
        show = partial(self._show, [], self.manifold_source, _branches, "")
        self.session.start("manifolds", show_search(self.session, "manifolds", show, search.saddle_manifolds,
                                                    self.settings(), (a, b), period),
                           budget=search.search_budget(search.MANIFOLD_SECONDS))
        return True
