"""Type stub of the lazy public API (explorer/__init__.py loads each name on first use; this
file lets IDEs and type checkers see the names).  tests/test_api.py keeps it equal to __all__."""

__version__: str

from explorer.analysis.chaos_map import (
    ChaosMap as ChaosMap,
)
from explorer.analysis.chaos_map import (
    chaos_map as chaos_map,
)
from explorer.analysis.fixedpoints import (
    Branch as Branch,
)
from explorer.analysis.fixedpoints import (
    FixedPoint as FixedPoint,
)
from explorer.analysis.fixedpoints import (
    continue_branch as continue_branch,
)
from explorer.analysis.fixedpoints import (
    find_fixed_point as find_fixed_point,
)
from explorer.analysis.fixedpoints import (
    separatrices as separatrices,
)
from explorer.analysis.greene import (
    GreeneResult as GreeneResult,
)
from explorer.analysis.greene import (
    greene as greene,
)
from explorer.analysis.lyapunov import (
    Indicators as Indicators,
)
from explorer.analysis.lyapunov import (
    chaotic_fraction as chaotic_fraction,
)
from explorer.analysis.lyapunov import (
    indicators as indicators,
)
from explorer.analysis.manifolds import (
    heteroclinic_points as heteroclinic_points,
)
from explorer.analysis.manifolds import (
    homoclinic_points as homoclinic_points,
)
from explorer.analysis.manifolds import (
    manifolds as manifolds,
)
from explorer.analysis.maps import (
    AreaPreservingMap as AreaPreservingMap,
)
from explorer.analysis.maps import (
    StandardMap as StandardMap,
)
from explorer.analysis.periodic import (
    PeriodicOrbit as PeriodicOrbit,
)
from explorer.analysis.periodic import (
    continue_periodic as continue_periodic,
)
from explorer.analysis.periodic import (
    find_periodic_orbit as find_periodic_orbit,
)
from explorer.analysis.periodic import (
    mirror_orbit as mirror_orbit,
)
from explorer.analysis.periodic import (
    search_periodic_orbits as search_periodic_orbits,
)
from explorer.analysis.rotation import (
    frequency_diffusion as frequency_diffusion,
)
from explorer.analysis.rotation import (
    rotation_number as rotation_number,
)
from explorer.analysis.rotation import (
    rotation_profile as rotation_profile,
)
from explorer.analysis.section_map import (
    SectionMap as SectionMap,
)
from explorer.analysis.sections import (
    METHODS as METHODS,
)
from explorer.analysis.sections import (
    CrossingBlock as CrossingBlock,
)
from explorer.analysis.sections import (
    Crossings as Crossings,
)
from explorer.analysis.sections import (
    StreamState as StreamState,
)
from explorer.analysis.sections import (
    crossings as crossings,
)
from explorer.analysis.sections import (
    iter_crossings as iter_crossings,
)
from explorer.analysis.sections import (
    propagate as propagate,
)
from explorer.analysis.system_flow import (
    flow as flow,
)
from explorer.analysis.transport import (
    exit_times as exit_times,
)
from explorer.analysis.transport import (
    flux_curve as flux_curve,
)
from explorer.analysis.transport import (
    lobes as lobes,
)
from explorer.app.runner import (
    SweepReport as SweepReport,
)
from explorer.app.runner import (
    run_sweep as run_sweep,
)
from explorer.app.serve.notebook import (
    explore as explore,
)
from explorer.io.scene import (
    Scene as Scene,
)
from explorer.io.scene import (
    load_scene as load_scene,
)
from explorer.io.store import (
    iter_rows as iter_rows,
)
from explorer.io.store import (
    read_store as read_store,
)
from explorer.kernels import (
    Status as Status,
)
from explorer.model import (
    FIGURE4 as FIGURE4,
)
from explorer.model import (
    FIGURE4_H as FIGURE4_H,
)
from explorer.model import (
    PARAM_NAMES as PARAM_NAMES,
)
from explorer.model import (
    ParameterError as ParameterError,
)
from explorer.model import (
    Params as Params,
)
from explorer.model import (
    allowed_ellipse as allowed_ellipse,
)
from explorer.model import (
    casimir as casimir,
)
from explorer.model import (
    classic as classic,
)
from explorer.model import (
    energy as energy,
)
from explorer.model import (
    section_state as section_state,
)
from explorer.model.system import (
    System as System,
)

__all__: list[str]
