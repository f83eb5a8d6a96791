"""Melnikov integral ur23 along the homoclinic orbits R7; check of ur24

Quadrature of J(g0) = int {F0, H1} dt along both homoclinic orbits R7 of solution I at
c = sqrt(2 b h) (g0: phi at the orbit's centre), fitted as J = A sin g0 + B cos g0 per unit mu,
compared with ur24 as printed and with the corrected closed form. --splitting adds the splitting
measured on the section phi = pi against mu J(g0). Needs lam > 0, a1 > a2, chi = zeta = 0,
lam b/a1 < c < lam b/a2.
"""
from __future__ import annotations

import json
import math
from functools import partial

from explorer import model
from explorer.app.commands import options
from explorer.app.commands.options import Command, opt

COMMAND = Command("melnikov", __doc__, "--splitting --mus 1e-4,1e-3 --json", (
    partial(options.add_energy_arg, help="energy level h = c^2/(2b) [%(default)s]"),
    opt("--splitting", action="store_true",
        help="also measure the splitting on the section for mu in --mus at phase --g0"),
    opt("--mus", default="1e-4,3e-4,1e-3,3e-3", help="mu values of --splitting [%(default)s]"),
    opt("--g0", type=options.angle, default=0.5 * math.pi,
        help="phase g0 of --splitting: a number or pi, pi/2, ... [pi/2]"),
    partial(options.add_model_args, json="print JSON"),
))


def run(args) -> int:
    from explorer.analysis import melnikov

    params = options.params_from(args)
    # --mus and --g0 are checked with or without --splitting (a bad value is a mistake either way)
    try:
        mus = [float(v) for v in args.mus.split(",")]
    except ValueError:
        raise model.ParameterError(f"--mus must be comma-separated numbers, got {args.mus!r}") from None
    if not mus or not all(math.isfinite(m) and m > 0 for m in mus):
        raise model.ParameterError(f"--mus must be finite and > 0, got {args.mus!r}")
    out = melnikov.amplitudes(params, args.h)
    if args.splitting:
        out["splitting"] = melnikov.melnikov_table(params, args.h, mus, (args.g0,))
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"c {out['c']!r}  (h {out['h']!r}; S {out['S']:.10g}, alpha {out['alpha']:.10g}, B {out['B']:.10g})")
    print("J(g0) per unit mu, g0 = phi at the centre of the homoclinic orbit (quadrature):")
    for s, name in ((1, "plus"), (-1, "minus")):
        print(f"  sign {s:+d}: J = {out['sin_' + name]:.12g} sin g0 {out['cos_' + name]:+.12g} cos g0"
              f"   (xi = eta = 0 amplitude {out['amplitude_' + name]:.12g})")
    print(f"ur24 as printed: J = {out['ur24_sin']:.12g} sin g0 {out['ur24_cos']:+.12g} cos g0"
          f"   (xi = eta = 0 amplitude {out['ur24']:.12g}, ratio to quadrature {out['ur24_ratio']:.6g})")
    print(f"closed form (residues, corrected): sign +1 {out['closed_form_sin_plus']:.12g} sin g0, "
          f"sign -1 {out['closed_form_sin_minus']:.12g} sin g0, {out['closed_form_cos']:.12g} cos g0")
    print("verdict: ur24 " + ("holds" if out["ur24_holds"] else "does NOT hold") + " (rtol 1e-6)")
    if args.splitting:
        print("splitting on phi = pi, F0(W^u) - F0(W^s):")
        print(melnikov.format_table(out["splitting"]))
    return 0
