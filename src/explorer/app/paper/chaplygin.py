"""Chaplygin's case (R6, mu = 0): critical levels, the branches of relative equilibria I, II, III,
their energies and stability, the admissible region of Figure 3 and its numerical check
(:func:`figure3_check`: monodromy of I, eigenvalues of the R6 Jacobian for II and III)."""
import math

import numpy as np

from explorer import model
from explorer.app.paper._common import CHAPLYGIN
from explorer.integrate.methods import MAP_TOL
from explorer.model import ParameterError


def check_chaplygin(params) -> model.Params:
    """The setting of the seed's bifurcation analysis: mu = 0, chi = zeta = 0, lam > 0, a1 > a2."""
    prm = params if isinstance(params, model.Params) else model.Params(**params)
    if prm.mu != 0.0 or prm.chi != 0.0 or prm.zeta != 0.0:
        raise ParameterError(f"Chaplygin's case needs mu = chi = zeta = 0, got mu = {prm.mu:g}, "
                             f"chi = {prm.chi:g}, zeta = {prm.zeta:g}")
    if not prm.lam > 0.0 or not prm.a1 > prm.a2:
        raise ParameterError(f"the bifurcation analysis (seed, docs/model.md R6) assumes lam > 0 and a1 > a2, "
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
    h = lam c/a_j - lam^2 b/(2 a_j^2) (ur21 with its 1/2, docs/model.md R6)."""
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
    field :func:`explorer.model.equations.rhs_tangent` (exact: the field is quadratic).  At mu = 0
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


def figure3_check(params=CHAPLYGIN, samples=None, *, tol=MAP_TOL):
    """Numerical stability at sample points of every branch of Figure 3, against :func:`branch_stable`:
    solution I as a fixed point of the section map (Newton and monodromy, trace against
    :func:`fixedpoints.analytic_eigenvalues_solution_I`; traces within TRACE_MARGIN of +-2 are not
    classified) and every branch by the eigenvalues of the R6 Jacobian (:func:`r6_jacobian`).
    Returns the records (branch, c, h, method, value, stable, expected, agree); raises
    :class:`CheckError` if one disagrees."""
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
