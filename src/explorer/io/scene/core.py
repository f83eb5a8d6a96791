"""The :class:`Scene`: a validated Poincaré-section sweep, its panels and (delegated to
:mod:`~explorer.io.scene.hashes`, :mod:`~explorer.io.scene.atlas`, :mod:`~explorer.io.scene.writer`)
its hashes, atlas cells and TOML text."""
from __future__ import annotations

import numbers
from dataclasses import dataclass, field

from explorer import model
from explorer.analysis.seeds import seed_points
from explorer.io.scene import atlas as _atlas
from explorer.io.scene import hashes as _hashes
from explorer.io.scene.checks import (
    SceneError,
    _checked,
    _choice,
    _distinct_reals,
    _fail,
    _got,
    _list,
    _own_scale,
    _scene_name,
    _str,
    _swept,
)
from explorer.io.scene.schema import COMPUTE_QUANTITIES, SWEEP_PARAMETERS
from explorer.io.scene.specs import FigureSpec, IntegrationSpec, LyapunovSpec, ManifoldSpec, SeedSpec
from explorer.io.scene.writer import scene_toml
from explorer.model import PARAM_NAMES, ParameterError, validation


@dataclass(frozen=True)
class Scene:
    """A Poincaré-section sweep, one panel per sweep value, validated on construction; ``text`` is
    its TOML source ("" when built in Python)."""

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
    manifolds: ManifoldSpec = field(default_factory=ManifoldSpec)   # [manifolds]: drawing only

    def __post_init__(self):
        _scene_name(self.name)
        _str("description", self.description)
        _str("text", self.text)
        if not isinstance(self.params, model.Params):
            _fail("model", f"must be a model.Params, {_got(self.params)}")
        object.__setattr__(self, "h", _checked(validation.magnitude, "energy.h", self.h))
        for attr, cls, key in (("seeds", SeedSpec, "seeds"), ("integration", IntegrationSpec, "integration"),
                               ("figure", FigureSpec, "figure"), ("manifolds", ManifoldSpec, "manifolds")):
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
        if self.lyapunov.frequency_diffusion is not None and self.integration.direction == -1:
            _fail("integration.direction", "must be 0 or 1 with the indicator frequency_diffusion (the section map's "
                  "returns cross with M > 0), got -1")
        object.__setattr__(self, "compute", compute)
        self._check_atlas()
        if self.is_atlas and self.manifolds.draw:
            _fail("manifolds.draw", "is not used by an atlas scene (it draws a heat map, no sections)")
        self._check_panels()
        _own_scale(self.figure, self.n_panels)

    def _check_sweep(self):
        if _swept(self, "sweep", SWEEP_PARAMETERS):
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
        fd = self.lyapunov.frequency_diffusion if "lyapunov" in self.compute else None
        if fd is not None:   # the centre's orbit is followed too (explorer.analysis.rotation): a point of the section
            c1, c2 = fd["center"]
            places = [self.panel(i) for i in range(self.n_panels)] if not self.is_atlas else \
                [self.cell(i) for i in range(self.n_cells) if self.cell_allowed(i)]
            for prm, h, label in places:
                if not model.section_M2(prm, c1, c2, h, phi0) > 0.0:
                    _fail("lyapunov.center", f"= {[c1, c2]!r} must lie inside the allowed region of the section "
                          f"(M^2 > 0) of every panel; it does not for {label}")

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
        return _hashes.panel_settings(self, i)

    def panel_hash(self, i) -> str:
        """sha256 hex of the canonical JSON of panel_settings(i) and FORMAT_VERSION: the whole
        panel (every product); stored as the panel's ``hash``."""
        return _hashes.panel_hash(self, i)

    def product_settings(self, i) -> dict:
        """{product: settings} of panel i (:func:`explorer.io.scene.hashes.product_settings`)."""
        return _hashes.product_settings(self, i)

    def product_hashes(self, i) -> dict:
        """{product: sha256 hex of the canonical JSON of its settings and FORMAT_VERSION}
        (:meth:`product_settings`); stored as the panel's ``sections_hash`` / ``indicators_hash``."""
        return _hashes.product_hashes(self, i)

    def figure_settings(self) -> str:
        """Canonical JSON of what changes the drawing but not the numbers, kept in the PNG
        (:func:`explorer.io.scene.hashes.figure_settings`)."""
        return _hashes.figure_settings(self)

    def _check_atlas(self):
        _atlas.check_atlas(self)

    @property
    def is_atlas(self) -> bool:
        return self.atlas_parameter is not None

    @property
    def n_cells(self) -> int:
        """Cells of an atlas: len(sweep.values) x len(atlas.values) (0 for other scenes)."""
        return _atlas.n_cells(self)

    def cell(self, i):
        """(Params, h, label) of atlas cell i = row * len(atlas.values) + column (row: sweep value,
        column: atlas value)."""
        return _atlas.cell(self, i)

    def cell_allowed(self, i) -> bool:
        """The allowed region of the section of cell i is non-empty (else the cell is drawn gray)."""
        return _atlas.cell_allowed(self, i)

    def atlas_hash(self) -> str:
        """sha256 of everything that determines an atlas's numbers (both axes, the model, h, seeds,
        integration and [lyapunov] settings; not name, description or figure)."""
        return _hashes.atlas_hash(self)

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
        d["manifolds"] = self.manifolds.to_dict()
        if self.atlas_parameter is not None:
            d["atlas"] = {"parameter": self.atlas_parameter, "values": list(self.atlas_values)}
        return d

    def to_toml(self) -> str:
        """TOML text of :meth:`to_dict` (``parse_scene(s.to_toml())`` equals ``s`` but for ``text``)."""
        return scene_toml(self.to_dict())
