"""What several commands share: their option groups and the readers of those options.

One copy each: the model parameters of every command come from :func:`add_model_args` (the
help line of each parameter is written once, in :data:`PARAM_HELP`), a start point on the
section from :func:`add_start_args`, the integration method from :func:`add_method_args`, the
Newton commands' options from :func:`add_newton_args`; :func:`pair`, :func:`continuation`,
:func:`section_map_args` and :func:`print_bifurcations` read and report them.
"""
from __future__ import annotations

import math

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
    p.add_argument("--h", type=float, default=model.FIGURE4_H, help="energy level [%(default)s]")


def add_method_args(p, tol, dt):
    """--method --tol --dt, with this command's defaults."""
    from explorer.integrate.methods import METHODS

    p.add_argument("--method", default="taylor", help=f"one of {', '.join(METHODS)} [%(default)s]")
    p.add_argument("--tol", type=float, default=tol, help="tolerance of taylor/dop853 [%(default)s]")
    p.add_argument("--dt", type=float, default=dt, help="fixed step of the split* methods [%(default)s]")


def params_from(args) -> model.Params:
    """The model parameters given on the command line (validated by :class:`model.Params`)."""
    return model.Params(**{n: getattr(args, n) for n in model.PARAM_NAMES})


def add_newton_args(p, continue_help):
    """The options of the Newton commands (fixedpoint, periodic): energy, continuation, the Taylor
    tolerance of the section map, the model."""
    p.add_argument("--h", type=float, default=model.FIGURE4_H, help="energy level [%(default)s]")
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
