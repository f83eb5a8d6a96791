"""The heat map of a two-parameter atlas: the chaotic fraction per cell, rows the [sweep]
values, columns the [atlas] values, equal-size labelled cells, gray without an allowed region."""
from __future__ import annotations

import numpy as np

from explorer.analysis.classification import class_text
from explorer.app.figures import _FONT_SIZE, _TICK_SIZE, FORBIDDEN_COLOR, _matplotlib, symbol_label


def _ticks(values, max_ticks=9):
    n = len(values)
    step = max(1, int(np.ceil(n / max_ticks)))
    idx = list(range(0, n, step))
    return idx, [f"{values[i]:.3g}" for i in idx]


def atlas_heatmap(atlas, *, title="", dpi=200):
    """A Figure of ``atlas`` (:class:`explorer.io.store.atlas.AtlasData`): the chaotic fraction per
    cell as a heat map with a colour bar (0 to 1, named by the indicator that classifies), gray
    where a cell has no allowed region."""
    mpl = _matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    frac = np.asarray(atlas.fraction, float)
    rows, cols = frac.shape
    cmap = mpl.colormaps["magma_r"].with_extremes(bad=FORBIDDEN_COLOR)
    with mpl.rc_context({"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6}):
        fig = Figure(figsize=(min(9.0, max(4.0, 2.0 + 0.32 * cols)), min(9.0, max(3.0, 1.4 + 0.28 * rows))), dpi=dpi,
                     layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.subplots()
        im = ax.imshow(np.ma.masked_invalid(frac), origin="lower", aspect="auto", cmap=cmap, vmin=0.0, vmax=1.0,
                       interpolation="nearest")
        xi, xl = _ticks(atlas.column_values)
        yi, yl = _ticks(atlas.row_values)
        ax.set_xticks(xi, xl, rotation=45, ha="right")
        ax.set_yticks(yi, yl)
        ax.set_xlabel(symbol_label(atlas.column_parameter), fontsize=_FONT_SIZE)
        ax.set_ylabel(symbol_label(atlas.row_parameter), fontsize=_FONT_SIZE)
        ax.tick_params(labelsize=_TICK_SIZE)
        if title:
            ax.set_title(title, fontsize=_TICK_SIZE)
        cb = fig.colorbar(im, ax=ax, fraction=0.05, pad=0.02)
        cb.set_label(f"chaotic fraction ({class_text(atlas.indicator, atlas.threshold)})", fontsize=_FONT_SIZE)
        cb.ax.tick_params(labelsize=_TICK_SIZE)
    return fig
