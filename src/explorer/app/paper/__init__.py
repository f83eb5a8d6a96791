"""The figures of the seed paper, regenerated: ``python -m explorer figures`` (docs/commands/figures.md).

Each figure is one module of this package with ``NAME``, ``DESCRIPTION`` and ``build(out_dir,
...)``, which returns a :class:`Drawn` (the figure and the numbers it shows);
:mod:`explorer.app.paper.registry` lists them in the order they are generated.  The admissible
region of Figure 3 is derived in docs/errata.md.
"""
from __future__ import annotations

import importlib

#: public name -> submodule that defines it (imported on first use, so that reading the
#: registry, e.g. for ``explorer figures --help``, does not import every figure)
_EXPORTS = {
    "CHAPLYGIN": "_common",
    "DENSE_TOL": "_common",
    "FIGURE2_ENERGIES": "_common",
    "Drawn": "_common",
    "FigureUnavailable": "_common",
    "Outcome": "_common",
    "advance": "_dense",
    "closed_curves": "_dense",
    "dense_orbits": "_dense",
    "meridian_points": "_dense",
    "QUICK_SCENES": "_sweeps",
    "ensure_sweep": "_sweeps",
    "store_complete": "_sweeps",
    "chaos_map_figure": "chaos_map",
    "chaotic_fraction_figure": "chaotic_fraction",
    "CheckError": "chaplygin",
    "admissible_hmin": "chaplygin",
    "branch_exists": "chaplygin",
    "branch_h": "chaplygin",
    "branch_stable": "chaplygin",
    "chaplygin_F": "chaplygin",
    "chaplygin_H": "chaplygin",
    "check_chaplygin": "chaplygin",
    "critical_c": "chaplygin",
    "critical_h": "chaplygin",
    "figure3_check": "chaplygin",
    "r6_jacobian": "chaplygin",
    "r6_rhs": "chaplygin",
    "relative_equilibrium": "chaplygin",
    "continuation_figure": "continuation",
    "periodic_figure": "periodic",
    "_figure2_levels": "figure2",
    "figure2_figure": "figure2",
    "figure3_figure": "figure3",
    "figure4_figure": "figure4",
    "homoclinic_figure": "homoclinic",
    "melnikov_figure": "melnikov",
    "FIGURES": "registry",
    "SWEEP_FIGURES": "registry",
    "generate": "registry",
    "make": "registry",
    "trajectory_figure": "trajectory",
    "find_benchmark": "work_precision",
    "work_precision_figure": "work_precision",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'explorer.app.paper' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"explorer.app.paper.{module}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
