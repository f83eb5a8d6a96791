#!/usr/bin/env python
"""Greene's residue criterion on the section of Figure 4's scene (h = 2, phi = pi), parameter mu.

For the noble rotation numbers nu = [0; a, (b,) 1, 1, 1, ...] ("noble:a[,b]", gamma = (sqrt 5 - 1)/2:
1/(a + gamma), 1/(a + 1/(b + gamma)); numbers equivalent to the golden mean) 4, (5, 2), 5, (6, 2) and
6, between the island's centre and its edge, the curves around the elliptic fixed point of each
island (the right one near (1.58, 0), the left one near (-1.16, 0)): mu_c(nu) by
:func:`explorer.greene` (convergents up to q = 150, half-orbit method on the symmetry line that
carries the island's elliptic orbits: p2 = 0 of phi = pi for the right island, of phi = 0 for the
left one, docs/greene.md "The left island"), then the cross-check of docs/greene.md: the orbit
on that line whose rotation number is nu, found by bisection between the last two convergents'
orbits, has (carried to the section phi = pi, averaged there around the island's centre) a
converged weighted-Birkhoff rotation number equal to nu at 0.99 mu_c; at 1.01 mu_c the orbit the
bisection ends on either does not converge (the cantorus) or converges to another rotation number
(an island of the broken zone): no regular orbit has rotation number nu.  The two islands are
images of each other under the half-turn (docs/model.md, "Symmetries"), so their mu_c must agree:
the last table compares them.

    python benchmarks/bench_greene_section.py           # both islands, ~10 min; GREENE-SECTION of RESULTS.md
                                                          # and results/greene_section.json
    python benchmarks/bench_greene_section.py --island left     # one island
    python benchmarks/bench_greene_section.py --quick   # noble:6 only, q <= 60, no RESULTS.md
"""
from __future__ import annotations

import argparse
import math
import time

import _common as C

SECTION = "GREENE-SECTION"
MU0, H = 0.025, 2.0
#: a guess of each island's elliptic fixed point on the section phi = pi (Newton finds it)
ISLANDS = {"right": (1.58, 0.0), "left": (-1.16, 0.0)}
NOBLES = ("4", "5,2", "5", "6,2", "6")
#: the orbit of the check is on the curve when its average converged to a rotation number this close to nu
ON_CURVE_TOL = 1e-6


def curve_orbit(smap, nu, centre, a, b, *, iterates, steps=24, search_iterates=300, line=None):
    """The weighted-Birkhoff rotation number around ``centre`` of the orbit through the point of the
    symmetry line p2 = 0 of phi = ``line`` (default ``smap``'s own) between p1 = ``a`` and ``b`` where
    |rotation| = ``nu`` (docs/greene.md, "Cross-check by rotation numbers"): bisection on p1 (``steps``
    halvings, 2 ``search_iterates`` returns each, on the line's section), then 2 ``iterates`` returns
    of the last midpoint's orbit on ``smap``'s section.  ``converged`` below the breakup, not above."""
    import numpy as np

    from explorer.analysis import greene_section as gs
    from explorer.analysis.rotation import rotation_number

    other = gs.line_map(smap, line)
    around = gs.line_point(smap, centre, other.phi0) if other is not smap else np.asarray(centre, float)

    def rot(x, n):
        return rotation_number(other, (x, 0.0), center=around, iterates=n)

    sign_a = math.copysign(1.0, abs(rot(a, search_iterates).value) - nu)
    for _ in range(steps):
        m = 0.5 * (a + b)
        r = rot(m, search_iterates)
        if not math.isfinite(r.value):
            break
        if math.copysign(1.0, abs(r.value) - nu) == sign_a:
            a = m
        else:
            b = m
    x = (0.5 * (a + b), 0.0)
    if other is not smap:
        x = tuple(gs.line_point(other, x, smap.phi0))
    return rotation_number(smap, x, center=centre, iterates=iterates)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--island", choices=(*ISLANDS, "both"), default="both", help="which island [%(default)s]")
    ap.add_argument("--iterates", type=int, default=10000, help="N of the weighted Birkhoff check [%(default)s]")
    args = ap.parse_args(argv)
    import explorer as ex
    from explorer import model
    from explorer.analysis import greene as gm
    from explorer.analysis import greene_section as gs

    command = C.command_line("bench_greene_section.py", argv)
    started, load0, t_start = C.now(), C.loadavg(), time.perf_counter()
    smap = ex.SectionMap(model.FIGURE4.with_(mu=MU0), H)
    islands = list(ISLANDS) if args.island == "both" else [args.island]
    rows = []
    for island in islands:
        around = ISLANDS[island]
        for a in (("6",) if args.quick else NOBLES):
            nu = gm.rotation_value(f"noble:{a}")
            t0 = time.perf_counter()
            r = gm.greene(smap, nu, qmax=60 if args.quick else 150, around=around)
            wall = time.perf_counter() - t0
            checks = {}
            for f in (0.99, 1.01):
                m = smap.with_parameter(f * r.critical)
                c = gs.island_centre(m, around)
                ends = [gs.section_symmetric_orbit(m, cv["q"], cv["line_start"], line=r.line).line_start
                        for cv in r.convergents[-2:]]
                t1 = time.perf_counter()
                rn = curve_orbit(m, nu, c, *ends, iterates=args.iterates, line=r.line)
                checks[f] = (rn, time.perf_counter() - t1)
            rows.append((island, a, nu, r, wall, checks))
            print(f"{island} noble:{a}: nu = {nu:.6f} mu_c = {r.critical:.9f} +- {r.uncertainty:.1e} (line phi = "
                  f"{r.line:g}, {wall:.1f} s); "
                  + "; ".join(f"{f} mu_c: rotation {rn.value:.12f} converged {rn.converged} (|WB_N - WB_2N| "
                              f"{rn.difference:.1e})" for f, (rn, _) in checks.items()), flush=True)
    seconds = time.perf_counter() - t_start
    lines, _ = C.header(f"Greene's residue criterion on the section of Figure 4's scene ({' and '.join(islands)} "
                        f"island{'s' if len(islands) > 1 else ''}, mu)", command, started, seconds, load0,
                        extra=[f"h = {H}, phi = pi, the elliptic fixed points near "
                               + ", ".join(f"{ISLANDS[i]} ({i})" for i in islands)
                               + f"; first guess mu = {MU0}; orbits on the symmetry line p2 = 0 of phi = 'line'; "
                               f"weighted Birkhoff check with N = {args.iterates} (2N returns on phi = pi, around the "
                               f"island's centre): converged when |WB_N - WB_2N| < 1e-10 turns; on the curve when "
                               f"also |rotation| = nu to {ON_CURVE_TOL:g}"])
    lines += ["", "| island | line phi | nu | noble: | mu_c | uncertainty | last ratio | convergents | wall (s) | "
              "0.99 mu_c: rotation, abs(WB_N - WB_2N), on the curve | "
              "1.01 mu_c: rotation, abs(WB_N - WB_2N), on the curve |",
              "|---|---:|---:|---:|---:|---:|---:|---|---:|---|---|"]
    doc = []
    for island, a, nu, r, wall, checks in rows:
        cells = []
        for f in (0.99, 1.01):
            rn = checks[f][0]
            on = bool(rn.converged and abs(abs(rn.value) - nu) < ON_CURVE_TOL)
            cells.append(f"{rn.value:.10f}, {rn.difference:.1e}, {'yes' if on else 'no'}")
        lines.append(f"| {island} | {r.line:g} | {nu:.6f} | {a} | {r.critical:.9f} | {r.uncertainty:.1e} | "
                     f"{r.ratio:.3f} | {', '.join(str(c['q']) for c in r.convergents)} | {wall:.1f} | {cells[0]} | "
                     f"{cells[1]} |")
        doc.append(dict(r.as_dict(), island=island, around=ISLANDS[island], line=r.line, a=a, ratio=r.ratio,
                        wall=wall, birkhoff={str(f): dict(rn.as_dict(), wall=w) for f, (rn, w) in checks.items()}))
    if len(islands) > 1:     # the half-turn pairs the islands: the same mu_c (docs/greene.md)
        by = {(i, a): r for i, a, _, r, _, _ in rows}
        lines += ["", "The two islands are each other's image under the half-turn: mu_c(left) - mu_c(right), "
                  "and the largest difference of the residues at mu_c of the same convergents:", "",
                  "| noble: | mu_c right | mu_c left | left - right | max abs(residue left - residue right) |",
                  "|---:|---:|---:|---:|---:|"]
        for a in (("6",) if args.quick else NOBLES):
            rr, rl = by[("right", a)], by[("left", a)]
            dres = max(abs(x["residue_at_critical"] - y["residue_at_critical"]) for x, y in zip(rl.convergents, rr.convergents))
            lines.append(f"| {a} | {rr.critical:.12f} | {rl.critical:.12f} | {rl.critical - rr.critical:.1e} | "
                         f"{dres:.1e} |")
    out = C.OUT_DIR / ("greene_section_quick.json" if args.quick else "greene_section.json" if len(islands) > 1
                       else f"greene_section_{islands[0]}.json")
    C.write_json(out, {"h": H, "islands": {i: ISLANDS[i] for i in islands}, "mu0": MU0, "curves": doc})
    return C.report(SECTION, lines, not args.quick and len(islands) > 1, written=(out,))


if __name__ == "__main__":
    raise SystemExit(main())
