"""explorer: Poincaré sections and chaos for Chaplygin's equations of a heavy
rigid body moving in an ideal fluid with circulation (Borisov & Mamaev).

The public Python API is the names in ``__all__``; each is loaded on first use
(``import explorer`` itself imports neither Numba, matplotlib nor h5py)::

    import explorer as ex

    prm = ex.FIGURE4.with_(mu=0.5)                        # docs/model.md R9: the scene of Figure 4
    smap = ex.SectionMap(prm, ex.FIGURE4_H)              # the system, given first
    res = ex.crossings(smap, [(0.1, 0.0), (0.3, 0.0)], n_crossings=1000)
    fp = ex.find_fixed_point(smap, (-0.2, 0.0))
    ind = ex.indicators(smap, [(0.1, 0.0)], tmax=1000.0)

The layers below (``explorer.kernels`` <- ``model`` <- ``integrate`` <- ``analysis``
<- ``io`` <- ``app``) are importable for more; see the documentation's architecture
page.  docs/model.md (R1-R11) gives the equations every module cites.
"""
from __future__ import annotations

import importlib

__version__ = "0.1.0"

#: public name -> module that defines it (loaded lazily by :func:`__getattr__`)
_EXPORTS = {
    # parameters, presets and the physics of docs/model.md (numpy only)
    "Params": "explorer.model",
    "ParameterError": "explorer.model",
    "FIGURE4": "explorer.model",
    "FIGURE4_H": "explorer.model",
    "PARAM_NAMES": "explorer.model",
    "energy": "explorer.model",
    "casimir": "explorer.model",
    "allowed_ellipse": "explorer.model",
    "section_state": "explorer.model",
    # a system from its equations (docs/systems.md)
    "System": "explorer.model.system",
    "classic": "explorer.model",            # the module explorer.model.classic (docs/classic.md)
    # crossings of the section
    "METHODS": "explorer.analysis.sections",
    "Crossings": "explorer.analysis.sections",
    "crossings": "explorer.analysis.sections",
    "flow": "explorer.analysis.system_flow",      # a System's orbits at given times
    "iter_crossings": "explorer.analysis.sections",
    "propagate": "explorer.analysis.sections",
    "CrossingBlock": "explorer.analysis.sections",
    "StreamState": "explorer.analysis.sections",
    "Status": "explorer.kernels",
    # chaos indicators
    "Indicators": "explorer.analysis.lyapunov",
    "indicators": "explorer.analysis.lyapunov",
    "chaotic_fraction": "explorer.analysis.lyapunov",
    "chaos_map": "explorer.analysis.chaos_map",          # an adaptive chaos map (docs/chaos_map.md)
    "ChaosMap": "explorer.analysis.chaos_map",
    # the section map and its fixed points
    "SectionMap": "explorer.analysis.section_map",
    "StandardMap": "explorer.analysis.maps",
    "AreaPreservingMap": "explorer.analysis.maps",
    "greene": "explorer.analysis.greene",
    "GreeneResult": "explorer.analysis.greene",
    "FixedPoint": "explorer.analysis.fixedpoints",
    "Branch": "explorer.analysis.fixedpoints",
    "find_fixed_point": "explorer.analysis.fixedpoints",
    "continue_branch": "explorer.analysis.fixedpoints",
    "separatrices": "explorer.analysis.fixedpoints",
    # periodic orbits of any period and rotation numbers
    "PeriodicOrbit": "explorer.analysis.periodic",
    "find_periodic_orbit": "explorer.analysis.periodic",
    "search_periodic_orbits": "explorer.analysis.periodic",
    "mirror_orbit": "explorer.analysis.periodic",
    "continue_periodic": "explorer.analysis.periodic",
    # invariant manifolds, homoclinic tangles and transport (docs/manifolds.md)
    "manifolds": "explorer.analysis.manifolds",
    "homoclinic_points": "explorer.analysis.manifolds",
    "heteroclinic_points": "explorer.analysis.manifolds",
    "lobes": "explorer.analysis.transport",
    "flux_curve": "explorer.analysis.transport",
    "exit_times": "explorer.analysis.transport",
    "rotation_number": "explorer.analysis.rotation",
    "rotation_profile": "explorer.analysis.rotation",
    "frequency_diffusion": "explorer.analysis.rotation",
    # scenes, sweeps and stores
    "Scene": "explorer.io.scene",
    "load_scene": "explorer.io.scene",
    "read_store": "explorer.io.store",
    "iter_rows": "explorer.io.store",
    "run_sweep": "explorer.app.runner",
    "SweepReport": "explorer.app.runner",
    # the explorer in a notebook cell (explorer serve's page)
    "explore": "explorer.app.serve.notebook",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'explorer' has no attribute {name!r}")
    mod = importlib.import_module(module)
    value = getattr(mod, name) if hasattr(mod, name) else importlib.import_module(f"{module}.{name}")
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
