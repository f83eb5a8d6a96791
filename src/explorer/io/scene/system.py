"""A scene of a System (docs/scenes.md, "A scene of your own system"): ``system = "module:attribute"``
names an :class:`explorer.System` (or a callable returning one); ``section``, ``direction``,
``coords``, ``solve`` and the energy make the section map each panel iterates.  The scene's text is
never evaluated: the module it names is the only code run, and ``section`` is read as arithmetic
of numbers and the system's symbols."""
from __future__ import annotations

import ast
import importlib
import operator
import os
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from explorer.io.scene import atlas as _atlas
from explorer.io.scene.checks import (
    SceneError,
    _bool,
    _choice,
    _distinct_reals,
    _fail,
    _got,
    _int,
    _list,
    _own_scale,
    _real,
    _scene_name,
    _short,
    _str,
    _sweep,
    _swept,
    _table,
)
from explorer.io.scene.core import Scene
from explorer.io.scene.hashes import _canonical_json, _sha256
from explorer.io.scene.schema import (
    _FIGURE_KEYS,
    _MANIFOLD_KEYS,
    DEFAULT_DIFFUSION_ITERATES,
    FORMAT_VERSION,
    MAX_MAP_RESOLUTION,
    MAX_SEEDS,
)
from explorer.io.scene.specs import (
    DiffusionSettings,
    FigureSpec,
    ManifoldSpec,
    SeedSpec,
    adaptive_map,
    class_settings,
    map_entries,
)
from explorer.kernels.indicator_table import NAMES as INDICATOR_NAMES
from explorer.model import ParameterError

#: the keys of a System's scene (Chaplygin's [model] and [energy] h are not among them)
SYSTEM_TOP_KEYS = ("name", "description", "system", "section", "direction", "coords", "solve", "parameters",
                   "energy", "sweep", "atlas", "seeds", "integration", "compute", "lyapunov", "figure", "manifolds")
SYSTEM_SEED_KINDS = ("grid", "random", "points")
_SEED_KEYS = ("kind", "n", "seed", "points", "window")
_INTEGRATION_KEYS = ("method", "crossings", "tol", "tmax", "max_steps")
_LYAPUNOV_KEYS = ("time", "tol", "threshold", "map_resolution", "indicators", "map_indicator", "exact", "center",
                  "diffusion_iterates")
_COMPUTE_KEYS = ("sections", "lyapunov", "separatrices")
#: the swept name of the energy level (a parameter of the system may not take it)
ENERGY = "energy"
#: longest section expression read from a scene
MAX_EXPRESSION = 500
_OPERATORS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv}


def resolve_system(value, label: str = "system", maps: bool = False):
    """The System named by ``value``, ``"module:attribute"`` (the module imported from the current
    directory or ``sys.path``; the attribute a System or a callable returning one; with ``maps``
    also a System's section map), or a System itself.  ParameterError naming the value otherwise."""
    from explorer.analysis.system_sections import is_system, is_system_map

    def is_system_or_map(obj):
        return is_system(obj) or (maps and is_system_map(obj))

    if is_system_or_map(value):
        return value
    form = f"{label} must be 'module:attribute' naming an explorer System, e.g. my_systems:henon_heiles"
    if not isinstance(value, str) or value.count(":") != 1:
        raise ParameterError(f"{form}; got {_short(value)}")
    mod_name, attr = (s.strip() for s in value.split(":"))
    if not all(p.isidentifier() for p in mod_name.split(".")) or not all(p.isidentifier() for p in attr.split(".")):
        raise ParameterError(f"{form}; got {value!r}")
    try:
        module = _import(mod_name)
    except ModuleNotFoundError as exc:
        if exc.name and (mod_name == exc.name or mod_name.startswith(exc.name + ".")):
            raise ParameterError(f"{label} {value!r}: no module named {mod_name!r} in the current directory or "
                                 "on sys.path") from None
        raise ParameterError(f"{label} {value!r}: importing {mod_name} failed: {exc}") from None
    except Exception as exc:   # the user's module raised: one line, not its traceback
        raise ParameterError(f"{label} {value!r}: importing {mod_name} failed: {type(exc).__name__}: {exc}") \
            from None
    obj = module
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ParameterError(f"{label} {value!r}: module {mod_name} has no attribute {attr!r}")
        obj = getattr(obj, part)
    if not is_system_or_map(obj) and callable(obj) and not isinstance(obj, type):
        try:
            obj = obj()
        except Exception as exc:
            raise ParameterError(f"{label} {value!r}: calling {attr}() failed: {type(exc).__name__}: {exc}") \
                from None
    if not is_system_or_map(obj):
        raise ParameterError(f"{label} {value!r} is a {type(obj).__name__}, not an explorer System "
                             f"{'or its section map ' if maps else ''}(nor a callable returning one)")
    return obj


def _import(name: str):
    """``importlib.import_module(name)`` with the current directory on the path (as ``python -m``)."""
    cwd = os.getcwd()
    added = cwd not in sys.path and "" not in sys.path
    if added:
        sys.path.insert(0, cwd)
    importlib.invalidate_caches()
    try:
        return importlib.import_module(name)
    finally:
        if added and cwd in sys.path:
            sys.path.remove(cwd)


def parse_expression(text, system, key: str):
    """The SymPy expression of ``text``: numbers, the state variables and parameters of ``system``,
    ``+ - * /`` and parentheses; anything else is a SceneError naming ``key`` (nothing is evaluated)."""
    import sympy as sp

    names = {s.name: s for s in (*system.states, *system.parameters)}
    allowed = f"numbers, {', '.join(names)}, + - * / and parentheses"
    text = _str(key, text)
    if len(text) > MAX_EXPRESSION:
        _fail(key, f"must have at most {MAX_EXPRESSION} characters, got {len(text)}")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError:
        _fail(key, f"must be an expression of {allowed}; got {_short(text)}")

    def build(node):
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            return sp.Integer(node.value) if type(node.value) is int else sp.Float(node.value)
        if isinstance(node, ast.Name) and node.id in names:
            return names[node.id]
        if isinstance(node, ast.BinOp) and type(node.op) in _OPERATORS:
            return _OPERATORS[type(node.op)](build(node.left), build(node.right))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            v = build(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        what = node.id if isinstance(node, ast.Name) else ast.unparse(node)
        _fail(key, f"uses {what!r}, which is not allowed ({allowed} of {system.name}); got {_short(text)}")

    return build(tree.body)


@dataclass(frozen=True)
class SystemSeeds:
    """[seeds] of a System's scene: ``grid`` (about n cell centres of ``window``), ``random`` (n
    uniform points of ``window``, ``seed``) or ``points`` (absolute (a, b)); points off the energy
    surface are left out.  ``window`` = [a_lo, a_hi, b_lo, b_hi] in the coords."""

    kind: str = "grid"
    n: int = 100
    seed: int = 0
    points: tuple | None = None
    window: tuple | None = None

    def __post_init__(self):
        object.__setattr__(self, "kind", _choice("seeds.kind", self.kind, SYSTEM_SEED_KINDS))
        object.__setattr__(self, "n", _int("seeds.n", self.n, 1, MAX_SEEDS))
        object.__setattr__(self, "seed", _int("seeds.seed", self.seed, 0))
        if self.window is not None:
            object.__setattr__(self, "window", window_of("seeds.window", self.window))
        if self.points is not None:   # the points of Chaplygin's [seeds], checked as there
            object.__setattr__(self, "points", SeedSpec(kind="points", points=self.points).points)
        if self.kind == "points" and self.points is None:
            _fail("seeds.points", "is required with kind = 'points'")
        if self.kind != "points" and self.window is None:
            _fail("seeds.window", f"is required with kind = {self.kind!r}: [a_lo, a_hi, b_lo, b_hi], the rectangle "
                  "of the section the seeds fill (points off the energy surface are left out)")

    def used_dict(self) -> dict:
        """The keys that determine the points of this kind."""
        if self.kind == "points":
            return {"kind": "points", "points": [list(p) for p in self.points or ()]}
        d = {"kind": self.kind, "n": self.n, "window": list(self.window or ())}
        if self.kind == "random":
            d["seed"] = self.seed
        return d

    def points_on(self, smap):
        """The seed points (M, 2) on the domain of the section map ``smap`` (analysis.sweep.system_seed_points)."""
        from explorer.analysis.sweep import system_seed_points

        return system_seed_points(self, smap)[0]


def window_of(key, v) -> tuple:
    """[a_lo, a_hi, b_lo, b_hi] with a_lo < a_hi and b_lo < b_hi."""
    items = _list(key, v)
    if len(items) != 4:
        _fail(key, f"must be [a_lo, a_hi, b_lo, b_hi] (4 numbers), got {len(items)} items")
    w = tuple(_real(f"{key}[{i}]", x) for i, x in enumerate(items))
    if not (w[0] < w[1] and w[2] < w[3]):
        _fail(key, f"must have a_lo < a_hi and b_lo < b_hi, got {list(w)}")
    return w


@dataclass(frozen=True)
class SystemIntegration:
    """[integration] of a System's scene: the Taylor method's ``tol``, ``crossings`` per orbit, the
    time budget ``tmax`` (None: 100 * crossings) and ``max_steps``."""

    crossings: int = 1000
    tol: float = 1e-13
    tmax: float | None = None
    max_steps: int = 10**9
    method: str = "taylor"
    direction: int = 1

    #: no fixed step (the Taylor method) and no phi0 (the section is the scene's ``section``)
    dt = float("nan")
    phi0 = float("nan")

    def __post_init__(self):
        from explorer.analysis import sections

        if isinstance(self.direction, bool) or self.direction not in (-1, 1):
            _fail("direction", f"must be 1 (d(section)/dt > 0) or -1, got {_short(self.direction)}")
        object.__setattr__(self, "crossings", _int("integration.crossings", self.crossings, 1))
        object.__setattr__(self, "tol", _real("integration.tol", self.tol, sections.MIN_TOL, sections.MAX_TOL))
        if self.tmax is not None:
            object.__setattr__(self, "tmax", _real("integration.tmax", self.tmax, 0.0, lo_open=True))
        object.__setattr__(self, "max_steps", _int("integration.max_steps", self.max_steps, 1))
        if self.method != "taylor":
            _fail("integration.method", f"must be 'taylor' for a System (its generated Taylor integrator), "
                  f"got {_short(self.method)}")

    @property
    def effective_tmax(self) -> float:
        return 100.0 * self.crossings if self.tmax is None else self.tmax

    def used_dict(self) -> dict:
        return {"crossings": self.crossings, "tol": self.tol, "tmax": self.effective_tmax, "max_steps": self.max_steps}


@dataclass(frozen=True)
class SystemLyapunov(DiffusionSettings):
    """[lyapunov] of a System's scene: ``indicators`` (MEGNO <Y> always) over ``time`` (Taylor
    ``tol``) of every seed, or of the cell centres of a ``map_resolution``^2 raster of [seeds]
    window, drawn by ``map_indicator``; ``threshold`` classifies by <Y> (a map by its own indicator,
    :func:`explorer.analysis.sweep.panel_class`).  A map is adaptive unless ``exact``
    (:func:`explorer.io.scene.specs.adaptive_map`, as Chaplygin's).  frequency_diffusion needs
    ``center`` and takes ``diffusion_iterates``, as Chaplygin's (:class:`~explorer.io.scene.specs.LyapunovSpec`)."""

    time: float = 1000.0
    tol: float = 1e-12
    threshold: float = 4.0
    map_resolution: int = 0
    indicators: tuple = ("megno",)
    map_indicator: str = "megno"
    exact: bool = False
    center: tuple | None = None
    diffusion_iterates: int = DEFAULT_DIFFUSION_ITERATES

    # a System's indicators: the Taylor method, no early classification
    method = "taylor"
    early_stop = False

    @property
    def adaptive(self) -> bool:
        return adaptive_map(self)


    def __post_init__(self):
        from explorer.analysis import sections

        object.__setattr__(self, "time", _real("lyapunov.time", self.time, 0.0, lo_open=True))
        object.__setattr__(self, "tol", _real("lyapunov.tol", self.tol, sections.MIN_TOL, sections.MAX_TOL))
        object.__setattr__(self, "threshold", _real("lyapunov.threshold", self.threshold, 2.0, lo_open=True))
        object.__setattr__(self, "map_resolution",
                           _int("lyapunov.map_resolution", self.map_resolution, 0, MAX_MAP_RESOLUTION))
        names = [_choice(f"lyapunov.indicators[{i}]", q, INDICATOR_NAMES)
                 for i, q in enumerate(_list("lyapunov.indicators", self.indicators))]
        object.__setattr__(self, "indicators", tuple(dict.fromkeys(["megno", *names])))
        object.__setattr__(self, "exact", _bool("lyapunov.exact", self.exact))
        self._check_diffusion()
        if self.map_indicator not in self.indicators:
            _fail("lyapunov.map_indicator", f"must be one of lyapunov.indicators {list(self.indicators)}; "
                  f"got {_short(self.map_indicator)}")

    def used_dict(self) -> dict:
        return {"time": self.time, "tol": self.tol, "indicators": list(self.indicators), **map_entries(self)}


@dataclass(frozen=True)
class SystemScene:
    """A sweep of a System's section map, one panel per sweep value (a parameter of the system or
    the energy), validated on construction (docs/scenes.md)."""

    name: str
    system: Any
    section: object
    coords: tuple
    solve: str
    energy: float
    system_ref: str = ""
    sweep_parameter: str | None = None
    sweep_values: tuple = ()
    seeds: SystemSeeds = field(default_factory=SystemSeeds)
    integration: SystemIntegration = field(default_factory=SystemIntegration)
    compute: tuple = ("sections",)
    lyapunov: SystemLyapunov = field(default_factory=SystemLyapunov)
    figure: FigureSpec = field(default_factory=FigureSpec)
    description: str = ""
    text: str = ""
    #: [compute] separatrices: the branches of the hyperbolic fixed points of each panel's map,
    #: computed when the figure is drawn (as [manifolds]), never stored
    separatrices: bool = False
    manifolds: ManifoldSpec = field(default_factory=ManifoldSpec)
    atlas_parameter: str | None = None
    atlas_values: tuple = ()

    def __post_init__(self):
        _scene_name(self.name)
        object.__setattr__(self, "energy", _real("energy.value", self.energy))
        swept = [p.name for p in self.system.parameters] + [ENERGY]
        if ENERGY in swept[:-1]:
            _fail("system", f"{self.system.name} has a parameter named {ENERGY!r}, the name a scene sweeps the "
                  "energy level by: rename the parameter")
        if _swept(self, "sweep", swept):
            object.__setattr__(self, "sweep_values", _distinct_reals("sweep.values", self.sweep_values))
        if not self.compute or any(q not in _COMPUTE_KEYS[:2] for q in self.compute):
            _fail("compute", f"must turn on sections or lyapunov (or both), got {list(self.compute)}")
        if self.lyapunov.map_resolution and self.seeds.window is None:
            _fail("seeds.window", "is required with lyapunov.map_resolution: the rectangle [a_lo, a_hi, b_lo, b_hi] "
                  "the chaos map covers")
        if self.lyapunov.map_resolution and "lyapunov" not in self.compute:
            _fail("lyapunov.map_resolution", "needs compute.lyapunov = true")
        _atlas.check_atlas(self, swept)
        drawn = "compute.separatrices" if self.separatrices else "manifolds.draw" if self.manifolds.draw else None
        if drawn and self.is_atlas:
            _fail(drawn, "is not used by an atlas scene (it draws a heat map, no sections)")
        if drawn and "sections" not in self.compute:
            _fail(drawn, "needs compute.sections = true (it is drawn over the section figure)")
        _own_scale(self.figure, self.n_panels)
        self._check_panels()

    def _key(self, i) -> str:
        return "energy.value" if self.sweep_parameter is None else f"sweep.values[{i}]"

    def _check_panels(self):
        """Every panel's section map (the section, coords, solve and energy checked by
        :class:`~explorer.analysis.system_section_map.SystemSectionMap`) and, but in an atlas (whose
        cells may lie off the energy surface), its seeds."""
        from explorer.analysis.sweep import system_seed_points

        for i in range(self.n_panels):
            try:
                smap = self.section_map(i)
            except ParameterError as e:
                first = str(e).split(" ")[0]
                key = first if first in ("coords", "solve") else "section" if i == 0 else self._key(i)
                raise SceneError(f"scene key '{key}' ({self.panel(i)[2] or self.system.name}): {e}") from None
            if self.is_atlas:
                continue
            pts, _dropped = system_seed_points(self.seeds, smap)
            if not len(pts) and ("sections" in self.compute or not self.lyapunov.map_resolution):
                where = f" of panel {i} ({self.panel(i)[2]})" if self.sweep_parameter is not None else ""
                _fail(f"seeds.{'points' if self.seeds.kind == 'points' else 'window'}",
                      f"gives no point on the energy surface{where} (E = {self.panel(i)[1]!r})")

    @property
    def direction(self) -> int:
        """The direction of the crossings (``integration.direction``, the scene's top-level ``direction``)."""
        return self.integration.direction

    # the panels and cells of [sweep] x [atlas], counted and labelled as in Chaplygin's scene
    n_panels = Scene.n_panels
    is_atlas = Scene.is_atlas
    n_cells = Scene.n_cells
    _check_index = Scene._check_index
    _label = Scene._label

    @property
    def params(self) -> dict:
        """The system's parameter values by name."""
        return {p.name: float(v) for p, v in self.system.parameters.items()}

    def _at(self, values: dict, key: str | None = None):
        """(System, energy) with ``values`` {parameter or 'energy': value} set; a refused value is
        a SceneError naming ``key`` (a ParameterError without one)."""
        energy = values.pop(ENERGY, self.energy)
        try:
            return (self.system.with_(**values) if values else self.system), energy
        except ParameterError as e:
            if key is None:
                raise
            raise SceneError(f"scene key '{key}': {e}") from None

    def panel(self, i):
        """(System, energy, label) of panel i; label e.g. ``"lam = 0.5"`` ("" without a sweep)."""
        i = self._check_index(i)
        if self.sweep_parameter is None:
            return self.system, self.energy, ""
        return (*self._at({self.sweep_parameter: self.sweep_values[i]}, f"sweep.values[{i}]"), self._label(i))

    def cell(self, i):
        """(System, energy, label) of atlas cell i = row * len(atlas.values) + column (row: sweep
        value, column: atlas value)."""
        if not self.is_atlas or isinstance(i, bool) or not isinstance(i, (int, np.integer)) \
                or not 0 <= i < self.n_cells:
            raise IndexError(f"atlas cell index must be an integer in [0, {self.n_cells - 1}], got {i!r}")
        r, c = divmod(int(i), len(self.atlas_values))
        values = {self.sweep_parameter: self.sweep_values[r], self.atlas_parameter: self.atlas_values[c]}
        return (*self._at(values), _atlas.cell_label(self, r, c))

    def panel_h(self, i) -> float:
        return self.panel(i)[1]

    def _map(self, system, energy):
        from explorer.analysis.system_section_map import SystemSectionMap

        return SystemSectionMap(system, energy, section=self.section, direction=self.direction, coords=self.coords,
                                solve=self.solve)

    def section_map(self, i):
        """The section map of panel i (:class:`~explorer.analysis.system_section_map.SystemSectionMap`)."""
        return self._map(*self.panel(i)[:2])

    def cell_map(self, i):
        """The section map of atlas cell i."""
        return self._map(*self.cell(i)[:2])

    def map_settings(self) -> dict:
        """The section map's definition, as stored (``coords`` and the columns of a crossing row)."""
        return {"section": str(self.section), "direction": self.direction, "coords": list(self.coords),
                "solve": self.solve, "columns": ["t", *self.coords, self.solve, "dE"]}

    def panel_settings(self, i) -> dict:
        """Everything that determines panel i's numbers, as plain JSON-able values."""
        system, energy, _label = self.panel(i)
        d = {"system": {"name": system.name, "content": system.content_hash},
             "params": {p.name: float(v) for p, v in system.parameters.items()}, "energy": energy,
             "map": self.map_settings(), "seeds": self.seeds.used_dict(),
             "integration": self.integration.used_dict(), "compute": {q: True for q in self.compute}}
        if "lyapunov" in self.compute:
            d["lyapunov"] = self.lyapunov.used_dict()
        return d

    def panel_hash(self, i) -> str:
        return _sha256({"format_version": FORMAT_VERSION, "panel": self.panel_settings(i)})

    def product_settings(self, i) -> dict:
        """{product: settings} of panel i: ``sections`` and ``indicators`` (of the seeds or the map's raster)."""
        d = self.panel_settings(i)
        base = {k: d[k] for k in ("system", "params", "energy", "map")}
        out = {}
        if "sections" in self.compute:
            out["sections"] = dict(base, seeds=d["seeds"], integration=d["integration"])
        if "lyapunov" in self.compute:
            ly = self.lyapunov.used_dict()
            grid = ly.pop("map_resolution", 0)
            seeds = {"map_resolution": grid, "window": list(self.seeds.window or ())} if grid else d["seeds"]
            out["indicators"] = dict(base, seeds=seeds, lyapunov=ly, alone="sections" not in self.compute)
        return out

    def product_hashes(self, i) -> dict:
        return {k: _sha256({"format_version": FORMAT_VERSION, k: v}) for k, v in self.product_settings(i).items()}

    def figure_settings(self) -> str:
        """Canonical JSON of what changes the drawing but not the numbers ([figure], the coords, the
        threshold and map_indicator with [lyapunov], separatrices and [manifolds] when drawn)."""
        d: dict = {"figure": self.figure.to_dict(), "coords": list(self.coords)}
        if "lyapunov" in self.compute:
            d.update(threshold=self.lyapunov.threshold, map_indicator=self.lyapunov.map_indicator)
        if self.separatrices:
            d["separatrices"] = True
        if self.manifolds.draw:
            d["manifolds"] = self.manifolds.to_dict()
        return _canonical_json(d)

    def atlas_hash(self) -> str:
        """sha256 of everything that determines an atlas's numbers: the system and the map, both
        axes, the seeds and [lyapunov] (not name, description, figure or [integration])."""
        d = {"system": {"name": self.system.name, "content": self.system.content_hash}, "params": self.params,
             "energy": self.energy, "map": self.map_settings(), "rows": [self.sweep_parameter, list(self.sweep_values)],
             "columns": [self.atlas_parameter, list(self.atlas_values)], "seeds": self.seeds.used_dict(),
             "lyapunov": self.lyapunov.used_dict(), "threshold": self.lyapunov.threshold,
             **class_settings(self.lyapunov)}
        return _sha256({"format_version": FORMAT_VERSION, "atlas": d})


def is_system_scene(data: dict, system=None) -> bool:
    """The tables ``data`` (or a ``system`` given beside them) make a System's scene: they name a
    ``system`` or a ``section`` (keys that Chaplygin's scenes do not have)."""
    return system is not None or (isinstance(data, dict) and ("system" in data or "section" in data))


def system_scene_from_dict(data: dict, text: str = "", system=None) -> SystemScene:
    """A validated :class:`SystemScene` from nested tables; ``system`` (a System or 'module:attribute')
    replaces the scene's ``system`` key."""
    if not isinstance(data, dict):
        _fail("<top level>", f"must be a table, {_got(data)}")
    from explorer.model.validation import did_you_mean

    if system is not None and "section" not in data:
        raise SceneError(f"--system needs a scene of a System (with section, coords, solve and [energy] value; "
                         f"docs/scenes.md); scene {data.get('name', '')!r} has no section")
    for k in data:
        if k not in SYSTEM_TOP_KEYS:
            hint = " ([model] is Chaplygin's model; a System's scene names its parameters in [parameters])" \
                if k == "model" else ""
            raise SceneError(f"scene: unknown key '{k}' of a System's scene{did_you_mean(k, SYSTEM_TOP_KEYS)}{hint} "
                             f"(allowed: {', '.join(SYSTEM_TOP_KEYS)})")
    if "name" not in data:
        _fail("name", "is required (a string matching [A-Za-z0-9_.-]+)")
    ref = system if system is not None else data.get("system")
    if ref is None:
        _fail("system", "is required: 'module:attribute' naming an explorer System (or --system)")
    try:
        sys_obj = resolve_system(ref, "scene key 'system'" if system is None else "--system")
    except ParameterError as e:
        raise SceneError(str(e)) from None
    given = _table("parameters", data.get("parameters", {}), [p.name for p in sys_obj.parameters])
    if given:
        values = {k: _real(f"parameters.{k}", v) for k, v in given.items()}
        sys_obj = sys_obj.with_(**values)
    for k in ("section", "coords", "solve"):
        if k not in data:
            _fail(k, f"is required in a System's scene (the section map: section = EXPR of EXPR = 0, coords = "
                  f"[a, b], solve = c; state variables of {sys_obj.name}: {', '.join(s.name for s in sys_obj.states)})")
    coords = _list("coords", data["coords"])
    if len(coords) != 2:
        _fail("coords", f"must be two state variables [a, b], got {len(coords)} items")
    kw: dict = {"name": data["name"], "description": _str("description", data.get("description", "")), "text": text,
                "system": sys_obj, "system_ref": ref if isinstance(ref, str) else "",
                "section": parse_expression(data["section"], sys_obj, "section"),
                "coords": tuple(_str(f"coords[{i}]", c) for i, c in enumerate(coords)),
                "solve": _str("solve", data["solve"])}
    energy = _table("energy", data.get("energy", {}), ("value",))
    if "value" not in energy:
        _fail("energy.value", f"is required: the energy level E of the section map of {sys_obj.name}")
    kw["energy"] = energy["value"]
    kw.update(_sweep(data))
    kw.update(_atlas._atlas_from_dict(data))
    seeds = dict(_table("seeds", data.get("seeds", {}), _SEED_KEYS))
    kw["seeds"] = SystemSeeds(**seeds) if seeds else SystemSeeds()
    kw["integration"] = SystemIntegration(**_table("integration", data.get("integration", {}), _INTEGRATION_KEYS),
                                          direction=data.get("direction", 1))
    comp = _table("compute", data.get("compute", {}), _COMPUTE_KEYS)
    kw["compute"] = tuple(q for q, default in (("sections", True), ("lyapunov", False))
                          if _bool(f"compute.{q}", comp.get(q, default)))
    kw["separatrices"] = _bool("compute.separatrices", comp.get("separatrices", False))
    # the specs check lists themselves (indicators, own_scale, guess)
    kw["lyapunov"] = SystemLyapunov(**_table("lyapunov", data.get("lyapunov", {}), _LYAPUNOV_KEYS))
    kw["figure"] = FigureSpec(**_table("figure", data.get("figure", {}), _FIGURE_KEYS))
    kw["manifolds"] = ManifoldSpec(**_table("manifolds", data.get("manifolds", {}), _MANIFOLD_KEYS))
    return SystemScene(**kw)
