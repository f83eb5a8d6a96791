"""Figures computed from stored sweeps: the scene's store is reused when complete with the
same settings hash (:func:`explorer.app.runner.run_sweep` computes only what is missing); with
``quick`` an incomplete store is replaced by a reduced copy of the scene named ``<scene>-quick``."""
from pathlib import Path

#: reduced scenes of ``quick``: (table, key) -> value
QUICK_SCENES = {
    "figure4": {("seeds", "n"): 40, ("integration", "crossings"): 200, ("integration", "tmax"): 2000.0},
    "chaos": {("seeds", "n"): 100, ("integration", "crossings"): 20, ("lyapunov", "time"): 200.0},
    "fraction": {("seeds", "n"): 60, ("integration", "crossings"): 20, ("integration", "tmax"): 400.0,
                 ("lyapunov", "time"): 200.0},
    "fraction_curve": {("seeds", "n"): 60, ("lyapunov", "time"): 200.0},
    "megno_map": {("lyapunov", "map_resolution"): 64, ("lyapunov", "time"): 200.0},
    "atlas": {("seeds", "n"): 24, ("lyapunov", "time"): 100.0},
}

def _quick_scene(name, results_dir):
    """A reduced copy of a preset scene (QUICK_SCENES), written as a TOML file; returns its path."""
    from explorer.io import scene as sc

    d = sc.load_scene(name).to_dict()
    d["name"] = f"{name}-quick"
    d["description"] = (d.get("description") or "") + " [reduced settings of `figures --quick`]"
    for (table, key), v in QUICK_SCENES[name].items():
        d[table][key] = v
    s = sc.scene_from_dict(d)
    path = Path(results_dir) / f"{s.name}.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    text = s.to_toml()
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return path


def store_complete(scene, path) -> bool:
    """True when every panel of ``scene`` is stored in ``path`` with its settings hash (an atlas:
    when its file holds this atlas, :meth:`~explorer.io.scene.Scene.atlas_hash`)."""
    from explorer.io import store

    if scene.is_atlas:
        from explorer.io.store.atlas import read_atlas

        try:
            return read_atlas(path).hash == scene.atlas_hash()
        except (OSError, ValueError, KeyError):
            return False

    try:
        on_disk = store.panel_hashes(path)
    except store.StoreError:
        return False
    return all(on_disk.get(i) == scene.panel_hash(i) for i in range(scene.n_panels))


def ensure_sweep(preset, *, results_dir="results", quick=False, quiet=True):
    """The scene and store of a preset, computing what is missing with
    :func:`explorer.app.runner.run_sweep` (complete panels with the same hash are skipped).
    Under ``quick`` an incomplete full store is left alone and the reduced scene is used.
    Returns (scene, store path, reduced?, summary text)."""
    from explorer.app import runner
    from explorer.io.scene import load_scene

    results_dir = Path(results_dir)
    scene = load_scene(preset)
    out = results_dir / f"{scene.name}.h5"
    reduced = False
    spec = preset
    if quick and not store_complete(scene, out):
        spec = str(_quick_scene(preset, results_dir))
        scene = load_scene(spec)
        out = results_dir / f"{scene.name}.h5"
        reduced = True
    report = runner.run_sweep(scene, out, draw=False, progress=not quiet)
    return scene, out, reduced, runner.format_report(report)


def _quick_note(scene):
    s = scene
    bits = [f"{s.seeds.n} seeds", f"{s.integration.crossings} crossings"]
    if "lyapunov" in s.compute:
        bits.append(f"MEGNO time {s.lyapunov.time:g}")
    return "reduced settings (figures --quick): " + ", ".join(bits)


def _lyapunov_panels(scene, out):
    from explorer.app.runner import lyapunov_panels
    from explorer.io import store

    return lyapunov_panels(scene, store.read_store(out))
