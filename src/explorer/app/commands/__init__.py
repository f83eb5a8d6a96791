"""The commands of ``python -m explorer``: one module per command, listed in
:mod:`explorer.app.commands.registry` (the only list of commands; :mod:`explorer.app.cli`
builds the parser from it and dispatches through it).

Each command module declares ``COMMAND`` (an :class:`~explorer.app.commands.options.Command`:
its name, its docstring as help and description, the example printed at the end of its
``--help``, its options as data) and ``run(args) -> int`` (the exit status).
:mod:`~explorer.app.commands.options` holds the one builder of the subparsers and what several
commands share: the model parameters, the start point, the method, the energy, the Newton and
section-map options and their readers.
"""
