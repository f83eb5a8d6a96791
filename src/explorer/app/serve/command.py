"""The ``serve`` command (docs/commands/serve.md); its options import no web library."""
from __future__ import annotations

import os

from explorer import model
from explorer.app.commands import options
from explorer.app.commands.options import Command
from explorer.model import ParameterError, validation


def add_options(s) -> None:
    """The options ``serve`` and ``explore`` share."""
    from explorer.analysis.sections import DEFAULT_DT, DEFAULT_TOL, METHODS
    from explorer.app.serve.server import DEFAULT_HOST, DEFAULT_PORT
    from explorer.app.serve.settings import DEFAULT_CROSSINGS

    s.add_argument("scene", nargs="?", default=None,
                   help="scene file (.toml) or preset name: start from its panel's parameters, h, integration "
                   "settings and seeds [none: Figure 4 with mu = 0, h = 2]")
    s.add_argument("--system", default=None,
                   help="module:attribute of an explorer System's section map, SectionMap(system, E, section=..., "
                   "direction=..., coords=(a, b), solve=c) (imported from the current directory or sys.path; a "
                   "callable returning one is called), or of a System whose scene is given (docs/commands/serve.md)")
    s.add_argument("--panel", type=int, default=0, help="panel of the scene [0]")
    s.add_argument("--port", type=int, default=DEFAULT_PORT, help="TCP port (0: any free port) [%(default)s]")
    s.add_argument("--host", default=DEFAULT_HOST, help="address to bind [%(default)s]; not a loopback "
                   "address: a token is required (made and printed when --token is not given)")
    s.add_argument("--token", default=None, help="require ?token=T on every page request [none on loopback]")
    s.add_argument("--export-dir", default=None, help="directory the page's 'Export scene' and 'Export figure' "
                   "buttons write into [none: the page offers its files as downloads only]")
    s.add_argument("--h", type=float, default=None, help="energy level [the scene's, else 2]")
    s.add_argument("--method", default=None, help=f"one of {', '.join(METHODS)} [the scene's, else taylor]")
    s.add_argument("--tol", type=float, default=None,
                   help=f"tolerance of taylor/dop853 [the scene's, else {DEFAULT_TOL}]")
    s.add_argument("--dt", type=float, default=None,
                   help=f"fixed step of the split* methods [the scene's, else {DEFAULT_DT}]")
    s.add_argument("--crossings", type=int, default=None,
                   help=f"crossings per click [the scene's, else {DEFAULT_CROSSINGS}]")
    s.add_argument("--megno-resolution", type=int, default=None,
                   help="finest raster of the MEGNO layer, n x n cells (a power of 2, 16 to 512; coarser ones "
                   "first) [128]")
    s.add_argument("--megno-time", type=float, default=None,
                   help="integration time T of the MEGNO layer's <Y>(T) [200]")
    options.add_model_args(s, None, title=options.SCENE_MODEL_GROUP)


PAGE_DESCRIPTION = ("A click on the section starts an orbit whose crossings appear as they are computed (those of "
                    "`explorer orbit` for the same start and settings); the fields set mu, h, lambda, a1, a2, b, "
                    "the method, tol, dt and the crossings per click; the URL keeps the view. Binds 127.0.0.1 "
                    "unless --host is given; another host needs a token.")

HELP = """the explorer in the browser: click on the section, watch the orbits appear

Serve the explorer as a web page (HoloViz Panel on Bokeh). The first line printed is the URL to open
(with the token when one is needed); runs until Ctrl-C. {page}
"""

COMMAND = Command("serve", HELP, "figure4 --mu 0.03", (add_options,), fields={"page": PAGE_DESCRIPTION})


def page_from_args(args) -> tuple:
    """(settings, label, seeds) the page starts from: a System's section map, else Chaplygin's model."""
    from explorer.app.serve.settings import page_settings

    names = (*model.PARAM_NAMES, "h", "method", "tol", "dt", "crossings")
    return page_settings(args.scene, args.system, args.panel, flag="--", **{n: getattr(args, n) for n in names})


def run(args, open_browser: bool = False) -> int:
    """Serve the page until Ctrl-C (status 0); ``open_browser``: also open it (``explore``)."""
    from explorer.app.serve import server

    validation.integer("--port", args.port, 0, 65535)
    if args.token is not None and (not args.token or len(args.token) > 256 or not args.token.isprintable()
                                   or any(c in args.token for c in " &#?%/")):
        raise ParameterError("--token must be 1 to 256 printable characters without spaces or & # ? % /")
    if not args.host or any(c.isspace() for c in args.host):
        raise ParameterError(f"--host must be an address or host name (127.0.0.1 by default), got {args.host!r}")
    if args.export_dir is not None and not os.path.isdir(args.export_dir):
        raise ParameterError(f"--export-dir must be an existing directory, got {args.export_dir!r}")
    from explorer.app.serve import raster

    megno_resolution = raster.RESOLUTIONS[-1] if args.megno_resolution is None else args.megno_resolution
    raster.resolutions_up_to(megno_resolution)
    megno_time = raster.RASTER_TIME if args.megno_time is None else args.megno_time
    validation.real("--megno-time", megno_time, 0.0, raster.MAX_RASTER_TIME, lo_open=True)
    base, label, seeds = page_from_args(args)
    try:
        server.run(base, host=args.host, port=args.port, token=args.token, export_dir=args.export_dir, label=label,
                   seeds=seeds, open_browser=open_browser, megno_resolution=megno_resolution,
                   megno_time=megno_time)
    except OSError as exc:          # the port is taken, the address is not ours, ...
        raise ParameterError(f"cannot serve on {args.host}:{args.port}: {exc.strerror or exc}") from None
    except KeyboardInterrupt:
        return 0
    return 0
