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

A point where no real root has that sign is refused (ParameterError naming the point and E). A
System's map has 4 state variables (2 degrees of freedom): coords, solve and fixed.

:meth:`SystemSectionMap.crossings` is what ``explorer.crossings(smap, points, n_crossings=K)``
runs: the points lifted to states, then the System's crossings of the map's section and direction.
"""
from __future__ import annotations

import numbers

import numpy as np

from explorer.analysis.system_sections import is_system, linear_section, system_crossings
from explorer.model import ParameterError, validation

__all__ = ["SystemSectionMap"]

#: (content hash, section, coords, solve, fixed) -> the lambdified roots, fixed, energy, dH/dsolve, ds/dt
_SOLUTIONS: dict = {}
#: a root is real where its imaginary part is at most this times max(1, |root|)
REAL_TOL = 1e-12


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
    ``solve``; fixed(a, b, c, *P); energy(*state, *P); dH/dsolve(*state, *P); ds/dt(*state, *P)."""
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
    roots = sp.solve(level, solve)
    if not roots:
        raise ParameterError(f"sympy finds no solution of energy = E for {solve.name} on the section "
                             f"{section} = 0: choose another solve")
    sdot = sum(sp.diff(section, s) * f for s, f in zip(system.states, system.rhs))
    args_point = [a, b, E, *pars]
    args_state = [*system.states, *pars]
    out = (sp.lambdify(args_point, roots, modules="numpy"),
           sp.lambdify([a, b, solve, *pars], fixed_expr, modules="numpy"),
           sp.lambdify(args_state, system.energy, modules="numpy"),
           sp.lambdify(args_state, sp.diff(system.energy, solve), modules="numpy"),
           sp.lambdify(args_state, sdot, modules="numpy"))
    _SOLUTIONS[key] = out
    return out


class SystemSectionMap:
    """The section map of ``system`` on its energy level ``energy_value``: points ``(a, b)`` of
    ``coords`` on ``section = 0``, crossed in ``direction``; ``solve`` from the energy (module
    docstring).  ``states(points)`` lifts points; ``explorer.crossings(smap, points,
    n_crossings=K)`` iterates the map."""

    def __init__(self, system, energy_value, *, section=None, direction=1, coords=None, solve=None):
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

    def __repr__(self):
        a, b = self.coords
        return (f"SectionMap({self.system.name}, {self.energy_value!r}, section={self.section.expr}, "
                f"direction={self.direction:+d}, coords=({a.name}, {b.name}), solve={self.solve.name})")

    def states(self, points) -> np.ndarray:
        """The states (N, 4) of the section points (N, 2), in the system's state order; ParameterError
        for a point where the energy level has no solution on the direction's branch."""
        try:
            pts = np.atleast_2d(np.asarray(points, dtype=np.float64))
        except (TypeError, ValueError):
            raise ParameterError(f"points must be (a, b) pairs (N, 2), got {points!r}") from None
        a, b = self.coords
        if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 1 or not np.all(np.isfinite(pts)):
            raise ParameterError(f"the points of a System's section map are finite ({a.name}, {b.name}) pairs "
                                 f"(N, 2); got {points!r}")
        roots_of, fixed_of, energy, dH, sdot = self._lift
        P = list(self.system.parameter_array())
        E = self.energy_value
        A, B = pts[:, 0], pts[:, 1]
        with np.errstate(all="ignore"):
            roots = [np.broadcast_to(np.asarray(r, dtype=np.complex128), A.shape)
                     for r in roots_of(A.astype(np.complex128), B.astype(np.complex128), E, *P)]
        out = np.full(pts.shape[0], np.nan)
        rate = np.zeros(pts.shape[0])
        n = self.system.dimension
        Y = np.empty((pts.shape[0], n))
        for r in roots:
            real = np.isfinite(r) & (np.abs(r.imag) <= REAL_TOL * np.maximum(1.0, np.abs(r.real)))
            C = self._polish(A, B, np.where(real, r.real, 0.0), P)
            state = self._assemble(A, B, C, P)
            with np.errstate(all="ignore"):
                s = np.broadcast_to(np.asarray(sdot(*state.T, *P), dtype=np.float64), A.shape)
            take = real & (np.sign(s) == self.direction) & np.isnan(out)
            out[take] = C[take]
            rate[take] = s[take]
            Y[take] = state[take]
        bad = np.flatnonzero(np.isnan(out))
        if bad.size:
            i = int(bad[0])
            raise ParameterError(
                f"the energy level E = {E!r} has no solution for {self.solve.name} at ({a.name}, {b.name}) = "
                f"({float(A[i])!r}, {float(B[i])!r}) with d({self.section.expr})/dt of sign {self.direction:+d}: "
                "the point lies outside the energy surface on the section (or on its boundary)")
        return Y

    def _assemble(self, A, B, C, P) -> np.ndarray:
        """The states from coords (A, B), solve C and the section's fixed variable."""
        ia, ib, ic, jf = self._index
        Y = np.empty((A.shape[0], self.system.dimension))
        Y[:, ia], Y[:, ib], Y[:, ic] = A, B, C
        Y[:, jf] = np.broadcast_to(np.asarray(self._lift[1](A, B, C, *P), dtype=np.float64), A.shape)
        return Y

    def _polish(self, A, B, C, P) -> np.ndarray:
        """One Newton step on energy(solve) = E where it lowers ``|H - E|`` (a root's closed form may
        lose digits)."""
        _, _, energy, dH, _ = self._lift
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

    def crossings(self, points, *, n_crossings: int, section=None, **kw):
        """The arguments of the Crossings of the orbits from ``points``: the System's crossings of
        this map's section and direction from :meth:`states`; settings add the energy, coords and
        solve."""
        if section is not None or "direction" in kw or "states" in kw:
            given = [k for k in ("section", "direction", "states") if (k == "section" and section is not None)
                     or k in kw]
            raise ParameterError(f"crossings of a SectionMap: {', '.join(given)} belong(s) to the map (or are its "
                                 "points); do not give them beside it")
        out = system_crossings(self.system, self.states(points), n_crossings=n_crossings,
                               section=self.section.expr, direction=self.direction, **kw)
        settings = dict(out[-1], energy=self.energy_value, coords=[s.name for s in self.coords],
                        solve=self.solve.name)
        return (*out[:-1], settings)

    def iterate(self, x, n: int) -> np.ndarray:
        """x and its first ``n`` images under the map: an (n + 1, 2) array (ParameterError when the
        orbit stops sooner)."""
        n = validation.integer("n", n, 1)
        data, count, status, *_ = self.crossings([x], n_crossings=n)
        if count[0] < n:
            from explorer.kernels import STATUS_NAMES

            raise ParameterError(f"section map of {self.system.name} from {tuple(x)}: {int(count[0])} of {n} "
                                 f"returns ({STATUS_NAMES[int(status[0])]})")
        cols = [1 + self.system.states.index(s) for s in self.coords]
        return np.vstack([np.asarray(x, dtype=np.float64)[None, :], data[0][:, cols]])
