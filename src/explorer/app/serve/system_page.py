"""The page of a System's section map (docs/commands/serve.md, "Your own system"), a
:class:`~explorer.app.serve.settings.PageSettings`, and what ``explorer serve`` starts from."""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from explorer import model
from explorer.analysis import sections, system_sections
from explorer.app.serve.settings import MAX_CROSSINGS, PageSettings, Settings, Window
from explorer.model import ParameterError, validation

#: names the page's link keeps for itself: a System parameter may not take one (its field is a link key)
RESERVED = ("energy", "tol", "crossings", "orbits", "hidden", "megno", "indicator", "separatrices", "periodic",
            "colour", "pause", "view", "token", "name")
#: cells per side of the allowed region's image (a System's region has no closed form)
REGION_CELLS = 256


@dataclass(frozen=True, eq=False)
class SystemSettings(PageSettings):
    """The page of a System's section map ``smap``: fields the system's parameters, ``energy``, ``tol``
    and ``crossings``; equal when their fields are."""

    smap: Any
    tol: float = 1e-13
    crossings: int = 2000

    method = "taylor"
    adaptive = True
    direction = 1                  # the map's own (smap.direction): the page counts every crossing it makes
    max_steps = system_sections.DEFAULT_MAX_STEPS    # an orbit's step budget
    scene_export = False

    def __post_init__(self):
        from explorer.analysis.system_sections import is_system_map
        from explorer.integrate.methods import MAX_TOL, MIN_TOL

        if not is_system_map(self.smap):
            raise ParameterError(f"a System's page needs its section map, got {type(self.smap).__name__}")
        for name in self.smap.parameters:
            if name in RESERVED[1:]:
                raise ParameterError(f"the page cannot show {self.smap.system.name}'s parameter {name!r}: the page's "
                                     f"link uses that name (rename it; reserved: {', '.join(RESERVED)})")
        validation.real("tol", self.tol, MIN_TOL, MAX_TOL)
        validation.integer("crossings", self.crossings, 1, MAX_CROSSINGS)

    def __eq__(self, other):
        return isinstance(other, SystemSettings) and other.fields() == self.fields()

    def __hash__(self):
        return hash(tuple(self.fields().items()))

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

    def region_mask(self):
        """The map's domain on a REGION_CELLS^2 grid of the :attr:`region` box (rows: the second coordinate)."""
        c1, c2, r1, r2 = self.region
        return self.allowed(*Window(c1 - r1, c1 + r1, c2 - r2, c2 + r2).centres(REGION_CELLS))

    def section_map(self, tol=None):
        s = self.smap
        if tol is None or tol == s.tol:
            return s
        return type(s)(s.system, s.energy_value, section=s.section.expr, direction=s.direction, coords=s.coords,
                       solve=s.solve, tol=tol, tmax=s.tmax)

    def indicators(self, p1, p2, time: float, max_steps: int, which):
        from explorer.analysis import lyapunov

        return lyapunov.indicators(self.smap, np.column_stack([p1, p2]), tmax=time, tol=self.tol,
                                   max_steps=max_steps, which=which)

    def stream(self, p1: float, p2: float, state, block: int, max_steps: int):
        """Settings.stream of the map's orbit from (p1, p2): rows (t, a, b, solve, E - E0)."""
        s = self.smap
        cols = [0, *(1 + s.system.states.index(v) for v in (*s.coords, s.solve)), -1]
        return ((b.rows(0)[:, cols], b.state) for b in sections.iter_crossings(
            s.system, states=s.states([(p1, p2)]), n_crossings=self.crossings, section=s.section.expr,
            direction=s.direction, tol=self.tol, tmax=s.tmax * self.crossings, max_steps=max_steps, block=block,
            state=state, threads=1))

    def seed_starts(self, seeds) -> list:
        """The scene's ``[seeds]`` on the map's domain (default: a grid of 100 over the region box)."""
        from explorer.analysis.sweep import system_seed_points
        from explorer.io.scene.system import SystemSeeds

        if seeds is None:
            c1, c2, r1, r2 = self.region or (0.0, 0.0, 1.0, 1.0)
            seeds = SystemSeeds(window=(c1 - r1, c1 + r1, c2 - r2, c2 + r2))
        pts, _dropped = system_seed_points(seeds, self.smap)
        if not len(pts):
            raise ParameterError(f"no seed point on the energy surface ({self.smap.describe_domain()})")
        return [(float(a), float(b)) for a, b in pts]


def page_settings(scene=None, system=None, panel: int = 0, flag: str = "", **values) -> tuple:
    """(settings, label, seeds) a page starts from: a System's section map (``system``: a section map or
    'module:attribute'; or ``scene``: a section map or a System's scene), else Chaplygin's model (``scene``'s
    panel ``panel``; None: Figure 4); the ``values`` given (not None) on top, validated; ``flag``: how the
    refusal of a Chaplygin option on a System's page names it."""
    from explorer.analysis.system_sections import is_system_map
    from explorer.io.scene import SeedSpec, SystemScene, load_scene
    from explorer.io.scene.system import resolve_system

    values = {k: v for k, v in values.items() if v is not None}
    if is_system_map(scene):
        system, scene = scene, None
    elif scene is not None:
        scene = load_scene(scene, system=system)
    if scene is None and panel != 0:
        raise ParameterError("panel needs a scene")
    i = 0 if scene is None else validation.integer("panel", panel, 0, scene.n_panels - 1)
    label = "" if scene is None else ": ".join(n for n in (scene.name, scene.panel(i)[2]) if n)
    given = {} if scene is None else {"tol": scene.integration.tol,
                                      "crossings": min(scene.integration.crossings, MAX_CROSSINGS)}
    if system is None and not isinstance(scene, SystemScene):
        params, h = (model.FIGURE4, model.FIGURE4_H) if scene is None else scene.panel(i)[:2]
        if scene is not None:
            integ = scene.integration
            given.update(method=integ.method, dt=integ.dt, phi0=integ.phi0, direction=integ.direction)
        params = params.with_(**{k: values.pop(k) for k in model.PARAM_NAMES if k in values})
        seeds = SeedSpec() if scene is None else scene.seeds
        return Settings(params=params, **{"h": h, **given, **values}), label, seeds
    wrong = [k for k in values if k not in ("h", "tol", "crossings")]
    if wrong:
        raise ParameterError(f"{flag}{wrong[0]} belongs to Chaplygin's model; a System's page takes {flag}h (its "
                             f"energy), {flag}tol and {flag}crossings")
    if scene is not None:
        smap = scene.section_map(i)
    else:
        smap = resolve_system(system, "--system", maps=True)
        if not is_system_map(smap):
            raise ParameterError(f"--system {system!r} is a System without a section: the page shows a section map. "
                                 "Name its map (SectionMap(system, E, section=..., direction=..., coords=(a, b), "
                                 "solve=c) as the attribute) or give a scene of it (explorer serve SCENE.toml "
                                 f"--system {system})")
        label = smap.system.name
    if "h" in values:
        smap = smap.with_value("energy", validation.magnitude(flag + "h", values.pop("h")))
    return SystemSettings(smap, **{**given, **values}), label, None if scene is None else scene.seeds
