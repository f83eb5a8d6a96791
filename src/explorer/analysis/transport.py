"""Lobes of a homoclinic tangle and the flux across a broken separatrix (MacKay, Meiss & Percival
1984; Rom-Kedar & Wiggins 1990): primary intersections, lobe areas by Green's theorem with a
Richardson error estimate, transit times (docs/manifolds.md, Lobes and flux).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from explorer.analysis.manifolds import Homoclinic, ManifoldBranch, homoclinic_points
from explorer.analysis.section_map import SectionMap, not_a_system, system_first
from explorer.model import ParameterError

__all__ = ["DEFAULT_FLUX_MUS", "FluxCurve", "Lobe", "REASON_LOBES_DIFFER", "REASON_NO_EYE", "REASON_NO_PAIR",
           "REASON_NO_SADDLE", "REASON_SECONDARY", "REASON_TORN", "exit_times", "flux_curve", "inside", "lobes",
           "melnikov_lobe_area", "polygon_area", "resonance_zone", "richardson_area", "torn", "turnstile",
           "turnstile_check"]

#: two homoclinic points are on the same orbit when their sigma_u + sigma_s agree to this
SAME_ORBIT_SUM = 1e-6
#: the two lobes of a turnstile have equal areas (area preservation): a flux is reported only
#: when they agree to this (relative) beyond their error estimates
LOBE_AGREEMENT = 1e-6


def polygon_area(points) -> float:
    """Signed area of the closed polygon ``points`` (m, 2) by Green's theorem (shoelace):
    (1/2) sum (x_i y_{i+1} - x_{i+1} y_i), positive counterclockwise."""
    P = np.asarray(points, float)
    x, y = P[:, 0], P[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def richardson_area(coarse, fine):
    """(area, error) from the polygon areas at a spacing and at half of it: Richardson
    A_fine + (A_fine - A_coarse)/3, error |A_fine - A_coarse|/3 (docs/manifolds.md)."""
    a, b = polygon_area(coarse), polygon_area(fine)
    return b + (b - a) / 3.0, abs(b - a) / 3.0


@dataclass(frozen=True)
class Lobe:
    """A lobe bounded by the unstable arc from ``start`` to ``end`` (adjacent primary homoclinic
    points) and the stable arc back: signed ``area``, ``error``, closed ``boundary`` (m, 2), and
    ``secondary`` homoclinic points on its turnstile's arcs (0: simple; else the area is not the flux)."""

    start: Homoclinic
    end: Homoclinic
    area: float
    error: float
    boundary: np.ndarray
    secondary: int = 0

    def as_dict(self):
        return {"area": abs(self.area), "signed_area": self.area, "error": self.error,
                "start": self.start.point.tolist(), "end": self.end.point.tolist(), "secondary": self.secondary}


def _arc(branch: ManifoldBranch, a, b):
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


def _unbroken(branch: ManifoldBranch, a, b) -> bool:
    """The arc of ``branch`` between sigma a and b holds no tear (ManifoldBranch.tears)."""
    lo, hi = min(a, b), max(a, b)
    t = branch.tears
    return not np.any((t >= lo) & (t < hi))


def _secondary(points, a, b, c, margin=1e-7) -> int:
    ulo, uhi = sorted((a.sigma_u, c.sigma_u))
    slo, shi = sorted((a.sigma_s, c.sigma_s))
    return sum(1 for p in points if ulo + margin < p.sigma_u < uhi - margin and slo + margin < p.sigma_s < shi - margin
               and abs(p.sigma_u - b.sigma_u) > margin)


def lobes(unstable: ManifoldBranch, stable: ManifoldBranch, *, points=None) -> list:
    """The two lobes (:class:`Lobe`) of the turnstile between the primary homoclinic orbits of
    (``unstable``, ``stable``) (docs/manifolds.md, Lobes and flux); [] when the branches are too
    short or every pair of arcs is torn.  ``points``: their homoclinic points, if computed."""
    hs = homoclinic_points(unstable, stable) if points is None else points
    if unstable.curve is None or stable.curve is None:
        raise ParameterError("lobes needs branches grown by grow_branch (they carry their parametrisation)")
    L = unstable.curve.L
    if not math.isclose(L, stable.curve.L, rel_tol=1e-9):
        raise ParameterError("lobes needs the unstable and stable branch of the same saddle")
    prim = _primary(hs, L)
    if prim is None:
        return []
    far = sorted(prim[0], key=lambda p: -np.linalg.norm(p.point - unstable.points[0]))
    for h0 in far:   # the lobe farthest from the saddle first (on p2 = 0 when reversible)
        q = [p for p in prim[1] if h0.sigma_u < p.sigma_u < h0.sigma_u + L]
        if not q:
            continue
        q0 = q[0]
        h1 = [p for p in prim[0] if abs(p.sigma_u - (h0.sigma_u + L)) < 1e-6]
        qm = [p for p in prim[1] if abs(p.sigma_u - (q0.sigma_u - L)) < 1e-6]
        pairs = ([((h0, q0), (q0, h1[0]))] if h1 else []) + ([((qm[0], h0), (h0, q0))] if qm else [])
        for pair in pairs:
            out = []
            crossings = _secondary(hs, pair[0][0], pair[0][1], pair[1][1])
            for a, b in pair:
                if not (_unbroken(unstable, a.sigma_u, b.sigma_u) and _unbroken(stable, b.sigma_s, a.sigma_s)):
                    break
                uc, uf = _arc(unstable, a.sigma_u, b.sigma_u)
                sc, sf = _arc(stable, b.sigma_s, a.sigma_s)
                if not (np.all(np.isfinite(uf)) and np.all(np.isfinite(sf))):
                    break
                coarse, fine = np.vstack([uc, sc[1:-1]]), np.vstack([uf, sf[1:-1]])
                area, err = richardson_area(coarse, fine)
                out.append(Lobe(a, b, area, err, fine, crossings))
            if len(out) == 2:
                return out
        if not pairs and _unbroken(unstable, h0.sigma_u, q0.sigma_u) and _unbroken(stable, q0.sigma_s, h0.sigma_s):
            uc, uf = _arc(unstable, h0.sigma_u, q0.sigma_u)
            sc, sf = _arc(stable, q0.sigma_s, h0.sigma_s)
            if np.all(np.isfinite(uf)) and np.all(np.isfinite(sf)):
                area, err = richardson_area(np.vstack([uc, sc[1:-1]]), np.vstack([uf, sf[1:-1]]))
                return [Lobe(h0, q0, area, err, np.vstack([uf, sf[1:-1]]))]
    return []


def torn(unstable: ManifoldBranch, stable: ManifoldBranch, points) -> bool:
    """No turnstile with unbroken arcs can exist on these branches however long they grow: the
    first tears sigma_u_t + sigma_s_t < S0 + L (S0 the smallest homoclinic sum, L its lobe span)."""
    if not points:
        return False
    S0 = min(p.sigma_u + p.sigma_s for p in points)
    return unstable.first_tear + stable.first_tear < S0 + unstable.curve.L


def turnstile(sd, *, arclength=6.0, sign=1, max_arclength=None, max_residual=1e-10):
    """The unstable branch ``sign`` of the saddle ``sd``, the stable branch it meets (the same
    sign first, then the other), their homoclinic points and the turnstile's lobes: a dict with
    keys "unstable", "stable", "homoclinic_points", "lobes", "arclength", "torn"."""
    from explorer.analysis.manifolds import grow_branch

    length = float(arclength)
    limit = length if max_arclength is None else float(max_arclength)
    bu, grown = None, {}
    while True:
        bu = grow_branch(sd, sign=sign, arclength=length, resume=bu)
        best = None
        for s in (sign, -sign):
            bs = grown[s] = grow_branch(sd, stable=True, sign=s, arclength=length, resume=grown.get(s),
                                        unstable=bu if s == sign else None)
            hs = homoclinic_points(bu, bs, max_residual=max_residual)
            lb = lobes(bu, bs, points=hs)
            cut = torn(bu, bs, hs)
            rank = (len(lb), cut, len(hs))
            if best is None or rank > (len(best["lobes"]), best["torn"], len(best["homoclinic_points"])):
                best = {"unstable": bu, "stable": bs, "homoclinic_points": hs, "lobes": lb, "arclength": length,
                        "torn": cut}
            if len(lb) == 2:
                return best
        if best["torn"] or 2 * length > limit * (1 + 1e-12):
            return best
        length *= 2


#: the reasons of a flux curve's row without a lobe flux (its "status" says more)
REASON_NO_PAIR = "no primary homoclinic pair within budget"
REASON_LOBES_DIFFER = "lobes differ"
REASON_TORN = "torn"
REASON_NO_EYE = "the eye is gone"
REASON_NO_SADDLE = "no hyperbolic fixed point"
REASON_SECONDARY = "secondary intersections"


def turnstile_check(lobes_found, arclength, *, torn_branches=False, points=()) -> str:
    """"ok" when both lobes of a turnstile were found and their areas agree (area preservation:
    relative ``LOBE_AGREEMENT`` beyond three times their error estimates), else why not: the
    branches are torn (:func:`torn`), the two lobes differ, or no pair within ``arclength``."""
    lb = lobes_found
    if len(lb) < 2 and torn_branches:
        return ("torn: the section map's discontinuity (orbits grazing the section's edge, M = 0) cuts "
                "the manifolds before a turnstile closes")
    if len(lb) < 2:
        return f"no pair of lobes within arclength {arclength:g}" + ("" if points else " (no homoclinic point)")
    if abs(abs(lb[0].area) - abs(lb[1].area)) > LOBE_AGREEMENT * abs(lb[0].area) + 3 * (lb[0].error + lb[1].error):
        return (f"the two lobes differ ({abs(lb[0].area):.6g}, {abs(lb[1].area):.6g}): the primary "
                "intersections were not identified")
    if any(lobe.secondary for lobe in lb):
        return (f"secondary intersections on the turnstile's arcs ({lb[0].secondary}): the lobes overlap "
                "and their signed area is not the flux")
    return "ok"


def melnikov_lobe_area(params, h, mu) -> float:
    """First-order lobe area lam mu int |J(g0)| dg0 between consecutive zeros of J = 2 lam mu
    sqrt(A^2 + B^2) for J = A sin g0 + B cos g0 (docs/manifolds.md, "From the Melnikov integral
    to the lobe area"); ParameterError when R7 does not apply."""
    from explorer import model
    from explorer.analysis import melnikov as mk

    prm0 = (params if isinstance(params, model.Params) else model.Params.from_array(params)).with_(mu=0.0)
    A, B, _, _ = mk.fit_harmonics(prm0, mk.check_params(prm0, h), 1)
    return 2.0 * abs(prm0.lam) * float(mu) * math.hypot(A, B)


#: mu of :func:`flux_curve` when none are given: from 1e-3 up to the loss of the central saddle
#: (Figure 4, h = 2: trace 2 at mu* ~ 2.98, docs/manifolds.md)
DEFAULT_FLUX_MUS = (1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.2, 0.3, 0.4, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 2.75, 3.0, 3.25, 3.5)
#: largest continuation step in mu between two rows of a flux curve (a larger one may jump to
#: another fixed point)
FOLLOW_STEP = 0.05
#: the homoclinic points of a flux curve are kept to this residual (rounding reaches 1e-10 at mu = 1)
FLUX_RESIDUAL = 1e-9
#: samples of the Monte Carlo exit flux of the eye (rows whose turnstile is torn)
EXIT_SAMPLES = 4000


class FluxCurve(list):
    """The rows of :func:`flux_curve` (a list of dicts), with ``destruction`` (the mu where the
    central saddle was lost, or None), ``stop_reason`` and ``trace_two``."""

    destruction: float | None = None
    stop_reason: str = ""
    #: the mu where the followed point's trace, interpolated linearly, is 2; None unless it stopped so
    trace_two: float | None = None


def _eye_point(points, reversible):
    if not points:
        return None
    S0 = min(p.sigma_u + p.sigma_s for p in points)
    first = [p for p in points if abs(p.sigma_u + p.sigma_s - S0) <= SAME_ORBIT_SUM]
    if reversible:
        on = [p for p in first if abs(p.sigma_u - p.sigma_s) < 1e-6]
        return max(on, key=lambda p: p.sigma_u) if on else None
    return min(first, key=lambda p: p.sigma_u)


@not_a_system("find its saddle (explorer.find_fixed_point, manifolds.saddle) and take the lobes of its tangle "
              "with transport.turnstile(saddle), exit_times with them")
@system_first
def flux_curve(system, mus=None, *, guess=(0.0, 0.0), arclength=6.0, max_arclength=None, sign=1,
               exit_samples=EXIT_SAMPLES, seed=0) -> FluxCurve:
    """The flux across the broken separatrix of the central saddle (the fixed point followed
    from ``guess`` at mu = 0 by continuation) for each mu of ``mus`` (increasing; default
    :data:`DEFAULT_FLUX_MUS`, from 1e-3 to beyond the saddle's loss), stopping at the first mu
    where the saddle is lost.  One row per mu: ``{"mu", "flux", "error", "lobes", "angle",
    "melnikov", "ratio", "arclength", "status", "reason", "eye_flux", "eye_error", "trace"}``."""
    from explorer.analysis import fixedpoints
    from explorer.analysis.manifolds import saddle
    from explorer.model.symmetry import is_reversible

    named = system.orbit_fields()       # Melnikov's integral needs the model's parameters and energy
    if "params" not in named:
        raise ParameterError(f"flux_curve follows the central saddle of Chaplygin's section map in mu (Melnikov's "
                             f"integral needs the model's parameters and energy h); {system!r} has none: grow its "
                             "branches (grow_branch) and use lobes and exit_times")
    prm, h = named["params"], named["h"]
    mus = [float(m) for m in (DEFAULT_FLUX_MUS if mus is None else mus)]
    if any(b <= a for a, b in zip(mus, mus[1:])) or not mus or mus[0] < 0:
        raise ParameterError(f"mus must be >= 0 and increasing, got {mus}")
    reversible = is_reversible(prm)
    rows = FluxCurve()
    prev, x = 0.0, tuple(guess)
    for mu in mus:
        row = {"mu": mu, "flux": None, "error": None, "lobes": [], "angle": None, "melnikov": None, "ratio": None,
               "arclength": None, "reason": "", "eye_flux": None, "eye_error": None, "trace": None}
        rows.append(row)
        try:
            row["melnikov"] = melnikov_lobe_area(prm, h, mu)
        except ParameterError:
            pass
        try:
            fp = fixedpoints.follow(system.with_value("mu", prev), "mu", prev, mu, x, max_step=FOLLOW_STEP)
        except ParameterError as exc:
            row.update(status=f"the fixed point was not followed to this mu: {exc}", reason=REASON_NO_SADDLE)
        else:
            row["trace"] = float(fp.trace)
            if fp.stable:
                row.update(status=f"elliptic (trace {fp.trace:.6g})", reason=REASON_NO_SADDLE)
            elif reversible and abs(fp.point[1]) > 1e-8:
                row.update(status=f"the followed point left the symmetry line p2 = 0 (at {fp.point.tolist()}): the "
                           "central point is no longer a saddle", reason=REASON_NO_SADDLE)
        if row["reason"] == REASON_NO_SADDLE:
            rows.destruction, rows.stop_reason = mu, row["status"]
            last = rows[-2] if len(rows) > 1 else None
            if last is not None and last["trace"] is not None and row["trace"] is not None and row["trace"] < 2.0:
                w = (last["trace"] - 2.0) / (last["trace"] - row["trace"])
                rows.trace_two = last["mu"] + w * (mu - last["mu"])
            break
        prev, x = mu, tuple(fp.point)
        try:
            at_fp = SectionMap(fp.params, fp.h, phi0=system.phi0, tol=system.tol, tmax=system.tmax)
            t = turnstile(saddle(at_fp, fp), arclength=arclength, sign=sign,
                          max_residual=FLUX_RESIDUAL,
                          max_arclength=4 * arclength if max_arclength is None else max_arclength)
        except ParameterError as exc:
            row.update(status=str(exc), reason=REASON_NO_PAIR)
            continue
        row["arclength"] = t["arclength"]
        lb = t["lobes"]
        row["status"] = turnstile_check(lb, t["arclength"], torn_branches=t["torn"], points=t["homoclinic_points"])
        bu, bs = t["unstable"], t["stable"]
        h0 = _eye_point(t["homoclinic_points"], reversible)
        eye = h0 is not None and bu.first_tear > h0.sigma_u and bs.first_tear > h0.sigma_s
        if eye and exit_samples:
            ex = exit_times(bu, bs, h0, samples=exit_samples, max_iter=1, seed=seed)
            row.update(eye_flux=ex["flux_mc"], eye_error=ex["flux_mc_sem"])
        if row["status"] == "ok":
            row.update(flux=abs(lb[0].area), error=max(lobe.error for lobe in lb),
                       lobes=[lobe.as_dict() for lobe in lb], angle=lb[0].start.angle)
            if row["melnikov"]:
                row["ratio"] = row["flux"] / row["melnikov"]
            continue
        if row["status"].startswith("the two lobes differ"):
            row["reason"] = REASON_LOBES_DIFFER
            continue
        if row["status"].startswith("secondary"):
            row.update(reason=REASON_SECONDARY, lobes=[lobe.as_dict() for lobe in lb])
            continue
        if t["torn"] and eye:
            row["reason"] = REASON_TORN
        elif t["torn"] or (h0 is None and (bu.tears.size or bs.tears.size)):
            row.update(reason=REASON_NO_EYE, status=row["status"] + "; no eye: no primary homoclinic point closes "
                       "an unbroken resonance zone")
        else:
            row["reason"] = REASON_NO_PAIR
    return rows


def inside(polygon, X) -> np.ndarray:
    """Whether each point of X (m, 2) lies inside the closed ``polygon`` (k, 2) (even-odd rule:
    a ray along +p1 crosses the boundary an odd number of times); NaN points are outside."""
    from explorer.kernels import geometry

    return geometry.inside(polygon, X)


def resonance_zone(unstable: ManifoldBranch, stable: ManifoldBranch, point: Homoclinic) -> np.ndarray:
    """The region bounded by the unstable arc from the saddle to the homoclinic ``point`` and the
    stable arc from it back (the pseudo-separatrix; MacKay, Meiss & Percival 1984), as a closed
    polygon (the stored points of the arcs and ``point``)."""
    u = unstable.points[unstable.sigma < point.sigma_u]
    s = stable.points[stable.sigma < point.sigma_s]
    return np.vstack([u, [point.point], s[::-1][:-1]])


def _steps_inside(smap, polygon, X, max_iter, block):
    from explorer.analysis.maps import images

    T = np.full(len(X), max_iter + 1, np.int64)
    alive = np.arange(len(X))
    cur = np.asarray(X, float).copy()
    done = 0
    while alive.size and done < max_iter:
        n = min(block, max_iter - done)
        pts = images(smap, cur[alive], n)
        ins = inside(polygon, pts.reshape(-1, 2)).reshape(len(alive), n)
        left = ~ins
        first = np.where(left.any(axis=1), np.argmax(left, axis=1), -1)
        gone = first >= 0
        T[alive[gone]] = done + first[gone] + 1
        cur[alive[~gone]] = pts[~gone, -1]
        alive = alive[~gone]
        done += n
    return T


def exit_times(unstable: ManifoldBranch, stable: ManifoldBranch, point: Homoclinic, *, samples=4000,
                  max_iter=400, seed=0, block=50) -> dict:
    """Transit times through the resonance zone R (:func:`resonance_zone`) and the mean-exit-time
    identity (Meiss 1992, Rev. Mod. Phys. 64, 795): for an area-preserving map, the points of the
    entry set I = {x in R: P^-1(x) not in R} (area = flux Phi) stay T(x) iterations in R, and
    int_I T dA = A_acc, the area of R's accessible part, so <T>_I = A_acc / Phi."""
    from explorer.analysis.manifolds import _images

    smap = unstable.curve.sd.smap
    R = resonance_zone(unstable, stable, point)
    area = abs(polygon_area(R))
    rng = np.random.default_rng(seed)
    lo, hi = R.min(axis=0), R.max(axis=0)
    X = np.empty((0, 2))
    while len(X) < samples:
        Y = lo + (hi - lo) * rng.random((2 * samples, 2))
        X = np.vstack([X, Y[inside(R, Y)]])
    X = X[:samples]
    pre = _images(smap, X, 1, True)
    entry = ~inside(R, pre)
    T_all = _steps_inside(smap, R, X, max_iter, block)
    T = T_all[entry]
    Tc = np.minimum(T, max_iter)
    acc = T_all <= max_iter
    n = len(X)
    p_acc = acc.mean()
    t = np.unique(T[T <= max_iter]) if T.size else np.array([], np.int64)
    surv = np.array([(T > k).mean() for k in t]) if T.size else np.array([])
    q = entry.mean()
    return {"area": area, "flux_mc": area * q, "flux_mc_sem": area * math.sqrt(q * (1 - q) / n),
            "entry": int(entry.sum()), "times": T, "mean": float(Tc.mean()) if T.size else float("nan"),
            "sem": float(Tc.std(ddof=1) / math.sqrt(T.size)) if T.size > 1 else float("nan"),
            "capped": int(np.sum(T > max_iter)), "accessible_area": area * p_acc,
            "accessible_sem": area * math.sqrt(p_acc * (1 - p_acc) / n), "survival": (t, surv),
            "all_times": T_all, "zone": R}
