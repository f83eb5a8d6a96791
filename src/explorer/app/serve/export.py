"""The page's exports (docs/commands/serve.md): the session's scene (docs/scenes.md) and store (docs/store.md),
the view as PNG/SVG; files go only into ``--export-dir``, under names made here, atomically."""
from __future__ import annotations

import io
import os
import time

from explorer.app.serve.image import FORMATS, render
from explorer.app.serve.settings import Settings
from explorer.app.serve.tasks import failure
from explorer.io import scene as scene_mod
from explorer.model import ParameterError

#: name of an exported scene (a scene name: letters, digits, _ . -)
SCENE_NAME = "browser-session"


def session_scene(settings: Settings, starts, overlays: tuple = ()) -> scene_mod.Scene:
    """The scene of a session (named SCENE_NAME): one panel, the admissible ``starts`` as points (ParameterError: none).
    ``overlays`` (URL names): "separatrices" is computed by the sweep; each is named in the description."""
    points = tuple((float(a), float(b)) for a, b in starts if settings.admissible(a, b))
    if not points:
        raise ParameterError("export: no orbit inside the allowed region yet; click on the section first")
    seeds = scene_mod.SeedSpec(kind="points", points=points, n=len(points))
    integ = scene_mod.IntegrationSpec(crossings=settings.crossings, **settings.section_kwargs())
    compute = ("sections", "separatrices") if "separatrices" in overlays else ("sections",)
    shown = f"; overlays on the page: {', '.join(overlays)}" if overlays else "; no overlay on the page"
    return scene_mod.Scene(name=SCENE_NAME, params=settings.params, h=settings.h, seeds=seeds, integration=integ,
                           compute=compute, description="orbits clicked in `explorer serve`" + shown)


def write_files(directory, name: str, contents: dict) -> list:
    """Write ``contents`` ({extension: bytes}) as ``directory/name-<UTC time>[-n].<extension>``, atomically, over
    no existing file; returns their paths."""
    from explorer.io.store.atomic import write_bytes_atomic

    stamp = time.strftime("%Y%m%dT%H%M%S", time.gmtime())
    stem, n = os.path.join(os.fspath(directory), f"{name}-{stamp}"), 1
    while any(os.path.exists(f"{stem}.{ext}") for ext in contents):
        n += 1
        stem = os.path.join(os.fspath(directory), f"{name}-{stamp}-{n}")
    for ext, data in contents.items():
        write_bytes_atomic(f"{stem}.{ext}", data)
    return [f"{stem}.{ext}" for ext in contents]


def write_scene(directory, scene: scene_mod.Scene) -> str:
    """Write ``scene`` as TOML into ``directory`` (:func:`write_files`); returns the file's path."""
    return write_files(directory, scene.name, {"toml": scene.to_toml().encode("utf-8")})[0]


def write_figure(directory, view) -> list:
    """Write the page's ``view`` as PNG and SVG into ``directory`` (:func:`write_files`); returns their paths."""
    return write_files(directory, SCENE_NAME, {fmt: render(view, fmt) for fmt in FORMATS})


def write_store(scene_path) -> str:
    """Run the scene written by :func:`write_scene` into the store next to it (``.h5``); returns its path."""
    from explorer.app.runner import run_sweep

    out = os.path.splitext(os.fspath(scene_path))[0] + ".h5"
    run_sweep(os.fspath(scene_path), out, draw=False, progress=False)
    return out


class Exports:
    """Scene and figure exports of a page: ``scene()`` its session's scene (:func:`session_scene`),
    ``view()`` what it shows (:class:`~explorer.app.serve.image.View`), ``say`` its message line."""

    def __init__(self, session, export_dir, scene, view, say):
        self.session, self.export_dir, self.scene, self.view, self.say = session, export_dir, scene, view, say

    def download(self, fmt: str):
        """A download button's file: the scene ("toml") or the view ("png", "svg"); empty, and why said, if it fails."""
        try:
            return io.BytesIO(self.scene().to_toml().encode("utf-8") if fmt == "toml" else render(self.view(), fmt))
        except ParameterError as exc:
            self.say(str(exc))
        except Exception as exc:  # noqa: BLE001 - reported in the page; the download is empty
            self.say(f"{fmt} download failed: {failure(exc)}")
        return io.BytesIO(b"")

    def export_figure(self) -> None:
        """Write the page's view as PNG and SVG into the export directory (drawn by a task)."""
        self.say("writing the figure ...", ok=True)
        self.session.start("figure", self._write(write_figure, (self.export_dir, self.view()), "figure export",
                                                 lambda paths: "figure written: " + " and ".join(
                                                     map(os.path.basename, paths))))

    def export(self) -> None:
        """Write the session's scene into the export directory (its store follows in a task)."""
        try:
            path = write_scene(self.export_dir, self.scene())
        except (ParameterError, OSError) as exc:
            self.say(f"export failed: {exc}")
            return
        name = os.path.basename(path)
        self.say(f"scene written: {name} (rerun: explorer sweep {name}); writing the orbits' store ...", ok=True)
        self.session.start("store", self._write(write_store, (path,), "store export", lambda out: (
            f"written: {name} and {os.path.basename(out)} (the orbits, sweep format)")))

    async def _write(self, fn, args, what: str, said):
        try:
            text, ok = said(await self.session.run(fn, *args)), True
        except Exception as exc:  # noqa: BLE001 - reported in the page
            text, ok = f"{what} failed: {failure(exc)}", False
        await self.session.apply(lambda: self.say(text, ok))
