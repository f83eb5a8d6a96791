"""Poincaré sections of every panel of a scene (default: figure4)

Run every panel of a scene (a TOML file or a built-in preset), store all crossings in one HDF5
file and draw the figure. Panels already stored with the same settings are skipped; a killed run
resumes where it stopped.
"""
from __future__ import annotations

from explorer import model
from explorer.app.commands.options import Command, opt
from explorer.model import validation

COMMAND = Command("sweep", __doc__, "figure4 --out results/figure4.h5 --jobs 2", (
    opt("scene", nargs="?", default="figure4", help="scene file (.toml) or preset name [figure4]"),
    opt("--system", default=None,
        help="module:attribute of an explorer System (imported from the current directory or sys.path): gives or "
             "replaces the scene's system (docs/scenes.md)"),
    opt("--out", default=None, help="HDF5 file [results/<scene>.h5]"),
    opt("--figure", default=None, help="figure path without extension [the --out path without .h5: beside the store]"),
    opt("--no-figure", action="store_true", help="do not draw the figure"),
    opt("--jobs", type=int, default=1,
        help="joblib worker processes (1: this process with Numba threads over orbits) [1]"),
    opt("--backend", default=None, choices=["loky", "multiprocessing", "dask"],
        help="joblib backend for --jobs > 1 (dask: run on a dask.distributed cluster)"),
    opt("--scheduler", default=None,
        help="dask scheduler address (with --backend dask; default: a local cluster of --jobs workers)"),
    opt("--force", action="store_true", help="recompute every panel"),
    opt("--quiet", action="store_true", help="no progress bar"),
))


def run(args) -> int:
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
    scene = args.scene
    if args.system is not None:
        from explorer.io.scene import load_scene

        scene = load_scene(args.scene, system=args.system)
    report = run_sweep(scene, args.out, figure=args.figure, draw=not args.no_figure, jobs=args.jobs,
                       backend=args.backend, scheduler=args.scheduler, force=args.force,
                       progress=not args.quiet)
    print(format_report(report))
    return 0
