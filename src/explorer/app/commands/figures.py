"""regenerate every figure of the paper (PNG and PDF)

Regenerate the figures of the seed paper into --out-dir (PNG and PDF): {figures}. Sweeps reuse
results/<scene>.h5 when complete with the same scene hash; --quick uses reduced settings where a
store is incomplete.
"""
from __future__ import annotations

from explorer.app.commands.options import Command, opt
from explorer.app.paper.registry import FIGURES
from explorer.model import validation

COMMAND = Command("figures", __doc__, "--only figure4 --quick", (
    opt("--only", default=None, metavar="NAME", help="only this figure (one name)"),
    opt("--out-dir", default="figures", help="where the figures go [%(default)s]"),
    opt("--results-dir", default="results", help="HDF5 stores of the sweeps [%(default)s]"),
    opt("--quick", action="store_true", help="reduced settings (sweeps whose store is incomplete, continuation step, "
        "curves)"),
    opt("--benchmark", default=None, help="W4 results JSON for work_precision [benchmarks/results_w4.json]"),
    opt("--quiet", action="store_true", help="no progress bar"),
), fields={"figures": ", ".join(FIGURES)})


def run(args) -> int:
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
