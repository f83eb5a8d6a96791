"""The section map of a :class:`explorer.model.system.System` on an energy level
(docs/systems.md, "Section map").

``SystemSectionMap(system, E, section=EXPR, direction=+1 or -1, coords=(a, b), solve=c)``: a
section point ``(a, b)`` becomes a full state on ``EXPR = 0`` with energy ``E``:

- the section's linear equation fixes one state variable, ``fixed``: of the variables neither in
  ``coords`` nor ``solve``, the one with the largest coefficient in EXPR (the first in state order
  at a tie), solved from EXPR = 0 in terms of the others;
- ``solve`` comes from ``energy = E`` with ``fixed`` put in: ``sympy.solve`` gives the roots as
  expressions (cached per system, section, coords and solve; E and the parameters stay symbols),
  evaluated in complex arithmetic and kept where real; each root gets one Newton step on the
  energy where that lowers ``|H - E|``;
- of the real roots, the one where ``d(EXPR)/dt`` has the sign of ``direction``.

A point where no real root has that sign is refused (ParameterError naming the point and E): the
map's domain is where one has (:meth:`SystemSectionMap.allowed`, a mask over many points).  A
System's map has 4 state variables (2 degrees of freedom): coords, solve and fixed.

The map is an :class:`explorer.analysis.maps.AreaPreservingMap`: ``smap(x)`` is a
:class:`~explorer.analysis.map_result.MapResult` with the Jacobian of the 2-D map, from the
variational equations (``System.variational(2)``) integrated to the next crossing: the monodromy
Phi applied to the lift of the unit vectors of coords (tangent to the section and the energy level,
by the implicit function theorem), corrected for the crossing time, ``(I - f a^T/(a . f)) Phi``
(``a`` the section's normal, ``f`` the vector field at the crossing), read in coords.  Backward is
the flow of ``-f``, crossing the section in the opposite direction.  A reversor of the System
(``System(..., reversor=...)``) that maps the section and its direction to themselves induces an
involution of the map (:attr:`SystemSectionMap.reversors`).

:meth:`SystemSectionMap.crossings` is what ``explorer.crossings(smap, points, n_crossings=K)``
runs: the points lifted to states, then the System's crossings of the map's section and direction at
the map's ``tol`` (as Chaplygin's map: another tolerance is ``smap.with_tol(tol)``, not ``tol=`` beside it).
"""
from __future__ import annotations

import copy
import functools
import numbers

import numpy as np

from explorer.analysis.map_result import RETURN_TMAX, FlowSection, MapResult
from explorer.analysis.maps import grid_minima, returns_increments
from explorer.analysis.symmetry_lines import half_turn_orbit, symmetric_seeds
from explorer.analysis.system_sections import is_system, iter_system_crossings, linear_section, system_crossings
from explorer.integrate.methods import MAP_TOL, MAX_TOL, MIN_TOL
from explorer.kernels import STATUS_NAMES
from explorer.model import ParameterError, validation

__all__ = ["ENERGY", "SEARCH_RETURNS", "SystemSectionMap", "refused_beside"]

#: the name of the energy level among a System map's parameters (``with_value("energy", E)``)
ENERGY = "energy"

#: (content hash, section, coords, solve, fixed) -> the lambdified roots, fixed, energy, dH/dsolve, ds/dt,
#: grad H, f, and per reversor (images, ds/dt at the image over ds/dt, on the section)
_SOLUTIONS: dict = {}
#: (content hash, jacobian) -> the System integrated by the map (values of the first map)
_FLOWS: dict = {}
#: a root is real where its imaginary part is at most this times max(1, |root|)
REAL_TOL = 1e-12
#: a periodic-orbit search gives one return of a seed at most this many typical return times
#: (:attr:`SystemSectionMap.search_tmax`): seeds whose orbits never come back (they escape, or graze the
#: section's edge) are cut early, while the slow returns near a hyperbolic point (their time grows like
#: the log of the distance) and near the domain's edge (2-3 typical on Chaplygin's and Henon-Heiles'
#: sections) are kept; Chaplygin's search budget, 50, is 8 of its typical returns (~6.2 at h = 2)
SEARCH_RETURNS = 8
#: the median return time of the points of a TYPICAL_GRID x TYPICAL_GRID grid of the domain is typical
TYPICAL_GRID = 8


def _symbol_of(system, label, s):
    """The state symbol ``s`` of ``system`` (a Symbol or its name), else a ParameterError naming ``label``."""
    by_name = {v.name: v for v in system.states}
    name = s if isinstance(s, str) else getattr(s, "name", None)
    if name not in by_name or (not isinstance(s, str) and s != by_name[name]):
        raise ParameterError(f"{label} must be a state variable of {system.name} "
                             f"({', '.join(by_name)}), got {s!r}")
    return by_name[name]


def _solutions(system, section, coords, solve, fixed):
    """The lambdified pieces of the lift (cached): roots(a, b, E, *P) -> list of complex values of
    ``solve``; fixed(a, b, c, *P); energy, dH/dsolve, ds/dt, grad H and f of (*state, *P); per
    reversor R its images and the ratio of ds/dt at R x to ds/dt at x on the section, of (*state, *P)
    (None where the section is not mapped to itself)."""
    import sympy as sp

    key = (system.content_hash, sp.srepr(section), coords, solve, fixed)
    if key in _SOLUTIONS:
        return _SOLUTIONS[key]
    E = sp.Dummy("E")
    pars = list(system.parameters)
    a, b = coords
    fixed_expr = sp.solve(section, fixed)[0]          # EXPR is linear with a nonzero coefficient of fixed
    level = sp.expand(system.energy.subs(fixed, fixed_expr) - E)
    if solve not in level.free_symbols:
        raise ParameterError(f"the energy of {system.name} on the section {section} = 0 does not depend on "
                             f"{solve.name}: solve must be a state variable the energy fixes")
    # no simplify: it costs seconds, and its factoring (Wang's, random evaluation points) can run for many
    # minutes on an unlucky draw of sympy's generator (the double pendulum's roots in one test process)
    roots = sp.solve(level, solve, simplify=False)
    if not roots:
        raise ParameterError(f"sympy finds no solution of energy = E for {solve.name} on the section "
                             f"{section} = 0: choose another solve")
    sdot = sum(sp.diff(section, s) * f for s, f in zip(system.states, system.rhs))
    args_point = [a, b, E, *pars]
    args_state = [*system.states, *pars]
    reversors = []
    for images in system.reversors:
        R = dict(zip(system.states, images))
        on = {fixed: fixed_expr}
        # R maps the section to itself; the orbit R x(-t) crosses it at R x with rate -d(s o R)/dt
        if sp.simplify(section.subs(R, simultaneous=True).subs(on)) != 0:
            reversors.append((sp.lambdify(args_state, list(images), modules="numpy"), None, None))
            continue
        rate = -sum(sp.diff(section.subs(R, simultaneous=True), s) * f for s, f in zip(system.states, system.rhs))
        ratio = sp.simplify((rate / sdot).subs(on))
        ratio = ratio if not (ratio.free_symbols & set(system.states)) else None
        # linear in coords: the images of a and b are c_a a + c_b b, with no other state
        ia, ib = system.states.index(a), system.states.index(b)
        M = [[sp.diff(images[i], v) for v in (a, b)] for i in (ia, ib)]
        linear = all(not (c.free_symbols & set(system.states)) for row in M for c in row) and all(
            sp.expand(images[i] - row[0] * a - row[1] * b) == 0 for i, row in zip((ia, ib), M))
        reversors.append((sp.lambdify(args_state, list(images), modules="numpy"),
                          None if ratio is None else sp.lambdify(pars, ratio, modules="numpy"),
                          sp.lambdify(pars, M, modules="numpy") if linear else None))
    out = (sp.lambdify(args_point, roots, modules="numpy"),
           sp.lambdify([a, b, solve, *pars], fixed_expr, modules="numpy"),
           sp.lambdify(args_state, system.energy, modules="numpy"),
           sp.lambdify(args_state, sp.diff(system.energy, solve), modules="numpy"),
           sp.lambdify(args_state, sdot, modules="numpy"),
           sp.lambdify(args_state, [sp.diff(system.energy, s) for s in system.states], modules="numpy"),
           sp.lambdify(args_state, list(system.rhs), modules="numpy"),
           tuple(reversors))
    _SOLUTIONS[key] = out
    return out


def _flow(system, jacobian: bool):
    """The System the map integrates, forward or backward in time: ``system``, with two deviation
    vectors for the Jacobian; at ``system``'s parameter values."""
    key = (system.content_hash, jacobian)
    if key not in _FLOWS:
        flow = system.variational(2) if jacobian else system
        _ = flow.content_hash, flow.flow_hash    # hashed once: with_ copies them to every integration's system
        _FLOWS[key] = flow
    flow = _FLOWS[key]
    return flow if flow is system else flow.with_(**{p.name: v for p, v in system.parameters.items()})


class _Linear:
    """x -> M x on points (..., 2): a reversor of the map that is linear in coords."""

    def __init__(self, M):
        self.M = np.asarray(M, dtype=np.float64)

    def __call__(self, x):
        return np.asarray(x, dtype=np.float64) @ self.M.T

    def __repr__(self):
        return f"_Linear({self.M.tolist()})"


def refused_beside(run: str, given: list) -> ParameterError:
    """The refusal of the map's own settings ``given`` beside a System's map to ``run`` (its crossings or
    indicators): they belong to the map; at another tol it is ``smap.with_tol(tol)`` (as Chaplygin's map)."""
    note = " (the states: its points)" if "states" in given else ""
    other = "; at another tol, give the map smap.with_tol(tol)" if "tol" in given else ""
    return ParameterError(f"{run} of a SectionMap: {', '.join(given)} belong(s) to the map{note}; do not give them "
                          f"beside it{other}")


class SystemSectionMap(FlowSection):
    """The section map of ``system`` on its energy level ``energy_value``: points ``(a, b)`` of
    ``coords`` on ``section = 0``, crossed in ``direction``; ``solve`` from the energy (module
    docstring).  ``states(points)`` lifts points; ``explorer.crossings(smap, points,
    n_crossings=K)`` iterates the map; ``smap(x)`` is one application with its Jacobian.  ``tol``:
    the Taylor tolerance of the map's returns and crossings; ``tmax``: the time budget of one return."""

    method = "taylor"
    periods = (0.0, 0.0)

    def __init__(self, system, energy_value, *, section=None, direction=1, coords=None, solve=None, tol=MAP_TOL,
                 tmax=RETURN_TMAX):
        if not is_system(system):
            raise ParameterError(f"SystemSectionMap takes a System, got {type(system).__name__}")
        if system.energy is None:
            raise ParameterError(f"SectionMap of {system.name}: the system has no energy; give System(..., "
                                 "energy=...) to solve a coordinate from the energy level")
        if system.dimension != 4:
            raise ParameterError(f"SectionMap of {system.name}: a section map of a System needs 4 state variables "
                                 f"(2 degrees of freedom: coords, solve and the section's), it has {system.dimension}")
        self.system = system
        self.energy_value = validation.real("energy_value", energy_value)
        if isinstance(direction, bool) or not isinstance(direction, numbers.Integral) or direction not in (-1, 1):
            raise ParameterError(f"direction must be +1 (ds/dt > 0) or -1 (ds/dt < 0), got {direction!r}")
        self.direction = int(direction)
        self.tol = validation.real("tol", tol, MIN_TOL, MAX_TOL)
        self.tmax = validation.real("tmax", tmax, 0.0, lo_open=True)
        self.section = linear_section(system, section)
        if not isinstance(coords, (tuple, list)) or len(coords) != 2:
            raise ParameterError(f"coords must be two state variables (a, b) of {system.name}, got {coords!r}")
        a, b = (_symbol_of(system, "coords", c) for c in coords)
        if a == b:
            raise ParameterError(f"coords must be two different state variables, got ({a.name}, {b.name})")
        if solve is None:
            raise ParameterError("solve is missing: give the state variable solved from the energy")
        c = _symbol_of(system, "solve", solve)
        if c in (a, b):
            raise ParameterError(f"solve must not be one of coords ({a.name}, {b.name}), got {c.name}")
        self.coords, self.solve = (a, b), c
        rest = [i for i, s in enumerate(system.states) if s not in (a, b, c)]
        i = rest[int(np.argmax(np.abs(self.section.a[rest])))]
        if self.section.a[i] == 0.0:
            raise ParameterError(f"section {self.section.expr} must involve {system.states[i].name}, the state "
                                 f"variable neither in coords ({a.name}, {b.name}) nor solve ({c.name})")
        self.fixed = system.states[i]
        self._index = [system.states.index(s) for s in (a, b, c, self.fixed)]
        self._lift = _solutions(system, self.section.expr, self.coords, c, self.fixed)

    def _settings(self) -> dict:
        return dict(section=self.section.expr, direction=self.direction, coords=self.coords, solve=self.solve,
                    tol=self.tol, tmax=self.tmax)

    def _key(self) -> tuple:
        """What makes two maps one: the system's equations (content hash), name and parameter values, the
        energy and :meth:`_settings`."""
        s = self.system
        return s.content_hash, s.name, tuple(s.parameters.values()), self.energy_value, *self._settings().values()

    def __eq__(self, other):
        """Equal maps give the same points, states and crossings (a map rebuilt with the same values is equal)."""
        return isinstance(other, SystemSectionMap) and other._key() == self._key()

    def __hash__(self):
        return hash(self._key())

    def __getstate__(self):
        """Pickled without the lambdified functions (rebuilt from the cache on unpickling)."""
        state = dict(self.__dict__)
        del state["_lift"]
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._lift = _solutions(self.system, self.section.expr, self.coords, self.solve, self.fixed)

    def __repr__(self):
        """What names the map: the system with its parameter values, the energy, the section and its
        direction, coords and solve."""
        a, b = self.coords
        pars = ", ".join(f"{p.name}={v!r}" for p, v in self.system.parameters.items())
        return (f"SectionMap({self.system.name}({pars}), energy={self.energy_value!r}, section={self.section.expr}, "
                f"direction={self.direction:+d}, coords=({a.name}, {b.name}), solve={self.solve.name})")

    # ------------------------------------------------------------------ points and states
    def _lifted(self, pts) -> np.ndarray:
        """The states (N, 4) of the points (N, 2); NaN rows where the energy level has no solution
        on the direction's branch (ds/dt = 0, the boundary, has none)."""
        roots_of, fixed_of, energy, dH, sdot = self._lift[:5]
        P = list(self.system.parameter_array())
        A, B = pts[:, 0], pts[:, 1]
        with np.errstate(all="ignore"):
            roots = [np.broadcast_to(np.asarray(r, dtype=np.complex128), A.shape)
                     for r in roots_of(A.astype(np.complex128), B.astype(np.complex128), self.energy_value, *P)]
        Y = np.full((pts.shape[0], self.system.dimension), np.nan)
        done = np.zeros(pts.shape[0], bool)
        for r in roots:
            real = np.isfinite(r) & (np.abs(r.imag) <= REAL_TOL * np.maximum(1.0, np.abs(r.real)))
            C = self._polish(A, B, np.where(real, r.real, 0.0), P)
            state = self._assemble(A, B, C, P)
            with np.errstate(all="ignore"):
                s = np.broadcast_to(np.asarray(sdot(*state.T, *P), dtype=np.float64), A.shape)
            take = real & (np.sign(s) == self.direction) & ~done & np.all(np.isfinite(state), axis=1)
            Y[take] = state[take]
            done |= take
        return Y

    @staticmethod
    def _on_surface(Y) -> np.ndarray:
        """The rows of :meth:`_lifted` that are states (the domain's one rule)."""
        return np.isfinite(Y[:, 0])

    def allowed(self, points) -> np.ndarray:
        """Mask (...) of the points (..., 2) in the map's domain (those :meth:`states` lifts): the
        energy level has a real root for ``solve`` with d(section)/dt of the direction's sign, not
        zero; False at a non-finite point.  Vectorised: one evaluation of the roots for all points."""
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim < 1 or pts.shape[-1] != 2:
            a, b = self.coords
            raise ParameterError(f"points must be ({a.name}, {b.name}) pairs (..., 2), got shape {pts.shape}")
        flat = pts.reshape(-1, 2)
        ok = np.all(np.isfinite(flat), axis=1)
        if ok.any():
            ok[ok] = self._on_surface(self._lifted(flat[ok]))
        return ok.reshape(pts.shape[:-1])

    def _points(self, points) -> np.ndarray:
        try:
            pts = np.atleast_2d(np.asarray(points, dtype=np.float64))
        except (TypeError, ValueError):
            raise ParameterError(f"points must be (a, b) pairs (N, 2), got {points!r}") from None
        a, b = self.coords
        if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 1 or not np.all(np.isfinite(pts)):
            raise ParameterError(f"the points of a System's section map are finite ({a.name}, {b.name}) pairs "
                                 f"(N, 2); got {points!r}")
        return pts

    def _point(self, x) -> np.ndarray:
        x = np.asarray(x, dtype=np.float64) if np.shape(x) == (2,) else None
        if x is None or not np.all(np.isfinite(x)):
            a, b = self.coords
            raise ParameterError(f"a point of the section map is ({a.name}, {b.name}), two finite numbers")
        return x

    def states(self, points) -> np.ndarray:
        """The states (N, 4) of the section points (N, 2), in the system's state order; ParameterError
        for a point where the energy level has no solution on the direction's branch."""
        pts = self._points(points)
        Y = self._lifted(pts)
        bad = np.flatnonzero(~self._on_surface(Y))
        if bad.size:
            i = int(bad[0])
            a, b = self.coords
            raise ParameterError(
                f"the energy level E = {self.energy_value!r} has no solution for {self.solve.name} at ({a.name}, "
                f"{b.name}) = ({float(pts[i, 0])!r}, {float(pts[i, 1])!r}) with d({self.section.expr})/dt of sign "
                f"{self.direction:+d}: the point lies outside the energy surface on the section (or on its boundary)")
        return Y

    def _assemble(self, A, B, C, P) -> np.ndarray:
        """The states from coords (A, B), solve C and the section's fixed variable."""
        ia, ib, ic, jf = self._index
        Y = np.empty((A.shape[0], self.system.dimension))
        Y[:, ia], Y[:, ib], Y[:, ic] = A, B, C
        with np.errstate(all="ignore"):
            Y[:, jf] = np.broadcast_to(np.asarray(self._lift[1](A, B, C, *P), dtype=np.float64), A.shape)
        return Y

    def _polish(self, A, B, C, P) -> np.ndarray:
        """One Newton step on energy(solve) = E where it lowers ``|H - E|`` (a root's closed form may
        lose digits)."""
        energy, dH = self._lift[2], self._lift[3]
        with np.errstate(all="ignore"):
            Y = self._assemble(A, B, C, P)
            r0 = np.asarray(energy(*Y.T, *P), dtype=np.float64) - self.energy_value
            C1 = C - r0 / np.asarray(dH(*Y.T, *P), dtype=np.float64)
            Y = self._assemble(A, B, C1, P)
            r1 = np.asarray(energy(*Y.T, *P), dtype=np.float64) - self.energy_value
        better = np.isfinite(C1) & (np.abs(r1) < np.abs(r0))
        return np.where(better, C1, C)

    def state(self, x) -> np.ndarray:
        """The state of one section point x = (a, b)."""
        return self.states([x])[0]

    def _starts(self, Y, backward: bool) -> np.ndarray:
        """The states Y moved by ulps of the fixed variable to the side of the section the flow
        leaves (a start a rounding error behind it would count as a crossing)."""
        Y = np.array(Y, dtype=np.float64)
        jf = self._index[3]
        sign = -self.direction if backward else self.direction      # ds/dt along the integrated flow
        up = np.inf if sign * self.section.a[jf] > 0 else -np.inf
        for _ in range(8):
            behind = sign * self.section(Y) < 0.0
            if not behind.any():
                break
            Y[behind, jf] = np.nextafter(Y[behind, jf], up)
        return Y

    # ------------------------------------------------------------------ the domain
    def in_domain(self, x) -> bool:
        """x is a point of the section where the energy level has a solution on the direction's branch."""
        x = np.asarray(x, dtype=np.float64)
        return bool(x.shape == (2,) and self.allowed(x))

    @functools.cached_property
    def domain(self) -> tuple:
        """((a0, a1), (b0, b1)): a box holding the domain, from a 101 x 101 grid of |a|, |b| <= 2^k,
        k = 0..20, the first that holds it inside (one cell of margin); what a grid search covers."""
        u = np.linspace(-1.0, 1.0, 101)
        for k in range(21):
            A, B = np.meshgrid(u * 2.0 ** k, u * 2.0 ** k, indexing="ij")
            inside = self.allowed(np.stack([A, B], axis=-1))
            i, j = np.flatnonzero(inside.any(axis=1)), np.flatnonzero(inside.any(axis=0))
            if i.size and i[0] > 0 and j[0] > 0 and i[-1] < 100 and j[-1] < 100:
                a, b = A[:, 0], B[0]
                return (float(a[i[0] - 1]), float(a[i[-1] + 1])), (float(b[j[0] - 1]), float(b[j[-1] + 1]))
        raise ParameterError(f"the domain of the section map of {self.system.name} is empty or unbounded within "
                             f"|a|, |b| <= 2^20 ({self.describe_domain()})")

    def describe_domain(self) -> str:
        """The domain in words."""
        a, b = self.coords
        return (f"allowed: the points ({a.name}, {b.name}) of the section {self.section.expr} = 0 where the energy "
                f"level E = {self.energy_value:g} of {self.system.name} has a real {self.solve.name} with "
                f"d({self.section.expr})/dt of sign {self.direction:+d}")

    def not_finite(self, x) -> str:
        """Why DP is not finite at x."""
        a, b = self.coords
        return (f"the section map's Jacobian is not finite at ({a.name}, {b.name}) = ({x[0]:.6g}, {x[1]:.6g}): the "
                f"variational equations of {self.system.name} overflow at E = {self.energy_value:g}")

    def orbit_fields(self) -> dict:
        """What names the map in a PeriodicOrbit: itself."""
        return {"system": self}

    # ------------------------------------------------------------------ the map
    def _tangent(self, y) -> np.ndarray:
        """The lift (2, 4) of the unit vectors of coords at the state y: tangent to the section and to
        the energy level (the solve and fixed components from the implicit function theorem)."""
        ia, ib, ic, jf = self._index
        gH = np.asarray(self._lift[5](*y, *self.system.parameter_array()), dtype=np.float64)
        s = self.section.a
        A = np.array([[s[ic], s[jf]], [gH[ic], gH[jf]]])
        V = np.zeros((2, 4))
        for r, j in enumerate((ia, ib)):
            V[r, j] = 1.0
            V[r, [ic, jf]] = np.linalg.solve(A, -np.array([s[j], gH[j]]))
        return V

    def _returns(self, Y, n: int, backward: bool, jacobian: bool, threads=None):
        """The crossings of the flow (backward: reversed) from the states Y on ``threads``: (data, count,
        status)."""
        direction = -self.direction if backward else self.direction
        data, count, status, *_ = system_crossings(_flow(self.system, jacobian), Y, n_crossings=n,
                                                   section=self.section.expr, direction=direction, tol=self.tol,
                                                   tmax=self.tmax * n, threads=1 if len(Y) == 1 else threads,
                                                   backward=backward)
        return data, count, status

    def __call__(self, x, *, backward=False, jacobian=True) -> MapResult:
        """P(x) (P^-1(x) with ``backward``) with its Jacobian; ParameterError outside the domain or
        for no return within ``tmax``."""
        x = self._point(x)
        y0 = self._starts(self.states(x[None, :]), backward)[0]
        start = np.concatenate([y0, self._tangent(y0).ravel()]) if jacobian else y0
        data, count, status = self._returns(start[None, :], 1, backward, jacobian)
        if count[0] < 1:
            a, b = self.coords
            raise ParameterError(f"section map of {self.system.name} from ({a.name}, {b.name}) = ({x[0]:.6g}, "
                                 f"{x[1]:.6g}): no return ({STATUS_NAMES[int(status[0])]})")
        row = data[0, 0]
        y = row[1:5].copy()
        ia, ib = self._index[:2]
        J = None
        if jacobian:
            D = row[5:13].reshape(2, 4)
            f = np.asarray(self._lift[6](*y, *self.system.parameter_array()), dtype=np.float64)
            n = self.section.a
            W = D - np.outer(D @ n, f) / (n @ f)      # the crossing-time correction
            J = W[:, [ia, ib]].T.copy()
        t = float(row[0])
        return MapResult(y[[ia, ib]], J, -t if backward else t, y)

    def jacobian(self, x) -> np.ndarray:
        """DP(x), the 2x2 Jacobian of the map at x."""
        return self(x).jacobian

    def inverse(self, x) -> np.ndarray:
        """P^-1(x): the previous crossing (the flow backward in time)."""
        return self(x, backward=True, jacobian=False).point

    def images(self, X, n, *, backward=False, threads=None) -> np.ndarray:
        """The first ``n`` images (preimages with ``backward``) of each point of X: (m, n, 2), NaN for a
        point outside the domain and after a failed return; one batch of crossings on ``threads``."""
        X = np.asarray(X, float).reshape(-1, 2)
        n = validation.integer("n", n, 0)
        out = np.full((X.shape[0], n, 2), np.nan)
        ok = np.all(np.isfinite(X), axis=1)
        if n == 0 or not ok.any():
            return out
        Y = self._lifted(X[ok])
        lifted = self._on_surface(Y)
        inside = np.flatnonzero(ok)[lifted]
        if inside.size:
            data, count, _ = self._returns(self._starts(Y[lifted], backward), n, backward, False, threads)
            img = data[:, :, list(self.columns[1:3])]
            for i in range(len(img)):
                img[i, count[i]:] = np.nan
            out[inside] = img
        return out

    def iterate(self, x, n, *, backward=False) -> np.ndarray:
        """x and its first ``n`` images (preimages with ``backward``): an (n + 1, 2) array
        (ParameterError when the orbit stops sooner)."""
        n = validation.integer("n", n, 0)
        x = self._point(x)
        if n == 0:
            return x[None, :].copy()
        data, count, status = self._returns(self._starts(self.states(x[None, :]), backward), n, backward, False)
        if count[0] < n:
            raise ParameterError(f"section map of {self.system.name} from {tuple(x)}: {int(count[0])} of {n} "
                                 f"returns ({STATUS_NAMES[int(status[0])]})")
        return np.vstack([x[None, :], data[0][:, list(self.columns[1:3])]])

    def lifted_increments(self, starts, center, n, threads=None) -> tuple:
        """The angle increments of the orbits' first ``n`` returns around ``center``: the returns' own
        (:func:`explorer.analysis.maps.returns_increments`)."""
        return returns_increments(self, starts, center, n)

    # ------------------------------------------------------------------ half turns (docs/greene.md)
    @property
    def section_label(self) -> float:
        """The direction, which tells this map's half of the section from :meth:`opposite`'s."""
        return float(self.direction)

    def opposite(self) -> SystemSectionMap:
        """The map of the same section crossed in the other direction."""
        return SystemSectionMap(self.system, self.energy_value, **dict(self._settings(), direction=-self.direction))

    def half_turns(self, X, q: int, threads=None) -> np.ndarray:
        """The coords (m, 2) of the ``q``-th crossing of the section in either direction (crossings
        alternate) after each point of X: on this map's half for even ``q``, :meth:`opposite`'s for
        odd; NaN outside the domain or for no crossing; one batch of crossings on ``threads``."""
        X = np.asarray(X, float).reshape(-1, 2)
        out = np.full(X.shape, np.nan)
        Y = self._lifted(X)
        ok = np.flatnonzero(self._on_surface(Y))
        ia, ib = self._index[:2]
        if q == 0 or not ok.size:
            out[ok] = X[ok]
            return out
        Y = self._starts(Y[ok], False)
        if q >= 2:
            data, count, _ = self._returns(Y, q // 2, False, False, threads)
            Y = np.where((count >= q // 2)[:, None], data[:, q // 2 - 1, 1:1 + self.system.dimension], np.nan)
        if q % 2:
            data, count, *_ = system_crossings(_flow(self.system, False), np.nan_to_num(Y), n_crossings=1,
                                               section=self.section.expr, direction=-self.direction, tol=self.tol,
                                               tmax=self.tmax, threads=1 if len(Y) == 1 else threads)
            reached = (count >= 1) & np.isfinite(Y[:, 0])
            Y = np.where(reached[:, None], data[:, 0, 1:1 + self.system.dimension], np.nan)
        out[ok] = Y[:, [ia, ib]]
        return out

    def symmetric_orbit(self, p, q, *, line=None, guess=None):
        """The symmetric orbit of period ``q`` through ``guess`` v on the fixed line of the linear reversor, on
        the half ``line`` (a direction, default this map's), shot over its half turns
        (:func:`explorer.analysis.symmetry_lines.half_turn_orbit`)."""
        return half_turn_orbit(self, p, q, line, guess)

    # ------------------------------------------------------------------ parameters
    @property
    def parameters(self) -> tuple:
        """The names :meth:`with_value` takes: the system's parameters and ``"energy"``."""
        names = tuple(p.name for p in self.system.parameters)
        return names if ENERGY in names else (*names, ENERGY)

    @property
    def parameter(self) -> str:
        """The default parameter of a continuation: the system's first, else the energy."""
        return self.parameters[0]

    @property
    def parameter_value(self) -> float:
        """The value of :attr:`parameter`."""
        return self._value(self.parameter)

    def value_of(self, name: str) -> float:
        """The value of the parameter ``name`` of :attr:`parameters`."""
        validation.choice("param", name, self.parameters)
        return self._value(name)

    def _value(self, name) -> float:
        for p, v in self.system.parameters.items():
            if p.name == name:
                return float(v)
        return self.energy_value

    def with_value(self, name: str, value) -> SystemSectionMap:
        """This map with the system's parameter ``name``, or the energy level (``"energy"``), set to ``value``."""
        if name not in self.parameters:
            raise ParameterError(f"the section map of {self.system.name} has no parameter {name!r} (its "
                                 f"parameters: {', '.join(self.parameters)})")
        if name == ENERGY and ENERGY not in {p.name for p in self.system.parameters}:
            return SystemSectionMap(self.system, value, **self._settings())
        return SystemSectionMap(self.system.with_(**{name: value}), self.energy_value, **self._settings())

    def with_parameter(self, value, name=None) -> SystemSectionMap:
        """:meth:`with_value` of ``name``, default :attr:`parameter`."""
        return self.with_value(self.parameter if name is None else name, value)

    # ------------------------------------------------------------------ reversors
    def _involution(self, k, x) -> np.ndarray:
        """The involution of the map that reversor k of the system induces, at the points x (..., 2):
        the state of x, its image, its coords; NaN outside the domain."""
        x = np.asarray(x, dtype=np.float64)
        pts = x.reshape(-1, 2)
        out = np.full(pts.shape, np.nan)
        ok = np.all(np.isfinite(pts), axis=1)
        if ok.any():
            Y = self._lifted(pts[ok])
            with np.errstate(all="ignore"):
                Z = np.column_stack([np.broadcast_to(np.asarray(v, dtype=np.float64), (len(Y),)) for v in
                                     self._lift[7][k][0](*Y.T, *self.system.parameter_array())])
            out[ok] = Z[:, self._index[:2]]
        return out.reshape(x.shape)

    @property
    def reversors(self) -> tuple:
        """The involutions R of the map with R P R = P^-1 that the system's reversors induce: those
        that map the section, with its direction, to itself (a callable on points (..., 2); linear in
        coords: the matrix's action, defined everywhere)."""
        out = []
        P = self.system.parameter_array()
        for k, (_, ratio, M) in enumerate(self._lift[7]):
            if ratio is None or not float(ratio(*P)) > 0.0:
                continue
            out.append(_Linear(M(*P)) if M is not None else functools.partial(self._involution, k))
        return tuple(out)

    @property
    def reflection(self):
        """A reversor of :attr:`reversors` linear in coords (its fixed line through the origin), else None."""
        return next((R for R in self.reversors if isinstance(R, _Linear)), None)

    def symmetry_line_points(self, n) -> np.ndarray:
        """``n`` points on the fixed line of each linear reversor (where R x = x), spread over the
        part of the line in the domain (found on a grid of 2001 points of |t| <= 2^k, k = 0..20)."""
        n = validation.integer("n", n, 1)
        lines = []
        for R in self.reversors:
            if not isinstance(R, _Linear):
                continue
            w, V = np.linalg.eig(R.M)
            fixed = np.flatnonzero(np.abs(w - 1.0) < 1e-12)
            if fixed.size != 1:
                continue
            v = np.real(V[:, fixed[0]])
            for k in range(21):
                t = np.linspace(-(2.0 ** k), 2.0 ** k, 2001)
                inside = np.flatnonzero(self.allowed(t[:, None] * v))
                if inside.size and inside[0] > 0 and inside[-1] < t.size - 1:
                    break
            if not inside.size:
                continue
            lo, hi = t[max(inside[0] - 1, 0)], t[min(inside[-1] + 1, t.size - 1)]
            pts = (lo + (hi - lo) * (np.arange(n) + 0.5) / n)[:, None] * v
            lines.append(pts[self.allowed(pts)])
        return np.concatenate(lines) if lines else np.empty((0, 2))

    @functools.cached_property
    def typical_return_time(self) -> float:
        """The median return time of the points of a TYPICAL_GRID x TYPICAL_GRID grid of cell centres of
        :attr:`domain` (those in the domain and returning within ``tmax``)."""
        (a0, a1), (b0, b1) = self.domain
        u = (np.arange(TYPICAL_GRID) + 0.5) / TYPICAL_GRID
        A, B = np.meshgrid(a0 + (a1 - a0) * u, b0 + (b1 - b0) * u, indexing="ij")
        Y = self._lifted(np.column_stack([A.ravel(), B.ravel()]))
        Y = Y[self._on_surface(Y)]
        data, count, _ = self._returns(self._starts(Y, False), 1, False, False) if len(Y) else (None, [0], None)
        times = data[:, 0, 0][np.asarray(count) >= 1] if len(Y) else np.empty(0)
        if not times.size:
            raise ParameterError(f"no point of a {TYPICAL_GRID} x {TYPICAL_GRID} grid of the domain of {self!r} "
                                 f"returns within tmax = {self.tmax:g}: the map has no typical return time")
        return float(np.median(times))

    @property
    def search_tmax(self) -> float:
        """The time budget of one return in a periodic-orbit search: SEARCH_RETURNS typical return times."""
        return SEARCH_RETURNS * self.typical_return_time

    def symmetric_seeds(self, period: int, n: int, *, threads=None) -> np.ndarray:
        """Seeds (m, 2) of the orbits of period ``period`` symmetric under the linear reversor, from ``n``
        points of its fixed line on each half of the section
        (:func:`explorer.analysis.symmetry_lines.symmetric_seeds`, on ``threads``); none without one."""
        return symmetric_seeds(self, period, n, threads)

    def grid_seeds(self, period: int, grid: int, *, threads=None) -> np.ndarray:
        """:func:`explorer.analysis.maps.grid_minima` over :attr:`domain`, on ``threads``."""
        return grid_minima(self, period, grid, threads)

    def partner_points(self, points, *, threads=None):
        """The images (n, 2) of ``points`` under the first of :attr:`reversors` not linear in coords (an orbit
        run backwards; a linear one gives the exact mirror image, :attr:`reflection`), else None."""
        R = next((R for R in self.reversors if not isinstance(R, _Linear)), None)
        return None if R is None else R(np.asarray(points, dtype=np.float64))

    def with_tmax(self, tmax) -> SystemSectionMap:
        """This map with the time budget ``tmax`` of one return (its lift and domain kept)."""
        out = copy.copy(self)
        out.tmax = validation.real("tmax", tmax, 0.0, lo_open=True)
        return out

    def with_tol(self, tol) -> SystemSectionMap:
        """This map with the Taylor tolerance ``tol`` of its returns (itself at its own)."""
        if tol == self.tol:
            return self
        return SystemSectionMap(self.system, self.energy_value, **dict(self._settings(), tol=tol))

    def require_reversor(self, what: str):
        """The first of :attr:`reversors`; ParameterError naming ``what`` needs it when there is none."""
        if self.reversors:
            return self.reversors[0]
        why = ("declares no reversor (System(..., reversor={...}))" if not self.system.reversors else
               f"has no reversor that maps the section {self.section.expr} = 0, crossed with direction "
               f"{self.direction:+d}, to itself")
        raise ParameterError(f"{what} needs a reversor of the map: {self.system.name} {why}")

    # ------------------------------------------------------------------ crossings
    @property
    def columns(self) -> tuple:
        """The columns (t, a, b, solve, E - E0) of a row of the map's crossings (t, state, E - E0)."""
        return (0, *(1 + i for i in self._index[:3]), -1)

    def crossings(self, points, *, n_crossings: int, section=None, **kw):
        """The arguments of the Crossings of the orbits from ``points``: the System's crossings of
        this map's section and direction from :meth:`states`, at its ``tol``; settings add the energy,
        coords and solve."""
        out = system_crossings(**self._crossing_args(points, n_crossings, section, kw))
        settings = dict(out[-1], energy=self.energy_value, coords=[s.name for s in self.coords],
                        solve=self.solve.name)
        return (*out[:-1], settings)

    def iter_crossings(self, points, *, n_crossings: int, section=None, **kw):
        """:meth:`crossings` in blocks (``explorer.iter_crossings(smap, points, n_crossings=K, block=...)``):
        the System's stream (:func:`~explorer.analysis.system_sections.iter_system_crossings`), the same rows."""
        return iter_system_crossings(**self._crossing_args(points, n_crossings, section, kw))

    def _crossing_args(self, points, n_crossings, section, kw) -> dict:
        """The System's crossings' arguments for the orbits from ``points``: this map's section, direction and
        tol, the states from :meth:`states`."""
        if kw.get("backward"):
            raise ParameterError("crossings of a SectionMap: backward= is not for a map; its preimages are "
                                 "smap.images(points, n, backward=True)")
        given = [k for k in ("section", "direction", "states", "tol") if (k == "section" and section is not None)
                 or k in kw]
        if given:
            raise refused_beside("crossings", given)
        return dict(kw, system=self.system, states=self.states(points), n_crossings=n_crossings,
                    section=self.section.expr, direction=self.direction, tol=self.tol)
