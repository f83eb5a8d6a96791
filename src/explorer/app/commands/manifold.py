"""stable and unstable manifolds of a hyperbolic orbit, homoclinic points, lobes and flux

Finds the periodic orbit of period --period from --guess (default: the central hyperbolic fixed
point), grows both branches of W^u and W^s at its point --index to --arclength (adaptive
insertion), locates their intersections (Newton, 1e-10) and the turnstile's lobes (Green's
theorem); docs/manifolds.md.
"""
from __future__ import annotations

import json
from functools import partial

from explorer import model
from explorer.app.commands import options
from explorer.app.commands.options import Command, opt
from explorer.model import validation

COMMAND = Command("manifold", __doc__, "--mu 0.03 --arclength 6 --json", (
    opt("--guess", default="0,0", help="start of Newton's method for the orbit: p1,p2 [0,0]"),
    opt("--period", type=int, default=1, help="period K of the orbit [%(default)s]"),
    opt("--index", type=int, default=0, help="which point of the orbit [%(default)s]"),
    opt("--arclength", type=float, default=6.0, help="length of each branch [%(default)s]"),
    opt("--max-points", type=int, default=20000, help="points per branch at most [%(default)s]"),
    opt("--max-time", type=float, default=None, help="seconds per branch at most [none]"),
    partial(options.add_map_args, tol_help="Taylor tolerance of the section map [%(default)s]",
            json="print JSON {orbit, branches, homoclinic_points, heteroclinic_points, lobes, flux}"),
))


def run(args) -> int:
    from explorer.analysis import manifolds, periodic, transport
    from explorer.analysis.section_map import SectionMap

    params = options.section_map_args(args)
    if args.period < 1:
        raise model.ParameterError(f"--period must be an integer K >= 1, got {args.period}")
    validation.integer("--period", args.period, 1, validation.MAX_PERIOD)
    # four branches of at most --max-points points (p1, p2 and their parameter: about 64 bytes each)
    validation.fits_in_memory("--max-points", args.max_points, 4 * 64, "4 branches of 64 bytes per point", lo=1)
    if args.max_time is not None:
        validation.real("--max-time", args.max_time, 0.0, lo_open=True)
    smap = SectionMap(params, args.h, tol=args.tol)
    orb = periodic.find_periodic_orbit(smap, options.pair(args.guess, "--guess"), args.period)
    sd = manifolds.saddle(smap, orb, index=args.index)
    kw = {"arclength": args.arclength, "max_points": args.max_points, "max_time": args.max_time}
    branches = [manifolds.grow_branch(sd, stable=st, sign=sg, **kw) for st in (False, True) for sg in (1, -1)]
    hps: list = []
    lobes: list = []
    for bu in branches[:2]:
        for bs in branches[2:]:
            found = manifolds.homoclinic_points(bu, bs)
            hps += [h.point.tolist() for h in found]
            if not lobes and found:
                lobes = transport.lobes(bu, bs, points=found)
    flux = abs(lobes[0].area) if lobes else None
    het = _heteroclinic(orb, args, kw)
    ev = [complex(e) for e in orb.eigenvalues]
    out = {"orbit": {"points": orb.points.tolist(), "period": int(orb.period),
                     "eigenvalues": [[e.real, e.imag] if e.imag else e.real for e in ev]},
           "branches": [{"kind": b.kind, "sign": b.sign, "points": b.points.tolist(), "arclength": b.arclength,
                         "status": b.status} for b in branches],
           "homoclinic_points": hps, "heteroclinic_points": het,
           "lobes": [{"area": abs(lb.area), "error": lb.error} for lb in lobes],
           "flux": flux}
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"orbit K={orb.period} point=({sd.point[0]:.10g},{sd.point[1]:.10g}) multiplier={sd.multiplier:.10g}")
    for b in branches:
        print(f"{b.kind} {b.sign:+d}: {len(b.points)} points, arclength {b.arclength:.6g} ({b.status})")
    print(f"{len(hps)} homoclinic point(s)")
    if orb.period > 1:
        print(f"{len(het)} heteroclinic point(s) between point {sd_index(args, orb)} of the orbit and its neighbours")
    for lb in lobes:
        print(f"lobe area {abs(lb.area):.10g} +- {lb.error:.2g}")
    print(f"flux per iteration {flux!r}")
    return 0


#: start distance of the branches grown for heteroclinic points (fewer generations, less rounding error:
#: explorer.analysis.manifolds.heteroclinic_points)
HETEROCLINIC_START_TOL = 1e-8


def sd_index(args, orb) -> int:
    return args.index % orb.period


def _heteroclinic(orb, args, kw) -> list:
    """Heteroclinic points of a periodic orbit (period K >= 2): W^u at point --index meets W^s at
    its neighbours index +- 1 (mod K); [] for a fixed point."""
    from explorer.analysis import manifolds
    from explorer.analysis.section_map import SectionMap

    K = orb.period
    if K < 2:
        return []
    i = sd_index(args, orb)
    grow = dict(kw, start_tol=HETEROCLINIC_START_TOL)
    smap = SectionMap(orb.params, orb.h, phi0=orb.phi0, tol=args.tol)
    src = manifolds.saddle(smap, orb, index=i)
    wu = [manifolds.grow_branch(src, sign=sg, **grow) for sg in (1, -1)]
    out = []
    for j in sorted({(i + 1) % K, (i - 1) % K}):
        dst = manifolds.saddle(smap, orb, index=j)
        for bs in (manifolds.grow_branch(dst, stable=True, sign=sg, **grow) for sg in (1, -1)):
            for bu in wu:
                out += [{"point": p.point.tolist(), "from": i, "to": j, "sign_u": bu.sign, "sign_s": bs.sign,
                         "angle": p.angle, "residual": p.residual}
                        for p in manifolds.heteroclinic_points(bu, bs)]
    return out
