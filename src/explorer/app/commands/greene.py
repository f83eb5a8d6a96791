"""the parameter at which an invariant curve breaks (Greene's residue criterion)

The parameter k_n at which the residue of each convergent P/Q of --nu reaches R* = 0.2500888,
extrapolated to the critical value. --map standard: Chirikov's standard map, --k the first
guess; --map section: the curves around the elliptic fixed point near --around, broken by
--param, whose value (--mu by default) is the first guess (docs/commands/greene.md).
"""
from __future__ import annotations

import json

from explorer import model
from explorer.analysis.greene_core import DEFAULT_QMAX, MAX_QMAX, NU_FORMS, SECTION_QMAX
from explorer.app.commands import options
from explorer.app.commands.options import Command, opt

MAPS = ("standard", "section")
MU_HELP = "weight (>= 0); with --param mu (the default), the first guess of mu_c, > 0"

COMMAND = Command("greene", __doc__, "--map standard --nu golden --json", (
    opt("--map", dest="map_name", default="section", help=f"one of {', '.join(MAPS)} [%(default)s]"),
    opt("--nu", default="golden", help=f"rotation number: {NU_FORMS} [%(default)s]"),
    opt("--around", default=None, help="(section map) the elliptic fixed point's guess p1,p2"),
    opt("--param", default="mu", help="(section map) the parameter that breaks the curve; its value is the first "
                                      "guess of the critical one [%(default)s]"),
    opt("--k", type=float, default=0.9, help="(standard map) first guess of the critical k [%(default)s]"),
    opt("--qmax", type=int, default=None,
        help=f"largest period of the convergents [{DEFAULT_QMAX} standard, {SECTION_QMAX} section]"),
    lambda p: options.add_map_args(p, helps={"mu": MU_HELP}),
))


def run(args) -> int:
    from explorer.analysis import greene as gm
    from explorer.analysis.maps import StandardMap
    from explorer.model import validation

    validation.choice("--map", args.map_name, MAPS)
    nu = gm.rotation_value(args.nu)
    validation.choice("--param", args.param, model.PARAM_NAMES + ("h",))
    params = options.section_map_args(args)
    centre = options.pair(args.around, "--around") if args.around is not None else None
    k = validation.real("--k", args.k, 0.0, lo_open=True)
    default_qmax = DEFAULT_QMAX if args.map_name == "standard" else SECTION_QMAX
    qmax = default_qmax if args.qmax is None else validation.integer("--qmax", args.qmax, 2, MAX_QMAX)
    if args.map_name == "standard":
        if centre is not None:
            raise model.ParameterError("--around is for --map section (the standard map has no island centre to give)")
        res = gm.greene(StandardMap(k), nu, qmax=qmax)
    else:
        if centre is None:
            raise model.ParameterError("--map section needs --around P1,P2 (the elliptic fixed point's guess)")
        if not model.is_admissible(params, centre[0], centre[1], args.h):
            raise model.ParameterError(f"--around ({centre[0]:g}, {centre[1]:g}) lies outside the allowed region; "
                                       f"allowed: {model.describe_region(params, args.h)}")
        if args.param == "mu" and params.mu == 0.0:
            raise model.ParameterError("--map section needs --mu, the first guess of mu_c (> 0: at mu = 0 the island's "
                                       "centre is parabolic, trace 2), e.g. --mu 0.025 for Figure 4's islands")
        from explorer.analysis.section_map import SectionMap

        res = gm.greene(SectionMap(params, args.h, tol=args.tol), nu, qmax=qmax, around=centre, param=args.param)
    if args.json:
        print(json.dumps(res.as_dict()))
        return 0
    print(f"{res.map} map, curve nu = {res.nu!r}: critical {res.param} = {res.critical!r} +- {res.uncertainty:.2g} "
          f"(residues of the convergents reach R* = {res.critical_residue} at {res.param}_n)")
    print(f"p,q,{res.param}_n,residue_at_critical,point_x,point_y")
    for c in res.convergents:
        x, y = c["point_at_critical"]
        print(f"{c['p']},{c['q']},{c['param_n']!r},{c['residue_at_critical']!r},{x!r},{y!r}")
    return 0
