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


def build_spec(scene, panel_indices, *, chunk_orbits: int) -> SweepSpec:
    """Seeds every panel to compute (inside the allowed region only, R9) and cuts it into chunks."""
    from explorer.analysis.seeds import seed_points

    integ = scene.integration
    panels = []
    chunks = []
    for pos, i in enumerate(panel_indices):
        params, h, label = scene.panel(i)
        p1, p2, _dropped = seed_points(scene.seeds, params, h, integ.phi0)
        if len(p1) == 0:
            raise ParameterError(f"scene panel {i} ({label}): no seed lies inside the allowed region")
        y0 = model.section_state(params, p1, p2, h, integ.phi0, integ.direction if integ.direction else 1)
        panels.append(PanelSpec(i, label, params.as_array(), float(h), np.ascontiguousarray(y0),
                                np.column_stack([p1, p2])))
        n = len(p1)
        step = max(1, chunk_orbits if chunk_orbits > 0 else math.ceil(n / CHUNKS_PER_PANEL_THREADS))
        for a in range(0, n, step):
            chunks.append((pos, a, min(n, a + step)))
    return SweepSpec(tuple(panels), integ.method, integ.tol, integ.dt, integ.crossings, integ.effective_tmax,
                     integ.max_steps, integ.phi0, integ.direction, tuple(chunks),
                     scene.lyapunov if "lyapunov" in scene.compute else None)


def task(spec: SweepSpec, i: int, threads: int | None = None) -> dict:
    """Pure map: integrate chunk i of the sweep and return its arrays."""
    pos, a, b = spec.chunks[i]
    panel = spec.panels[pos]
    t0 = time.perf_counter()
    res = sections.crossings(panel.P, panel.y0[a:b], spec.crossings, method=spec.method, tol=spec.tol,
                             dt=spec.dt, tmax=spec.tmax, max_steps=spec.max_steps, phi0=spec.phi0,
                             direction=spec.direction, threads=threads)
    out = {"chunk": i, "data": res.data, "count": res.count, "status": res.status, "final": res.final,
           "info": res.info, "settings": res.settings}
    if spec.lyapunov is not None:
        from explorer.analysis.lyapunov import indicators

        ly = spec.lyapunov
        ind = indicators(panel.P, panel.y0[a:b], ly.time, method=ly.method, tol=ly.tol, dt=ly.dt, threads=threads)
        out.update(megno=ind.megno, mlce=ind.mlce, fli=ind.fli, lyapunov_status=ind.status)
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
    out = {k: np.concatenate([p[k] for p in parts]) for k in keys}
    out["settings"] = parts[0]["settings"]
    out["wall_time"] = float(sum(p["wall_time"] for p in parts))
    return out


def default_jobs_layout(jobs: int) -> int:
    """Number of chunk orbits for a given job count (0: one chunk per quarter panel)."""
    return 0 if jobs == 1 else CHUNK_ORBITS_JOBS


def cpu_count() -> int:
    return os.cpu_count() or 1
