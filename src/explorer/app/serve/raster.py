"""The chaos layer's rasters of the visible window, coarse first, NaN outside the allowed region
(docs/commands/serve.md, "Chaos layer"; the adaptive raster: docs/chaos_map.md)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from time import monotonic

import numpy as np

from explorer.analysis.chaos_map import RULES, TOLERANCE, CellRaster, default_threshold, refinement
from explorer.analysis.rotation import frequency_diffusion
from explorer.app.serve.overlays import elliptic_center, rotation_tol
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
#: an adaptive raster's partial image at most this often (s), unless BATCH cells were computed since the last
IMAGE_SECONDS = 0.25
#: N of the layer's frequency diffusion: nu1 from the first N returns, nu2 from the next N
DIFFUSION_ITERATES = 100


@dataclass(frozen=True)
class Image:
    """One (partial) raster: ``values`` (n, n), NaN outside the region or not yet computed."""

    window: Window
    n: int
    values: np.ndarray
    complete: bool
    indicator: str = "megno"
    computed: np.ndarray | None = None      # cells integrated (adaptive rasters; None: every allowed cell)


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
    return frequency_diffusion(settings.section_map(rotation_tol(settings)), np.column_stack([np.ravel(p1),
                               np.ravel(p2)]), center=center, iterates=iterates)


def _shown(coarser, inside) -> np.ndarray:
    """What a raster shows of the cells ``inside`` until each is computed: ``coarser``'s value (None: NaN)."""
    if coarser is None:
        return np.full(inside.shape, np.nan)
    k = inside.shape[0] // coarser.shape[0]
    return np.where(inside, np.kron(coarser, np.ones((k, k))), np.nan)


def rasters(settings: Settings, window: Window, resolutions: tuple = RESOLUTIONS, time: float = RASTER_TIME,
            indicator: str = "megno", center=None, iterates: int = DIFFUSION_ITERATES, adaptive: bool = False):
    """Yield the :class:`Image` of ``indicator`` after every batch of every resolution (``center`` None:
    :func:`diffusion_center`); ``adaptive`` (MEGNO): the first resolution, then the last by :func:`adaptive_raster`."""
    validation.choice("indicator", indicator, INDICATORS)
    if indicator == "megno":
        batch, cells = BATCH, partial(settings.megno, time=time, max_steps=RASTER_MAX_STEPS)
    else:
        point = diffusion_center(settings)[0] if center is None else center
        batch, cells = DIFFUSION_BATCH, partial(diffusion_cells, settings, center=point, iterates=iterates)
    previous = None
    for n in resolutions:
        if adaptive and indicator == "megno" and previous is not None:
            yield from adaptive_raster(settings, window, resolutions[-1], time, previous)
            return
        P1, P2 = window.centres(n)
        inside = settings.allowed(P1, P2)
        values = _shown(previous, inside)
        rows, cols = np.nonzero(inside)
        for a in range(0, len(rows), batch):
            r, c = rows[a:a + batch], cols[a:a + batch]
            values[r, c] = cells(P1[r, c], P2[r, c])
            yield Image(window, n, values.copy(), a + batch >= len(rows), indicator)
        if not len(rows):
            yield Image(window, n, values.copy(), True, indicator)
        previous = values


def adaptive_raster(settings: Settings, window: Window, n: int, time: float = RASTER_TIME, coarser=None):
    """Yield MEGNO's n x n :class:`Image` after every batch, computing the cells ``refinement`` asks for, each the
    exact raster's bit for bit, the others filled (docs/chaos_map.md); a cell not yet known shows ``coarser``'s."""
    P1, P2 = window.centres(n)
    inside = np.asarray(settings.allowed(P1, P2), bool)
    shown = _shown(coarser, inside)
    raster = CellRaster(None, None, inside, "megno", RULES["megno"], default_threshold("megno", time), {})
    coarse = n // 8 if coarser is None else coarser.shape[0]
    last, pending = monotonic(), 0
    for r, c in refinement(raster, inside, n, coarse, TOLERANCE, n * n):
        for a in range(0, len(r), BATCH):
            rr, cc = r[a:a + BATCH], c[a:a + BATCH]
            v = np.asarray(settings.megno(P1[rr, cc], P2[rr, cc], time, RASTER_MAX_STEPS), float)
            raster.record(rr, cc, v, np.zeros(len(v), bool), np.isfinite(v))
            pending += len(rr)
            if pending >= BATCH or monotonic() - last >= IMAGE_SECONDS:    # (the rule's small steps: fewer images)
                known = raster.computed | np.isfinite(raster.values)
                yield Image(window, n, np.where(known, raster.values, shown), False, "megno",
                            raster.computed & inside)
                last, pending = monotonic(), 0
    values = np.where(inside, raster.values, np.nan)
    yield Image(window, n, values, True, "megno", raster.computed & inside)
