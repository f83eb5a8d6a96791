"""The chaotic fraction against mu (scene preset ``fraction``)."""


from explorer.app.paper._common import Drawn, Outcome, save
from explorer.app.paper._sweeps import _lyapunov_panels, _quick_note, ensure_sweep

#: the figure's name (``explorer figures --only chaotic_fraction``) and what it shows
NAME = "chaotic_fraction"
DESCRIPTION = "the chaotic fraction against mu (preset fraction)"


def fraction_drawn(preset, title, *, results_dir="results", quick=False, quiet=True, dpi=200) -> Drawn:
    """The chaotic fraction against the swept parameter of a stored (or computed) sweep of
    ``preset``, titled by ``title(scene, rows)``: the figure of this module and of
    :mod:`explorer.app.paper.fraction_curve`."""
    from explorer.app import figures

    scene, out, reduced, _summary = ensure_sweep(preset, results_dir=results_dir, quick=quick, quiet=quiet)
    _maps, fr = _lyapunov_panels(scene, out)
    fig = figures.fraction_curve(fr[:, 0], fr[:, 1], fr[:, 2], parameter=scene.sweep_parameter or "mu",
                                 threshold=scene.lyapunov.threshold, dpi=dpi)
    ax = fig.axes[0]   # x-label: the parameter's symbol (figures.symbol_label)
    text = title(scene, fr)
    ax.set_title(text, fontsize=7 if "\n" in text else 8)
    if reduced:
        ax.text(0.02, 0.97, _quick_note(scene), transform=ax.transAxes, ha="left", va="top", fontsize=6,
                color="#b2182b")
    return Drawn(fig, {"values": fr[:, 0], "fraction": fr[:, 1], "error": fr[:, 2], "store": str(out),
                       "reduced": reduced}, [f"from {out}" + (f"; {_quick_note(scene)}" if reduced else "")])


def chaotic_fraction_figure(*, results_dir="results", quick=False, quiet=True, dpi=200) -> Drawn:
    return fraction_drawn("fraction", lambda scene, fr: (
        f"section $\\varphi = \\pi$ at $h = {scene.h:g}$: {scene.seeds.n} seeds per panel, "
        f"MEGNO time {scene.lyapunov.time:g}"), results_dir=results_dir, quick=quick, quiet=quiet, dpi=dpi)


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = chaotic_fraction_figure(results_dir=results_dir, quick=quick, quiet=quiet)
    return Outcome(NAME, "written", save(d, out_dir, NAME), "; ".join(d.notes), d.data)
