"""A browser session as a scene (docs/scenes.md) that ``explorer sweep`` reruns crossing for
crossing, its orbits as a store in the sweep's format (docs/store.md) and its figure files:
written only into ``--export-dir``, under names made here, atomically.
"""
from __future__ import annotations

import os
import time

from explorer.app.serve.settings import Settings
from explorer.io import scene as scene_mod
from explorer.model import ParameterError

#: name of an exported scene (a scene name: letters, digits, _ . -)
SCENE_NAME = "browser-session"


def session_scene(settings: Settings, starts, name: str = SCENE_NAME, overlays: tuple = ()) -> scene_mod.Scene:
    """The scene of a session: one panel, the admissible ``starts`` [(p1, p2), ...] as points
    (ParameterError when there is none).  ``overlays``: the page's overlays that are on (their URL names,
    ``SectionPage.overlays_on``): "separatrices" becomes [compute] separatrices = true (a sweep draws them);
    every one is named in the description (a scene has no field for the page's other layers)."""
    points = tuple((float(a), float(b)) for a, b in starts if settings.admissible(a, b))
    if not points:
        raise ParameterError("export: no orbit inside the allowed region yet; click on the section first")
    seeds = scene_mod.SeedSpec(kind="points", points=points, n=len(points))
    integ = scene_mod.IntegrationSpec(method=settings.method, tol=settings.tol, dt=settings.dt,
                                      crossings=settings.crossings, phi0=settings.phi0,
                                      direction=settings.direction)
    compute = ("sections", "separatrices") if "separatrices" in overlays else ("sections",)
    shown = f"; overlays on the page: {', '.join(overlays)}" if overlays else "; no overlay on the page"
    return scene_mod.Scene(name=name, params=settings.params, h=settings.h, seeds=seeds, integration=integ,
                           compute=compute, description="orbits clicked in `explorer serve`" + shown)


def write_scene(directory, scene: scene_mod.Scene) -> str:
    """Write ``scene`` as TOML into ``directory`` (atomically); returns the file's path."""
    from explorer.io.store.atomic import write_bytes_atomic

    stamp = time.strftime("%Y%m%dT%H%M%S", time.gmtime())
    path = os.path.join(os.fspath(directory), f"{scene.name}-{stamp}.toml")
    n = 1
    while os.path.exists(path):
        n += 1
        path = os.path.join(os.fspath(directory), f"{scene.name}-{stamp}-{n}.toml")
    write_bytes_atomic(path, scene.to_toml().encode("utf-8"))
    return path


def write_figure(directory, view, name: str = SCENE_NAME) -> list:
    """Write the page's ``view`` (:class:`explorer.app.serve.image.View`) as
    ``<name>-<UTC time>.png`` and ``.svg`` into ``directory`` (atomically); returns their paths."""
    from explorer.app.serve.image import FORMATS, render
    from explorer.io.store.atomic import write_bytes_atomic

    stamp = time.strftime("%Y%m%dT%H%M%S", time.gmtime())
    stem = os.path.join(os.fspath(directory), f"{name}-{stamp}")
    n = 1
    while any(os.path.exists(f"{stem}.{fmt}") for fmt in FORMATS):
        n += 1
        stem = os.path.join(os.fspath(directory), f"{name}-{stamp}-{n}")
    paths = []
    for fmt in FORMATS:
        write_bytes_atomic(f"{stem}.{fmt}", render(view, fmt))
        paths.append(f"{stem}.{fmt}")
    return paths


def write_store(scene_path) -> str:
    """Run the scene written by :func:`write_scene` into the store next to it (``.h5`` for
    ``.toml``; the sweep's own atomic commit); returns the store's path."""
    from explorer.app.runner import run_sweep

    out = os.path.splitext(os.fspath(scene_path))[0] + ".h5"
    run_sweep(os.fspath(scene_path), out, draw=False, progress=False)
    return out
