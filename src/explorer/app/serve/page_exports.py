"""The page's exports: the session as a scene (download, and into --export-dir with its HDF5 store)
and the view as PNG/SVG (downloads, and into --export-dir): :mod:`explorer.app.serve.export` and
:mod:`explorer.app.serve.image` do the work.  A part of :class:`~explorer.app.serve.page.SectionPage`
(a mixin)."""
from __future__ import annotations

import io
import math
import os
import threading
from functools import partial

import numpy as np

from explorer.app.serve import export
from explorer.app.serve.orbits import COLORS
from explorer.model import ParameterError


class ExportsMixin:
    """Scene and figure exports of :class:`~explorer.app.serve.page.SectionPage`."""

    def _scene_text(self) -> str:
        return export.session_scene(self.settings, [(a, b) for _i, a, b, _c in self.starts],
                                    overlays=self.overlays_on()).to_toml()

    def overlays_on(self) -> tuple:
        """The names of the overlays that are on (separatrices, periodic, megno), as in the URL."""
        q = self.url_query()
        return tuple(n for n in ("separatrices", "periodic", "megno") if q.get(n) == "1")

    def _scene_file(self):
        try:
            return io.StringIO(self._scene_text())
        except ParameterError as exc:
            self.say(str(exc))
            return io.StringIO("")

    def view(self):
        """What the page shows now, copied (:class:`explorer.app.serve.image.View`: drawn by
        :func:`explorer.app.serve.image.render`, in any thread)."""
        from explorer.app.serve.image import View

        d = self.crossings.data
        orbit = np.asarray(d["orbit"])
        p = np.column_stack([np.asarray(d["p1"], float), np.asarray(d["p2"], float)])
        orbits = [(i, COLORS[c], p[orbit == i], self.indicators.get(i, (math.nan,))[0]) for i, _a, _b, c in self.starts]
        w = self.window
        window = (w.x0, w.x1, w.y0, w.y1) if w is not None else (-1.0, 1.0, -1.0, 1.0)
        r = self.raster_source.data
        raster = None
        if len(r["image"]):
            x, y = r["x"][0], r["y"][0]
            raster = (np.array(r["image"][0], float), (x, x + r["dw"][0], y, y + r["dh"][0]))
        f, q = self.fixed.data, self.periodic.data
        s = self.settings
        title = f"mu = {s.params.mu:g}, h = {s.h:g}, {s.method}" + (f" ({self.label})" if self.label else "")
        return View(window=window, region=s.region, orbits=orbits,
                    starts=[(a, b, COLORS[c]) for _i, a, b, c in self.starts], raster=raster,
                    fixed=[(a, b, k == "elliptic") for a, b, k in zip(f["p1"], f["p2"], f["kind"])],
                    separatrices=[np.column_stack([x, y]) for x, y in zip(self.curves.data["xs"],
                                                                          self.curves.data["ys"])],
                    manifolds=[(k, np.column_stack([x, y])) for k, x, y in zip(
                        self.manifold_source.data["kind"], self.manifold_source.data["xs"],
                        self.manifold_source.data["ys"])],
                    periodic=[(a, b, k, e == "elliptic") for a, b, k, e in zip(q["p1"], q["p2"], q["period"],
                                                                               q["kind"])],
                    by_megno=bool(self.colour_box.value), title=title)

    def figure_bytes(self, fmt: str) -> bytes:
        """The page's view as a PNG or SVG file (the *Figure* downloads)."""
        from explorer.app.serve.image import render

        return render(self.view(), fmt)

    def _figure_file(self, fmt):
        try:
            return io.BytesIO(self.figure_bytes(fmt))
        except Exception as exc:  # noqa: BLE001 - reported in the page; the download is empty
            self.say(f"figure failed: {type(exc).__name__}: {' '.join(str(exc).split())}")
            return io.BytesIO(b"")

    def export_figure(self) -> None:
        """Write the page's view as PNG and SVG into the export directory (drawn in a thread)."""
        view = self.view()
        self.tell("writing the figure ...")
        threading.Thread(target=self._write_figure, args=(view,), name="explorer-serve-figure", daemon=True).start()

    def _write_figure(self, view):
        try:
            paths = export.write_figure(self.export_dir, view)
            text, ok = "figure written: " + " and ".join(os.path.basename(p) for p in paths), True
        except Exception as exc:  # noqa: BLE001 - reported in the page
            text, ok = f"figure export failed: {type(exc).__name__}: {' '.join(str(exc).split())}", False
        self._post(partial(self.say, text, ok))

    def export(self) -> str | None:
        """Write the session's scene into the export directory; returns its path."""
        try:
            sc = export.session_scene(self.settings, [(a, b) for _i, a, b, _c in self.starts],
                                      overlays=self.overlays_on())
            path = export.write_scene(self.export_dir, sc)
        except (ParameterError, OSError) as exc:
            self.say(f"export failed: {exc}")
            return None
        name = os.path.basename(path)
        self.tell(f"scene written: {name} (rerun: explorer sweep {name}); writing the orbits' store ...")
        threading.Thread(target=self._write_store, args=(path,), name="explorer-serve-store", daemon=True).start()
        return path

    def _write_store(self, scene_path):
        """In a thread: the exported scene's orbits as an HDF5 store next to it."""
        try:
            out = export.write_store(scene_path)
            text = f"written: {os.path.basename(scene_path)} and {os.path.basename(out)} (the orbits, sweep format)"
            ok = True
        except Exception as exc:  # noqa: BLE001 - reported in the page
            text, ok = f"store export failed: {type(exc).__name__}: {' '.join(str(exc).split())}", False
        self._post(partial(self.say, text, ok))
