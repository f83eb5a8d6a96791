"""A sweep over the panels of a scene as a pure map (docs/architecture.md, Parallelism and
Streaming): ``task(spec, i)`` integrates chunk i of a picklable :class:`SweepSpec` with no side
effects, so results do not depend on jobs, backend or chunking; ``run`` maps it with joblib or in
this process and hands finished panels, in order, to the parent's callback.  Panels above
:data:`STREAM_BYTES` are computed in resumable blocks (``task_block``).
"""
from __future__ import annotations

import contextvars
import math
import os
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from explorer import model
from explorer._jit import max_threads
from explorer.analysis import sections
from explorer.analysis.classification import FREQUENCY, default_threshold, fraction, orbit_classes
from explorer.kernels import indicator_table
from explorer.model import ParameterError

#: orbits per chunk when joblib processes share the work
CHUNK_ORBITS_JOBS = 32
#: chunks per panel when this process runs everything with Numba threads (progress granularity)
CHUNKS_PER_PANEL_THREADS = 4
#: ... but at most this many orbits per chunk (threads over orbits): one kernel call is then one
#: chunk of at most this many orbits x one block of a streamed panel (at most 256 crossings when
#: the panel has more than about 800 orbits), about a second on 2 cores, and a sweep checks for
#: Ctrl-C between calls (:func:`run`'s ``check``); the numbers do not depend on the chunking
CHUNK_ORBITS_THREADS = 512
#: a panel whose crossing rows (40 bytes each) exceed this is streamed to the store in blocks
#: (8 MiB: the default Figure-4 panels, 200 orbits x 1000 crossings, are not; the environment
#: variable EXPLORER_STREAM_BYTES overrides it, e.g. to stream small runs)
STREAM_BYTES = int(os.environ.get("EXPLORER_STREAM_BYTES", 8 * 2**20))
#: the smallest block (crossings per orbit and round) of a streamed panel
MIN_BLOCK = 256
#: per-orbit arrays of the chaos indicators that ``task`` returns: one per indicator of the registry
#: (explorer.kernels.indicator_table), its status, its early-classification code and ``lyapunov_dh``
#: (|H - H0| at the end of each orbit's indicator integration, measured, not stored)
INDICATOR_ARRAYS = indicator_table.NAMES + ("lyapunov_status", "lyapunov_early", "lyapunov_dh", "map_computed",
                                            "map_chaotic")
#: the coarse lattice of an adaptive map panel: about this many cells a side (explorer.chaos_map)
MAP_COARSE = 64
#: ``run``'s ``check`` while it runs in this process: an adaptive map panel (one task) calls it
#: before each batch of cells, so Ctrl-C stops it between batches (the panel is then not stored)
_CHECK: contextvars.ContextVar = contextvars.ContextVar("sweep_check", default=None)


@dataclass(frozen=True)
class PanelSpec:
    """A panel (or atlas cell) of a sweep: Chaplygin's parameters ``P`` (None for a System) or its
    ``system`` (None for Chaplygin's model), energy ``h``, seeds (N, 2) of the section and their
    states ``y0``; ``grid`` the raster of a chaos map, ``dropped`` the [seeds] left out."""

    index: int
    label: str
    P: np.ndarray | None
    h: float
    y0: np.ndarray
    seeds: np.ndarray
    grid: tuple = ()
    dropped: int = 0
    system: Any = None


@dataclass(frozen=True)
class SweepSpec:
    panels: tuple
    method: str
    tol: float
    dt: float
    crossings: int
    tmax: float | None
    max_steps: int
    phi0: float
    direction: int
    chunks: tuple = field(default=())
    lyapunov: Any = None
    sections: bool = True
    blocks: tuple = ()

    def streamed(self, pos: int) -> bool:
        """Panel ``pos`` is computed in rounds of blocks and streamed to the store."""
        return bool(self.sections and self.blocks and self.blocks[pos] < self.crossings)

    def chunk_crossings(self, panel, a: int, b: int, threads: int | None = None) -> dict:
        """The crossings of the seeds a:b of ``panel`` as :func:`task` returns them."""
        res = sections.crossings(panel.P, states=panel.y0[a:b], n_crossings=self.crossings, method=self.method,
                                 tol=self.tol, dt=self.dt, tmax=self.tmax, max_steps=self.max_steps, phi0=self.phi0,
                                 direction=self.direction, threads=threads)
        return {"data": res.data, "count": res.count, "status": res.status, "final": res.final, "info": res.info,
                "settings": res.settings}

    def initial_state(self, panel):
        """The StreamState of a streamed ``panel`` before its first block."""
        return sections.StreamState.initial(panel.P, panel.y0, phi0=self.phi0)

    def task_block(self, i: int, state, threads: int | None = None) -> dict:
        """Chunk i's next block (:func:`task_block`)."""
        return chaplygin_task_block(self, i, state, threads)

    def indicator_arrays(self, panel, rows, threads=None, diffusion: bool = True) -> tuple:
        """(Indicators, arrays) of the seeds ``rows`` of ``panel`` (:func:`chaplygin_indicator_arrays`)."""
        return chaplygin_indicator_arrays(self, panel, rows, threads, diffusion)

    def section_map(self, panel):
        """The section map of ``panel`` whose returns give frequency diffusion ([lyapunov] tol)."""
        from explorer.analysis.section_map import SectionMap

        return SectionMap(panel.P, panel.h, phi0=self.phi0, tol=self.lyapunov.frequency_diffusion["tol"])


def panel_block(n_orbits: int, crossings: int, budget: int | None = None) -> int:
    """Crossings per orbit and round of a panel of ``n_orbits``: all of them when its rows fit in
    ``budget`` bytes (default :data:`STREAM_BYTES`), else the block that fits (at least MIN_BLOCK)."""
    fit = int(STREAM_BYTES if budget is None else budget) // (sections.ROW_BYTES * max(1, int(n_orbits)))
    return int(crossings) if crossings <= fit else int(max(MIN_BLOCK, fit))


#: the products of a panel a spec can compute (``build_spec``'s ``product``; Scene.product_hashes)
PRODUCTS = ("sections", "indicators")


def build_spec(scene, panel_indices, *, chunk_orbits: int,
               product: str | None = None) -> SweepSpec | SystemSweepSpec:
    """Seeds every panel to compute (inside the allowed region only, R9) and cuts it into chunks; a
    System's scene (one with a ``system``): :func:`build_system_spec`."""
    from explorer.analysis.seeds import seed_points

    if getattr(scene, "system", None) is not None:
        return build_system_spec(scene, panel_indices, chunk_orbits=chunk_orbits, product=product)

    if product is not None and product not in PRODUCTS:
        raise ValueError(f"product must be one of {PRODUCTS} or None, got {product!r}")
    integ = scene.integration
    panels = []
    chunks: list = []
    blocks = []
    ly = scene.lyapunov if "lyapunov" in scene.compute and product != "sections" else None
    with_sections = "sections" in scene.compute and product != "indicators"
    if product is None and with_sections and ly is not None and ly.map_resolution:
        raise ValueError("sections with a map grid are two products: build one spec for each")
    for pos, i in enumerate(panel_indices):
        params, h, label = scene.panel(i)
        grid: tuple = ()
        dropped = 0
        if ly is not None and ly.map_resolution:
            p1, p2, grid = map_seeds(params, h, integ.phi0, ly.map_resolution)
        else:
            p1, p2, dropped = seed_points(scene.seeds, params, h, integ.phi0)
        if len(p1) == 0:
            raise ParameterError(f"scene panel {i} ({label}): no seed lies inside the allowed region")
        y0 = model.section_state(params, p1, p2, h, integ.phi0, integ.direction if integ.direction else 1)
        panels.append(PanelSpec(i, label, params.as_array(), float(h), np.ascontiguousarray(y0),
                                np.column_stack([p1, p2]), grid, dropped))
        n = len(p1)
        blocks.append(panel_block(n, integ.crossings))
        # an adaptive map refines level by level: one chunk (its batches follow chaos_map's levels)
        chunks += [(pos, 0, n)] if grid and ly is not None and ly.adaptive else _chunks(pos, n, chunk_orbits)
    return SweepSpec(tuple(panels), integ.method, integ.tol, integ.dt, integ.crossings, integ.effective_tmax,
                     integ.max_steps, integ.phi0, integ.direction, tuple(chunks), ly,
                     with_sections, tuple(blocks))


def _chunks(pos: int, n: int, chunk_orbits: int, parts: int = CHUNKS_PER_PANEL_THREADS) -> list:
    part = min(math.ceil(n / parts), CHUNK_ORBITS_THREADS)
    step = max(1, chunk_orbits if chunk_orbits > 0 else max(part, max_threads()))
    return [(pos, a, min(n, a + step)) for a in range(0, n, step)]


def build_atlas_spec(scene, *, chunk_orbits: int, cells=None) -> SweepSpec | SystemSweepSpec:
    """The cells of a two-parameter atlas (a scene with [atlas]) as the panels of a sweep of
    indicators only: cell i (row = sweep value, column = atlas value) with its seeds (R9), or
    with [lyapunov] map_resolution the cells of its map (adaptive as a map panel is);
    cells whose allowed region is empty are left out (drawn gray), and so are cells not in
    ``cells`` (None: all; a resumed atlas computes only its missing cells).  ``task(spec, i)``
    maps it unchanged (PanelSpec.index is the cell index).  A System's scene: its own cells
    (:func:`build_system_atlas_spec`)."""
    if getattr(scene, "system", None) is not None:
        return build_system_atlas_spec(scene, chunk_orbits=chunk_orbits, cells=cells)
    from explorer.analysis.seeds import seed_points

    integ = scene.integration
    panels: list[PanelSpec] = []
    chunks: list[tuple[int, int, int]] = []
    for i in range(scene.n_cells):
        if not scene.cell_allowed(i) or (cells is not None and i not in cells):
            continue
        params, h, label = scene.cell(i)
        grid: tuple = ()
        if scene.lyapunov.map_resolution:
            p1, p2, grid = map_seeds(params, h, integ.phi0, scene.lyapunov.map_resolution)
        else:
            p1, p2, _dropped = seed_points(scene.seeds, params, h, integ.phi0)
        if len(p1) == 0:
            continue
        y0 = model.section_state(params, p1, p2, h, integ.phi0, integ.direction if integ.direction else 1)
        chunks += ([(len(panels), 0, len(p1))] if grid and scene.lyapunov.adaptive else
                   _chunks(len(panels), len(p1), chunk_orbits, parts=1))
        panels.append(PanelSpec(i, label, params.as_array(), float(h), np.ascontiguousarray(y0),
                                np.column_stack([p1, p2]), grid))
    return SweepSpec(tuple(panels), integ.method, integ.tol, integ.dt, 1, integ.effective_tmax, integ.max_steps,
                     integ.phi0, integ.direction, tuple(chunks), scene.lyapunov, False, ())


def map_seeds(params, h: float, phi0: float, resolution: int):
    """The seeds of a chaos map: the centres of the cells of a resolution x resolution raster over
    the bounding box of the allowed ellipse of the section (docs/model.md R9) that lie inside the
    allowed region (section_M2 > 0), in raster order (p2 rows ascending, then p1)."""
    ell = model.allowed_ellipse(params, h, phi0)
    if ell is None or not (ell[2] > 0.0 and ell[3] > 0.0):
        raise ParameterError(f"energy h = {h!r}: the allowed region of the section is empty; no chaos map")
    c1, c2, r1, r2 = ell
    n = int(resolution)
    u = (np.arange(n) + 0.5) / n
    P1, P2 = np.meshgrid(c1 - r1 + 2 * r1 * u, c2 - r2 + 2 * r2 * u)
    inside = model.section_M2(params, P1, P2, h, phi0) > 0.0
    return P1[inside], P2[inside], (n, c1 - r1, c1 + r1, c2 - r2, c2 + r2)


def raster_cells(seeds, grid) -> tuple:
    """(rows, columns) of the cells of ``grid`` that hold the points ``seeds`` (N, 2)."""
    n, a1, b1, a2, b2 = grid
    n = int(n)
    c = np.floor((seeds[:, 0] - a1) / (b1 - a1) * n).astype(int).clip(0, n - 1)
    r = np.floor((seeds[:, 1] - a2) / (b2 - a2) * n).astype(int).clip(0, n - 1)
    return r, c


def map_raster(seeds, values, grid):
    """values per seed -> a (resolution, resolution) raster (NaN outside the allowed region),
    row r = p2 index, column c = p1 index (the geometry of :func:`map_seeds`)."""
    n = int(grid[0])
    img = np.full((n, n), np.nan)
    r, c = raster_cells(seeds, grid)
    img[r, c] = values
    return img


def task(spec: SweepSpec | SystemSweepSpec, i: int, threads: int | None = None) -> dict:
    """Pure map: chunk i's crossings (the spec's ``chunk_crossings``; none without [sections]) and, with
    [lyapunov], its orbits' indicators (``indicator_arrays``; a map panel adaptive as :func:`adaptive_map`)."""
    pos, a, b = spec.chunks[i]
    panel = spec.panels[pos]
    t0 = time.perf_counter()
    if spec.sections:
        out = {"chunk": i, **spec.chunk_crossings(panel, a, b, threads)}
    else:
        n = b - a
        out = {"chunk": i, "data": np.zeros((n, 0, 5)), "count": np.zeros(n, np.int64),
               "status": np.zeros(n, np.int64), "final": panel.y0[a:b].copy(), "info": np.zeros((n, 3)),
               "settings": {"sections": False}}
    if spec.lyapunov is not None:
        out.update(adaptive_map(spec, panel, threads) if adaptive_panel(spec, panel)
                   else spec.indicator_arrays(panel, np.arange(a, b), threads)[1])
    out["wall_time"] = time.perf_counter() - t0
    return out


def chaplygin_indicator_arrays(spec: SweepSpec, panel: PanelSpec, rows: np.ndarray, threads=None,
                               diffusion: bool = True) -> tuple:
    """(Indicators, arrays) of the seeds ``rows`` of ``panel``: [lyapunov]'s indicators as ``task``
    returns them (each orbit alone: the same numbers whatever the rows); frequency diffusion only
    with ``diffusion``."""
    from explorer.analysis.lyapunov import indicators

    ly = spec.lyapunov
    which = tuple(q for q in ly.indicators if indicator_table.BY_NAME[q].tangent) or None
    y0 = panel.y0[rows]
    ind = indicators(panel.P, states=y0, tmax=ly.time, method=ly.method, tol=ly.tol, dt=ly.dt,
                     threads=threads, which=which, early_stop=ly.early_stop, early_sali=ly.early_sali,
                     early_megno=ly.early_megno, early_time=ly.early_time)
    with np.errstate(invalid="ignore", over="ignore"):
        dh = np.abs(model.energy(panel.P, ind.final) - model.energy(panel.P, y0))
    out = {i.name: ind.values[i.name] for i in indicator_table.TANGENT if i.vectors == 1 or ly.second_vector}
    out.update(lyapunov_status=ind.status, lyapunov_dh=dh)
    if ly.frequency_diffusion is not None and diffusion:
        out["frequency_diffusion"] = _frequency_diffusion(spec, panel, panel.seeds[rows], threads)
    if ly.early_stop:
        out.update(lyapunov_early=ind.early)
    return ind, out


def _frequency_diffusion(spec, panel, seeds, threads, smap=None):
    from explorer.analysis.rotation import frequency_diffusion

    fd = spec.lyapunov.frequency_diffusion
    smap = spec.section_map(panel) if smap is None else smap
    return frequency_diffusion(smap, seeds, center=fd["center"], iterates=fd["iterates"], threads=threads)


def map_rule() -> dict:
    """The settings of the adaptive map's refinement (:func:`explorer.chaos_map`): part of the
    indicators' hash of an adaptive map panel (docs/scenes.md)."""
    from explorer.analysis.chaos_map import REACH, REACH_CELLS, RULE_VERSION, TOLERANCE

    return {"rule": RULE_VERSION, "coarse": int(MAP_COARSE), "tolerance": float(TOLERANCE),
            "reach": tuple(sorted(REACH.items())), "reach_cells": int(REACH_CELLS)}


def map_time(ly) -> float:
    """The time of a [lyapunov] table's map indicator: ``time``, for frequency diffusion its N."""
    return float(ly.diffusion_iterates if ly.map_indicator == "frequency_diffusion" else ly.time)


def map_threshold(ly) -> float:
    """The class threshold of a [lyapunov] table's map: ``threshold`` for MEGNO, else the map
    indicator's default at its time (explorer.analysis.classification.default_threshold)."""
    ind = ly.map_indicator
    return float(ly.threshold) if ind == "megno" else float(default_threshold(ind, map_time(ly)))


def panel_class(ly, grid: bool) -> tuple:
    """(indicator, threshold) that classify the orbits of a panel of a [lyapunov] table ``ly``: a
    map's (``grid``) its own (:func:`map_threshold`), any other panel's MEGNO at ``threshold``."""
    return (ly.map_indicator, map_threshold(ly)) if grid else ("megno", float(ly.threshold))


def adaptive_panel(spec, panel) -> bool:
    """Panel ``panel`` of ``spec`` is a chaos map computed adaptively ([lyapunov] ``adaptive``)."""
    return bool(panel.grid) and spec.lyapunov is not None and bool(getattr(spec.lyapunov, "adaptive", False))


class _MapCells:
    """The raster of a map panel as a map for :func:`explorer.chaos_map`: ``domain`` its grid,
    ``allowed`` the cells with a seed, ``own_indicators`` (``lifted_increments`` for frequency
    diffusion) the sweep's arrays of the cells asked (each cell its own seed's orbit, as the exact
    path integrates it), kept in ``arrays``."""

    def __init__(self, spec, panel, threads):
        self.spec, self.panel, self.threads = spec, panel, threads
        n, a1, b1, a2, b2 = panel.grid
        self.domain = ((a1, b1), (a2, b2))
        self.row = np.full((int(n), int(n)), -1, np.int64)
        r, c = raster_cells(panel.seeds, panel.grid)
        self.row[r, c] = np.arange(len(panel.seeds))
        self.arrays: dict = {}

    def _rows(self, points):
        p = np.asarray(points, float).reshape(-1, 2)
        r, c = raster_cells(p, self.panel.grid)
        return self.row[r, c].reshape(np.shape(points)[:-1])

    def allowed(self, points):
        return self._rows(points) >= 0

    def _compute(self, points, **kw):
        """The sweep's arrays of the cells of ``points``, kept; returns (rows, Indicators)."""
        check = _CHECK.get()
        if check is not None:
            check()
        rows = self._rows(points).ravel()
        ind, arrays = self.spec.indicator_arrays(self.panel, rows, self.threads, **kw)
        n = len(self.panel.seeds)
        for k, v in arrays.items():
            v = np.asarray(v)
            if k not in self.arrays:
                fill = np.nan if v.dtype.kind == "f" else 0
                self.arrays[k] = np.full(n, fill, dtype=v.dtype)
            self.arrays[k][rows] = v
        return rows, ind

    def own_indicators(self, y0, settings: dict):
        import dataclasses

        ind = self._compute(y0)[1]
        return {f.name: getattr(ind, f.name) for f in dataclasses.fields(ind)}

    def lifted_increments(self, points, center, n, threads):
        """Frequency diffusion's returns (explorer.frequency_diffusion) of the cells' own seeds on the
        panel's section map; the cells' other indicators are kept as :meth:`own_indicators` keeps them."""
        rows = self._compute(points, diffusion=False)[0]
        return self.spec.section_map(self.panel).lifted_increments(self.panel.seeds[rows], center, n, threads)


def adaptive_map(spec: SweepSpec | SystemSweepSpec, panel: PanelSpec, threads=None) -> dict:
    """The indicator arrays of the map panel ``panel`` computed adaptively: :func:`explorer.
    chaos_map` of [lyapunov] map_indicator at its class threshold (:func:`map_threshold`) over
    the panel's grid; a computed cell's arrays are the exact path's bit for
    bit, a filled cell has the map's indicator filled and the others NaN; ``map_computed`` marks
    the computed seeds, ``map_chaotic`` every cell's class (docs/scenes.md)."""
    from explorer.analysis.chaos_map import chaos_map

    ly = spec.lyapunov
    ind = ly.map_indicator
    cells = _MapCells(spec, panel, threads)
    rule = map_rule()
    fd = ind == FREQUENCY
    m = chaos_map(cells, resolution=int(panel.grid[0]), indicator=ind, tmax=map_time(ly), threshold=map_threshold(ly),
                  tolerance=rule["tolerance"], coarse=rule["coarse"], threads=threads,
                  early_stop=ly.early_stop and not fd, center=ly.frequency_diffusion["center"] if fd else None)
    r, c = raster_cells(panel.seeds, panel.grid)
    out = cells.arrays
    computed = m.computed[r, c]
    out[ind] = np.where(computed, out[ind], m.values[r, c]) if ind in out else m.values[r, c]
    out.update(map_computed=computed, map_chaotic=m.chaotic[r, c])
    return out


def classify(arrays, indicator: str, threshold: float) -> tuple:
    """(chaotic, valid) per seed of a panel's indicator ``arrays`` by ``indicator`` at ``threshold``
    (explorer.analysis.classification.orbit_classes; valid: stopped early, or integrated to the end
    with a finite value); a filled cell of an adaptive map has the class it was filled with
    (``map_chaotic``)."""
    if indicator == FREQUENCY:   # frequency diffusion: no early stop, no status
        early = ok = None
    else:
        early, ok = arrays.get("lyapunov_early"), np.asarray(arrays["lyapunov_status"]) == 0
    chaotic, valid = orbit_classes(arrays[indicator], indicator, threshold, early, ok)
    if "map_chaotic" in arrays:
        chaotic = np.where(np.asarray(arrays["map_computed"], bool), chaotic, arrays["map_chaotic"])
    return chaotic & valid, valid


def panel_fraction(arrays, indicator: str, threshold: float) -> tuple:
    """(chaotic fraction, binomial standard error, valid orbits) of a panel (:func:`classify`)."""
    return fraction(*classify(arrays, indicator, threshold))


def _worker_task(spec, i):
    return task(spec, i, threads=1)


def task_block(spec: SweepSpec | SystemSweepSpec, i: int, state, threads: int | None = None) -> dict:
    """Pure map of a streamed panel: the next block of chunk i's orbits, continued from ``state``
    (their :class:`~explorer.analysis.sections.StreamState`; the spec's own ``task_block``)."""
    return spec.task_block(i, state, threads)


def chaplygin_task_block(spec: SweepSpec, i: int, state, threads: int | None = None) -> dict:
    """:func:`task_block` of a sweep of Chaplygin's model."""
    pos, a, b = spec.chunks[i]
    panel = spec.panels[pos]
    it = sections.iter_crossings(panel.P, states=panel.y0[a:b], n_crossings=spec.crossings, block=spec.blocks[pos],
                                 state=state, method=spec.method, tol=spec.tol, dt=spec.dt, tmax=spec.tmax,
                                 max_steps=spec.max_steps, phi0=spec.phi0, direction=spec.direction, threads=threads)
    return _block_arrays(i, a, it, state)


def _block_arrays(i: int, a: int, it, state, columns=slice(None)) -> dict:
    """The arrays of chunk i's next block of the stream ``it`` (its rows' ``columns``: the store's)."""
    t0 = time.perf_counter()
    blk = next(it, None)
    it.close()
    if blk is None:
        return {"chunk": i, "index": np.zeros(0, np.int64), "start": np.zeros(0, np.int64),
                "count": np.zeros(0, np.int64), "data": np.zeros((0, 0, 5)), "state": state,
                "wall_time": time.perf_counter() - t0}
    return {"chunk": i, "index": a + blk.index, "start": blk.start, "count": blk.count,
            "data": blk.data[..., columns], "state": blk.state, "wall_time": time.perf_counter() - t0}


def _worker_task_block(spec, i, state):
    return task_block(spec, i, state, threads=1)


def _map(fn_local, fn_worker, args, jobs, backend, check=None):
    """fn(*a) for every a of ``args``, results as they come: in this process, or with joblib."""
    if jobs == 1 and backend is None:
        for a in args:
            if check is not None:
                check()
            yield fn_local(*a)
        return
    import joblib

    if check is not None:
        check()
    with joblib.parallel_config(backend=backend or "loky"):
        results = joblib.Parallel(n_jobs=jobs, return_as="generator")(joblib.delayed(fn_worker)(*a) for a in args)
        for r in results:
            yield r
            if check is not None:
                try:
                    check()
                except BaseException as exc:
                    results.throw(exc)
                    raise


def _stream_panel(spec: SweepSpec, pos: int, chunk_ids, streamer, jobs, backend, progress, check=None) -> dict:
    import dataclasses

    panel = spec.panels[pos]
    state = streamer.resume(panel, spec.initial_state(panel))
    rounds = max(1, math.ceil(spec.crossings / spec.blocks[pos]))
    wall = 0.0
    while not state.finished.all():
        todo = [i for i in chunk_ids if not state.finished[spec.chunks[i][1]:spec.chunks[i][2]].all()]
        args = [(spec, i, state.take(spec.chunks[i][1], spec.chunks[i][2])) for i in todo]
        for r in _map(task_block, _worker_task_block, args, jobs, backend, check):
            _, a, b = spec.chunks[r["chunk"]]
            state.put(a, r["state"])
            state.blocks += 1
            streamer.block(panel, state.blocks, r["index"], r["start"], r["count"], r["data"],
                           np.arange(a, b), r["state"].as_arrays())
            wall += r["wall_time"]
            if progress is not None:
                progress(1.0 / rounds)
    out = {"count": state.done.copy(), "status": state.status.copy(), "final": state.y.copy(),
           "info": state.info.copy(), "streamed": True, "settings": {}}
    if spec.lyapunov is not None:
        ly_spec = dataclasses.replace(spec, sections=False)
        parts = sorted(_map(task, _worker_task, [(ly_spec, i) for i in chunk_ids], jobs, backend, check),
                       key=lambda p: p["chunk"])
        ly = _assemble(parts)
        for k in INDICATOR_ARRAYS:
            if k in ly:
                out[k] = ly[k]
        wall += ly["wall_time"]
    out["wall_time"] = wall
    return out


def run(spec: SweepSpec, on_panel, *, jobs: int = 1, backend: str | None = None, progress=None, streamer=None,
        check=None):
    """Map ``task`` over the chunks and call ``on_panel(panel_spec, arrays)`` for each completed panel,
    in panel order, in this (the parent) process."""
    checked = check if check is not None else (lambda: None)
    token = _CHECK.set(check)
    try:
        _run(spec, on_panel, jobs, backend, progress, streamer, check, checked)
    finally:
        _CHECK.reset(token)


def _run(spec, on_panel, jobs, backend, progress, streamer, check, checked):
    if any(spec.streamed(pos) for pos in range(len(spec.panels))):
        if streamer is None:
            raise ValueError("a streamed panel needs a streamer (the store's writer of blocks)")
        for pos, panel in enumerate(spec.panels):
            chunk_ids = [i for i, c in enumerate(spec.chunks) if c[0] == pos]
            if spec.streamed(pos):
                on_panel(panel, _stream_panel(spec, pos, chunk_ids, streamer, jobs, backend, progress, check))
                checked()
                continue
            parts = []
            for r in _map(task, _worker_task, [(spec, i) for i in chunk_ids], jobs, backend, check):
                parts.append(r)
                if progress is not None:
                    progress(1)
            on_panel(panel, _assemble(sorted(parts, key=lambda p: p["chunk"])))
            checked()
        return
    per_panel: dict[int, list[int]] = {}
    for i, (pos, _a, _b) in enumerate(spec.chunks):
        per_panel.setdefault(pos, []).append(i)
    done: dict[int, dict] = {}
    next_pos = 0

    def flush():
        nonlocal next_pos
        while next_pos < len(spec.panels) and all(c in done for c in per_panel.get(next_pos, [])):
            parts = [done.pop(c) for c in per_panel.get(next_pos, [])]
            on_panel(spec.panels[next_pos], _assemble(parts))
            next_pos += 1

    for r in _map(task, _worker_task, [(spec, i) for i in range(len(spec.chunks))], jobs, backend, check):
        done[r["chunk"]] = r
        if progress is not None:
            progress(1)
        flush()
    flush()


def _assemble(parts):
    keys = ["data", "count", "status", "final", "info"]
    keys += [k for k in INDICATOR_ARRAYS if k in parts[0]]
    out = {k: np.concatenate([p[k] for p in parts]) for k in keys}
    out["settings"] = parts[0]["settings"]
    out["wall_time"] = float(sum(p["wall_time"] for p in parts))
    return out


def default_jobs_layout(jobs: int) -> int:
    """Number of chunk orbits for a given job count (0: one chunk per quarter panel)."""
    return 0 if jobs == 1 else CHUNK_ORBITS_JOBS


def cpu_count() -> int:
    return os.cpu_count() or 1


@dataclass(frozen=True)
class SystemSweepSpec:
    """The panels of a System's sweep and the section map they share (docs/scenes.md, "A scene of
    your own system"); ``task`` and ``task_block`` map it as a :class:`SweepSpec`'s."""

    panels: tuple
    section: Any
    direction: int
    coords: tuple
    solve: str
    crossings: int
    tol: float
    tmax: float
    max_steps: int
    chunks: tuple = ()
    lyapunov: Any = None
    sections: bool = True
    blocks: tuple = ()

    streamed = SweepSpec.streamed

    def chunk_crossings(self, panel, a: int, b: int, threads: int | None = None) -> dict:
        """The crossings of the seeds a:b of ``panel``'s section map at ``tol`` (rows :meth:`columns`) as :func:`task`
        returns them."""
        smap = self.section_map(panel).with_tol(self.tol)
        res = sections.crossings(smap, panel.seeds[a:b], n_crossings=self.crossings, tmax=self.tmax,
                                 max_steps=self.max_steps, threads=threads)
        return {"data": res.data[..., self.columns(panel.system)], "count": res.count, "status": res.status,
                "final": res.final, "info": res.info, "settings": res.settings}

    def stream_settings(self, panel) -> dict:
        """The keywords of the System's crossings of ``panel``'s section map (iter_crossings)."""
        smap = self.section_map(panel)
        return dict(n_crossings=self.crossings, section=smap.section.expr, direction=smap.direction, tol=self.tol,
                    tmax=self.tmax, max_steps=self.max_steps)

    def initial_state(self, panel):
        """The StreamState of a streamed ``panel`` before its first block."""
        from explorer.analysis.system_sections import initial_state

        return initial_state(panel.system, panel.y0, **self.stream_settings(panel))

    def task_block(self, i: int, state, threads: int | None = None) -> dict:
        """Chunk i's next block (:func:`task_block`), rows :meth:`columns`."""
        pos, a, b = self.chunks[i]
        panel = self.panels[pos]
        it = sections.iter_crossings(panel.system, states=panel.y0[a:b], block=self.blocks[pos], state=state,
                                     threads=threads, **self.stream_settings(panel))
        return _block_arrays(i, a, it, state, self.columns(panel.system))

    def indicator_arrays(self, panel, rows, threads=None, diffusion: bool = True) -> tuple:
        """(Indicators, arrays) of the seeds ``rows`` of ``panel`` (:func:`system_indicator_arrays`)."""
        return system_indicator_arrays(self, panel, rows, threads, diffusion=diffusion)

    def section_map(self, panel):
        """The section map of ``panel``; with frequency diffusion its returns at [lyapunov] tol (as Chaplygin's)."""
        from explorer.analysis.system_section_map import SystemSectionMap

        fd = None if self.lyapunov is None else self.lyapunov.frequency_diffusion
        return SystemSectionMap(panel.system, panel.h, section=self.section, direction=self.direction,
                                coords=self.coords, solve=self.solve, **({} if fd is None else {"tol": fd["tol"]}))

    def columns(self, system) -> list:
        """The columns of a System's crossing row (t, x_1..x_n, E - E0) stored as the panel's rows:
        (t, a, b, solve, E - E0), the store's (t, p1, p2, M, dH) (docs/store.md)."""
        index = [s.name for s in system.states]
        return [0] + [1 + index.index(c) for c in (*self.coords, self.solve)] + [1 + len(index)]


def _window_grid(window, na: int, nb: int) -> np.ndarray:
    """Cell centres of an na x nb raster of ``window`` (a_lo, a_hi, b_lo, b_hi), b rows ascending, then a."""
    a0, a1, b0, b1 = window
    A, B = np.meshgrid(a0 + (a1 - a0) * (np.arange(na) + 0.5) / na, b0 + (b1 - b0) * (np.arange(nb) + 0.5) / nb)
    return np.column_stack([A.ravel(), B.ravel()])


def system_seed_points(seeds, smap):
    """(points (M, 2), dropped) of a System scene's [seeds] on ``smap``'s energy surface: ``grid``
    about n cell centres of the window, ``random`` n uniform points of it (``seed``), ``points``
    as given; candidates off the surface are left out (``dropped`` counts them for ``points``)."""
    if seeds.kind == "points":
        cand = np.array(seeds.points, dtype=np.float64).reshape(-1, 2)
    elif seeds.kind == "grid":
        a0, a1, b0, b1 = seeds.window
        na = max(1, round(math.sqrt(seeds.n * (a1 - a0) / (b1 - b0))))
        cand = _window_grid(seeds.window, na, max(1, round(seeds.n / na)))
    else:
        a0, a1, b0, b1 = seeds.window
        u = np.random.default_rng(seeds.seed).random((seeds.n, 2))
        cand = np.column_stack([a0 + (a1 - a0) * u[:, 0], b0 + (b1 - b0) * u[:, 1]])
    ok = smap.allowed(cand)
    return cand[ok], int((~ok).sum()) if seeds.kind == "points" else 0


def system_map_seeds(smap, window, resolution: int):
    """The seeds of a System's chaos map: the cell centres of a resolution^2 raster of ``window``
    on the energy surface, in raster order, and the grid (resolution, a_lo, a_hi, b_lo, b_hi) of
    :func:`map_raster`."""
    n = int(resolution)
    pts = _window_grid(window, n, n)
    return pts[smap.allowed(pts)], (n, *(float(w) for w in window))


def build_system_spec(scene, panel_indices, *, chunk_orbits: int, product: str | None = None) -> SystemSweepSpec:
    """The panels of a System's scene to compute (seeds on each panel's energy surface), in chunks."""
    if product is not None and product not in PRODUCTS:
        raise ValueError(f"product must be one of {PRODUCTS} or None, got {product!r}")
    ly = scene.lyapunov if "lyapunov" in scene.compute and product != "sections" else None
    with_sections = "sections" in scene.compute and product != "indicators"
    if product is None and with_sections and ly is not None and ly.map_resolution:
        raise ValueError("sections with a map grid are two products: build one spec for each")
    integ = scene.integration
    panels: list = []
    chunks: list = []
    blocks: list = []
    for pos, i in enumerate(panel_indices):
        smap = scene.section_map(i)
        grid: tuple = ()
        dropped = 0
        if ly is not None and ly.map_resolution:
            pts, grid = system_map_seeds(smap, scene.seeds.window, ly.map_resolution)
        else:
            pts, dropped = system_seed_points(scene.seeds, smap)
        system, energy, label = scene.panel(i)
        if len(pts) == 0:
            raise ParameterError(f"scene panel {i} ({label or system.name}): no seed lies on the energy surface "
                                 f"E = {energy!r}")
        panels.append(PanelSpec(i, label, None, float(energy), np.ascontiguousarray(smap.states(pts)), pts, grid,
                                dropped, system))
        blocks.append(panel_block(len(pts), integ.crossings))
        # an adaptive map refines level by level: one chunk (as a Chaplygin map panel)
        whole = grid and ly is not None and ly.adaptive
        chunks += [(pos, 0, len(pts))] if whole else _chunks(pos, len(pts), chunk_orbits)
    return SystemSweepSpec(tuple(panels), scene.section, scene.direction, tuple(scene.coords), scene.solve,
                           integ.crossings, integ.tol, integ.effective_tmax, integ.max_steps, tuple(chunks), ly,
                           with_sections, tuple(blocks))


def build_system_atlas_spec(scene, *, chunk_orbits: int, cells=None) -> SystemSweepSpec:
    """The cells of a System scene's [atlas] (row = sweep value, column = atlas value) as the panels
    of a sweep of indicators only, seeded by [seeds] on each cell's energy surface, or with
    [lyapunov] map_resolution by the cells of its map's raster of [seeds] window; cells with no
    seed there are left out (drawn gray), and so are cells not in ``cells`` (None: all); a map is
    adaptive as a map panel is.  The panel's ``index`` is the cell's, as in :func:`build_atlas_spec`."""
    panels: list = []
    chunks: list = []
    resolution = scene.lyapunov.map_resolution
    for i in range(scene.n_cells):
        if cells is not None and i not in cells:
            continue
        smap = scene.cell_map(i)
        if resolution:
            pts, grid = system_map_seeds(smap, scene.seeds.window, resolution)
        else:
            (pts, _dropped), grid = system_seed_points(scene.seeds, smap), ()
        if not len(pts):
            continue
        system, energy, label = scene.cell(i)
        chunks += ([(len(panels), 0, len(pts))] if grid and scene.lyapunov.adaptive else
                   _chunks(len(panels), len(pts), chunk_orbits, parts=1))
        panels.append(PanelSpec(i, label, None, float(energy), np.ascontiguousarray(smap.states(pts)), pts, grid,
                                system=system))
    integ = scene.integration
    return SystemSweepSpec(tuple(panels), scene.section, scene.direction, tuple(scene.coords), scene.solve, 1,
                           integ.tol, integ.effective_tmax, integ.max_steps, tuple(chunks), scene.lyapunov, False)


def system_indicator_arrays(spec: SystemSweepSpec, panel, rows, threads=None, diffusion: bool = True) -> tuple:
    """(Indicators, arrays) of the seeds ``rows`` of a System's ``panel`` (each orbit alone, on the panel's
    map at [lyapunov] tol); frequency diffusion (:func:`explorer.analysis.rotation.frequency_diffusion` on
    the panel's section map) only with ``diffusion``."""
    from explorer.analysis.lyapunov import indicators

    ly = spec.lyapunov
    smap = spec.section_map(panel)
    which = tuple(q for q in ly.indicators if indicator_table.BY_NAME[q].tangent)
    ind = indicators(smap.with_tol(ly.tol), panel.seeds[rows], tmax=ly.time, which=which, threads=threads)
    out = {k: ind.values[k] for k in which}
    out.update(lyapunov_status=ind.status, lyapunov_dh=ind.energy_error)
    if ly.frequency_diffusion is not None and diffusion:
        out["frequency_diffusion"] = _frequency_diffusion(spec, panel, panel.seeds[rows], threads, smap)
    return ind, out
