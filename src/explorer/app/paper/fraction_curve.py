"""The chaotic-fraction curve against mu at high resolution (scene preset ``fraction_curve``:
41 values of mu, 0 and 40 log-spaced over [1e-3, 10], about 1600 seeds each, MEGNO with early
classification, indicators only)."""

from explorer.app.paper._common import Drawn, Outcome, save
from explorer.app.paper.chaotic_fraction import fraction_drawn

#: the figure's name (``explorer figures --only fraction_curve``) and what it shows
NAME = "fraction_curve"
DESCRIPTION = "the chaotic fraction against mu, 41 values x 1600 seeds (preset fraction_curve)"
PRESET = "fraction_curve"


def fraction_curve_figure(*, results_dir="results", quick=False, quiet=True, dpi=200) -> Drawn:
    def title(scene, fr):
        early = " with early classification" if scene.lyapunov.early_stop else ""
        return (f"section $\\varphi = \\pi$ at $h = {scene.h:g}$: {len(fr)} values of $\\mu$, ~{scene.seeds.n} "
                f"seeds each\nMEGNO time {scene.lyapunov.time:g}{early}")

    return fraction_drawn(PRESET, title, results_dir=results_dir, quick=quick, quiet=quiet, dpi=dpi)


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = fraction_curve_figure(results_dir=results_dir, quick=quick, quiet=quiet)
    return Outcome(NAME, "written", save(d, out_dir, NAME), "; ".join(d.notes), d.data)
