"""The chaos layer of the page: a MEGNO raster of the visible window, coarse first, then refined.

For each resolution of ``RESOLUTIONS`` (n x n cells over the window), the centres of the cells
inside the allowed region are started on the section (docs/model.md R9, M > 0) and their mean MEGNO
<Y>(``RASTER_TIME``) is computed with :func:`explorer.analysis.lyapunov.indicators` (the tangent
lanes, the page's method and tolerance), ``BATCH`` seeds per call; cells outside the region are
NaN.  After each batch the partial image is handed out (``on_image(generation, image)``), so the
page fills in while the next batch runs; its ``stop()`` ends the raster at the next batch (the page's
ChaosLayer runs it as a job of the session's task helper: a new window or new settings supersede
it).  No web library here.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.app.serve.settings import Settings

#: resolutions of the successive rasters of one window (each a refinement of the last), by default
RESOLUTIONS = (16, 32, 64, 128)
#: the finest resolution the command accepts (--megno-resolution: a power of 2 in [16, MAX_RESOLUTION])
MAX_RESOLUTION = 512
#: integration time of the MEGNO of a cell (quasi-periodic: <Y> -> 2, chaotic: grows ~ chi t / 2), by
#: default, and the longest the command accepts (--megno-time)
RASTER_TIME = 200.0
MAX_RASTER_TIME = 100_000.0
#: steps per cell at most (a few thousand at Figure 4's parameters and RASTER_TIME; at extreme
#: parameters the time scale shrinks and a batch no one can stop would run for hours); a cell past
#: it is unknown (NaN, transparent)
RASTER_MAX_STEPS = 100_000
#: seeds per call of the indicators (bounds the time until a cancel takes effect)
BATCH = 512


@dataclass(frozen=True)
class Window:
    """The visible part of the section: p1 in [x0, x1], p2 in [y0, y1]."""

    x0: float
    x1: float
    y0: float
    y1: float

    def __post_init__(self):
        if not all(np.isfinite([self.x0, self.x1, self.y0, self.y1])) or not (self.x1 > self.x0 and self.y1 > self.y0):
            raise ValueError(f"not a window: {self}")

    def centres(self, n: int):
        """Cell centres of an n x n raster, (n, n) arrays P1, P2 (row = p2 index)."""
        u = (np.arange(n) + 0.5) / n
        return np.meshgrid(self.x0 + (self.x1 - self.x0) * u, self.y0 + (self.y1 - self.y0) * u)


@dataclass(frozen=True)
class Image:
    """One (partial) raster: ``values`` (n, n) mean MEGNO, NaN outside the region or not yet
    computed; ``complete`` when every cell of this resolution is in."""

    window: Window
    n: int
    values: np.ndarray
    complete: bool


def resolutions_up_to(n: int) -> tuple:
    """The resolutions 16, 32, ... up to ``n`` (a power of 2 in [16, MAX_RESOLUTION]: ParameterError)."""
    from explorer.model import ParameterError

    if not isinstance(n, int) or n < 16 or n > MAX_RESOLUTION or n & (n - 1):
        raise ParameterError(f"--megno-resolution must be a power of 2 in [16, {MAX_RESOLUTION}], got {n!r}")
    return tuple(16 << k for k in range(n.bit_length() - 4))


def megno_cells(settings: Settings, p1, p2, time: float = RASTER_TIME) -> np.ndarray:
    """Mean MEGNO <Y>(``time``) of the orbits started at (p1, p2) on the section."""
    from explorer.analysis import lyapunov

    y0 = model.section_state(settings.params, p1, p2, settings.h, settings.phi0, settings.direction or 1)
    res = lyapunov.indicators(settings.params, y0, tmax=time, method=settings.method, tol=settings.tol,
                              dt=settings.dt, which=("megno",), max_steps=RASTER_MAX_STEPS)
    return np.where(np.asarray(res.status) == 0, np.asarray(res.megno, dtype=np.float64), np.nan)


def rasters(settings: Settings, window: Window, stop: Callable[[], bool] = lambda: False,
            resolutions: tuple = RESOLUTIONS, time: float = RASTER_TIME):
    """Yield the :class:`Image` after every batch of every resolution (until ``stop()``)."""
    previous = None
    for n in resolutions:
        P1, P2 = window.centres(n)
        inside = model.section_M2(settings.params, P1, P2, settings.h, settings.phi0) > 0.0
        values = np.full((n, n), np.nan)
        if previous is not None:     # until a cell is computed, it shows the coarser raster's value
            k = n // previous.shape[0]
            values = np.where(inside, np.kron(previous, np.ones((k, k))), np.nan)
        rows, cols = np.nonzero(inside)
        for a in range(0, len(rows), BATCH):
            if stop():
                return
            r, c = rows[a:a + BATCH], cols[a:a + BATCH]
            values[r, c] = megno_cells(settings, P1[r, c], P2[r, c], time)
            yield Image(window, n, values.copy(), a + BATCH >= len(rows))
        if not len(rows):
            yield Image(window, n, values.copy(), True)
        previous = values
