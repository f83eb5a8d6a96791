"""What the page asks of its section (docs/commands/serve.md, "Your own system"): implemented by
:class:`ChaplyginPage` (Chaplygin's Settings) and by :class:`~explorer.app.serve.system_page.SystemSettings`."""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np


def megno_of(res, shape, mlce: bool):
    """<Y> (and the mLCE with ``mlce``) of the Indicators ``res`` in ``shape``, NaN where a run stopped early."""
    def of(values):
        return np.where(np.asarray(res.status) == 0, np.asarray(values, dtype=np.float64), np.nan).reshape(shape)
    return (of(res.megno), of(res.mlce)) if mlce else of(res.megno)


class ChaplyginPage:
    """The page's protocol for Chaplygin's model (mixed into Settings: params, h, phi0, method, ...)."""

    scene_export = True            # the session exports as a scene that `explorer sweep` reruns
    axes = ("p1", "p2")
    if TYPE_CHECKING:              # (Settings' fields and methods)
        params: Any
        h: Any
        phi0: Any
        method: Any
        tol: Any
        dt: Any
        direction: Any
        adaptive: Any
        admissible: Any

    def describe(self) -> str:
        return f"mu = {self.params.mu:g}, h = {self.h:g}, {self.method}"

    def title(self) -> str:
        return f"Poincaré section φ = {'π' if self.phi0 == math.pi else f'{self.phi0:.6g}'}"

    def empty_region(self) -> str:
        return f"the allowed region is empty at h = {self.h:g} (h is below the minimum of the energy on the section)"

    def region_mask(self):
        """None: the region is the ellipse :attr:`region` (docs/model.md R9)."""
        return None

    def allowed(self, p1, p2) -> np.ndarray:
        """Mask of the points strictly inside the allowed region (M^2 > 0)."""
        from explorer import model

        return model.section_M2(self.params, p1, p2, self.h, self.phi0) > 0.0

    def refusal(self, p1: float, p2: float) -> str | None:
        """Why a click at (p1, p2) starts no orbit (None: it does)."""
        if self.admissible(p1, p2):
            return None
        return f"({p1:.4g}, {p2:.4g}) is outside the allowed region (M^2 < 0 there): click in the white ellipse"

    def section_map(self, tol=None):
        """The section map the page's searches ask (fixed points, manifolds, rotation numbers)."""
        from explorer.analysis.section_map import DEFAULT_TOL, SectionMap

        return SectionMap(self.params, self.h, phi0=self.phi0, tol=DEFAULT_TOL if tol is None else tol)

    def megno(self, p1, p2, time: float, max_steps: int, mlce: bool = False):
        """<Y>(time) (and the mLCE with ``mlce``) of the orbits from (p1, p2), NaN where a run stops early."""
        from explorer import model
        from explorer.analysis import lyapunov

        if not self.adaptive and time / self.dt > max_steps:
            nan = np.full(np.shape(p1), np.nan)
            return (nan, nan) if mlce else nan
        y0 = model.section_state(self.params, p1, p2, self.h, self.phi0, self.direction or 1)
        return megno_of(lyapunov.indicators(self.params, states=y0, tmax=time, method=self.method, tol=self.tol,
                                            dt=self.dt, which=("megno", "mlce") if mlce else ("megno",),
                                            max_steps=max_steps), np.shape(p1), mlce)

    def new_run(self, ident: int, p1: float, p2: float):
        from explorer.app.serve.orbits import OrbitRun

        return OrbitRun(ident, p1, p2, self)
