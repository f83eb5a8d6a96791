"""What the page and its link may set, validated as the command line's values are (docs/commands/serve.md):
a bad value raises :class:`~explorer.model.ParameterError` naming the field; the page of Chaplygin's section
map and of a System's ("Your own system"), and what ``explorer serve`` starts from.  No web library here."""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from explorer import model
from explorer.analysis import sections, system_sections
from explorer.analysis.chaos_map import cell_centres
from explorer.model import ParameterError, validation
from explorer.model.validation import MAX_TEXT_CHARS, angle_text, number_text

#: every field of Chaplygin's page, in the order shown (and written in the URL): mu and h (most often changed) first
FIELDS = ("mu", "h", *(n for n in model.PARAM_NAMES if n != "mu"), "method", "tol", "dt", "crossings", "phi0")
#: crossings per click: the page's default and its upper bound (40 bytes a row in the server)
DEFAULT_CROSSINGS = 2000
MAX_CROSSINGS = 1_000_000
#: at most this many orbits (clicked starts) in one session
MAX_STARTS = 256
#: at most this many crossings on one session's page (orbits x crossings per click; ~0.2 GB)
MAX_SESSION_CROSSINGS = 4_000_000
#: names the page's link keeps for itself: a System parameter may not take one (its field is a link key)
RESERVED = ("energy", "tol", "crossings", "orbits", "hidden", "megno", "indicator", "separatrices", "periodic",
            "colour", "pause", "view", "token", "name")
#: cells per side of the allowed region's image (a System's region has no closed form)
REGION_CELLS = 256
#: the URL argument that carries the token (explorer.app.serve.server)
TOKEN_ARG = "token"
#: a link's arguments at most this many characters in all (a page's own link, 256 starts, is under 20,000)
MAX_LINK_CHARS = 100_000


def room_for(n_orbits: int, crossings: int) -> str | None:
    """Why ``n_orbits`` orbits of ``crossings`` crossings do not fit in a session (None: they do)."""
    if n_orbits > MAX_STARTS:
        return f"at most {MAX_STARTS} orbits in a session: clear or undo first"
    if n_orbits * crossings > MAX_SESSION_CROSSINGS:
        return (f"at most {MAX_SESSION_CROSSINGS:,} crossings on a page: {n_orbits} orbits x {crossings} crossings "
                "per click is more; clear, undo or lower the crossings per click")
    return None


class PageSettings:
    """The page of a section map ``self.smap`` (docs/commands/serve.md): its fields (the map's parameters,
    then ``own_fields``), region and refusals are the map's answers, one code path for Chaplygin's page
    (:class:`Settings`) and a System's (:class:`SystemSettings`); ``on(smap, **values)``: the same page
    on another map."""

    smap: Any                      # the section map the page shows
    tol: float                     # the tolerance of the page's orbits
    crossings: int                 # crossings per click
    adaptive: bool                 # the step is adaptive (else fixed, ``dt``)
    dt: float
    max_steps: int                 # an orbit's step budget
    on: Any                        # (smap, **values) -> these settings on ``smap`` with ``values``
    stream_kwargs: Any             # () -> the integration keywords of stream, beside the map at tol
    own_fields: tuple = ("tol", "crossings")

    @property
    def field_names(self) -> tuple:
        """The map's parameters (mu and h first) and ``own_fields``."""
        return (*sorted(self.smap.parameters, key=lambda n: (n != "mu", n != "h")), *self.own_fields)

    def fields(self) -> dict:
        """The page's fields as text (``repr`` of each float: read back, the same number)."""
        own = {n: str(getattr(self, n)) if n in ("method", "crossings") else repr(float(getattr(self, n)))
               for n in self.own_fields}
        return {n: own[n] if n in own else repr(float(self.smap.value_of(n))) for n in self.field_names}

    def with_fields(self, fields: dict):
        """These settings with the page's ``fields`` ({name: text}) applied, each validated."""
        values, smap = read_fields(self.field_names, fields, numbers=self.smap.parameters), self.smap
        for name in self.smap.parameters:
            if name in values and values[name] != smap.value_of(name):
                smap = smap.with_value(name, values[name])
            values.pop(name, None)
        return self.on(smap, **values)

    @functools.cached_property
    def _domain(self) -> tuple:
        """(region, why): the map's domain asked once (a System's is a scan, not kept by the map when empty)."""
        try:
            (a0, a1), (b0, b1) = self.smap.domain
        except ParameterError as exc:
            return None, str(exc)
        return (0.5 * (a0 + a1), 0.5 * (b0 + b1), 0.5 * (a1 - a0), 0.5 * (b1 - b0)), ""

    @property
    def region(self):
        """(c1, c2, r1, r2): the centre and half-sizes of the box of the map's domain; None when it is empty."""
        return self._domain[0]

    def empty_region(self) -> str:
        """Why the region is empty, in the map's words ("" when it is not)."""
        return self._domain[1]

    def region_mask(self):
        """The map's domain on a REGION_CELLS^2 grid of the :attr:`region` box (rows: the second coordinate);
        None when the region is empty."""
        if self.region is None:
            return None
        c1, c2, r1, r2 = self.region
        return self.smap.allowed(cell_centres((c1 - r1, c1 + r1, c2 - r2, c2 + r2), REGION_CELLS))

    def refusal(self, p1: float, p2: float) -> str | None:
        """Why a click at (p1, p2) starts no orbit, in the map's words (None: the map lifts it to a state)."""
        try:
            self.smap.states([(p1, p2)])
        except ParameterError as exc:
            return str(exc)
        return None

    def admissible(self, p1: float, p2: float) -> bool:
        return self.refusal(p1, p2) is None

    def stream(self, p1: float, p2: float, state, block: int, step_block: int | None):
        """Blocks (rows (n, 5): t, a, b, solve, E - E0; the stream's state) of the orbit from (p1, p2), on from
        ``state`` (None: its start): :func:`explorer.analysis.sections.iter_crossings` of the map at ``tol``, its
        blocks cut at ``step_block`` steps (None: at crossings only)."""
        s = self.smap.with_tol(self.tol)
        return ((b.rows(0)[:, list(s.columns)], b.state) for b in sections.iter_crossings(
            s, [(p1, p2)], n_crossings=self.crossings, block=block, state=state, max_steps=self.max_steps,
            step_block=step_block, **self.stream_kwargs()))

    def indicator_run(self, points) -> tuple:
        """(system, keywords) of lyapunov.indicators for the orbits from ``points``: the map at ``tol``, its points."""
        return self.smap.with_tol(self.tol), {"y0": points}

    def seed_starts(self, seeds) -> list:
        """The starts [(a, b), ...] ``explorer sweep`` runs for a scene's ``seeds`` on the map (``seeds.points_on``;
        None, no scene: a scene's default on Chaplygin's map, a grid of 100 over the region box on a System's)."""
        from explorer.io.scene import SeedSpec
        from explorer.io.scene.system import SystemSeeds

        if seeds is None:
            c1, c2, r1, r2 = self.region or (0.0, 0.0, 1.0, 1.0)
            system = system_sections.is_system_map(self.smap)
            seeds = SystemSeeds(window=(c1 - r1, c1 + r1, c2 - r2, c2 + r2)) if system else SeedSpec()
        pts = seeds.points_on(self.smap)
        if not len(pts):
            raise ParameterError(f"no seed point on the section ({self.smap.describe_domain()})")
        return [(float(a), float(b)) for a, b in pts]

    def megno(self, p1, p2, time: float, max_steps: int, mlce: bool = False):
        """<Y>(time) (and the mLCE with ``mlce``) of the orbits from (p1, p2) (lyapunov.indicators of
        :meth:`indicator_run`), NaN where a run stops early or a fixed step would take over ``max_steps``."""
        from explorer.analysis import lyapunov

        ok, res = np.zeros(np.size(p1), bool), None
        if self.adaptive or time / self.dt <= max_steps:
            system, kw = self.indicator_run(np.column_stack([np.ravel(p1), np.ravel(p2)]))
            res = lyapunov.indicators(system, tmax=time, max_steps=max_steps,
                                      which=("megno", "mlce") if mlce else ("megno",), **kw)
            ok = np.asarray(res.status) == 0

        def of(name):
            return np.where(ok, np.asarray(getattr(res, name, np.nan), dtype=np.float64), np.nan).reshape(np.shape(p1))
        return (of("megno"), of("mlce")) if mlce else of("megno")


@dataclass(frozen=True)
class Settings(PageSettings, sections.Integration):
    """Chaplygin's page: its map ``SectionMap(params, h, phi0=phi0)`` and an
    :class:`~explorer.analysis.sections.Integration`; a clicked orbit's crossings are bit for bit those of
    ``explorer orbit`` with the same values."""

    params: model.Params = model.FIGURE4
    h: float = model.FIGURE4_H
    crossings: int = DEFAULT_CROSSINGS

    scene_export = True            # the session exports as a scene that `explorer sweep` reruns
    axes = ("p1", "p2")
    own_fields = FIELDS[-5:]

    def __post_init__(self):
        super().__post_init__()
        validation.integer("crossings", self.crossings, 1, MAX_CROSSINGS)
        validation.magnitude("h", self.h)
        e = model.allowed_ellipse(self.params, self.h, self.phi0)
        if e is not None and not all(math.isfinite(float(v)) for v in e):
            # e.g. lam = -1e-300: the ellipse's centre or radii overflow
            shown = ", ".join(f"{float(v):g}" for v in e)
            raise ParameterError(f"the allowed region is not finite at these values (centre and radii {shown}): "
                                 "a parameter is too far from 1 (lam, a1, a2, b)")

    @functools.cached_property
    def smap(self):
        from explorer.analysis.section_map import SectionMap

        return SectionMap(self.params, self.h, phi0=self.phi0)

    def section_kwargs(self) -> dict:
        """Keywords of :func:`explorer.analysis.sections.iter_crossings` (with ``crossings``)."""
        return {"method": self.method, "tol": self.tol, "dt": self.dt, "phi0": self.phi0, "direction": self.direction}

    def on(self, smap, **values) -> Settings:
        return replace(self, params=smap.params, h=smap.h, **values)

    def region_mask(self):
        """None: the region is the ellipse, drawn in closed form (docs/model.md R9)."""
        return None

    def describe(self) -> str:
        return f"mu = {self.params.mu:g}, h = {self.h:g}, {self.method}"

    def title(self) -> str:
        return f"Poincaré section φ = {'π' if self.phi0 == math.pi else f'{self.phi0:.6g}'}"

    def indicator_run(self, points) -> tuple:
        """The flow from the points' states on the page's crossing direction, with its integration."""
        states = self.smap.states(points, self.direction)
        return self.params, {"states": states, "method": self.method, "tol": self.tol, "dt": self.dt}

    def stream_kwargs(self) -> dict:
        """:meth:`stream`'s integration: the method, its step and the crossing direction."""
        return {"method": self.method, "dt": self.dt, "direction": self.direction}


@dataclass(frozen=True)
class SystemSettings(PageSettings):
    """The page of a System's section map ``smap``: fields the system's parameters, ``energy``, ``tol``
    and ``crossings``; equal when their maps (equal by value), ``tol`` and ``crossings`` are."""

    smap: Any
    tol: float = 1e-13
    crossings: int = DEFAULT_CROSSINGS

    method = "taylor"
    adaptive = True
    direction = 1                  # the map's own (smap.direction): the page counts every crossing it makes
    max_steps = system_sections.DEFAULT_MAX_STEPS    # an orbit's step budget
    scene_export = False

    def __post_init__(self):
        from explorer.integrate.methods import MAX_TOL, MIN_TOL

        if not system_sections.is_system_map(self.smap):
            raise ParameterError(f"a System's page needs its section map, got {type(self.smap).__name__}")
        for name in self.smap.parameters:
            if name in RESERVED[1:]:
                raise ParameterError(f"the page cannot show {self.smap.system.name}'s parameter {name!r}: the page's "
                                     f"link uses that name (rename it; reserved: {', '.join(RESERVED)})")
        validation.real("tol", self.tol, MIN_TOL, MAX_TOL)
        validation.integer("crossings", self.crossings, 1, MAX_CROSSINGS)

    @property
    def axes(self) -> tuple:
        return tuple(s.name for s in self.smap.coords)

    def on(self, smap, **values) -> SystemSettings:
        return replace(self, smap=smap, **values)

    def describe(self) -> str:
        values = ", ".join(f"{n} = {self.smap.value_of(n):g}" for n in self.smap.parameters)
        return f"{self.smap.system.name}: {values}"

    def title(self) -> str:
        s = self.smap
        return f"Poincaré section {s.section.expr} = 0 ({s.direction:+d}) of {s.system.name}, {s.solve.name} from E"

    def stream_kwargs(self) -> dict:
        """:meth:`stream`'s integration beside the map at ``tol``: its return budget per crossing, on this thread."""
        return {"tmax": self.smap.tmax * self.crossings, "threads": 1}


def page_settings(scene=None, system=None, panel: int = 0, flag: str = "", **values) -> tuple:
    """(settings, label, seeds) a page starts from: a System's section map (``system``: a section map or
    'module:attribute'; or ``scene``: a section map or a System's scene), else Chaplygin's model (``scene``'s
    panel ``panel``; None: Figure 4); the ``values`` given (not None) on top, validated; ``flag``: how the
    refusal of a Chaplygin option on a System's page names it."""
    from explorer.io.scene import SystemScene, load_scene
    from explorer.io.scene.system import resolve_system

    values = {k: v for k, v in values.items() if v is not None}
    if system_sections.is_system_map(scene):
        system, scene = scene, None
    elif scene is not None:
        scene = load_scene(scene, system=system)
    if scene is None and panel != 0:
        raise ParameterError("panel needs a scene")
    i = 0 if scene is None else validation.integer("panel", panel, 0, scene.n_panels - 1)
    label = "" if scene is None else ": ".join(n for n in (scene.name, scene.panel(i)[2]) if n)
    given = {} if scene is None else {"tol": scene.integration.tol,
                                      "crossings": min(scene.integration.crossings, MAX_CROSSINGS)}
    seeds = None if scene is None else scene.seeds      # (None: the page's default, PageSettings.seed_starts)
    if system is None and not isinstance(scene, SystemScene):
        params, h = (model.FIGURE4, model.FIGURE4_H) if scene is None else scene.panel(i)[:2]
        if scene is not None:
            integ = scene.integration
            given.update(method=integ.method, dt=integ.dt, phi0=integ.phi0, direction=integ.direction)
        params = params.with_(**{k: values.pop(k) for k in model.PARAM_NAMES if k in values})
        return Settings(params=params, **{"h": h, **given, **values}), label, seeds
    wrong = [k for k in values if k not in ("h", "tol", "crossings")]
    if wrong:
        raise ParameterError(f"{flag}{wrong[0]} belongs to Chaplygin's model; a System's page takes {flag}h (its "
                             f"energy), {flag}tol and {flag}crossings")
    if scene is not None:
        smap = scene.section_map(i)
    else:
        smap = resolve_system(system, "--system", maps=True)
        if not system_sections.is_system_map(smap):
            raise ParameterError(f"--system {system!r} is a System without a section: the page shows a section map. "
                                 "Name its map (SectionMap(system, E, section=..., direction=..., coords=(a, b), "
                                 "solve=c) as the attribute) or give a scene of it (explorer serve SCENE.toml "
                                 f"--system {system})")
        label = smap.system.name
    if "h" in values:
        smap = smap.with_value("energy", validation.magnitude(flag + "h", values.pop("h")))
    return SystemSettings(smap, **{**given, **values}), label, seeds


def read_fields(names, fields: dict, numbers=()) -> dict:
    """{name: value} of the page's ``fields`` ({name: text}) among ``names``, each validated (ParameterError
    naming it); ``numbers``: the names read as plain numbers (a System's parameters)."""
    out: dict = {}
    for name, text in fields.items():
        if name not in names:
            raise ParameterError(f"unknown field {str(name)[:MAX_TEXT_CHARS]!r}; one of {', '.join(names)}")
        if name in numbers:
            out[name] = number_text(name, text)
        elif name == "method":
            out[name] = validation.choice("method", str(text).strip(), sections.METHODS)
        else:
            out[name] = angle_text(name, text) if name == "phi0" else number_text(name, text, name == "crossings")
    return out


def parse_link_fields(base, fields: dict) -> tuple:
    """(settings, refusals): ``base`` with every field of a link that applies, and why each other is refused."""
    try:
        return base.with_fields(fields), []
    except ParameterError:
        pass
    settings, refused = base, []
    for name, text in fields.items():
        try:
            settings = settings.with_fields({name: text})
        except ParameterError as exc:
            refused.append(str(exc))
    return settings, refused


def screen_link(args: dict, names) -> tuple:
    """(args, refusals): a link's arguments among ``names``, and a message naming the others (or
    refusing a link longer than MAX_LINK_CHARS)."""
    size = sum(len(k) + len(v) + 2 for k, v in args.items())
    if size > MAX_LINK_CHARS:
        return {}, [f"the link is {size:,} characters long (at most {MAX_LINK_CHARS:,}): none of it applies"]
    unknown = [repr(k[:MAX_TEXT_CHARS]) for k in args if k not in names]
    shown = ", ".join(unknown[:3]) + (f" and {len(unknown) - 3} more" if len(unknown) > 3 else "")
    refused = [f"unknown {'key' if len(unknown) == 1 else 'keys'} {shown} (removed)"] if unknown else []
    return {k: v for k, v in args.items() if k in names}, refused


def format_starts(starts) -> str:
    """Starts as URL text: ``p1,p2;p1,p2`` with each float's ``repr`` (read back exactly)."""
    return ";".join(f"{float(a)!r},{float(b)!r}" for a, b in starts)


def read_numbers(name: str, text, labels) -> list:
    """Comma-separated numbers, one per label, each within MAX_MAGNITUDE (ParameterError naming ``name``)."""
    pieces = str(text).split(",")
    if len(pieces) != len(labels):
        raise ParameterError(f"{name} must be {','.join(labels)} ({len(labels)} numbers), "
                             f"got {str(text).strip()[:MAX_TEXT_CHARS * 4]!r}")
    return [validation.magnitude(f"{name}.{n}", number_text(f"{name}.{n}", v)) for n, v in zip(labels, pieces)]


def parse_starts(text: str) -> list:
    """The starts of :func:`format_starts` (ParameterError for anything else)."""
    pieces = str(text).strip().split(";") if str(text).strip() else []
    if len(pieces) > MAX_STARTS:
        raise ParameterError(f"orbits must list at most {MAX_STARTS} starts, got {len(pieces)}")
    return [tuple(read_numbers(f"orbits[{i}]", piece, ("p1", "p2"))) for i, piece in enumerate(pieces)]


def format_hidden(positions) -> str:
    """Hidden starts as URL text: their positions (from 1) among the link's ``orbits``, ``2,5``."""
    return ",".join(str(int(k)) for k in sorted(positions))


def parse_hidden(text: str, n_starts: int) -> set:
    """The positions of :func:`format_hidden`, each in 1..``n_starts`` (ParameterError otherwise)."""
    pieces = [p.strip() for p in str(text).split(",")[:MAX_STARTS + 1]] if str(text).strip() else []
    for i, piece in enumerate(pieces):
        if not (piece.isascii() and piece.isdigit() and len(piece) <= 4 and 1 <= int(piece) <= n_starts):
            raise ParameterError(f"hidden[{i}] must be the position of one of the link's {n_starts} orbits "
                                 f"(1 to {n_starts}), got {piece[:MAX_TEXT_CHARS]!r}")
    return {int(p) for p in pieces}


@dataclass(frozen=True)
class Window:
    """The visible part of the section, the link's ``view``: p1 in [x0, x1], p2 in [y0, y1] (ParameterError, a
    ValueError, otherwise)."""

    x0: float
    x1: float
    y0: float
    y1: float

    def __post_init__(self):
        if not all(np.isfinite([self.x0, self.x1, self.y0, self.y1])) or not (self.x1 > self.x0 and self.y1 > self.y0):
            raise ParameterError(f"view must have finite x0 < x1 and y0 < y1, got {format_window(self)}")

    def centres(self, n: int):
        """Cell centres of an n x n raster, (n, n) arrays P1, P2 (row = p2 index): analysis.chaos_map's."""
        return tuple(np.moveaxis(cell_centres((self.x0, self.x1, self.y0, self.y1), n), -1, 0))


def format_window(w) -> str:
    """A view window (x0, x1, y0, y1) as URL text: ``x0,x1,y0,y1`` with each float's ``repr``."""
    return ",".join(repr(float(v)) for v in (w.x0, w.x1, w.y0, w.y1))


def parse_window(text: str):
    """The :class:`Window` of :func:`format_window` (ParameterError otherwise)."""
    return Window(*read_numbers("view", text, ("x0", "x1", "y0", "y1")))
