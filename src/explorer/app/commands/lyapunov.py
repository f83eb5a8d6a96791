"""chaos indicators of one orbit: {titles}

Start on the section phi = pi at (p1, p2) with M from the energy h and integrate the orbit with
one deviation vector (tangent to the energy shell) for a time T; print the finite-time maximal
Lyapunov exponent, the mean MEGNO <Y> and the FLI, with their convergence history; with the
Taylor method also SALI and GALI2 from a second deviation vector (null for other methods).
"""
from __future__ import annotations

import json
import math
import sys
from functools import partial

import numpy as np

from explorer import model
from explorer.app.commands import options
from explorer.app.commands.options import Command, opt
from explorer.integrate.methods import DEFAULT_DT, DEFAULT_TOL
from explorer.kernels.indicator_table import TANGENT

COMMAND = Command("lyapunov", __doc__, "--p1 -0.2 --p2 0.1 --mu 1 --tmax 1000 --json", (
    options.add_start_args,
    opt("--tmax", type=float, default=1000.0, help="integration time: the time the orbit runs to "
        "[%(default)s]"),
    partial(options.add_method_args, tol=DEFAULT_TOL, dt=DEFAULT_DT),
    opt("--history", type=int, default=12, help="history points (log-spaced in time) [%(default)s]"),
    partial(options.add_model_args, json="print JSON"),
), fields={"titles": ", ".join(i.title for i in TANGENT)})


def run(args) -> int:
    from explorer.analysis import lyapunov
    from explorer.analysis.sections import METHODS
    from explorer.kernels.indicator_table import RES_T

    params = options.params_from(args)
    if args.method not in METHODS:
        raise model.ParameterError(f"method must be one of {', '.join(METHODS)}; got {args.method!r}")
    for name in ("p1", "p2", "h"):
        if not math.isfinite(getattr(args, name)):
            raise model.ParameterError(f"{name} must be finite, got {getattr(args, name)!r}")
    y0 = model.section_state(params, [args.p1], [args.p2], args.h)
    # every indicator of the tangent loops the method computes (SALI and GALI_2: Taylor's tangent lanes;
    # frequency diffusion, of the section map's returns around a centre, is a sweep's: [lyapunov] center)
    r = lyapunov.indicators(params, states=y0, tmax=args.tmax, method=args.method, tol=args.tol, dt=args.dt,
                            history=args.history, which=lyapunov.available(args.method))
    cols = [RES_T] + [i.column for i in TANGENT if i.in_history]
    hist = [[float(row[c]) for c in cols] for row in r.history[0] if np.isfinite(row[RES_T])]
    reached = float(r.time[0])
    status = r.status_name(0)

    def estimate(v):      # an orbit stopped at t = 0 has no estimate (null, never a made-up 0)
        return float(v) if reached > 0 and math.isfinite(float(v)) else None

    out = {"params": params.as_dict(), "h": args.h, "p1": args.p1, "p2": args.p2, "method": args.method,
           "settings": r.settings, "status": status, "time": reached,
           **{i.name: estimate(r.values[i.name][0]) for i in TANGENT},
           "regular_bound": lyapunov.regular_bound(reached) if reached > 1 else None,
           "history": hist}
    if status != "done":
        cover = f"the estimates cover [0, {reached:g}]" if reached > 0 else "no estimate"
        print(f"explorer: the orbit stopped at t = {reached:g} of {args.tmax:g} ({status}); {cover}",
              file=sys.stderr)
    if args.json:
        print(json.dumps(out))
    else:
        print("\n".join(f"{k} {out[k]!r}" for k in ("time",) + tuple(i.name for i in TANGENT))
              + f"\nstatus {out['status']}")
        if hist:
            print("history: " + ", ".join(["t"] + [i.name for i in TANGENT if i.in_history]))
            for row in hist:
                print(",".join(repr(v) for v in row))
    return 0
