"""the explorer in your web browser: click on the section, watch the orbits appear

Start the page of `explorer serve` and open it in the web browser (Python's webbrowser module).
The first line printed is the URL; without a browser (or with --no-browser) open it yourself.
Runs until Ctrl-C. {page}
"""
from __future__ import annotations

from explorer.app.commands.options import Command, opt
from explorer.app.serve import command as serve_command

# the options of serve (one definition, explorer.app.serve.command.add_options) and --no-browser
COMMAND = Command("explore", __doc__, "figure4 --panel 2", (
    serve_command.add_options,
    opt("--no-browser", action="store_true", help="do not open a browser: only print the URL (as serve does)"),
), fields={"page": serve_command.PAGE_DESCRIPTION})


def run(args) -> int:
    return serve_command.run(args, open_browser=not args.no_browser)
