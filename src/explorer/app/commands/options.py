"""What several commands share: :class:`Command` (a command line declared as data, one builder of
every subparser), :func:`opt`, :func:`one_of`, and one copy of each option group
(``add_model_args``, ``add_start_args``, ``add_method_args``, ``add_newton_args``,
``add_map_args``) with their readers."""
from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from explorer import model
from explorer.integrate.methods import MAP_TOL
from explorer.model import validation

#: the help line of each model parameter (model.PARAMETERS, the table "Notation" of docs/model.md);
#: its default is appended
PARAM_HELP = {p.name: p.help for p in model.PARAMETERS}
#: the title of the model parameters' group in --help
MODEL_GROUP = "model parameters (docs/model.md; defaults: Figure 4, R9)"
#: the title of that group for the commands that start from a scene (explore, serve)
SCENE_MODEL_GROUP = "model parameters (override the scene's; defaults: Figure 4, R9, mu = 0)"


@dataclass(frozen=True)
class Option:
    """One option or positional argument: the arguments of ``parser.add_argument``."""

    flags: tuple[str, ...]
    kwargs: dict = field(default_factory=dict)

    def __call__(self, parser) -> None:
        parser.add_argument(*self.flags, **self.kwargs)


def opt(*flags: str, **kwargs) -> Option:
    """``opt("--n", type=int, default=21, help=...)``: an option as ``add_argument`` takes it."""
    return Option(flags, kwargs)


def angle(text: str) -> float:
    """An angle option's word: a number or a multiple of pi (``pi/2``, ``-pi``, ``2pi``; validation.angle_text)."""
    try:
        return validation.angle_text("the angle", text)
    except model.ParameterError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def one_of(*choices: Option, required: bool = False) -> Callable:
    """The options ``choices`` as a mutually exclusive group (``required``: one must be given)."""
    def add(parser) -> None:
        group = parser.add_mutually_exclusive_group(required=required)
        for choice in choices:
            choice(group)
    return add


@dataclass(frozen=True)
class Command:
    """A command's line, declared once in its module as ``COMMAND``: ``doc`` its docstring (first
    paragraph: ``explorer --help``'s line, the rest the description, ``{key}`` filled from
    ``fields``), ``example`` the arguments of the example in ``--help`` (it must parse), ``options``
    in the order of ``--help``."""

    name: str
    doc: str | None
    example: str
    options: Sequence[Callable] = ()
    fields: dict = field(default_factory=dict)

    def _paragraphs(self) -> list[str]:
        text = (self.doc or "").format(**self.fields) if self.fields else (self.doc or "")
        return [" ".join(p.split()) for p in text.strip().split("\n\n")]

    @property
    def help(self) -> str:
        return self._paragraphs()[0]

    @property
    def description(self) -> str:
        return " ".join(self._paragraphs()[1:])

    @property
    def example_line(self) -> str:
        return f"python -m explorer {self.name} {self.example}"

    def add_parser(self, sub):
        """Add the command to the command line's subparsers ``sub`` and return its parser."""
        parser = sub.add_parser(self.name, help=self.help, description=self.description)
        for add in self.options:
            add(parser)
        return with_example(parser, self.example_line)


def with_example(parser, example: str):
    """``parser`` with ``example`` printed at the end of its ``--help`` (cli's formatter keeps
    the lines after ``example:`` as they are)."""
    parser.epilog = f"example:\n  {example}"
    return parser


def add_model_args(p, defaults: model.Params | None = model.FIGURE4, json: str | None = None, *,
                   title: str = MODEL_GROUP, helps: dict[str, str] | None = None):
    """--json (with this help) and the model parameters ``--a1 ... --eta``.

    ``defaults``: the parameters each option defaults to (shown in its help), or None: every
    option is None unless given (a scene's value stands) and has no help line.  ``helps``
    replaces the help of some parameters (e.g. trajectory's lam, which may be 0)."""
    if json:
        p.add_argument("--json", action="store_true", help=json)
    g = p.add_argument_group(title)
    helps = {**PARAM_HELP, **(helps or {})}
    for name in model.PARAM_NAMES:
        if defaults is None:
            g.add_argument(f"--{name}", type=float, default=None)
        else:
            g.add_argument(f"--{name}", type=float, default=getattr(defaults, name),
                           help=f"{helps[name]} [%(default)s]")


def add_start_args(p):
    """--p1 --p2 --h: a start point on the section and the energy level (M from R9)."""
    p.add_argument("--p1", type=float, required=True, help="start point p1 on the section")
    p.add_argument("--p2", type=float, required=True, help="start point p2 on the section")
    add_energy_arg(p)


def add_method_args(p, tol, dt):
    """--method --tol --dt, with this command's defaults."""
    from explorer.integrate.methods import METHODS

    p.add_argument("--method", default="taylor", help=f"one of {', '.join(METHODS)} [%(default)s]")
    p.add_argument("--tol", type=float, default=tol, help="tolerance of taylor/dop853 [%(default)s]")
    p.add_argument("--dt", type=float, default=dt, help="fixed step of the split* methods [%(default)s]")


def params_from(args) -> model.Params:
    """The model parameters given on the command line (validated by :class:`model.Params`)."""
    return model.Params(**{n: getattr(args, n) for n in model.PARAM_NAMES})


def add_energy_arg(p, help="energy level [%(default)s]"):
    """--h: the energy level (default that of Figure 4)."""
    p.add_argument("--h", type=float, default=model.FIGURE4_H, help=help)


def add_map_args(p, tol_help="Taylor tolerance [%(default)s]", json="print JSON", helps=None):
    """The options of a command on the section map (rotation, manifold): --h, the Taylor --tol
    of the map (:data:`~explorer.integrate.methods.MAP_TOL`), the model with --json (``helps``: as
    :func:`add_model_args`)."""
    add_energy_arg(p)
    p.add_argument("--tol", type=float, default=MAP_TOL, help=tol_help)
    add_model_args(p, model.FIGURE4, json=json, helps=helps)


def add_newton_args(p, continue_help):
    """The options of the Newton commands (fixedpoint, periodic): energy, continuation, the Taylor
    tolerance of the section map, the model."""
    add_energy_arg(p)
    p.add_argument("--continue", dest="cont", nargs=4, metavar=("PARAM", "START", "STOP", "STEP"), help=continue_help)
    p.add_argument("--tol", type=float, default=MAP_TOL, help="Taylor tolerance [%(default)s]")
    add_model_args(p, model.FIGURE4, json="print JSON")


def pair(text, name):
    """``p1,p2`` of option ``name``: two finite numbers."""
    try:
        a, b = (float(v) for v in text.split(","))
    except ValueError:
        raise model.ParameterError(f"{name} must be two numbers p1,p2 (e.g. 0.1,-0.2), got {text!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise model.ParameterError(f"{name} must be finite, got {text!r}")
    return a, b


def continuation(cont):
    """PARAM, START, STOP, STEP of --continue: numbers, STEP towards STOP, a bounded number of steps."""
    name, *nums = cont
    validation.choice("--continue PARAM", name, model.PARAM_NAMES + ("h",))
    try:
        start, stop, step = (float(v) for v in nums)
    except ValueError:
        raise model.ParameterError(f"--continue needs PARAM START STOP STEP numbers, got {nums}") from None
    return (name, *validation.continuation_steps("--continue", start, stop, step))


def print_bifurcations(br, name) -> None:
    """The stability changes and touches of a continued branch (fixed point or periodic orbit:
    one detector, one report)."""
    print("stability changes: " + (", ".join(f"{b['type']} at {name} = {b['value']:.10g}"
                                             for b in br.bifurcations) or "none in range"))
    if br.stopped:
        print(f"branch stopped: {br.stopped}")


def section_map_args(args):
    """The model parameters of a command on the section map (periodic, rotation, manifold), with
    its energy ``--h`` (finite, a non-empty allowed region) and Taylor ``--tol`` checked."""
    from explorer.analysis.sections import MAX_TOL, MIN_TOL

    params = params_from(args)
    if not math.isfinite(args.h):
        raise model.ParameterError(f"h must be finite, got {args.h!r}")
    validation.real("tol", args.tol, MIN_TOL, MAX_TOL)
    if model.allowed_ellipse(params, args.h) is None:
        raise model.ParameterError(f"the region is empty at h = {args.h:g}; raise --h")
    return params
