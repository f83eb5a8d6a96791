"""The figures of the seed paper, regenerated: ``python -m explorer figures``.

Borisov & Mamaev, *On the motion of a heavy rigid body in an ideal fluid with circulation*
(``shared/seed``), with the equations of ``shared/MODEL.md`` (labels R1-R10).  Each figure
has a builder returning a :class:`Drawn` (the matplotlib figure and the numbers it shows,
so that tests can check what was drawn) and is written by :func:`generate` as
``<out_dir>/<name>.png`` and ``.pdf`` (:func:`explorer.figures.save_figure`).

=====================  ==========================================================================
name                   what
=====================  ==========================================================================
``figure2``            Chaplygin's case (R6): closed curves {H = h} n {F = c} in (p1, p2, M),
                       integrated with the project's Taylor integrator, one panel per energy
                       interval of the seed (below, inside, above the unstable band of I)
``figure3``            the bifurcation diagram in the (c, h) plane, admissible region in gray,
                       unstable branches dashed, checked numerically (:func:`figure3_check`)
``figure4``            the sweep of the scene preset ``figure4`` (sections + separatrices)
``chaotic_fraction``   the chaotic fraction against mu (scene preset ``fraction``)
``chaos_map``          MEGNO maps of the Figure-4 panels (scene preset ``chaos``)
``continuation``       the central fixed point of the section map continued in mu (0..8)
``work_precision``     one-step error against throughput, ``benchmarks/results_w4.json``
``homoclinic``         R7 against the integrated flow, with its crossings of phi = pi
``melnikov``           :func:`explorer.app.melnikov_figure.melnikov_figure`
``trajectory``         :func:`explorer.app.trajectory_figure.path_figure`
=====================  ==========================================================================

Sweeps (``figure4``, ``chaotic_fraction``, ``chaos_map``) go through
:func:`explorer.app.runner.run_sweep`, which reuses ``<results_dir>/<scene>.h5`` when its panels
are stored with the same settings hash and computes only what is missing.  With ``quick``
a scene whose store is not complete is replaced by a reduced copy (fewer seeds, crossings,
shorter MEGNO time) named ``<scene>-quick`` with its own store; the figure says so.

The admissible region of Figure 3 (derivation, also in ``docs/errata.md``)
-----------------------------------------------------------------------------
For mu = chi = zeta = 0, lam > 0, a1 > a2: on {F = c}, M = c - (u + v)/(2 lam) with
u = p1^2, v = p2^2 >= 0, and

    H = 1/2 (u/a1 + v/a2 + (c - (u + v)/(2 lam))^2 / b)

is a convex quadratic in (u, v) with dH/du = (1/a1 - M/(lam b))/2, dH/dv = (1/a2 - M/(lam b))/2.
Its minimum over u, v >= 0 (KKT): if c <= lam b/a1, at u = v = 0 (solution I,
h = c^2/(2b)); otherwise at v = 0, M = lam b/a1 (solution II, h = lam c/a1 - lam^2 b/(2 a1^2)).
H is unbounded above on {F = c} (|p| -> infinity), so the set of (c, h) of real motions is

    h >= h_min(c) = c^2/(2b)                        for c <= lam b/a1,
                    lam c/a1 - lam^2 b/(2 a1^2)     for c >= lam b/a1,

the parabola of I continued by its tangent, the line of II (C^1 at the tangency point).
The line of III (c > lam b/a2) and the arc of I with c > lam b/a1 lie inside the region.
"""
from __future__ import annotations

import json
import math
import os
import sys
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from explorer import model
from explorer.model import ParameterError

#: every figure, in the order they are generated
FIGURES = ("figure2", "figure3", "figure4", "chaotic_fraction", "chaos_map", "continuation",
           "work_precision", "homoclinic", "melnikov", "trajectory")
#: figures computed from stored sweeps (reduced under ``quick`` when their store is incomplete)
SWEEP_FIGURES = {"figure4": "figure4", "chaotic_fraction": "fraction", "chaos_map": "chaos"}

#: the parameters of the seed's Figures 2 and 3: lam = 1, b = 2, a1 = 1, a2 = 1/2, chi = zeta = 0
#: (mu = 0: Chaplygin's case, MODEL.md R6; Figure 4's scene at mu = 0)
CHAPLYGIN = model.FIGURE4.with_(mu=0.0)
#: the energies of Figure 2, one in each interval of the seed, (0, b lam^2/(2 a1^2)) = (0, 1),
#: (1, b lam^2/(2 a2^2)) = (1, 4), (4, inf); h = 2 is Figure 4's level
FIGURE2_ENERGIES = (0.5, 2.0, 6.0)
#: Taylor tolerance of the dense integrations
DENSE_TOL = 1e-14

#: reduced scenes of ``quick``: (table, key) -> value
QUICK_SCENES = {
    "figure4": {("seeds", "n"): 40, ("integration", "crossings"): 200, ("integration", "tmax"): 2000.0},
    "chaos": {("seeds", "n"): 100, ("integration", "crossings"): 20, ("lyapunov", "time"): 200.0},
    "fraction": {("seeds", "n"): 60, ("integration", "crossings"): 20, ("integration", "tmax"): 400.0,
                 ("lyapunov", "time"): 200.0},
}

_FS = 9       # font size of labels
_TS = 8       # tick labels
_SMALL = 7    # annotations
_RC = {"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6, "font.size": _FS,
       "xtick.labelsize": _TS, "ytick.labelsize": _TS, "legend.fontsize": _SMALL,
       "xtick.direction": "in", "ytick.direction": "in", "xtick.top": True, "ytick.right": True,
       "xtick.major.width": 0.5, "ytick.major.width": 0.5, "xtick.minor.width": 0.4,
       "ytick.minor.width": 0.4, "lines.linewidth": 1.0}


class FigureUnavailable(Exception):
    """A figure that cannot be made here (module or input missing): reported, not an error."""


@dataclass
class Drawn:
    """A figure and the numbers it shows (for tests and reports)."""

    fig: object
    data: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)


@dataclass
class Outcome:
    name: str
    status: str            # "written", "not available", "skipped", "failed"
    paths: list = field(default_factory=list)
    message: str = ""
    data: dict = field(default_factory=dict)

    def line(self) -> str:
        if self.status == "written":
            s = f"{self.name}: " + ", ".join(str(p) for p in self.paths)
            return s + (f"  ({self.message})" if self.message else "")
        return f"{self.name}: {self.status}" + (f" ({self.message})" if self.message else "")


# ====================================================================== matplotlib
def _new_figure(figsize, dpi=200, layout="constrained"):
    from explorer.app.figures import _matplotlib

    _matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi, layout=layout)
    FigureCanvasAgg(fig)
    return fig


def _rc():
    from explorer.app.figures import _matplotlib

    return _matplotlib().rc_context(_RC)


# ====================================================================== Chaplygin's case (R6)
def check_chaplygin(params) -> model.Params:
    """The setting of the seed's bifurcation analysis: mu = 0, chi = zeta = 0, lam > 0, a1 > a2."""
    prm = params if isinstance(params, model.Params) else model.Params(**params)
    if prm.mu != 0.0 or prm.chi != 0.0 or prm.zeta != 0.0:
        raise ParameterError(f"Chaplygin's case needs mu = chi = zeta = 0, got mu = {prm.mu:g}, "
                             f"chi = {prm.chi:g}, zeta = {prm.zeta:g}")
    if not prm.lam > 0.0 or not prm.a1 > prm.a2:
        raise ParameterError(f"the bifurcation analysis (seed, MODEL.md R6) assumes lam > 0 and a1 > a2, "
                             f"got lam = {prm.lam:g}, a1 = {prm.a1:g}, a2 = {prm.a2:g}")
    return prm


def critical_c(params):
    """(lam b/a1, lam b/a2): the band of c where solution I is unstable (R6)."""
    prm = check_chaplygin(params)
    return prm.lam * prm.b / prm.a1, prm.lam * prm.b / prm.a2


def critical_h(params):
    """(b lam^2/(2 a1^2), b lam^2/(2 a2^2)): the energies that bound the seed's three intervals."""
    prm = check_chaplygin(params)
    return prm.b * prm.lam ** 2 / (2 * prm.a1 ** 2), prm.b * prm.lam ** 2 / (2 * prm.a2 ** 2)


def _aj(prm, branch):
    return {"II": prm.a1, "III": prm.a2}[branch]


def branch_exists(branch, c, params) -> bool:
    """I exists for every c; II (p2 = 0, j = 1) for c > lam b/a1; III (p1 = 0, j = 2) for c > lam b/a2."""
    prm = check_chaplygin(params)
    if branch == "I":
        return True
    return c > prm.lam * prm.b / _aj(prm, branch)


def branch_h(branch, c, params):
    """Energy of the permanent rotation of a branch at F = c: I: h = c^2/(2b); II, III:
    h = lam c/a_j - lam^2 b/(2 a_j^2) (ur21 with its 1/2, MODEL.md R6)."""
    prm = check_chaplygin(params)
    c = np.asarray(c, dtype=float)
    if branch == "I":
        return c * c / (2 * prm.b)
    a = _aj(prm, branch)
    return prm.lam * c / a - prm.lam ** 2 * prm.b / (2 * a * a)


def branch_stable(branch, c, params) -> bool:
    """The seed's (and R6's) classification: I unstable for lam b/a1 < c < lam b/a2, stable
    outside (the boundaries need a special analysis and are not classified: ValueError);
    II (the body's narrower side towards the centre) always stable; III always unstable."""
    c1, c2 = critical_c(params)
    if branch == "I":
        if c in (c1, c2):
            raise ValueError(f"c = {c!r} is a boundary of the band of I: stability needs a special analysis")
        return not (c1 < c < c2)
    if not branch_exists(branch, c, params):
        raise ValueError(f"branch {branch} does not exist at c = {c!r}")
    return branch == "II"


def relative_equilibrium(branch, c, params, sign=1):
    """The state (p1, p2, M) of a permanent rotation: I: (0, 0, c); II: (+-P, 0, lam b/a1);
    III: (0, +-P, lam b/a2), P = sqrt(2 lam (c - b lam/a_j)) (ur20)."""
    prm = check_chaplygin(params)
    if branch == "I":
        return np.array([0.0, 0.0, float(c)])
    if not branch_exists(branch, c, prm):
        raise ValueError(f"branch {branch} does not exist at c = {c!r}")
    a = _aj(prm, branch)
    P = sign * math.sqrt(2 * prm.lam * (c - prm.b * prm.lam / a))
    M = prm.lam * prm.b / a
    return np.array([P, 0.0, M]) if branch == "II" else np.array([0.0, P, M])


def admissible_hmin(c, params):
    """The least energy of a real state with F = c (see the module docstring): the lower
    boundary of the admissible region of Figure 3."""
    prm = check_chaplygin(params)
    c = np.asarray(c, dtype=float)
    c1 = prm.lam * prm.b / prm.a1
    return np.where(c <= c1, c * c / (2 * prm.b), prm.lam * c / prm.a1 - prm.lam ** 2 * prm.b / (2 * prm.a1 ** 2))


def chaplygin_F(params, y):
    """F = M + (p1^2 + p2^2)/(2 lam) (ur19, R6) of states y[..., :3]."""
    prm = params if isinstance(params, model.Params) else model.Params(**params)
    y = np.asarray(y, dtype=float)
    return y[..., 2] + (y[..., 0] ** 2 + y[..., 1] ** 2) / (2 * prm.lam)


def chaplygin_H(params, y):
    """H = (p1^2/a1 + p2^2/a2 + M^2/b)/2 (ur19, R6) of states y[..., :3]."""
    prm = params if isinstance(params, model.Params) else model.Params(**params)
    y = np.asarray(y, dtype=float)
    return 0.5 * (y[..., 0] ** 2 / prm.a1 + y[..., 1] ** 2 / prm.a2 + y[..., 2] ** 2 / prm.b)


def r6_jacobian(params, y3):
    """The 3x3 Jacobian of R6 in (p1, p2, M) at y3, from the project's compiled variational
    field :func:`explorer.equations.rhs_tangent` (exact: the field is quadratic).  At mu = 0
    the (p, M) block does not depend on gamma."""
    from explorer.model.equations import rhs_tangent

    prm = params if isinstance(params, model.Params) else model.Params(**params)
    P = prm.as_array()
    y = np.array([y3[0], y3[1], y3[2], 0.0, 1.0])
    J = np.empty((3, 3))
    dv = np.empty(5)
    for k in range(3):
        v = np.zeros(5)
        v[k] = 1.0
        rhs_tangent(y, v, P, dv)
        J[:, k] = dv[:3]
    return J


def r6_rhs(params, y3):
    """R6 (= R3 at mu = chi = zeta = 0) for (p1, p2, M), from the project's compiled field."""
    from explorer.model.equations import rhs

    prm = params if isinstance(params, model.Params) else model.Params(**params)
    out = np.empty(5)
    rhs(np.array([y3[0], y3[1], y3[2], 0.0, 1.0]), prm.as_array(), out)
    return out[:3]


#: sample points of each branch checked by :func:`figure3_check` (values of c)
CHECK_SAMPLES = {"I": (-1.0, 0.8, 1.5, 2.5, 2.0 * math.sqrt(2.0), 3.5, 5.0, 7.0),
                 "II": (3.0, 4.0, 5.5, 6.5), "III": (4.4, 4.8, 5.5)}
#: monodromy traces closer than this to +-2 are resonances of the section map, not classified
TRACE_MARGIN = 0.02


class CheckError(AssertionError):
    """The numerical stability disagrees with the classification drawn in Figure 3."""


def figure3_check(params=CHAPLYGIN, samples=None, *, tol=1e-15):
    """Numerical stability at sample points of every branch of Figure 3, against the
    dashed/solid classification of :func:`branch_stable`.

    * I (p = 0, M = c) is a fixed point of the section map phi = pi at h = c^2/(2b) when c > 0:
      :func:`explorer.fixedpoints.find_fixed_point` (Newton, monodromy from the tangent dynamics)
      and its ``stable`` (|trace| < 2); traces within TRACE_MARGIN of +-2 (resonances of the
      rotation, e.g. c = 4 + 4/sqrt(3)) are not classified.  The found point must be p = 0 and
      the trace that of :func:`fixedpoints.analytic_eigenvalues_solution_I`.
    * Every branch (I included, also c <= 0): eigenvalues of the Jacobian of R6 at the relative
      equilibrium (:func:`r6_jacobian`); stable when every eigenvalue is on the imaginary axis.
      For II/III they must be 0, +-i P kappa (II) and 0, +-P kappa (III), kappa =
      sqrt((a1 - a2)/(a1 a2 b)) (R6), and the point must be an equilibrium of R6.

    Returns a list of records (dicts: branch, c, h, method, value, stable, expected, agree);
    raises :class:`CheckError` if any record disagrees."""
    from explorer.analysis import fixedpoints

    prm = check_chaplygin(params)
    samples = CHECK_SAMPLES if samples is None else samples
    kappa = math.sqrt((prm.a1 - prm.a2) / (prm.a1 * prm.a2 * prm.b))
    out = []
    problems = []
    for branch in ("I", "II", "III"):
        for c in samples.get(branch, ()):
            c = float(c)
            expected = branch_stable(branch, c, prm)
            h = float(branch_h(branch, c, prm))
            y3 = relative_equilibrium(branch, c, prm)
            residual = float(np.max(np.abs(r6_rhs(prm, y3))))
            ev = np.linalg.eigvals(r6_jacobian(prm, y3))
            scale = max(1.0, float(np.max(np.abs(ev))))
            stable = bool(np.max(np.abs(ev.real)) <= 1e-9 * scale)
            rec = {"branch": branch, "c": c, "h": h, "method": "jacobian", "eigenvalues": ev.tolist(),
                   "value": float(np.max(np.abs(ev.real))), "stable": stable, "expected": expected,
                   "residual": residual}
            if branch != "I":
                Pj = abs(y3[0] if branch == "II" else y3[1])
                want = np.array([0.0, Pj * kappa, -Pj * kappa]) * (1j if branch == "II" else 1.0)
                err = max(np.min(np.abs(ev - w)) for w in want)
                rec["analytic_error"] = float(err)
                if err > 1e-12 * max(1.0, Pj * kappa):
                    problems.append(f"{branch} at c = {c:g}: eigenvalues {ev} differ from 0, "
                                    f"{'+-i' if branch == 'II' else '+-'} P kappa = {Pj * kappa:.12g}")
            if residual > 1e-12:
                problems.append(f"{branch} at c = {c:g} is not an equilibrium of R6 (|f| = {residual:.3g})")
            rec["agree"] = stable == expected
            out.append(rec)
            if branch == "I" and c > 0.0:
                fp = fixedpoints.find_fixed_point(prm, h, (0.0, 0.0), tol=tol)
                _ev, tr_exact = fixedpoints.analytic_eigenvalues_solution_I(prm, h)
                rec = {"branch": branch, "c": c, "h": h, "method": "monodromy", "value": float(fp.trace),
                       "trace_analytic": float(tr_exact), "point": fp.point.tolist(), "stable": bool(fp.stable),
                       "expected": expected}
                if abs(abs(fp.trace) - 2.0) < TRACE_MARGIN:
                    rec["agree"] = None   # resonance: not classified
                else:
                    rec["agree"] = bool(fp.stable) == expected
                if np.max(np.abs(fp.point)) > 1e-9 or abs(fp.trace - tr_exact) > 1e-6 * max(1.0, abs(tr_exact)):
                    problems.append(f"I at c = {c:g}: fixed point {fp.point} trace {fp.trace:.10g}, "
                                    f"expected p = 0 and trace {tr_exact:.10g}")
                out.append(rec)
    for r in out:
        if r["agree"] is False:
            problems.append(f"{r['branch']} at c = {r['c']:g} ({r['method']}): numerically "
                            f"{'stable' if r['stable'] else 'unstable'}, drawn "
                            f"{'solid (stable)' if r['expected'] else 'dashed (unstable)'}")
    if problems:
        raise CheckError("figure3_check: " + "; ".join(problems))
    return out


# ====================================================================== dense integration
def advance(params, Y, tau, *, tol=DENSE_TOL):
    """States Y (N, 5) advanced by the time tau > 0 with the project's Taylor integrator
    (:func:`explorer.sections.crossings` stopped by its time budget, which ends the last step
    exactly at tau).  One thread: the call is short."""
    from explorer.analysis import sections
    from explorer.kernels import STATUS_TMAX

    Y = np.ascontiguousarray(np.atleast_2d(Y), dtype=float)
    res = sections.crossings(params, Y, 16, tmax=float(tau), tol=tol, threads=1)
    if not (np.all(res.status == STATUS_TMAX) and np.all(res.info[:, 0] == float(tau))):
        bad = int(np.flatnonzero((res.status != STATUS_TMAX) | (res.info[:, 0] != float(tau)))[0])
        raise RuntimeError(f"dense integration stopped early ({res.status_name(bad)} at t = {res.info[bad, 0]!r})")
    return res.final.copy()


def dense_orbits(params, Y0, t_end, dt, *, tol=DENSE_TOL, stop=None):
    """Samples of the orbits from Y0 (N, 5) every dt up to t_end: returns (t (n,), Y (n, N, 5)).
    ``stop(k, Y_k) -> bool`` may end the run early (checked after every sample)."""
    Y = np.ascontiguousarray(np.atleast_2d(Y0), dtype=float)
    n = int(math.ceil(t_end / dt - 1e-9))
    out = [Y.copy()]
    for k in range(1, n + 1):
        Y = advance(params, Y, dt, tol=tol)
        out.append(Y.copy())
        if stop is not None and stop(k, Y):
            break
    Ys = np.array(out)
    return dt * np.arange(len(Ys)), Ys


def _refine_p2_root(params, y_prev, dt, tol=DENSE_TOL):
    """The state where p2 changes sign within [0, dt] from y_prev (Illinois regula falsi on
    the integrated p2); returns (tau, state)."""
    a, fa = 0.0, y_prev[1]
    yb = advance(params, y_prev, dt, tol=tol)[0]
    b, fb = dt, yb[1]
    best = (b, yb)
    side = 0
    for _ in range(60):
        if fb == 0.0 or abs(b - a) < 1e-15:
            break
        x = b - fb * (b - a) / (fb - fa)
        if not (min(a, b) < x < max(a, b)):
            x = 0.5 * (a + b)
        yx = advance(params, y_prev, x, tol=tol)[0] if x > 0 else y_prev.copy()
        fx = yx[1]
        best = (x, yx)
        if abs(fx) < 1e-13:
            break
        if fx * fb < 0:
            a, fa = b, fb
            side = 0
        else:
            fa = fa / 2 if side == 1 else fa
            side = 1
        b, fb = x, fx
    return best


def _state5(y3):
    y3 = np.atleast_2d(y3)
    Y = np.zeros((len(y3), 5))
    Y[:, :3] = y3
    Y[:, 4] = 1.0   # phi = 0: gamma does not enter R6 (mu = 0)
    return Y


def meridian_points(params, h, c, n_grid=4001):
    """Points of {H = h} n {F = c} on the meridian p2 = 0 of the energy ellipsoid:
    p1 = sqrt(2 a1 h) sin(theta), M = sqrt(2 b h) cos(theta); every closed curve of the
    level set crosses it twice (R6 is reversible under (p2, t) -> (-p2, -t))."""
    prm = check_chaplygin(params)
    R1, R3 = math.sqrt(2 * prm.a1 * h), math.sqrt(2 * prm.b * h)

    def f(th):
        return R3 * np.cos(th) + (R1 * np.sin(th)) ** 2 / (2 * prm.lam) - c

    th = np.linspace(-math.pi, math.pi, n_grid)
    v = f(th)
    idx = np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)
    roots = []
    for i in idx:
        a, b = th[i], th[i + 1]
        fa = f(a)
        for _ in range(80):
            m = 0.5 * (a + b)
            fm = f(m)
            if fm == 0.0:
                a = b = m
                break
            if np.sign(fm) == np.sign(fa):
                a, fa = m, fm
            else:
                b = m
        roots.append(0.5 * (a + b))
    th = np.array(roots)
    return np.column_stack([R1 * np.sin(th), np.zeros_like(th), R3 * np.cos(th)])


def closed_curves(params, h, c_levels, *, dt=0.02, t_max=400.0, tol=DENSE_TOL):
    """The closed curves of {H = h} n {F = c} for each c of ``c_levels``, integrated with the
    Taylor method from their points on the meridian p2 = 0 over one period (until p2 has
    changed sign twice; the return point is located by regula falsi on the integrated p2).
    Duplicates (the second meridian point of a curve already drawn) are dropped.

    Returns a list of dicts: c, start (3,), y (n, 3) samples (last = located return point),
    t (n,), period, half (the other meridian point), closure (|return - start|)."""
    prm = check_chaplygin(params)
    starts, levels = [], []
    for c in c_levels:
        pts = meridian_points(prm, h, c)
        starts += list(pts)
        levels += [float(c)] * len(pts)
    if not starts:
        return []
    Y0 = _state5(np.array(starts))
    N = len(Y0)
    changes = [[] for _ in range(N)]      # sample indices k where p2 changed sign in (k-1, k]
    last_sign = np.zeros(N)

    def stop(k, Y):
        s = np.sign(Y[:, 1])
        for i in range(N):
            if s[i] == 0.0:
                continue
            if last_sign[i] != 0.0 and s[i] != last_sign[i] and len(changes[i]) < 2:
                changes[i].append(k)
            last_sign[i] = s[i]
        return all(len(ch) >= 2 for ch in changes)

    t, Ys = dense_orbits(prm, Y0, t_max, dt, tol=tol, stop=stop)
    curves = []
    covered = []
    for i in range(N):
        if len(changes[i]) < 2:
            raise RuntimeError(f"curve c = {levels[i]:g} through {starts[i]} did not close within t = {t_max:g}")
        k1, k2 = changes[i]
        tau1, y_half = _refine_p2_root(prm, Ys[k1 - 1, i], dt, tol)
        tau2, y_end = _refine_p2_root(prm, Ys[k2 - 1, i], dt, tol)
        start = np.asarray(starts[i])
        if any(levels[j] == levels[i] and np.linalg.norm(start - covered_pt) < 1e-6
               for j, covered_pt in covered):
            continue
        covered.append((i, y_half[:3].copy()))
        y = np.vstack([Ys[:k2, i, :3], y_end[None, :3]])
        tt = np.concatenate([t[:k2], [t[k2 - 1] + tau2]])
        curves.append({"c": levels[i], "start": start, "y": y, "t": tt, "period": float(tt[-1]),
                       "half": y_half[:3].copy(), "closure": float(np.linalg.norm(y_end[:3] - start))})
    return curves


def _figure2_levels(prm, h, n_levels, min_per_interval=2):
    """Values of c for the curves of one panel: n_levels uniform in (min F, max F) on the
    ellipsoid, at least ``min_per_interval`` (equally spaced) in every interval between
    critical values, none within 8 % of an interval's width from a critical value.
    Returns (levels, critical list)."""
    c1, c2 = critical_c(prm)
    hI = math.sqrt(2 * prm.b * h)
    crit = [(-hI, "I-"), (hI, "I+")]
    for branch, cj in (("II", c1), ("III", c2)):
        a = _aj(prm, branch)
        if h > prm.b * prm.lam ** 2 / (2 * a * a):
            crit.append((a * h / prm.lam + prm.lam * prm.b / (2 * a), branch))
    crit.sort()
    lo, hi = crit[0][0], crit[-1][0]
    uniform = lo + (hi - lo) * (np.arange(n_levels) + 0.5) / n_levels
    levels = []
    for (ca, _), (cb, _) in zip(crit[:-1], crit[1:]):
        w = cb - ca
        if w <= 0:
            continue
        inside = [c for c in uniform if ca + 0.08 * w < c < cb - 0.08 * w]
        if len(inside) < min_per_interval:
            inside = list(ca + w * (np.arange(min_per_interval) + 1.0) / (min_per_interval + 1))
        levels += inside
    return sorted(levels), crit


def _separatrix_III(prm, h, c, *, dt, tol, t_max=60.0):
    """Heteroclinic curves of the saddles III at F = c: integrated forward from their meridian
    points until they reach a saddle (within 1e-3); the backward half is the mirror image
    p2 -> -p2 (the reversibility (p2, t) -> (-p2, -t) of R6)."""
    pts = meridian_points(prm, h, c)
    if not len(pts):
        return []
    sad = np.array([relative_equilibrium("III", c, prm, s) for s in (1, -1)])
    near = np.zeros(len(pts), bool)
    ends = np.full(len(pts), -1)

    def stop(k, Y):
        d = np.min(np.linalg.norm(Y[:, None, :3] - sad[None], axis=2), axis=1)
        for i in np.flatnonzero((d < 1e-3) & ~near):
            near[i] = True
            ends[i] = k
        return bool(np.all(near))

    t, Ys = dense_orbits(prm, _state5(pts), t_max, dt, tol=tol, stop=stop)
    out = []
    for i in range(len(pts)):
        k = ends[i] if ends[i] > 0 else len(t)
        fwd = Ys[:k + 1, i, :3]
        back = fwd[::-1] * np.array([1.0, -1.0, 1.0])
        out.append(np.vstack([back[:-1], fwd]))
    return out


def figure2(params=CHAPLYGIN, energies=FIGURE2_ENERGIES, *, n_levels=9, dt=0.02, tol=DENSE_TOL, dpi=200,
            elev=24.0, azim=-55.0) -> Drawn:
    """The seed's Figure 2: trajectories of R6 in (p1, p2, M), the curves where the energy
    ellipsoid H = h meets the paraboloid F = c, one panel per energy (the seed's three
    intervals).  Closed curves integrated over one period (:func:`closed_curves`); the
    separatrices in red: R7 for the saddle I (exact, both branches p -> -p) and the integrated
    heteroclinic curves of the saddles III; permanent rotations marked (filled: stable, open:
    unstable).  Curves in front of the ellipsoid are dark, behind it light.

    data["panels"][i]: h, curves (list of closed_curves dicts), separatrices (list of (n, 3)),
    equilibria (list of (branch, state, stable)), levels, critical."""
    from explorer.model import exact

    prm = check_chaplygin(params)
    h1, h2 = critical_h(prm)
    panels = []
    for h in energies:
        levels, crit = _figure2_levels(prm, h, n_levels)
        curves = closed_curves(prm, h, levels, dt=dt, tol=tol)
        seps = []
        c1, c2 = critical_c(prm)
        cI = math.sqrt(2 * prm.b * h)
        if c1 < cI < c2:   # the upper pole I is a saddle: its homoclinic loops R7
            tt = np.linspace(-30.0, 30.0, 3001)
            for s in (1, -1):
                p1, p2, M, _phi = exact.homoclinic(prm.as_array(), cI, tt, sign=s)
                seps.append(np.column_stack([p1, p2, M]))
        for cval, kind in crit:
            if kind == "III":
                seps += _separatrix_III(prm, h, cval, dt=dt, tol=tol)
        eq = []
        for cval, kind in crit:
            if kind in ("I+", "I-"):
                y = np.array([0.0, 0.0, cval])
                st = branch_stable("I", cval, prm) if cval not in (c1, c2) else True
                eq.append(("I", y, st))
            else:
                for s in (1, -1):
                    eq.append((kind, relative_equilibrium(kind, cval, prm, s), kind == "II"))
        panels.append({"h": h, "curves": curves, "separatrices": seps, "equilibria": eq, "levels": levels,
                       "critical": crit})
    fig = _draw_figure2(prm, panels, (h1, h2), dpi=dpi, elev=elev, azim=azim)
    return Drawn(fig, {"panels": panels, "params": prm.as_dict()})


def _interval_title(h, h1, h2, k):
    tag = "abcdefgh"[k]
    if h < h1:
        rel = rf"$h = {h:g} < b\lambda^2/2a_1^2 = {h1:g}$"
    elif h < h2:
        rel = rf"${h1:g} < h = {h:g} < b\lambda^2/2a_2^2 = {h2:g}$"
    else:
        rel = rf"$h = {h:g} > b\lambda^2/2a_2^2 = {h2:g}$"
    return f"({tag}) " + rel


def _ellipsoid_silhouette(R, eye, n=400):
    """The outline of the ellipsoid sum (x_i/R_i)^2 = 1 seen along ``eye`` (orthographic):
    its intersection with the plane through 0 normal to A eye, A = diag(1/R^2)."""
    nrm = eye / R ** 2
    nrm = nrm / np.linalg.norm(nrm)
    u = np.cross(nrm, [0.0, 0.0, 1.0] if abs(nrm[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(nrm, u)
    th = np.linspace(0, 2 * math.pi, n)
    d = np.cos(th)[:, None] * u + np.sin(th)[:, None] * v
    s = 1.0 / np.sqrt(np.sum((d / R) ** 2, axis=1))
    return d * s[:, None]


def _split_visible(y, R, eye):
    """Split a polyline on the ellipsoid into runs in front of (normal . eye >= 0) and behind it."""
    vis = (y / R ** 2) @ eye >= 0
    runs = []
    start = 0
    for k in range(1, len(y) + 1):
        if k == len(y) or vis[k] != vis[start]:
            seg = y[start:min(k + 1, len(y))]
            runs.append((bool(vis[start]), seg))
            start = k
    return runs


def _draw_figure2(prm, panels, hcrit, *, dpi, elev, azim):
    import mpl_toolkits.mplot3d  # noqa: F401  (registers the 3d projection)
    from matplotlib.ticker import MaxNLocator

    h1, h2 = hcrit
    n = len(panels)
    eye = np.array([math.cos(math.radians(elev)) * math.cos(math.radians(azim)),
                    math.cos(math.radians(elev)) * math.sin(math.radians(azim)), math.sin(math.radians(elev))])
    with _rc():
        fig = _new_figure((3.4 * n, 4.1), dpi=dpi, layout=None)
        for k, p in enumerate(panels):
            h = p["h"]
            R = np.array([math.sqrt(2 * prm.a1 * h), math.sqrt(2 * prm.a2 * h), math.sqrt(2 * prm.b * h)])
            ax = fig.add_axes([k / n + 0.005, 0.085, 1.0 / n - 0.01, 0.79], projection="3d", proj_type="ortho")
            ax.view_init(elev=elev, azim=azim)
            # faint ellipsoid and its outline
            uu, vv = np.meshgrid(np.linspace(0, 2 * math.pi, 60), np.linspace(0, math.pi, 30))
            ax.plot_surface(R[0] * np.cos(uu) * np.sin(vv), R[1] * np.sin(uu) * np.sin(vv), R[2] * np.cos(vv),
                            color="0.85", alpha=0.12, linewidth=0, shade=False, zorder=0)
            sil = _ellipsoid_silhouette(R, eye)
            ax.plot(sil[:, 0], sil[:, 1], sil[:, 2], color="0.35", lw=0.6, zorder=1)
            for cur in p["curves"]:
                for front, seg in _split_visible(cur["y"], R, eye):
                    ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], color="k" if front else "0.72",
                            lw=0.75 if front else 0.5, zorder=3 if front else 2, gid="curve")
            for sep in p["separatrices"]:
                for front, seg in _split_visible(sep, R, eye):
                    ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], color="#c0392b" if front else "#eaa39b",
                            lw=1.2 if front else 0.8, zorder=4 if front else 2, gid="separatrix")
            for kind, y, st in p["equilibria"]:
                front = (y / R ** 2) @ eye >= -1e-12
                ax.scatter([y[0]], [y[1]], [y[2]], s=14, marker="o", depthshade=False, zorder=5,
                           facecolors=("k" if st else "white"), edgecolors="k" if front else "0.6",
                           linewidths=0.8, gid=f"eq-{kind}")
                if kind == "I":
                    pos = y + np.array([0.09 * R[0], 0.0, 0.07 * R[2] * (1 if y[2] > 0 else -1)])
                else:
                    pos = y * np.array([1.2, 1.2, 1.0]) + np.array([0.0, 0.0, 0.06 * R[2]])
                ax.text(pos[0], pos[1], pos[2], kind, fontsize=_SMALL, ha="center", va="center",
                        color="k" if front else "0.55", zorder=6)
            ax.set_xlim(-R[0], R[0])
            ax.set_ylim(-R[1], R[1])
            ax.set_zlim(-R[2], R[2])
            ax.set_box_aspect(tuple(R), zoom=1.12)
            ax.set_xlabel("$p_1$", fontsize=_FS, labelpad=-5)
            ax.set_ylabel("$p_2$", fontsize=_FS, labelpad=-5)
            ax.set_zlabel("$M$", fontsize=_FS, labelpad=-6)
            ax.tick_params(labelsize=6, pad=-2.5)
            for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
                axis.set_pane_color((1, 1, 1, 0))
                axis._axinfo["grid"]["color"] = (0.88, 0.88, 0.88, 1)
                axis._axinfo["grid"]["linewidth"] = 0.3
                axis.set_major_locator(MaxNLocator(3, symmetric=True))
            fig.text((k + 0.5) / n, 0.905, _interval_title(h, h1, h2, k), ha="center", va="center", fontsize=_FS)
        fig.text(0.5, 0.985, r"$\lambda = %g,\ b = %g,\ a_1 = %g,\ a_2 = %g,\ \chi = \zeta = \mu = 0$.  "
                 r"Black: $\{H = h\}\cap\{F = c\}$ (integrated), light: behind the ellipsoid; red: separatrices; "
                 r"$\bullet$ stable, $\circ$ unstable permanent rotations I, II, III"
                 % (prm.lam, prm.b, prm.a1, prm.a2), ha="center", va="top", fontsize=_SMALL)
    return fig


# ====================================================================== Figure 3
def figure3(params=CHAPLYGIN, *, check=True, c_range=(-1.5, 6.6), h_max=8.0, energies=FIGURE2_ENERGIES,
            dpi=200) -> Drawn:
    """The seed's Figure 3, the bifurcation diagram of Chaplygin's case in the (c, h) plane:
    the parabola of I (h = c^2/(2b)) and the lines of II and III tangent to it at
    c = lam b/a_j, unstable parts dashed (I for lam b/a1 < c < lam b/a2; III), the admissible
    region {h >= :func:`admissible_hmin` (c)} in gray, the marks lam b/a_j and b lam^2/(2 a_j^2),
    the energies of Figure 2, and the points checked by :func:`figure3_check` (filled:
    numerically stable, open: unstable).

    Artists carry gids: "admissible", "I-stable", "I-unstable", "II", "III", "checked".
    data: segments {gid: (c array, h array, dashed)}, checks (the records)."""
    prm = check_chaplygin(params)
    c1, c2 = critical_c(prm)
    hc1, hc2 = critical_h(prm)
    c0, cE = c_range
    records = figure3_check(prm) if check else []
    cc = np.linspace(c0, cE, 1601)
    segs = {}

    def seg(gid, lo, hi, branch, dashed):
        c = np.linspace(lo, hi, 400)
        segs.setdefault(gid, []).append((c, branch_h(branch, c, prm), dashed))

    seg("I-stable", c0, c1, "I", False)
    seg("I-unstable", c1, c2, "I", True)
    seg("I-stable", c2, cE, "I", False)
    seg("II", c1, cE, "II", False)
    seg("III", c2, cE, "III", True)
    styles = {"I": dict(color="k"), "II": dict(color="#1f4e9c"), "III": dict(color="#b2182b")}
    with _rc():
        fig = _new_figure((5.2, 4.0), dpi=dpi)
        ax = fig.subplots()
        hmin = admissible_hmin(cc, prm)
        ax.fill_between(cc, hmin, h_max + 1.0, color="0.86", lw=0, zorder=0, gid="admissible",
                        label="admissible $(c, h)$")
        for gid, parts in segs.items():
            base = styles[gid.split("-")[0]]
            for j, (c, hh, dashed) in enumerate(parts):
                ax.plot(c, hh, ls=(0, (5, 3)) if dashed else "-", lw=1.3, gid=gid, zorder=3, **base)
        # tangency marks
        for cj, hj, lab in ((c1, hc1, "1"), (c2, hc2, "2")):
            ax.plot([cj, cj], [0, hj], ls=":", color="0.4", lw=0.7, zorder=1)
            ax.plot([c0, cj], [hj, hj], ls=":", color="0.4", lw=0.7, zorder=1)
            ax.plot([cj], [hj], "o", ms=3, color="k", zorder=4)
        # labels of the branches
        def lab(x, branch, text, dy, ha="left"):
            y = float(branch_h(branch, x, prm))
            ax.text(x, y + dy, text, fontsize=_SMALL, ha=ha, va="center", color=styles[branch]["color"],
                    zorder=5, bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
        lab(-0.9, "I", r"I: $h = c^2/2b$", 0.75)
        lab(5.0, "II", r"II: $h = \frac{\lambda}{a_1}c - \frac{\lambda^2 b}{2a_1^2}$", -0.75)
        ax.annotate(r"III: $h = \frac{\lambda}{a_2}c - \frac{\lambda^2 b}{2a_2^2}$",
                    xy=(4.9, float(branch_h("III", 4.9, prm))), xytext=(4.45, 6.4), fontsize=_SMALL, ha="right",
                    va="center", color=styles["III"]["color"], zorder=5,
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8),
                    arrowprops=dict(arrowstyle="-", lw=0.5, color=styles["III"]["color"], shrinkA=0, shrinkB=1))
        # checked points
        for r in records:
            if r["method"] == "jacobian" and r["branch"] == "I" and r["c"] > 0:
                continue    # shown by the monodromy check
            if r["agree"] is None:
                continue
            ax.plot([r["c"]], [r["h"]], marker="o" if r["method"] == "monodromy" else "s", ms=4.2,
                    mfc="k" if r["stable"] else "white", mec="k", mew=0.8, ls="none", zorder=6, gid="checked")
        # energies of Figure 2
        for k, h in enumerate(energies):
            if h < h_max:
                ax.annotate(f"Fig. 2({'abc'[k]})", xy=(cE, h), xytext=(cE - 0.08, h), fontsize=6, ha="right",
                            va="center", color="0.3")
                ax.plot([cE - 0.06, cE], [h, h], color="0.3", lw=0.8, zorder=2)
        ax.set_xlim(c0, cE)
        ax.set_ylim(0, h_max)
        ax.set_xlabel("$c$ (value of $F$)")
        ax.set_ylabel("$h$ (value of $H$)")
        ax.minorticks_on()
        top = ax.secondary_xaxis("top")
        top.set_xticks([c1, c2], [r"$\lambda b/a_1$", r"$\lambda b/a_2$"])
        top.tick_params(labelsize=_TS, direction="in", length=3)
        right = ax.secondary_yaxis("right")
        right.set_yticks([hc1, hc2], [r"$\frac{b\lambda^2}{2a_1^2}$", r"$\frac{b\lambda^2}{2a_2^2}$"])
        right.tick_params(labelsize=_TS, direction="in", length=3)
        from matplotlib.lines import Line2D
        from matplotlib.patches import Patch

        handles = [Line2D([], [], color="k", lw=1.3, label="stable"),
                   Line2D([], [], color="k", lw=1.3, ls=(0, (5, 3)), label="unstable"),
                   Line2D([], [], marker="o", ls="none", mfc="k", mec="k", ms=4,
                          label="checked: monodromy of the orbit I"),
                   Line2D([], [], marker="s", ls="none", mfc="k", mec="k", ms=4,
                          label="checked: eigenvalues of R6 (II, III; I at c < 0)"),
                   Line2D([], [], marker="o", ls="none", mfc="white", mec="k", ms=4,
                          label="open marker: numerically unstable"),
                   Patch(color="0.86", label="admissible region")]
        ax.legend(handles=handles, loc="upper left", frameon=True, framealpha=0.9, edgecolor="none",
                  borderpad=0.4, handlelength=2.4)
        ax.set_title(rf"$a_1 > a_2$:  $\lambda = {prm.lam:g}$, $b = {prm.b:g}$, $a_1 = {prm.a1:g}$, "
                     rf"$a_2 = {prm.a2:g}$", fontsize=_FS)
    data = {"segments": {g: [(c, hh, d) for c, hh, d in parts] for g, parts in segs.items()}, "checks": records,
            "critical_c": (c1, c2), "critical_h": (hc1, hc2)}
    return Drawn(fig, data)


# ====================================================================== homoclinic (R7)
def homoclinic_figure(params=CHAPLYGIN, h=2.0, *, T0=20.0, dt=0.02, tol=1e-15, dpi=200) -> Drawn:
    """R7 (both separatrices, sign = +1 and the p -> -p branch sign = -1) against the
    integrated flow: the exact state at t = -T0 is integrated with the Taylor method (dense
    samples every dt, and the crossings of phi = pi by :func:`explorer.sections.crossings`),
    drawn in (p1, p2) and (t, M); the crossing times of
    :func:`explorer.exact.homoclinic_crossing_times` against the integrator's.

    data[sign]: t_exact, t_integrated (crossing times), max_dt (their largest difference),
    t (samples), y (integrated samples (n, 5)), exact (p1, p2, M at the samples)."""
    from explorer.analysis import sections
    from explorer.model import exact

    prm = check_chaplygin(params)
    P = prm.as_array()
    c = math.sqrt(2 * prm.b * h)
    data = {"c": c, "h": h, "T0": T0}
    starts = []
    for s in (1, -1):
        p1, p2, M, phi = exact.homoclinic(P, c, np.array([-T0]), sign=s)
        starts.append([p1[0], p2[0], M[0], math.sin(phi[0]), math.cos(phi[0])])
    Y0 = np.array(starts)
    t, Ys = dense_orbits(prm, Y0, 2 * T0, dt, tol=tol)
    t = t - T0
    for i, s in enumerate((1, -1)):
        expect = exact.homoclinic_crossing_times(P, c, math.pi, -T0, T0, sign=s)
        res = sections.crossings(prm, Y0[i], len(expect), tmax=2 * T0, tol=tol, threads=1)
        got = res.orbit(0)[:, 0] - T0
        n = min(len(got), len(expect))
        diff = np.abs(got[:n] - expect[:n]) if n else np.array([np.inf])
        p1, p2, M, _ = exact.homoclinic(P, c, t, sign=s)
        pts_exact = exact.homoclinic(P, c, expect, sign=s)
        data[s] = {"t_exact": expect, "t_integrated": got, "count_exact": len(expect), "count_integrated": len(got),
                   "max_dt": float(diff.max()), "t": t, "y": Ys[:, i, :], "exact": np.column_stack([p1, p2, M]),
                   "cross_exact": np.column_stack(pts_exact[:3]), "cross_integrated": res.orbit(0)[:, 1:4]}
    colours = {1: "#1f4e9c", -1: "#b2182b"}
    with _rc():
        fig = _new_figure((10.5, 3.4), dpi=dpi)
        axs = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1.0, 1.35, 1.0]})
        ax = axs[0]
        for s in (1, -1):
            d = data[s]
            ax.plot(d["exact"][:, 0], d["exact"][:, 1], color=colours[s], lw=1.4, alpha=0.55,
                    label=f"R7, sign {s:+d}")
            ax.plot(d["y"][::10, 0], d["y"][::10, 1], ".", color=colours[s], ms=1.8, label="integrated")
            ax.plot(d["cross_exact"][:, 0], d["cross_exact"][:, 1], "o", mfc="none", mec="k", ms=4, mew=0.6)
            ax.plot(d["cross_integrated"][:, 0], d["cross_integrated"][:, 1], "x", color="k", ms=3, mew=0.7)
        ax.plot([0], [0], "o", color="k", ms=3)
        ax.annotate("I", (0, 0), xytext=(4, 4), textcoords="offset points", fontsize=_SMALL)
        ax.set_xlabel("$p_1$")
        ax.set_ylabel("$p_2$")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title("(a) the two separatrices of I", fontsize=_FS)
        from matplotlib.lines import Line2D

        ax.legend(handles=[Line2D([], [], color=colours[1], lw=1.4, alpha=0.6, label="R7, sign +1"),
                           Line2D([], [], color=colours[-1], lw=1.4, alpha=0.6, label=r"R7, sign $-1$ ($p\to-p$)"),
                           Line2D([], [], ls="none", marker=".", ms=3, color="0.3", label="integrated (Taylor)"),
                           Line2D([], [], ls="none", marker="o", ms=4, mfc="none", mec="k",
                                  label=r"exact crossing $\varphi=\pi$"),
                           Line2D([], [], ls="none", marker="x", ms=3, color="k", label="integrator's crossing")],
                  loc="lower center", fontsize=6, frameon=False, ncol=2, bbox_to_anchor=(0.5, -0.02))
        ax.margins(0.05, 0.28)
        ax = axs[1]
        d = data[1]
        ax.plot(d["t"], d["exact"][:, 2], color="k", lw=1.4, alpha=0.5, label="R7 (both signs)")
        ax.plot(d["t"][::10], d["y"][::10, 2], ".", color=colours[1], ms=1.8, label="integrated, sign +1")
        ax.plot(data[-1]["t"][5::10], data[-1]["y"][5::10, 2], ".", color=colours[-1], ms=1.8,
                label=r"integrated, sign $-1$")
        Mx = exact.homoclinic(P, c, d["t_exact"])[2]
        ax.plot(d["t_exact"], Mx, "o", mfc="none", mec="k", ms=4.5, mew=0.7,
                label=r"exact crossings of $\varphi = \pi$")
        ax.plot(d["t_integrated"], d["cross_integrated"][:, 2], "x", color="k", ms=4, mew=0.8,
                label="integrator's crossings")
        ax.axhline(c, color="0.6", lw=0.6, ls=":")
        ax.set_xlabel("$t$")
        ax.set_ylabel("$M$")
        ax.set_xlim(-T0, T0)
        ax.set_title(rf"(b) $M(t)$, $c = \sqrt{{2bh}} = {c:.4g}$", fontsize=_FS)
        ax.legend(loc="lower left", fontsize=6, frameon=False)
        ax = axs[2]
        for s, mk, ms in ((1, "o", 6.0), (-1, "s", 3.0)):
            d = data[s]
            n = min(len(d["t_exact"]), len(d["t_integrated"]))
            err = np.abs(d["t_integrated"][:n] - d["t_exact"][:n])
            ax.semilogy(d["t_exact"][:n], np.maximum(err, 1e-17), mk, color=colours[s], ms=ms, mfc="none",
                        mew=0.9, label=f"sign {s:+d}: max {d['max_dt']:.1e}")
        ax.axhline(1e-8, color="0.4", lw=0.7, ls="--")
        ax.text(T0 * 0.97, 1.5e-8, "test bound $10^{-8}$", fontsize=6, color="0.3", ha="right", va="bottom")
        ax.text(T0 * 0.97, 1.6e-17, "(0 drawn at $10^{-17}$)", fontsize=5.5, color="0.4", ha="right", va="bottom")
        ax.set_ylim(1e-17, 1e-6)
        ax.set_xlabel(r"crossing time $t_k$ (exact)")
        ax.set_ylabel(r"$|t_k^{\rm integrated} - t_k^{\rm exact}|$")
        ax.set_title("(c) crossing times: integrator vs R7", fontsize=_FS)
        ax.legend(loc="upper left", fontsize=6, frameon=False)
        fig.suptitle(rf"Homoclinic orbits of solution I (R7) at $h = {h:g}$, $\mu = 0$; start $t = -{T0:g}$, "
                     rf"Taylor tol {tol:.0e}", fontsize=_FS)
    return Drawn(fig, data)


# ====================================================================== continuation
def _refine_trace_min(prm, h, mu, tr, points):
    """(mu, trace) of the least trace near the sampled minimum, by golden-section search over
    fixed points (Newton from the neighbouring sample); None if the minimum is at an end or
    not near -2."""
    from explorer.analysis import fixedpoints

    k = int(np.argmin(tr))
    if k == 0 or k == len(tr) - 1 or tr[k] > -1.9:
        return None
    guess = points[k]

    def f(m):
        return fixedpoints.find_fixed_point(prm.with_(mu=float(m)), h, guess).trace

    a, b = float(mu[k - 1]), float(mu[k + 1])
    g = (math.sqrt(5) - 1) / 2
    x1, x2 = b - g * (b - a), a + g * (b - a)
    f1, f2 = f(x1), f(x2)
    while b - a > 1e-7:
        if f1 < f2:
            b, x2, f2 = x2, x1, f1
            x1 = b - g * (b - a)
            f1 = f(x1)
        else:
            a, x1, f1 = x1, x2, f2
            x2 = a + g * (b - a)
            f2 = f(x2)
    return (x1, f1) if f1 < f2 else (x2, f2)


def continuation_figure(params=None, h=None, *, start=0.0, stop=8.0, step=0.1, dpi=200,
                        marks=(0.002, 0.01, 0.03, 4.0, 8.0), refine_min=True) -> Drawn:
    """The central fixed point of the section map phi = pi at h = 2 continued in mu
    (:func:`explorer.fixedpoints.continue_branch`): its p1 and the monodromy trace against mu,
    the lines trace = +-2, the value where it turns stable; the analytic trace of solution I at
    mu = 0 (:func:`fixedpoints.analytic_eigenvalues_solution_I`); ticks at Figure 4's mu."""
    from explorer.analysis import fixedpoints

    prm = model.FIGURE4 if params is None else params
    h = model.FIGURE4_H if h is None else h
    br = fixedpoints.continue_branch(prm, h, "mu", start, stop, step)
    mu = np.asarray(br.values, float)
    p1 = np.array([fp.point[0] for fp in br.points])
    p2 = np.array([fp.point[1] for fp in br.points])
    tr = np.array([fp.trace for fp in br.points])
    _ev, tr0 = fixedpoints.analytic_eigenvalues_solution_I(prm.with_(mu=0.0), h)
    stable = np.abs(tr) < 2
    tmin = _refine_trace_min(prm, h, mu, tr, [fp.point for fp in br.points]) if refine_min else None
    with _rc():
        fig = _new_figure((5.0, 4.6), dpi=dpi)
        ax1, ax2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [1, 1.3]})
        for ax in (ax1, ax2):
            for b in br.bifurcations:
                ax.axvline(b, color="0.45", lw=0.8, ls="--", zorder=1)
        c1s = np.array([model.allowed_ellipse(prm.with_(mu=m), h)[0] for m in mu])
        ax1.plot(mu, c1s, color="0.6", lw=0.8, ls=":", label=r"centre of the allowed region, $-a_1\mu/\lambda$")
        ax1.plot(mu[~stable], p1[~stable], "o", color="#b2182b", ms=2.6, label="hyperbolic (unstable)")
        ax1.plot(mu[stable], p1[stable], "o", color="#1f4e9c", ms=2.6, label="elliptic (stable)")
        ax1.set_ylabel("$p_1$ of the fixed point")
        ax1.legend(fontsize=6, frameon=False, loc="lower left")
        ax1.text(0.98, 0.94, rf"$p_2 = 0$ (max $|p_2|$ = {np.max(np.abs(p2)):.0e})", transform=ax1.transAxes,
                 ha="right", va="top", fontsize=6)
        ax2.axhspan(-2, 2, color="0.9", lw=0, zorder=0)
        ax2.axhline(2, color="0.3", lw=0.7)
        ax2.axhline(-2, color="0.3", lw=0.7)
        ax2.plot(mu, tr, "-", color="k", lw=1.0, zorder=2)
        ax2.plot(mu[~stable], tr[~stable], "o", color="#b2182b", ms=2.6, zorder=3)
        ax2.plot(mu[stable], tr[stable], "o", color="#1f4e9c", ms=2.6, zorder=3)
        ax2.plot([0.0], [tr0], "*", color="k", ms=9, mfc="none", zorder=4, clip_on=False,
                 label=rf"solution I, linearised R6: $2\cosh(\sqrt{{-\alpha\beta}}\,T)$ = {tr0:.5g}")
        for b in br.bifurcations:
            ax2.annotate(rf"$\mu^* = {b:.6g}$", xy=(b, 2), xytext=(b + 0.25, 5.0), fontsize=_SMALL,
                         arrowprops=dict(arrowstyle="->", lw=0.6))
        ax2.text(stop * 0.98, 1.55, "stable: $|\\mathrm{tr}| < 2$", ha="right", va="center", fontsize=_SMALL,
                 color="0.3")
        ax2.set_ylabel("trace of the monodromy")
        ax2.set_xlabel(r"$\mu$")
        ax2.legend(fontsize=6, frameon=False, loc="upper right")
        ax2.set_xlim(start, stop)
        for ax in (ax1, ax2):
            ax.minorticks_on()
        ax1.plot(list(marks), [1.0] * len(marks), "v", color="#b2182b", ms=4, clip_on=False, zorder=5,
                 transform=ax1.get_xaxis_transform(), label=r"the $\mu$ of Figure 4's panels")
        ax1.legend(fontsize=6, frameon=False, loc="lower left")
        if tmin is not None:
            ax2.annotate(f"least trace at $\\mu = {tmin[0]:.4f}$: tr + 2 = {tmin[1] + 2:.0e},\n"
                         "touches $-2$ to round-off, no crossing (1:2 resonance)", xy=(tmin[0], tmin[1]),
                         xytext=(6.35, -0.55), fontsize=6, ha="center", va="center",
                         arrowprops=dict(arrowstyle="->", lw=0.5))
        ax1.set_title(rf"central fixed point of $\varphi = \pi$, $h = {h:g}$ (Figure 4's scene)", fontsize=_FS)
    data = {"mu": mu, "p1": p1, "p2": p2, "trace": tr, "bifurcations": list(br.bifurcations), "trace_mu0": tr0,
            "trace_min": tmin}
    return Drawn(fig, data)


# ====================================================================== work-precision
def _method_group(row):
    m = row["method"]
    setting = row.get("setting", "")
    if "1 thread" in setting:
        return m + " (1 thread)"
    if "heyoka" in m and "batch" in m:
        return "heyoka batch, " + ("2 processes" if "2 proc" in setting else "1 process")
    if "heyoka" in m:
        return "heyoka scalar, 1 process"
    if "scipy" in m:
        return "scipy solve_ivp DOP853"
    return m


def _short_setting(s):
    s = s.split(",")[0].replace("rtol=atol ", "").replace("tol ", "").replace("dt ", "dt = ")
    return s


#: marker, colour, line style of each method group of the work-precision figure
WP_STYLE = {
    "explorer taylor": ("o", "#1f4e9c", "-"), "explorer taylor (1 thread)": ("o", "#7fa6d9", ":"),
    "explorer dop853": ("s", "#2a9d4b", "-"), "explorer split8": ("D", "#8e44ad", "-"),
    "explorer split6": ("v", "#c27ba0", "-"), "explorer split4": ("^", "#e08e0b", "-"),
    "scipy solve_ivp DOP853": ("P", "0.3", "-"),
    "heyoka batch, 2 processes": ("h", "#b2182b", "-"), "heyoka batch, 1 process": ("h", "#e88f85", ":"),
    "heyoka scalar, 1 process": ("X", "#7b241c", "-"),
}


def work_precision_figure(path, *, dpi=200) -> Drawn:
    """One-step error of the section map (median, with a bar up to the max) against the
    throughput (crossings per second) of every method and setting of the W4 benchmark,
    scipy and heyoka included (log-log).  Points of one method are joined in the order of
    their median error; scipy's rate is extrapolated from a few orbits (open marker).

    data: groups {name: number of rows}, n_rows, points {name: [(rate, median, max, setting)]}."""
    path = Path(path)
    doc = json.loads(path.read_text())
    rows = doc["rows"]
    groups = {}
    for r in rows:
        groups.setdefault(_method_group(r), []).append(r)
    points = {}
    with _rc():
        fig = _new_figure((6.6, 4.7), dpi=dpi)
        ax = fig.subplots()
        for g, rs in groups.items():
            mk, col, ls = WP_STYLE.get(g, ("o", "0.5", "-"))
            rs = sorted(rs, key=lambda r: -r["err_median"])
            x = np.array([r["rate"] for r in rs])
            y = np.array([r["err_median"] for r in rs])
            ymax = np.array([r["err_max"] for r in rs])
            extra = any(r.get("extrapolated") for r in rs)
            points[g] = [(r["rate"], r["err_median"], r["err_max"], r["setting"]) for r in rs]
            ax.vlines(x, y, ymax, color=col, lw=0.6, alpha=0.6, zorder=1)
            ax.plot(x, ymax, ls="none", marker="_", color=col, ms=5, mew=0.8, zorder=2)
            label = g.replace("explorer ", "explorer: ") + (" (rate extrapolated)" if extra else "")
            ax.plot(x, y, ls=ls, lw=0.8, marker=mk, color=col, ms=4, mfc="white" if extra else col,
                    mec=col, mew=0.8, zorder=3, label=label)
            below = g.startswith("explorer") or g.startswith("scipy")
            for r in rs:
                ax.annotate(_short_setting(r["setting"]), (r["rate"], r["err_median"]),
                            xytext=(3, -6) if below else (-3, 4), textcoords="offset points", fontsize=4.5,
                            color=col, ha="left" if below else "right")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("throughput (section crossings per second)")
        ax.set_ylabel("one-step error of the section map\n(median; bar up to the maximum)")
        meta = doc.get("meta", {})
        wl = meta.get("workload", {})
        mach = meta.get("machine", {})
        mu = wl.get("params", {}).get("mu", "?")
        ax.set_title(f"W4: Figure-4 section, $\\mu = {mu}$, $h = {wl.get('h', '?')}$, {wl.get('n_orbits', '?')} orbits "
                     f"$\\times$ {wl.get('n_crossings', '?')} crossings, {mach.get('cpus', '?')} cores "
                     f"({str(meta.get('date', ''))[:10]})", fontsize=8)
        ax.legend(fontsize=5.5, loc="upper left", frameon=True, framealpha=0.95, edgecolor="none", ncol=2,
                  handlelength=2.2)
        ax.grid(which="major", color="0.92", lw=0.4)
        ref = doc.get("reference", {}).get("reference", "")
        if ref:
            ax.text(0.01, 0.01, "one-step error against " + ref, transform=ax.transAxes, ha="left", va="bottom",
                    fontsize=4.5, color="0.4")
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi * 30)   # room for the legend
    return Drawn(fig, {"groups": {g: len(rs) for g, rs in groups.items()}, "n_rows": len(rows), "points": points})


# ====================================================================== sweeps
def _quick_scene(name, results_dir):
    """A reduced copy of a preset scene (QUICK_SCENES), written as a TOML file; returns its path."""
    from explorer.io import scene as sc

    d = sc.load_scene(name).to_dict()
    d["name"] = f"{name}-quick"
    d["description"] = (d.get("description") or "") + " [reduced settings of `figures --quick`]"
    for (table, key), v in QUICK_SCENES[name].items():
        d[table][key] = v
    s = sc.scene_from_dict(d)
    path = Path(results_dir) / f"{s.name}.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    text = s.to_toml()
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return path


def store_complete(scene, path) -> bool:
    """True when every panel of ``scene`` is stored in ``path`` with its settings hash."""
    from explorer.io import store

    try:
        on_disk = store.panel_hashes(path)
    except store.StoreError:
        return False
    return all(on_disk.get(i) == scene.panel_hash(i) for i in range(scene.n_panels))


def ensure_sweep(preset, *, results_dir="results", quick=False, quiet=True):
    """The scene and store of a preset, computing what is missing with
    :func:`explorer.app.runner.run_sweep` (complete panels with the same hash are skipped).
    Under ``quick`` an incomplete full store is left alone and the reduced scene is used.
    Returns (scene, store path, reduced?, summary text)."""
    from explorer.app import runner
    from explorer.io.scene import load_scene

    results_dir = Path(results_dir)
    scene = load_scene(preset)
    out = results_dir / f"{scene.name}.h5"
    reduced = False
    spec = preset
    if quick and not store_complete(scene, out):
        spec = str(_quick_scene(preset, results_dir))
        scene = load_scene(spec)
        out = results_dir / f"{scene.name}.h5"
        reduced = True
    report = runner.run_sweep(scene, out, draw=False, progress=not quiet)
    return scene, out, reduced, runner.format_report(report)


def _quick_note(scene):
    s = scene
    bits = [f"{s.seeds.n} seeds", f"{s.integration.crossings} crossings"]
    if "lyapunov" in s.compute:
        bits.append(f"MEGNO time {s.lyapunov.time:g}")
    return "reduced settings (figures --quick): " + ", ".join(bits)


def figure4_figure(out_dir, *, results_dir="results", quick=False, quiet=True):
    """Figure 4 from the preset scene's store (computed if needed): runner.draw_figure."""
    from explorer.app import runner

    scene, out, reduced, summary = ensure_sweep("figure4", results_dir=results_dir, quick=quick, quiet=quiet)
    stem = Path(out_dir) / "figure4"
    paths = runner.draw_figure(scene, out, stem)
    msg = f"from {out}" + (f"; {_quick_note(scene)}" if reduced else "")
    return [Path(p) for p in paths], msg, {"store": str(out), "reduced": reduced, "summary": summary}


def _lyapunov_panels(scene, out):
    from explorer.analysis.fixedpoints import chaotic_fraction
    from explorer.io import store

    data = store.read_store(out)
    maps, fractions = [], []
    for i in range(scene.n_panels):
        params, h, label = scene.panel(i)
        pd = data.panels.get(i)
        if pd is None or "megno" not in pd.extra:
            continue
        ok = pd.extra["lyapunov_status"] == 0
        maps.append({"seeds": pd.seeds, "megno": pd.extra["megno"], "valid": ok, "params": params, "h": h,
                     "phi0": scene.integration.phi0, "label": label})
        value = scene.sweep_values[i] if scene.sweep_values else 0.0
        fractions.append((value,) + chaotic_fraction(pd.extra["megno"], scene.lyapunov.threshold, ok)[:2])
    return maps, np.array(fractions)


def chaotic_fraction_figure(*, results_dir="results", quick=False, quiet=True, dpi=200) -> Drawn:
    from explorer.app import figures

    scene, out, reduced, summary = ensure_sweep("fraction", results_dir=results_dir, quick=quick, quiet=quiet)
    _maps, fr = _lyapunov_panels(scene, out)
    fig = figures.fraction_curve(fr[:, 0], fr[:, 1], fr[:, 2], parameter=scene.sweep_parameter or "mu",
                                 threshold=scene.lyapunov.threshold, dpi=dpi)
    ax = fig.axes[0]
    ax.set_xlabel(r"$\mu$" if scene.sweep_parameter == "mu" else str(scene.sweep_parameter))
    ax.set_title(f"section $\\varphi = \\pi$ at $h = {scene.h:g}$: {scene.seeds.n} seeds per panel, "
                 f"MEGNO time {scene.lyapunov.time:g}", fontsize=8)
    if reduced:
        ax.text(0.02, 0.97, _quick_note(scene), transform=ax.transAxes, ha="left", va="top", fontsize=6,
                color="#b2182b")
    return Drawn(fig, {"values": fr[:, 0], "fraction": fr[:, 1], "error": fr[:, 2], "store": str(out),
                       "reduced": reduced}, [f"from {out}" + (f"; {_quick_note(scene)}" if reduced else "")])


def chaos_map_figure(*, results_dir="results", quick=False, quiet=True) -> Drawn:
    from explorer.app import figures

    scene, out, reduced, summary = ensure_sweep("chaos", results_dir=results_dir, quick=quick, quiet=quiet)
    maps, fr = _lyapunov_panels(scene, out)
    fig = figures.chaos_maps(maps, layout=scene.figure.layout, columns=scene.figure.columns,
                             threshold=scene.lyapunov.threshold, dpi=scene.figure.dpi)
    if reduced:
        fig.text(0.99, 0.005, _quick_note(scene), ha="right", va="bottom", fontsize=6, color="#b2182b")
    return Drawn(fig, {"panels": len(maps), "fraction": fr[:, 1] if len(fr) else [], "store": str(out),
                       "reduced": reduced}, [f"from {out}" + (f"; {_quick_note(scene)}" if reduced else "")])


# ====================================================================== Melnikov, the body in the plane
def melnikov_figure(*, quick=False) -> Drawn:
    from explorer.app.melnikov_figure import melnikov_figure as mf

    kw = dict(mus=(1e-3, 3e-3), n_measured=4) if quick else {}
    return Drawn(mf(**kw), {"quick": quick})


def trajectory_figure(*, quick=False) -> Drawn:
    from explorer.analysis.trajectory import full_params, initial_state, trajectory
    from explorer.app.trajectory_figure import path_figure

    prm = full_params(None)
    T, n = (60.0, 4001) if quick else (300.0, 20001)
    res = trajectory(prm, initial_state(prm, 0.5, 0.0, 2.0, 0.0), T, n, 1e-12, phi_start=0.0)
    return Drawn(path_figure(res, prm), {"T": T, "status": res["status"]})


# ====================================================================== driver
def find_benchmark(path=None):
    """benchmarks/results_w4.json: the given path, else in the current directory, else next to
    the package's repository root; None when absent."""
    cands = [Path(path)] if path else [Path("benchmarks") / "results_w4.json",
                                       Path(__file__).resolve().parents[2] / "benchmarks" / "results_w4.json"]
    for p in cands:
        if p.is_file():
            return p
    return None


def _save(drawn, out_dir, name):
    from explorer.app.figures import save_figure

    return [Path(p) for p in save_figure(drawn.fig, Path(out_dir) / name)]


def make(name, *, out_dir="figures", results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    """Generate one figure; raises on error (FigureUnavailable for a missing module or input)."""
    out_dir = Path(out_dir)
    if name == "figure2":
        d = figure2(n_levels=6 if quick else 9, dt=0.04 if quick else 0.02)
        curves = [(p["h"], c) for p in d.data["panels"] for c in p["curves"]]
        dH = max(float(np.max(np.abs(chaplygin_H(CHAPLYGIN, c["y"]) - h))) for h, c in curves)
        dF = max(float(np.max(np.abs(chaplygin_F(CHAPLYGIN, c["y"]) - c["c"]))) for h, c in curves)
        return Outcome(name, "written", _save(d, out_dir, name),
                       f"{len(curves)} integrated curves, max |H - h| {dH:.1e}, max |F - c| {dF:.1e}", d.data)
    if name == "figure3":
        d = figure3()
        n = sum(1 for r in d.data["checks"] if r["agree"])
        return Outcome(name, "written", _save(d, out_dir, name),
                       f"stability checked at {n} points, all agree", d.data)
    if name == "figure4":
        paths, msg, data = figure4_figure(out_dir, results_dir=results_dir, quick=quick, quiet=quiet)
        return Outcome(name, "written", paths, msg, data)
    if name == "chaotic_fraction":
        d = chaotic_fraction_figure(results_dir=results_dir, quick=quick, quiet=quiet)
        return Outcome(name, "written", _save(d, out_dir, name), "; ".join(d.notes), d.data)
    if name == "chaos_map":
        d = chaos_map_figure(results_dir=results_dir, quick=quick, quiet=quiet)
        return Outcome(name, "written", _save(d, out_dir, name), "; ".join(d.notes), d.data)
    if name == "continuation":
        d = continuation_figure(step=0.2 if quick else 0.1)
        b = ", ".join(f"{v:.8g}" for v in d.data["bifurcations"])
        return Outcome(name, "written", _save(d, out_dir, name), f"stability changes at mu = {b}", d.data)
    if name == "work_precision":
        p = find_benchmark(benchmark)
        if p is None:
            raise FigureUnavailable("benchmarks/results_w4.json not found (run benchmarks/bench_w4.py)")
        d = work_precision_figure(p)
        return Outcome(name, "written", _save(d, out_dir, name), f"from {p}", d.data)
    if name == "homoclinic":
        d = homoclinic_figure()
        worst = max(d.data[1]["max_dt"], d.data[-1]["max_dt"])
        return Outcome(name, "written", _save(d, out_dir, name),
                       f"crossing times: integrator vs R7 within {worst:.1e}", d.data)
    if name == "melnikov":
        d = melnikov_figure(quick=quick)
        return Outcome(name, "written", _save(d, out_dir, name), data=d.data)
    if name == "trajectory":
        d = trajectory_figure(quick=quick)
        return Outcome(name, "written", _save(d, out_dir, name), data=d.data)
    raise ParameterError(f"unknown figure {name!r}; names: {', '.join(FIGURES)}")


def generate(names=None, *, out_dir="figures", results_dir="results", quick=False, benchmark=None,
             quiet=False, raise_errors=False):
    """Every figure of :data:`FIGURES` (or ``names``) into ``out_dir``, with a tqdm progress bar
    over the figures on stderr.  A missing optional module or input gives status "not
    available"; an error gives "failed" (or is raised with ``raise_errors``).  Returns the
    list of :class:`Outcome`."""
    names = list(FIGURES) if names is None else list(names)
    for n in names:
        if n not in FIGURES:
            raise ParameterError(f"unknown figure {n!r}; names: {', '.join(FIGURES)}")
    from tqdm import tqdm

    outcomes = []
    bar = tqdm(names, desc="figures", unit="figure", file=sys.stderr, disable=True if quiet else None)
    for name in bar:
        bar.set_postfix_str(name)
        try:
            o = make(name, out_dir=out_dir, results_dir=results_dir, quick=quick, benchmark=benchmark, quiet=quiet)
        except FigureUnavailable as exc:
            o = Outcome(name, "not available", message=str(exc))
        except Exception as exc:  # noqa: BLE001 - reported per figure, the others still run
            if raise_errors:
                raise
            msg = " ".join(str(exc).split()) or type(exc).__name__
            if os.environ.get("EXPLORER_DEBUG"):
                traceback.print_exc()
            o = Outcome(name, "failed", message=f"{type(exc).__name__}: {msg}")
        outcomes.append(o)
    bar.close()
    return outcomes
