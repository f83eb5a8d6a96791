"""Scenes: what a Poincaré-section sweep computes and how it is drawn, read from TOML.

A scene names the model parameters, the energy ``h``, an optional swept
parameter (one panel per value), how initial conditions are seeded on the
section phi = phi0 (docs/model.md R9), the integration settings (method,
tolerance or step, crossings per orbit, budgets), what to compute and how to
draw it.  Pure Python + numpy: no numba, h5py or matplotlib here.

Format
------
All tables are optional; ``name`` is the only required key.  The example
below shows every key (keys marked "grid only", "random only", ... are
accepted with any kind/layout but only used with theirs)::

    name = "figure4"                 # required, [A-Za-z0-9_.-]+ (not starting with '.')
    description = "..."              # optional free text
    [model]                          # any of a1 a2 b lam chi zeta mu xi eta; defaults = model.FIGURE4
    mu = 0.0
    [energy]
    h = 2.0                          # default model.FIGURE4_H
    [sweep]                          # optional; without it the scene has one panel
    parameter = "mu"                 # any model parameter name or "h"
    values = [0.05, 0.2, 0.5, 1.0, 2.0]   # non-empty list of finite numbers, no duplicates
    [seeds]
    kind = "grid"                    # "grid" | "lines" | "random" | "points"
    n = 200                          # grid: target points inside the region; random: count; lines: per line
    margin = 0.98                    # points stay inside the ellipse scaled by margin (0 < margin <= 1)
    seed = 12345                     # random only (numpy default_rng)
    lines = [[-1.0, 0.0, 1.0, 0.0]]  # lines only: segments [u_a, v_a, u_b, v_b], u, v in [-1, 1]
    points = [[0.1, 0.0], [0.3, 0.2]]  # points only: absolute (p1, p2)
    [integration]
    method = "taylor"                # one of sections.METHODS
    tol = 1e-13                      # adaptive methods (taylor, dop853), in [1e-16, 0.01]
    dt = 0.05                        # splitting methods (split*), > 0
    crossings = 1000                 # K >= 1
    tmax = 2e4                       # time budget per orbit (> 0); default 100 * crossings
    max_steps = 1000000000           # step budget per orbit (>= 1)
    phi0 = 3.141592653589793         # section angle; default pi (exactly math.pi)
    direction = 1                    # 1 (dphi/dt > 0), -1 (< 0) or 0 (both)
    [compute]
    sections = true                  # the only quantity for now; unknown keys are errors
    [figure]
    layout = "row"                   # "row" | "grid"
    columns = 3                      # grid only (default ceil(sqrt(panels)))
    share_scale = true               # same axes limits for all panels ...
    own_scale = [4]                  # ... except these panel indices
    marker_size = 0.25               # > 0
    dpi = 200                        # integer in [10, 2400]

Defaults of [seeds]: kind "grid", n 200, margin 0.98, seed 0.  Defaults of
[integration]: taylor, tol ``sections.DEFAULT_TOL``, dt ``sections.DEFAULT_DT``,
1000 crossings, max_steps ``sections.DEFAULT_MAX_STEPS``, phi0 = pi, direction 1.
Defaults of [figure]: row, share_scale true, own_scale [], marker_size 0.25, dpi 200.

Validation: unknown tables or keys, wrong types (a string or a boolean for a
number, a float for an integer; an integer is fine for a float) and values
out of range raise :class:`SceneError` (a :class:`model.ParameterError`)
with a one-line message naming the dotted key, e.g. ``scene key
'integration.tol' must be in [1e-16, 0.01], got 0.5``.  Every panel is
checked: its parameters must be valid (:class:`model.Params`) and its
allowed region of the section non-empty (error names ``sweep.values[i]``,
or ``energy.h`` when there is no sweep or no panel has a region).

Atlas
-----
An optional ``[atlas]`` table (``parameter``: a model parameter name or "h", not the [sweep]
parameter; ``values``: a non-empty list without duplicates) makes the scene a two-parameter
atlas: cell i = (row r, column c), i = r * len(atlas.values) + c, has the [sweep] value r and the
[atlas] value c (:meth:`Scene.cell`).  An atlas needs ``[compute]`` lyapunov = true,
sections = false, separatrices = false and no ``lyapunov.map_resolution``; it stores only the
chaotic fraction per cell (``explorer.io.store.atlas``), keyed by :meth:`Scene.atlas_hash`.
Cells whose allowed region is empty are left out (NaN, drawn gray).

Seeding
-------
The rules are in :mod:`explorer.analysis.seeds` (:func:`~explorer.analysis.seeds.seed_points`).

Panel hashes
------------
:meth:`Scene.panel_settings` lists everything that determines panel i's
numbers (its parameters, h, the seeding keys used by the kind, the
integration keys used by the method with tmax resolved, compute) and
:meth:`Scene.panel_hash` is the sha256 of its canonical JSON (sorted keys,
floats by ``repr``) together with :data:`FORMAT_VERSION`.  Name,
description, figure and the panel's position do not enter the hash.
The products of a panel, sections and indicators, have their own hashes
(:meth:`Scene.product_hashes`): a sweep recomputes only the product whose
settings changed.  :meth:`Scene.figure_settings` are the drawing settings.
"""
from __future__ import annotations

import hashlib
import json
import math
import numbers
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib


from explorer import model
from explorer.analysis import sections
from explorer.analysis.seeds import grid_spacing, seed_points  # noqa: F401  (re-exported)
from explorer.model import PARAM_NAMES, ParameterError, validation

#: Version of the panel-settings layout; part of every panel hash.
FORMAT_VERSION = 1

SEED_KINDS = ("grid", "lines", "random", "points")
LAYOUTS = ("row", "grid")
SWEEP_PARAMETERS = PARAM_NAMES + ("h",)
COMPUTE_QUANTITIES = ("sections", "lyapunov", "separatrices")
#: quantities computed when [compute] does not mention them
COMPUTE_DEFAULTS = {"sections": True, "lyapunov": False, "separatrices": False}

DEFAULT_SEED_N = 200
DEFAULT_MARGIN = 0.98
DEFAULT_RANDOM_SEED = 0
DEFAULT_CROSSINGS = 1000
DEFAULT_MARKER_SIZE = 0.25
DEFAULT_DPI = 200
MIN_DPI, MAX_DPI = 10, 2400
#: largest number of seeds per panel (n, n * len(lines), len(points))
MAX_SEEDS = 10_000_000
MAX_NAME_LENGTH = 128

_NAME_RE = re.compile(r"[A-Za-z0-9_.-]+\Z")
_TOP_KEYS = ("name", "description", "model", "energy", "sweep", "seeds", "integration", "compute", "lyapunov",
             "figure", "atlas")
_SEED_KEYS = ("kind", "n", "margin", "seed", "lines", "points")
#: the [seeds] keys that determine the points of each kind
_SEED_USED = {"grid": ("kind", "n", "margin"), "random": ("kind", "n", "margin", "seed"),
              "lines": ("kind", "n", "margin", "lines"), "points": ("kind", "points")}
_INTEGRATION_KEYS = ("method", "tol", "dt", "crossings", "tmax", "max_steps", "phi0", "direction")
_FIGURE_KEYS = ("layout", "columns", "share_scale", "own_scale", "marker_size", "dpi")
_LYAPUNOV_KEYS = ("time", "method", "tol", "dt", "threshold", "indicators", "early_stop", "early_sali", "early_megno",
                  "early_time", "map_resolution", "map_indicator")
#: the indicators a scene can ask for (explorer.analysis.lyapunov.INDICATOR_NAMES)
from explorer.kernels.indicator_table import NAMES as LYAPUNOV_INDICATORS  # noqa: E402  (the registry)

#: largest raster side of a chaos map ([lyapunov] map_resolution)
MAX_MAP_RESOLUTION = 4096


class SceneError(ParameterError):
    """Bad scene: a one-line message naming the dotted key and what is allowed."""


# ---------------------------------------------------------------- validators
def _short(v, limit=60) -> str:
    r = repr(v)
    return r if len(r) <= limit else r[: limit - 3] + "..."


def _fail(key, msg):
    raise SceneError(f"scene key '{key}' {msg}")


def _got(v) -> str:
    return f"got {_short(v)} ({type(v).__name__})"


def _checked(check, key, *args, **kwargs):
    """A value checked by :mod:`explorer.model.validation`, its refusal as a SceneError."""
    try:
        return check(f"scene key '{key}'", *args, **kwargs)
    except ParameterError as exc:
        raise SceneError(str(exc)) from None


def _real(key, v, lo=None, hi=None, lo_open=False) -> float:
    """A finite real number (int or float, not bool) in [lo, hi] (or (lo, hi] if lo_open)."""
    return _checked(validation.real, key, v, lo, hi, lo_open=lo_open)


def _int(key, v, lo=None, hi=None) -> int:
    return _checked(validation.integer, key, v, lo, hi)


def _bool(key, v) -> bool:
    return _checked(validation.boolean, key, v)


def _str(key, v) -> str:
    if not isinstance(v, str):
        _fail(key, f"must be a string, {_got(v)}")
    return v


def _choice(key, v, choices) -> str:
    return _checked(validation.choice, key, v, choices)


def _list(key, v, min_len=1) -> list:
    if not isinstance(v, (list, tuple)):
        _fail(key, f"must be a list, {_got(v)}")
    if len(v) < min_len:
        _fail(key, "must be a non-empty list" if min_len == 1 else f"must have at least {min_len} items")
    return list(v)


def _distinct_reals(key, seq) -> tuple:
    """The finite reals of the list ``key``, each once (a repeated value names both places)."""
    values: list = []
    for i, v in enumerate(_list(key, seq)):
        x = _real(f"{key}[{i}]", v)
        if x in values:
            _fail(f"{key}[{i}]", f"duplicates {key}[{values.index(x)}] = {x!r}")
        values.append(x)
    return tuple(values)


def _table(key, v, allowed) -> dict:
    """Check that ``v`` is a table whose keys are all in ``allowed``."""
    if not isinstance(v, dict):
        _fail(key, f"must be a table, {_got(v)}")
    for k in v:
        if k not in allowed:
            raise SceneError(f"scene: unknown key '{key}.{k}'{validation.did_you_mean(k, allowed)} "
                             f"(allowed: {', '.join(allowed)})")
    return v


# ---------------------------------------------------------------- specs
@dataclass(frozen=True)
class SeedSpec:
    """How initial conditions are placed on the section (see the module docstring).

    ``lines`` is a tuple of (u_a, v_a, u_b, v_b), ``points`` a tuple of (p1, p2);
    keys not used by ``kind`` are validated and kept but do not affect the seeds.
    """

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


@dataclass(frozen=True)
class IntegrationSpec:
    """Settings handed to :func:`explorer.analysis.sections.section_crossings`.

    ``tmax`` None means the default budget 100 * crossings (:attr:`effective_tmax`).
    """

    method: str = "taylor"
    tol: float = sections.DEFAULT_TOL
    dt: float = sections.DEFAULT_DT
    crossings: int = DEFAULT_CROSSINGS
    tmax: float | None = None
    max_steps: int = sections.DEFAULT_MAX_STEPS
    phi0: float = math.pi
    direction: int = 1

    def __post_init__(self):
        values = {
            "method": _choice("integration.method", self.method, sections.METHODS),
            "tol": _real("integration.tol", self.tol, sections.MIN_TOL, sections.MAX_TOL),
            "dt": _real("integration.dt", self.dt, 0.0, lo_open=True),
            "crossings": _int("integration.crossings", self.crossings, 1),
            "tmax": None if self.tmax is None else _real("integration.tmax", self.tmax, 0.0, lo_open=True),
            "max_steps": _int("integration.max_steps", self.max_steps, 1),
            "phi0": _real("integration.phi0", self.phi0),
            "direction": _int("integration.direction", self.direction),
        }
        if values["direction"] not in (-1, 0, 1):
            _fail("integration.direction", f"must be 1, -1 or 0 (both), got {values['direction']}")
        for name, value in values.items():
            object.__setattr__(self, name, value)

    @property
    def adaptive(self) -> bool:
        return self.method in sections.ADAPTIVE_METHODS

    @property
    def effective_tmax(self) -> float:
        return 100.0 * self.crossings if self.tmax is None else self.tmax

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
        """Keywords for ``sections.section_crossings(params, p1, p2, h, self.crossings, **kw)``."""
        d = self.used_dict()
        del d["crossings"]
        return d


@dataclass(frozen=True)
class LyapunovSpec:
    """Chaos indicators of every seed (:func:`explorer.analysis.lyapunov.indicators`): integration time,
    method and tolerance/step, and the MEGNO threshold above which an orbit counts as chaotic
    (regular orbits have <Y> -> 2, chaotic ones <Y> ~ chi T / 2)."""

    time: float = 1000.0
    method: str = "taylor"
    tol: float = sections.DEFAULT_TOL
    dt: float = sections.DEFAULT_DT
    threshold: float = 4.0
    #: what to compute ("sali"/"gali2" add a second deviation vector; Taylor method)
    indicators: tuple = ("mlce", "megno", "fli")
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
        if (self.early_stop or {"sali", "gali2"} & set(self.indicators)) and self.method != "taylor":
            _fail("lyapunov.method", f"must be 'taylor' for early_stop, sali and gali2; got {self.method!r}")
        if self.map_resolution and self.map_indicator not in self.indicators:
            _fail("lyapunov.map_indicator", f"must be one of lyapunov.indicators {list(self.indicators)}; "
                  f"got {self.map_indicator!r}")

    @property
    def second_vector(self) -> bool:
        """SALI or GALI_2 asked for: two deviation vectors."""
        return bool({"sali", "gali2"} & set(self.indicators))

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in _LYAPUNOV_KEYS}
        d["indicators"] = list(self.indicators)
        return d

    def used_dict(self) -> dict:
        """The keys that determine the numbers (tol or dt by method; the threshold only
        classifies, so it is left out of panel hashes)."""
        d = {"time": self.time, "method": self.method}
        if self.method in sections.ADAPTIVE_METHODS:
            d["tol"] = self.tol
        else:
            d["dt"] = self.dt
        # keys added by issue 10 enter only when they differ from what was computed before them,
        # so the panels stored by earlier scenes keep their hashes
        if self.second_vector:
            d["indicators"] = sorted({"sali", "gali2"} & set(self.indicators))
        if self.early_stop:
            d.update(early_stop=True, early_sali=self.early_sali if self.second_vector else 0.0,
                     early_megno=self.early_megno, early_time=self.early_time)
        if self.map_resolution:
            d["map_resolution"] = self.map_resolution
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


def _canonical_json(obj) -> str:
    """Sorted keys, no spaces, floats by repr (json's float formatting), no NaN."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False, ensure_ascii=True)


@dataclass(frozen=True)
class Scene:
    """A Poincaré-section sweep: one panel per sweep value (one panel without a sweep).

    Validated on construction (every panel's parameters and allowed region);
    ``text`` is the TOML source ("" for a scene built in Python; see :meth:`to_toml`).
    """

    name: str
    params: model.Params = model.FIGURE4
    h: float = model.FIGURE4_H
    sweep_parameter: str | None = None
    sweep_values: tuple = ()
    seeds: SeedSpec = field(default_factory=SeedSpec)
    integration: IntegrationSpec = field(default_factory=IntegrationSpec)
    compute: tuple = ("sections",)
    lyapunov: LyapunovSpec = field(default_factory=LyapunovSpec)
    figure: FigureSpec = field(default_factory=FigureSpec)
    description: str = ""
    text: str = ""
    atlas_parameter: str | None = None   # [atlas]: the second swept parameter (columns of the atlas)
    atlas_values: tuple = ()

    def __post_init__(self):
        name = _str("name", self.name)
        if not _NAME_RE.match(name) or name.startswith(".") or len(name) > MAX_NAME_LENGTH:
            _fail("name", f"must match [A-Za-z0-9_.-]+, not start with '.', and have at most "
                  f"{MAX_NAME_LENGTH} characters; got {_short(name)}")
        _str("description", self.description)
        _str("text", self.text)
        if not isinstance(self.params, model.Params):
            _fail("model", f"must be a model.Params, {_got(self.params)}")
        object.__setattr__(self, "h", _checked(validation.magnitude, "energy.h", self.h))
        for attr, cls, key in (("seeds", SeedSpec, "seeds"), ("integration", IntegrationSpec, "integration"),
                               ("figure", FigureSpec, "figure")):
            if not isinstance(getattr(self, attr), cls):
                _fail(key, f"must be a {cls.__name__}, {_got(getattr(self, attr))}")
        self._check_sweep()
        compute = tuple(_choice(f"compute[{i}]", q, COMPUTE_QUANTITIES)
                        for i, q in enumerate(_list("compute", self.compute, min_len=0)))
        if "sections" not in compute and "lyapunov" not in compute:
            _fail("compute.sections", "must be true unless compute.lyapunov is (a scene of chaos indicators only "
                  "stores no crossings)")
        if not isinstance(self.lyapunov, LyapunovSpec):
            _fail("lyapunov", f"must be a LyapunovSpec, {_got(self.lyapunov)}")
        if self.lyapunov.map_resolution and "lyapunov" not in compute:
            _fail("lyapunov.map_resolution", "needs compute.lyapunov = true")
        object.__setattr__(self, "compute", compute)
        self._check_atlas()
        self._check_panels()
        for j, idx in enumerate(self.figure.own_scale):
            if idx >= self.n_panels:
                _fail(f"figure.own_scale[{j}]", f"must be a panel index in [0, {self.n_panels - 1}], got {idx}")

    def _check_sweep(self):
        if self.sweep_parameter is None:
            if len(self.sweep_values):
                _fail("sweep.parameter", "is required when sweep values are given")
            object.__setattr__(self, "sweep_values", ())
            return
        _choice("sweep.parameter", self.sweep_parameter, SWEEP_PARAMETERS)
        object.__setattr__(self, "sweep_values", _distinct_reals("sweep.values", self.sweep_values))

    def _panel_key(self, i) -> str:
        return "energy.h" if self.sweep_parameter is None else f"sweep.values[{i}]"

    def _check_panels(self):
        phi0 = self.integration.phi0
        empty = []
        for i in range(self.n_panels):
            try:
                prm, h, label = self.panel(i)
            except ParameterError as e:
                raise SceneError(f"scene key '{self._panel_key(i)}' ({self._label(i)}): {e}") from None
            ell = model.allowed_ellipse(prm, h, phi0)
            if ell is None or not (ell[2] > 0.0 and ell[3] > 0.0):
                empty.append(i)
        if empty:
            i = empty[0]
            key = self._panel_key(i)
            if self.sweep_parameter not in (None, "h") and len(empty) == self.n_panels:
                key = "energy.h"
            h = self.panel_h(i)
            what = f"= {h!r}" if key == "energy.h" else f"({self._label(i)})"
            _fail(key, f"{what}: the allowed region of the section phi0 = {phi0!r} at h = {h!r} is empty "
                  f"(h is below the minimum of the energy on the section)")
        if self.seeds.kind in ("lines", "points"):
            for i in range(self.n_panels):
                p1, _p2, _dropped = self.panel_seeds(i)
                if p1.size == 0:
                    where = f" of panel {i} ({self._label(i)})" if self.sweep_parameter is not None else ""
                    _fail(f"seeds.{self.seeds.kind}", f"gives no point inside the allowed region{where}")

    # ------------------------------------------------------------ panels
    @property
    def n_panels(self) -> int:
        return max(1, len(self.sweep_values))

    def _check_index(self, i):
        if isinstance(i, bool) or not isinstance(i, numbers.Integral) or not 0 <= i < self.n_panels:
            raise IndexError(f"panel index must be an integer in [0, {self.n_panels - 1}], got {i!r}")
        return int(i)

    def _label(self, i) -> str:
        if self.sweep_parameter is None:
            return ""
        return f"{self.sweep_parameter} = {self.sweep_values[i]!r}"

    def panel_h(self, i) -> float:
        i = self._check_index(i)
        return self.sweep_values[i] if self.sweep_parameter == "h" else self.h

    def panel(self, i):
        """(Params, h, label) of panel i; label is e.g. ``"mu = 0.5"`` ("" without a sweep)."""
        i = self._check_index(i)
        prm = self.params
        if self.sweep_parameter in PARAM_NAMES:
            prm = prm.with_(**{self.sweep_parameter: self.sweep_values[i]})
        return prm, self.panel_h(i), self._label(i)

    def panel_seeds(self, i):
        """:func:`seed_points` of panel i: (p1, p2, n_dropped)."""
        prm, h, _label = self.panel(i)
        return seed_points(self.seeds, prm, h, self.integration.phi0)

    def panel_settings(self, i) -> dict:
        """Everything that determines panel i's numbers, as plain JSON-able values."""
        prm, h, _label = self.panel(i)
        d = {"params": prm.as_dict(), "h": h, "seeds": self.seeds.used_dict(),
             "integration": self.integration.used_dict(), "compute": {q: True for q in self.compute}}
        if "lyapunov" in self.compute:
            d["lyapunov"] = self.lyapunov.used_dict()
        return d

    def panel_hash(self, i) -> str:
        """sha256 hex of the canonical JSON of panel_settings(i) and FORMAT_VERSION: the whole
        panel (every product); stored as the panel's ``hash``."""
        payload = {"format_version": FORMAT_VERSION, "panel": self.panel_settings(i)}
        return hashlib.sha256(_canonical_json(payload).encode("ascii")).hexdigest()

    def product_settings(self, i) -> dict:
        """What determines each product of panel i, {product: settings}: ``"sections"`` (when
        [compute] sections: the crossings of the [seeds] and, with separatrices, the fixed point's
        separatrices) and ``"indicators"`` (when [compute] lyapunov: the indicators of the [seeds],
        or of the map's grid when [lyapunov] map_resolution > 0).  Each is recomputed only when
        its own settings change (:meth:`product_hashes`)."""
        prm, h, _label = self.panel(i)
        base = {"params": prm.as_dict(), "h": h}
        out = {}
        if "sections" in self.compute:
            out["sections"] = dict(base, seeds=self.seeds.used_dict(), integration=self.integration.used_dict(),
                                   separatrices="separatrices" in self.compute)
        if "lyapunov" in self.compute:
            ly = self.lyapunov.used_dict()
            grid = ly.pop("map_resolution", 0)
            d = dict(base, seeds={"map_resolution": grid} if grid else self.seeds.used_dict(),
                     phi0=self.integration.phi0, direction=self.integration.direction, lyapunov=ly)
            if "sections" not in self.compute:   # the indicators are the whole panel, separatrices included
                d["alone"] = {"separatrices": "separatrices" in self.compute}
            out["indicators"] = d
        return out

    def product_hashes(self, i) -> dict:
        """{product: sha256 hex of the canonical JSON of its settings and FORMAT_VERSION}
        (:meth:`product_settings`); stored as the panel's ``sections_hash`` / ``indicators_hash``."""
        return {k: hashlib.sha256(_canonical_json({"format_version": FORMAT_VERSION, k: v}).encode("ascii"))
                .hexdigest() for k, v in self.product_settings(i).items()}

    def figure_settings(self) -> str:
        """Canonical JSON of everything that changes the drawing but not the numbers ([figure], and
        with [compute] lyapunov the MEGNO threshold and map_indicator): kept in the PNG, so a rerun
        redraws the figure when they change, without recomputing."""
        d: dict = {"figure": self.figure.to_dict()}
        if "lyapunov" in self.compute:
            d.update(threshold=self.lyapunov.threshold, map_indicator=self.lyapunov.map_indicator)
        return _canonical_json(d)

    def grid_shape(self) -> tuple:
        """(rows, columns) of the figure: (1, n) for "row"; for "grid" ``columns``
        (default ceil(sqrt(n))) and as many rows as needed."""
        n = self.n_panels
        if self.figure.layout == "row":
            return 1, n
        cols = self.figure.columns if self.figure.columns is not None else math.ceil(math.sqrt(n))
        cols = min(cols, n)
        return -(-n // cols), cols

    # ------------------------------------------------------------ atlas
    def _check_atlas(self):
        """[atlas]: a scene of two swept parameters, [sweep] (rows) x [atlas] (columns), storing
        only the chaotic fraction per cell (indicators only)."""
        if self.atlas_parameter is None:
            if len(self.atlas_values):
                _fail("atlas.parameter", "is required when atlas values are given")
            object.__setattr__(self, "atlas_values", ())
            return
        _choice("atlas.parameter", self.atlas_parameter, SWEEP_PARAMETERS)
        if self.sweep_parameter is None:
            _fail("sweep.parameter", "is required in an atlas scene (the atlas sweeps [sweep] x [atlas])")
        if self.atlas_parameter == self.sweep_parameter:
            _fail("atlas.parameter", f"must differ from sweep.parameter ({self.sweep_parameter!r})")
        if "lyapunov" not in self.compute or "sections" in self.compute or "separatrices" in self.compute:
            _fail("compute", "of an atlas scene must be lyapunov = true, sections = false, separatrices = false "
                  "(an atlas stores only the chaotic fraction per cell)")
        if self.lyapunov.map_resolution:
            _fail("lyapunov.map_resolution", "is not used by an atlas scene (its cells are seeded by [seeds])")
        object.__setattr__(self, "atlas_values", _distinct_reals("atlas.values", self.atlas_values))
        for i in range(self.n_cells):
            try:
                self.cell(i)
            except ParameterError as e:
                r, c = divmod(i, len(self.atlas_values))
                raise SceneError(f"scene key 'atlas.values[{c}]' ({self._cell_label(r, c)}): {e}") from None

    @property
    def is_atlas(self) -> bool:
        return self.atlas_parameter is not None

    @property
    def n_cells(self) -> int:
        """Cells of an atlas: len(sweep.values) x len(atlas.values) (0 for other scenes)."""
        return len(self.sweep_values) * len(self.atlas_values) if self.is_atlas else 0

    def _cell_label(self, r, c) -> str:
        return (f"{self.sweep_parameter} = {self.sweep_values[r]!r}, "
                f"{self.atlas_parameter} = {self.atlas_values[c]!r}")

    def cell(self, i):
        """(Params, h, label) of atlas cell i = row * len(atlas.values) + column (row: sweep value,
        column: atlas value)."""
        if not self.is_atlas or isinstance(i, bool) or not isinstance(i, numbers.Integral) \
                or not 0 <= i < self.n_cells:
            raise IndexError(f"atlas cell index must be an integer in [0, {self.n_cells - 1}], got {i!r}")
        r, c = divmod(int(i), len(self.atlas_values))
        upd, h = {}, self.h
        for name, v in ((self.sweep_parameter, self.sweep_values[r]), (self.atlas_parameter, self.atlas_values[c])):
            if name == "h":
                h = v
            else:
                upd[name] = v
        return self.params.with_(**upd), h, self._cell_label(r, c)

    def cell_allowed(self, i) -> bool:
        """The allowed region of the section of cell i is non-empty (else the cell is drawn gray)."""
        prm, h, _label = self.cell(i)
        ell = model.allowed_ellipse(prm, h, self.integration.phi0)
        return ell is not None and ell[2] > 0.0 and ell[3] > 0.0

    def atlas_hash(self) -> str:
        """sha256 of everything that determines an atlas's numbers (both axes, the model, h, seeds,
        integration and [lyapunov] settings; not name, description or figure)."""
        d = {"params": self.params.as_dict(), "h": self.h, "rows": [self.sweep_parameter, list(self.sweep_values)],
             "columns": [self.atlas_parameter, list(self.atlas_values)], "seeds": self.seeds.used_dict(),
             "phi0": self.integration.phi0, "direction": self.integration.direction,
             "lyapunov": self.lyapunov.used_dict(), "threshold": self.lyapunov.threshold}
        payload = {"format_version": FORMAT_VERSION, "atlas": d}
        return hashlib.sha256(_canonical_json(payload).encode("ascii")).hexdigest()

    # ------------------------------------------------------------ export
    def to_dict(self) -> dict:
        """The scene as nested plain values in the layout of the TOML tables
        (``scene_from_dict(s.to_dict(), s.text) == s``)."""
        d = {"name": self.name, "description": self.description, "model": self.params.as_dict(),
             "energy": {"h": self.h}}
        if self.sweep_parameter is not None:
            d["sweep"] = {"parameter": self.sweep_parameter, "values": list(self.sweep_values)}
        d["seeds"] = self.seeds.to_dict()
        d["integration"] = self.integration.to_dict()
        d["compute"] = {q: (q in self.compute) for q in COMPUTE_QUANTITIES}
        d["lyapunov"] = self.lyapunov.to_dict()
        d["figure"] = self.figure.to_dict()
        if self.atlas_parameter is not None:
            d["atlas"] = {"parameter": self.atlas_parameter, "values": list(self.atlas_values)}
        return d

    def to_toml(self) -> str:
        """TOML text of :meth:`to_dict` (``parse_scene(s.to_toml())`` equals ``s`` but for ``text``)."""
        d = self.to_dict()
        out = []
        for k in ("name", "description"):
            out.append(f"{k} = {_toml_value(d[k])}")
        for table in _TOP_KEYS[2:]:
            if table in d:
                out.append(f"\n[{table}]")
                out.extend(f"{k} = {_toml_value(v)}" for k, v in d[table].items())
        return "\n".join(out) + "\n"


def _toml_string(s: str) -> str:
    r = json.dumps(s, ensure_ascii=False)  # TOML basic strings share JSON's escapes
    return r.replace("\x7f", "\\u007f")


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, numbers.Integral):
        return str(int(v))
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return _toml_string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} as TOML")


# ---------------------------------------------------------------- loading
def scene_from_dict(data: dict, text: str = "") -> Scene:
    """A validated :class:`Scene` from nested tables (as produced by ``tomllib``)."""
    if not isinstance(data, dict):
        _fail("<top level>", f"must be a table, {_got(data)}")
    for k, v in data.items():
        if k not in _TOP_KEYS:
            what = "table" if isinstance(v, dict) else "key"
            raise SceneError(f"scene: unknown {what} '{k}'{validation.did_you_mean(k, _TOP_KEYS)} "
                             f"(allowed: {', '.join(_TOP_KEYS)})")
    if "name" not in data:
        _fail("name", "is required (a string matching [A-Za-z0-9_.-]+)")
    kw = {"name": data["name"], "description": data.get("description", ""), "text": text}

    given = _table("model", data.get("model", {}), PARAM_NAMES)
    values = {k: _real(f"model.{k}", v) for k, v in given.items()}
    try:
        kw["params"] = model.FIGURE4.with_(**values)
    except ParameterError as e:
        msg = str(e)
        bad = next((k for k in values if msg.startswith(k + " ")), None)
        raise SceneError(f"scene key 'model.{bad}': {msg}" if bad else f"scene key 'model': {msg}") from None

    energy = _table("energy", data.get("energy", {}), ("h",))
    if "h" in energy:
        kw["h"] = energy["h"]

    if "sweep" in data:
        sweep = _table("sweep", data["sweep"], ("parameter", "values"))
        for k in ("parameter", "values"):
            if k not in sweep:
                _fail(f"sweep.{k}", "is required in a [sweep] table")
        kw["sweep_parameter"] = _str("sweep.parameter", sweep["parameter"])
        kw["sweep_values"] = tuple(_list("sweep.values", sweep["values"]))

    kw["seeds"] = SeedSpec(**_table("seeds", data.get("seeds", {}), _SEED_KEYS))
    kw["integration"] = IntegrationSpec(**_table("integration", data.get("integration", {}), _INTEGRATION_KEYS))

    comp = _table("compute", data.get("compute", {}), COMPUTE_QUANTITIES)
    kw["compute"] = tuple(q for q in COMPUTE_QUANTITIES
                          if _bool(f"compute.{q}", comp.get(q, COMPUTE_DEFAULTS[q])))
    ly = dict(_table("lyapunov", data.get("lyapunov", {}), _LYAPUNOV_KEYS))
    if "indicators" in ly:
        ly["indicators"] = tuple(_list("lyapunov.indicators", ly["indicators"]))
    kw["lyapunov"] = LyapunovSpec(**ly)

    fig = dict(_table("figure", data.get("figure", {}), _FIGURE_KEYS))
    if "own_scale" in fig:
        fig["own_scale"] = tuple(_list("figure.own_scale", fig["own_scale"], min_len=0))
    kw["figure"] = FigureSpec(**fig)
    kw.update(_atlas_from_dict(data))
    return Scene(**kw)


def _atlas_from_dict(data: dict) -> dict:
    if "atlas" not in data:
        return {}
    atlas = _table("atlas", data["atlas"], ("parameter", "values"))
    for k in ("parameter", "values"):
        if k not in atlas:
            _fail(f"atlas.{k}", "is required in an [atlas] table")
    return {"atlas_parameter": _str("atlas.parameter", atlas["parameter"]),
            "atlas_values": tuple(_list("atlas.values", atlas["values"]))}


def parse_scene(text: str, source: str = "<string>") -> Scene:
    """A validated :class:`Scene` from TOML text (``source`` names it in syntax errors)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        msg = " ".join(str(e).split())
        raise SceneError(f"scene: TOML syntax error in {source}: {msg}") from None
    return scene_from_dict(data, text=text)


def load_scene(spec) -> Scene:
    """A scene: a built-in preset by name (``figure4``, ``chaos``, ``fraction``: :data:`PRESETS`,
    the TOML files of ``explorer/io/presets``), else the path of a ``.toml`` file, validated
    (every bad key or value raises :class:`SceneError` naming the dotted key).

    Returns
    -------
    Scene
        Parameters, energy, the swept parameter, seeds, integration and figure settings; each
        panel's settings hash (:meth:`Scene.panel_hash`) decides what a sweep recomputes.
    """
    if isinstance(spec, str) and spec in PRESETS:
        return parse_scene(PRESETS[spec], source=f"preset '{spec}'")
    path = Path(os.fspath(spec))
    if not path.is_file():
        raise SceneError(f"scene: no built-in preset or file named '{path}' "
                         f"(presets: {', '.join(sorted(PRESETS))})")
    try:
        text = path.read_bytes().decode("utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SceneError(f"scene: cannot read '{path}': {' '.join(str(e).split())}") from None
    return parse_scene(text, source=str(path))


# ---------------------------------------------------------------- presets
def _read_presets() -> dict:
    """Built-in scenes: name -> TOML text, from the files ``explorer/io/presets/*.toml``."""
    from importlib.resources import files

    folder = files("explorer.io").joinpath("presets")
    return {f.name[:-5]: f.read_text(encoding="utf-8")
            for f in sorted(folder.iterdir(), key=lambda f: f.name) if f.name.endswith(".toml")}


#: Built-in scenes: name -> TOML text (``src/explorer/io/presets/<name>.toml``, each complete).
PRESETS = _read_presets()
