"""The chaos layer's rasters of the visible window, coarse first, NaN outside the allowed region
(docs/commands/serve.md, "Chaos layer"; the adaptive raster: docs/chaos_map.md)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from time import monotonic

import numpy as np

from explorer.analysis.chaos_map import TOLERANCE, CellRaster, refinement
from explorer.analysis.classification import default_threshold
from explorer.analysis.rotation import frequency_diffusion
from explorer.app.serve.overlays import elliptic_center, rotation_map
from explorer.app.serve.settings import Settings, Window
from explorer.model import ParameterError, validation

#: the default resolutions of one window's rasters (each refines the last), and the finest --megno-resolution accepts
RESOLUTIONS = (16, 32, 64, 128)
MAX_RESOLUTION = 512
#: integration time of a cell's MEGNO by default, and the longest --megno-time accepts
RASTER_TIME = 200.0
MAX_RASTER_TIME = 100_000.0
#: steps per cell at most (a batch must stay stoppable at extreme parameters); a cell past it is NaN
RASTER_MAX_STEPS = 100_000
#: seeds per call of MEGNO and of frequency_diffusion (bounds the time until a cancel takes effect)
BATCH = 512
DIFFUSION_BATCH = 32
#: the indicators the layer can show (names of the registry, explorer.kernels.indicator_table)
INDICATORS = ("megno", "frequency_diffusion")
#: a raster's partial image after each batch, or after fewer cells (an adaptive raster's small steps) this long (s)
IMAGE_SECONDS = 0.25
#: N of the layer's frequency diffusion: nu1 from the first N returns, nu2 from the next N
DIFFUSION_ITERATES = 100


@dataclass(frozen=True)
class Image:
    """One (partial) raster: ``values`` (n, n), NaN outside the region; a cell not yet known shows the coarser
    raster's value (none: NaN)."""

    window: Window
    n: int
    values: np.ndarray
    complete: bool
    computed: np.ndarray        # the cells integrated (an adaptive raster fills the others)


def resolutions_up_to(n: int) -> tuple:
    """The resolutions 16, 32, ... up to ``n`` (a power of 2 in [16, MAX_RESOLUTION]: ParameterError)."""
    if not isinstance(n, int) or n < 16 or n > MAX_RESOLUTION or n & (n - 1):
        raise ParameterError(f"--megno-resolution must be a power of 2 in [16, {MAX_RESOLUTION}], got {n!r}")
    return tuple(16 << k for k in range(n.bit_length() - 4))


def diffusion_center(settings: Settings) -> tuple:
    """(point, elliptic): frequency diffusion's centre, the elliptic fixed point from the region's centre,
    else that centre (docs/greene.md, "Frequency diffusion")."""
    c1, c2 = settings.region[:2]
    fp = elliptic_center(settings, (c1, c2))
    point = (c1, c2) if fp is None else fp.point
    return (float(point[0]), float(point[1])), fp is not None


def diffusion_cells(settings: Settings, p1, p2, center, iterates: int = DIFFUSION_ITERATES) -> np.ndarray:
    """log10 |nu1 - nu2| of the orbits from (p1, p2) around ``center`` (ParameterError in direction -1)."""
    if settings.direction == -1:
        raise ParameterError("frequency diffusion needs crossings in direction + or both (the section map's "
                             "returns); these settings count them in direction -")
    return frequency_diffusion(rotation_map(settings), np.column_stack([np.ravel(p1), np.ravel(p2)]), center=center,
                               iterates=iterates)


def rasters(settings: Settings, window: Window, resolutions: tuple = RESOLUTIONS, time: float = RASTER_TIME,
            indicator: str = "megno", center=None, iterates: int = DIFFUSION_ITERATES, adaptive: bool = False):
    """Yield the :class:`Image` of ``indicator`` after every batch of every resolution (``center`` None:
    :func:`diffusion_center`); ``adaptive`` (MEGNO): the first resolution, then the last computing the cells
    ``refinement`` asks for, each the exact raster's bit for bit, the others filled (docs/chaos_map.md)."""
    validation.choice("indicator", indicator, INDICATORS)
    if indicator == "megno":
        batch, cells = BATCH, partial(settings.megno, time=time, max_steps=RASTER_MAX_STEPS)
    else:
        point = diffusion_center(settings)[0] if center is None else center
        batch, cells = DIFFUSION_BATCH, partial(diffusion_cells, settings, center=point, iterates=iterates)
    adaptive = adaptive and indicator == "megno"
    if adaptive:
        resolutions = resolutions[:1] + resolutions[1:][-1:]        # the first and the last (if another)
    previous = np.full((1, 1), np.nan)          # the coarser raster (before the first: nothing known)
    for i, n in enumerate(resolutions):
        P1, P2 = window.centres(n)
        inside = np.asarray(settings.smap.allowed(np.stack([P1, P2], axis=-1)), bool)
        k = n // previous.shape[0]
        shown = np.where(inside, np.kron(previous, np.ones((k, k))), np.nan)
        raster = CellRaster(None, None, inside, indicator, default_threshold(indicator, time), {})
        steps = iter([np.nonzero(inside)])              # every cell, or those refinement asks for
        if adaptive and i:
            steps = refinement(raster, inside, n, previous.shape[0], TOLERANCE, n * n)
        last, pending = monotonic(), 0
        for r, c in steps:
            for a in range(0, len(r), batch):
                # an image of the cells known before the next batch (the rule's small steps: fewer images)
                if pending >= batch or (pending and monotonic() - last >= IMAGE_SECONDS):
                    known = raster.computed | np.isfinite(raster.values)
                    yield Image(window, n, np.where(known, raster.values, shown), False, raster.computed & inside)
                    last, pending = monotonic(), 0
                rr, cc = r[a:a + batch], c[a:a + batch]
                v = np.asarray(cells(P1[rr, cc], P2[rr, cc]), float)
                raster.record(rr, cc, v)
                pending += len(rr)
        previous = np.where(inside, raster.values, np.nan)
        yield Image(window, n, previous, True, raster.computed & inside)
