"""Command line ``python -m explorer COMMAND ...``: the parser, built from the commands' registry,
and the dispatch; bad input is one line ``explorer: error: ...`` and status 2 (docs/bad_input.md)."""
from __future__ import annotations

import argparse
import re
import sys

from explorer import __version__, model
from explorer.app.commands import registry

EXIT_USAGE = 2


class UsageError(Exception):
    """Bad input: reported on one line, exit status 2."""


#: a token that is a value, not an option, although it starts with "-": numbers and number
#: lists such as -1.2, -3e-1, -0.4,0, -inf (argparse alone accepts only -1 and -1.5)
NEGATIVE_VALUE = re.compile(r"^-(\d|\.\d|inf\b|nan\b)[\w.,+\-]*$")

#: the example printed at the end of each command's --help (tests/app/test_cli.py parses each);
#: each is written once, in the ``COMMAND`` of the command's module
EXAMPLES = registry.examples()


class _Formatter(argparse.HelpFormatter):
    """Wraps the description as usual; keeps the example (epilog) on its own lines."""

    def _fill_text(self, text, width, indent):
        if text.startswith("example:"):
            return "".join(indent + line for line in text.splitlines(keepends=True))
        return super()._fill_text(text, width, indent)


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)
        # values with a leading minus without "=" (--guess -0.4,0, --p1 -3e-1): argparse consults
        # this matcher (CPython's argparse, stable since 3.2) before treating "-..." as an option;
        # no option of this parser looks like a number, so the wider pattern is unambiguous
        self._negative_number_matcher = NEGATIVE_VALUE

    def error(self, message):  # one line, no usage dump
        raise UsageError(message)


def build_parser() -> argparse.ArgumentParser:
    """The parser of every command of :mod:`explorer.app.commands.registry`, in its order."""
    parser = _Parser(prog="explorer", description="Poincaré sections and chaos for Chaplygin's equations "
                     "of a heavy rigid body in an ideal fluid with circulation.")
    parser.add_argument("--version", action="version", version=f"explorer {__version__}")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser)
    for name in registry.COMMANDS:
        registry.add_parser(name, sub)
    return parser


def main(argv=None) -> int:
    """Parse ``argv`` and run the command; returns its exit status (2 for bad input)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help()
            return EXIT_USAGE
        return registry.module(args.command).run(args)
    except (UsageError, model.ParameterError) as exc:
        msg = " ".join(str(exc).split())
        print(f"explorer: error: {msg}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt as exc:   # a sweep says what it kept (explorer.app.interrupt.Interrupted)
        print("explorer: interrupted" + (f": {exc}" if str(exc) else ""), file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
