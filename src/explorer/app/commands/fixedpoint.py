"""a fixed point of the section map, its stability, continuation

Newton's method on the section map phi = pi (Jacobian from the tangent dynamics); prints the
point, the monodromy eigenvalues, trace and stability. With --continue PARAM START STOP STEP,
follows the branch and reports where |trace| = 2.
"""
from __future__ import annotations

import json
import math
from functools import partial

from explorer import model
from explorer.app.commands import options
from explorer.app.commands.options import Command, opt

COMMAND = Command("fixedpoint", __doc__, "--guess -0.4,0 --mu 0.5 --continue mu 0.5 3.5 0.1", (
    opt("--guess", default="0,0", help="start of Newton's method: p1,p2, e.g. --guess -0.4,0 [0,0]"),
    partial(options.add_newton_args, continue_help="continue the fixed point in PARAM (a model parameter or h)"),
))


def run(args) -> int:
    from explorer.analysis import fixedpoints

    params = options.params_from(args)
    if not math.isfinite(args.h):
        raise model.ParameterError(f"h must be finite, got {args.h!r}")
    guess = options.pair(args.guess, "--guess")
    if args.cont:
        name, start, stop, step = options.continuation(args.cont)
        br = fixedpoints.continue_branch(params, args.h, name, start, stop, step, guess, tol=args.tol)
        rows = [dict(fp.as_dict(), **{name: float(v)}) for v, fp in zip(br.values, br.orbits)]
        if args.json:
            print(json.dumps({"parameter": name, "branch": rows, "bifurcations": br.bifurcations,
                              "stopped": br.stopped}))
        else:
            print(f"{name},p1,p2,trace,stable")
            for r in rows:
                print(f"{r[name]:.10g},{r['p1']!r},{r['p2']!r},{r['trace']!r},{r['stable']}")
            options.print_bifurcations(br, name)
        return 0
    fp = fixedpoints.find_fixed_point(params, args.h, guess, tol=args.tol)
    out = dict(fp.as_dict(), params=params.as_dict(), h=args.h)
    if args.json:
        print(json.dumps(out))
    else:
        for k in ("p1", "p2", "trace", "det", "eigenvalues", "stable", "return_time"):
            print(f"{k} {out[k]!r}")
    return 0
