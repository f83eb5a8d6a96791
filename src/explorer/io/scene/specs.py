"""The validated tables of a scene: [seeds], [integration], [lyapunov], [figure]."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from explorer.analysis import sections
from explorer.analysis.lyapunov import EARLY_STOP_METHODS, methods_for
from explorer.io.scene.checks import SceneError, _bool, _choice, _fail, _int, _list, _real
from explorer.io.scene.schema import (
    _FIGURE_KEYS,
    _INTEGRATION_KEYS,
    _LYAPUNOV_KEYS,
    _MANIFOLD_KEYS,
    _SEED_USED,
    DEFAULT_CROSSINGS,
    DEFAULT_DIFFUSION_ITERATES,
    DEFAULT_DPI,
    DEFAULT_MANIFOLD_ARCLENGTH,
    DEFAULT_MANIFOLD_POINTS,
    DEFAULT_MARGIN,
    DEFAULT_MARKER_SIZE,
    DEFAULT_RANDOM_SEED,
    DEFAULT_SEED_N,
    LAYOUTS,
    LYAPUNOV_INDICATORS,
    MAX_DIFFUSION_ITERATES,
    MAX_DPI,
    MAX_MANIFOLD_ARCLENGTH,
    MAX_MANIFOLD_PERIOD,
    MAX_MANIFOLD_POINTS,
    MAX_MAP_RESOLUTION,
    MAX_SEEDS,
    MIN_DPI,
    SEED_KINDS,
)
from explorer.kernels.indicator_table import BY_NAME as INDICATOR_BY_NAME
from explorer.kernels.indicator_table import DEFAULT_NAMES as INDICATOR_DEFAULTS
from explorer.kernels.indicator_table import ORBIT
from explorer.model import ParameterError


@dataclass(frozen=True)
class SeedSpec:
    """[seeds]: how initial conditions are placed on the section (docs/scenes.md); keys that
    ``kind`` does not use are validated and kept."""

    kind: str = "grid"
    n: int = DEFAULT_SEED_N
    margin: float = DEFAULT_MARGIN
    seed: int = DEFAULT_RANDOM_SEED
    lines: tuple | None = None
    points: tuple | None = None

    def __post_init__(self):
        kind = _choice("seeds.kind", self.kind, SEED_KINDS)
        n = _int("seeds.n", self.n, 1, MAX_SEEDS)
        margin = _real("seeds.margin", self.margin, 0.0, 1.0, lo_open=True)
        seed = _int("seeds.seed", self.seed, 0)
        lines = points = None
        if self.lines is not None:
            lines = []
            for i, seg in enumerate(_list("seeds.lines", self.lines)):
                k = f"seeds.lines[{i}]"
                seg = _list(k, seg)
                if len(seg) != 4:
                    _fail(k, f"must be [u_a, v_a, u_b, v_b] (4 numbers), got {len(seg)} items")
                lines.append(tuple(_real(k, x, -1.0, 1.0) for x in seg))
            lines = tuple(lines)
            if n * len(lines) > MAX_SEEDS:
                _fail("seeds.n", f"times the number of lines must be <= {MAX_SEEDS}, got {n} * {len(lines)}")
        if self.points is not None:
            pts = _list("seeds.points", self.points)
            if len(pts) > MAX_SEEDS:
                _fail("seeds.points", f"must have at most {MAX_SEEDS} points, got {len(pts)}")
            points = []
            for i, pt in enumerate(pts):
                k = f"seeds.points[{i}]"
                pt = _list(k, pt)
                if len(pt) != 2:
                    _fail(k, f"must be [p1, p2] (2 numbers), got {len(pt)} items")
                points.append((_real(k, pt[0]), _real(k, pt[1])))
            points = tuple(points)
        if kind == "lines" and lines is None:
            _fail("seeds.lines", "is required with kind = 'lines'")
        if kind == "points" and points is None:
            _fail("seeds.points", "is required with kind = 'points'")
        for name, value in (("kind", kind), ("n", n), ("margin", margin), ("seed", seed),
                            ("lines", lines), ("points", points)):
            object.__setattr__(self, name, value)

    def to_dict(self) -> dict:
        """All keys (as in the [seeds] table), JSON-able."""
        d = {"kind": self.kind, "n": self.n, "margin": self.margin, "seed": self.seed}
        if self.lines is not None:
            d["lines"] = [list(s) for s in self.lines]
        if self.points is not None:
            d["points"] = [list(p) for p in self.points]
        return d

    def used_dict(self) -> dict:
        """Only the keys that determine the points of this kind."""
        d = self.to_dict()
        return {k: d[k] for k in _SEED_USED[self.kind]}

    def points_on(self, smap):
        """The seed points (M, 2) on Chaplygin's section map ``smap`` (analysis.seeds.seed_points)."""
        from explorer.analysis.seeds import seed_points

        return np.column_stack(seed_points(self, smap.params, smap.h, smap.phi0)[:2])


@dataclass(frozen=True)
class IntegrationSpec(sections.Integration):
    """[integration]: the settings of a run of crossings (validated by
    :class:`explorer.analysis.sections.Integration`, refusals named by scene key); ``tmax`` None:
    100 * crossings (:attr:`effective_tmax`)."""

    crossings: int = DEFAULT_CROSSINGS

    def _label(self, name: str) -> str:
        return f"scene key 'integration.{name}'"

    def _refusal(self, exc: ParameterError) -> ParameterError:
        return SceneError(str(exc))

    def to_dict(self) -> dict:
        """All keys as in the [integration] table (tmax only when set)."""
        d = {k: getattr(self, k) for k in _INTEGRATION_KEYS}
        if self.tmax is None:
            del d["tmax"]
        return d

    def used_dict(self) -> dict:
        """The settings that determine the numbers: tol or dt by method, tmax resolved."""
        d = {"method": self.method, "crossings": self.crossings, "tmax": self.effective_tmax,
             "max_steps": self.max_steps, "phi0": self.phi0, "direction": self.direction}
        if self.adaptive:
            d["tol"] = self.tol
        else:
            d["dt"] = self.dt
        return d

    def section_kwargs(self) -> dict:
        """Keywords for ``sections.crossings(params, h, points, n_crossings=self.crossings, **kw)``."""
        d = self.used_dict()
        del d["crossings"]
        return d


def adaptive_map(ly) -> bool:
    """A [lyapunov] table's map is computed adaptively: a map grid without ``exact``, whatever its
    ``map_indicator`` (Chaplygin's scenes and a System's)."""
    return bool(ly.map_resolution and not ly.exact)


def class_settings(ly) -> dict:
    """For an atlas's hash, the class of a map of another indicator than MEGNO (whose ``threshold``
    the hash holds already): {"class": [indicator, threshold]}, else nothing."""
    from explorer.analysis.sweep import panel_class

    return {"class": list(panel_class(ly, True))} if ly.map_resolution and ly.map_indicator != "megno" else {}


def adaptive_settings(ly) -> dict:
    """What decides which cells an adaptive map computes, for its hashes: the refinement rule
    (explorer.analysis.sweep.map_rule), the map's indicator and its class threshold."""
    from explorer.analysis.sweep import map_rule, map_threshold

    return dict(map_rule(), indicator=ly.map_indicator, threshold=map_threshold(ly))


def map_entries(ly) -> dict:
    """The ``[lyapunov]`` keys of a chaos map that enter the panels' hashes only when set (a scene
    without them keeps its hashes): the map's resolution, its adaptive rule, frequency diffusion."""
    d = {}
    if ly.map_resolution:
        d["map_resolution"] = ly.map_resolution
    if ly.adaptive:   # which cells are computed depends on the class threshold and the rule
        d["adaptive"] = adaptive_settings(ly)
    if ly.frequency_diffusion is not None:
        d["frequency_diffusion"] = ly.frequency_diffusion
    return d


class DiffusionSettings:
    """Frequency diffusion's keys of a ``[lyapunov]`` table (``center``, ``diffusion_iterates``), shared by
    Chaplygin's :class:`LyapunovSpec` and a System's (docs/scenes.md)."""

    indicators: tuple
    center: Any
    diffusion_iterates: int
    tol: float

    def _check_diffusion(self):
        """``center`` a point [p1, p2], required with frequency_diffusion, and ``diffusion_iterates`` N."""
        if self.center is not None:
            c = _list("lyapunov.center", self.center)
            if len(c) != 2:
                _fail("lyapunov.center", f"must be a point [p1, p2] (two numbers), got {len(c)} items")
            object.__setattr__(self, "center", (_real("lyapunov.center[0]", c[0]), _real("lyapunov.center[1]", c[1])))
        object.__setattr__(self, "diffusion_iterates", _int("lyapunov.diffusion_iterates", self.diffusion_iterates,
                                                            10, MAX_DIFFUSION_ITERATES))
        if self.center is None and self._orbit_names():
            _fail("lyapunov.center", "is required with the indicator frequency_diffusion: the point [p1, p2] its "
                  "rotation numbers turn around, e.g. the elliptic fixed point of the island studied (docs/greene.md)")

    def _orbit_names(self) -> list:
        """The indicators asked for that the section map's returns give (frequency diffusion)."""
        return [q for q in self.indicators if INDICATOR_BY_NAME[q].row == ORBIT]

    @property
    def frequency_diffusion(self) -> dict | None:
        """The settings of the indicator frequency_diffusion when asked for (None otherwise): its
        centre, N and the Taylor tolerance of its section returns (``tol``, whatever the method)."""
        if self.center is None or not self._orbit_names():   # (__post_init__ refuses it without a centre)
            return None
        return {"center": list(self.center), "iterates": self.diffusion_iterates, "tol": self.tol}


@dataclass(frozen=True)
class LyapunovSpec(DiffusionSettings):
    """[lyapunov]: the chaos indicators of every seed (docs/scenes.md): integration settings and the
    MEGNO threshold above which an orbit counts as chaotic."""

    time: float = 1000.0
    method: str = "taylor"
    tol: float = sections.DEFAULT_TOL
    dt: float = sections.DEFAULT_DT
    threshold: float = 4.0
    #: what to compute (explorer.kernels.indicator_table: those of two deviation vectors, SALI
    #: and GALI_2, add a second one and need the methods their entry names)
    indicators: tuple = INDICATOR_DEFAULTS
    #: early classification (off by default; the rule: explorer.analysis.lyapunov.indicators)
    early_stop: bool = False
    early_sali: float = 1e-8
    early_megno: float = 8.0
    early_time: float = 100.0
    #: > 0: the indicators' seeds are the cell centres of a map_resolution^2 raster over the allowed
    #: region's bounding box (cells outside it are the forbidden region), drawn as an image of
    #: map_indicator; the sections keep the [seeds]
    map_resolution: int = 0
    map_indicator: str = "megno"
    #: false: a map is adaptive (explorer.analysis.chaos_map: a coarse lattice, refined where
    #: neighbours disagree by map_indicator's class or value, the rest filled); true: every cell computed
    exact: bool = False
    #: the indicator frequency_diffusion (explorer.analysis.rotation.frequency_diffusion): the point
    #: (p1, p2) its rotation numbers turn around, required with it (docs/greene.md, "Frequency
    #: diffusion": a decision, not found by Newton), and N (2N section returns per orbit)
    center: tuple | None = None
    diffusion_iterates: int = DEFAULT_DIFFUSION_ITERATES

    def __post_init__(self):
        object.__setattr__(self, "time", _real("lyapunov.time", self.time, 0.0, lo_open=True))
        object.__setattr__(self, "method", _choice("lyapunov.method", self.method, sections.METHODS))
        object.__setattr__(self, "tol", _real("lyapunov.tol", self.tol, sections.MIN_TOL, sections.MAX_TOL))
        object.__setattr__(self, "dt", _real("lyapunov.dt", self.dt, 0.0, lo_open=True))
        object.__setattr__(self, "threshold", _real("lyapunov.threshold", self.threshold, 2.0, lo_open=True))
        ind = tuple(_choice(f"lyapunov.indicators[{i}]", q, LYAPUNOV_INDICATORS)
                    for i, q in enumerate(_list("lyapunov.indicators", self.indicators)))
        object.__setattr__(self, "indicators", tuple(dict.fromkeys(ind)))
        object.__setattr__(self, "early_stop", _bool("lyapunov.early_stop", self.early_stop))
        object.__setattr__(self, "early_sali", _real("lyapunov.early_sali", self.early_sali, 0.0, 1.0))
        object.__setattr__(self, "early_megno", _real("lyapunov.early_megno", self.early_megno, 2.0, lo_open=True))
        object.__setattr__(self, "early_time", _real("lyapunov.early_time", self.early_time, 0.0))
        object.__setattr__(self, "map_resolution",
                           _int("lyapunov.map_resolution", self.map_resolution, 0, MAX_MAP_RESOLUTION))
        object.__setattr__(self, "map_indicator",
                           _choice("lyapunov.map_indicator", self.map_indicator, LYAPUNOV_INDICATORS))
        object.__setattr__(self, "exact", _bool("lyapunov.exact", self.exact))
        self._check_diffusion()
        if self.early_stop and self.method not in EARLY_STOP_METHODS:
            _fail("lyapunov.method", f"must be {' or '.join(repr(n) for n in EARLY_STOP_METHODS)} for early_stop; "
                  f"got {self.method!r}")
        for q in self.indicators:
            if self.method not in methods_for(q):
                _fail("lyapunov.method", f"must be one of {list(methods_for(q))} for {q}; got {self.method!r}")
        if self.map_resolution and self.map_indicator not in self.indicators:
            _fail("lyapunov.map_indicator", f"must be one of lyapunov.indicators {list(self.indicators)}; "
                  f"got {self.map_indicator!r}")

    @property
    def adaptive(self) -> bool:
        return adaptive_map(self)

    @property
    def second_vector(self) -> bool:
        """SALI or GALI_2 asked for: two deviation vectors."""
        return bool(self._two_vector_names())

    def _two_vector_names(self) -> list:
        """The indicators asked for that need two deviation vectors (the registry's EXTRA row)."""
        return sorted(q for q in self.indicators if INDICATOR_BY_NAME[q].vectors == 2)

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in _LYAPUNOV_KEYS}
        d["indicators"] = list(self.indicators)
        if self.center is None:   # TOML has no null: no key
            del d["center"]
        else:
            d["center"] = list(self.center)
        return d

    def used_dict(self) -> dict:
        """The keys that determine the numbers (tol or dt by method; the threshold only
        classifies, so it is left out of panel hashes)."""
        d = {"time": self.time, "method": self.method}
        if self.method in sections.ADAPTIVE_METHODS:
            d["tol"] = self.tol
        else:
            d["dt"] = self.dt
        # optional keys enter only when set, so a scene without them keeps its panels' hashes
        if self.second_vector:
            d["indicators"] = self._two_vector_names()
        if self.early_stop:
            d.update(early_stop=True, early_sali=self.early_sali if self.second_vector else 0.0,
                     early_megno=self.early_megno, early_time=self.early_time)
        d.update(map_entries(self))
        return d


@dataclass(frozen=True)
class FigureSpec:
    """How the panels are drawn (never affects the numbers nor the panel hashes)."""

    layout: str = "row"
    columns: int | None = None
    share_scale: bool = True
    own_scale: tuple = ()
    marker_size: float = DEFAULT_MARKER_SIZE
    dpi: int = DEFAULT_DPI

    def __post_init__(self):
        own = []
        for i, j in enumerate(_list("figure.own_scale", self.own_scale, min_len=0)):
            j = _int(f"figure.own_scale[{i}]", j, 0)
            if j in own:
                _fail(f"figure.own_scale[{i}]", f"duplicates panel index {j}")
            own.append(j)
        values = {
            "layout": _choice("figure.layout", self.layout, LAYOUTS),
            "columns": None if self.columns is None else _int("figure.columns", self.columns, 1),
            "share_scale": _bool("figure.share_scale", self.share_scale),
            "own_scale": tuple(own),
            "marker_size": _real("figure.marker_size", self.marker_size, 0.0, lo_open=True),
            "dpi": _int("figure.dpi", self.dpi, MIN_DPI, MAX_DPI),
        }
        for name, value in values.items():
            object.__setattr__(self, name, value)

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in _FIGURE_KEYS}
        d["own_scale"] = list(self.own_scale)
        if self.columns is None:
            del d["columns"]
        return d


@dataclass(frozen=True)
class ManifoldSpec:
    """[manifolds]: draw W^u and W^s of the orbit of ``period`` found by Newton from ``guess`` over
    each panel (docs/manifolds.md).  Drawing only: never in a panel's numbers or hashes."""

    draw: bool = False
    arclength: float = DEFAULT_MANIFOLD_ARCLENGTH
    guess: tuple = (0.0, 0.0)
    period: int = 1
    max_points: int = DEFAULT_MANIFOLD_POINTS

    def __post_init__(self):
        guess = _list("manifolds.guess", self.guess)
        if len(guess) != 2:
            _fail("manifolds.guess", f"must be [p1, p2] (2 numbers), got {len(guess)} items")
        values = {
            "draw": _bool("manifolds.draw", self.draw),
            "arclength": _real("manifolds.arclength", self.arclength, 0.0, MAX_MANIFOLD_ARCLENGTH, lo_open=True),
            "guess": tuple(_real(f"manifolds.guess[{i}]", x) for i, x in enumerate(guess)),
            "period": _int("manifolds.period", self.period, 1, MAX_MANIFOLD_PERIOD),
            "max_points": _int("manifolds.max_points", self.max_points, 3, MAX_MANIFOLD_POINTS),
        }
        for name, value in values.items():
            object.__setattr__(self, name, value)

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in _MANIFOLD_KEYS}
        d["guess"] = list(self.guess)
        return d
