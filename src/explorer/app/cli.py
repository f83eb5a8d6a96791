"""Command line: ``python -m explorer COMMAND ...``.

Bad input prints one line ``explorer: error: ...`` naming the parameter and
what is allowed, and exits with status 2 (no traceback).
"""
from __future__ import annotations

import argparse
import json
import math
import re
import sys

import numpy as np

from explorer import __version__, model
from explorer.integrate.methods import MAP_TOL, TRAJECTORY_TOL
from explorer.model import validation

EXIT_USAGE = 2


class UsageError(Exception):
    """Bad input: reported on one line, exit status 2."""


#: a token that is a value, not an option, although it starts with "-": numbers and number
#: lists such as -1.2, -3e-1, -0.4,0, -inf (argparse alone accepts only -1 and -1.5)
NEGATIVE_VALUE = re.compile(r"^-(\d|\.\d|inf\b|nan\b)[\w.,+\-]*$")

#: the example printed at the end of each command's --help (tests/app/test_cli.py parses each)
EXAMPLES = {
    "orbit": "python -m explorer orbit --p1 -0.4 --p2 0 --mu 0.5 --crossings 20 --json",
    "sweep": "python -m explorer sweep figure4 --out results/figure4.h5 --jobs 2",
    "lyapunov": "python -m explorer lyapunov --p1 -0.2 --p2 0.1 --mu 1 -T 1000 --json",
    "fixedpoint": "python -m explorer fixedpoint --guess -0.4,0 --mu 0.5 --continue mu 0.5 3.5 0.1",
    "periodic": "python -m explorer periodic --period 3 --search --grid 10 --mu 0.03 --json",
    "rotation": "python -m explorer rotation --from 1.5822,0 --to 1.0,0 --n 30 --mu 0.03",
    "explore": "python -m explorer explore figure4 --panel 2",
    "serve": "python -m explorer serve figure4 --mu 0.03",
    "melnikov": "python -m explorer melnikov --splitting --mus 1e-4,1e-3 --json",
    "trajectory": "python -m explorer trajectory --p1 0.5 --M 2 --mu 0.5 -T 300 --out figures/trajectory",
    "figures": "python -m explorer figures --only figure4 --quick",
    "manifold": "python -m explorer manifold --mu 0.03 --arclength 6 --json",
}


class _Formatter(argparse.HelpFormatter):
    """Wraps the description as usual; keeps the example (epilog) on its own lines."""

    def _fill_text(self, text, width, indent):
        if text.startswith("example:"):
            return "".join(indent + line for line in text.splitlines(keepends=True))
        return super()._fill_text(text, width, indent)


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)
        # values with a leading minus without "=" (--guess -0.4,0, --p1 -3e-1): argparse consults
        # this matcher (CPython's argparse, stable since 3.2) before treating "-..." as an option;
        # no option of this parser looks like a number, so the wider pattern is unambiguous
        self._negative_number_matcher = NEGATIVE_VALUE

    def error(self, message):  # one line, no usage dump
        raise UsageError(message)


def _add_model_args(p, defaults: model.Params, json: str | None = None):
    """--json (with this help) and the model parameters with their defaults."""
    if json:
        p.add_argument("--json", action="store_true", help=json)
    g = p.add_argument_group("model parameters (docs/model.md; defaults: Figure 4, R9)")
    for name, help_ in (("a1", "added mass along axis 1 (> 0)"), ("a2", "added mass along axis 2 (> 0)"),
                        ("b", "added moment of inertia (> 0)"), ("lam", "circulation x density (!= 0)"),
                        ("chi", "asymmetry term chi"), ("zeta", "asymmetry term zeta"),
                        ("mu", "weight (>= 0)"), ("xi", "centre of mass xi"), ("eta", "centre of mass eta")):
        g.add_argument(f"--{name}", type=float, default=getattr(defaults, name), help=f"{help_} [%(default)s]")


def _add_start_args(p):
    """--p1 --p2 --h: a start point on the section and the energy level (M from R9)."""
    p.add_argument("--p1", type=float, required=True, help="start point p1 on the section")
    p.add_argument("--p2", type=float, required=True, help="start point p2 on the section")
    p.add_argument("--h", type=float, default=model.FIGURE4_H, help="energy level [%(default)s]")


def _add_method_args(p, tol, dt):
    """--method --tol --dt, with this command's defaults."""
    from explorer.integrate.methods import METHODS

    p.add_argument("--method", default="taylor", help=f"one of {', '.join(METHODS)} [%(default)s]")
    p.add_argument("--tol", type=float, default=tol, help="tolerance of taylor/dop853 [%(default)s]")
    p.add_argument("--dt", type=float, default=dt, help="fixed step of the split* methods [%(default)s]")


def _params_from(args) -> model.Params:
    return model.Params(**{n: getattr(args, n) for n in model.PARAM_NAMES})


def _add_newton_args(p, continue_help):
    """The options of the Newton commands (fixedpoint, periodic): energy, continuation, the Taylor
    tolerance of the section map, the model."""
    p.add_argument("--h", type=float, default=model.FIGURE4_H, help="energy level [%(default)s]")
    p.add_argument("--continue", dest="cont", nargs=4, metavar=("PARAM", "START", "STOP", "STEP"), help=continue_help)
    p.add_argument("--tol", type=float, default=MAP_TOL, help="Taylor tolerance [%(default)s]")
    _add_model_args(p, model.FIGURE4, json="print JSON")


def build_parser() -> argparse.ArgumentParser:
    from explorer.analysis.sections import DEFAULT_DT, DEFAULT_TOL, METHODS

    parser = _Parser(prog="explorer", description="Poincaré sections and chaos for Chaplygin's equations "
                     "of a heavy rigid body in an ideal fluid with circulation.")
    parser.add_argument("--version", action="version", version=f"explorer {__version__}")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser)

    o = sub.add_parser("orbit", help="crossings of one orbit with the section phi = phi0",
                       description="Start on the section phi = phi0 at (p1, p2) with M from the energy h "
                       "(docs/model.md R9) and print the next K crossings as CSV (k,t,p1,p2,M,dH) or JSON.")
    _add_start_args(o)
    o.add_argument("--crossings", "-K", type=int, default=10, help="number of crossings K [%(default)s]")
    _add_method_args(o, DEFAULT_TOL, DEFAULT_DT)
    o.add_argument("--tmax", type=float, default=None, help="time budget [100 K]")
    o.add_argument("--max-steps", type=int, default=10**9, help="step budget [%(default)s]")
    o.add_argument("--phi0", type=float, default=math.pi, help="section angle phi0 [pi]")
    o.add_argument("--direction", default="+", help="crossing direction: + (dphi/dt > 0), - or both [+]")
    o.add_argument("--out", default=None,
                   help="stream the crossings into this HDF5 store, block by block (a rerun after a kill "
                   "continues where it stopped) instead of printing them")
    o.add_argument("--block", type=int, default=None,
                   help="crossings computed (and printed or stored) per block; memory is O(block) "
                   "[100000]")
    o.add_argument("--force", action="store_true", help="with --out: overwrite a store of another run")
    _add_model_args(o, model.FIGURE4, json="print JSON instead of CSV (with --out: a summary)")

    w = sub.add_parser("sweep", help="Poincaré sections of every panel of a scene (default: figure4)",
                       description="Run every panel of a scene (a TOML file or a built-in preset), store all "
                       "crossings in one HDF5 file and draw the figure. Panels already stored with the same "
                       "settings are skipped; a killed run resumes where it stopped.")
    w.add_argument("scene", nargs="?", default="figure4", help="scene file (.toml) or preset name [figure4]")
    w.add_argument("--out", default=None, help="HDF5 file [results/<scene>.h5]")
    w.add_argument("--figure", default=None,
                   help="figure path without extension [the --out path without .h5: beside the store]")
    w.add_argument("--no-figure", action="store_true", help="do not draw the figure")
    w.add_argument("--jobs", type=int, default=1,
                   help="joblib worker processes (1: this process with Numba threads over orbits) [1]")
    w.add_argument("--backend", default=None, choices=["loky", "multiprocessing", "dask"],
                   help="joblib backend for --jobs > 1 (dask: run on a dask.distributed cluster)")
    w.add_argument("--scheduler", default=None,
                   help="dask scheduler address (with --backend dask; default: a local cluster of --jobs workers)")
    w.add_argument("--force", action="store_true", help="recompute every panel")
    w.add_argument("--quiet", action="store_true", help="no progress bar")

    ly = sub.add_parser("lyapunov", help="chaos indicators of one orbit: finite-time mLCE, MEGNO, FLI, SALI, GALI2",
                        description="Start on the section phi = pi at (p1, p2) with M from the energy h and "
                        "integrate the orbit with one deviation vector (tangent to the energy shell) for a "
                        "time T; print the finite-time maximal Lyapunov exponent, the mean MEGNO <Y> and the "
                        "FLI, with their convergence history; with the Taylor method also SALI and GALI2 "
                        "from a second deviation vector (null for other methods).")
    _add_start_args(ly)
    ly.add_argument("--time", "-T", type=float, default=1000.0, help="integration time T [%(default)s]")
    _add_method_args(ly, DEFAULT_TOL, DEFAULT_DT)
    ly.add_argument("--history", type=int, default=12, help="history points (log-spaced in time) [%(default)s]")
    _add_model_args(ly, model.FIGURE4, json="print JSON")

    fx = sub.add_parser("fixedpoint", help="a fixed point of the section map, its stability, continuation",
                        description="Newton's method on the section map phi = pi (Jacobian from the tangent "
                        "dynamics); prints the point, the monodromy eigenvalues, trace and stability. With "
                        "--continue PARAM START STOP STEP, follows the branch and reports where |trace| = 2.")
    fx.add_argument("--guess", default="0,0", help="start of Newton's method: p1,p2, e.g. --guess -0.4,0 [0,0]")
    _add_newton_args(fx, "continue the fixed point in PARAM (a model parameter or h)")

    # ---- periodic, rotation: periodic orbits and rotation numbers (analysis/periodic.py, rotation.py)
    pd = sub.add_parser("periodic", help="periodic orbits of period K of the section map, stability, continuation",
                        description="Newton's method on P^K(x) = x for the section map phi = pi (Jacobian from "
                        "the tangent dynamics; multiple shooting for K > 4), from --guess or by a --search "
                        "covering the allowed region and the symmetry lines; prints each orbit once with its "
                        "minimal period, points, trace, Greene's residue, eigenvalues, stability and symmetry. "
                        "With --continue PARAM START STOP STEP (and --guess), follows the orbit and reports "
                        "where |trace| crosses or touches 2.")
    pd.add_argument("--period", "-K", type=int, required=True, help="period K >= 1")
    pmode = pd.add_mutually_exclusive_group(required=True)
    pmode.add_argument("--guess", default=None, help="start of Newton's method: p1,p2, e.g. --guess -0.4,0")
    pmode.add_argument("--search", action="store_true", help="search the allowed region for all orbits")
    pd.add_argument("--grid", type=int, default=12, help="grid points per axis of --search [%(default)s]")
    pd.add_argument("--max-guesses", type=int, default=60, help="Newton starts of --search [%(default)s]")
    _add_newton_args(pd, "continue the orbit through --guess in PARAM (a model parameter or h)")

    rt = sub.add_parser("rotation", help="rotation numbers along a segment of the section (weighted Birkhoff)",
                        description="Rotation numbers (turns per return) of orbits started at --n points from "
                        "--from to --to around the elliptic fixed point (Newton from --center, default "
                        "--from), by weighted Birkhoff averages over N and 2N returns; 'converged' false "
                        "flags a chaotic orbit. Plateaus at m/K mark island chains of period K.")
    rt.add_argument("--from", dest="start", required=True, help="start of the segment p1,p2")
    rt.add_argument("--to", dest="stop", required=True, help="end of the segment p1,p2")
    rt.add_argument("--n", type=int, default=21, help="points on the segment [%(default)s]")
    rt.add_argument("--iterates", type=int, default=2000, help="N: each orbit has 2N returns [%(default)s]")
    rt.add_argument("--center", default=None, help="guess of the elliptic fixed point p1,p2 [--from]")
    rt.add_argument("--h", type=float, default=model.FIGURE4_H, help="energy level [%(default)s]")
    rt.add_argument("--tol", type=float, default=MAP_TOL, help="Taylor tolerance [%(default)s]")
    _add_model_args(rt, model.FIGURE4, json="print JSON")
    # ---- end periodic, rotation ----------------------------------------------------------------
    # ---- explore: interactive explorer (explorer/explore.py) -------------------------------
    x = sub.add_parser("explore", help="interactive window: click on the section, watch the orbit appear",
                       description="Open a matplotlib window with the allowed region of the section phi = pi at "
                       "energy h; a click inside starts an orbit and draws its crossings as they are computed. "
                       "Keys: c clear, r re-run seeds, s save PNG, w write HDF5, x colour by the divergence "
                       "proxy, p separatrices, o periodic orbits of periods 1..4. Needs a display.")
    x.add_argument("scene", nargs="?", default=None,
                   help="scene file (.toml) or preset name (e.g. figure4): start from its panel's parameters, "
                   "h and integration settings [none: Figure 4 with mu = 0, h = 2]")
    x.add_argument("--panel", type=int, default=0, help="panel of the scene [0]")
    x.add_argument("--h", type=float, default=None, help="energy level [the scene's, else 2]")
    x.add_argument("--method", default=None, help=f"one of {', '.join(METHODS)} [the scene's, else taylor]")
    x.add_argument("--tol", type=float, default=None, help=f"tolerance of taylor/dop853 [{DEFAULT_TOL}]")
    x.add_argument("--dt", type=float, default=None, help=f"fixed step of the split* methods [{DEFAULT_DT}]")
    x.add_argument("--crossings-per-chunk", type=int, default=50,
                   help="crossings computed per orbit between redraws [%(default)s]")
    x.add_argument("--max-crossings", type=int, default=2000, help="crossings per orbit [%(default)s]")
    x.add_argument("--out-dir", default=".", help="where s (PNG) and w (HDF5) write [current directory]")
    xg = x.add_argument_group("model parameters (override the scene's; defaults: Figure 4, R9, mu = 0)")
    for name in model.PARAM_NAMES:
        xg.add_argument(f"--{name}", type=float, default=None)
    # ---- end explore ------------------------------------------------------------------------
    from explorer.app.serve.command import add_parser as add_serve_parser  # the explorer in the browser

    add_serve_parser(sub)
    # ---- melnikov: Melnikov integral ur23/ur24 (explorer/melnikov.py) ------------------------
    mk = sub.add_parser("melnikov", help="Melnikov integral ur23 along the homoclinic orbits R7; check of ur24",
                        description="Quadrature of J(g0) = int {F0, H1} dt along both homoclinic orbits R7 of "
                        "solution I at c = sqrt(2 b h) (g0: phi at the orbit's centre), fitted as "
                        "J = A sin g0 + B cos g0 per unit mu, compared with ur24 as printed and with the "
                        "corrected closed form. --splitting adds the splitting measured on the section "
                        "phi = pi against mu J(g0). Needs lam > 0, a1 > a2, chi = zeta = 0, "
                        "lam b/a1 < c < lam b/a2.")
    mk.add_argument("--h", type=float, default=model.FIGURE4_H, help="energy level h = c^2/(2b) [%(default)s]")
    mk.add_argument("--splitting", action="store_true",
                    help="also measure the splitting on the section for mu in --mus at phase --g0")
    mk.add_argument("--mus", default="1e-4,3e-4,1e-3,3e-3", help="mu values of --splitting [%(default)s]")
    mk.add_argument("--g0", type=float, default=0.5 * math.pi, help="phase g0 of --splitting [pi/2]")
    _add_model_args(mk, model.FIGURE4, json="print JSON")
    # ---- end melnikov -------------------------------------------------------------------------
    # ---- trajectory: the body in the plane, full system R1 (explorer/trajectory.py) ----------
    tj = sub.add_parser("trajectory", help="the body in the plane (full system R1, any lam): drift, band, "
                        "falling body",
                        description="Integrate the full system R1 (p1, p2, M, phi, x, y) with adaptive DOP853, "
                        "check H and the momentum integrals R2, print the measured mean horizontal velocity "
                        "against +mu/lam and the band in y (lam != 0) or, for lam = 0 (the falling body), "
                        "the fitted exponents of the amplitude (Kozlov: -1/2) and frequency (Kozlov: 1) of "
                        "the oscillation of phi; draw the path with the body's orientation (PNG and PDF).")
    tj.add_argument("--p1", type=float, default=0.5, help="initial p1 [%(default)s]")
    tj.add_argument("--p2", type=float, default=0.0, help="initial p2 [%(default)s]")
    tj.add_argument("--M", type=float, default=2.0, help="initial M [%(default)s]")
    tj.add_argument("--phi", type=float, default=0.0, help="initial angle phi [%(default)s]")
    tj.add_argument("--time", "-T", type=float, default=300.0, help="integration time T [%(default)s]")
    tj.add_argument("--samples", type=int, default=20001, help="samples on [0, T] [%(default)s]")
    tj.add_argument("--tol", type=float, default=TRAJECTORY_TOL, help="DOP853 tolerance (rtol = atol) [%(default)s]")
    tj.add_argument("--glyphs", type=int, default=40, help="orientation glyphs along the path [%(default)s]")
    tj.add_argument("--out", default="figures/trajectory",
                    help="figure path without extension (lam = 0 adds <out>_kozlov) [%(default)s]")
    tj.add_argument("--no-figure", action="store_true", help="do not draw the figure")
    tj.add_argument("--json", action="store_true", help="print JSON")
    tjg = tj.add_argument_group("model parameters (docs/model.md; defaults: Figure 4 with mu = 0.5)")
    for name, help_ in (("a1", "added mass along axis 1 (> 0)"), ("a2", "added mass along axis 2 (> 0)"),
                        ("b", "added moment of inertia (> 0)"),
                        ("lam", "circulation x density (any; 0 = falling body)"),
                        ("chi", "asymmetry term chi"), ("zeta", "asymmetry term zeta"),
                        ("mu", "weight (>= 0)"), ("xi", "centre of mass xi"), ("eta", "centre of mass eta")):
        tjg.add_argument(f"--{name}", type=float, default=model.FIGURE4.with_(mu=0.5).as_dict()[name],
                         help=f"{help_} [%(default)s]")
    # ---- end trajectory -----------------------------------------------------------------------
    # ---- figures: every figure of the seed paper (explorer/app/paper/) -------------------------
    from explorer.app.paper.registry import FIGURES

    fg = sub.add_parser("figures", help="regenerate every figure of the paper (PNG and PDF)",
                        description="Regenerate the figures of the seed paper into --out-dir (PNG and PDF): "
                        f"{', '.join(FIGURES)}. Sweeps reuse results/<scene>.h5 when complete with "
                        "the same scene hash; --quick uses reduced settings where a store is incomplete.")
    fg.add_argument("--only", default=None, metavar="NAME", help="only this figure (one name)")
    fg.add_argument("--out-dir", default="figures", help="where the figures go [%(default)s]")
    fg.add_argument("--results-dir", default="results", help="HDF5 stores of the sweeps [%(default)s]")
    fg.add_argument("--quick", action="store_true",
                    help="reduced settings (sweeps whose store is incomplete, continuation step, curves)")
    fg.add_argument("--benchmark", default=None,
                    help="W4 results JSON for work_precision [benchmarks/results_w4.json]")
    fg.add_argument("--quiet", action="store_true", help="no progress bar")
    # ---- end figures ----------------------------------------------------------------------------
    _add_manifold_parser(sub)
    for name, cmd in sub.choices.items():
        cmd.epilog = f"example:\n  {EXAMPLES[name]}"
    return parser


def _direction(text: str) -> int:
    table = {"+": 1, "+1": 1, "1": 1, "up": 1, "-": -1, "-1": -1, "down": -1, "both": 0, "0": 0}
    if text not in table:
        raise model.ParameterError(f"direction must be one of +, -, both; got {text!r}")
    return table[text]


def cmd_orbit(args) -> int:
    from explorer.analysis.sections import DEFAULT_BLOCK, METHODS, energy_warning

    params = _params_from(args)
    if args.method not in METHODS:
        raise model.ParameterError(f"method must be one of {', '.join(METHODS)}; got {args.method!r}")
    for name in ("p1", "p2", "h", "phi0"):
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


def cmd_sweep(args) -> int:
    from explorer.app.runner import format_report, run_sweep

    if args.jobs < 1:  # the API says "jobs"; the command line names its option
        raise model.ParameterError(f"--jobs must be >= 1, got {args.jobs}")
    validation.integer("--jobs", args.jobs, 1, validation.MAX_JOBS)
    if args.scheduler is not None and args.backend != "dask":
        raise model.ParameterError("--scheduler needs --backend dask")
    if args.scheduler is not None and not args.scheduler.strip():
        raise model.ParameterError("--scheduler must be a dask scheduler address (host:port), got ''")
    for option, path in (("--out", args.out), ("--figure", args.figure)):
        if path is not None:
            validation.output_path(option, path)
    report = run_sweep(args.scene, args.out, figure=args.figure, draw=not args.no_figure, jobs=args.jobs,
                       backend=args.backend, scheduler=args.scheduler, force=args.force,
                       progress=not args.quiet)
    print(format_report(report))
    return 0


def cmd_lyapunov(args) -> int:
    from explorer.analysis import lyapunov
    from explorer.analysis.sections import METHODS

    params = _params_from(args)
    if args.method not in METHODS:
        raise model.ParameterError(f"method must be one of {', '.join(METHODS)}; got {args.method!r}")
    for name in ("p1", "p2", "h"):
        if not math.isfinite(getattr(args, name)):
            raise model.ParameterError(f"{name} must be finite, got {getattr(args, name)!r}")
    y0 = model.section_state(params, [args.p1], [args.p2], args.h)
    # SALI and GALI_2 (a second deviation vector) with the Taylor method's tangent lanes
    which = lyapunov.INDICATOR_NAMES if args.method == "taylor" else lyapunov.DEFAULT_INDICATORS
    r = lyapunov.indicators(params, y0, args.time, method=args.method, tol=args.tol, dt=args.dt,
                            history=args.history, which=which)
    hist = [[float(v) for v in row[:3]] + [float(row[4])] for row in r.history[0] if np.isfinite(row[0])]
    reached = float(r.time[0])
    status = r.status_name(0)

    def estimate(v):      # an orbit stopped at t = 0 has no estimate (null, never a made-up 0)
        return float(v) if reached > 0 and math.isfinite(float(v)) else None

    out = {"params": params.as_dict(), "h": args.h, "p1": args.p1, "p2": args.p2, "method": args.method,
           "settings": r.settings, "status": status, "time": reached,
           "mlce": estimate(r.mlce[0]), "megno": estimate(r.megno[0]), "fli": estimate(r.fli[0]),
           "sali": estimate(r.sali[0]), "gali2": estimate(r.gali2[0]),
           "regular_bound": lyapunov.regular_bound(reached) if reached > 1 else None,
           "history": hist}
    if status != "done":
        cover = f"the estimates cover [0, {reached:g}]" if reached > 0 else "no estimate"
        print(f"explorer: the orbit stopped at t = {reached:g} of {args.time:g} ({status}); {cover}",
              file=sys.stderr)
    if args.json:
        print(json.dumps(out))
    else:
        print(f"time {out['time']!r}\nmlce {out['mlce']!r}\nmegno {out['megno']!r}\nfli {out['fli']!r}\n"
              f"sali {out['sali']!r}\ngali2 {out['gali2']!r}\nstatus {out['status']}")
        if hist:
            print("history: t, mlce, megno, fli")
            for row in hist:
                print(",".join(repr(v) for v in row))
    return 0


def _pair(text, name):
    try:
        a, b = (float(v) for v in text.split(","))
    except ValueError:
        raise model.ParameterError(f"{name} must be two numbers p1,p2 (e.g. 0.1,-0.2), got {text!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise model.ParameterError(f"{name} must be finite, got {text!r}")
    return a, b


def _continuation(cont):
    """PARAM, START, STOP, STEP of --continue: numbers, STEP towards STOP, a bounded number of steps."""
    name, *nums = cont
    validation.choice("--continue PARAM", name, model.PARAM_NAMES + ("h",))
    try:
        start, stop, step = (float(v) for v in nums)
    except ValueError:
        raise model.ParameterError(f"--continue needs PARAM START STOP STEP numbers, got {nums}") from None
    return (name, *validation.continuation_steps("--continue", start, stop, step))


def _print_bifurcations(br, name) -> None:
    """The stability changes and touches of a continued branch (fixed point or periodic orbit:
    one detector, one report)."""
    print("stability changes: " + (", ".join(f"{b['type']} at {name} = {b['value']:.10g}"
                                             for b in br.bifurcations) or "none in range"))
    if br.stopped:
        print(f"branch stopped: {br.stopped}")


def cmd_fixedpoint(args) -> int:
    from explorer.analysis import fixedpoints

    params = _params_from(args)
    if not math.isfinite(args.h):
        raise model.ParameterError(f"h must be finite, got {args.h!r}")
    guess = _pair(args.guess, "--guess")
    if args.cont:
        name, start, stop, step = _continuation(args.cont)
        br = fixedpoints.continue_branch(params, args.h, name, start, stop, step, guess, tol=args.tol)
        rows = [dict(fp.as_dict(), **{name: float(v)}) for v, fp in zip(br.values, br.points)]
        if args.json:
            print(json.dumps({"parameter": name, "branch": rows, "bifurcations": br.bifurcations,
                              "stopped": br.stopped}))
        else:
            print(f"{name},p1,p2,trace,stable")
            for r in rows:
                print(f"{r[name]:.10g},{r['p1']!r},{r['p2']!r},{r['trace']!r},{r['stable']}")
            _print_bifurcations(br, name)
        return 0
    fp = fixedpoints.find_fixed_point(params, args.h, guess, tol=args.tol)
    out = dict(fp.as_dict(), params=params.as_dict(), h=args.h)
    if args.json:
        print(json.dumps(out))
    else:
        for k in ("p1", "p2", "trace", "det", "eigenvalues", "stable", "return_time"):
            print(f"{k} {out[k]!r}")
    return 0


# ---- periodic, rotation --------------------------------------------------------------------
def _orbit_line(o) -> str:
    pts = " ".join(f"({p[0]:.10g},{p[1]:.10g})" for p in o.points)
    return (f"K={o.period} {o.kind} trace={o.trace:.10g} residue={o.residue:.6g} "
            f"symmetric={o.symmetric}{' degenerate' if o.degenerate else ''} points={pts}")


def _section_map_args(args):
    """The model parameters of a command on the section map (periodic, rotation), with its energy
    ``--h`` (finite, a non-empty allowed region) and Taylor ``--tol`` checked."""
    from explorer.analysis.sections import MAX_TOL, MIN_TOL

    params = _params_from(args)
    if not math.isfinite(args.h):
        raise model.ParameterError(f"h must be finite, got {args.h!r}")
    validation.real("tol", args.tol, MIN_TOL, MAX_TOL)
    if model.allowed_ellipse(params, args.h) is None:
        raise model.ParameterError(f"the region is empty at h = {args.h:g}; raise --h")
    return params


def cmd_periodic(args) -> int:
    from explorer.analysis import periodic

    if args.period < 1:
        raise model.ParameterError(f"--period must be an integer K >= 1, got {args.period}")
    validation.integer("--period", args.period, 1, validation.MAX_PERIOD)
    # --grid and --max-guesses are checked with or without --search (a bad value is a mistake either way)
    validation.fits_in_memory("--grid", args.grid, 16 * args.grid, "grid^2 points of 16 bytes", lo=2)
    validation.integer("--max-guesses", args.max_guesses, 1)
    params = _section_map_args(args)
    K = args.period
    if args.cont:
        if args.guess is None:
            raise model.ParameterError("--continue needs --guess (a point of the orbit at START)")
        name, start, stop, step = _continuation(args.cont)
        guess = _pair(args.guess, "--guess")
        br = periodic.continue_periodic(params, args.h, K, name, start, stop, step, guess, tol=args.tol)
        rows = [dict(o.as_dict(), **{name: float(v)}) for v, o in zip(br.values, br.orbits)]
        if args.json:
            print(json.dumps({"period": K, "parameter": name, "branch": rows, "bifurcations": br.bifurcations,
                              "stopped": br.stopped}))
        else:
            print(f"{name},p1,p2,trace,residue,stable")
            for r in rows:
                print(f"{r[name]:.10g},{r['points'][0][0]!r},{r['points'][0][1]!r},{r['trace']!r},{r['residue']!r},"
                      f"{r['stable']}")
            _print_bifurcations(br, name)
        return 0
    if args.search:
        orbits = periodic.search_periodic_orbits(params, args.h, K, grid=args.grid, max_guesses=args.max_guesses,
                                                 tol=args.tol)
    else:
        guess = _pair(args.guess, "--guess")
        orbits = [periodic.find_periodic_orbit(params, args.h, guess, K, tol=args.tol)]
    if args.json:
        print(json.dumps({"period": K, "params": params.as_dict(), "h": args.h,
                          "orbits": [o.as_dict() for o in orbits]}))
    else:
        if args.search:
            print(f"{len(orbits)} orbit(s) of minimal period {K}")
        for o in orbits:
            print(_orbit_line(o))
    return 0


def cmd_rotation(args) -> int:
    from explorer.analysis import rotation

    a, b = _pair(args.start, "--from"), _pair(args.stop, "--to")
    if args.n < 2:
        raise model.ParameterError(f"--n must be an integer >= 2, got {args.n}")
    if args.iterates < 10:
        raise model.ParameterError(f"--iterates must be an integer >= 10, got {args.iterates}")
    from explorer.analysis.fixedpoints import find_fixed_point

    # each point keeps its 2N returns (p1, p2: 16 bytes each)
    validation.fits_in_memory("--n", args.n, 32 * args.iterates, "2 x --iterates returns of 16 bytes per point", lo=2)
    params = _section_map_args(args)
    c_guess = _pair(args.center, "--center") if args.center is not None else a
    for name, x in (("--from", a), ("--to", b), ("--center", c_guess)):
        if not model.is_admissible(params, x[0], x[1], args.h):
            raise model.ParameterError(f"{name} ({x[0]:g}, {x[1]:g}) lies outside the allowed region; allowed: "
                                       f"{model.describe_region(params, args.h)}")
    center = find_fixed_point(params, args.h, c_guess, tol=args.tol)
    prof = rotation.rotation_profile(params, args.h, a, b, args.n, center=center.point, iterates=args.iterates,
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


# ---- end periodic, rotation ----------------------------------------------------------------
# ---- melnikov: Melnikov integral ur23/ur24 (explorer/melnikov.py) --------------------------
def cmd_melnikov(args) -> int:
    from explorer.analysis import melnikov

    params = _params_from(args)
    # --mus and --g0 are checked with or without --splitting (a bad value is a mistake either way)
    try:
        mus = [float(v) for v in args.mus.split(",")]
    except ValueError:
        raise model.ParameterError(f"--mus must be comma-separated numbers, got {args.mus!r}") from None
    if not mus or not all(math.isfinite(m) and m > 0 for m in mus):
        raise model.ParameterError(f"--mus must be finite and > 0, got {args.mus!r}")
    if not math.isfinite(args.g0):
        raise model.ParameterError(f"g0 must be finite, got {args.g0!r}")
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


# ---- end melnikov ---------------------------------------------------------------------------
# ---- trajectory: the body in the plane, full system R1 (explorer/trajectory.py) ------------
def cmd_trajectory(args) -> int:
    from explorer.analysis import trajectory as tr
    from explorer.app import trajectory_figure

    # R1 allows lam = 0: full_params validates the rest with model.Params (lam replaced by 1)
    prm = tr.full_params({n: getattr(args, n) for n in model.PARAM_NAMES})
    y0 = tr.initial_state(prm, args.p1, args.p2, args.M, args.phi)
    if args.glyphs < 1:
        raise model.ParameterError(f"glyphs must be >= 1, got {args.glyphs!r}")
    if not args.no_figure:
        validation.output_path("--out", args.out)
    res = tr.trajectory(prm, y0, args.time, args.samples, args.tol, phi_start=args.phi)
    cons = tr.conservation(res)
    d = k = None
    if prm["lam"] != 0.0:
        d = tr.drift(prm, y0, args.time, result=res)
    elif prm["mu"] > 0.0 and prm["a1"] != prm["a2"]:
        k = tr.kozlov(prm, y0, args.time, result=res)
    out = {"params": prm, "initial": {"p1": args.p1, "p2": args.p2, "M": args.M, "phi": args.phi},
           "time": args.time, "samples": args.samples, "tol": args.tol, "status": res.status,
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
    print(f"status {res.status}  (T {args.time:g}, {res.steps} steps, tol {args.tol:g})")
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


# ---- end trajectory -------------------------------------------------------------------------
# ---- figures: every figure of the seed paper (explorer/app/paper/) -------------------------
def cmd_figures(args) -> int:
    from explorer.app import paper

    if args.only is not None:
        paper.registry.module(args.only)  # an unknown name: ParameterError listing the names
    validation.output_path("--out-dir", args.out_dir, directory=True)
    validation.output_path("--results-dir", args.results_dir, directory=True)
    if args.benchmark is not None:
        validation.input_file("--benchmark", args.benchmark)
    names = [args.only] if args.only else None
    outcomes = paper.generate(names, out_dir=args.out_dir, results_dir=args.results_dir, quick=args.quick,
                              benchmark=args.benchmark, quiet=args.quiet)
    for o in outcomes:
        print(o.line())
    return 1 if any(o.status == "failed" for o in outcomes) else 0


# ---- end figures ----------------------------------------------------------------------------
COMMANDS = {"figures": cmd_figures, "trajectory": cmd_trajectory, "orbit": cmd_orbit,
            "sweep": cmd_sweep, "lyapunov": cmd_lyapunov, "fixedpoint": cmd_fixedpoint,
            "melnikov": cmd_melnikov, "periodic": cmd_periodic, "rotation": cmd_rotation}


# ---- explore: interactive explorer (explorer/explore.py) -----------------------------------
def cmd_explore(args) -> int:
    from explorer.app import explore

    explore.check_args(args)  # bad input is reported as such, with or without a display
    problem = explore.display_problem()  # no display: one line, exit 2 (no traceback)
    if problem:
        raise model.ParameterError(problem)
    explore.from_args(args).run()
    return 0


COMMANDS["explore"] = cmd_explore


def cmd_serve(args) -> int:
    from explorer.app.serve.command import cmd_serve as serve

    return serve(args)


COMMANDS["serve"] = cmd_serve
# ---- end explore ----------------------------------------------------------------------------


# ---- manifold: invariant manifolds, homoclinic points, lobes (analysis/manifolds.py, transport.py)
def _add_manifold_parser(sub):
    mf = sub.add_parser("manifold", help="stable and unstable manifolds of a hyperbolic orbit, homoclinic "
                        "points, lobes and flux",
                        description="Finds the periodic orbit of period --period from --guess (default: the "
                        "central hyperbolic fixed point), grows both branches of W^u and W^s at its point "
                        "--index to --arclength (adaptive insertion), locates their intersections (Newton, "
                        "1e-10) and the turnstile's lobes (Green's theorem); docs/manifolds.md.")
    mf.add_argument("--guess", default="0,0", help="start of Newton's method for the orbit: p1,p2 [0,0]")
    mf.add_argument("--period", type=int, default=1, help="period K of the orbit [%(default)s]")
    mf.add_argument("--index", type=int, default=0, help="which point of the orbit [%(default)s]")
    mf.add_argument("--arclength", type=float, default=6.0, help="length of each branch [%(default)s]")
    mf.add_argument("--max-points", type=int, default=20000, help="points per branch at most [%(default)s]")
    mf.add_argument("--max-time", type=float, default=None, help="seconds per branch at most [none]")
    mf.add_argument("--h", type=float, default=model.FIGURE4_H, help="energy level [%(default)s]")
    mf.add_argument("--tol", type=float, default=MAP_TOL, help="Taylor tolerance of the section map [%(default)s]")
    _add_model_args(mf, model.FIGURE4, json="print JSON {orbit, branches, homoclinic_points, lobes, flux}")


def cmd_manifold(args) -> int:
    from explorer.analysis import manifolds, periodic, transport

    params = _section_map_args(args)
    if args.period < 1:
        raise model.ParameterError(f"--period must be an integer K >= 1, got {args.period}")
    validation.integer("--period", args.period, 1, validation.MAX_PERIOD)
    # four branches of at most --max-points points (p1, p2 and their parameter: about 64 bytes each)
    validation.fits_in_memory("--max-points", args.max_points, 4 * 64, "4 branches of 64 bytes per point", lo=1)
    if args.max_time is not None:
        validation.real("--max-time", args.max_time, 0.0, lo_open=True)
    orb = periodic.find_periodic_orbit(params, args.h, _pair(args.guess, "--guess"), args.period, tol=args.tol)
    sd = manifolds.saddle(orb, index=args.index, tol=args.tol)
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
    ev = [complex(e) for e in orb.eigenvalues]
    out = {"orbit": {"points": orb.points.tolist(), "period": int(orb.period),
                     "eigenvalues": [[e.real, e.imag] if e.imag else e.real for e in ev]},
           "branches": [{"kind": b.kind, "sign": b.sign, "points": b.points.tolist(), "arclength": b.arclength,
                         "status": b.status} for b in branches],
           "homoclinic_points": hps, "lobes": [{"area": abs(lb.area), "error": lb.error} for lb in lobes],
           "flux": flux}
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"orbit K={orb.period} point=({sd.point[0]:.10g},{sd.point[1]:.10g}) multiplier={sd.multiplier:.10g}")
    for b in branches:
        print(f"{b.kind} {b.sign:+d}: {len(b.points)} points, arclength {b.arclength:.6g} ({b.status})")
    print(f"{len(hps)} homoclinic point(s)")
    for lb in lobes:
        print(f"lobe area {abs(lb.area):.10g} +- {lb.error:.2g}")
    print(f"flux per iteration {flux!r}")
    return 0


COMMANDS["manifold"] = cmd_manifold
# ---- end manifold ---------------------------------------------------------------------------


def main(argv=None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help()
            return EXIT_USAGE
        return COMMANDS[args.command](args)
    except (UsageError, model.ParameterError) as exc:
        msg = " ".join(str(exc).split())
        print(f"explorer: error: {msg}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt as exc:   # a sweep says what it kept (explorer.app.interrupt.Interrupted)
        print("explorer: interrupted" + (f": {exc}" if str(exc) else ""), file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
