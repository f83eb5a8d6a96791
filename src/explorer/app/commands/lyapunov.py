"""``explorer lyapunov``: chaos indicators of one orbit (explorer.analysis.lyapunov).

Its page: docs/commands/lyapunov.md.
"""
from __future__ import annotations

import json
import math
import sys

import numpy as np

from explorer import model
from explorer.app.commands import options

#: printed at the end of ``explorer lyapunov --help`` (tests/app/test_cli.py parses it)
EXAMPLE = "python -m explorer lyapunov --p1 -0.2 --p2 0.1 --mu 1 -T 1000 --json"


def add_parser(sub):
    """Add ``lyapunov`` to the command line's subparsers."""
    from explorer.analysis.sections import DEFAULT_DT, DEFAULT_TOL
    from explorer.kernels.indicator_table import INDICATORS

    titles = ", ".join(i.title for i in INDICATORS)
    ly = sub.add_parser("lyapunov", help=f"chaos indicators of one orbit: {titles}",
                        description="Start on the section phi = pi at (p1, p2) with M from the energy h and "
                        "integrate the orbit with one deviation vector (tangent to the energy shell) for a "
                        "time T; print the finite-time maximal Lyapunov exponent, the mean MEGNO <Y> and the "
                        "FLI, with their convergence history; with the Taylor method also SALI and GALI2 "
                        "from a second deviation vector (null for other methods).")
    options.add_start_args(ly)
    ly.add_argument("--time", "-T", type=float, default=1000.0, help="integration time T [%(default)s]")
    options.add_method_args(ly, DEFAULT_TOL, DEFAULT_DT)
    ly.add_argument("--history", type=int, default=12, help="history points (log-spaced in time) [%(default)s]")
    options.add_model_args(ly, model.FIGURE4, json="print JSON")
    return ly


def run(args) -> int:
    from explorer.analysis import lyapunov
    from explorer.analysis.sections import METHODS
    from explorer.kernels.indicator_table import INDICATORS, RES_T

    params = options.params_from(args)
    if args.method not in METHODS:
        raise model.ParameterError(f"method must be one of {', '.join(METHODS)}; got {args.method!r}")
    for name in ("p1", "p2", "h"):
        if not math.isfinite(getattr(args, name)):
            raise model.ParameterError(f"{name} must be finite, got {getattr(args, name)!r}")
    y0 = model.section_state(params, [args.p1], [args.p2], args.h)
    # every indicator of the registry the method computes (SALI and GALI_2: Taylor's tangent lanes)
    r = lyapunov.indicators(params, y0, args.time, method=args.method, tol=args.tol, dt=args.dt,
                            history=args.history, which=lyapunov.available(args.method))
    cols = [RES_T] + [i.column for i in INDICATORS if i.in_history]
    hist = [[float(row[c]) for c in cols] for row in r.history[0] if np.isfinite(row[RES_T])]
    reached = float(r.time[0])
    status = r.status_name(0)

    def estimate(v):      # an orbit stopped at t = 0 has no estimate (null, never a made-up 0)
        return float(v) if reached > 0 and math.isfinite(float(v)) else None

    out = {"params": params.as_dict(), "h": args.h, "p1": args.p1, "p2": args.p2, "method": args.method,
           "settings": r.settings, "status": status, "time": reached,
           **{i.name: estimate(r.values[i.name][0]) for i in INDICATORS},
           "regular_bound": lyapunov.regular_bound(reached) if reached > 1 else None,
           "history": hist}
    if status != "done":
        cover = f"the estimates cover [0, {reached:g}]" if reached > 0 else "no estimate"
        print(f"explorer: the orbit stopped at t = {reached:g} of {args.time:g} ({status}); {cover}",
              file=sys.stderr)
    if args.json:
        print(json.dumps(out))
    else:
        print("\n".join(f"{k} {out[k]!r}" for k in ("time",) + tuple(i.name for i in INDICATORS))
              + f"\nstatus {out['status']}")
        if hist:
            print("history: " + ", ".join(["t"] + [i.name for i in INDICATORS if i.in_history]))
            for row in hist:
                print(",".join(repr(v) for v in row))
    return 0
