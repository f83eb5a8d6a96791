"""The commands of ``python -m explorer``: one module per command, listed in
:mod:`explorer.app.commands.registry` (the only list of commands; :mod:`explorer.app.cli`
builds the parser from it and dispatches through it).

Each command module has ``EXAMPLE`` (the line printed at the end of its ``--help``),
``add_parser(sub)`` (adds its subparser and returns it) and ``run(args) -> int`` (the exit
status).  :mod:`~explorer.app.commands.options` holds what several commands share: the model
parameters, the start point, the method, the Newton options and their readers.
"""
