"""``explorer explore``: the browser explorer of ``explorer serve``, opened in the user's web
browser (:mod:`explorer.app.serve`).  Same options as ``serve`` (one definition,
:func:`explorer.app.serve.command.add_options`) and ``--no-browser``.

Its page: docs/commands/explore.md.
"""
from __future__ import annotations

from explorer.app.serve import command as serve_command

#: printed at the end of ``explorer explore --help`` (tests/app/test_cli.py parses it)
EXAMPLE = "python -m explorer explore figure4 --panel 2"


def add_parser(sub):
    """Add ``explore`` to the command line's subparsers."""
    x = sub.add_parser("explore", help="the explorer in your web browser: click on the section, watch the orbits "
                       "appear", description="Start the page of `explorer serve` and open it in the web browser "
                       "(Python's webbrowser module). The first line printed is the URL; without a browser (or "
                       "with --no-browser) open it yourself. Runs until Ctrl-C. "
                       + serve_command.PAGE_DESCRIPTION)
    serve_command.add_options(x)
    x.add_argument("--no-browser", action="store_true",
                   help="do not open a browser: only print the URL (as serve does)")
    return x


def run(args) -> int:
    return serve_command.run(args, open_browser=not args.no_browser)
