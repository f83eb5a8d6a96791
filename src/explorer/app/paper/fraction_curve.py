"""The chaotic-fraction curve against mu at high resolution (scene preset ``fraction_curve``:
41 values of mu, 0 and 40 log-spaced over [1e-3, 10], about 1600 seeds each, MEGNO with early
classification, indicators only)."""

from explorer.app.paper._common import Drawn, Outcome, save
from explorer.app.paper._sweeps import _lyapunov_panels, _quick_note, ensure_sweep

#: the figure's name (``explorer figures --only fraction_curve``) and what it shows
NAME = "fraction_curve"
DESCRIPTION = "the chaotic fraction against mu, 41 values x 1600 seeds (preset fraction_curve)"
PRESET = "fraction_curve"


def fraction_curve_figure(*, results_dir="results", quick=False, quiet=True, dpi=200) -> Drawn:
    from explorer.app import figures

    scene, out, reduced, _summary = ensure_sweep(PRESET, results_dir=results_dir, quick=quick, quiet=quiet)
    _maps, fr = _lyapunov_panels(scene, out)
    fig = figures.fraction_curve(fr[:, 0], fr[:, 1], fr[:, 2], parameter=scene.sweep_parameter or "mu",
                                 threshold=scene.lyapunov.threshold, dpi=dpi)
    ax = fig.axes[0]
    ax.set_xlabel(r"$\mu$")
    early = " with early classification" if scene.lyapunov.early_stop else ""
    ax.set_title(f"section $\\varphi = \\pi$ at $h = {scene.h:g}$: {len(fr)} values of $\\mu$, ~{scene.seeds.n} seeds "
                 f"each\nMEGNO time {scene.lyapunov.time:g}{early}", fontsize=7)
    if reduced:
        ax.text(0.02, 0.97, _quick_note(scene), transform=ax.transAxes, ha="left", va="top", fontsize=6,
                color="#b2182b")
    return Drawn(fig, {"values": fr[:, 0], "fraction": fr[:, 1], "error": fr[:, 2], "store": str(out),
                       "reduced": reduced}, [f"from {out}" + (f"; {_quick_note(scene)}" if reduced else "")])


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = fraction_curve_figure(results_dir=results_dir, quick=quick, quiet=quiet)
    return Outcome(NAME, "written", save(d, out_dir, NAME), "; ".join(d.notes), d.data)
