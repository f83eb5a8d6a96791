#!/usr/bin/env python
"""Greene's residue criterion on the section of Figure 4's scene (h = 2, phi = pi), parameter mu.

For the noble rotation numbers nu = [0; a, (b,) 1, 1, 1, ...] ("noble:a[,b]", gamma = (sqrt 5 - 1)/2:
1/(a + gamma), 1/(a + 1/(b + gamma)); numbers equivalent to the golden mean) 4, (5, 2), 5, (6, 2) and
6, between the island's centre and its edge, the curves around the right island's
elliptic fixed point (near (1.58, 0)): mu_c(nu) by :func:`explorer.greene` (convergents up to
q = 150, half-orbit method on p2 = 0), then the cross-check of docs/greene.md: the orbit on the
line p2 = 0 whose rotation number is nu, found by bisection between the last two convergents'
orbits, has a converged weighted-Birkhoff rotation number equal to nu at 0.99 mu_c; at 1.01 mu_c the
orbit the bisection ends on either does not converge (the cantorus) or converges to another rotation
number (an island of the broken zone): no regular orbit has rotation number nu.

    python benchmarks/bench_greene_section.py           # ~5 min; GREENE-SECTION of RESULTS.md and
                                                          # results/greene_section.json (the breakup figure's data)
    python benchmarks/bench_greene_section.py --quick   # noble:6 only, q <= 60, no RESULTS.md
"""
from __future__ import annotations

import argparse
import time

import _common as C

SECTION = "GREENE-SECTION"
MU0, H, AROUND = 0.025, 2.0, (1.58, 0.0)
NOBLES = ("4", "5,2", "5", "6,2", "6")
#: the orbit of the check is on the curve when its average converged to a rotation number this close to nu
ON_CURVE_TOL = 1e-6


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--iterates", type=int, default=10000, help="N of the weighted Birkhoff check [%(default)s]")
    args = ap.parse_args(argv)
    import explorer as ex
    from explorer import model
    from explorer.analysis import greene as gm
    from explorer.analysis import greene_section as gs

    command = C.command_line("bench_greene_section.py", argv)
    started, load0, t_start = C.now(), C.loadavg(), time.perf_counter()
    smap = ex.SectionMap(model.FIGURE4.with_(mu=MU0), H)
    rows = []
    for a in (("6",) if args.quick else NOBLES):
        nu = gm.rotation_value(f"noble:{a}")
        t0 = time.perf_counter()
        r = gm.greene(smap, nu, qmax=60 if args.quick else 150, around=AROUND)
        wall = time.perf_counter() - t0
        checks = {}
        for f in (0.99, 1.01):
            m = smap.with_parameter(f * r.critical)
            c = gm._centre(m, AROUND)
            (P1, Q1), (P2, Q2) = [(cv["p"], cv["q"]) for cv in r.convergents[-2:]]
            o1 = gs.section_symmetric_orbit(m, Q1, r.convergents[-2]["point"][0])
            o2 = gs.section_symmetric_orbit(m, Q2, r.convergents[-1]["point"][0])
            t1 = time.perf_counter()
            rn = gs.curve_orbit(m, nu, c, o1.points[0, 0], o2.points[0, 0], iterates=args.iterates)
            checks[f] = (rn, time.perf_counter() - t1)
        rows.append((a, nu, r, wall, checks))
        print(f"noble:{a}: nu = {nu:.6f} mu_c = {r.critical:.9f} +- {r.uncertainty:.1e} ({wall:.1f} s); "
              + "; ".join(f"{f} mu_c: rotation {rn.value:.12f} converged {rn.converged} (|WB_N - WB_2N| "
                          f"{rn.difference:.1e})" for f, (rn, _) in checks.items()), flush=True)
    seconds = time.perf_counter() - t_start
    lines, _ = C.header("Greene's residue criterion on the section of Figure 4's scene (right island, mu)", command,
                        started, seconds, load0,
                        extra=[f"h = {H}, phi = pi, the elliptic fixed point near {AROUND}; first guess mu = {MU0}; "
                               f"weighted Birkhoff check with N = {args.iterates} (2N returns): converged when "
                               f"|WB_N - WB_2N| < 1e-10 turns; on the curve when also |rotation| = nu to "
                               f"{ON_CURVE_TOL:g}"])
    lines += ["", "| nu | noble: | mu_c | uncertainty | last ratio | convergents | wall (s) | "
              "0.99 mu_c: rotation, abs(WB_N - WB_2N), on the curve | "
              "1.01 mu_c: rotation, abs(WB_N - WB_2N), on the curve |",
              "|---:|---:|---:|---:|---:|---|---:|---|---|"]
    doc = []
    for a, nu, r, wall, checks in rows:
        cells = []
        for f in (0.99, 1.01):
            rn = checks[f][0]
            on = bool(rn.converged and abs(abs(rn.value) - nu) < ON_CURVE_TOL)
            cells.append(f"{rn.value:.10f}, {rn.difference:.1e}, {'yes' if on else 'no'}")
        lines.append(f"| {nu:.6f} | {a} | {r.critical:.9f} | {r.uncertainty:.1e} | {r.ratio:.3f} | "
                     f"{', '.join(str(c['q']) for c in r.convergents)} | {wall:.1f} | {cells[0]} | {cells[1]} |")
        doc.append(dict(r.as_dict(), a=a, ratio=r.ratio, wall=wall,
                        birkhoff={str(f): dict(rn.as_dict(), wall=w) for f, (rn, w) in checks.items()}))
    out = C.OUT_DIR / ("greene_section_quick.json" if args.quick else "greene_section.json")
    C.write_json(out, {"h": H, "around": AROUND, "mu0": MU0, "curves": doc})
    return C.report(SECTION, lines, not args.quick, written=(out,))


if __name__ == "__main__":
    raise SystemExit(main())
