"""The page's layers under and over the orbits: the MEGNO raster of the visible window
(:class:`explorer.app.serve.raster.RasterWorker`), the density image of the crossings that are not
drawn as glyphs (the older orbits past :data:`explorer.app.serve.density.GLYPH_BUDGET` crossings,
all past :data:`explorer.app.serve.density.THRESHOLD`), the fixed points, separatrices and periodic
orbits (:mod:`explorer.app.serve.overlays`, in a thread), and the manifolds of a picked hyperbolic
point (:func:`explorer.app.serve.overlays.saddle_manifolds`, in a thread).  A part of
:class:`~explorer.app.serve.page.SectionPage` (a mixin)."""
from __future__ import annotations

import threading
import time
from functools import partial

import numpy as np

from explorer.app.serve import density
from explorer.app.serve import raster as raster_mod
from explorer.app.serve.jobs import LatestJob
from explorer.app.serve.orbits import COLORS
from explorer.app.serve.overlays import PERIODIC_MAX
from explorer.app.serve.style import MANIFOLD_COLORS, MEGNO_HIGH, MEGNO_LOW, MEGNO_ORBIT_SKIP, megno_palette


def _empty_raster() -> dict:
    return {"image": [], "x": [], "y": [], "dw": [], "dh": [], "n": [], "complete": []}

#: while orbits stream in, the density image is redrawn at most this often (s)
DENSITY_SECONDS = 0.5


#: the columns of the page's crossings (and c, the orbit's colour index)
CROSSING_COLUMNS = ("orbit", "t", "p1", "p2", "M", "dH", "megno")


def _empty_crossings() -> dict:
    d = {c: np.zeros(0) for c in CROSSING_COLUMNS}
    d["orbit"] = np.zeros(0, np.int64)
    d["c"] = np.zeros(0, np.int64)
    return d


def _empty_density() -> dict:
    return {"image": [], "x": [], "y": [], "dw": [], "dh": [], "n": []}


def _empty_manifolds() -> dict:
    return {"xs": [], "ys": [], "color": [], "kind": []}


def _empty_periodic() -> dict:
    return {"p1": [], "p2": [], "period": [], "kind": [], "marker": []}


class LayersMixin:
    """The MEGNO layer, the density image of many crossings and the overlays of
    :class:`~explorer.app.serve.page.SectionPage`."""

    # ------------------------------------------------------------ the MEGNO layer
    def _on_ranges(self, event):
        """The view moved (zoom, pan, reset): the layer follows the new window."""
        try:
            self.window = raster_mod.Window(float(event.x0), float(event.x1), float(event.y0), float(event.y1))
        except (TypeError, ValueError):
            return
        if self.layer.value:
            self._restart_raster()
        self._refresh_density(force=True)
        self._push_url_soon()             # (the zoom window is in the link)

    def _refresh_density(self, force: bool = False) -> None:
        """Draw the crossings that are not glyphs as the density image of the visible window: past
        density.GLYPH_BUDGET crossings, those of the older orbits (the glyphs keep the newest,
        :func:`~explorer.app.serve.density.glyph_cutoff`); past density.THRESHOLD, all of them
        (the glyphs hidden, the browser holds no rows); below the budget, none (no image).  The
        image is redrawn at most every DENSITY_SECONDS while orbits stream in, at once when
        ``force`` (the view moved, the colouring changed, the last orbit finished) or when orbits
        move between the glyphs and the image; never when what it shows is unchanged.  (Not called
        by a message carrying a click's first crossings: those go alone, SectionPage._flush.)"""
        orbit = self.crossings.data["orbit"]
        n = len(orbit)
        dense = n > density.THRESHOLD
        if dense != self.dense:
            self.dense = dense
            self.points.visible = not dense
            # past the threshold the browser holds no rows (one message empties them); below it again,
            # every row goes back
            self._show_all()
            force = True
        first = 0 if dense else density.glyph_cutoff(orbit)
        if first != self.glyph_first:
            self.glyph_first = first
            self.glyph_filter.args = {"first": first}
            force = True
        if not dense and first == 0:
            if self.density.data["image"]:
                self.density.data = _empty_density()
            self._density_key = None
            return
        w = self.window
        if w is None:
            return
        px, py = self._frame_px()
        nx, ny = max(int(px) // density.CELL_PX, 1), max(int(py) // density.CELL_PX, 1)
        by_megno = bool(self.colour_box.value)
        keep = None if dense else np.asarray(orbit) < first           # the image's rows: the older orbits
        shown = n if keep is None else int(np.count_nonzero(keep))
        # the image's rows change only by growing, by leaving (undo, clear: first or their count
        # changes) and (coloured by MEGNO) by the MEGNO of an orbit becoming known
        key = (dense, first, shown, len(self.indicators) if by_megno else -1, by_megno, w, nx, ny)
        if key == self._density_key:
            return
        now = time.monotonic()
        if not force and now - self._density_at < DENSITY_SECONDS:
            return
        self._density_at = now
        self._density_key = key
        d = self.crossings.data
        if keep is None:
            p1, p2, c, megno = d["p1"], d["p2"], d["c"], d["megno"]
        else:
            p1, p2, c, megno = (np.asarray(d[k])[keep] for k in ("p1", "p2", "c", "megno"))
        image = density.density_rgba(p1, p2, c, (w.x0, w.x1, w.y0, w.y1), nx, ny, COLORS,
                                     megno=megno if by_megno else None,
                                     palette=megno_palette(MEGNO_ORBIT_SKIP) if by_megno else None,
                                     lo=MEGNO_LOW, hi=MEGNO_HIGH)
        self.density.data = {"image": [image], "x": [w.x0], "y": [w.y0], "dw": [w.x1 - w.x0], "dh": [w.y1 - w.y0],
                             "n": [shown]}

    def _layer_changed(self):
        self.colour_bar.visible = bool(self.layer.value)
        self._restart_raster()
        self._push_url()

    def _restart_raster(self):
        if not self.layer.value or self.window is None or self.settings.region is None:
            self.raster.cancel()
            self._raster_generation = -1
            self.raster_source.data = _empty_raster()
            return
        self._raster_generation = self.raster.start(self.settings, self.window)

    def _on_image(self, generation, image):
        self._post(partial(self._show_image, generation, image))

    def _on_raster_error(self, exc):
        self._post(partial(self.say, f"MEGNO layer failed: {type(exc).__name__}: {' '.join(str(exc).split())}"))

    def _show_image(self, generation, image):
        if generation != self._raster_generation:
            return                          # an older window or older settings
        w = image.window
        self.raster_source.data = {"image": [image.values], "x": [w.x0], "y": [w.y0], "dw": [w.x1 - w.x0],
                                   "dh": [w.y1 - w.y0], "n": [image.n], "complete": [image.complete]}

    # ------------------------------------------------------------ fixed points and separatrices
    def _overlay_changed(self):
        self._restart_overlay()
        self._push_url()

    def _restart_overlay(self):
        """Search the fixed points (and separatrices) and the periodic orbits the boxes ask for,
        at the current settings, in a thread of its own, under a budget
        (:func:`explorer.app.serve.overlays.search_budget`: FIXED_SECONDS, PERIODIC_SECONDS); a
        newer request cancels the older search (its compiled loops stop within a step) and makes
        its result stale."""
        self._overlay_generation += 1
        self._cancel_overlay()
        self._clear_manifolds()
        self.fixed.data = {"p1": [], "p2": [], "kind": [], "marker": []}
        self.curves.data = {"xs": [], "ys": []}
        self.periodic.data = _empty_periodic()
        self.overlay_text.text = ""
        wanted = (self.overlay.value, self.periodic_box.value)
        if not any(wanted) or self.settings.region is None:
            return
        self.overlay_text.text = "searching ..."
        from explorer.app.serve.overlays import FIXED_SECONDS, PERIODIC_SECONDS, search_budget

        budget = search_budget(FIXED_SECONDS * wanted[0] + PERIODIC_SECONDS * wanted[1])
        self._overlay_budget = budget
        threading.Thread(target=self._compute_overlay, args=(self._overlay_generation, budget, self.settings, *wanted),
                         name="explorer-serve-overlay", daemon=True).start()

    _overlay_budget = None

    def _cancel_overlay(self) -> None:
        """Stop the running overlay search, if any (a newer one replaces it, or the page closes)."""
        if self._overlay_budget is not None:
            self._overlay_budget.cancel()
            self._overlay_budget = None

    def _compute_overlay(self, generation, budget, settings, fixed, periodic):
        from explorer.app.serve.overlays import fixed_points_and_curves, periodic_orbits

        texts: list = []

        def on_points(points, text):
            self._post(partial(self._show_fixed, generation, points, [], "; ".join([*texts, text])))

        with budget:
            if fixed:
                try:
                    points, curves, text = fixed_points_and_curves(settings, on_points)
                except Exception as exc:  # noqa: BLE001 - reported in the page
                    points, curves, text = [], [], f"fixed points: failed ({type(exc).__name__}: {exc})"
                texts.append(text)
                self._post(partial(self._show_fixed, generation, points, curves, "; ".join(texts)))
            if periodic and generation == self._overlay_generation:
                if fixed:
                    self._post(partial(self._show_overlay_text, generation,
                                       "; ".join([*texts, "searching the periodic orbits ..."])))
                try:
                    orbits, text = periodic_orbits(settings, PERIODIC_MAX)
                except Exception as exc:  # noqa: BLE001 - reported in the page
                    orbits, text = [], f"periodic orbits: failed ({type(exc).__name__}: {exc})"
                texts.append(text)
                self._post(partial(self._show_periodic, generation, orbits, "; ".join(texts)))

    def _show_overlay_text(self, generation, text):
        if generation == self._overlay_generation:
            self.overlay_text.text = text

    def _show_periodic(self, generation, orbits, text):
        if generation != self._overlay_generation:
            return
        rows = [(float(p[0]), float(p[1]), int(o.period), o.stable) for o in orbits for p in np.asarray(o.points)]
        self.periodic.data = {"p1": [r[0] for r in rows], "p2": [r[1] for r in rows], "period": [r[2] for r in rows],
                              "kind": ["elliptic" if r[3] else "hyperbolic" for r in rows],
                              "marker": ["circle" if r[3] else "x" for r in rows]}
        self.overlay_text.text = text

    def _show_fixed(self, generation, points, curves, text):
        if generation != self._overlay_generation:
            return
        self.fixed.data = {"p1": [float(fp.point[0]) for fp in points], "p2": [float(fp.point[1]) for fp in points],
                           "kind": ["elliptic" if fp.stable else "hyperbolic" for fp in points],
                           "marker": ["circle" if fp.stable else "x" for fp in points]}
        self.curves.data = {"xs": [c[:, 0] for c in curves], "ys": [c[:, 1] for c in curves]}
        self.overlay_text.text = text

    # ------------------------------------------------------------ manifolds of a picked saddle
    def saddle_near(self, p1: float, p2: float, radius_px: float) -> tuple | None:
        """(point, period) of the hyperbolic mark (fixed point or point of a periodic orbit) within
        ``radius_px`` screen pixels of (p1, p2), the nearest; None when there is none."""
        px, py = self._pixel()
        best = None
        for src, period_of in ((self.fixed.data, lambda i: 1), (self.periodic.data, None)):
            for i, (a, b, kind) in enumerate(zip(src["p1"], src["p2"], src["kind"])):
                if kind != "hyperbolic":
                    continue
                d = float(np.hypot((a - p1) / (px or 1.0), (b - p2) / (py or 1.0)))
                k = 1 if period_of else int(src["period"][i])
                if d <= radius_px and (best is None or d < best[0]):
                    best = (d, (float(a), float(b)), k)
        return None if best is None else best[1:]

    def show_manifolds(self, point, period: int = 1) -> None:
        """Grow and draw W^u and W^s of the hyperbolic orbit of ``period`` through ``point`` (in
        the session's manifold thread: the latest request only; a new value or overlay drops it)."""
        self._manifold_generation = getattr(self, "_manifold_generation", 0) + 1
        self._cancel_manifolds()
        self.manifold_source.data = _empty_manifolds()
        self.overlay_text.text = (f"growing the manifolds of the period-{period} orbit at "
                                  f"({point[0]:.6g}, {point[1]:.6g}) ...")
        self._manifold_jobs.put((self._manifold_generation, tuple(point), int(period), self.settings))

    @property
    def _manifold_jobs(self):
        return LatestJob.of(self, "_manifold_worker", self._compute_manifolds, "explorer-serve-manifolds")

    def _stop_manifolds(self) -> None:
        self._cancel_manifolds()
        LatestJob.stop_of(self, "_manifold_worker")

    _manifold_budget = None

    def _cancel_manifolds(self) -> None:
        """Stop the manifolds being grown, if any (their result is no longer wanted)."""
        if self._manifold_budget is not None:
            self._manifold_budget.cancel()

    def _clear_manifolds(self) -> None:
        self._manifold_generation = getattr(self, "_manifold_generation", 0) + 1
        self._cancel_manifolds()
        self.manifold_source.data = _empty_manifolds()

    def _compute_manifolds(self, generation, point, period, settings):
        from explorer.app.serve.overlays import MANIFOLD_SECONDS, saddle_manifolds, search_budget

        budget = search_budget(MANIFOLD_SECONDS)
        self._manifold_budget = budget
        if generation != self._manifold_generation:
            return                           # a newer pick or a new value came meanwhile
        try:
            with budget:
                branches, text = saddle_manifolds(settings, point, period)
        except Exception as exc:  # noqa: BLE001 - reported in the page
            branches, text = [], f"manifolds: failed ({type(exc).__name__}: {' '.join(str(exc).split())})"
        self._post(partial(self._show_manifolds, generation, settings, branches, text))

    def _show_manifolds(self, generation, settings, branches, text):
        if generation != self._manifold_generation or settings is not self.settings:
            return                           # a newer pick, a new value or the overlay changed meanwhile
        pts = [np.asarray(b.points, float) for b in branches]
        self.manifold_source.data = {"xs": [p[:, 0] for p in pts], "ys": [p[:, 1] for p in pts],
                                     "color": [MANIFOLD_COLORS[b.kind] for b in branches],
                                     "kind": [b.kind for b in branches]}
        self.overlay_text.text = text
