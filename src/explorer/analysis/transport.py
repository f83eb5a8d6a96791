"""Lobes of a homoclinic tangle and the flux across a broken separatrix (MacKay, Meiss &
Percival 1984, Physica D 13, 55; Rom-Kedar & Wiggins 1990, Arch. Rat. Mech. Anal. 109, 239).
docs/manifolds.md has the method, the error estimate and the Melnikov conversion.

The section map P preserves dp1 dp2 (MODEL.md R11: (l, L') with p - s = sqrt(2 lam L')(cos l,
sin l) is canonical, dp1 ^ dp2 = lam dL' ^ dl; tests/analysis/test_manifolds.py checks det DP = 1),
so areas in the (p1, p2) plane are invariant and the flux is an area per iteration.

Primary intersections: along a pair (W^u, W^s) of branches every homoclinic point x has
parameters (sigma_u, sigma_s) (:mod:`explorer.analysis.manifolds`) and F = P^m maps it to
(sigma_u + L, sigma_s - L): sigma_u + sigma_s is constant on a homoclinic orbit.  The two
orbits with the smallest sums are the primary ones (they leave the saddle and come back
soonest).  A point h0 of the first and the point q0 of the second with sigma_u(h0) <
sigma_u(q0) < sigma_u(h0) + L bound a lobe: the unstable arc [sigma_u(h0), sigma_u(q0)] and the
stable arc [sigma_s(q0), sigma_s(h0)]; the arcs from q0 to F(h0) bound the second lobe of the
turnstile.  The flux across the broken separatrix per iteration of F is the area of one lobe
(MacKay, Meiss & Percival 1984: the two lobes have equal areas, which the tests check).

Area: Green's theorem, A = (1/2) closed-integral (p1 dp2 - p2 dp1), along the polygon of
exactly computed points of the arcs (the shoelace sum) at the branch's spacing and at half that
spacing (midpoints in sigma); the polygon's error is O(spacing^2), so the Richardson value
A = A_fine + (A_fine - A_coarse)/3 is reported with the error estimate |A_fine - A_coarse|/3
(conservative: the extrapolated value is better than that).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer.analysis.manifolds import Homoclinic, ManifoldBranch, homoclinic_points
from explorer.model import ParameterError

__all__ = ["Lobe", "flux_curve", "lobes", "melnikov_lobe_area", "polygon_area", "richardson_area", "turnstile"]

#: two homoclinic points are on the same orbit when their sigma_u + sigma_s agree to this
SAME_ORBIT_SUM = 1e-6


def polygon_area(points) -> float:
    """Signed area of the closed polygon ``points`` (m, 2) by Green's theorem (shoelace):
    (1/2) sum (x_i y_{i+1} - x_{i+1} y_i), positive counterclockwise."""
    P = np.asarray(points, float)
    x, y = P[:, 0], P[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def richardson_area(coarse, fine):
    """(area, error) from the polygon areas at a spacing and at half of it (module docstring)."""
    a, b = polygon_area(coarse), polygon_area(fine)
    return b + (b - a) / 3.0, abs(b - a) / 3.0


@dataclass(frozen=True)
class Lobe:
    """A lobe bounded by the unstable arc from ``start`` to ``end`` (two adjacent primary
    homoclinic points) and the stable arc back: signed ``area`` (counterclockwise positive),
    its ``error`` estimate, the boundary ``boundary`` (closed polygon, (m, 2))."""

    start: Homoclinic
    end: Homoclinic
    area: float
    error: float
    boundary: np.ndarray

    def as_dict(self):
        return {"area": abs(self.area), "signed_area": self.area, "error": self.error,
                "start": self.start.point.tolist(), "end": self.end.point.tolist()}


def _arc(branch: ManifoldBranch, a, b):
    """Points of ``branch`` with sigma from a to b (either order): the stored ones inside and the
    two ends computed afresh; and the same with the midpoints in sigma inserted."""
    lo, hi = min(a, b), max(a, b)
    inner = branch.sigma[(branch.sigma > lo) & (branch.sigma < hi)]
    sig = np.concatenate([[lo], inner, [hi]])
    mid = 0.5 * (sig[:-1] + sig[1:])
    fine = np.empty(2 * sig.size - 1)
    fine[0::2], fine[1::2] = sig, mid
    pc, pf = branch.at(sig), branch.at(fine)
    if a > b:
        pc, pf = pc[::-1], pf[::-1]
    return pc, pf


def _primary(hs, L):
    """The first points of the two primary homoclinic orbits (smallest sigma_u + sigma_s)."""
    sums = np.array([h.sigma_u + h.sigma_s for h in hs])
    classes: list[float] = []
    for s in np.sort(sums):
        if not classes or s - classes[-1] > SAME_ORBIT_SUM:
            classes.append(float(s))
    if len(classes) < 2:
        return None
    return [[h for h, s in zip(hs, sums) if abs(s - c) <= SAME_ORBIT_SUM] for c in classes[:2]]


def lobes(unstable: ManifoldBranch, stable: ManifoldBranch, *, points=None) -> list:
    """The two lobes of the turnstile between the primary homoclinic orbits of the pair
    (``unstable``, ``stable``) (module docstring), as :class:`Lobe` s; [] when the branches are
    too short to hold two primary orbits and the arcs between them.  ``points``: their
    :func:`~explorer.analysis.manifolds.homoclinic_points` when already computed."""
    hs = homoclinic_points(unstable, stable) if points is None else points
    if unstable.curve is None or stable.curve is None:
        raise ParameterError("lobes needs branches grown by grow_branch (they carry their parametrisation)")
    L = unstable.curve.L
    if not math.isclose(L, stable.curve.L, rel_tol=1e-9):
        raise ParameterError("lobes needs the unstable and stable branch of the same saddle")
    prim = _primary(hs, L)
    if prim is None:
        return []
    out = []
    far = sorted(prim[0], key=lambda p: -np.linalg.norm(p.point - unstable.points[0]))
    for h0 in far:   # the lobe farthest from the saddle first (on p2 = 0 when reversible)
        q = [p for p in prim[1] if h0.sigma_u < p.sigma_u < h0.sigma_u + L]
        if not q:
            continue
        q0 = q[0]
        h1 = [p for p in prim[0] if abs(p.sigma_u - (h0.sigma_u + L)) < 1e-6]
        for a, b in ((h0, q0),) + (((q0, h1[0]),) if h1 else ()):
            uc, uf = _arc(unstable, a.sigma_u, b.sigma_u)
            sc, sf = _arc(stable, b.sigma_s, a.sigma_s)
            if not (np.all(np.isfinite(uf)) and np.all(np.isfinite(sf))):
                continue
            coarse, fine = np.vstack([uc, sc[1:-1]]), np.vstack([uf, sf[1:-1]])
            area, err = richardson_area(coarse, fine)
            out.append(Lobe(a, b, area, err, fine))
        if out:
            break
    return out


def turnstile(sd, *, arclength=6.0, sign=1, **kw):
    """The unstable branch ``sign`` of the saddle ``sd``, the stable branch it meets (either
    sign), their homoclinic points and the turnstile's lobes: a dict with keys "unstable",
    "stable", "homoclinic_points", "lobes" (``kw``: options of :func:`grow_branch`)."""
    from explorer.analysis.manifolds import grow_branch

    bu = grow_branch(sd, sign=sign, arclength=arclength, **kw)
    best = None
    for s in (sign, -sign):
        bs = grow_branch(sd, stable=True, sign=s, arclength=arclength, **kw)
        hs = homoclinic_points(bu, bs)
        lb = lobes(bu, bs, points=hs)
        if lb or best is None:
            best = {"unstable": bu, "stable": bs, "homoclinic_points": hs, "lobes": lb}
        if lb:
            break
    return best


def melnikov_lobe_area(params, h, mu) -> float:
    """First-order lobe area lam mu int |J(g0)| dg0 between consecutive zeros of J = 2 lam mu
    sqrt(A^2 + B^2) for J = A sin g0 + B cos g0 (docs/manifolds.md, "From the Melnikov integral
    to the lobe area"); ParameterError when R7 does not apply."""
    from explorer import model
    from explorer.analysis import melnikov as mk

    prm0 = (params if isinstance(params, model.Params) else model.Params.from_array(params)).with_(mu=0.0)
    A, B, _, _ = mk.fit_harmonics(prm0, mk.check_params(prm0, h), 1)
    return 2.0 * abs(prm0.lam) * float(mu) * math.hypot(A, B)


def flux_curve(params, h, mus, *, guess=(0.0, 0.0), arclength=6.0, sign=1, **kw) -> list:
    """The flux across the broken separatrix of the central saddle (the fixed point followed
    from ``guess`` at mu = 0 by continuation) for each mu of ``mus`` (increasing): one row per
    mu, ``{"mu", "flux", "error", "lobes", "angle", "melnikov", "ratio", "status"}`` (flux: area
    of one lobe of the turnstile per iteration; melnikov: :func:`melnikov_lobe_area` or None;
    status "ok", or why there is no value: "elliptic", "no lobes", a ParameterError's text)."""
    from explorer import model
    from explorer.analysis import fixedpoints
    from explorer.analysis.manifolds import saddle

    prm = params if isinstance(params, model.Params) else model.Params.from_array(params)
    mus = [float(m) for m in mus]
    if any(b <= a for a, b in zip(mus, mus[1:])) or not mus or mus[0] < 0:
        raise ParameterError(f"mus must be >= 0 and increasing, got {mus}")
    rows = []
    prev, x = 0.0, tuple(guess)
    for mu in mus:
        row = {"mu": mu, "flux": None, "error": None, "lobes": [], "angle": None, "melnikov": None, "ratio": None}
        try:
            fp = fixedpoints.follow(prm.with_(mu=prev), h, "mu", prev, mu, x, max_step=max(0.05, mu - prev))
            prev, x = mu, tuple(fp.point)
            try:
                row["melnikov"] = melnikov_lobe_area(prm, h, mu)
            except ParameterError:
                pass
            if fp.stable:
                row["status"] = "elliptic"
                rows.append(row)
                continue
            t = turnstile(saddle(fp), arclength=arclength, sign=sign, **kw)
            if not t["lobes"]:
                row["status"] = "no lobes"
            else:
                lb = t["lobes"]
                row.update(flux=abs(lb[0].area), error=max(lobe.error for lobe in lb),
                           lobes=[lobe.as_dict() for lobe in lb], angle=lb[0].start.angle, status="ok")
                if row["melnikov"]:
                    row["ratio"] = row["flux"] / row["melnikov"]
        except ParameterError as exc:
            row["status"] = str(exc)
        rows.append(row)
    return rows
