"""Chaos maps that compute only the cells the picture needs (docs/chaos_map.md).

The cells of a resolution^2 raster of a window are seeded at their centres.  The adaptive map
computes a coarse lattice of cells (spacing s), then halves s level by level: a block of the
lattice is uniform when its allowed corners are of one class (chaotic or regular by the
indicator's threshold) and, both regular, within ``tolerance`` in the indicator's compared value
(its logarithm, clipped at the threshold: the chaotic sea's finite-time values are compared by
class alone).  The new lattice cells of a block that is not uniform, or that has no allowed
corner, are computed; the others are filled from their block's corners (bilinear in the drawn
scale) with its class, and marked filled.  Then the boundary grows: a filled cell of the new
lattice within :data:`REACH` lattice steps (and :data:`REACH_CELLS` cells) of a computed cell of
the other class is computed, until none is left.  Each computed cell is the orbit of its own centre
(:func:`explorer.indicators`), so it is the exact map's cell bit for bit whatever the batches
and threads.  What a map must give: ``domain`` (the default window), ``allowed(points)`` (the
cells computed) and its indicators through :func:`explorer.indicators`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer.analysis import budget
from explorer.analysis.classification import FREQUENCY, RULES, default_threshold, orbit_classes
from explorer.kernels import indicator_table as table
from explorer.model import ParameterError, validation

__all__ = ["CellRaster", "ChaosMap", "INDICATORS", "chaos_map", "refinement"]

#: the largest raster side
MAX_RESOLUTION = 4096
#: cells per call of the indicators (a budget or Ctrl-C is checked between calls)
BATCH = 16384
#: the default coarse lattice: about this many cells a side
COARSE = 64
#: default tolerance on the compared value (natural log for a log scale): a factor e^2
TOLERANCE = 2.0
#: class codes of the cells
REGULAR, CHAOTIC, OUTSIDE, FAILED = 0, 1, 2, 3
#: lattice steps (Chebyshev) around a computed cell within which a filled cell of the other class is
#: computed, and at least :data:`REACH_CELLS` cells: farther around a regular cell (a fill misses thin
#: regular structures in a chaotic sea more often than the reverse)
REACH = {REGULAR: 2, CHAOTIC: 1}
REACH_CELLS = 1
#: the version of :func:`refinement`'s rule: raise it when a change of the rule changes which cells it
#: computes (a scene's adaptive map is hashed with it: explorer.analysis.sweep.map_rule)
RULE_VERSION = 3
#: the indicators a chaos map draws
INDICATORS = tuple(n for n in table.TANGENT_NAMES if n in RULES) + (FREQUENCY,)


@dataclass(frozen=True)
class ChaosMap:
    """A chaos map on a (resolution, resolution) raster, row = second coordinate, column = first
    (docs/chaos_map.md): ``values`` of ``indicator`` (NaN outside the allowed region),
    ``chaotic``, ``computed`` (False where filled or outside), ``allowed``; ``window`` (a_lo,
    a_hi, b_lo, b_hi)."""

    values: np.ndarray
    chaotic: np.ndarray
    computed: np.ndarray
    allowed: np.ndarray
    window: tuple
    indicator: str
    threshold: float
    tmax: float
    exact: bool

    @property
    def resolution(self) -> int:
        return int(self.values.shape[0])

    @property
    def grid(self) -> tuple:
        """(resolution, a_lo, a_hi, b_lo, b_hi): the raster's geometry (analysis.sweep.map_raster)."""
        return (self.resolution, *self.window)

    @property
    def chaotic_fraction(self) -> float:
        """Chaotic cells over allowed cells (NaN when none is allowed)."""
        n = int(self.allowed.sum())
        return float(self.chaotic.sum()) / n if n else float("nan")

    @property
    def computed_fraction(self) -> float:
        """Computed cells over allowed cells."""
        n = int(self.allowed.sum())
        return float(self.computed.sum()) / n if n else float("nan")

    def centres(self) -> np.ndarray:
        """The cell centres (resolution, resolution, 2)."""
        return cell_centres(self.window, self.resolution)


def cell_centres(window, n: int) -> np.ndarray:
    """(n, n, 2) centres of the cells of ``window``: [r, c] = (a of column c, b of row r)."""
    a0, a1, b0, b1 = window
    u = (np.arange(n) + 0.5) / n
    A, B = np.meshgrid(a0 + (a1 - a0) * u, b0 + (b1 - b0) * u)
    return np.stack([A, B], axis=-1)


def _window(smap, window) -> tuple:
    if window is None:
        (a0, a1), (b0, b1) = smap.domain
        return (float(a0), float(a1), float(b0), float(b1))
    try:
        w = tuple(float(v) for v in window)
    except (TypeError, ValueError):
        w = ()
    if len(w) != 4 or not all(math.isfinite(v) for v in w) or not (w[0] < w[1] and w[2] < w[3]):
        raise ParameterError(f"window must be (a_lo, a_hi, b_lo, b_hi), four finite numbers with a_lo < a_hi and "
                             f"b_lo < b_hi; got {window!r}")
    return w


class CellRaster:
    """The cells' values, classes and compared values, and how a batch of them is computed."""

    def __init__(self, smap, centres, allowed, indicator, threshold, options):
        n = allowed.shape[0]
        self.smap, self.centres, self.indicator, self.threshold = smap, centres, indicator, threshold
        self.rule = RULES[indicator]
        self.options = options
        self.values = np.full((n, n), np.nan)
        self.cls = np.where(allowed, FAILED, OUTSIDE).astype(np.int8)
        self.q = np.full((n, n), np.nan)        # the compared value
        self.computed = np.zeros((n, n), bool)

    def scale(self, v):
        """The drawn scale of values (log for a log indicator)."""
        if not self.rule.log:
            return v
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.log(np.maximum(v, self.rule.floor))

    def compute(self, r, c) -> None:
        from explorer.analysis.lyapunov import indicators
        from explorer.analysis.rotation import frequency_diffusion

        for a in range(0, len(r), BATCH):
            budget.checkpoint()
            rr, cc = r[a:a + BATCH], c[a:a + BATCH]
            if self.indicator == FREQUENCY:
                v = frequency_diffusion(self.smap, self.centres[rr, cc], **self.options)
                self.record(rr, cc, v)
                continue
            ind = indicators(self.smap, self.centres[rr, cc], which=(self.indicator,), **self.options)
            self.record(rr, cc, ind.values[self.indicator], ind.early, np.asarray(ind.status) == 0)

    def record(self, r, c, v, early=None, ok=None) -> None:
        """Cells (r, c) computed: values ``v``, stopped ``early`` (chaotic), integrated to the end (``ok``;
        None: none stopped early, all integrated to the end: classification.orbit_classes)."""
        v = np.asarray(v, float)
        chaotic, ok = orbit_classes(v, self.indicator, self.threshold, early, ok)
        self.values[r, c] = v
        self.computed[r, c] = True
        self.cls[r, c] = np.where(ok, np.where(chaotic, CHAOTIC, REGULAR), FAILED)
        self.q[r, c] = self._compared(v, chaotic)

    def _compared(self, v, chaotic):
        t = self.threshold
        lo, hi = (self.rule.floor, t) if self.rule.above else (t, np.inf)
        with np.errstate(invalid="ignore"):
            q = self.scale(np.clip(v, lo, hi)) if self.rule.log else np.clip(v, -np.inf if self.rule.above else t,
                                                                               hi)
        return np.where(chaotic, self.scale(np.float64(t)), q)

    def fill(self, r, c, r0, r1, c0, c1) -> None:
        """Cells (r, c) from the allowed corners of their blocks [r0, r1] x [c0, c1] (bilinear in
        the drawn scale, weights renormalised), with the class of the nearest allowed corner."""
        fr = (r - r0) / (r1 - r0)
        fc = (c - c0) / (c1 - c0)
        corners = ((r0, c0, (1 - fr) * (1 - fc)), (r0, c1, (1 - fr) * fc), (r1, c0, fr * (1 - fc)), (r1, c1, fr * fc))
        z = np.zeros(len(r))
        q = np.zeros(len(r))
        total = np.zeros(len(r))
        best = np.full(len(r), -1.0)
        cls = np.full(len(r), OUTSIDE, np.int8)
        for a, b, w in corners:
            ok = self.cls[a, b] <= CHAOTIC
            w = np.where(ok, w + 1e-9, 0.0)     # an allowed corner at weight 0 still counts
            z += w * np.where(ok, self.scale(self.values[a, b]), 0.0)
            q += w * np.where(ok, self.q[a, b], 0.0)
            total += w
            near = ok & (w > best)
            cls = np.where(near, self.cls[a, b], cls)
            best = np.where(near, w, best)
        with np.errstate(invalid="ignore", divide="ignore"):
            z /= total
            q /= total
        self.values[r, c] = np.exp(z) if self.rule.log else z
        self.q[r, c] = q
        self.cls[r, c] = np.where(cls == OUTSIDE, FAILED, cls)


def _lattice(n: int, s: int) -> np.ndarray:
    """Lattice rows (columns) of spacing s: 0, s, 2s, ... and the last, n - 1."""
    return np.unique(np.r_[np.arange(0, n, s), n - 1])


def _growth(raster: CellRaster, allowed: np.ndarray, idx: np.ndarray, t: int):
    """Yield (rows, cols) of the filled allowed cells of the lattice ``idx`` (spacing t) within
    :data:`REACH` of a computed cell of another class, until none is left; the caller computes
    each batch."""
    ix = np.ix_(idx, idx)
    ok = allowed[ix]
    m = len(idx)
    fi, fj = np.nonzero(raster.computed[ix])     # the frontier: every computed cell, then the new ones
    while len(fi):
        cls = raster.cls[ix]
        kind = cls[fi, fj]
        want = np.zeros((m, m), bool)
        for k, steps in REACH.items():
            reach = max(steps, -(-REACH_CELLS // t))
            a, b = fi[kind == k], fj[kind == k]
            for di in range(-reach, reach + 1):
                for dj in range(-reach, reach + 1):
                    i, j = a + di, b + dj
                    inside = (i >= 0) & (i < m) & (j >= 0) & (j < m)
                    i, j = i[inside], j[inside]
                    other = cls[i, j] != k
                    want[i[other], j[other]] = True
        want &= ok & ~raster.computed[ix]
        fi, fj = np.nonzero(want)
        if len(fi):
            yield idx[fi], idx[fj]


def _agree(raster: CellRaster, idx: np.ndarray, tolerance: float) -> tuple:
    """(disagree, empty) of the blocks (len(idx) - 1)^2 of the lattice ``idx``: the allowed corners
    of a block disagree (the module's rule); no corner of a block is allowed."""
    cls = raster.cls[np.ix_(idx, idx)]
    q = raster.q[np.ix_(idx, idx)]
    cs = (cls[:-1, :-1], cls[1:, :-1], cls[:-1, 1:], cls[1:, 1:])
    qs = (q[:-1, :-1], q[1:, :-1], q[:-1, 1:], q[1:, 1:])
    inside = [c != OUTSIDE for c in cs]
    lo = np.minimum.reduce([np.where(a, c, FAILED) for a, c in zip(inside, cs)])
    hi = np.maximum.reduce([np.where(a, c, REGULAR) for a, c in zip(inside, cs)])
    empty = ~np.logical_or.reduce(inside)
    with np.errstate(invalid="ignore"):
        spread = np.fmax.reduce(qs) - np.fmin.reduce(qs)
    same = (lo == hi) & (hi <= CHAOTIC) & ((hi == CHAOTIC) | (spread <= tolerance))
    return ~empty & ~same, empty


def chaos_map(smap, resolution: int = 512, indicator: str = "megno", tmax: float = 1000.0, exact: bool = False,
              window=None, *, threshold: float | None = None, tolerance: float = TOLERANCE, coarse: int = COARSE,
              max_cells: int | None = None, threads: int | None = None, early_stop: bool = False,
              early_megno: float | None = None, center=None) -> ChaosMap:
    """The map of ``indicator`` (of :data:`INDICATORS`) over ``tmax`` on a ``resolution``^2 raster of
    ``window`` (default: the map's ``domain``, the box of its allowed region): adaptive (the
    module's rule, from a lattice of about ``coarse`` cells a side) unless ``exact``.  Cells
    outside the allowed region are NaN, neither computed nor chaotic.  ``threshold`` (default
    :func:`default_threshold`) classifies; ``max_cells`` bounds the computed cells (refinement
    stops there and the rest is filled); ``threads``, ``early_stop``, ``early_megno`` (default
    :func:`explorer.indicators`'): :func:`explorer.indicators`;
    frequency diffusion: N = ``tmax`` returns per half around ``center``
    (:func:`explorer.frequency_diffusion`; docs/chaos_map.md)."""
    n = validation.integer("resolution", resolution, 2, MAX_RESOLUTION)
    indicator = validation.choice("indicator", indicator, INDICATORS)
    T = validation.real("tmax", tmax, 0.0, lo_open=True)
    exact = validation.boolean("exact", exact)
    thr = default_threshold(indicator, T) if threshold is None else validation.real("threshold", threshold)
    tolerance = validation.real("tolerance", tolerance, 0.0)
    coarse = validation.integer("coarse", coarse, 2)
    cap = n * n if max_cells is None else validation.integer("max_cells", max_cells, 1)
    w = _window(smap, window)
    centres = cell_centres(w, n)
    allowed = np.asarray(smap.allowed(centres), bool)
    if indicator == FREQUENCY:
        if early_stop or early_megno is not None:
            raise ParameterError("early_stop and early_megno belong to the tangent indicators (MEGNO, SALI); "
                                 "frequency_diffusion has no early stop")
        options = {"center": center, "iterates": validation.integer("tmax", int(T) if T.is_integer() else T, 10),
                   "threads": threads}
    elif center is not None:
        raise ParameterError(f"center belongs to the indicator frequency_diffusion, not {indicator!r}")
    else:
        options = {"tmax": T, "threads": threads, "early_stop": bool(early_stop)}
        if early_megno is not None:
            options["early_megno"] = validation.real("early_megno", early_megno, 2.0, lo_open=True)
    raster = CellRaster(smap, centres, allowed, indicator, thr, options)
    if exact:
        r, c = np.nonzero(allowed)
        raster.compute(r, c)
    else:
        _refine(raster, allowed, n, coarse, tolerance, cap)
    chaotic = allowed & (raster.cls == CHAOTIC)
    return ChaosMap(np.where(allowed, raster.values, np.nan), chaotic, raster.computed & allowed, allowed, w,
                    indicator, float(thr), T, exact)


def _refine(raster: CellRaster, allowed: np.ndarray, n: int, coarse: int, tolerance: float, cap: int) -> None:
    for r, c in refinement(raster, allowed, n, coarse, tolerance, cap):
        raster.compute(r, c)


def refinement(raster: CellRaster, allowed: np.ndarray, n: int, coarse: int, tolerance: float, cap: int):
    """Yield (rows, cols) of the cells to compute, the coarse lattice first, then level by level (the
    module's rule); the caller computes them into ``raster`` before the next, the rest is filled."""
    s = 2 ** max(0, int(math.floor(math.log2(n / coarse)))) if n > coarse else 1
    idx = _lattice(n, s)
    R, C = np.meshgrid(idx, idx, indexing="ij")
    first = allowed[R, C]
    yield R[first], C[first]
    left = cap - int(first.sum())
    while s > 1:
        t = s // 2
        disagree, empty = _agree(raster, idx, tolerance)
        refine = disagree | empty
        new = _lattice(n, t)
        R, C = np.meshgrid(new, new, indexing="ij")
        fresh = ~(np.isin(R, idx) & np.isin(C, idx)) & allowed[R, C]
        r, c = R[fresh], C[fresh]
        bi = np.clip(np.searchsorted(idx, r, side="right") - 1, 0, len(idx) - 2)
        bj = np.clip(np.searchsorted(idx, c, side="right") - 1, 0, len(idx) - 2)
        need = refine[bi, bj]
        if int(need.sum()) > left:          # the budget: no more refinement, the rest is filled
            need[:] = False
            left = 0
        yield r[need], c[need]
        left -= int(need.sum())
        fill = ~need
        raster.fill(r[fill], c[fill], idx[bi[fill]], idx[bi[fill] + 1], idx[bj[fill]], idx[bj[fill] + 1])
        for gr, gc in _growth(raster, allowed, new, t) if left else ():
            if len(gr) > left:
                left = 0
                break
            yield gr, gc
            left -= len(gr)
        idx, s = new, t
