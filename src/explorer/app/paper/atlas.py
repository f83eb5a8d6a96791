"""The two-parameter atlas of the chaotic fraction (scene preset ``atlas``: mu, 0 and 15
log-spaced values over [1e-3, 10], against h, 12 energies from 1.25 to 8; 200 grid seeds per cell,
MEGNO over T = 500 with early classification), drawn as a heat map from its stored fractions."""

from explorer.app.paper._common import Drawn, Outcome, save
from explorer.app.paper._sweeps import ensure_sweep

#: the figure's name (``explorer figures --only atlas``) and what it shows
NAME = "atlas"
DESCRIPTION = "chaotic fraction over mu x h, 16 x 12 cells (preset atlas)"
PRESET = "atlas"


def atlas_figure(*, results_dir="results", quick=False, quiet=True, dpi=200) -> Drawn:
    import numpy as np

    from explorer.app.atlas_figure import atlas_heatmap
    from explorer.app.runner import atlas_seeding
    from explorer.io.store.atlas import read_atlas

    scene, out, reduced, _summary = ensure_sweep(PRESET, results_dir=results_dir, quick=quick, quiet=quiet)
    atlas = read_atlas(out)
    ly = scene.lyapunov
    title = (f"chaotic fraction (MEGNO > {ly.threshold:g}, T = {ly.time:g}), {atlas_seeding(scene, atlas)}"
             + (" [reduced settings: figures --quick]" if reduced else ""))
    fig = atlas_heatmap(atlas, title=title, dpi=dpi)
    frac = np.asarray(atlas.fraction, float)
    return Drawn(fig, {"shape": frac.shape, "fraction": frac, "row_values": atlas.row_values,
                       "column_values": atlas.column_values, "store": str(out), "reduced": reduced},
                 [f"from {out}" + ("; reduced settings" if reduced else "")])


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = atlas_figure(results_dir=results_dir, quick=quick, quiet=quiet)
    return Outcome(NAME, "written", save(d, out_dir, NAME), "; ".join(d.notes), d.data)
