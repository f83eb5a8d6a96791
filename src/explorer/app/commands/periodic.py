"""periodic orbits of period K of the section map, stability, continuation

Newton's method on P^K(x) = x for the section map phi = pi (Jacobian from the tangent dynamics;
multiple shooting for K > 4), from --guess or by a --search covering the allowed region and the
symmetry lines; prints each orbit once with its minimal period, points, trace, Greene's residue,
eigenvalues, stability and symmetry. With --continue PARAM START STOP STEP (and --guess), follows
the orbit and reports where |trace| crosses or touches 2.
"""
from __future__ import annotations

import json
from functools import partial

from explorer import model
from explorer.app.commands import options
from explorer.app.commands.options import Command, one_of, opt
from explorer.model import validation

COMMAND = Command("periodic", __doc__, "--period 3 --search --grid 10 --mu 0.03 --json", (
    opt("--period", "-K", type=int, required=True, help="period K >= 1"),
    one_of(opt("--guess", default=None, help="start of Newton's method: p1,p2, e.g. --guess -0.4,0"),
           opt("--search", action="store_true", help="search the allowed region for all orbits"), required=True),
    opt("--grid", type=int, default=12, help="grid points per axis of --search [%(default)s]"),
    opt("--max-guesses", type=int, default=60, help="Newton starts of --search [%(default)s]"),
    partial(options.add_newton_args, continue_help="continue the orbit through --guess in PARAM (a model parameter "
            "or h)"),
))


def _orbit_line(o) -> str:
    pts = " ".join(f"({p[0]:.10g},{p[1]:.10g})" for p in o.points)
    return (f"K={o.period} {o.kind} trace={o.trace:.10g} residue={o.residue:.6g} "
            f"symmetric={o.symmetric}{' degenerate' if o.degenerate else ''} points={pts}")


def run(args) -> int:
    from explorer.analysis import periodic

    if args.period < 1:
        raise model.ParameterError(f"--period must be an integer K >= 1, got {args.period}")
    validation.integer("--period", args.period, 1, validation.MAX_PERIOD)
    # --grid and --max-guesses are checked with or without --search (a bad value is a mistake either way)
    validation.fits_in_memory("--grid", args.grid, 16 * args.grid, "grid^2 points of 16 bytes", lo=2)
    validation.integer("--max-guesses", args.max_guesses, 1)
    params = options.section_map_args(args)
    K = args.period
    if args.cont:
        if args.guess is None:
            raise model.ParameterError("--continue needs --guess (a point of the orbit at START)")
        name, start, stop, step = options.continuation(args.cont)
        guess = options.pair(args.guess, "--guess")
        br = periodic.continue_periodic(params, args.h, K, name, start, stop, step, guess, tol=args.tol)
        rows = [dict(o.as_dict(), **{name: float(v)}) for v, o in zip(br.values, br.orbits)]
        if args.json:
            print(json.dumps({"period": K, "parameter": name, "branch": rows, "bifurcations": br.bifurcations,
                              "stopped": br.stopped}))
        else:
            print(f"{name},p1,p2,trace,residue,stable")
            for r in rows:
                print(f"{r[name]:.10g},{r['points'][0][0]!r},{r['points'][0][1]!r},{r['trace']!r},{r['residue']!r},"
                      f"{r['stable']}")
            options.print_bifurcations(br, name)
        return 0
    if args.search:
        orbits = periodic.search_periodic_orbits(params, args.h, K, grid=args.grid, max_guesses=args.max_guesses,
                                                 tol=args.tol)
    else:
        guess = options.pair(args.guess, "--guess")
        orbits = [periodic.find_periodic_orbit(params, args.h, guess, K, tol=args.tol)]
    if args.json:
        print(json.dumps({"period": K, "params": params.as_dict(), "h": args.h,
                          "orbits": [o.as_dict() for o in orbits]}))
    else:
        if args.search:
            print(f"{len(orbits)} orbit(s) of minimal period {K}")
        for o in orbits:
            print(_orbit_line(o))
    return 0
