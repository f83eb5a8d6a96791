"""Fixed points of the section map, their stability, continuation, and separatrices.

The section map P: (p1, p2) -> (p1', p2') sends a point of phi = phi0 on the energy level h
(M > 0 from the energy, MODEL.md R9) to the next crossing with dphi/dt > 0.  Its Jacobian
comes from the tangent dynamics (variational Taylor series, :func:`explorer.integrate.tangent.return_map_taylor`),
not from finite differences:

    DP = Pi (I - f grad(g)^T / (grad(g) . f)) DPhi_T L

where L lifts (dp1, dp2) to the energy shell (dM = -(H_p1 dp1 + H_p2 dp2) / H_M, dg = 0),
DPhi_T is the flow's tangent map up to the crossing time T, the bracket corrects for the
change of T (g = sin(phi - phi0)), and Pi keeps (p1, p2).  At a fixed point det DP = 1 (the
map preserves area in these coordinates up to a constant factor that cancels at a fixed
point); |trace| < 2 is stable (elliptic), > 2 unstable (hyperbolic).

Newton's method solves P(x) = x with (DP - I); continuation steps a parameter and detects
where |trace| crosses 2 (bisection to the bifurcation value).  Separatrices of a hyperbolic
point: a fundamental domain along the unstable (stable) eigenvector iterated forward
(backward in time), with points inserted where consecutive images are far apart, so the
curves stay smooth (Parker & Chua, Practical Numerical Algorithms for Chaotic Systems, 1989,
Sec. 6; Krauskopf et al., Int. J. Bifurc. Chaos 15 (2005) 763).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from explorer import model
from explorer.analysis.lyapunov import energy_gradient
from explorer.integrate.tangent import return_map_taylor
from explorer.kernels import STATUS_DONE, STATUS_NAMES
from explorer.kernels.taylor import order_for_tolerance
from explorer.model import ParameterError, validation
from explorer.model.equations import rhs

NEWTON_TOL = 1e-12
NEWTON_MAX_ITER = 30
#: residual |P(x) - x| accepted when Newton's steps stall (parabolic points)
ACCEPT_RESIDUAL = 1e-9
#: continuation: a failed step is split in two at most this many times
MAX_HALVINGS = 8
DEFAULT_TOL = 1e-15
#: time budget of one return of the map
RETURN_TMAX = 1e3


@dataclass(frozen=True)
class MapResult:
    point: np.ndarray      # (p1, p2) image
    jacobian: np.ndarray   # 2x2
    time: float            # signed return time
    state: np.ndarray      # full state at the crossing


class SectionMap:
    """The section map at fixed parameters, energy and section angle (Taylor method)."""

    def __init__(self, params, h, *, phi0=math.pi, tol=DEFAULT_TOL, tmax=RETURN_TMAX):
        self.params = params if isinstance(params, model.Params) else model.Params.from_array(params)
        self.P = self.params.as_array()
        self.h = float(h)
        self.phi0 = phi0
        g1, g2 = model.section_gamma(phi0)
        self.sphi, self.cphi = g1, g2
        from explorer.analysis.sections import MAX_TOL, MIN_TOL

        self.order = order_for_tolerance(validation.real("tol", tol, MIN_TOL, MAX_TOL))
        self.tmax = tmax

    def state(self, x):
        return model.section_state(self.params, [x[0]], [x[1]], self.h, self.phi0)[0]

    def lift(self, y):
        """Tangent vectors on the energy shell for dp1 = 1 and dp2 = 1 (dg = 0)."""
        gH = energy_gradient(self.P, y)
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
                                      self.tmax, self.order, 10**8, yout, Vout)
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


@dataclass(frozen=True)
class FixedPoint:
    """A fixed point of the section map P (phi = phi0, MODEL.md R9) and its linear stability.

    Attributes
    ----------
    point : ndarray (2,)
        (p1, p2) with P(point) = point (Newton residual ``residual``).
    jacobian : ndarray (2, 2)
        DP at the point, from the tangent dynamics (variational equations of R3) projected on
        the section; area-preserving, so ``det`` = 1 up to the integration error.
    eigenvalues : ndarray (2,)
        Eigenvalues of ``jacobian``; ``trace`` their sum. ``|trace| < 2``: elliptic (``stable``),
        ``|trace| > 2``: hyperbolic.
    period_time : float
        Return time of the periodic orbit through the point.
    iterations : int
        Newton iterations taken.
    """

    point: np.ndarray
    jacobian: np.ndarray
    eigenvalues: np.ndarray
    trace: float
    det: float
    period_time: float
    iterations: int
    residual: float
    params: model.Params = None
    h: float = float("nan")

    @property
    def stable(self) -> bool:
        return abs(self.trace) < 2.0

    @property
    def kind(self) -> str:
        return "elliptic (stable)" if self.stable else "hyperbolic (unstable)"

    def as_dict(self):
        ev = [complex(e) for e in self.eigenvalues]
        return {"p1": float(self.point[0]), "p2": float(self.point[1]), "trace": float(self.trace),
                "det": float(self.det), "eigenvalues": [[e.real, e.imag] if e.imag else e.real for e in ev],
                "stable": bool(self.stable), "return_time": self.period_time, "iterations": self.iterations,
                "residual": self.residual}


def find_fixed_point(params, h, guess=(0.0, 0.0), *, phi0=math.pi, tol=DEFAULT_TOL) -> FixedPoint:
    """A fixed point of the section map P of phi = ``phi0`` at energy ``h`` (MODEL.md R9).

    Newton's method on P(x) - x = 0 in (p1, p2), with DP from the tangent dynamics of R3 carried
    to the next crossing (the Taylor return map, :func:`explorer.integrate.tangent.return_map_taylor`)
    and projected on the section; steps halved when the residual grows. At mu = 0 the central
    fixed point is solution I of R6, with the eigenvalues of its linearisation.

    Parameters
    ----------
    params : Params
        Model parameters.
    h : float
        Energy level.
    guess : (float, float)
        Start of Newton's method, (p1, p2) inside the allowed region.
    phi0 : float
        Section angle (default pi, the seed's section).
    tol : float
        Taylor tolerance of the return map.

    Returns
    -------
    FixedPoint
        The point, DP, its eigenvalues, trace and determinant, the return time.

    Raises
    ------
    ParameterError
        When Newton's method does not converge from ``guess`` (the message says so).
    """
    smap = SectionMap(params, h, phi0=phi0, tol=tol)
    x = np.array(guess, dtype=float)
    if not model.is_admissible(smap.params, x[0], x[1], h, phi0):
        raise ParameterError(f"guess (p1, p2) = ({x[0]:g}, {x[1]:g}) lies outside the allowed region; allowed: "
                             f"{model.describe_region(smap.params, h, phi0)}")
    for it in range(1, NEWTON_MAX_ITER + 1):
        r = smap(x)
        G = r.point - x
        dx = np.linalg.solve(r.jacobian - np.eye(2), -G)
        # damped step: never leave the allowed region (where the map is defined)
        for _ in range(40):
            if model.section_M2(smap.params, x[0] + dx[0], x[1] + dx[1], h, phi0) > 0:
                break
            dx = 0.5 * dx
        x = x + dx
        if np.max(np.abs(dx)) < NEWTON_TOL * max(1.0, np.max(np.abs(x))):
            break
    r = smap(x)
    if it == NEWTON_MAX_ITER and not np.max(np.abs(r.point - x)) < ACCEPT_RESIDUAL:
        # (near |trace| = 2 the matrix DP - I is nearly singular and Newton converges slowly:
        # a small residual is accepted there)
        raise ParameterError(f"Newton's method did not converge from guess ({guess[0]:.6g}, {guess[1]:.6g}) "
                             f"(last step {np.max(np.abs(dx)):.3g}); try another --guess")
    J = r.jacobian
    ev = np.linalg.eigvals(J)
    return FixedPoint(x, J, ev, float(np.trace(J)), float(np.linalg.det(J)), r.time, it,
                      float(np.max(np.abs(r.point - x))), smap.params, float(h))


@dataclass(frozen=True)
class Branch:
    """A branch of fixed points followed in one parameter by :func:`continue_branch`.

    ``points[i]`` is the :class:`FixedPoint` at ``values[i]`` of ``parameter`` (a model
    parameter or ``"h"``); ``bifurcations`` holds the values where ``|trace| = 2`` (stability
    changes), located by bisection.
    """

    parameter: str
    values: np.ndarray
    points: list
    bifurcations: list = field(default_factory=list)   # parameter values where |trace| = 2


def continuation_values(parameter, start, stop, step) -> np.ndarray:
    """The values start, start + step, ..., up to stop of a continuation in ``parameter`` (a model
    parameter or "h"), validated (ParameterError naming what is allowed)."""
    if parameter not in model.PARAM_NAMES + ("h",):
        raise ParameterError(f"continuation parameter must be one of {', '.join(model.PARAM_NAMES + ('h',))}")
    if step == 0 or not all(math.isfinite(v) for v in (start, stop, step)) or (stop - start) * step < 0:
        raise ParameterError("--continue needs finite START, STOP and a STEP of the sign of STOP - START")
    n = int(math.floor((stop - start) / step + 1e-9)) + 1
    return start + step * np.arange(n)


def secant_follower(solve, guess, state_of, max_halvings):
    """Natural-parameter continuation: returns ``advance(v)``, the solution at parameter value
    ``v`` by ``solve(v, prediction)``, predicted from the last two solutions by a secant (from
    ``guess`` at first); when ``solve`` raises ParameterError the step is halved (the midpoint
    solved first), at most ``max_halvings`` times.  ``state_of(solution)`` is what is predicted
    (a point, or the K points of a periodic orbit)."""
    prev: list = []  # (value, state) of the last two solutions

    def predict(v):
        if len(prev) < 2:
            return prev[-1][1] if prev else guess
        (v0, x0), (v1, x1) = prev[-2], prev[-1]
        return x1 + (x1 - x0) * (v - v1) / (v1 - v0)

    def advance(v, depth=0):
        try:
            sol = solve(v, predict(v))
        except ParameterError:
            if depth >= max_halvings or not prev:
                raise
            advance(0.5 * (prev[-1][0] + v), depth + 1)
            return advance(v, depth + 1)
        prev.append((v, state_of(sol)))
        del prev[:-2]
        return sol

    return advance


def golden_section_max(f, a, b, tol):
    """Maximum of a unimodal f on [a, b] by golden-section search, to ``tol`` relative to
    max(1, |b|); returns (x, f(x))."""
    g = (math.sqrt(5.0) - 1.0) / 2.0
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = f(c), f(d)
    while abs(b - a) > tol * max(1.0, abs(b)):
        if fc > fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = f(d)
    return (c, fc) if fc > fd else (d, fd)


def continue_branch(params, h, parameter, start, stop, step, guess=(0.0, 0.0), *, phi0=math.pi,
                    tol=DEFAULT_TOL, bisect_tol=1e-8) -> Branch:
    """Natural-parameter continuation of a fixed point in any model parameter (or "h").

    From ``start`` to ``stop`` by ``step``, each point from the previous one (secant predictor,
    steps halved on failure); the values where the stability changes (``|trace|`` crosses 2:
    elliptic <-> hyperbolic) are located by bisection to ``bisect_tol`` (relative). For
    Figure 4 (MODEL.md R9, h = 2) the central point turns stable at mu* ~ 2.98316.

    Returns
    -------
    Branch
        The parameter values, the fixed points and the bifurcation values.
    """
    values = continuation_values(parameter, start, stop, step)

    def solve(v, g):
        prm, hh = validation.with_value(params, h, parameter, v)
        return find_fixed_point(prm, hh, g, phi0=phi0, tol=tol)

    points = []
    advance = secant_follower(solve, np.asarray(guess, float), lambda fp: fp.point, MAX_HALVINGS)
    for v in values:
        points.append(advance(v))
    bif = []
    for a, b, fa, fb in zip(values[:-1], values[1:], points[:-1], points[1:]):
        if (abs(fa.trace) < 2) != (abs(fb.trace) < 2):
            lo, hi, flo = a, b, fa
            while hi - lo > bisect_tol * max(1.0, abs(hi)):
                mid = 0.5 * (lo + hi)
                fm = solve(mid, flo.point)
                if (abs(fm.trace) < 2) == (abs(flo.trace) < 2):
                    lo, flo = mid, fm
                else:
                    hi = mid
            bif.append(0.5 * (lo + hi))
    return Branch(parameter, values, points, bif)


# ---------------------------------------------------------------- separatrices
def manifold(fp: FixedPoint, *, stable=False, branch=1, iterations=6, n_domain=60, first=1e-6,
             max_gap=0.02, max_points=20000, phi0=math.pi, tol=1e-14):
    """One branch (+1 or -1 along the eigenvector) of the unstable (stable: backward in time)
    manifold of a hyperbolic fixed point, as an (M, 2) polyline on the section.

    A fundamental domain x* + s e, s in [first, first |lambda|) (log-spaced), is iterated
    ``iterations`` times; wherever two consecutive images are more than ``max_gap`` apart the
    parameter interval is bisected (the new point iterated from scratch), up to max_points."""
    if fp.stable:
        raise ParameterError("the fixed point is elliptic: it has no separatrices")
    smap = SectionMap(fp.params, fp.h, phi0=phi0, tol=tol)
    w, V = np.linalg.eig(fp.jacobian)
    w = np.real(w)
    V = np.real(V)
    i = int(np.argmin(np.abs(w))) if stable else int(np.argmax(np.abs(w)))
    lam = abs(w[i])
    lam_u = max(lam, 1.0 / lam)
    e = V[:, i] / np.linalg.norm(V[:, i]) * branch
    x0 = fp.point

    def images(s):
        """x* + s e and its first ``iterations`` images (n + 1, 2)."""
        out = np.empty((iterations + 1, 2))
        x = x0 + s * e
        out[0] = x
        for k in range(iterations):
            x = smap(x, backward=stable, jacobian=False).point
            out[k + 1] = x
        return out

    s_vals = list(first * np.geomspace(1.0, lam_u, n_domain))
    orbits = [images(v) for v in s_vals]
    # refine: wherever two consecutive points of any image of the fundamental domain are more
    # than max_gap apart, insert the (geometric) midpoint of their parameters
    k = 0
    while k < len(s_vals) - 1 and len(s_vals) < max_points:
        gap = np.max(np.linalg.norm(orbits[k + 1] - orbits[k], axis=1))
        if gap > max_gap and s_vals[k + 1] - s_vals[k] > 1e-13 * s_vals[k]:
            s_mid = math.sqrt(s_vals[k] * s_vals[k + 1])
            s_vals.insert(k + 1, s_mid)
            orbits.insert(k + 1, images(s_mid))
        else:
            k += 1
    # the manifold from the fixed point outwards: image 0 of the domain, then image 1, ...
    curve = np.concatenate([np.array([x0])] + [np.array([o[j] for o in orbits]) for j in range(iterations + 1)])
    return curve


def separatrices(fp: FixedPoint, **kw):
    """The four branches (unstable +-, stable +-) as a list of polylines."""
    return [manifold(fp, stable=s, branch=b, **kw) for s in (False, True) for b in (1, -1)]


def analytic_eigenvalues_solution_I(params, h):
    """MODEL.md R6/R9: at mu = 0 (chi = zeta = 0) the point p = 0 is solution I, M = c = sqrt(2 b h),
    a uniform rotation with return time T = 2 pi b / c.  Linearising R6 about it,
    dp1/dt = alpha p2, dp2/dt = -beta p1 with alpha = c/b - lam/a2, beta = c/b - lam/a1
    (dM is of second order), so the monodromy over T has eigenvalues exp(+-sqrt(-alpha beta) T)
    when alpha beta < 0 (lam b/a1 < c < lam b/a2: hyperbolic) and exp(+-i sqrt(alpha beta) T)
    otherwise."""
    P = params.as_array()
    a1, a2, b, lam = P[0], P[1], P[2], P[3]
    c = math.sqrt(2 * b * h)
    alpha = c / b - lam / a2
    beta = c / b - lam / a1
    T = 2 * math.pi * b / c
    ab = alpha * beta
    if ab < 0:
        k = math.sqrt(-ab) * T
        return np.array([math.exp(k), math.exp(-k)]), 2 * math.cosh(k)
    w = math.sqrt(ab) * T
    return np.array([complex(math.cos(w), math.sin(w)), complex(math.cos(w), -math.sin(w))]), 2 * math.cos(w)


def follow(params, h, parameter, start, stop, guess, *, max_step=0.25, phi0=math.pi, tol=DEFAULT_TOL) -> FixedPoint:
    """The fixed point at ``parameter = stop`` on the branch through the point found near
    ``guess`` at ``parameter = start`` (continuation in steps of at most ``max_step``)."""
    if start == stop:
        prm, hh = validation.with_value(params, h, parameter, start)
        return find_fixed_point(prm, hh, guess, phi0=phi0, tol=tol)
    n = max(1, math.ceil(abs(stop - start) / max_step))
    br = continue_branch(params, h, parameter, start, stop, (stop - start) / n, guess, phi0=phi0, tol=tol)
    return br.points[-1]


def chaotic_fraction(megno, threshold, valid=None):
    """Fraction of orbits with <Y> > threshold among the valid ones, with its binomial standard
    error sqrt(p (1 - p) / n): with seeds on a uniform grid of the allowed region this estimates
    the chaotic fraction of the section's area.  Returns (fraction, error, n)."""
    megno = np.asarray(megno, float)
    ok = np.isfinite(megno) if valid is None else (np.asarray(valid, bool) & np.isfinite(megno))
    n = int(ok.sum())
    if n == 0:
        return float("nan"), float("nan"), 0
    p = float(np.mean(megno[ok] > threshold))
    return p, math.sqrt(max(p * (1 - p), 0.25 / n) / n), n
