"""The searches of the page's check boxes and picks, each giving (found, message) (docs/commands/serve.md)."""
from __future__ import annotations

import math

import numpy as np

from explorer.analysis import rotation
from explorer.analysis.budget import Budget, BudgetExceeded
from explorer.analysis.fixedpoints import find_fixed_point
from explorer.analysis.manifolds import manifolds
from explorer.analysis.periodic import search_periodic_orbits
from explorer.app.serve.orbits import INDICATOR_TIME, orbit_indicators
from explorer.app.serve.style import megno_kind
from explorer.app.serve.tasks import failure

#: the searches' limits (docs/bad_input.md): the periods marked, wall-clock budgets (s), steps per orbit of a
#: crossing batch, and the arclength and budget (s) of each separatrix branch and of each branch of a pick's manifolds
PERIODIC_MAX = 4
FIXED_SECONDS = 30.0
PERIODIC_SECONDS = 60.0
READOUT_SECONDS = 30.0
SEARCH_MAX_STEPS = 100_000
SEPARATRIX_ARCLENGTH = 4.0
SEPARATRIX_MAX_TIME = 4.0
MANIFOLD_ARCLENGTH = 10.0
MANIFOLD_MAX_TIME = 10.0
#: Newton's method and the four branches
MANIFOLD_SECONDS = 4 * MANIFOLD_MAX_TIME + 5.0


def search_budget(seconds: float) -> Budget:
    """The Budget a page's search runs in: ``seconds`` and SEARCH_MAX_STEPS."""
    return Budget(seconds, max_steps=SEARCH_MAX_STEPS)


def _at(p) -> str:
    """``(p1, p2)`` in 4 digits, round-off-sized values as 0."""
    return "(" + ", ".join("0" if abs(float(x)) < 1e-12 else f"{float(x):.4g}" for x in p[:2]) + ")"


def _fixed_points_from(view, first):
    """Lazily, the fixed points Newton's method reaches from ``first``, the region's centre and half-way to its edge."""
    c1, c2, r1, r2 = view.region
    for g in (first, (c1, c2), (c1 - 0.5 * r1, c2), (c1 + 0.5 * r1, c2), (c1, c2 - 0.5 * r2), (c1, c2 + 0.5 * r2)):
        try:
            if view.admissible(*g):
                yield find_fixed_point(view.smap, g)
        except BudgetExceeded:
            raise
        except Exception:  # noqa: BLE001 - no convergence from this guess
            continue


def fixed_points(view) -> tuple:
    """(points, message): the distinct fixed points of :func:`_fixed_points_from` p = 0 (docs/commands/serve.md)."""
    points: list = []
    stopped = ""
    try:
        for fp in _fixed_points_from(view, (0.0, 0.0)):
            if not any(fp.same_orbit(q) for q in points):
                points.append(fp)
    except BudgetExceeded as exc:
        stopped = f": search {exc}"
    found = ", ".join(f"{_at(fp.point)} {'elliptic' if fp.stable else 'hyperbolic'}" for fp in points)
    found = found or "none found (Newton's method from p = 0, the region's centre, half-way to its edge)"
    return points, f"fixed points {found}{stopped}"


def separatrices(view, points) -> tuple:
    """(curves, message): the (M, 2) separatrix branches of the hyperbolic ``points`` (docs/manifolds.md) and what
    they gave (none: "")."""
    curves: list = []
    notes = []
    for fp in (fp for fp in points if not fp.stable):
        at = _at(fp.point)
        try:
            branches = manifolds(view.smap, fp, arclength=SEPARATRIX_ARCLENGTH, max_time=SEPARATRIX_MAX_TIME)
        except BudgetExceeded as exc:
            notes.append(f"separatrices {exc}")
            break
        except Exception as exc:  # noqa: BLE001 - reported in the status line, the other points go on
            notes.append(f"separatrices of {at} failed ({failure(exc)})")
            continue
        curves += [np.asarray(b.points, dtype=np.float64) for b in branches if len(b.points)]
        short = sorted({b.status for b in branches if b.status != "arclength"})
        if short:
            notes.append(f"{at}: some branches stopped short ({', '.join(short)})")
    return curves, "; ".join([f"{len(curves)} separatrix branches", *notes]) if points else ""


def periodic_orbits(view):
    """(orbits, message): the periodic orbits of minimal periods 1..PERIODIC_MAX (docs/commands/serve.md)."""
    orbits, stopped, done = [], "", 0
    for k in range(1, PERIODIC_MAX + 1):
        try:
            orbits += search_periodic_orbits(view.smap, k, grid=8, max_guesses=30)
        except BudgetExceeded as exc:
            stopped = f"; periods {k}-{PERIODIC_MAX} not searched: {exc}"
            break
        except Exception:  # noqa: BLE001 - a failed search marks nothing for this period
            pass
        done = k
    counts = ", ".join(f"K={k}: {sum(o.period == k for o in orbits)} "
                       f"({sum(o.period == k and o.stable for o in orbits)} stable)" for k in range(1, done + 1))
    return orbits, f"periodic orbits {counts}{stopped}"


def elliptic_center(view, start):
    """The first elliptic fixed point Newton's method reaches from ``start``, then the other guesses (or None)."""
    return next((fp for fp in _fixed_points_from(view, tuple(start)) if fp.stable), None)


def orbit_readout(settings, start) -> tuple:
    """(values, message): a picked orbit's megno, mlce, rotation number, its :func:`elliptic_center` (or None)
    and the readout's words (docs/commands/serve.md, "Pick an orbit")."""
    p1, p2 = float(start[0]), float(start[1])
    megno, mlce = orbit_indicators(settings, p1, p2)
    values = {"megno": megno, "mlce": mlce, "rotation": None, "center": None}
    text = f"mLCE = {mlce:.4g}, <Y> = {megno:.4g} over t <= {INDICATOR_TIME:g} ({megno_kind(megno)}); rotation number"
    try:
        fp = values["center"] = elliptic_center(settings, (p1, p2))
        if fp is None:
            return values, f"{text}: none (Newton's method found no elliptic fixed point)"
        rot = values["rotation"] = rotation.rotation_number(rotation_map(settings), (p1, p2), center=fp.point)
    except Exception as exc:  # noqa: BLE001 - shown in the readout (a spent budget too: the indicators stay)
        return values, f"{text}: none ({failure(exc)})"
    if not math.isfinite(rot.value):
        return values, f"{text}: none ({rot.status})"
    return values, (f"{text} {rot.value:.10g} around ({fp.point[0]:.6g}, {fp.point[1]:.6g}) over {rot.iterates} "
                    "returns, " + ("converged" if rot.converged else
                                   f"not converged (|WB_N - WB_2N| = {rot.difference:.2g})"))


def rotation_map(settings):
    """The section map of an orbit's rotation number: Taylor only, at the page's tol, else the rotation's default."""
    return settings.smap.with_tol(float(settings.tol) if settings.method == "taylor" else float(rotation.DEFAULT_TOL))


def saddle_manifolds(settings, point, period=1):
    """(branches, message): W^u then W^s of the hyperbolic orbit of ``period`` through ``point``, grown
    to MANIFOLD_ARCLENGTH (docs/manifolds.md); ParameterError when there is no such orbit."""
    p1, p2 = float(point[0]), float(point[1])
    branches = manifolds(settings.smap, (p1, p2), arclength=MANIFOLD_ARCLENGTH, period=int(period),
                         max_time=MANIFOLD_MAX_TIME)
    npts = sum(len(b.points) for b in branches)
    text = (f"manifolds of the hyperbolic period-{int(period)} orbit at {_at((p1, p2))}: "
            f"{len(branches)} branches (W^u red, W^s blue) to arclength {MANIFOLD_ARCLENGTH:g}, {npts} points")
    return branches, text
