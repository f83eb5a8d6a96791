"""MEGNO maps of the Figure-4 panels (scene preset ``chaos``)."""


from explorer.app.paper._common import Drawn, Outcome, save
from explorer.app.paper._sweeps import _lyapunov_panels, _quick_note, ensure_sweep

#: the figure's name (``explorer figures --only chaos_map``) and what it shows
NAME = "chaos_map"
DESCRIPTION = "MEGNO maps of the Figure-4 panels (preset chaos)"


def chaos_map_figure(*, results_dir="results", quick=False, quiet=True) -> Drawn:
    from explorer.app import figures

    scene, out, reduced, summary = ensure_sweep("chaos", results_dir=results_dir, quick=quick, quiet=quiet)
    maps, fr = _lyapunov_panels(scene, out)
    fig = figures.chaos_maps(maps, layout=scene.figure.layout, columns=scene.figure.columns,
                             threshold=scene.lyapunov.threshold, dpi=scene.figure.dpi)
    if reduced:
        fig.text(0.99, 0.005, _quick_note(scene), ha="right", va="bottom", fontsize=6, color="#b2182b")
    return Drawn(fig, {"panels": len(maps), "fraction": fr[:, 1] if len(fr) else [], "store": str(out),
                       "reduced": reduced}, [f"from {out}" + (f"; {_quick_note(scene)}" if reduced else "")])


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = chaos_map_figure(results_dir=results_dir, quick=quick, quiet=quiet)
    return Outcome(NAME, "written", save(d, out_dir, NAME), "; ".join(d.notes), d.data)
