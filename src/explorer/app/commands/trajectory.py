"""the body in the plane (full system R1, any lam): drift, band, falling body

Integrate the full system R1 (p1, p2, M, phi, x, y) with adaptive DOP853, check H and the
momentum integrals R2, print the measured mean horizontal velocity against +mu/lam and the band
in y (lam != 0) or, for lam = 0 (the falling body), the fitted exponents of the amplitude
(Kozlov: -1/2) and frequency (Kozlov: 1) of the oscillation of phi; draw the path with the
body's orientation (PNG and PDF).
"""
from __future__ import annotations

import json
from functools import partial

from explorer import model
from explorer.app.commands import options
from explorer.app.commands.options import Command, opt
from explorer.integrate.methods import TRAJECTORY_TOL
from explorer.model import validation

COMMAND = Command("trajectory", __doc__, "--p1 0.5 --M 2 --mu 0.5 --tmax 300 --out figures/trajectory", (
    opt("--p1", type=float, default=0.5, help="initial p1 [%(default)s]"),
    opt("--p2", type=float, default=0.0, help="initial p2 [%(default)s]"),
    opt("--M", type=float, default=2.0, help="initial M [%(default)s]"),
    opt("--phi", type=options.angle, default=0.0, help="initial angle phi: a number or pi, pi/2, ... [%(default)s]"),
    opt("--tmax", type=float, default=300.0, help="integration time: the time the orbit runs to "
        "[%(default)s]"),
    opt("--samples", type=int, default=20001, help="samples on [0, T] [%(default)s]"),
    opt("--tol", type=float, default=TRAJECTORY_TOL, help="DOP853 tolerance (rtol = atol) [%(default)s]"),
    opt("--glyphs", type=int, default=40, help="orientation glyphs along the path [%(default)s]"),
    opt("--out", default="figures/trajectory", help="figure path without extension (lam = 0 adds <out>_kozlov) "
        "[%(default)s]"),
    opt("--no-figure", action="store_true", help="do not draw the figure"),
    partial(options.add_model_args, defaults=model.FIGURE4.with_(mu=0.5), json="print JSON",
            title="model parameters (docs/model.md; defaults: Figure 4 with mu = 0.5)",
            helps={"lam": "circulation x density (any; 0 = falling body)"}),
))


def run(args) -> int:
    from explorer.analysis import trajectory as tr
    from explorer.app import trajectory_figure

    # R1 allows lam = 0: full_params validates the rest with model.Params (lam replaced by 1)
    prm = tr.full_params({n: getattr(args, n) for n in model.PARAM_NAMES})
    y0 = tr.initial_state(prm, args.p1, args.p2, args.M, args.phi)
    if args.glyphs < 1:
        raise model.ParameterError(f"glyphs must be >= 1, got {args.glyphs!r}")
    if not args.no_figure:
        validation.output_path("--out", args.out)
    res = tr.trajectory(prm, y0, args.tmax, args.samples, args.tol, phi_start=args.phi)
    cons = tr.conservation(res)
    d = k = None
    if prm["lam"] != 0.0:
        d = tr.drift(prm, y0, args.tmax, result=res)
    elif prm["mu"] > 0.0 and prm["a1"] != prm["a2"]:
        k = tr.kozlov(prm, y0, args.tmax, result=res)
    out = {"params": prm, "initial": {"p1": args.p1, "p2": args.p2, "M": args.M, "phi": args.phi},
           "time": args.tmax, "samples": args.samples, "tol": args.tol, "status": res.status,
           "steps": res.steps}
    out.update(tr.summary(d, k, cons))
    if not args.no_figure:
        figs = []
        from explorer.app.figures import save_figure

        fig = trajectory_figure.path_figure(res, prm, glyphs=args.glyphs, band=None if d is None else d["band"])
        figs += [str(p) for p in save_figure(fig, args.out)]
        if k is not None:
            figs += [str(p) for p in save_figure(trajectory_figure.kozlov_figure(k, prm), str(args.out) + "_kozlov")]
        out["figures"] = figs
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"status {res.status}  (T {args.tmax:g}, {res.steps} steps, tol {args.tol:g})")
    print(f"conservation: |dH| {cons['H']:.3g} (rel {cons['H_rel']:.3g}), |d p_x| {cons['px']:.3g} "
          f"(rel {cons['px_rel']:.3g}), |d(p_y + mu t)| {cons['py']:.3g} (rel {cons['py_rel']:.3g})")
    if d is not None:
        b = d["band"]
        print(f"drift: measured {d['measured']:.10g} (fit of x(t)), endpoint {d['endpoint']:.10g}; "
              f"predicted +mu/lam = {d['predicted']:.10g} (seed ur25: {d['seed']:.10g}); "
              f"relative error {d['rel_error']:.3g}")
        print(f"band in y: measured [{b['y_min']:.6g}, {b['y_max']:.6g}]; predicted c1/lam +- max|p - s|/|lam| = "
              f"{b['centre']:.6g} +- {b['halfwidth_orbit']:.6g} (energy bound +- {b['halfwidth_energy']:.6g}); "
              f"inside: {b['inside']}")
    elif k is not None:
        print(f"falling body (lam = 0), fit over t in [{k['fit_window'][0]:g}, {k['fit_window'][1]:g}], "
              f"{k['n_half_periods']} half-periods:")
        print(f"  amplitude ~ t^{k['amplitude_exponent']:.5f} (Kozlov: -1/2); "
              f"frequency ~ t^{k['frequency_exponent']:.5f} (Kozlov: 1)")
        print(f"  frequency/t {k['freq_rate']:.6g} (linearised ur17: {k['freq_rate_predicted']:.6g}); "
              f"phi_inf = {k['phi_inf_mod_pi']:.6g} mod pi (predicted {k['phi_inf_predicted_mod_pi']:.6g})")
    else:
        print("lam = 0 without a restoring torque (mu = 0 or a1 = a2): no drift, no Kozlov fit")
    for f in out.get("figures", []):
        print(f"wrote {f}")
    return 0
