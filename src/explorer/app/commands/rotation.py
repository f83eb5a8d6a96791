"""rotation numbers along a segment of the section (weighted Birkhoff)

Rotation numbers (turns per return) of orbits started at --n points from --from to --to around
the elliptic fixed point (Newton from --center, default --from), by weighted Birkhoff averages
over N and 2N returns; 'converged' false flags a chaotic orbit. Plateaus at m/K mark island
chains of period K.
"""
from __future__ import annotations

import json

from explorer import model
from explorer.app.commands import options
from explorer.app.commands.options import Command, opt
from explorer.model import validation

COMMAND = Command("rotation", __doc__, "--from 1.5822,0 --to 1.0,0 --n 30 --mu 0.03", (
    opt("--from", dest="start", required=True, help="start of the segment p1,p2"),
    opt("--to", dest="stop", required=True, help="end of the segment p1,p2"),
    opt("--n", type=int, default=21, help="points on the segment [%(default)s]"),
    opt("--iterates", type=int, default=2000, help="N: each orbit has 2N returns [%(default)s]"),
    opt("--center", default=None, help="guess of the elliptic fixed point p1,p2 [--from]"),
    options.add_map_args,
))


def run(args) -> int:
    from explorer.analysis import rotation

    a, b = options.pair(args.start, "--from"), options.pair(args.stop, "--to")
    if args.n < 2:
        raise model.ParameterError(f"--n must be an integer >= 2, got {args.n}")
    if args.iterates < 10:
        raise model.ParameterError(f"--iterates must be an integer >= 10, got {args.iterates}")
    from explorer.analysis.fixedpoints import find_fixed_point

    # each point keeps its 2N returns (p1, p2: 16 bytes each)
    validation.fits_in_memory("--n", args.n, 32 * args.iterates, "2 x --iterates returns of 16 bytes per point", lo=2)
    params = options.section_map_args(args)
    c_guess = options.pair(args.center, "--center") if args.center is not None else a
    for name, x in (("--from", a), ("--to", b), ("--center", c_guess)):
        if not model.is_admissible(params, x[0], x[1], args.h):
            raise model.ParameterError(f"{name} ({x[0]:g}, {x[1]:g}) lies outside the allowed region; allowed: "
                                       f"{model.describe_region(params, args.h)}")
    center = find_fixed_point(params, args.h, c_guess, tol=args.tol)
    prof = rotation.rotation_profile(params, args.h, a, b, n=args.n, center=center.point, iterates=args.iterates,
                                     tol=args.tol)
    out = dict(prof.as_dict(), params=params.as_dict(), h=args.h, center_stable=bool(center.stable))
    if args.json:
        print(json.dumps(out))
    else:
        print(f"center ({float(prof.center[0])!r}, {float(prof.center[1])!r}) {center.kind}; "
              f"{prof.iterates} returns per orbit")
        print("s,p1,p2,rotation,converged")
        for r in out["profile"]:
            print(f"{r['s']!r},{r['p1']!r},{r['p2']!r},{r['rotation']!r},{r['converged']}")
    return 0
