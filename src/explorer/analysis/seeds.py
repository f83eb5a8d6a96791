"""Initial conditions on the section (docs/model.md R9, docs/scenes.md ``[seeds]``), in units
(u, v) of the allowed ellipse scaled by the margin s: p1 = c1 + s r1 u, p2 = c2 + s r2 v, kept
where u^2 + v^2 <= 1 (< 1 for grid and random) and M^2 > 0 (dropped points are counted).  ``grid``:
the square lattice of spacing d0 * 1.001^k (d0 = sqrt(pi/n), |k| <= 150) whose count is closest
to n, row-major; ``random``: uniform in the area from ``default_rng(seed)``; ``lines``: n points
per segment, ends included (the midpoint when n = 1); ``points``: absolute (p1, p2), no margin.
"""
from __future__ import annotations

import math

import numpy as np

from explorer import model
from explorer.model import ParameterError

#: the lattice spacings tried for a grid of about n points: d0 * GRID_SCAN_RATIO**k, |k| <= GRID_SCAN_HALF
GRID_SCAN_RATIO = 1.001
GRID_SCAN_HALF = 150
#: what seed_points reads of a seeds specification
SEED_ATTRIBUTES = ("kind", "n", "margin", "seed", "lines", "points")


def _grid_count(d: float) -> int:
    """Number of lattice points (i d, j d) with (i d)^2 + (j d)^2 < 1 (the selection rule)."""
    k = int(math.floor(1.0 / d)) + 1
    q = (np.arange(-k, k + 1) * d) ** 2
    return int(np.searchsorted(np.sort(q), 1.0 - q, side="left").sum())


def grid_spacing(n: int) -> float:
    """Lattice spacing d (in units of the scaled semi-axes) of a grid of about n points."""
    d0 = math.sqrt(math.pi / n)
    keyed = ((abs(_grid_count(d0 * GRID_SCAN_RATIO ** k) - n), abs(k), k) for k in
             range(-GRID_SCAN_HALF, GRID_SCAN_HALF + 1))
    return d0 * GRID_SCAN_RATIO ** min(keyed)[2]


def _unit_grid(n: int):
    d = grid_spacing(n)
    k = int(math.floor(1.0 / d)) + 1
    u = np.arange(-k, k + 1) * d
    uu = u * u
    inside = uu[None, :] + uu[:, None] < 1.0     # [j, i]: row j is v = u[j]
    U, V = np.meshgrid(u, u)
    return U[inside], V[inside]


def seed_points(seeds, params, h: float, phi0: float = math.pi):
    """Initial points (p1, p2) strictly inside the allowed region of the section phi = phi0
    at energy h (docs/model.md R9), following ``seeds`` (rules in the module docstring)."""
    missing = [k for k in SEED_ATTRIBUTES if not hasattr(seeds, k)]
    if missing:
        raise TypeError(f"seeds must have the attributes {', '.join(SEED_ATTRIBUTES)} (a SeedSpec); "
                        f"{type(seeds).__name__} lacks {', '.join(missing)}")
    h = float(h)
    phi0 = float(phi0)
    ell = model.allowed_ellipse(params, h, phi0)
    if ell is None or not (ell[2] > 0.0 and ell[3] > 0.0):
        raise ParameterError(f"scene key 'energy.h' = {h!r}: the allowed region of the section phi0 = {phi0!r} "
                         f"is empty; cannot place seeds")
    c1, c2, r1, r2 = ell
    s = seeds.margin
    n_dropped = 0
    if seeds.kind == "points":
        pts = np.array(seeds.points, dtype=np.float64).reshape(-1, 2)
        p1, p2 = pts[:, 0].copy(), pts[:, 1].copy()
    else:
        if seeds.kind == "grid":
            u, v = _unit_grid(seeds.n)
        elif seeds.kind == "random":
            rng = np.random.default_rng(seeds.seed)
            rho = np.sqrt(rng.random(seeds.n))
            theta = 2.0 * math.pi * rng.random(seeds.n)
            u, v = rho * np.cos(theta), rho * np.sin(theta)
        else:
            t = np.linspace(0.0, 1.0, seeds.n) if seeds.n > 1 else np.array([0.5])
            seg = np.array(seeds.lines, dtype=np.float64).reshape(-1, 4)
            u = (seg[:, 0:1] + t[None, :] * (seg[:, 2:3] - seg[:, 0:1])).ravel()
            v = (seg[:, 1:2] + t[None, :] * (seg[:, 3:4] - seg[:, 1:2])).ravel()
            keep = u * u + v * v <= 1.0
            n_dropped += int(u.size - np.count_nonzero(keep))
            u, v = u[keep], v[keep]
        p1 = c1 + (s * r1) * u
        p2 = c2 + (s * r2) * v
    with np.errstate(over="ignore", invalid="ignore"):
        m2 = model.section_M2(params, p1, p2, h, phi0)
    keep = m2 > 0.0
    n_dropped += int(p1.size - np.count_nonzero(keep))
    return (np.ascontiguousarray(p1[keep], dtype=np.float64),
            np.ascontiguousarray(p2[keep], dtype=np.float64), n_dropped)
