"""Reading scenes: from nested tables, TOML text, a file or a built-in preset."""
from __future__ import annotations

import os
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

from explorer import model
from explorer.io.scene.atlas import _atlas_from_dict
from explorer.io.scene.checks import SceneError, _bool, _fail, _got, _list, _real, _sweep, _table
from explorer.io.scene.core import Scene
from explorer.io.scene.schema import (
    _FIGURE_KEYS,
    _INTEGRATION_KEYS,
    _LYAPUNOV_KEYS,
    _MANIFOLD_KEYS,
    _SEED_KEYS,
    _TOP_KEYS,
    COMPUTE_DEFAULTS,
    COMPUTE_QUANTITIES,
)
from explorer.io.scene.specs import FigureSpec, IntegrationSpec, LyapunovSpec, ManifoldSpec, SeedSpec
from explorer.io.scene.system import SystemScene, is_system_scene, system_scene_from_dict
from explorer.model import PARAM_NAMES, ParameterError, validation


def scene_from_dict(data: dict, text: str = "", system=None):
    """A validated :class:`Scene` from nested tables (as produced by ``tomllib``); a
    :class:`~explorer.io.scene.system.SystemScene` when they name a ``system`` or ``system`` (a
    System or 'module:attribute') is given."""
    if is_system_scene(data, system):
        return system_scene_from_dict(data, text, system)
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

    kw.update(_sweep(data))

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
    mf = dict(_table("manifolds", data.get("manifolds", {}), _MANIFOLD_KEYS))
    if "guess" in mf:
        mf["guess"] = tuple(_list("manifolds.guess", mf["guess"]))
    kw["manifolds"] = ManifoldSpec(**mf)
    kw.update(_atlas_from_dict(data))
    return Scene(**kw)


def parse_scene(text: str, source: str = "<string>", system=None):
    """A validated scene from TOML text (``source`` names it in syntax errors; ``system``: as
    :func:`scene_from_dict`)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        msg = " ".join(str(e).split())
        raise SceneError(f"scene: TOML syntax error in {source}: {msg}") from None
    return scene_from_dict(data, text=text, system=system)


def load_scene(spec, system=None):
    """A scene: a preset by name (:data:`PRESETS`), else the path of a ``.toml`` file, validated
    (:class:`SceneError` names the dotted key; docs/scenes.md); ``system`` (a System or
    'module:attribute') gives or replaces a System's scene's ``system``.  A scene object is returned as it is."""
    if isinstance(spec, (Scene, SystemScene)) and system is None:
        return spec
    if isinstance(spec, str) and spec in PRESETS:
        return parse_scene(PRESETS[spec], source=f"preset '{spec}'", system=system)
    path = Path(os.fspath(spec))
    if not path.is_file():
        raise SceneError(f"scene: no built-in preset or file named '{path}' "
                         f"(presets: {', '.join(sorted(PRESETS))})")
    try:
        text = path.read_bytes().decode("utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SceneError(f"scene: cannot read '{path}': {' '.join(str(e).split())}") from None
    return parse_scene(text, source=str(path), system=system)


def _read_presets() -> dict:
    """Built-in scenes: name -> TOML text, from the files ``explorer/io/presets/*.toml``."""
    from importlib.resources import files

    folder = files("explorer.io").joinpath("presets")
    return {f.name[:-5]: f.read_text(encoding="utf-8")
            for f in sorted(folder.iterdir(), key=lambda f: f.name) if f.name.endswith(".toml")}


#: Built-in scenes: name -> TOML text (``src/explorer/io/presets/<name>.toml``, each complete).
PRESETS = _read_presets()
