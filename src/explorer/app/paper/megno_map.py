"""The high-resolution MEGNO raster map of Figure 4's mu = 0.03 panel (scene preset ``megno_map``:
512 x 512 cells, T = 1000, indicators only; adaptive unless the scene's [lyapunov] exact, the
fraction of cells computed in the raster's corner).  The stored panel is redrawn from its grid geometry
when the store is complete; ``--quick`` otherwise computes a 64 x 64 map over T = 200."""

from explorer.app.paper._common import Drawn, Outcome, save
from explorer.app.paper._sweeps import ensure_sweep

#: the figure's name (``explorer figures --only megno_map``) and what it shows
NAME = "megno_map"
DESCRIPTION = "512 x 512 MEGNO raster map of Figure 4's mu = 0.03 panel (preset megno_map)"
PRESET = "megno_map"


def quick_note(scene) -> str:
    ly = scene.lyapunov
    return (f"reduced settings (figures --quick): {ly.map_resolution} x {ly.map_resolution} cells, "
            f"MEGNO time {ly.time:g}")


def megno_map_figure(*, results_dir="results", quick=False, quiet=True) -> Drawn:
    from explorer.app.chaos_raster import chaos_rasters
    from explorer.app.paper._sweeps import _lyapunov_panels
    from explorer.app.runner import raster_maps

    scene, out, reduced, _summary = ensure_sweep(PRESET, results_dir=results_dir, quick=quick, quiet=quiet)
    maps, _fr = _lyapunov_panels(scene, out)
    maps = raster_maps(scene, maps)
    ind = scene.lyapunov.map_indicator
    fig = chaos_rasters(maps, indicator=ind, threshold=scene.lyapunov.threshold, columns=1, dpi=scene.figure.dpi)
    notes = [f"from {out}"]
    if reduced:
        notes.append(quick_note(scene))
        fig.text(0.99, 0.005, quick_note(scene), ha="right", va="bottom", fontsize=6, color="#b2182b")
    m = maps[0]
    return Drawn(fig, {"resolution": int(m["grid"][0]), "grid": tuple(m["grid"]), "orbits": len(m["seeds"]),
                       "fraction": float(m["fraction"]), "computed": m["computed"], "store": str(out),
                       "reduced": reduced}, notes)


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = megno_map_figure(results_dir=results_dir, quick=quick, quiet=quiet)
    return Outcome(NAME, "written", save(d, out_dir, NAME), "; ".join(d.notes), d.data)
