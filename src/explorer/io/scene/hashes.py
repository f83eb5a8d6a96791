"""What determines a scene's numbers and drawing, and their hashes (panel, products, figure,
atlas): sha256 of the canonical JSON of the settings with FORMAT_VERSION (docs/store.md)."""
from __future__ import annotations

import hashlib
import json

from explorer.io.scene.schema import FORMAT_VERSION
from explorer.io.scene.specs import class_settings


def _canonical_json(obj) -> str:
    """Sorted keys, no spaces, floats by repr (json's float formatting), no NaN."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False, ensure_ascii=True)


def _sha256(payload) -> str:
    return hashlib.sha256(_canonical_json(payload).encode("ascii")).hexdigest()


def panel_settings(scene, i) -> dict:
    """Everything that determines panel i's numbers, as plain JSON-able values."""
    prm, h, _label = scene.panel(i)
    d = {"params": prm.as_dict(), "h": h, "seeds": scene.seeds.used_dict(),
         "integration": scene.integration.used_dict(), "compute": {q: True for q in scene.compute}}
    if "lyapunov" in scene.compute:
        d["lyapunov"] = scene.lyapunov.used_dict()
    return d


def panel_hash(scene, i) -> str:
    """sha256 hex of the canonical JSON of panel_settings(i) and FORMAT_VERSION: the whole
    panel (every product); stored as the panel's ``hash``."""
    return _sha256({"format_version": FORMAT_VERSION, "panel": panel_settings(scene, i)})


def product_settings(scene, i) -> dict:
    """{product: settings} of panel i: ``"sections"`` (the crossings of the [seeds], separatrices)
    and ``"indicators"`` (of the [seeds] or the map's grid); each recomputed only when its own
    settings change (docs/store.md, "Products of a panel")."""
    prm, h, _label = scene.panel(i)
    base = {"params": prm.as_dict(), "h": h}
    out = {}
    if "sections" in scene.compute:
        out["sections"] = dict(base, seeds=scene.seeds.used_dict(), integration=scene.integration.used_dict(),
                               separatrices="separatrices" in scene.compute)
    if "lyapunov" in scene.compute:
        ly = scene.lyapunov.used_dict()
        grid = ly.pop("map_resolution", 0)
        d = dict(base, seeds={"map_resolution": grid} if grid else scene.seeds.used_dict(),
                 phi0=scene.integration.phi0, direction=scene.integration.direction, lyapunov=ly)
        if "sections" not in scene.compute:   # the indicators are the whole panel, separatrices included
            d["alone"] = {"separatrices": "separatrices" in scene.compute}
        out["indicators"] = d
    return out


def product_hashes(scene, i) -> dict:
    """{product: sha256 hex of the canonical JSON of its settings and FORMAT_VERSION}
    (:func:`product_settings`); stored as the panel's ``sections_hash`` / ``indicators_hash``."""
    return {k: _sha256({"format_version": FORMAT_VERSION, k: v}) for k, v in product_settings(scene, i).items()}


def figure_settings(scene) -> str:
    """Canonical JSON of everything that changes the drawing but not the numbers ([figure], with
    [compute] lyapunov the MEGNO threshold and map_indicator, and [manifolds] when drawn): kept in
    the PNG, so a rerun redraws the figure when they change, without recomputing.  [manifolds]
    enters only with draw = true, so the figures of scenes without it keep their settings."""
    d: dict = {"figure": scene.figure.to_dict()}
    if "lyapunov" in scene.compute:
        d.update(threshold=scene.lyapunov.threshold, map_indicator=scene.lyapunov.map_indicator)
    if scene.manifolds.draw:
        d["manifolds"] = scene.manifolds.to_dict()
    return _canonical_json(d)


def atlas_hash(scene) -> str:
    """sha256 of everything that determines an atlas's numbers (both axes, the model, h, seeds,
    integration and [lyapunov] settings; not name, description or figure)."""
    d = {"params": scene.params.as_dict(), "h": scene.h, "rows": [scene.sweep_parameter, list(scene.sweep_values)],
         "columns": [scene.atlas_parameter, list(scene.atlas_values)], "seeds": scene.seeds.used_dict(),
         "phi0": scene.integration.phi0, "direction": scene.integration.direction,
         "lyapunov": scene.lyapunov.used_dict(), "threshold": scene.lyapunov.threshold,
         **class_settings(scene.lyapunov)}
    return _sha256({"format_version": FORMAT_VERSION, "atlas": d})
