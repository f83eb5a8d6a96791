"""A sweep over the panels of a scene as a pure map (orchestration layer).

A :class:`SweepSpec` is small and picklable: for each panel to compute, the
packed parameters, the energy, the seeds on the section and the integration
settings.  ``task(spec, i)`` integrates chunk ``i`` (a slice of one panel's
orbits) and returns arrays; it has no side effects, so the results cannot
depend on the number of jobs, the backend or the chunking (each orbit's
arithmetic is independent of the others).  ``run`` maps ``task`` over the
chunks with joblib (processes, one Numba thread each) or in this process
(Numba threads over orbits), never both at once, and hands each finished
panel to a callback in panel order; only that callback (in the parent) writes
files.  Compare heyoka's ensemble ``gen(template, i)``.
"""
from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from explorer import model
from explorer.analysis import sections
from explorer.model import ParameterError

#: orbits per chunk when joblib processes share the work
CHUNK_ORBITS_JOBS = 32
#: chunks per panel when this process runs everything with Numba threads (progress granularity)
CHUNKS_PER_PANEL_THREADS = 4


@dataclass(frozen=True)
class PanelSpec:
    index: int
    label: str
    P: np.ndarray          # packed parameters (9,)
    h: float
    y0: np.ndarray         # (N, 5) initial states on the section
    seeds: np.ndarray      # (N, 2) p1, p2
    grid: tuple = ()       # chaos map raster: (resolution, p1_lo, p1_hi, p2_lo, p2_hi); () otherwise


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
    chunks: tuple = field(default=())   # (panel position, start, stop) for each task
    lyapunov: Any = None                # scene.LyapunovSpec when chaos indicators are asked for
    sections: bool = True               # False: indicators only, no crossings are computed or stored


def build_spec(scene, panel_indices, *, chunk_orbits: int) -> SweepSpec:
    """Seeds every panel to compute (inside the allowed region only, R9) and cuts it into chunks."""
    from explorer.analysis.seeds import seed_points

    integ = scene.integration
    panels = []
    chunks = []
    ly = scene.lyapunov if "lyapunov" in scene.compute else None
    for pos, i in enumerate(panel_indices):
        params, h, label = scene.panel(i)
        grid: tuple = ()
        if ly is not None and ly.map_resolution:
            p1, p2, grid = map_seeds(params, h, integ.phi0, ly.map_resolution)
        else:
            p1, p2, _dropped = seed_points(scene.seeds, params, h, integ.phi0)
        if len(p1) == 0:
            raise ParameterError(f"scene panel {i} ({label}): no seed lies inside the allowed region")
        y0 = model.section_state(params, p1, p2, h, integ.phi0, integ.direction if integ.direction else 1)
        panels.append(PanelSpec(i, label, params.as_array(), float(h), np.ascontiguousarray(y0),
                                np.column_stack([p1, p2]), grid))
        n = len(p1)
        step = max(1, chunk_orbits if chunk_orbits > 0 else math.ceil(n / CHUNKS_PER_PANEL_THREADS))
        for a in range(0, n, step):
            chunks.append((pos, a, min(n, a + step)))
    return SweepSpec(tuple(panels), integ.method, integ.tol, integ.dt, integ.crossings, integ.effective_tmax,
                     integ.max_steps, integ.phi0, integ.direction, tuple(chunks), ly,
                     "sections" in scene.compute)


def map_seeds(params, h: float, phi0: float, resolution: int):
    """The seeds of a chaos map: the centres of the cells of a resolution x resolution raster over
    the bounding box of the allowed ellipse of the section (MODEL.md R9) that lie inside the
    allowed region (section_M2 > 0), in raster order (p2 rows ascending, then p1).  Returns
    (p1, p2, grid) with grid = (resolution, p1_lo, p1_hi, p2_lo, p2_hi): cell (r, c) has centre
    (p1_lo + (c + 1/2) d1, p2_lo + (r + 1/2) d2), d = (hi - lo) / resolution."""
    ell = model.allowed_ellipse(params, h, phi0)
    if ell is None or not (ell[2] > 0.0 and ell[3] > 0.0):
        raise ParameterError(f"energy h = {h!r}: the allowed region of the section is empty; no chaos map")
    c1, c2, r1, r2 = ell
    n = int(resolution)
    u = (np.arange(n) + 0.5) / n
    P1, P2 = np.meshgrid(c1 - r1 + 2 * r1 * u, c2 - r2 + 2 * r2 * u)
    inside = model.section_M2(params, P1, P2, h, phi0) > 0.0
    return P1[inside], P2[inside], (n, c1 - r1, c1 + r1, c2 - r2, c2 + r2)


def map_raster(seeds, values, grid):
    """values per seed -> a (resolution, resolution) raster (NaN outside the allowed region),
    row r = p2 index, column c = p1 index (the geometry of :func:`map_seeds`)."""
    n, a1, b1, a2, b2 = grid
    n = int(n)
    img = np.full((n, n), np.nan)
    c = np.floor((seeds[:, 0] - a1) / (b1 - a1) * n).astype(int).clip(0, n - 1)
    r = np.floor((seeds[:, 1] - a2) / (b2 - a2) * n).astype(int).clip(0, n - 1)
    img[r, c] = values
    return img


def task(spec: SweepSpec, i: int, threads: int | None = None) -> dict:
    """Pure map: integrate chunk i of the sweep and return its arrays."""
    pos, a, b = spec.chunks[i]
    panel = spec.panels[pos]
    t0 = time.perf_counter()
    if spec.sections:
        res = sections.crossings(panel.P, panel.y0[a:b], spec.crossings, method=spec.method, tol=spec.tol,
                                 dt=spec.dt, tmax=spec.tmax, max_steps=spec.max_steps, phi0=spec.phi0,
                                 direction=spec.direction, threads=threads)
        out = {"chunk": i, "data": res.data, "count": res.count, "status": res.status, "final": res.final,
               "info": res.info, "settings": res.settings}
    else:   # indicators only: no crossings computed or stored
        n = b - a
        out = {"chunk": i, "data": np.zeros((n, 0, 5)), "count": np.zeros(n, np.int64),
               "status": np.zeros(n, np.int64), "final": panel.y0[a:b].copy(), "info": np.zeros((n, 3)),
               "settings": {"sections": False}}
    if spec.lyapunov is not None:
        from explorer.analysis.lyapunov import indicators

        ly = spec.lyapunov
        ind = indicators(panel.P, panel.y0[a:b], ly.time, method=ly.method, tol=ly.tol, dt=ly.dt, threads=threads,
                         which=ly.indicators, early_stop=ly.early_stop, early_sali=ly.early_sali,
                         early_megno=ly.early_megno, early_time=ly.early_time)
        out.update(megno=ind.megno, mlce=ind.mlce, fli=ind.fli, lyapunov_status=ind.status)
        if ly.second_vector:
            out.update(sali=ind.sali, gali2=ind.gali2)
        if ly.early_stop:
            out.update(lyapunov_early=ind.early)
    out["wall_time"] = time.perf_counter() - t0
    return out


def _worker_task(spec, i):
    # one level of parallelism: a joblib worker uses one Numba thread
    return task(spec, i, threads=1)


def run(spec: SweepSpec, on_panel, *, jobs: int = 1, backend: str | None = None, progress=None):
    """Map ``task`` over the chunks and call ``on_panel(panel_spec, arrays)`` for each completed panel,
    in panel order, in this (the parent) process.  ``jobs == 1`` runs in this process with Numba
    threads over orbits; otherwise joblib runs ``jobs`` workers (``backend`` as joblib names it:
    "loky" by default, "dask" with a dask.distributed Client active)."""
    n_chunks = len(spec.chunks)
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

    if jobs == 1 and backend is None:
        results = (task(spec, i) for i in range(n_chunks))
    else:
        import joblib

        # parallel_config registers external backends such as "dask" on first use
        with joblib.parallel_config(backend=backend or "loky"):
            parallel = joblib.Parallel(n_jobs=jobs, return_as="generator")
            for r in parallel(joblib.delayed(_worker_task)(spec, i) for i in range(n_chunks)):
                done[r["chunk"]] = r
                if progress is not None:
                    progress(1)
                flush()
        flush()
        return
    for r in results:
        done[r["chunk"]] = r
        if progress is not None:
            progress(1)
        flush()
    flush()


def _assemble(parts):
    keys = ["data", "count", "status", "final", "info"]
    if "megno" in parts[0]:
        keys += ["megno", "mlce", "fli", "lyapunov_status"]
        keys += [k for k in ("sali", "gali2", "lyapunov_early") if k in parts[0]]
    out = {k: np.concatenate([p[k] for p in parts]) for k in keys}
    out["settings"] = parts[0]["settings"]
    out["wall_time"] = float(sum(p["wall_time"] for p in parts))
    return out


def default_jobs_layout(jobs: int) -> int:
    """Number of chunk orbits for a given job count (0: one chunk per quarter panel)."""
    return 0 if jobs == 1 else CHUNK_ORBITS_JOBS


def cpu_count() -> int:
    return os.cpu_count() or 1
