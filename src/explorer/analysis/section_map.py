"""The section map P of phi = phi0 at energy h, with its Jacobian from the tangent dynamics.

P: (p1, p2) -> (p1', p2') sends a point of the section phi = phi0 on the energy level h
(M > 0 from the energy, docs/model.md R9) to the next crossing with dphi/dt > 0 (backward in
time: the previous one, P^{-1}).  Its Jacobian comes from the tangent dynamics (the
variational Taylor series of R3, :func:`explorer.integrate.tangent.return_map_taylor`), not
from finite differences:

    DP = Pi (I - f grad(g)^T / (grad(g) . f)) DPhi_T L

where L lifts (dp1, dp2) to the energy shell (dM = -(H_p1 dp1 + H_p2 dp2) / H_M, dg = 0),
DPhi_T is the flow's tangent map up to the crossing time T, the bracket corrects for the
change of T (g = sin(phi - phi0)), and Pi keeps (p1, p2).  P preserves area in these
coordinates up to a factor that cancels along a periodic orbit (det of a monodromy = 1).

:class:`SectionMap` is the object every analysis of the map takes (fixed points, periodic
orbits, continuation, rotation numbers, separatrices), as DynamicalSystems.jl's
``PoincareMap`` is for its algorithms.

One argument order for every analysis: the system first -- a :class:`SectionMap`, or the
model parameters and the energy ``(params, h)`` with the section's ``phi0`` and ``tol`` as
keywords -- then the point(s), then the budgets (keywords).  :func:`takes_section_map` gives
a function written for ``(params, h, ...)`` the form ``(smap, ...)``: the map's ``params``,
``h``, ``phi0``, ``tol`` (and ``tmax``, where the function's ``tmax`` is the map's return
budget) are passed on, so both forms give the same numbers.
"""
from __future__ import annotations

import functools
import inspect
import math
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.analysis import budget
from explorer.integrate.methods import MAP_TOL, MAX_TOL, MIN_TOL
from explorer.integrate.tangent import return_map_taylor
from explorer.kernels import STATUS_CANCELLED, STATUS_DONE, STATUS_NAMES
from explorer.kernels.taylor import order_for_tolerance
from explorer.model import ParameterError, validation
from explorer.model.equations import rhs

__all__ = ["DEFAULT_TOL", "MAX_STEPS", "RETURN_TMAX", "MapResult", "SectionMap", "takes_section_map"]

#: Taylor tolerance of the section map in Newton's method and its relatives (fixed points,
#: periodic orbits, continuation, separatrices): the map is evaluated a few hundred times,
#: never millions, so it is taken at the tightest tolerance the order rule allows
DEFAULT_TOL = MAP_TOL
#: time budget of one return of the map
RETURN_TMAX = 1e3
#: step budget of one return of the map
MAX_STEPS = 10**8


@dataclass(frozen=True)
class MapResult:
    """One application of the section map."""

    point: np.ndarray      # (p1, p2) image
    jacobian: np.ndarray   # 2x2 DP at the start point (None when not asked for)
    time: float            # signed return time
    state: np.ndarray      # full state (p1, p2, M, g1, g2) at the crossing


class SectionMap:
    """The section map P of phi = ``phi0`` at energy ``h`` (Taylor method, order from ``tol``).

    ``smap(x)`` is P(x) with DP(x) and the return time (a :class:`MapResult`);
    ``smap.jacobian(x)``, ``smap.iterate(x, n)`` and ``smap.inverse(x)`` are shorthands.
    A point with no return within ``tmax`` raises :class:`~explorer.model.ParameterError`.
    Inside a :class:`~explorer.analysis.budget.Budget` (its thread's current one) a return stops
    within a step of the budget's switch and raises
    :class:`~explorer.analysis.budget.BudgetExceeded`.
    """

    #: the integrator of the map (its Jacobian is the variational Taylor series); the analyses
    #: given a map integrate with it (``section_crossings``, ``indicators``)
    method = "taylor"

    def __init__(self, params, h, *, phi0=math.pi, tol=DEFAULT_TOL, tmax=RETURN_TMAX):
        self.params = params if isinstance(params, model.Params) else model.Params.from_array(params)
        self.P = self.params.as_array()
        self.h = validation.real("h", h)
        self.phi0 = validation.real("phi0", phi0)
        g1, g2 = model.section_gamma(self.phi0)
        self.sphi, self.cphi = g1, g2
        self.tol = validation.real("tol", tol, MIN_TOL, MAX_TOL)
        self.order = order_for_tolerance(self.tol)
        self.tmax = validation.real("tmax", tmax, 0.0, lo_open=True)

    def __repr__(self):
        return f"SectionMap({self.params!r}, h={self.h!r}, phi0={self.phi0!r}, tol={self.tol!r})"

    def state(self, x):
        """The full state (p1, p2, M, g1, g2) of the section point x (M > 0 from the energy)."""
        return model.section_state(self.params, [x[0]], [x[1]], self.h, self.phi0)[0]

    def lift(self, y):
        """Tangent vectors on the energy shell for dp1 = 1 and dp2 = 1 (dg = 0)."""
        gH = model.energy_gradient(self.P, y)
        V = np.zeros((2, 5))
        for r in range(2):
            V[r, r] = 1.0
            V[r, 2] = -gH[r] / gH[2]
        return V

    def __call__(self, x, *, backward=False, jacobian=True) -> MapResult:
        y0 = self.state(x)
        V0 = self.lift(y0) if jacobian else np.zeros((0, 5))
        yout = np.empty(5)
        Vout = np.empty_like(V0)
        stop = budget.stop_switch()
        status, t = return_map_taylor(y0, V0, self.P, self.cphi, self.sphi, -1.0 if backward else 1.0,
                                      self.tmax, self.order, MAX_STEPS, stop, yout, Vout)
        if status == STATUS_CANCELLED:
            budget.stop_switch()                      # raises BudgetExceeded with the budget's reason
        if status != STATUS_DONE:
            raise ParameterError(f"section map from (p1, p2) = ({x[0]:.6g}, {x[1]:.6g}): no return "
                                 f"({STATUS_NAMES[int(status)]})")
        J = None
        if jacobian:
            f = np.empty(5)
            rhs(yout, self.P, f)
            grad_g = np.array([0.0, 0.0, 0.0, self.cphi, -self.sphi])
            W = Vout - np.outer(Vout @ grad_g, f) / (grad_g @ f)
            J = W[:, :2].T.copy()
        return MapResult(yout[:2].copy(), J, float(t), yout.copy())

    def jacobian(self, x) -> np.ndarray:
        """DP(x), the 2x2 Jacobian of the map at x."""
        return self(x).jacobian

    def inverse(self, x) -> np.ndarray:
        """P^{-1}(x): the previous crossing (the flow backward in time)."""
        return self(x, backward=True, jacobian=False).point

    def iterate(self, x, n, *, backward=False) -> np.ndarray:
        """x and its first ``n`` images (preimages with ``backward``): an (n + 1, 2) array."""
        n = validation.integer("n", n, 0)
        out = np.empty((n + 1, 2))
        out[0] = np.asarray(x, float)
        for k in range(n):
            out[k + 1] = self(out[k], backward=backward, jacobian=False).point
        return out


#: the settings of a SectionMap that an analysis of the form (params, h, ...) takes as keywords
MAP_SETTINGS = ("phi0", "tol", "tmax")


def takes_section_map(fn):
    """Let ``fn(params, h, *args, phi0=..., tol=..., **kw)`` also be called as
    ``fn(smap, *args, **kw)`` with a :class:`SectionMap` ``smap`` (the system first): it runs
    ``fn(smap.params, smap.h, *args, phi0=smap.phi0, tol=smap.tol, **kw)`` (and
    ``tmax=smap.tmax`` when ``fn``'s ``tmax`` defaults to :data:`RETURN_TMAX`, the map's return
    budget).  Those settings belong to the map: given beside it they raise ParameterError."""
    sig = inspect.signature(fn)
    taken = tuple(k for k in MAP_SETTINGS if k in sig.parameters
                  and (k != "tmax" or sig.parameters[k].default == RETURN_TMAX))

    @functools.wraps(fn)
    def call(system, *args, **kw):
        if not isinstance(system, SectionMap):
            return fn(system, *args, **kw)
        given = [k for k in taken if k in kw]
        if given:
            raise ParameterError(f"{fn.__name__}: {', '.join(given)} belong(s) to the SectionMap; "
                                 f"do not give them beside it")
        if "tmax" not in taken and system.tmax != RETURN_TMAX:
            raise ParameterError(f"{fn.__name__} has no return budget of the map: use a SectionMap with the "
                                 f"default tmax ({RETURN_TMAX:g}), got {system.tmax!r}")
        kw.update({k: getattr(system, k) for k in taken})
        return fn(system.params, system.h, *args, **kw)

    note = (f"    System first: ``{fn.__name__}(smap, ...)`` with a "
            f":class:`~explorer.analysis.section_map.SectionMap` in place of ``params, h`` uses the map's "
            f"{', '.join(f'``{k}``' for k in taken)}.")
    doc = fn.__doc__ or ""
    head, sep, tail = doc.partition("\n\n")
    call.__doc__ = head + "\n\n" + note + (sep + tail if sep else "\n")
    return call
