"""The section map P of phi = phi0 at energy h with its Jacobian from the tangent dynamics
(docs/model.md R9), and the one rule for the system argument of every analysis (docs/api.md,
"The system argument")."""
from __future__ import annotations

import functools
import inspect
import math
import numbers

import numpy as np

from explorer import model
from explorer.analysis import budget, system_sections
from explorer.analysis.crossings_run import run
from explorer.analysis.flow_lift import lifted_increments
from explorer.analysis.map_result import RETURN_TMAX, FlowSection, MapResult
from explorer.analysis.section_symmetry import grid_seeds, half_turn_partners, half_turn_seeds
from explorer.analysis.symmetry_lines import half_turn_orbit
from explorer.integrate.methods import MAP_TOL, MAX_TOL, MIN_TOL
from explorer.integrate.tangent import return_map_taylor
from explorer.kernels import STATUS_DONE, STATUS_NAMES
from explorer.kernels.taylor import order_for_tolerance
from explorer.model import ParameterError, symmetry, validation, with_value
from explorer.model.equations import rhs

__all__ = ["DEFAULT_TOL", "MAP_SETTINGS", "MAX_STEPS", "RETURN_TMAX", "SEARCH_TMAX", "MapResult", "SectionMap",
           "as_system", "is_params", "not_a_system", "system_first"]

#: Taylor tolerance of the section map: the tightest the order rule allows
DEFAULT_TOL = MAP_TOL
#: step budget of one return of the map (the time budget: RETURN_TMAX)
MAX_STEPS = 10**8
#: a batch of the map with fewer returns (points x n) runs on one thread
SERIAL_RETURNS = 4096
#: time budget of one return in a periodic-orbit search: 8 typical returns (~6.2 at h = 2), the rule of
#: a System's map (explorer.analysis.system_section_map.SEARCH_RETURNS)
SEARCH_TMAX = 50.0


class SectionMap(FlowSection):
    """The section map P of phi = ``phi0`` at energy ``h``: ``smap(x)`` is a :class:`MapResult`
    (P(x), DP(x), the return time); ParameterError for no return within ``tmax``.
    ``SectionMap(system, E, section=, direction=, coords=, solve=)`` with a System is that
    system's map on its energy level E, a :class:`~explorer.analysis.system_section_map.SystemSectionMap`
    (docs/systems.md, "Section map")."""

    #: the integrator of the map, which the analyses given a map use
    method = "taylor"
    #: the time budget of one return in a periodic-orbit search
    search_tmax = SEARCH_TMAX

    def __new__(cls, *args, **kw):
        """A System first gives its section map on an energy level (docs/systems.md, "Section map")."""
        if args and system_sections.is_system(args[0]):
            from explorer.analysis.system_section_map import SystemSectionMap

            return SystemSectionMap(*args, **kw)
        return super().__new__(cls)

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

    def with_value(self, name: str, value) -> SectionMap:
        """This map with one model parameter, or "h", set to ``value``."""
        prm, h = with_value(self.params, self.h, name, value)
        return SectionMap(prm, h, phi0=self.phi0, tol=self.tol, tmax=self.tmax)

    def states(self, points, direction: int = 1) -> np.ndarray:
        """The states (N, 5) of the section points, M's sign from ``direction`` (docs/model.md R9)."""
        pts = np.atleast_2d(np.asarray(points, dtype=np.float64))
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise ParameterError(f"the start points on the section of a map are (p1, p2) pairs (N, 2); got shape "
                                 f"{np.shape(points)}")
        return model.section_state(self.params, pts[:, 0], pts[:, 1], self.h, self.phi0,
                                   direction if direction != 0 else 1)

    def state(self, x):
        """The state (p1, p2, M, g1, g2) of the section point x, M > 0."""
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
        budget.raise_if_cancelled(status)
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

    parameter = "mu"

    @property
    def parameter_value(self) -> float:
        """The value of :attr:`parameter`."""
        return float(getattr(self.params, self.parameter))

    def with_parameter(self, value, name=None) -> SectionMap:
        """:meth:`with_value` of ``name``, default :attr:`parameter`."""
        name = self.parameter if name is None else name
        prm, h = with_value(self.params, self.h, name, value)
        return SectionMap(prm, h, phi0=self.phi0, tol=self.tol, tmax=self.tmax)

    parameters = model.PARAM_NAMES + ("h",)
    periods = (0.0, 0.0)
    #: the columns (t, p1, p2, M, H - H0) of a row of the map's crossings: (t, a, b, solve, E - E0) of docs/systems.md
    columns = (0, 1, 2, 3, 4)

    @property
    def reflection(self):
        """G0, the linear reversor G0 P G0 = P^-1, where it applies; else None."""
        return symmetry.reversor if symmetry.is_reversible(self.params, self.phi0) else None

    @property
    def reversors(self) -> tuple:
        """(G0,) or ()."""
        R = self.reflection
        return () if R is None else (R,)

    def require_reversor(self, what: str):
        """:attr:`reflection`; ParameterError naming ``what`` needs it when there is none."""
        if self.reflection is None:
            raise ParameterError(f"{what} needs a reversor of the map: G0 reverses it only at zeta = xi = 0 on "
                                 f"phi0 = 0 or pi (docs/model.md, \"Symmetries\"); got {self!r}")
        return self.reflection

    def symmetry_line_points(self, n) -> np.ndarray:
        """``n`` points of p2 = 0 (Fix G0) across the allowed region (none without G0)."""
        n = validation.integer("n", n, 1)
        e = model.allowed_ellipse(self.params, self.h, self.phi0)
        if e is None or self.reflection is None:
            return np.empty((0, 2))
        c1, c2, r1, r2 = e
        half = r1 * math.sqrt(max(0.0, 1.0 - (c2 / r2) ** 2)) * (1.0 - 1e-3)     # off the edge M = 0
        return np.column_stack([np.linspace(c1 - half, c1 + half, n), np.zeros(n)])

    def symmetric_seeds(self, period: int, n: int, *, threads=None) -> np.ndarray:
        """Seeds (m, 2) of the symmetric orbits of period ``period``, from ``n`` points of each symmetry
        line (:func:`explorer.analysis.section_symmetry.half_turn_seeds`)."""
        return half_turn_seeds(self, period, n, threads)

    def grid_seeds(self, period: int, grid: int, *, threads=None) -> np.ndarray:
        """The local minima of ``|P^K(x) - x|`` on a ``grid`` x ``grid`` grid, best first
        (:func:`explorer.analysis.section_symmetry.grid_seeds`)."""
        return grid_seeds(self, period, grid, threads)

    def partner_points(self, points, *, threads=None):
        """The images (n, 2) of ``points`` under the half-turn reversor T, which maps an orbit to an orbit
        run backwards, where T is a symmetry (docs/model.md, "Symmetries"); else None."""
        if not symmetry.has_half_turn_symmetry(self.params, self.phi0):
            return None
        return half_turn_partners(self, points, threads).points

    def with_tmax(self, tmax) -> SectionMap:
        """This map with the time budget ``tmax`` of one return."""
        return SectionMap(self.params, self.h, phi0=self.phi0, tol=self.tol, tmax=tmax)

    def with_tol(self, tol) -> SectionMap:
        """This map with the Taylor tolerance ``tol`` of its returns (itself at its own)."""
        return self if tol == self.tol else SectionMap(self.params, self.h, phi0=self.phi0, tol=tol, tmax=self.tmax)

    @property
    def section_label(self) -> float:
        """phi0, which tells this section from :meth:`opposite`'s."""
        return self.phi0

    def opposite(self) -> SectionMap:
        """The map on the section phi = phi0 + pi, half a turn of phi on."""
        return SectionMap(self.params, self.h, phi0=(self.phi0 + math.pi) % (2.0 * math.pi), tol=self.tol,
                          tmax=self.tmax)

    def half_turns(self, X, q: int, threads=None) -> np.ndarray:
        """(p1, p2) (m, 2) of each point of X after ``q`` half-turns of phi: on phi0 for even ``q``, on
        :meth:`opposite`'s section for odd; NaN outside the allowed region or for no crossing; point by
        point on this thread (``threads`` unused)."""
        X = np.asarray(X, float).reshape(-1, 2)
        out = np.full(X.shape, np.nan)
        sections = (model.section_gamma((self.phi0 + math.pi) % (2.0 * math.pi)), model.section_gamma(self.phi0))
        stop = budget.stop_switch()
        none = np.zeros((0, 5))
        for i, x in enumerate(X):
            if not (np.all(np.isfinite(x)) and self.in_domain(x)):
                continue
            y, yout = self.state(x), np.empty(5)
            for j in range(q):
                g1, g2 = sections[j % 2]
                status, _ = return_map_taylor(y, none, self.P, g2, g1, 1.0, self.tmax, self.order, MAX_STEPS, stop,
                                              yout, none)
                if status != STATUS_DONE:
                    budget.raise_if_cancelled(status)     # a cancel is not a point without a return
                    break
                y = yout.copy()
            else:
                out[i] = y[:2]
        return out

    def symmetric_orbit(self, p, q, *, line=None, guess=None):
        """The symmetric orbit of period ``q`` through (``guess``, 0) on p2 = 0 of the half phi0 = ``line``
        (default this map's), shot over its half turns (:func:`explorer.analysis.symmetry_lines.half_turn_orbit`)."""
        return half_turn_orbit(self, p, q, line, guess)

    def value_of(self, name: str) -> float:
        """The value of the parameter ``name`` of :attr:`parameters`."""
        validation.choice("param", name, self.parameters)
        return self.h if name == "h" else float(getattr(self.params, name))

    def in_domain(self, x) -> bool:
        """x lies inside the allowed region, M^2 > 0 (docs/model.md R9)."""
        return bool(model.section_M2(self.params, x[0], x[1], self.h, self.phi0) > 0)

    @property
    def domain(self) -> tuple:
        """((p1_lo, p1_hi), (p2_lo, p2_hi)): the box of the allowed ellipse (docs/model.md R9)."""
        ell = model.allowed_ellipse(self.params, self.h, self.phi0)
        if ell is None or not (ell[2] > 0.0 and ell[3] > 0.0):
            raise ParameterError(f"energy h = {self.h!r}: the allowed region of the section is empty")
        c1, c2, r1, r2 = ell
        return (float(c1 - r1), float(c1 + r1)), (float(c2 - r2), float(c2 + r2))

    def allowed(self, points) -> np.ndarray:
        """Mask (...) of the points (..., 2) inside the allowed region, M^2 > 0 (docs/model.md R9)."""
        pts = np.asarray(points, float)
        with np.errstate(invalid="ignore", over="ignore"):
            return np.asarray(model.section_M2(self.params, pts[..., 0], pts[..., 1], self.h, self.phi0) > 0.0)

    def describe_domain(self) -> str:
        """The allowed region in words."""
        return f"allowed: {model.describe_region(self.params, self.h, self.phi0)}"

    def not_finite(self, x) -> str:
        """Why DP is not finite at x."""
        p = self.params
        return (f"the section map's Jacobian is not finite at (p1, p2) = ({x[0]:.6g}, {x[1]:.6g}): the tangent "
                f"dynamics overflow at lam = {p.lam:g}, mu = {p.mu:g}, h = {self.h:g} (the motion is too fast)")

    def orbit_fields(self) -> dict:
        """What names the map in a PeriodicOrbit: ``params``, ``h``, ``phi0``."""
        return {"params": self.params, "h": self.h, "phi0": self.phi0}

    def images(self, X, n, *, backward=False, threads=None) -> np.ndarray:
        """The first ``n`` images (preimages with ``backward``) of each point of X: (m, n, 2), NaN from
        a failure; one batch of the lanes on ``threads`` (backward through G0), else point by point."""
        X = np.asarray(X, float).reshape(-1, 2)
        out = np.full((X.shape[0], n, 2), np.nan)
        G = self.reflection
        if n and X.size and (G is not None or not backward):
            Y = G(X) if backward else X
            with np.errstate(invalid="ignore"):
                ok = model.section_M2(self.params, Y[:, 0], Y[:, 1], self.h, self.phi0) > 0
            if ok.any():
                c = run(self.params, self.states(Y[ok]), n_crossings=n, phi0=self.phi0, tol=self.tol,
                        tmax=self.tmax * n, threads=1 if int(ok.sum()) * n < SERIAL_RETURNS else threads)
                img = np.array(c.data[:, :n, 1:3], float)
                for i in range(len(img)):
                    img[i, c.count[i]:] = np.nan
                out[ok] = G(img) if backward else img
            return out
        for i, x in enumerate(X):
            if not np.all(np.isfinite(x)):
                continue
            try:
                out[i] = self.iterate(x, n, backward=backward)[1:]
            except ParameterError:
                for j in range(n):
                    try:
                        x = self(x, backward=backward, jacobian=False).point
                    except ParameterError:
                        break
                    out[i, j] = x
        return out

    def lifted_increments(self, starts, center, n, threads=None):
        """(increments (m, n) around ``center``, returns reached, status names, lifted) of the orbits from
        ``starts``, lifted through the flow (:func:`explorer.analysis.flow_lift.lifted_increments`); the section
        has no angle coordinate, so ``center`` is required."""
        if center is None:
            raise ParameterError("the section map has no angle coordinate: give center=(p1, p2), the point the "
                                 "rotation turns around (e.g. an elliptic fixed point)")
        return lifted_increments(self.params, self.h, np.atleast_2d(np.asarray(starts, float)),
                                 np.asarray(center, float), n, self.phi0, self.tol, threads)

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


MAP_SETTINGS = ("phi0", "tol", "tmax")


def is_params(system) -> bool:
    """True for model parameters (Params or the packed vector)."""
    if isinstance(system, model.Params):
        return True
    try:
        return isinstance(system, (np.ndarray, list, tuple)) and np.shape(system) == (model.N_PARAMS,)
    except ValueError:   # a ragged sequence
        return False


def as_system(name: str, system, args: tuple, kw: dict, settings: tuple = MAP_SETTINGS, defaults=None,
              flow: bool = False, systems: bool = False):
    """The one rule for the system argument of an analysis ``name``: ``(system, args, kw)`` with
    the system a map object.  A System or a System's map is refused unless ``systems`` (the
    analysis takes them: they pass unchanged; ``systems="map"``: a System's map only)."""
    if systems and (system_sections.is_system(system) or system_sections.is_system_map(system)):
        if systems == "map" and system_sections.is_system(system):
            raise ParameterError(f"{name} takes a map: give the System's section map, SectionMap(system, E, "
                                 "section=..., direction=..., coords=..., solve=...) (docs/systems.md)")
        return system, args, kw
    system_sections.refuse_a_system(name, system)
    if flow:
        states = kw.pop("states", None)
        if states is not None:
            if not is_params(system):
                raise ParameterError(f"{name}: states= are the flow's start, given with the model parameters alone "
                                     f"({name}(params, states=...)); a map takes section points (p1, p2)")
            if args or "h" in kw:
                raise ParameterError(f"{name}(params, states=...): the flow has no energy h and no section points; "
                                     "give either states= or h and points")
            return system, (states,), kw
        if is_params(system) and "h" not in kw and args and not isinstance(args[0], numbers.Real):
            raise ParameterError(f"{name}(params, ...): the next positional argument is the energy h; give the "
                                 f"flow's full states as states= ({name}(params, states=...))")
    if is_params(system):
        if "h" in kw:
            h = kw.pop("h")
        elif args:
            h, args = args[0], args[1:]
        else:
            raise ParameterError(f"{name}(params, h, ...): h is missing")
        given = dict(defaults or {}, **{k: kw.pop(k) for k in settings if k in kw})
        return SectionMap(system, h, **given), args, kw
    given = [k for k in ("h", *settings) if k in kw and hasattr(system, k)]     # the map's own settings
    if given:
        raise ParameterError(f"{name}: {', '.join(given)} belong(s) to the SectionMap; do not give them "
                             "beside it")
    if "tmax" not in settings and getattr(system, "tmax", RETURN_TMAX) != RETURN_TMAX:
        raise ParameterError(f"{name} has no return budget of the map: use a SectionMap with the default "
                             f"tmax ({RETURN_TMAX:g}), got {system.tmax!r}")
    return system, args, kw


def not_a_system(hint: str):
    """Refuse a System or its map in the decorated analysis, pointing to ``hint`` (docs/systems.md)."""

    def wrap(fn):
        @functools.wraps(fn)
        def call(system, *args, **kw):
            if system_sections.is_system(system) or system_sections.is_system_map(system):
                raise ParameterError(f"{fn.__name__} is for Chaplygin's model; of a System, {hint} (docs/systems.md)")
            return fn(system, *args, **kw)

        return call

    return wrap


def system_first(fn=None, *, settings: tuple = MAP_SETTINGS, defaults=None, flow: bool = False,
                 systems: bool = False):
    """Let an analysis ``fn(system, ...)`` of a map also take ``params, h`` with the map's
    ``settings`` as keywords (``defaults`` where its purpose has its own; ``flow``: ``params,
    states=``; ``systems``: a System or its map passes unchanged): :func:`as_system`."""

    def wrap(fn):
        @functools.wraps(fn)
        def call(system, *args, **kw):
            system, args, kw = as_system(fn.__name__, system, args, kw, settings, defaults, flow, systems)
            return fn(system, *args, **kw)

        sig = inspect.signature(fn)
        ps = list(sig.parameters.values())
        extra = [inspect.Parameter(k, inspect.Parameter.KEYWORD_ONLY, default=None) for k in settings
                 if k not in sig.parameters]
        if flow:   # the flow gives states= instead of the points
            ps = [ps[0], ps[1].replace(default=None), *ps[2:]]
            if "states" not in sig.parameters:   # fn names it when a System's states reach it (systems=True)
                extra.append(inspect.Parameter("states", inspect.Parameter.KEYWORD_ONLY, default=None))
        tail = [p for p in ps if p.kind == inspect.Parameter.VAR_KEYWORD]
        call.__signature__ = sig.replace(parameters=[p for p in ps if p not in tail] + extra + tail)
        note = (f"    The system first (docs/api.md, \"The system argument\"): a SectionMap, or ``params, h`` "
                f"with {', '.join(f'``{k}=``' for k in settings)} for its settings"
                + (", or the flow: ``params, states=`` full states." if flow else "."))
        doc = fn.__doc__ or ""
        head, sep, rest = doc.partition("\n\n")
        call.__doc__ = head + "\n\n" + note + (sep + rest if sep else "\n")
        return call

    return wrap if fn is None else wrap(fn)
