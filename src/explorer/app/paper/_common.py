"""Shared pieces of the paper's figures: the Chaplygin parameters, the style, the result types."""
from dataclasses import dataclass, field
from pathlib import Path

from explorer import model

#: the parameters of the seed's Figures 2 and 3: lam = 1, b = 2, a1 = 1, a2 = 1/2, chi = zeta = 0
#: (mu = 0: Chaplygin's case, docs/model.md R6; Figure 4's scene at mu = 0)
CHAPLYGIN = model.FIGURE4.with_(mu=0.0)
#: the energies of Figure 2, one in each interval of the seed, (0, b lam^2/(2 a1^2)) = (0, 1),
#: (1, b lam^2/(2 a2^2)) = (1, 4), (4, inf); h = 2 is Figure 4's level
FIGURE2_ENERGIES = (0.5, 2.0, 6.0)
#: Taylor tolerance of the dense integrations
DENSE_TOL = 1e-14

_FS = 9       # font size of labels
_TS = 8       # tick labels
_SMALL = 7    # annotations
_RC = {"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6, "font.size": _FS,
       "xtick.labelsize": _TS, "ytick.labelsize": _TS, "legend.fontsize": _SMALL,
       "xtick.direction": "in", "ytick.direction": "in", "xtick.top": True, "ytick.right": True,
       "xtick.major.width": 0.5, "ytick.major.width": 0.5, "xtick.minor.width": 0.4,
       "ytick.minor.width": 0.4, "lines.linewidth": 1.0}


class FigureUnavailable(Exception):
    """A figure that cannot be made here (an input is missing, e.g. the W4 results): reported, not an error."""


@dataclass
class Drawn:
    """A figure and the numbers it shows (for tests and reports)."""

    fig: object
    data: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)


@dataclass
class Outcome:
    name: str
    status: str            # "written", "not available", "skipped", "failed"
    paths: list = field(default_factory=list)
    message: str = ""
    data: dict = field(default_factory=dict)

    def line(self) -> str:
        if self.status == "written":
            s = f"{self.name}: " + ", ".join(str(p) for p in self.paths)
            return s + (f"  ({self.message})" if self.message else "")
        return f"{self.name}: {self.status}" + (f" ({self.message})" if self.message else "")


def _new_figure(figsize, dpi=200, layout="constrained"):
    from explorer.app.figures import _matplotlib

    _matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi, layout=layout)
    FigureCanvasAgg(fig)
    return fig


def _rc():
    from explorer.app.figures import _matplotlib

    return _matplotlib().rc_context(_RC)


def save(drawn, out_dir, name):
    """Write ``drawn.fig`` as ``<out_dir>/<name>.png`` and ``.pdf``; returns the paths."""
    from explorer.app.figures import save_figure

    return [Path(p) for p in save_figure(drawn.fig, Path(out_dir) / name)]
