"""The [atlas] of a scene: two swept parameters, [sweep] (rows) x [atlas] (columns), storing only the
chaotic fraction per cell (indicators only).  The :class:`~explorer.io.scene.Scene` methods
``cell``, ``cell_allowed``, ``n_cells`` and ``is_atlas`` call these."""
from __future__ import annotations

import numbers

from explorer import model
from explorer.io.scene.checks import SceneError, _distinct_reals, _fail, _list, _str, _swept, _table
from explorer.io.scene.schema import SWEEP_PARAMETERS
from explorer.model import ParameterError


def check_atlas(scene, parameters=SWEEP_PARAMETERS) -> None:
    """[atlas]: a scene of two swept ``parameters``, [sweep] (rows) x [atlas] (columns), storing
    only the chaotic fraction per cell (indicators only)."""
    if not _swept(scene, "atlas", parameters):
        return
    if scene.sweep_parameter is None:
        _fail("sweep.parameter", "is required in an atlas scene (the atlas sweeps [sweep] x [atlas])")
    if scene.atlas_parameter == scene.sweep_parameter:
        _fail("atlas.parameter", f"must differ from sweep.parameter ({scene.sweep_parameter!r})")
    if "lyapunov" not in scene.compute or "sections" in scene.compute or "separatrices" in scene.compute:
        _fail("compute", "of an atlas scene must be lyapunov = true, sections = false, separatrices = false "
              "(an atlas stores only the chaotic fraction per cell)")
    object.__setattr__(scene, "atlas_values", _distinct_reals("atlas.values", scene.atlas_values))
    for i in range(scene.n_cells):
        try:
            scene.cell(i)
        except ParameterError as e:
            r, c = divmod(i, len(scene.atlas_values))
            raise SceneError(f"scene key 'atlas.values[{c}]' ({cell_label(scene, r, c)}): {e}") from None


def n_cells(scene) -> int:
    """Cells of an atlas: len(sweep.values) x len(atlas.values) (0 for other scenes)."""
    return len(scene.sweep_values) * len(scene.atlas_values) if scene.is_atlas else 0


def cell_label(scene, r, c) -> str:
    return (f"{scene.sweep_parameter} = {scene.sweep_values[r]!r}, "
            f"{scene.atlas_parameter} = {scene.atlas_values[c]!r}")


def cell(scene, i):
    """(Params, h, label) of atlas cell i = row * len(atlas.values) + column (row: sweep value,
    column: atlas value)."""
    if not scene.is_atlas or isinstance(i, bool) or not isinstance(i, numbers.Integral) \
            or not 0 <= int(i) < scene.n_cells:
        raise IndexError(f"atlas cell index must be an integer in [0, {scene.n_cells - 1}], got {i!r}")
    r, c = divmod(int(i), len(scene.atlas_values))
    upd: dict = {}
    h = scene.h
    for name, v in ((scene.sweep_parameter, scene.sweep_values[r]), (scene.atlas_parameter, scene.atlas_values[c])):
        if name == "h":
            h = v
        else:
            upd[name] = v
    return scene.params.with_(**upd), h, cell_label(scene, r, c)


def cell_allowed(scene, i) -> bool:
    """The allowed region of the section of cell i is non-empty (else the cell is drawn gray)."""
    prm, h, _label = scene.cell(i)
    ell = model.allowed_ellipse(prm, h, scene.integration.phi0)
    return ell is not None and ell[2] > 0.0 and ell[3] > 0.0


def _atlas_from_dict(data: dict) -> dict:
    if "atlas" not in data:
        return {}
    atlas = _table("atlas", data["atlas"], ("parameter", "values"))
    for k in ("parameter", "values"):
        if k not in atlas:
            _fail(f"atlas.{k}", "is required in an [atlas] table")
    return {"atlas_parameter": _str("atlas.parameter", atlas["parameter"]),
            "atlas_values": tuple(_list("atlas.values", atlas["values"]))}
