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
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.integrate.methods import MAP_TOL, MAX_TOL, MIN_TOL
from explorer.integrate.tangent import return_map_taylor
from explorer.kernels import STATUS_DONE, STATUS_NAMES
from explorer.kernels.taylor import order_for_tolerance
from explorer.model import ParameterError, validation
from explorer.model.equations import rhs

__all__ = ["DEFAULT_TOL", "MAX_STEPS", "RETURN_TMAX", "MapResult", "SectionMap"]

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
    """

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
        status, t = return_map_taylor(y0, V0, self.P, self.cphi, self.sphi, -1.0 if backward else 1.0,
                                      self.tmax, self.order, MAX_STEPS, yout, Vout)
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
