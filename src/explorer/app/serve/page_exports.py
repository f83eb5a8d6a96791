"""The page's exports (:mod:`explorer.app.serve.export`, :mod:`explorer.app.serve.image`): the
session as a scene and its store (every orbit), the view as PNG/SVG (hidden orbits left out)."""
from __future__ import annotations

import io
import math
import os

import numpy as np

from explorer.app.serve import export
from explorer.app.serve.orbits import COLORS
from explorer.model import ParameterError


def _why(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"


class Exports:
    """Scene and figure exports of a page (``host``: its settings, components and messages)."""

    def __init__(self, host, session, export_dir=None, label: str = ""):
        self.host, self.session, self.export_dir, self.label = host, session, export_dir, label

    def _starts(self) -> list:
        return [(a, b) for _i, a, b, _c in self.host.orbits.starts]

    def scene_text(self) -> str:
        return export.session_scene(self.host.settings, self._starts(), overlays=self.host.overlays_on()).to_toml()

    def scene_file(self):
        try:
            return io.StringIO(self.scene_text())
        except ParameterError as exc:
            self.host.say(str(exc))
            return io.StringIO("")

    def view(self):
        """What the page shows now, hidden orbits left out, copied (drawn in any thread)."""
        from explorer.app.serve.image import View

        host = self.host
        orbits, ov = host.orbits, host.overlays
        d = orbits.crossings.data
        orbit = np.asarray(d["orbit"])
        p = np.column_stack([np.asarray(d["p1"], float), np.asarray(d["p2"], float)])
        visible = [s for s in orbits.starts if s[0] not in orbits.hidden]
        shown = [(i, COLORS[c], p[orbit == i], orbits.indicators.get(i, (math.nan,))[0]) for i, _a, _b, c in visible]
        w = host.section.window
        window = (w.x0, w.x1, w.y0, w.y1) if w is not None else (-1.0, 1.0, -1.0, 1.0)
        r = host.chaos.raster_source.data
        raster = None
        if len(r["image"]):
            x, y = r["x"][0], r["y"][0]
            raster = (np.array(r["image"][0], float), (x, x + r["dw"][0], y, y + r["dh"][0]))
        f, q, m = ov.fixed.data, ov.periodic.data, ov.manifold_source.data
        s = host.settings
        title = s.describe() + (f" ({self.label})" if self.label else "")
        mask = s.region_mask()
        return View(window=window, region=s.region, region_mask=mask, orbits=shown, axes=s.axes,
                    starts=[(a, b, COLORS[c]) for _i, a, b, c in visible], raster=raster,
                    raster_scale=host.chaos.scale(),
                    fixed=[(a, b, k == "elliptic") for a, b, k in zip(f["p1"], f["p2"], f["kind"])],
                    separatrices=[np.column_stack([x, y]) for x, y in zip(ov.curves.data["xs"], ov.curves.data["ys"])],
                    manifolds=[(k, np.column_stack([x, y])) for k, x, y in zip(m["kind"], m["xs"], m["ys"])],
                    periodic=[(a, b, k, e == "elliptic") for a, b, k, e in zip(q["p1"], q["p2"], q["period"],
                                                                               q["kind"])],
                    by_megno=bool(orbits.colour_box.value), title=title)

    def figure_bytes(self, fmt: str) -> bytes:
        """The page's view as a PNG or SVG file (the *Figure* downloads)."""
        from explorer.app.serve.image import render

        return render(self.view(), fmt)

    def figure_file(self, fmt):
        try:
            return io.BytesIO(self.figure_bytes(fmt))
        except Exception as exc:  # noqa: BLE001 - reported in the page; the download is empty
            self.host.say(f"figure failed: {_why(exc)}")
            return io.BytesIO(b"")

    def export_figure(self) -> None:
        """Write the page's view as PNG and SVG into the export directory (drawn by a task)."""
        view = self.view()
        self.host.tell("writing the figure ...")
        self.session.start("figure", self._write_figure(view))

    async def _write_figure(self, view):
        try:
            paths = await self.session.run(export.write_figure, self.export_dir, view)
            text, ok = "figure written: " + " and ".join(os.path.basename(p) for p in paths), True
        except Exception as exc:  # noqa: BLE001 - reported in the page
            text, ok = f"figure export failed: {_why(exc)}", False
        await self.session.apply(lambda: self.host.say(text, ok))

    def export(self) -> str | None:
        """Write the session's scene into the export directory (its store follows in a task); returns its path."""
        try:
            sc = export.session_scene(self.host.settings, self._starts(), overlays=self.host.overlays_on())
            path = export.write_scene(self.export_dir, sc)
        except (ParameterError, OSError) as exc:
            self.host.say(f"export failed: {exc}")
            return None
        name = os.path.basename(path)
        self.host.tell(f"scene written: {name} (rerun: explorer sweep {name}); writing the orbits' store ...")
        self.session.start("store", self._write_store(path))
        return path

    async def _write_store(self, scene_path):
        """The exported scene's orbits as an HDF5 store next to it."""
        try:
            out = await self.session.run(export.write_store, scene_path)
            text = f"written: {os.path.basename(scene_path)} and {os.path.basename(out)} (the orbits, sweep format)"
            ok = True
        except Exception as exc:  # noqa: BLE001 - reported in the page
            text, ok = f"store export failed: {_why(exc)}", False
        await self.session.apply(lambda: self.host.say(text, ok))
