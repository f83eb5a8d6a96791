"""``python -m explorer sweep``: scene -> sweep -> HDF5 store -> figure (docs/commands/sweep.md).
Only the parent process writes; a panel whose stored hash is the scene's is skipped, so a rerun
after a kill computes only what is missing."""
from __future__ import annotations

import contextlib
import json
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from explorer.analysis import sections, sweep
from explorer.analysis.classification import CLASS_NAMES, class_text
from explorer.analysis.sections import ADAPTIVE_METHODS, energy_warning
from explorer.app import interrupt
from explorer.app.interrupt import Interrupted
from explorer.io import store
from explorer.io.store import stream
from explorer.kernels import STATUS_NAMES, STATUS_TMAX
from explorer.model import ParameterError, validation, with_value


def _panel_points(panel_data):
    rows = panel_data.arrays["crossings"]
    return rows[:, 1:3] if len(rows) else np.zeros((0, 2))


#: separatrices (explorer.analysis.manifolds.grow_branch): the arclength of each branch (the page's,
#: explorer.app.serve.overlays.SEPARATRIX_ARCLENGTH), images of the fundamental domain at most,
#: points at most
SEPARATRIX_SETTINGS = dict(arclength=4.0, iterations=6, max_points=6000)


def panel_separatrices(scene, i):
    """The central fixed point of panel i, continued from mu = 0 (solution I, R6) or the first sweep
    value, and its separatrix branches when hyperbolic.  Returns (fixed point attrs, curves)."""
    from explorer import model as mdl
    from explorer.analysis import fixedpoints as fpm

    prm, h, _label = scene.panel(i)
    name = scene.sweep_parameter
    phi0 = scene.integration.phi0
    if name is None:
        c1, c2, _r1, _r2 = mdl.allowed_ellipse(prm, h, phi0)
        fp = fpm.find_fixed_point(prm, h, (c1, c2), phi0=phi0)
    else:
        start = 0.0 if name == "mu" else scene.sweep_values[0]
        sprm, sh = with_value(prm, h, name, start)
        c1, c2, _r1, _r2 = mdl.allowed_ellipse(sprm, sh, phi0)
        target = scene.sweep_values[i]
        fp = fpm.follow(prm, h, name, start, target, (c1, c2), phi0=phi0)
    info = {k: v for k, v in fp.as_dict().items() if k != "eigenvalues"}
    curves = [] if fp.stable else fpm.separatrices(fp.params, fp.h, fp, phi0=phi0, **SEPARATRIX_SETTINGS)
    return info, curves


def panel_manifolds(scene, i):
    """[manifolds] draw = true: the branches of W^u and W^s at each point of panel i's orbit (as
    ``explorer manifold`` finds and grows them), computed when the figure is drawn, never stored.
    Returns (list of (kind, (M, 2) array), note saying why there are none or "")."""
    from explorer.analysis import manifolds as mf
    from explorer.analysis import periodic
    from explorer.analysis.section_map import SectionMap

    spec = scene.manifolds
    prm, h, _label = scene.panel(i)
    branches: list = []
    try:
        smap = SectionMap(prm, h, phi0=scene.integration.phi0)
        orb = periodic.find_periodic_orbit(smap, spec.guess, spec.period)
        for j in range(orb.period):
            branches += [(b.kind, b.points) for b in mf.manifolds(smap, orb, index=j, arclength=spec.arclength,
                                                                 max_points=spec.max_points)]
    except ParameterError as exc:
        msg = str(exc).split(" (")[0]
        return [], "no manifolds: " + (msg if len(msg) <= 60 else msg[:57] + "...")
    return branches, ""


def raster_maps(scene, maps) -> list:
    """The map panels of ``maps`` (those with a grid) as :func:`explorer.app.chaos_raster.chaos_rasters`
    draws them: the values of ``map_indicator``, the panel's class and fraction, the cells computed,
    the orbits stopped early and the stop's level."""
    ly = scene.lyapunov
    rasters = [m for m in maps if m.get("grid")]
    for m in rasters:
        m["values"] = m["extra"][ly.map_indicator] if ly.map_indicator in m["extra"] else m["megno"]
        m["fraction"] = sweep.panel_fraction(m["extra"], *scene_class(scene))[0]
        m["computed"] = computed_fraction(m["extra"])
        m["classified"] = class_text(*scene_class(scene))
        m["stopped"] = stopped_early(m["extra"])
        m["stop_level"] = ly.early_megno if ly.early_stop else None
    return rasters


def stopped_early(arrays):
    """Per orbit: was it stopped early as chaotic (``lyapunov_early`` > 0; None without early stop)?"""
    early = arrays.get("lyapunov_early")
    return None if early is None else np.asarray(early) > 0


def scene_class(scene) -> tuple:
    """(indicator, threshold) that classify the orbits of ``scene``'s panels (a map: its own)."""
    return sweep.panel_class(scene.lyapunov, bool(scene.lyapunov.map_resolution))


def stored_class(attrs) -> tuple:
    """(indicator, threshold) that classified a stored panel (a store without ``class_indicator``: MEGNO)."""
    if "class_indicator" in attrs:
        return str(attrs["class_indicator"]), float(attrs["class_threshold"])
    return "megno", float(attrs.get("megno_threshold", float("nan")))


def lyapunov_panels(scene, data):
    """The chaos maps of the stored panels of ``scene`` and the chaotic fraction per panel as rows
    (swept value, fraction, binomial error) by the scene's class (:func:`scene_class`)."""
    maps, fractions = [], []
    for i in range(scene.n_panels):
        params, h, label = scene.panel(i)
        pd = data.panels.get(i)
        if pd is None or "megno" not in pd.extra:
            continue
        ok = pd.extra["lyapunov_status"] == 0
        seeds = pd.extra.get("lyapunov_seeds", pd.seeds)   # a map grid beside sections has its own seeds
        maps.append({"seeds": seeds, "megno": pd.extra["megno"], "valid": ok, "params": params, "h": h,
                     "phi0": scene.integration.phi0, "label": label})
        value = scene.sweep_values[i] if scene.sweep_values else 0.0
        maps[-1].update(grid=_grid_of(pd.attrs), extra=pd.extra, curves=pd.separatrices())
        fractions.append((value,) + sweep.panel_fraction(pd.extra, *scene_class(scene))[:2])
    return maps, np.array(fractions).reshape(-1, 3)


def computed_fraction(extra) -> float | None:
    """The fraction of a map panel's cells computed, not filled (``map_computed``; None without one)."""
    mask = extra.get("map_computed")
    return float(np.mean(mask)) if mask is not None and len(mask) else None


def _grid_of(attrs):
    """The raster geometry of a stored chaos map panel, (resolution, p1_lo, p1_hi, p2_lo, p2_hi), or ()."""
    if "map_resolution" not in attrs:
        return ()
    a1, b1 = (float(v) for v in attrs["map_p1"])
    a2, b2 = (float(v) for v in attrs["map_p2"])
    return (int(attrs["map_resolution"]), a1, b1, a2, b2)


def draw_figure(scene, out_path, stem):
    """Read the store and draw the scene's figure (PNG and PDF). Returns the paths."""
    from explorer.app import figures

    if getattr(scene, "system", None) is not None:   # a System's scene (docs/scenes.md)
        from explorer.app.system_sweep import draw_system_figure

        return draw_system_figure(scene, out_path, stem, text={FIGURE_SETTINGS_KEY: scene.figure_settings()})

    data = store.read_store(out_path)
    panels = []
    for i in range(scene.n_panels):
        params, h, label = scene.panel(i)
        pd = data.panels.get(i)
        points = _panel_points(pd) if pd is not None else np.zeros((0, 2))
        panels.append({"points": points, "params": params, "h": h, "phi0": scene.integration.phi0,
                       "label": label})
        if pd is not None:
            panels[-1]["curves"] = pd.separatrices()
            fpa = pd.attrs.get("fixed_point")
            if fpa:
                fp = json.loads(fpa)
                if fp.get("stable"):
                    panels[-1]["note"] = f"fixed point stable (trace {fp['trace']:.3g})"
    if scene.manifolds.draw:
        for i, panel in enumerate(panels):
            panel["manifolds"], note = panel_manifolds(scene, i)
            if note:
                panel["note"] = f"{panel['note']}\n{note}" if panel.get("note") else note
    fs = scene.figure
    text = {FIGURE_SETTINGS_KEY: scene.figure_settings()}
    fig = figures.section_panels(panels, layout=fs.layout, columns=fs.columns, share_scale=fs.share_scale,
                                 own_scale=tuple(fs.own_scale), marker_size=fs.marker_size, dpi=fs.dpi)
    paths = list(figures.save_figure(fig, stem, text=text))
    if "lyapunov" in scene.compute:
        maps, fractions = lyapunov_panels(scene, data)
        rasters = raster_maps(scene, maps)
        if rasters:
            from explorer.app.chaos_raster import chaos_rasters

            ind = scene.lyapunov.map_indicator
            fig = chaos_rasters(rasters, indicator=ind, threshold=scene.lyapunov.threshold, columns=fs.columns,
                                dpi=fs.dpi)
            paths += figures.save_figure(fig, stem.with_name(stem.name + "_map"), text=text)
        elif maps:
            fig = figures.chaos_maps(maps, layout=fs.layout, columns=fs.columns, threshold=scene.lyapunov.threshold,
                                     dpi=fs.dpi)
            paths += figures.save_figure(fig, stem.with_name(stem.name + "_chaosmap"), text=text)
        if len(fractions) > 1:
            paths += figures.save_fraction_curve(fractions, scene, fs.dpi, stem, text)
    return paths


@dataclass(frozen=True)
class SweepReport:
    """What one :func:`run_sweep` did; :func:`format_report` turns it into the CLI's summary."""

    scene: str
    out: Path
    n_panels: int
    computed: tuple          # indices of the panels of which this run computed a product
    orbits: int              # orbits whose crossings were computed
    crossings: int
    stopped: int             # orbits that stopped crossing within the time budget
    statuses: dict           # status name -> number of orbits
    max_dh: float            # largest |H - H0| over all crossings computed
    warning: str | None      # energy-error warning naming the setting to tighten
    fractions: tuple         # (panel label, chaotic fraction, binomial error) per computed panel
    threshold: float         # the threshold of the fractions (of ``classified``)
    figure: tuple            # paths of the figure files drawn by this run (empty: none)
    wall_time: float
    restamped: tuple = ()    # stored panels whose chaotic fraction was reclassified (new threshold)
    dropped: int = 0         # [seeds] candidates outside the allowed region (not integrated)
    products: dict = field(default_factory=dict)   # product -> indices of the panels computed
    indicator_orbits: int = 0    # orbits whose chaos indicators were computed
    indicator_dh: float = 0.0    # largest |H - H0| at the end of the indicator integrations
    indicator_warning: str | None = None
    indicator_statuses: dict = field(default_factory=dict)
    map_cells: tuple = ()        # (panel label, cells computed, allowed cells) per adaptive map panel
    classified: str = ""         # how the fractions classify (class_text), e.g. "MEGNO > 4"


def _head(label: str) -> str:
    """A summary line's panel label (none for a scene of one unlabelled panel)."""
    return f"{label}: " if label else ""


def format_report(r: SweepReport) -> str:
    """The summary that ``explorer sweep`` prints: what was computed and what was measured."""
    lines = [f"scene {r.scene}: {r.n_panels} panels ({len(r.computed)} computed, "
             f"{r.n_panels - len(r.computed)} already stored) -> {r.out}"]
    if len(r.products) > 1 and r.computed:
        lines.append("  computed: " + "; ".join(
            f"{k} of panels {', '.join(map(str, v))}" if v else f"{k} already stored" for k, v in r.products.items()))
    if r.products.get("sections"):
        st = ", ".join(f"{k}: {v}" for k, v in sorted(r.statuses.items()))
        lines.append(f"  orbits {r.orbits}, crossings {r.crossings}, "
                     f"orbits that stopped crossing {r.stopped} ({st})")
        lines.append(f"  energy error max |H - H0| over all crossings {r.max_dh:.1e}")
        if r.warning:
            lines.append(f"  warning: {r.warning}")
    if r.products.get("indicators"):
        st = ", ".join(f"{k}: {v}" for k, v in sorted(r.indicator_statuses.items()))
        lines.append(f"  chaos indicators of {r.indicator_orbits} orbits ({st}); energy error at the end of the "
                     f"indicator integrations max |H - H0| {r.indicator_dh:.1e}")
        if r.indicator_warning:
            lines.append(f"  warning: {r.indicator_warning}")
    if r.products.get("cells"):   # an atlas: chaotic fractions only
        lines.append(f"  cells {len(r.products['cells'])}, orbits {r.orbits} (chaos indicators only)")
    elif r.computed:
        lines.append(f"  seeds outside the allowed region (dropped, not integrated): {r.dropped}")
    if r.restamped:
        lines.append(f"  chaotic fraction reclassified at {r.classified} (stored indicators, "
                     f"nothing recomputed) for panels {', '.join(str(i) for i in r.restamped)}")
    for label, done, cells in r.map_cells:
        lines.append(f"  {_head(label)}map cells computed {done} of {cells} ({done / max(cells, 1):.1%}), "
                     "the rest filled (adaptive; [lyapunov] exact = true computes every cell)")
    for label, frac, err in r.fractions:
        lines.append(f"  {_head(label)}chaotic fraction {frac:.3f} +- {err:.3f} ({r.classified})")
    if r.figure:
        lines.append("  figure " + ", ".join(str(p) for p in r.figure))
    lines.append(f"  wall time {r.wall_time:.2f} s")
    return "\n".join(lines)


def _stored_products(scene, i, stored: dict, want: dict) -> set:
    """The products of panel i that the store holds with the scene's hashes (a panel with ``hash``
    only counts as whole when it is the scene's, unless sections beside a map grid)."""
    if any(a in stored for a in store.PRODUCT_HASH_ATTRS.values()):
        return {k for k, h in want.items() if stored.get(store.PRODUCT_HASH_ATTRS[k]) == h}
    if stored.get("hash") == scene.panel_hash(i) and not ("sections" in want and scene.lyapunov.map_resolution):
        return set(want)
    return set()


def run_sweep(scene, out=None, *, figure=None, draw=None, jobs=1, backend=None, scheduler=None,
              force=False, progress=True) -> SweepReport:
    """Compute the products (sections, indicators) of every panel of ``scene`` that ``out`` lacks
    with the scene's hashes, commit each panel atomically and, with ``draw``, redraw a stale figure
    (docs/commands/sweep.md).  ``scene``: a Scene, TOML path or preset name; ``out`` [results/<scene>.h5];
    ``figure``: the figure's stem [``out`` without .h5]; ``draw`` [only when ``figure`` is given];
    ``jobs``/``backend``/``scheduler``: joblib processes or a dask cluster; ``force``: recompute all.
    Returns a :class:`SweepReport`; bad settings raise ParameterError."""
    from explorer.io.scene import Scene, load_scene

    t_start = time.perf_counter()
    draw = figure is not None if draw is None else validation.boolean("draw", draw)
    jobs = _check_jobs(jobs, backend, scheduler)
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    if scene.is_atlas:
        return run_atlas(scene, out, figure=figure, draw=draw, jobs=jobs, backend=backend, scheduler=scheduler,
                         force=force, progress=progress)
    out, stem = _outputs(scene, out, figure, draw)
    with _guarded(out) as stop:
        return _sweep(scene, out, stem, draw=draw, jobs=jobs, backend=backend, scheduler=scheduler, force=force,
                      progress=progress, stop=stop, t_start=t_start)


def _sweep(scene, out, stem, *, draw, jobs, backend, scheduler, force, progress, stop, t_start) -> SweepReport:
    """:func:`run_sweep` with the store held and Ctrl-C deferred: plan, compute and write each
    product panel by panel, draw, report."""
    _check_same_scene(scene, out, force)
    plan = _plan(scene, out, force)
    client = _dask_client(scheduler, jobs) if backend == "dask" else None
    if client is not None:
        jobs = -1
    specs = _specs(scene, plan, jobs, backend)
    if "sections" in specs:
        _check_disk(specs["sections"], out)
    writer = _PanelWriter(scene, out, plan, specs, _streams(scene, out, plan, specs.get("sections"), force))
    try:
        for product, on_panel in (("sections", writer.sections), ("indicators", writer.indicators)):
            if product in specs:
                _map_with_progress(specs[product], on_panel, jobs, backend, None, progress,
                                   f"sweep {scene.name} {product}", writer.streams, _checker(stop, client))
    except KeyboardInterrupt:   # ours, or a worker's when Ctrl-C reached the whole process group
        raise Interrupted(_kept(scene, out, plan.want)) from None
    finally:
        if client is not None:
            client.close()
    if stop.requested:      # every panel is stored; the figure is drawn by the next run
        raise Interrupted(_kept(scene, out, plan.want))
    figure_paths = ()
    if draw and (plan.computed or plan.restamped or force or _figure_stale(stem, out, scene.figure_settings())):
        figure_paths = tuple(draw_figure(scene, out, stem))
    return writer.stats.report(scene, out, plan, figure_paths, time.perf_counter() - t_start)


@dataclass(frozen=True)
class _Plan:
    """What a sweep run computes: per panel its hash, the products' hashes wanted and held
    (``want``, ``have``); per product the panels ``todo``; ``computed``; ``restamped``."""

    hashes: list
    want: list
    have: list
    todo: dict
    computed: list
    restamped: tuple

    @property
    def alone(self) -> bool:
        """Indicators only: they are the whole panel (no sections)."""
        return "sections" not in self.want[0]


def _plan(scene, out, force) -> _Plan:
    """The :class:`_Plan` of a sweep of ``scene`` into ``out`` (``force``: recompute all)."""
    try:
        on_disk = {} if force else store.panel_product_hashes(out)
    except store.StoreError as exc:
        raise ParameterError(str(exc)) from None
    n = scene.n_panels
    hashes = [scene.panel_hash(i) for i in range(n)]
    want = [scene.product_hashes(i) for i in range(n)]
    have = [_stored_products(scene, i, on_disk.get(i, {}), want[i]) for i in range(n)]
    todo = {k: [i for i in range(n) if k in want[i] and k not in have[i]] for k in sweep.PRODUCTS if k in want[0]}
    computed = sorted(set().union(*todo.values()))
    restamped = _restamp_fractions(scene, out, [i for i in range(n) if i not in todo.get("indicators", ())])
    return _Plan(hashes, want, have, todo, computed, restamped)


def _specs(scene, plan: _Plan, jobs, backend) -> dict:
    """The sweep spec of each product with panels to compute."""
    chunk_orbits = sweep.default_jobs_layout(1 if (jobs == 1 and backend is None) else 2)
    return {k: sweep.build_spec(scene, v, chunk_orbits=chunk_orbits, product=k) for k, v in plan.todo.items() if v}


def _streams(scene, out, plan: _Plan, sec, force) -> stream.PanelStreams:
    """The writer of the streamed sections panels, once the block folders of finished, replaced or
    no longer streamed panels are removed (nothing resumes from them)."""
    stream.remove_stale_blocks(out, keep={p.index for k, p in enumerate(sec.panels) if sec.streamed(k)}
                               if sec is not None else ())
    return stream.PanelStreams(out, [w.get("sections") for w in plan.want], scene.integration.phi0, force)


@dataclass
class _SweepStats:
    """What the panels written so far measured: the totals of :class:`SweepReport`."""

    orbits: int = 0
    crossings: int = 0
    stopped: int = 0
    statuses: dict = field(default_factory=dict)
    max_dh: float = 0.0
    warning: str | None = None
    fractions: list = field(default_factory=list)
    dropped: dict = field(default_factory=dict)
    ind_orbits: int = 0
    ind_dh: float = 0.0
    ind_warning: str | None = None
    ind_statuses: dict = field(default_factory=dict)
    map_cells: list = field(default_factory=list)

    def add_dropped(self, i, panel) -> None:
        self.dropped[i] = max(self.dropped.get(i, 0), int(panel.dropped))

    def add_sections(self, panel, arrays, dh, setting, crossings) -> None:
        """A sections panel: its orbits, crossings, energy error (``dh``: against ``setting``),
        orbits stopped by the time budget before ``crossings``, statuses."""
        self.orbits += len(arrays["count"])
        self.crossings += int(arrays["count"].sum())
        self.add_dropped(panel.index, panel)
        self.max_dh = max(self.max_dh, dh)
        self.warning = self.warning or energy_warning(dh, panel.h, setting)  # each panel its own h
        stopped = (arrays["status"] == STATUS_TMAX) & (arrays["count"] < crossings)
        self.stopped += int(stopped.sum())
        _count_statuses(self.statuses, arrays["status"])

    def add_indicators(self, panel, arrays, fraction, setting) -> None:
        """An indicators panel: its chaotic fraction (label, fraction, error), orbits, energy error
        at the end (against ``setting``), statuses."""
        self.fractions.append((panel.label,) + tuple(fraction))
        dh = arrays["lyapunov_dh"]
        dh = float(np.max(dh[np.isfinite(dh)])) if np.isfinite(dh).any() else 0.0
        self.ind_orbits += len(arrays["megno"])
        self.ind_dh = max(self.ind_dh, dh)
        self.ind_warning = self.ind_warning or energy_warning(dh, panel.h, setting)
        _count_statuses(self.ind_statuses, arrays["lyapunov_status"])
        if "map_computed" in arrays:
            self.map_cells.append((panel.label, int(np.sum(arrays["map_computed"])), len(arrays["map_computed"])))

    def report(self, scene, out, plan: _Plan, figure, wall_time) -> SweepReport:
        return SweepReport(scene=scene.name, out=out, n_panels=scene.n_panels, computed=tuple(plan.computed),
                           orbits=self.orbits, crossings=self.crossings, stopped=self.stopped,
                           statuses=dict(self.statuses), max_dh=self.max_dh, warning=self.warning,
                           fractions=tuple(self.fractions), threshold=scene_class(scene)[1],
                           figure=figure, wall_time=wall_time, restamped=plan.restamped,
                           dropped=sum(self.dropped.values()), products={k: tuple(v) for k, v in plan.todo.items()},
                           indicator_orbits=self.ind_orbits, indicator_dh=self.ind_dh,
                           indicator_warning=self.ind_warning, indicator_statuses=dict(self.ind_statuses),
                           map_cells=tuple(self.map_cells), classified=class_text(*scene_class(scene)))


def _setting(section) -> str:
    """The accuracy setting of an [integration] or [lyapunov] table, as an energy warning names it."""
    return f"tol = {section.tol:g}" if section.method in ADAPTIVE_METHODS else f"dt = {section.dt:g}"


class _PanelWriter:
    """Writes each finished panel of a sweep (``sweep.run``'s callbacks, in the parent) through
    :func:`explorer.io.store.write_panel`, and adds what it measured to ``stats``."""

    def __init__(self, scene, out, plan: _Plan, specs: dict, streams: stream.PanelStreams):
        self.scene, self.out, self.plan, self.specs, self.streams = scene, out, plan, specs, streams
        self.stats = _SweepStats()
        self.file_attrs = store.file_attrs(scene.name, scene.text, {"scene": scene.name})
        self.setting = _setting(scene.integration) + " ([integration])"
        self.ly_setting = _setting(scene.lyapunov) + " ([lyapunov])"

    def panel_attrs(self, panel, i, complete) -> dict:
        """The attributes every panel carries (its settings hash only when ``complete``)."""
        scene = self.scene
        settings = scene.panel_settings(i)
        return store.PanelAttrs(i, panel.label, panel.h, settings.get("params", {}), settings,
                                scene.sweep_parameter or "",
                                float(scene.sweep_values[i]) if scene.sweep_values else float("nan"),
                                self.plan.hashes[i] if complete else None).attrs()

    def _kept_indicators(self, i) -> dict:
        """The stored indicators of panel i (datasets and attributes) that stay with its new sections."""
        if not ("indicators" in self.plan.want[i] and "indicators" in self.plan.have[i]):
            return {}
        kept, old_attrs = store.read_panel_datasets(self.out, i, store.INDICATOR_DATASETS)
        return dict(kept, **{k: old_attrs[k] for k in store.INDICATOR_ATTRS if k in old_attrs})

    def sections(self, panel, arrays) -> None:
        """Write panel ``panel``'s sections (whole, or from its streamed blocks), with its stored
        indicators kept and, with [compute] separatrices, its fixed point and separatrices."""
        i, integ = panel.index, self.scene.integration
        keep = self._kept_indicators(i)
        attrs = self.panel_attrs(panel, i, "indicators" not in self.plan.want[i] or bool(keep))
        attrs.update(store.PanelAttrs.section_run(method=integ.method, tol=integ.tol, dt=integ.dt, phi0=integ.phi0,
                                                  direction=integ.direction, crossings=integ.crossings,
                                                  wall_time=arrays["wall_time"]),
                     sections_hash=self.plan.want[i]["sections"], seeds_dropped=int(panel.dropped))
        attrs.update({k: v for k, v in keep.items() if k in store.INDICATOR_ATTRS})
        extra = {k: v for k, v in keep.items() if k in store.INDICATOR_DATASETS}
        _separatrices(self.scene, i, extra, attrs)
        blocks = None
        if arrays.get("streamed"):   # rows stored block by block: the panel written from the blocks
            attrs.update(block=int(self.specs["sections"].blocks[self.plan.todo["sections"].index(i)]),
                         resumed_blocks=self.streams.resumed.get(i, 0))
            blocks = self.streams.take(i)
        dh = store.write_panel(self.out, i, attrs, panel.seeds, panel.y0, arrays, rows=arrays.get("data"),
                               blocks=blocks, extra=extra, file_attrs=self.file_attrs)
        self.stats.add_sections(panel, arrays, dh, self.setting, integ.crossings)

    def _indicators_part(self, panel, i, arrays) -> tuple:
        """(payload, attrs) of panel i's indicators: the datasets, the map grid, the chaotic fraction."""
        payload = {k: arrays[k] for k in store.INDICATOR_DATASETS if k in arrays}
        attrs = {"indicators_hash": self.plan.want[i]["indicators"], "indicators_wall_time": arrays["wall_time"]}
        if panel.grid:
            n, a1, b1, a2, b2 = panel.grid
            attrs.update(map_resolution=int(n), map_p1=[float(a1), float(b1)], map_p2=[float(a2), float(b2)])
            if not self.plan.alone:
                payload["lyapunov_seeds"] = panel.seeds
        ind, thr = scene_class(self.scene)
        frac, err, _n_ok = sweep.panel_fraction(arrays, ind, thr)
        attrs.update(chaotic_fraction=frac, chaotic_fraction_error=err, class_indicator=ind, class_threshold=thr)
        self.stats.add_indicators(panel, arrays, (frac, err), self.ly_setting)
        return payload, attrs

    def indicators(self, panel, arrays) -> None:
        """Write panel ``panel``'s indicators: the whole panel when there are no sections, else
        beside its stored sections (which stay as they are)."""
        i, integ = panel.index, self.scene.integration
        payload, attrs = self._indicators_part(panel, i, arrays)
        self.stats.add_dropped(i, panel)   # 0 for a map grid
        if self.plan.alone:   # the panel is its seeds and their indicators (no crossings)
            attrs.update(self.panel_attrs(panel, i, True), phi0=float(integ.phi0), direction=int(integ.direction),
                         wall_time=arrays["wall_time"], seeds_dropped=int(panel.dropped))
            _separatrices(self.scene, i, payload, attrs)
            store.write_panel(self.out, i, attrs, panel.seeds, panel.y0, arrays, rows=arrays["data"], extra=payload,
                              file_attrs=self.file_attrs)
        else:
            attrs.update(self.panel_attrs(panel, i, True))
            stale = [k for k in store.INDICATOR_DATASETS + store.INDICATOR_ATTRS if k not in payload and k not in attrs]
            store.update_panel(self.out, i, payload, attrs, remove=stale)


def _count_statuses(counts: dict, status) -> None:
    """Add the orbits of each status code in ``status`` to ``counts`` (status name -> orbits)."""
    for code, n in zip(*np.unique(status, return_counts=True)):
        name = STATUS_NAMES[int(code)]
        counts[name] = counts.get(name, 0) + int(n)


def _separatrices(scene, i, payload, attrs) -> None:
    """With [compute] separatrices: panel i's fixed point (attrs) and separatrix branches (payload)."""
    if "separatrices" in scene.compute:
        fp_info, curves = panel_separatrices(scene, i)
        attrs["fixed_point"] = json.dumps(fp_info, sort_keys=True)
        if curves:
            payload["separatrix_offsets"] = np.concatenate([[0], np.cumsum([len(c) for c in curves])])
            payload["separatrix_points"] = np.concatenate(curves)


#: the PNG text key of the drawing settings a figure was drawn with (Scene.figure_settings)
FIGURE_SETTINGS_KEY = "explorer-figure-settings"


def _figure_stale(stem: Path, out: Path, settings: str) -> bool:
    """The figure ``stem`` (.png, .pdf) must be drawn again: a file is missing or older than the
    store ``out``, or the PNG was drawn with other drawing settings (or records none)."""
    from explorer.app.figures import png_text

    png, pdf = stem.with_suffix(".png"), stem.with_suffix(".pdf")
    if not png.exists() or not pdf.exists():
        return True
    if png.stat().st_mtime < out.stat().st_mtime or pdf.stat().st_mtime < out.stat().st_mtime:
        return True
    return png_text(png, FIGURE_SETTINGS_KEY) != settings


#: an atlas stores its finished cells at most this often (seconds; and when it ends or is interrupted)
ATLAS_COMMIT_SECONDS = 2.0


def run_atlas(scene, out=None, *, figure=None, draw=True, jobs=1, backend=None, scheduler=None, force=False,
              progress=True) -> SweepReport:
    """A two-parameter atlas (a scene with [atlas]): the chaotic fraction of every cell ([sweep] x
    [atlas] value), mapped as a sweep is and stored in one small file (:mod:`explorer.io.store.atlas`)
    rewritten atomically every :data:`ATLAS_COMMIT_SECONDS`, so a rerun with the same atlas hash
    computes only the cells it lacks; drawn as a heat map."""
    from explorer.app.atlas_figure import atlas_heatmap
    from explorer.app.figures import save_figure
    from explorer.io.store import atlas as atlas_store

    t_start = time.perf_counter()
    jobs = _check_jobs(jobs, backend, scheduler)
    out, stem = _outputs(scene, out, figure, draw)
    rows, cols = len(scene.sweep_values), len(scene.atlas_values)
    key = scene.atlas_hash()
    computed: tuple = ()
    orbits = 0
    with _guarded(out) as stop:
        held = _stored_atlas(out, force)
        if held is not None and held.attrs.get("scene_name") != scene.name and not force:
            raise ParameterError(f"--out {out} holds the atlas '{held.attrs.get('scene_name')}', not '{scene.name}'; "
                                 "use --force to replace it or choose another --out")
        if force or held is None or held.hash != key:
            held = None
        if held is None or not held.complete:
            frac = np.full((rows, cols), np.nan) if held is None else held.fraction.copy()
            err = np.full((rows, cols), np.nan) if held is None else held.error.copy()
            n_ok = np.zeros((rows, cols), np.int64) if held is None else held.orbits.copy()
            wall = np.zeros((rows, cols)) if held is None else held.wall_time.copy()
            done = np.zeros((rows, cols), bool) if held is None else held.done.copy()
            held_computed = None if held is None else held.computed
            computed_cells = np.full((rows, cols), np.nan) if held_computed is None else held_computed.copy()
            client = None
            if backend == "dask":
                client = _dask_client(scheduler, jobs)
                jobs = -1
            chunk_orbits = sweep.default_jobs_layout(1 if (jobs == 1 and backend is None) else 2)
            missing = {i for i in range(scene.n_cells) if not done.flat[i]}
            spec = sweep.build_atlas_spec(scene, chunk_orbits=chunk_orbits, cells=missing)
            done.flat[sorted(missing - {p.index for p in spec.panels})] = True   # no allowed region: gray
            last = [time.perf_counter(), 0]      # time of the last commit, cells since
            cls = scene_class(scene)

            def commit():
                atlas_store.write_atlas(out, scene_name=scene.name, scene_text=scene.text, hash=key,
                                        row_parameter=scene.sweep_parameter, column_parameter=scene.atlas_parameter,
                                        row_values=scene.sweep_values, column_values=scene.atlas_values,
                                        fraction=frac, error=err, orbits=n_ok, wall_time=wall,
                                        indicator=cls[0], threshold=cls[1],
                                        provenance=store.provenance({"scene": scene.name}), done=done,
                                        computed=computed_cells if scene.lyapunov.adaptive else None)
                last[:] = [time.perf_counter(), 0]

            def on_cell(panel, arrays):
                r, c = divmod(panel.index, cols)
                f, e, n = sweep.panel_fraction(arrays, *cls)
                frac[r, c], err[r, c], n_ok[r, c], wall[r, c] = f, e, n, arrays["wall_time"]
                if "map_computed" in arrays:
                    computed_cells[r, c] = np.mean(arrays["map_computed"])
                done[r, c] = True
                last[1] += 1
                if time.perf_counter() - last[0] >= ATLAS_COMMIT_SECONDS:
                    commit()

            try:
                _map_with_progress(spec, on_cell, jobs, backend, client, progress, f"atlas {scene.name}", None,
                                   _checker(stop, client))
            except KeyboardInterrupt:
                if last[1]:
                    commit()
                raise Interrupted(f"{int(done.sum())} of {done.size} cells stored in {out}; the same command "
                                  "continues from there") from None
            commit()
            computed = tuple(p.index for p in spec.panels)
            orbits = int(sum(len(p.y0) for p in spec.panels))
        figure_paths: tuple = ()
        if stop.requested:      # every cell is stored; the heat map is drawn by the next run
            raise Interrupted(f"all {scene.n_cells} cells stored in {out}; the same command draws the heat map")
        settings = scene.figure_settings()
        if draw and (computed or force or _figure_stale(stem, out, settings)):
            data = atlas_store.read_atlas(out)
            ly = scene.lyapunov
            time_ = sweep.map_time(ly) if ly.map_resolution else ly.time
            title = (f"{scene.name}: chaotic fraction\n{atlas_seeding(scene, data)}, "
                     f"{CLASS_NAMES[data.indicator]} time {time_:g}"
                     + (", early classification" if ly.early_stop else ""))
            figure_paths = tuple(save_figure(atlas_heatmap(data, title=title, dpi=scene.figure.dpi), stem,
                                             text={FIGURE_SETTINGS_KEY: settings}))
    return SweepReport(scene=scene.name, out=out, n_panels=scene.n_cells, computed=computed, orbits=orbits,
                       crossings=0, stopped=0, statuses={}, max_dh=0.0, warning=None, fractions=(),
                       threshold=scene_class(scene)[1], figure=figure_paths,
                       wall_time=time.perf_counter() - t_start, products={"cells": computed},
                       classified=class_text(*scene_class(scene)))


def atlas_seeding(scene, data) -> str:
    """How an atlas's cells are seeded, for its title: [seeds] n, or the map (and, adaptive, the
    fraction of its cells computed over the atlas)."""
    n = scene.lyapunov.map_resolution
    if not n:
        seeds = scene.seeds
        count = len(seeds.points) if seeds.kind == "points" and seeds.points is not None else seeds.n
        return f"{count} seeds per cell"
    text = f"a {n}x{n} map per cell"
    if data.computed is not None and np.isfinite(data.computed).any():
        text += f" ({float(np.nanmean(data.computed)):.0%} of map cells computed, adaptive)"
    return text


def _stored_atlas(out: Path, force: bool):
    """The atlas stored at ``out`` (None: no file); a file that is not an atlas is refused without
    ``force`` (with it, it is replaced)."""
    from explorer.io.store import atlas as atlas_store

    if not out.exists():
        return None
    try:
        return atlas_store.read_atlas(out)
    except (OSError, ValueError, KeyError) as exc:
        if force:
            return None
        raise ParameterError(f"--out {out}: not an explorer atlas file ({' '.join(str(exc).split())}); use --force "
                             "to replace it or choose another --out") from None


def _restamp_fractions(scene, out, stored) -> tuple:
    """The class threshold of seeds and of an exact map is outside the panel hash: a stored panel
    classified otherwise than the scene's class (:func:`scene_class`, :func:`stored_class`) gets its
    chaotic fraction recomputed from its stored indicators (an atomic attribute update).  Returns
    the panels restamped."""
    if "lyapunov" not in scene.compute or not stored:
        return ()
    ind, threshold = scene_class(scene)
    on_disk = store.panel_product_hashes(out)   # complete panels whose files are there
    done = []
    for i in stored:
        if i not in on_disk:
            continue
        extra, attrs = store.read_panel_datasets(out, i, store.INDICATOR_DATASETS)   # not the crossings
        if ind not in extra or stored_class(attrs) == (ind, threshold):
            continue
        frac, err, _n_ok = sweep.panel_fraction(extra, ind, threshold)
        store.update_panel_attrs(out, i, {"chaotic_fraction": frac, "chaotic_fraction_error": err,
                                          "class_indicator": ind, "class_threshold": threshold})
        done.append(i)
    return tuple(done)


def _map_with_progress(spec, on_panel, jobs, backend, client, progress, desc, streamer=None, check=None) -> None:
    """sweep.run with a progress bar on stderr (unless ``progress`` is false); the dask
    ``client`` (if any) is closed afterwards, whatever happens."""
    try:
        bar = _progress(len(spec.chunks), not progress, desc)
        try:
            sweep.run(spec, on_panel, jobs=jobs, backend="dask" if client is not None else backend,
                      progress=bar.update if bar is not None else None, streamer=streamer, check=check)
        finally:
            if bar is not None:
                bar.close()
    finally:
        if client is not None:
            client.close()


def _checker(stop, client):
    """``stop.check``, which first quiets the logs of a dask ``client`` (its cancelled tasks are not news)."""
    if client is None:
        return stop.check

    def check():
        if stop.requested:
            import logging

            for name in list(logging.root.manager.loggerDict):
                if name.split(".")[0] in ("distributed", "tornado"):
                    logging.getLogger(name).setLevel(logging.CRITICAL + 1)
        stop.check()
    return check


def _check_jobs(jobs, backend, scheduler) -> int:
    jobs = validation.integer("jobs", jobs, lo=1)
    if scheduler and backend != "dask":
        raise ParameterError("scheduler needs backend 'dask' (--scheduler needs --backend dask)")
    return jobs


def _outputs(scene, out, figure, draw) -> tuple[Path, Path]:
    """The store path [results/<scene>.h5] and figure stem [the store's path without .h5], both
    places checked writable."""
    out = Path(out) if out else Path("results") / f"{scene.name}.h5"
    stem = Path(figure) if figure else out.with_suffix("")   # beside the store (docs/commands/sweep.md)
    store.check_writable(out.parent, "--out", out)
    validation.output_path("--out", out)       # the default path too: a read-only store is never replaced
    if draw:
        store.check_writable(stem.parent, "--figure", stem)
    return out, stem


@contextlib.contextmanager
def _guarded(out: Path):
    """While a run writes ``out``: the store held (:func:`explorer.io.store.writing`) and Ctrl-C
    deferred to ``stop.check()``."""
    with interrupt.deferred_interrupt() as stop, store.writing(out):
        yield stop


def _check_same_scene(scene, out: Path, force: bool) -> None:
    """A store holds one scene (its ``scene_name``): another scene is refused without ``force``;
    with ``force`` the old store and its block folders are removed before anything is computed."""
    try:
        held = store.stored_scene_name(out)
    except store.StoreError as exc:
        if not force:
            raise ParameterError(str(exc)) from None
        held = ""
    if held is None or held == scene.name:
        return
    if not force:
        raise ParameterError(f"--out {out} holds the scene '{held}', not '{scene.name}'; use --force to replace it "
                             "or choose another --out")
    store.remove_store(out)
    stream.remove_stale_blocks(out)


def _kept(scene, out: Path, want) -> str:
    """What an interrupted sweep leaves in ``out``: the panels stored whole (every product with the
    scene's hash), the blocks of streamed ones."""
    try:
        on_disk = store.panel_product_hashes(out)
    except store.StoreError:
        on_disk = {}
    stored = sum(_stored_products(scene, i, on_disk.get(i, {}), w) == set(w) for i, w in enumerate(want))
    blocks = sum(len([n for n in os.listdir(d) if n.endswith(".npz")]) for d in stream.panel_block_dirs(out).values())
    return (f"{stored} of {len(want)} panels stored whole in {out}" + (f", {blocks} blocks of streamed panels kept"
            if blocks else "") + "; the same command continues from there")


def _check_disk(spec, out: Path) -> None:
    """Refuse up front a sweep whose rows may not fit on the disk of ``out`` (a streamed panel
    needs its rows twice while its store is written)."""
    need = 0
    for pos, panel in enumerate(spec.panels):
        if spec.sections:
            rows = sections.result_bytes(len(panel.y0), spec.crossings)
            need += 2 * rows if spec.streamed(pos) else rows
    store.check_disk(out.resolve().parent, need, f"scene: crossings = {spec.crossings} for "
                     f"{sum(len(p.y0) for p in spec.panels)} orbits", "lower [integration] crossings or the seeds")


def _progress(total, quiet, desc):
    if quiet or total == 0:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="chunk", file=sys.stderr, disable=None, leave=False)


def _dask_client(address, jobs):
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise ParameterError("--backend dask needs the 'distributed' package (pip install 'explorer[dask]')") from None
    if address:
        return Client(address)
    import logging

    # no dashboard, and the scheduler's HTTP routes on a free port: on its default, 8787, a second local
    # cluster (another sweep) made distributed warn on stderr that the port was in use
    cluster = LocalCluster(n_workers=max(1, jobs), threads_per_worker=1, processes=True, silence_logs=logging.ERROR,
                           scheduler_kwargs={"dashboard": False, "dashboard_address": ":0"})
    return _ClientWithCluster(Client(cluster), cluster)


class _ClientWithCluster:
    """A client to a local cluster this run started: closing it closes both."""

    def __init__(self, client, cluster):
        self.client = client
        self.cluster = cluster

    def close(self):
        self.client.close()
        self.cluster.close()

