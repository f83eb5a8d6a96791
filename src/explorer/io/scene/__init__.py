"""Scenes: what a Poincaré-section sweep computes and how it is drawn, read from TOML.

The format, every key, its default and its checks: docs/scenes.md.  Pure Python and numpy (no
numba, h5py or matplotlib); every public name is importable from ``explorer.io.scene``.
"""
from __future__ import annotations

from explorer.analysis.seeds import grid_spacing, seed_points
from explorer.io.scene import schema
from explorer.io.scene.checks import SceneError
from explorer.io.scene.core import Scene
from explorer.io.scene.hashes import _canonical_json
from explorer.io.scene.loading import PRESETS, load_scene, parse_scene, scene_from_dict
from explorer.io.scene.schema import *  # noqa: F403  (the names of schema.__all__)
from explorer.io.scene.specs import FigureSpec, IntegrationSpec, LyapunovSpec, ManifoldSpec, SeedSpec
from explorer.io.scene.system import SystemScene, resolve_system
from explorer.io.scene.writer import _toml_string, _toml_value

__all__ = [
    "PRESETS", "FigureSpec", "IntegrationSpec", "LyapunovSpec", "ManifoldSpec", "Scene", "SceneError", "SeedSpec",
    "SystemScene", "grid_spacing", "load_scene", "parse_scene", "resolve_system", "scene_from_dict", "seed_points",
    # the writer's helpers, for the tests
    "_canonical_json", "_toml_string", "_toml_value",
]
__all__ += schema.__all__   # the keys, limits and defaults (explorer.io.scene.schema)
