"""The page's images under the orbits: the chaos layer and the density image (docs/commands/serve.md)."""
from __future__ import annotations

import time

import numpy as np
import panel as pn
from bokeh.models import ColorBar, ColumnDataSource, LinearColorMapper

from explorer.analysis.budget import Budget
from explorer.app.chaos_raster import STYLES
from explorer.app.serve import density
from explorer.app.serve import raster as raster_mod
from explorer.app.serve.box import Box
from explorer.app.serve.orbits import COLORS
from explorer.app.serve.style import MEGNO_HIGH, MEGNO_LOW, MEGNO_ORBIT_SKIP, megno_palette
from explorer.app.serve.tasks import failure

#: while orbits stream in, the density image is redrawn at most this often (s)
DENSITY_SECONDS = 0.5
#: the chaos layer's colour bar label and (low, high) scale of each indicator (frequency diffusion: the chaos maps')
SCALES = {"megno": ("⟨Y⟩ (MEGNO)", MEGNO_LOW, MEGNO_HIGH),
          "frequency_diffusion": ("log10|ν1 − ν2| (frequency diffusion)", STYLES["frequency_diffusion"].vmin,
                                  STYLES["frequency_diffusion"].vmax)}


def _empty(*extra) -> dict:
    return {k: [] for k in ("image", "x", "y", "dw", "dh", "n", *extra)}


class ChaosLayer:
    """The chaos layer of ``settings()``; ``on_changed()`` after its box or indicator changed.  ``center``: frequency
    diffusion's last (settings, point, elliptic); ``exact``: MEGNO's finest raster not adaptive (``megno=exact``)."""

    def __init__(self, view, session, resolutions: tuple, time: float, settings, say, on_changed):
        self.view, self.settings, self.say, self.on_changed = view, settings, say, on_changed
        self.resolutions, self.time = resolutions, float(time)
        self.iterates = raster_mod.DIFFUSION_ITERATES
        self.session = session
        self.exact = False
        self.raster_source = ColumnDataSource(_empty("complete"), name="raster")
        self.center: tuple | None = None
        self.layer = Box(label="chaos layer", value=False)
        self.indicator = pn.widgets.Select(options={f"MEGNO ⟨Y⟩ (T = {self.time:g})": "megno",
                                                    f"frequency diffusion (N = {self.iterates})":
                                                    "frequency_diffusion"},
                                           value="megno", width=210)
        self.layer.param.watch(lambda _e: session.soon(self._changed), "value")
        self.indicator.param.watch(lambda _e: session.soon(lambda: self._changed(clear=True)), "value")
        view.on_window(self.restart)

    def draw(self, fig) -> None:
        self.mapper = LinearColorMapper(palette=megno_palette(), nan_color=(0, 0, 0, 0))
        fig.image(image="image", x="x", y="y", dw="dw", dh="dh", source=self.raster_source, color_mapper=self.mapper,
                  alpha=0.85)
        self.colour_bar = ColorBar(color_mapper=self.mapper, width=12, name="megno-colour-bar")
        fig.add_layout(self.colour_bar, "right")
        self._show_scale()

    def _show_scale(self) -> None:
        """The colour bar: shown with the layer, the indicator's label and scale (frequency diffusion: its centre)."""
        title, low, high = SCALES[self.indicator.value]
        self.mapper.update(low=low, high=high)
        c = self.center
        if self.indicator.value == "frequency_diffusion" and c is not None and c[0] == self.settings():
            title += f" around {'elliptic point' if c[2] else 'region centre'} ({c[1][0]:.4g}, {c[1][1]:.4g})"
        self.colour_bar.update(title=title, visible=bool(self.layer.value))

    def load_url(self, args: dict) -> list:
        """The layer from a link (``indicator``; ``megno``: "1" on, "exact" not adaptive); returns what it refused."""
        name, refused = args.get("indicator") or "megno", []
        if name not in raster_mod.INDICATORS:
            refused = [f"indicator must be one of {', '.join(raster_mod.INDICATORS)}, got {name[:40]!r}"]
            name = "megno"
        self.indicator.value = name
        self.exact = args.get("megno") == "exact"
        self.layer.value = args.get("megno") in ("1", "exact")
        return refused

    def url_query(self) -> dict:
        on = "exact" if self.exact else "1"
        return {"megno": on if self.layer.value else "0", "indicator": self.indicator.value}

    def view_fields(self) -> dict:
        """Its part of the exported view (image.View): the raster shown and its colour scale."""
        r, raster = self.raster_source.data, None
        if len(r["image"]):
            x, y = r["x"][0], r["y"][0]
            raster = (np.array(r["image"][0], float), (x, x + r["dw"][0], y, y + r["dh"][0]))
        return {"raster": raster, "raster_scale": SCALES[self.indicator.value][1:]}

    def _changed(self, clear: bool = False):
        if clear:
            self.raster_source.data = _empty("complete")       # no value of the other indicator on its scale
        self.restart()
        self.on_changed()

    def restart(self) -> None:
        """The rasters of the current window, indicator and settings (none when the layer is off)."""
        window, settings = self.view.window, self.settings()
        self._show_scale()
        if not self.layer.value or window is None or settings.region is None:
            self.session.cancel("raster")
            self.raster_source.data = _empty("complete")
            return
        self.session.start("raster", self._compute(settings, window, self.indicator.value),
                           on_error=lambda exc: self.say(f"chaos layer failed: {failure(exc)}"),
                           budget=Budget(None, max_steps=raster_mod.RASTER_MAX_STEPS))

    async def _compute(self, settings, window, indicator) -> None:
        session, c = self.session, self.center
        if indicator == "frequency_diffusion" and (c is None or c[0] != settings):
            c = self.center = (settings, *await session.run(raster_mod.diffusion_center, settings))
            await session.apply(self._show_scale)
        images = raster_mod.rasters(settings, window, resolutions=self.resolutions, time=self.time, indicator=indicator,
                                    center=None if c is None else c[1], iterates=self.iterates, adaptive=not self.exact)
        while (image := await session.run(next, images, None)) is not None:
            await session.apply(lambda image=image: self.show_image(image))

    def show_image(self, image) -> None:
        w = image.window
        self.raster_source.data = {"image": [image.values], "x": [w.x0], "y": [w.y0], "dw": [w.x1 - w.x0],
                                   "dh": [w.y1 - w.y0], "n": [image.n], "complete": [image.complete]}


class DensityImage:
    """The density image of the crossings not drawn as glyphs, redrawn for the visible window."""

    def __init__(self, orbits, view):
        self.orbits, self.view = orbits, view
        self.density = ColumnDataSource(_empty(), name="density")
        self.dense = False                      # the density image replaces the crossings' glyphs
        self._key: tuple | None = None          # what the image on the page shows
        self._at = 0.0
        view.on_window(self.refresh)

    def draw(self, fig) -> None:
        fig.image_rgba(image="image", x="x", y="y", dw="dw", dh="dh", source=self.density)

    def refresh(self, force: bool = False) -> None:
        """Redraw the image of the crossings that are not dots: at once when ``force`` or which orbits it images,
        where or how changed, at most every DENSITY_SECONDS while their rows change alone, never unchanged."""
        orbits = self.orbits
        counts = {r.ident: r.done for r in orbits.runs.values() if not r.hidden}
        dense = sum(counts.values()) > density.THRESHOLD
        first = 0 if dense else density.glyph_cutoff(counts)
        if dense != self.dense:
            self.dense = dense
            orbits.points.visible = not dense
            orbits.show_all()
        orbits.glyph_filter.args = {"first": first}
        imaged = [orbits.runs[i] for i in counts if dense or i < first]      # every orbit, or the older ones
        n = sum(r.done for r in imaged)
        w = self.view.window
        if not n or w is None:
            if not n and self.density.data["image"]:
                self.density.data = _empty()
            self._key = None
            return
        px, py = self.view.frame_px()
        nx, ny = max(int(px) // density.CELL_PX, 1), max(int(py) // density.CELL_PX, 1)
        by_megno = bool(orbits.colour_box.value)
        # (which orbits, where, how coloured), (their rows: they change only by growing, leaving, or a MEGNO known)
        known = sum(r.indicators is not None for r in imaged) if by_megno else -1
        key = (dense, first, w, nx, ny, by_megno), (n, known)
        rows_alone = not force and self._key is not None and key[0] == self._key[0]
        if key == self._key or rows_alone and time.monotonic() - self._at < DENSITY_SECONDS:
            return
        self._at, self._key = time.monotonic(), key
        p1, p2, c, megno = orbits.columns(imaged, keys=("p1", "p2", "c", "megno")).values()
        image = density.density_rgba(p1, p2, c, (w.x0, w.x1, w.y0, w.y1), nx, ny, COLORS,
                                     megno=megno if by_megno else None, palette=megno_palette(MEGNO_ORBIT_SKIP),
                                     lo=MEGNO_LOW, hi=MEGNO_HIGH)
        self.density.data = {"image": [image], "x": [w.x0], "y": [w.y0], "dw": [w.x1 - w.x0], "dh": [w.y1 - w.y0],
                             "n": [n]}
