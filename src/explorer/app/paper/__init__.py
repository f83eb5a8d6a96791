"""The figures of the seed paper, regenerated: ``python -m explorer figures``.

Borisov & Mamaev, *On the motion of a heavy rigid body in an ideal fluid with circulation*
(the seed paper), with the equations of ``docs/model.md`` (labels R1-R11).  Each figure is
one module of this package with ``NAME``, ``DESCRIPTION`` and ``build(out_dir, ...)``; its
builder returns a :class:`Drawn` (the matplotlib figure and the numbers it shows, so that tests
can check what was drawn). :mod:`explorer.app.paper.registry` lists the modules in the order
they are generated; ``explorer figures`` and :func:`generate` read it and write
``<out_dir>/<name>.png`` and ``.pdf`` (:func:`explorer.app.figures.save_figure`).
Adding a figure: a module with those three names and one line in the registry.

=====================  ==========================================================================
name                   what
=====================  ==========================================================================
``figure2``            Chaplygin's case (R6): closed curves {H = h} n {F = c} in (p1, p2, M),
                       integrated with the project's Taylor integrator, one panel per energy
                       interval of the seed (below, inside, above the unstable band of I)
``figure3``            the bifurcation diagram in the (c, h) plane, admissible region in gray,
                       unstable branches dashed, checked numerically (:func:`figure3_check`)
``figure4``            the sweep of the scene preset ``figure4`` (sections + separatrices)
``chaotic_fraction``   the chaotic fraction against mu (scene preset ``fraction``)
``chaos_map``          MEGNO maps of the Figure-4 panels (scene preset ``chaos``)
``continuation``       the central fixed point of the section map continued in mu (0..8)
``periodic``           Figure 4 at mu = 0.03 with the periodic orbits of periods 1..8 marked and
                       the rotation-number profile from the elliptic fixed point
``work_precision``     one-step error against throughput, ``benchmarks/results_w4.json``
``homoclinic``         R7 against the integrated flow, with its crossings of phi = pi
``melnikov``           :func:`explorer.app.melnikov_figure.melnikov_figure`
``trajectory``         :func:`explorer.app.trajectory_figure.path_figure`
=====================  ==========================================================================

Sweeps (``figure4``, ``chaotic_fraction``, ``chaos_map``) go through
:func:`explorer.app.runner.run_sweep`, which reuses ``<results_dir>/<scene>.h5`` when its panels
are stored with the same settings hash and computes only what is missing.  With ``quick``
a scene whose store is not complete is replaced by a reduced copy (fewer seeds, crossings,
shorter MEGNO time) named ``<scene>-quick`` with its own store; the figure says so.

The admissible region of Figure 3 (derivation, also in ``docs/errata.md``)
-----------------------------------------------------------------------------
For mu = chi = zeta = 0, lam > 0, a1 > a2: on {F = c}, M = c - (u + v)/(2 lam) with
u = p1^2, v = p2^2 >= 0, and

    H = 1/2 (u/a1 + v/a2 + (c - (u + v)/(2 lam))^2 / b)

is a convex quadratic in (u, v) with dH/du = (1/a1 - M/(lam b))/2, dH/dv = (1/a2 - M/(lam b))/2.
Its minimum over u, v >= 0 (KKT): if c <= lam b/a1, at u = v = 0 (solution I,
h = c^2/(2b)); otherwise at v = 0, M = lam b/a1 (solution II, h = lam c/a1 - lam^2 b/(2 a1^2)).
H is unbounded above on {F = c} (|p| -> infinity), so the set of (c, h) of real motions is

    h >= h_min(c) = c^2/(2b)                        for c <= lam b/a1,
                    lam c/a1 - lam^2 b/(2 a1^2)     for c >= lam b/a1,

the parabola of I continued by its tangent, the line of II (C^1 at the tangency point).
The line of III (c > lam b/a2) and the arc of I with c > lam b/a1 lie inside the region.
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
