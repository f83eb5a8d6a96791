"""The page's section view: the Bokeh figure, the allowed region and the visible ``window``, fitted
to the region and followed through the browser's zoom and pan."""
from __future__ import annotations

import numpy as np
from bokeh.core.property.descriptors import UnsetValueError
from bokeh.events import RangesUpdate
from bokeh.models import ColumnDataSource, Range1d
from bokeh.plotting import figure

from explorer.app.serve import style
from explorer.app.serve.settings import Window, format_window, parse_window
from explorer.model import ParameterError

#: ms after a wheel or pan step at which BokehJS ends its interactive mode and sends the new window
#: (RangesUpdate): Bokeh's default, 500, delays every zoom's first raster by half a second
LOD_TIMEOUT_MS = 100


class SectionView:
    """The figure, the ``region`` source (the allowed ellipse: x, y, width, height) and the window."""

    def __init__(self):
        self.region = ColumnDataSource(name="region")
        # a region without a closed form (a System's map): its mask, white where allowed
        self.region_image = ColumnDataSource(name="region-image")
        # Range1d, set by the server (a DataRange1d keeps its first window in the browser for Reset)
        fig = figure(name="section", width=style.FIGURE_WIDTH, height=style.FIGURE_HEIGHT, sizing_mode="scale_width",
                     min_width=style.FIGURE_MIN_WIDTH, x_range=Range1d(-1.0, 1.0), y_range=Range1d(-1.0, 1.0),
                     tools="pan,wheel_zoom,box_zoom,reset,save", active_scroll="wheel_zoom", toolbar_location="above",
                     background_fill_color=style.FORBIDDEN_COLOR, lod_timeout=LOD_TIMEOUT_MS)
        fig.ellipse("x", "y", width="width", height="height", source=self.region, fill_color=style.ALLOWED_COLOR,
                    line_color=style.BOUNDARY_COLOR, line_width=1.0)
        fig.image_rgba(image="image", x="x", y="y", dw="dw", dh="dh", source=self.region_image)
        fig.grid.visible = False
        fig.on_event(RangesUpdate, self._on_ranges)
        self.figure = fig
        self.window: Window | None = None
        self._listeners: list = []
        self.draw_region(None)

    def on_window(self, listener) -> None:
        """``listener()`` after the browser moved the window (zoom, pan, Reset)."""
        self._listeners.append(listener)

    def _on_ranges(self, event) -> None:
        try:
            self.window = Window(float(event.x0), float(event.x1), float(event.y0), float(event.y1))
        except (TypeError, ValueError):
            return
        for listener in self._listeners:
            listener()

    def frame_px(self) -> tuple:
        """Width and height of the plot's frame in screen pixels, at least 1 (before it is drawn: the nominal size)."""
        try:
            return max(float(self.figure.inner_width), 1.0), max(float(self.figure.inner_height), 1.0)
        except UnsetValueError:  # not drawn in a browser yet: the figure's nominal size
            return style.FIGURE_WIDTH - 60.0, style.FIGURE_HEIGHT - 60.0

    def nearest(self, xs, ys, p1: float, p2: float, radius_px: float) -> int | None:
        """The index of the point of (xs, ys) nearest to (p1, p2) within ``radius_px`` screen pixels, or None."""
        w = self.window
        if w is None or not len(xs):
            return None
        width, height = self.frame_px()
        d = np.hypot((np.asarray(xs, float) - p1) * (width / (w.x1 - w.x0)),
                     (np.asarray(ys, float) - p2) * (height / (w.y1 - w.y0)))
        k = int(np.argmin(d))
        return k if d[k] <= radius_px else None

    def draw_region(self, region, mask=None) -> None:
        """The allowed region (c1, c2, r1, r2; None: empty) as the ellipse or ``mask`` over its box; the view fitted."""
        ellipse: dict = {"x": [], "y": [], "width": [], "height": []}
        image: dict = {"image": [], "x": [], "y": [], "dw": [], "dh": []}
        if region is not None:
            c1, c2, r1, r2 = region
            if mask is None:
                ellipse = {"x": [c1], "y": [c2], "width": [2 * r1], "height": [2 * r2]}
            else:
                rgba = np.where(np.asarray(mask, bool), np.uint32(0xFFFFFFFF), np.uint32(0)).astype(np.uint32)
                image = {"image": [rgba], "x": [c1 - r1], "y": [c2 - r2], "dw": [2 * r1], "dh": [2 * r2]}
        self.region.data, self.region_image.data = ellipse, image
        if region is not None:
            self.fit(c1, c2, (1 + style.VIEW_MARGIN) * r1, (1 + style.VIEW_MARGIN) * r2)

    def load_url(self, args: dict) -> list:
        """A link's ``view`` shown (Reset still goes to the region's view); returns what it refused."""
        try:
            w = parse_window(args["view"]) if args.get("view") else None
        except ParameterError as exc:
            return [str(exc)]
        if w is not None:
            self.figure.x_range.update(start=w.x0, end=w.x1)
            self.figure.y_range.update(start=w.y0, end=w.y1)
            self.window = w
        return []

    def url_query(self) -> dict:
        return {"view": "" if self.window is None else format_window(self.window)}

    def view_fields(self) -> dict:
        """Its part of the exported view (image.View): the window."""
        w = self.window
        return {"window": (-1.0, 1.0, -1.0, 1.0) if w is None else (w.x0, w.x1, w.y0, w.y1)}

    def fit(self, c1: float, c2: float, m1: float, m2: float) -> None:
        """Show the box c1 +- m1, c2 +- m2, equal length per pixel along both axes; Reset goes back to it."""
        px, py = self.frame_px()
        scale = max(2.0 * m1 / px, 2.0 * m2 / py)     # p-units per pixel
        h1, h2 = 0.5 * scale * px, 0.5 * scale * py
        for rng, lo, hi in ((self.figure.x_range, c1 - h1, c1 + h1), (self.figure.y_range, c2 - h2, c2 + h2)):
            rng.update(start=lo, end=hi, reset_start=lo, reset_end=hi)
        self.window = Window(c1 - h1, c1 + h1, c2 - h2, c2 + h2)
