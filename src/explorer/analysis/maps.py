"""Area-preserving maps: the protocol the map analyses ask (docs/greene.md, "The map protocol")
and Chirikov's standard map (S1) with its reversors (docs/greene.md, "The standard map and its
sign convention")."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from explorer._jit import njit
from explorer.analysis.flow_lift import WRAP_SAFE
from explorer.analysis.greene_core import MIN_Q, Residue
from explorer.analysis.map_result import MapResult
from explorer.model import ParameterError, validation

__all__ = ["AreaPreservingMap", "StandardMap", "SymmetricOrbit", "angle_increments", "difference", "grid_minima",
           "has_angle", "images", "orbit_turns", "reduce", "returns_increments", "with_value"]


@runtime_checkable
class AreaPreservingMap(Protocol):
    """What an analysis of an area-preserving map asks of it (docs/greene.md, "The map protocol")."""

    parameter: str
    parameters: tuple
    periods: tuple         # of each coordinate, 0: not periodic

    def __call__(self, x, *, backward: bool = False, jacobian: bool = True) -> MapResult: ...

    def jacobian(self, x) -> np.ndarray: ...

    def inverse(self, x) -> np.ndarray: ...

    def iterate(self, x, n, *, backward: bool = False) -> np.ndarray: ...

    @property
    def parameter_value(self) -> float: ...

    def with_parameter(self, value): ...

    def with_value(self, name: str, value): ...

    def images(self, X, n, *, backward: bool = False, threads=None) -> np.ndarray: ...

    @property
    def reversors(self) -> tuple: ...

    @property
    def reflection(self): ...

    def in_domain(self, x) -> bool: ...

    def describe_domain(self) -> str: ...

    def not_finite(self, x) -> str: ...

    def require_reversor(self, what: str): ...

    def orbit_fields(self) -> dict: ...

    def with_tmax(self, tmax): ...

    @property
    def search_tmax(self) -> float: ...

    def symmetric_seeds(self, period: int, n: int, *, threads=None) -> np.ndarray: ...

    def grid_seeds(self, period: int, grid: int, *, threads=None) -> np.ndarray: ...

    def partner_points(self, points, *, threads=None): ...

    def lifted_increments(self, starts, center, n, threads=None) -> tuple: ...

    def symmetric_orbit(self, p, q, *, line=None, guess=None): ...

    def generating_function(self, theta, theta_next): ...

    def own_indicators(self, points, settings: dict): ...


def with_value(system, name: str, value):
    """The map with its parameter ``name`` set to ``value``."""
    return system.with_value(name, value)


def _periods(system) -> np.ndarray:
    return np.asarray(system.periods, float)


def has_angle(system) -> bool:
    """The map's first coordinate is an angle (``periods[0] > 0``): types of orbits are counted by its lift."""
    return bool(_periods(system)[0] > 0)


def reduce(system, x) -> np.ndarray:
    """Points ``x`` (..., 2) with each periodic coordinate reduced to [0, period)."""
    y = np.array(x, dtype=float, copy=True)
    for i, L in enumerate(_periods(system)):
        if L > 0:
            y[..., i] = np.mod(y[..., i], L)
    return y


def difference(system, a, b) -> np.ndarray:
    """a - b with each periodic coordinate taken to (-period/2, period/2]."""
    d = np.asarray(a, float) - np.asarray(b, float)
    for i, L in enumerate(_periods(system)):
        if L > 0:
            d[..., i] -= L * np.round(d[..., i] / L)
    return d


def images(system, X, n: int, *, backward: bool = False, threads=None) -> np.ndarray:
    """The first ``n`` images (preimages with ``backward``) of each point of X (m, 2): (m, n, 2),
    NaN from a failure: the map's own ``images`` (a section map's one batch of the lanes, on ``threads``)."""
    X = np.asarray(X, float).reshape(-1, 2)
    if n == 0 or X.size == 0:
        return np.full((X.shape[0], n, 2), np.nan)
    return system.images(X, n, backward=backward, threads=threads)


def grid_minima(system, K: int, grid: int, threads=None) -> np.ndarray:
    """The centres of a ``grid`` x ``grid`` grid of cells over the map's ``domain`` where
    ``|P^K(x) - x|`` (on its cylinder) has a local minimum, best first; the images on ``threads``."""
    (a0, a1), (b0, b1) = system.domain
    u = (np.arange(grid) + 0.5) / grid
    U, V = np.meshgrid(a0 + (a1 - a0) * u, b0 + (b1 - b0) * u, indexing="ij")
    X = np.column_stack([U.ravel(), V.ravel()])
    img = images(system, X, K, threads=threads)[:, -1]
    R = np.linalg.norm(difference(system, img, X), axis=1).reshape(grid, grid)
    R[~np.isfinite(R)] = np.inf
    pad = np.pad(R, 1, constant_values=np.inf)
    nb = np.stack([pad[1 + di:1 + di + grid, 1 + dj:1 + dj + grid]
                   for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj])
    idx = np.flatnonzero((np.isfinite(R) & (R <= nb.min(axis=0))).ravel())
    idx = idx[np.argsort(R.ravel()[idx])]
    return X[idx]


def angle_increments(points, center):
    """Angle increments around center, each wrapped to (-pi, pi]: (..., n) from (..., n + 1, 2)."""
    th = np.arctan2(points[..., 1] - center[1], points[..., 0] - center[0])
    d = np.diff(th, axis=-1)
    return d - 2.0 * np.pi * np.ceil((d - np.pi) / (2.0 * np.pi))


def _lifted_through_gap(inc):
    """The increments lifted into one window of 2 pi cut in the middle of the largest gap of their
    values mod 2 pi (an invariant circle's increments span less than a turn), when that gap is at
    least the fast path's margin 2 pi - 2 WRAP_SAFE; else None."""
    v = np.sort(np.mod(inc, 2.0 * np.pi))
    gaps = np.diff(np.concatenate([v, [v[0] + 2.0 * np.pi]]))
    k = int(np.argmax(gaps))
    if not gaps[k] >= 2.0 * np.pi - 2.0 * WRAP_SAFE:
        return None
    cut = v[k] + 0.5 * gaps[k]
    return np.mod(inc - cut, 2.0 * np.pi) + cut - 2.0 * np.pi


def _returns_increments(system, x, center, n):
    pts = system.iterate(x, n)
    if center is None:
        return np.diff(pts[:, 0]) * (2.0 * np.pi / _periods(system)[0])
    inc = angle_increments(center + difference(system, pts, center), center)
    return inc if np.all(np.abs(inc) <= WRAP_SAFE) else _lifted_through_gap(inc)


def returns_increments(system, starts, center, n: int) -> tuple:
    """:meth:`AreaPreservingMap.lifted_increments` of a map with no flow to lift through: the angle
    increments of the first ``n`` returns around ``center`` wrapped to (-pi, pi], lifted through the
    largest gap of their values mod 2 pi where one exceeds WRAP_SAFE ("unresolved" where that gap is
    too small); ``center=None``: the increments of the map's angle coordinate (:attr:`periods`), exact."""
    X = np.atleast_2d(np.asarray(starts, float))
    if center is None and not has_angle(system):
        raise ParameterError("center=None needs a map with an angle coordinate (periods); give center=")
    c = None if center is None else np.asarray(center, float)
    if c is not None and (c.shape != (2,) or not np.all(np.isfinite(c))):
        raise ParameterError(f"center must be a finite point, got {center!r}")
    inc = np.full((len(X), n), np.nan)
    status = np.full(len(X), "done", dtype=object)
    for i, x in enumerate(X):
        row = _returns_increments(system, x, c, n)
        if row is None:
            status[i] = "unresolved"
        else:
            inc[i] = row
    return inc, np.full(len(X), n), status, status == "done"


def orbit_turns(system, start, center, n: int) -> float:
    """Turns per return around ``center`` over the first ``n`` returns from ``start`` (the map's
    ``lifted_increments``); ParameterError where the lift is not defined."""
    x, c = np.asarray(start, float), np.asarray(center, float)
    inc, _, status, _ = system.lifted_increments(x[None, :], c, n)
    if status[0] != "done" or not np.all(np.isfinite(inc[0])):
        raise ParameterError(f"the rotation of the orbit from {tuple(x)} around the centre is not defined "
                             f"({status[0]})")
    return float(np.sum(inc[0])) / (2.0 * math.pi * n)


@njit
def standard_orbit(theta, p, k, n, backward, out):
    """The lifted orbit of (S1) from (theta, p): out[j] = T^j (T^-j with ``backward``), j = 0..n."""
    out[0, 0] = theta
    out[0, 1] = p
    for j in range(n):
        if backward:
            theta_prev = theta - p
            p = p - k * math.sin(theta_prev)
            theta = theta_prev
        else:
            p = p + k * math.sin(theta)
            theta = theta + p
        out[j + 1, 0] = theta
        out[j + 1, 1] = p


@njit
def standard_images(X, k, n, backward, out):
    """out[i, j] = T^(j+1)(X[i]) (T^-(j+1) with ``backward``): the first n images of each point."""
    buf = np.empty((n + 1, 2))
    for i in range(X.shape[0]):
        standard_orbit(X[i, 0], X[i, 1], k, n, backward, buf)
        for j in range(n):   # element by element: an array assignment compiles numba's slow shape-error path
            out[i, j, 0] = buf[j + 1, 0]
            out[i, j, 1] = buf[j + 1, 1]


@njit
def standard_half_orbit(theta, p, k, n):
    """(theta_n, p_n, d theta_n / d p, d p_n / d p) of T^n(theta, p): the half-orbit shooting."""
    dth = 0.0
    dp = 1.0
    for _ in range(n):
        kc = k * math.cos(theta)
        dp = dp + kc * dth
        p = p + k * math.sin(theta)
        dth = dth + dp
        theta = theta + p
    return theta, p, dth, dp


@njit
def standard_monodromy(theta, p, k, n):
    """DT(x_{n-1}) ... DT(x_0) as (a, b, c, d) = [[a, b], [c, d]], and (theta_n, p_n)."""
    a, b, c, d = 1.0, 0.0, 0.0, 1.0
    for _ in range(n):
        kc = k * math.cos(theta)
        a, b, c, d = (1.0 + kc) * a + c, (1.0 + kc) * b + d, kc * a + c, kc * b + d
        p = p + k * math.sin(theta)
        theta = theta + p
    return a, b, c, d, theta, p


#: Newton on the half orbit: the step in p relative to max(1, |p|) at convergence, or below the floor
#: once the steps stop shrinking (round-off)
SHOOT_TOL, SHOOT_MAX_ITER, SHOOT_FLOOR = 1e-15, 40, 1e-11
#: the closure after Q steps, relative to max(1, |M|)
CLOSURE_TOL = 1e-9


@dataclass(frozen=True)
class SymmetricOrbit(Residue):
    """A symmetric orbit of type P/Q of the standard map: ``points`` (Q, 2) from theta = ``line``,
    theta lifted; ``closure`` = max |T^Q(x_0) - x_0 - (2 pi P, 0)|."""

    p: int
    q: int
    points: np.ndarray
    monodromy: np.ndarray
    param_value: float
    line: float
    closure: float


def _shoot(k, P, Q, theta0, p0):
    """Newton on the half-orbit equation (docs/greene.md) for the start p0 on theta = theta0."""
    even = Q % 2 == 0
    n = Q // 2 if even else (Q + 1) // 2
    p = float(p0)
    prev = math.inf
    for _ in range(SHOOT_MAX_ITER):
        th, pn, dth, dpn = standard_half_orbit(theta0, p, k, n)
        if even:
            f, df = th - theta0 - math.pi * P, dth
        else:
            f, df = 2.0 * th - pn - 2.0 * theta0 - 2.0 * math.pi * P, 2.0 * dth - dpn
        if not (math.isfinite(f) and math.isfinite(df)) or df == 0.0:
            break
        step = -f / df
        p += step
        scale = max(1.0, abs(p))
        if abs(step) <= SHOOT_TOL * scale or (abs(step) <= SHOOT_FLOOR * scale and abs(step) >= 0.5 * abs(prev)):
            return p
        prev = step
    raise ParameterError(f"no symmetric orbit of type {P}/{Q} on theta = {theta0:g} at k = {k:.12g} "
                         f"(Newton on the half orbit did not converge from p = {p0:.12g})")


def _half_orbit_monodromy(k, Q, theta0, p0) -> np.ndarray:
    """The monodromy from the half orbit's Jacobian A (docs/greene.md): Q = 2n: M = G(z_0) A^-1 G(z_n) A;
    Q = 2n - 1: M = H DT(z_0) A^-1 H A."""
    even = Q % 2 == 0
    n = Q // 2 if even else (Q + 1) // 2
    a, b, c, d, theta_n, _ = standard_monodromy(theta0, p0, k, n)
    A = np.array([[a, b], [c, d]])
    A_inv = np.array([[d, -b], [-c, a]])
    if even:
        G0 = np.array([[-1.0, 0.0], [k * math.cos(theta0), 1.0]])
        Gn = np.array([[-1.0, 0.0], [k * math.cos(theta_n), 1.0]])
        return G0 @ A_inv @ Gn @ A
    H = np.array([[-1.0, 1.0], [0.0, 1.0]])
    kc = k * math.cos(theta0)
    return H @ np.array([[1.0 + kc, 1.0], [kc, 1.0]]) @ A_inv @ H @ A


class StandardMap:
    """Chirikov's standard map (S1) p' = p + k sin(theta), theta' = theta + p', theta lifted."""

    parameter = "k"
    parameters = ("k",)
    reflection = None
    #: the lines theta = const of Fix I0
    I0_LINES = (0.0, math.pi)
    periods = (2.0 * math.pi, 0.0)
    #: an application is one step: no time budget (:meth:`with_tmax`)
    search_tmax = math.inf
    #: the fundamental domain drawn and searched ((theta0, theta1), (p0, p1))
    domain = ((0.0, 2.0 * math.pi), (-math.pi, math.pi))

    def __init__(self, k):
        self.k = validation.real("k", k)

    def __repr__(self):
        return f"StandardMap(k={self.k!r})"

    def __eq__(self, other):
        return isinstance(other, StandardMap) and other.k == self.k

    def __hash__(self):
        return hash(("StandardMap", self.k))

    @property
    def parameter_value(self) -> float:
        return self.k

    def with_parameter(self, value) -> StandardMap:
        """The same map at k = ``value``."""
        return StandardMap(value)

    def with_value(self, name: str, value) -> StandardMap:
        """The same map at k = ``value`` (``name`` must be "k")."""
        if name != self.parameter:
            raise ParameterError(f"StandardMap is continued in its parameter {self.parameter!r}, got {name!r}")
        return StandardMap(value)

    def in_domain(self, x) -> bool:
        """True: the cylinder."""
        return True

    def describe_domain(self) -> str:
        return "the cylinder theta mod 2 pi"

    def allowed(self, points) -> np.ndarray:
        """Mask (...) of the finite points (..., 2): the whole cylinder."""
        return np.all(np.isfinite(np.asarray(points, float)), axis=-1)

    def indicators(self, points, *, tmax, which=("mlce", "megno", "fli"), threads=None, early_stop=False,
                   early_megno=8.0, early_time=100.0, v0=None, history=0, max_steps=None, method=None, tol=None,
                   dt=None, w0=None, phi0=None, h=None) -> dict:
        """The chaos indicators of the orbits from ``points``: :func:`explorer.analysis.map_indicators.
        standard_indicators` (what :func:`explorer.indicators` gives for this map)."""
        from explorer.analysis.map_indicators import standard_indicators

        return standard_indicators(self.k, points, tmax=tmax, which=which, threads=threads, early_stop=early_stop,
                                   early_megno=early_megno, early_time=early_time, v0=v0, history=history,
                                   max_steps=max_steps, flow={"method": method, "tol": tol, "dt": dt, "w0": w0,
                                                              "phi0": phi0, "h": h})

    def own_indicators(self, points, settings: dict) -> dict:
        """:meth:`indicators` with the keywords ``settings``: the map has its own tangent map."""
        return self.indicators(points, **settings)

    def not_finite(self, x) -> str:
        return f"the map's Jacobian is not finite at ({x[0]:.6g}, {x[1]:.6g})"

    def orbit_fields(self) -> dict:
        """What names the map in a PeriodicOrbit: itself."""
        return {"system": self}

    @staticmethod
    def _point(x) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if x.shape != (2,) or not np.all(np.isfinite(x)):
            raise ParameterError(f"a point of the standard map is (theta, p), two finite numbers; got {x!r}")
        return x

    def __call__(self, x, *, backward=False, jacobian=True) -> MapResult:
        th, p = self._point(x)
        out = np.empty((2, 2))
        standard_orbit(th, p, self.k, 1, backward, out)
        y = out[1].copy()
        J: Any = None
        if jacobian:
            J = self._jacobian(y if backward else np.array([th, p]))
            if backward:
                J = np.array([[J[1, 1], -J[0, 1]], [-J[1, 0], J[0, 0]]])   # DT(T^-1 x)^-1, det 1
        return MapResult(y, J, -1.0 if backward else 1.0, y.copy())

    def _jacobian(self, x) -> np.ndarray:
        kc = self.k * math.cos(x[0])
        return np.array([[1.0 + kc, 1.0], [kc, 1.0]])

    def jacobian(self, x) -> np.ndarray:
        """DT(x) = [[1 + k cos theta, 1], [k cos theta, 1]] (det 1)."""
        return self._jacobian(self._point(x))

    def inverse(self, x) -> np.ndarray:
        """T^-1(x): theta = theta' - p', p = p' - k sin(theta)."""
        return self(x, backward=True, jacobian=False).point

    def iterate(self, x, n, *, backward=False) -> np.ndarray:
        """x and its first ``n`` images (preimages with ``backward``): an (n + 1, 2) array."""
        th, p = self._point(x)
        n = validation.integer("n", n, 0)
        out = np.empty((n + 1, 2))
        standard_orbit(th, p, self.k, n, bool(backward), out)
        return out

    def images(self, X, n, *, backward=False, threads=None) -> np.ndarray:
        """The first ``n`` images of each point of X (m, 2): (m, n, 2), one compiled serial loop (``threads``
        unused: an image costs a few operations)."""
        X = np.ascontiguousarray(np.asarray(X, float).reshape(-1, 2))
        n = validation.integer("n", n, 0)
        out = np.empty((X.shape[0], n, 2))
        if n and X.shape[0]:
            standard_images(X, self.k, n, bool(backward), out)
        return out

    def symmetric_orbit(self, p, q, *, line=None, guess=None) -> SymmetricOrbit:
        """The symmetric orbit of type ``p``/``q`` through theta = ``line`` (default pi), Newton on the half
        orbit from p = ``guess`` (default 2 pi p/q) (docs/greene.md, "The half-orbit (symmetry-line) method")."""
        P = validation.integer("p", p, 0)
        Q = validation.integer("q", q, MIN_Q)
        theta0 = math.pi if line is None else validation.real("line", line)
        k = self.k
        p0 = _shoot(k, P, Q, theta0, 2.0 * math.pi * P / Q if guess is None else validation.real("guess", guess))
        pts = self.iterate((theta0, p0), Q)
        M = _half_orbit_monodromy(k, Q, theta0, p0)
        closure = float(max(abs(pts[Q, 0] - theta0 - 2.0 * math.pi * P), abs(pts[Q, 1] - p0)))
        if not closure <= CLOSURE_TOL * max(1.0, float(np.max(np.abs(M)))):
            raise ParameterError(f"the orbit of type {P}/{Q} from theta = {theta0:g} does not close at k = {k:.12g} "
                                 f"(error {closure:.3g}): too far above the breakup for double precision")
        return SymmetricOrbit(P, Q, pts[:Q].copy(), M, float(k), theta0, closure)

    def i0(self, x) -> np.ndarray:
        """I0(theta, p) = (-theta, p + k sin theta): an involution with I0 T I0 = T^-1."""
        x = np.asarray(x, dtype=float)
        y = np.empty_like(x)
        y[..., 0] = -x[..., 0]
        y[..., 1] = x[..., 1] + self.k * np.sin(x[..., 0])
        return y

    def i1(self, x) -> np.ndarray:
        """I1(theta, p) = (p - theta, p): an involution with I1 T I1 = T^-1, and T = I1 I0."""
        x = np.asarray(x, dtype=float)
        y = np.empty_like(x)
        y[..., 0] = x[..., 1] - x[..., 0]
        y[..., 1] = x[..., 1]
        return y

    @property
    def reversors(self) -> tuple:
        """(I0, I1)."""
        return (self.i0, self.i1)

    def require_reversor(self, what: str):
        """I0, a reversor of the map (``what`` needs one: the map always has it)."""
        return self.i0

    def with_tmax(self, tmax) -> StandardMap:
        """This map: an application is one step, with no time budget."""
        return self

    def symmetric_seeds(self, period: int, n: int, *, threads=None) -> np.ndarray:
        """The seeds of symmetric orbits of any period: :meth:`symmetry_line_points`."""
        return self.symmetry_line_points(n)

    def grid_seeds(self, period: int, grid: int, *, threads=None) -> np.ndarray:
        """:func:`grid_minima` over :attr:`domain`."""
        return grid_minima(self, period, grid, threads)

    def lifted_increments(self, starts, center, n, threads=None) -> tuple:
        """The angle increments of the orbits' first ``n`` returns around ``center``
        (:func:`returns_increments`; ``center=None``: of theta, lifted exactly)."""
        return returns_increments(self, starts, center, n)

    def partner_points(self, points, *, threads=None):
        """None: the map's reversors are I0 and I1 (an orbit's image under I1 is its image under I0, moved on
        by one step)."""
        return None

    def generating_function(self, theta, theta_next):
        """F(theta, theta') = (theta' - theta)^2/2 - k cos(theta), with p = -dF/dtheta and p' = dF/dtheta'
        (MacKay, Meiss & Percival 1984)."""
        d = np.asarray(theta_next, float) - np.asarray(theta, float)
        return 0.5 * d * d - self.k * np.cos(theta)

    def symmetry_line_points(self, n) -> np.ndarray:
        """``n`` points on each symmetry line (Fix I0, Fix I1) across :attr:`domain`."""
        n = validation.integer("n", n, 1)
        (_, _), (p0, p1) = self.domain
        p = p0 + (p1 - p0) * (np.arange(n) + 0.5) / n
        lines = [np.column_stack([np.full(n, th), p]) for th in self.I0_LINES]
        lines += [np.column_stack([0.5 * p + shift, p]) for shift in self.I0_LINES]
        return self.wrap(np.concatenate(lines))

    @staticmethod
    def wrap(x) -> np.ndarray:
        """Points with theta reduced to [0, 2 pi)."""
        y = np.array(x, dtype=float, copy=True)
        y[..., 0] = np.mod(y[..., 0], 2.0 * math.pi)
        return y
