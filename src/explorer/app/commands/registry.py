"""The registry of the commands, name -> module, in the order of ``explorer --help``: the one list
of commands.  A module declares ``COMMAND`` and ``run(args) -> int`` and imports at the top only
what ``--help`` needs."""
from __future__ import annotations

import importlib

#: command name -> its module, in the order of ``explorer --help``
MODULES = {
    "orbit": "explorer.app.commands.orbit",
    "sweep": "explorer.app.commands.sweep",
    "lyapunov": "explorer.app.commands.lyapunov",
    "fixedpoint": "explorer.app.commands.fixedpoint",
    "periodic": "explorer.app.commands.periodic",
    "rotation": "explorer.app.commands.rotation",
    "greene": "explorer.app.commands.greene",
    "explore": "explorer.app.commands.explore",
    "serve": "explorer.app.serve.command",       # beside the web page it serves (explorer.app.serve)
    "melnikov": "explorer.app.commands.melnikov",
    "trajectory": "explorer.app.commands.trajectory",
    "figures": "explorer.app.commands.figures",
    "manifold": "explorer.app.commands.manifold",
}
#: every command, in order
COMMANDS = tuple(MODULES)


def module(name):
    """The module of command ``name`` (KeyError for an unknown name: argparse refuses those first)."""
    return importlib.import_module(MODULES[name])


def example(name) -> str:
    """The example line of command ``name`` (printed at the end of its ``--help``)."""
    return module(name).COMMAND.example_line


def add_parser(name, sub):
    """Add command ``name`` to the subparsers ``sub``, its example at the end of its ``--help``."""
    return module(name).COMMAND.add_parser(sub)


def examples() -> dict[str, str]:
    """name -> the example line of every command, in order."""
    return {name: example(name) for name in COMMANDS}
