"""Many crossings as one packed RGBA image (docs/architecture.md, "Many crossings in the browser")."""
from __future__ import annotations

import numpy as np

from explorer.app.serve.style import UNKNOWN_MEGNO_COLOR

#: crossings on a page above which the density image replaces the glyphs
THRESHOLD = 200_000
#: at most this many crossings are drawn as glyphs (the newest orbits, whole; docs/commands/serve.md, "Latency")
GLYPH_BUDGET = 10_000
#: one cell of the image per this many screen pixels (each way)
CELL_PX = 2
#: opacity of a cell with one crossing; the densest cell of the window is opaque
MIN_ALPHA = 0.45


def glyph_cutoff(counts: dict, budget: int = GLYPH_BUDGET) -> int:
    """The first orbit id drawn as glyphs, given {orbit id: crossings} in ascending ids: the newest whole orbits
    within ``budget`` crossings (0: every one fits)."""
    ids, n = list(counts), np.fromiter(counts.values(), np.int64, len(counts))
    if n.sum() <= budget:
        return 0
    fits = np.flatnonzero(np.cumsum(n[::-1])[::-1] <= budget)     # the orbits from each on fit
    return ids[fits[0]] if fits.size else ids[-1] + 1


def density_rgba(p1, p2, colour_index, window, nx: int, ny: int, colors, megno=None, palette=None,
                 lo: float = 0.0, hi: float = 8.0) -> np.ndarray:
    """The (ny, nx) uint32 RGBA image of (p1, p2) in ``window``: each cell in its most frequent orbit colour,
    or the ``palette`` colour of its mean ``megno`` in [lo, hi]; opacity growing with log(count)."""
    ncell = nx * ny
    x0, x1, y0, y1 = window
    ix = np.floor((np.asarray(p1, float) - x0) * (nx / (x1 - x0)))
    iy = np.floor((np.asarray(p2, float) - y0) * (ny / (y1 - y0)))
    inside = (ix >= 0) & (ix < nx) & (iy >= 0) & (iy < ny)
    cell = (iy[inside] * nx + ix[inside]).astype(np.int64)
    count = np.bincount(cell, minlength=ncell)
    if megno is None or palette is None:
        table = colors
        k = np.asarray(colour_index, np.int64)[inside] % len(colors)
        per = np.bincount(cell * len(colors) + k, minlength=ncell * len(colors)).reshape(ncell, len(colors))
        idx = np.argmax(per, axis=1)
    else:
        table = [*palette, UNKNOWN_MEGNO_COLOR]           # the last: grey, a cell without a known MEGNO
        m = np.asarray(megno, float)[inside]
        known = np.isfinite(m)
        n_known = np.bincount(cell[known], minlength=ncell)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = np.bincount(cell[known], weights=m[known], minlength=ncell) / n_known
        u = np.clip((mean - lo) / (hi - lo), 0.0, 1.0)
        idx = np.where(n_known > 0, np.round(np.nan_to_num(u) * (len(palette) - 1)), len(palette)).astype(np.int64)
    top = max(int(count.max()) if count.size else 0, 1)
    alpha = np.where(count > 0, 255 * (MIN_ALPHA + (1 - MIN_ALPHA) * np.log1p(count) / np.log1p(top)), 0)
    rgba = np.empty((ncell, 4), np.uint8)
    rgba[:, :3] = np.array([list(bytes.fromhex(c.lstrip("#"))) for c in table], np.uint8)[idx]     # ("#rrggbb")
    rgba[:, 3] = alpha.astype(np.uint8)
    return rgba.view(np.uint32).reshape(ny, nx)
