"""The registry of the paper's figures, name -> module, in the order ``explorer figures`` makes
them: the one list of figures."""
from __future__ import annotations

import importlib
import os
import sys
import traceback

from explorer.app.paper._common import FigureUnavailable, Outcome
from explorer.model import ParameterError

#: figure name -> module of this package, in the order they are generated
MODULES = {
    "figure2": "explorer.app.paper.figure2",
    "figure3": "explorer.app.paper.figure3",
    "figure4": "explorer.app.paper.figure4",
    "chaotic_fraction": "explorer.app.paper.chaotic_fraction",
    "chaos_map": "explorer.app.paper.chaos_map",
    "fraction_curve": "explorer.app.paper.fraction_curve",
    "megno_map": "explorer.app.paper.megno_map",
    "atlas": "explorer.app.paper.atlas",
    "continuation": "explorer.app.paper.continuation",
    "periodic": "explorer.app.paper.periodic",
    "work_precision": "explorer.app.paper.work_precision",
    "homoclinic": "explorer.app.paper.homoclinic",
    "melnikov": "explorer.app.paper.melnikov",
    "tangle": "explorer.app.paper.tangle",
    "trajectory": "explorer.app.paper.trajectory",
    "breakup": "explorer.app.paper.breakup",
}
#: every figure, in the order they are generated
FIGURES = tuple(MODULES)
#: figures computed from stored sweeps (reduced under ``quick`` when their store is incomplete)
SWEEP_FIGURES = {"figure4": "figure4", "chaotic_fraction": "fraction", "chaos_map": "chaos",
                 "fraction_curve": "fraction_curve", "megno_map": "megno_map", "atlas": "atlas"}


def module(name):
    """The module of figure ``name`` (ParameterError naming the known figures otherwise)."""
    if name not in MODULES:
        raise ParameterError(f"unknown figure {name!r}; names: {', '.join(FIGURES)}")
    return importlib.import_module(MODULES[name])


def make(name, *, out_dir="figures", results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    """Generate one figure; raises on error (FigureUnavailable for a missing input)."""
    return module(name).build(out_dir, results_dir=results_dir, quick=quick, benchmark=benchmark, quiet=quiet)


def generate(names=None, *, out_dir="figures", results_dir="results", quick=False, benchmark=None,
             quiet=False, raise_errors=False):
    """Every figure of :data:`FIGURES` (or ``names``) into ``out_dir``, with a tqdm progress bar
    over the figures on stderr.  A missing input gives status "not available"; an error gives
    "failed" (or is raised with ``raise_errors``).  Returns the list of :class:`Outcome`."""
    names = list(FIGURES) if names is None else list(names)
    for n in names:
        module(n)
    from tqdm import tqdm

    outcomes = []
    bar = tqdm(names, desc="figures", unit="figure", file=sys.stderr, disable=True if quiet else None)
    for name in bar:
        bar.set_postfix_str(name)
        try:
            o = make(name, out_dir=out_dir, results_dir=results_dir, quick=quick, benchmark=benchmark, quiet=quiet)
        except FigureUnavailable as exc:
            o = Outcome(name, "not available", message=str(exc))
        except Exception as exc:  # noqa: BLE001 - reported per figure, the others still run
            if raise_errors:
                raise
            msg = " ".join(str(exc).split()) or type(exc).__name__
            if os.environ.get("EXPLORER_DEBUG"):
                traceback.print_exc()
            o = Outcome(name, "failed", message=f"{type(exc).__name__}: {msg}")
        outcomes.append(o)
    bar.close()
    return outcomes
