"""How the page and its exported figures look, in one place (no web library)."""
from __future__ import annotations

import math

#: colours of the section (as the figures: forbidden region light gray, allowed region white)
FORBIDDEN_COLOR = "#cccccc"
ALLOWED_COLOR = "#ffffff"
BOUNDARY_COLOR = "#262626"
#: the figure's nominal size (px; its aspect kept), least width, the page's height around it, a dot's size
FIGURE_WIDTH = 720
FIGURE_HEIGHT = 560
FIGURE_MIN_WIDTH = 360
FIGURE_CHROME_PX = 200
#: width of a field (two columns of them left of the figure) and of the orbit list (right of it)
FIELD_WIDTH = 100
LIST_WIDTH = 280
#: the page's width beside the figure: the controls, the orbit list, margins and a scroll bar (px)
FIGURE_SIDES_PX = 230 + LIST_WIDTH + 60
POINT_SIZE = 2.0
#: the figure's CSS max-width: as wide as the window leaves it, no taller than the window less the lines around it
FIGURE_MAX_WIDTH = (f"max({FIGURE_MIN_WIDTH}px, min(calc((100vh - {FIGURE_CHROME_PX}px) * "
                    f"{FIGURE_WIDTH / FIGURE_HEIGHT:.6f}), calc(100vw - {FIGURE_SIDES_PX}px)))")
#: a dot's casing on the chaos layer: size (px), fill, edge colour and width
DOT_CASING = (4.5, "#ffffff", "#101010", 0.6)
#: the view shows the region's bounding box and this margin around it (fraction of the semi-axes)
VIEW_MARGIN = 0.08
#: colour scale of the MEGNO layer: <Y> from 0 over 2 (quasi-periodic, light) to MEGNO_HIGH (chaotic, dark)
MEGNO_LOW, MEGNO_HIGH = 0.0, 8.0
#: mean MEGNO above this is called "chaotic-like" (quasi-periodic orbits: <Y> -> 2)
CHAOTIC_MEGNO = 3.0
#: an orbit or a density cell whose MEGNO is unknown (NaN), when orbits are coloured by MEGNO
UNKNOWN_MEGNO_COLOR = "#9e9e9e"
#: periodic orbits of periods 1..PERIODIC_MAX are marked, filled with the colour of their period
PERIOD_COLORS = ("#ffffff", "#f4a582", "#92c5de", "#b8e186")
MESSAGE_ERROR_COLOR = "#b00020"
MESSAGE_OK_COLOR = "#1b5e20"
#: the separatrices: cyan over a dark casing, visible on white and on every colour of the MEGNO layer
SEPARATRIX_COLOR = "#00e5ff"
SEPARATRIX_CASING = "#101010"


def megno_palette(skip: int = 0) -> list:
    """The MEGNO colour scale, light (regular) to dark (chaotic): Inferno reversed, less ``skip`` lightest."""
    from bokeh.palettes import Inferno256  # (a table of colours: no server, no document)

    return list(reversed(Inferno256))[skip:]


def megno_kind(megno: float) -> str:
    """What an orbit's MEGNO <Y> says (the status line's and the readout's words)."""
    if not math.isfinite(megno):
        return "unknown: the run stopped early"
    if megno > CHAOTIC_MEGNO:
        return "chaotic-like"
    return "regular-like" + (": below 0, near a stable periodic orbit, where <Y> tends to 0" if megno < 0 else "")


#: the MEGNO layer's palette and the one of the orbits coloured by MEGNO (without its near-white end)
MEGNO_ORBIT_SKIP = 32
