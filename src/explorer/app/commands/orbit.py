"""crossings of one orbit with the section phi = phi0

Start on the section phi = phi0 at (p1, p2) with M from the energy h (docs/model.md R9) and
print the next K crossings as CSV (k,t,p1,p2,M,dH) or JSON.
"""
from __future__ import annotations

import json
import math
import sys
from functools import partial

from explorer import model
from explorer.app.commands import options
from explorer.app.commands.options import Command, opt
from explorer.integrate.methods import DEFAULT_DT, DEFAULT_TOL
from explorer.model import validation

COMMAND = Command("orbit", __doc__, "--p1 -0.4 --p2 0 --mu 0.5 --crossings 20 --json", (
    options.add_start_args,
    opt("--crossings", "-K", type=int, default=10, help="number of crossings K [%(default)s]"),
    partial(options.add_method_args, tol=DEFAULT_TOL, dt=DEFAULT_DT),
    opt("--tmax", type=float, default=None, help="time budget [100 K]"),
    opt("--max-steps", type=int, default=10**9, help="step budget [%(default)s]"),
    opt("--phi0", type=options.angle, default=math.pi, help="section angle phi0: a number or pi, pi/2, ... [pi]"),
    opt("--direction", default="+", help="crossing direction: + (dphi/dt > 0), - or both [+]"),
    opt("--out", default=None, help="stream the crossings into this HDF5 store, block by block (a rerun after a "
        "kill continues where it stopped) instead of printing them"),
    opt("--block", type=int, default=None, help="crossings computed (and printed or stored) per block; memory is "
        "O(block) [100000]"),
    opt("--force", action="store_true", help="with --out: overwrite a store of another run"),
    partial(options.add_model_args, json="print JSON instead of CSV (with --out: a summary)"),
))


def _direction(text: str) -> int:
    table = {"+": 1, "+1": 1, "1": 1, "up": 1, "-": -1, "-1": -1, "down": -1, "both": 0, "0": 0}
    if text not in table:
        raise model.ParameterError(f"direction must be one of +, -, both; got {text!r}")
    return table[text]


def run(args) -> int:
    from explorer.analysis.sections import DEFAULT_BLOCK, METHODS, energy_warning

    params = options.params_from(args)
    if args.method not in METHODS:
        raise model.ParameterError(f"method must be one of {', '.join(METHODS)}; got {args.method!r}")
    for name in ("p1", "p2", "h"):
        v = getattr(args, name)
        if not math.isfinite(v):
            raise model.ParameterError(f"{name} must be finite, got {v!r}")
    from explorer.analysis.sections import ROW_BYTES

    block = validation.integer("--block", DEFAULT_BLOCK if args.block is None else args.block, 1)
    # a block holds min(block, crossings) rows (sections.iter_crossings)
    validation.fits_in_memory("--block", min(block, max(args.crossings, 1)), ROW_BYTES, "crossing rows of 40 bytes")
    if args.out is not None:
        validation.output_path("--out", args.out)
    kw = dict(method=args.method, tol=args.tol, dt=args.dt, tmax=args.tmax, max_steps=args.max_steps,
              phi0=args.phi0, direction=_direction(args.direction))
    from explorer.app import orbit

    orbit.check_request(params, args.p1, args.p2, args.h, args.crossings, **kw)
    rep = _run_orbit(args, params, block, kw)
    settings = rep.settings or {}
    setting = f"--dt {settings['dt']:g}" if "dt" in settings else f"--tol {args.tol:g}"
    warning = energy_warning(rep.max_dh, args.h, setting)
    if warning:
        print(f"explorer: warning: {warning}", file=sys.stderr)
    return 0


def _run_orbit(args, params, block, kw):
    from explorer.app import orbit

    if args.out is not None:
        rep = orbit.to_store(args.out, params, args.p1, args.p2, args.h, args.crossings, block=block,
                             force=args.force, **kw)
        summary = {"out": rep.out, "crossings": rep.crossings, "status": rep.status, "max_dh": rep.max_dh,
                   "blocks": rep.blocks, "resumed_blocks": rep.resumed_blocks,
                   "already_complete": rep.already_complete, "settings": rep.settings}
        if args.json:
            print(json.dumps(summary))
        else:
            how = ("already complete" if rep.already_complete else
                   f"{rep.blocks} blocks" + (f", {rep.resumed_blocks} of them from an earlier run"
                                              if rep.resumed_blocks else ""))
            print(f"{rep.out}: {rep.crossings} crossings ({how}); status {rep.status}; "
                  f"max |H - H0| {rep.max_dh:.3g}")
    else:
        rep = orbit.print_rows(params, args.p1, args.p2, args.h, args.crossings, as_json=args.json, block=block,
                               **kw)
        if rep.status != "done" and not args.json:
            print(f"explorer: orbit stopped after {rep.crossings} crossings: {rep.status}", file=sys.stderr)
    return rep
