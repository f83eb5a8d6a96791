"""``explorer explore``: the interactive matplotlib window (explorer.app.explore).

Its page: docs/commands/explore.md.
"""
from __future__ import annotations

from explorer import model
from explorer.app.commands import options

#: printed at the end of ``explorer explore --help`` (tests/app/test_cli.py parses it)
EXAMPLE = "python -m explorer explore figure4 --panel 2"


def add_parser(sub):
    """Add ``explore`` to the command line's subparsers."""
    from explorer.analysis.sections import DEFAULT_DT, DEFAULT_TOL, METHODS

    x = sub.add_parser("explore", help="interactive window: click on the section, watch the orbit appear",
                       description="Open a matplotlib window with the allowed region of the section phi = pi at "
                       "energy h; a click inside starts an orbit and draws its crossings as they are computed. "
                       "Keys: c clear, r re-run seeds, s save PNG, w write HDF5, x colour by the divergence "
                       "proxy, p separatrices, o periodic orbits of periods 1..4. Needs a display.")
    x.add_argument("scene", nargs="?", default=None,
                   help="scene file (.toml) or preset name (e.g. figure4): start from its panel's parameters, "
                   "h and integration settings [none: Figure 4 with mu = 0, h = 2]")
    x.add_argument("--panel", type=int, default=0, help="panel of the scene [0]")
    x.add_argument("--h", type=float, default=None, help="energy level [the scene's, else 2]")
    x.add_argument("--method", default=None, help=f"one of {', '.join(METHODS)} [the scene's, else taylor]")
    x.add_argument("--tol", type=float, default=None, help=f"tolerance of taylor/dop853 [{DEFAULT_TOL}]")
    x.add_argument("--dt", type=float, default=None, help=f"fixed step of the split* methods [{DEFAULT_DT}]")
    x.add_argument("--crossings-per-chunk", type=int, default=50,
                   help="crossings computed per orbit between redraws [%(default)s]")
    x.add_argument("--max-crossings", type=int, default=2000, help="crossings per orbit [%(default)s]")
    x.add_argument("--out-dir", default=".", help="where s (PNG) and w (HDF5) write [current directory]")
    options.add_model_args(x, None, title=options.SCENE_MODEL_GROUP)
    return x


def run(args) -> int:
    from explorer.app import explore

    explore.check_args(args)  # bad input is reported as such, with or without a display
    problem = explore.display_problem()  # no display: one line, exit 2 (no traceback)
    if problem:
        raise model.ParameterError(problem)
    explore.from_args(args).run()
    return 0
