"""The keys of a scene, what each table allows, and the defaults (plain constants)."""
from __future__ import annotations

import re

from explorer.kernels.indicator_table import NAMES as INDICATOR_NAMES
from explorer.model import PARAM_NAMES

#: Version of the panel-settings layout; part of every panel hash.
FORMAT_VERSION = 1

SEED_KINDS = ("grid", "lines", "random", "points")
LAYOUTS = ("row", "grid")
SWEEP_PARAMETERS = PARAM_NAMES + ("h",)
COMPUTE_QUANTITIES = ("sections", "lyapunov", "separatrices")
#: quantities computed when [compute] does not mention them
COMPUTE_DEFAULTS = {"sections": True, "lyapunov": False, "separatrices": False}

DEFAULT_SEED_N = 200
DEFAULT_MARGIN = 0.98
DEFAULT_RANDOM_SEED = 0
DEFAULT_CROSSINGS = 1000
DEFAULT_MARKER_SIZE = 0.25
DEFAULT_DPI = 200
MIN_DPI, MAX_DPI = 10, 2400
#: largest number of seeds per panel (n, n * len(lines), len(points))
MAX_SEEDS = 10_000_000
MAX_NAME_LENGTH = 128

_NAME_RE = re.compile(r"[A-Za-z0-9_.-]+\Z")
_TOP_KEYS = ("name", "description", "model", "energy", "sweep", "seeds", "integration", "compute", "lyapunov",
             "figure", "manifolds", "atlas")
_SEED_KEYS = ("kind", "n", "margin", "seed", "lines", "points")
#: the [seeds] keys that determine the points of each kind
_SEED_USED = {"grid": ("kind", "n", "margin"), "random": ("kind", "n", "margin", "seed"),
              "lines": ("kind", "n", "margin", "lines"), "points": ("kind", "points")}
_INTEGRATION_KEYS = ("method", "tol", "dt", "crossings", "tmax", "max_steps", "phi0", "direction")
_FIGURE_KEYS = ("layout", "columns", "share_scale", "own_scale", "marker_size", "dpi")
_MANIFOLD_KEYS = ("draw", "arclength", "guess", "period", "max_points")
_LYAPUNOV_KEYS = ("time", "method", "tol", "dt", "threshold", "indicators", "early_stop", "early_sali", "early_megno",
                  "early_time", "map_resolution", "map_indicator", "exact", "center", "diffusion_iterates")
#: the indicators a scene can ask for (explorer.analysis.lyapunov.INDICATOR_NAMES)
LYAPUNOV_INDICATORS = INDICATOR_NAMES
#: [lyapunov] diffusion_iterates: N of frequency_diffusion (2N section returns per orbit), by
#: default and at most (docs/greene.md, "Frequency diffusion")
DEFAULT_DIFFUSION_ITERATES = 300
MAX_DIFFUSION_ITERATES = 100_000
#: largest raster side of a chaos map ([lyapunov] map_resolution)
MAX_MAP_RESOLUTION = 4096
#: [manifolds]: defaults and limits of the branches drawn over each panel (docs/manifolds.md)
DEFAULT_MANIFOLD_ARCLENGTH = 6.0
MAX_MANIFOLD_ARCLENGTH = 1000.0
DEFAULT_MANIFOLD_POINTS = 20000
MAX_MANIFOLD_POINTS = 1_000_000
#: largest period of the orbit whose manifolds are drawn (its K points each get four branches)
MAX_MANIFOLD_PERIOD = 64

#: re-exported by :mod:`explorer.io.scene` (its ``__all__`` extends this one): the limits and
#: defaults, the model's parameter names, and the key tables (private: for the validators and tests)
__all__ = [
    "COMPUTE_DEFAULTS", "COMPUTE_QUANTITIES", "DEFAULT_CROSSINGS", "DEFAULT_DIFFUSION_ITERATES", "DEFAULT_DPI",
    "DEFAULT_MANIFOLD_ARCLENGTH", "DEFAULT_MANIFOLD_POINTS", "DEFAULT_MARGIN", "DEFAULT_MARKER_SIZE",
    "DEFAULT_RANDOM_SEED", "DEFAULT_SEED_N", "FORMAT_VERSION", "LAYOUTS", "LYAPUNOV_INDICATORS",
    "MAX_DIFFUSION_ITERATES", "MAX_DPI", "MAX_MANIFOLD_ARCLENGTH", "MAX_MANIFOLD_PERIOD", "MAX_MANIFOLD_POINTS",
    "MAX_MAP_RESOLUTION", "MAX_NAME_LENGTH", "MAX_SEEDS", "MIN_DPI", "PARAM_NAMES",
    "SEED_KINDS", "SWEEP_PARAMETERS",
    "_FIGURE_KEYS", "_INTEGRATION_KEYS", "_LYAPUNOV_KEYS", "_MANIFOLD_KEYS", "_NAME_RE", "_SEED_KEYS", "_SEED_USED",
    "_TOP_KEYS",
]
