"""What the search for periodic orbits asks of Chaplygin's section map, by its symmetries
(docs/commands/periodic.md): the seeds of symmetric orbits on the lines p2 = 0 of phi0 and
phi0 + pi, the grid minima of |P^K(x) - x| over the allowed ellipse, and the partners under the
half-turn reversor T (docs/model.md, "Symmetries")."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.analysis.crossings_run import run
from explorer.integrate.methods import DEFAULT_TOL as SECTIONS_TOL
from explorer.model import ParameterError, symmetry

__all__ = ["Partners", "grid_seeds", "half_turn_partners", "half_turn_seeds"]

#: time budget of the half-turn flow, per point
TMAX = 1e3
#: |pi - 2 phi0| (mod 2 pi) below which K maps the section phi0 to itself
SAME_SECTION = 1e-15


def _line_p1(params, h, phi0, n):
    e = model.allowed_ellipse(params, h, phi0)
    if e is None:
        return np.empty(0)
    c1, c2, r1, r2 = e
    if abs(c2) > r2:
        return np.empty(0)
    half = r1 * math.sqrt(max(0.0, 1.0 - (c2 / r2) ** 2))
    return c1 + half * np.linspace(-1.0, 1.0, n + 2)[1:-1]


def half_turn_seeds(smap, K: int, n: int, threads=None) -> np.ndarray:
    """Seeds (m, 2) of ``smap``'s symmetric orbits of period K: the roots of p2 after K half-turns
    from ``n`` points of p2 = 0 on phi0 and on phi0 + pi, bracketed and bisected (Newton does the
    rest); none unless G0 reverses the map."""
    prm, h, phi0, tol, tmax = smap.params, smap.h, smap.phi0, smap.tol, smap.tmax
    if not symmetry.is_reversible(prm, phi0):
        return np.empty((0, 2))
    other = phi0 + math.pi

    def turns(p1, line, threads=threads):
        """(p2 after K half-turns, point on phi0) for starts p1 on line 0 or 1 (NaN when stopped)."""
        start_phi = phi0 if line == 0 else other
        Y0 = model.section_state(prm, p1, np.zeros_like(p1), h, start_phi)
        target = phi0 if (K % 2 == 0) == (line == 0) else other
        n_target = (K + line) // 2 if target == phi0 else (K + 1 - line) // 2
        n_target = max(n_target, 1)
        c = run(prm, Y0, n_crossings=n_target, phi0=target, tol=tol, tmax=tmax * n_target, threads=threads)
        f = np.where(c.count >= n_target, c.data[:, n_target - 1, 2], np.nan)
        if line == 0:
            on = np.column_stack([p1, np.zeros_like(p1)])
        else:
            c1 = run(prm, Y0, n_crossings=1, phi0=phi0, tol=tol, tmax=tmax, threads=threads)
            on = np.where((c1.count >= 1)[:, None], c1.data[:, 0, 1:3], np.nan)
        return f, on

    seeds = []
    for line in (0, 1):
        p1 = _line_p1(prm, h, phi0 if line == 0 else other, n)
        if len(p1) < 2:
            continue
        f, _ = turns(p1, line)
        for i in np.flatnonzero(np.isfinite(f[:-1]) & np.isfinite(f[1:]) & (np.sign(f[:-1]) != np.sign(f[1:]))):
            a, b, fa = p1[i], p1[i + 1], f[i]
            for _ in range(16):   # Newton does the rest
                m = 0.5 * (a + b)
                fm, _ = turns(np.array([m]), line, 1)
                if not np.isfinite(fm[0]):
                    break
                if np.sign(fm[0]) == np.sign(fa):
                    a, fa = m, fm[0]
                else:
                    b = m
            _, on = turns(np.array([0.5 * (a + b)]), line, 1)
            if np.all(np.isfinite(on[0])):
                seeds.append(on[0])
    return np.array(seeds).reshape(-1, 2)


def grid_seeds(smap, K: int, grid: int, threads=None) -> np.ndarray:
    """Points of a ``grid`` x ``grid`` grid over the allowed ellipse of ``smap`` where ``|P^K(x) - x|``
    has a local minimum, best first; ParameterError when the region is empty."""
    prm, h, phi0, tol, tmax = smap.params, smap.h, smap.phi0, smap.tol, smap.tmax
    e = model.allowed_ellipse(prm, h, phi0)
    if e is None:
        raise ParameterError(f"the allowed region is empty at h = {h:g}; allowed: "
                             f"{model.describe_region(prm, h, phi0)}")
    c1, c2, r1, r2 = e
    u = np.linspace(-1.0, 1.0, grid + 2)[1:-1]
    U, V = np.meshgrid(c1 + r1 * u, c2 + r2 * u, indexing="ij")
    inside = model.section_M2(prm, U, V, h, phi0) > 0
    R = np.full(U.shape, np.inf)
    if inside.any():
        Y0 = model.section_state(prm, U[inside], V[inside], h, phi0, 1)
        c = run(prm, Y0, n_crossings=K, phi0=phi0, tol=max(tol, SECTIONS_TOL), tmax=tmax * K, threads=threads)
        ok = c.count >= K
        r = np.full(ok.shape, np.inf)
        r[ok] = np.hypot(c.data[ok, K - 1, 1] - U[inside][ok], c.data[ok, K - 1, 2] - V[inside][ok])
        R[inside] = r
    pad = np.pad(R, 1, constant_values=np.inf)
    nb = np.stack([pad[1 + di:1 + di + grid, 1 + dj:1 + dj + grid]
                   for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj])
    ismin = np.isfinite(R) & (R <= nb.min(axis=0))
    idx = np.flatnonzero(ismin.ravel())
    idx = idx[np.argsort(R.ravel()[idx])]
    return np.column_stack([U.ravel()[idx], V.ravel()[idx]])


@dataclass(frozen=True)
class Partners:
    """Result of :func:`half_turn_partners` for n points: the partner ``points`` (n, 2), the ``times``
    (n,) of the flow from K(x) to the section (NaN where it did not get there) and the ``status``
    name of each flow."""

    points: np.ndarray
    times: np.ndarray
    status: tuple


def half_turn_partners(smap, points, threads=None) -> Partners:
    """The partners T(x) of the points x = (p1, p2) ((2,) or (n, 2)) of ``smap``'s section phi = phi0
    at energy h (crossed with dphi/dt > 0) under the half-turn reversor T = (flow to phi0) o K."""
    params, h, phi0, tol = smap.params, smap.h, smap.phi0, smap.tol
    bad = symmetry.half_turn_violations(params)
    if bad:
        raise ParameterError(f"the half-turn is a symmetry only when chi = 0 and mu eta = 0; here {', '.join(bad)}")
    x = np.atleast_2d(np.asarray(points, dtype=np.float64))
    if x.ndim != 2 or x.shape[1] != 2:
        raise ParameterError(f"points must be (p1, p2) or an (n, 2) array, got shape {np.shape(points)}")
    y = symmetry.half_turn_reversor(model.section_state(params, x[:, 0], x[:, 1], h, phi0))
    image = symmetry.half_turn_section(phi0)
    if abs(math.remainder(image - phi0, 2.0 * math.pi)) < SAME_SECTION:
        # K maps the section to itself (phi0 = pi/2 or 3 pi/2): T = K
        return Partners(y[:, :2].copy(), np.zeros(len(x)), ("done",) * len(x))
    c = run(params, y, n_crossings=1, phi0=phi0, tol=tol, threads=threads, tmax=TMAX)
    return Partners(c.data[:, 0, 1:3].copy(), c.data[:, 0, 0].copy(), tuple(c.status_name(i) for i in range(len(x))))
