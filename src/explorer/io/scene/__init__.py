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
    [manifolds]                      # drawing only: W^u and W^s over each panel (docs/manifolds.md)
    draw = false                     # true: overlay the manifolds of the orbit below
    arclength = 6.0                  # length of each branch, in (0, 1000]
    guess = [0.0, 0.0]               # Newton's start for the orbit, [p1, p2]
    period = 1                       # period K of the orbit, in [1, 64]
    max_points = 20000               # points per branch at most, in [3, 1000000]

Defaults of [seeds]: kind "grid", n 200, margin 0.98, seed 0.  Defaults of
[integration]: taylor, tol ``sections.DEFAULT_TOL``, dt ``sections.DEFAULT_DT``,
1000 crossings, max_steps ``sections.DEFAULT_MAX_STEPS``, phi0 = pi, direction 1.
Defaults of [figure]: row, share_scale true, own_scale [], marker_size 0.25, dpi 200.
Defaults of [manifolds]: draw false, arclength 6, guess [0, 0], period 1, max_points 20000.

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
description, figure, manifolds and the panel's position do not enter the hash.
The products of a panel, sections and indicators, have their own hashes
(:meth:`Scene.product_hashes`): a sweep recomputes only the product whose
settings changed.  :meth:`Scene.figure_settings` are the drawing settings.

Modules
-------
:mod:`~explorer.io.scene.schema` the keys, allowed values and defaults;
:mod:`~explorer.io.scene.checks` the validators (:class:`SceneError` naming the dotted key);
:mod:`~explorer.io.scene.specs` the [seeds], [integration], [lyapunov], [figure] and [manifolds] tables;
:mod:`~explorer.io.scene.core` the :class:`Scene` and its panels;
:mod:`~explorer.io.scene.hashes` the panel, product, figure and atlas hashes;
:mod:`~explorer.io.scene.atlas` the cells of an [atlas];
:mod:`~explorer.io.scene.writer` the TOML writer;
:mod:`~explorer.io.scene.loading` reading TOML, files and the built-in :data:`PRESETS`.
Every public name is importable from ``explorer.io.scene``.
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
from explorer.io.scene.writer import _toml_string, _toml_value

__all__ = [
    "PRESETS", "FigureSpec", "IntegrationSpec", "LyapunovSpec", "ManifoldSpec", "Scene", "SceneError", "SeedSpec",
    "grid_spacing", "load_scene", "parse_scene", "scene_from_dict", "seed_points",
    # the writer's helpers, for the tests
    "_canonical_json", "_toml_string", "_toml_value",
]
__all__ += schema.__all__   # the keys, limits and defaults (explorer.io.scene.schema)
