"""Stress tests of numerical stability: every test asserts a number (never a timing).

Fast versions (each well under 20 s); the long versions are scripts in benchmarks/stress/
(see benchmarks/stress/README.md for their thresholds and last results).

- observed convergence order: Taylor at fixed step for several orders, error/tol of the adaptive
  Taylor method; DOP853 at fixed step and tolerance proportionality of the adaptive DOP853 on
  the real model (the splitting orders are in test_sections.py);
- energy and Casimir of the splitting methods over 1e6 steps (bounded, no drift);
- forward-then-backward integration returns to the start (splitting: negative dt on
  drivers.split_step; Taylor: drivers_tangent.return_map_taylor backward; Taylor and DOP853:
  the time-reversed system, bitwise the same arithmetic as negative steps);
- crossings against scipy's DOP853 with events near the boundary of the allowed region
  (grazing), orbits that stop crossing, crossings at step ends;
- extreme parameters: correct numbers or a ParameterError, never NaN stored;
- lyapunov.indicators and fixedpoints bit-identical for 1 and 2 threads.
"""
import functools
import math
import warnings

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import reference
from explorer import model
from explorer._jit import get_num_threads, njit, prange, set_num_threads
from explorer.analysis import fixedpoints, lyapunov, sections
from explorer.integrate import drivers
from explorer.integrate._lanes_generated import taylor_coefficients
from explorer.integrate.tangent import return_map_taylor
from explorer.kernels import STATUS_DONE, STATUS_NONFINITE, STATUS_TMAX, splitting
from explorer.kernels import dop853 as dp
from explorer.kernels import taylor as tk
from explorer.kernels.taylor import order_for_tolerance
from explorer.model import ParameterError, exact
from explorer.model.equations import N_FLOWS, rhs

EPS = np.finfo(float).eps
ASYM = model.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=-0.15, mu=0.7, xi=0.3, eta=-0.25)
BIG_K = 10000   # "never reached": runs that must stop at their time budget


def on_section(prm, u, v, h=2.0):
    """States on phi = pi at energy h from points in units of the allowed ellipse."""
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h)
    return model.section_state(prm, c1 + r1 * np.asarray(u, float), c2 + r2 * np.asarray(v, float), h)


def final_state(prm, y0, T, method, **kw):
    """State at time T (the run stops at its time budget: K is never reached)."""
    r = sections.crossings(prm, states=y0, n_crossings=BIG_K, method=method, tmax=T, **kw)
    assert np.all(r.status == STATUS_TMAX) and np.all(r.info[:, 0] == T)
    return r.final


def homoclinic_state(t):
    """The exact homoclinic orbit R7 of the Figure-4 scene at mu = 0 (exact.homoclinic)."""
    P = model.FIGURE4.as_array()
    p1, p2, m, phi = exact.homoclinic(P, 2 * math.sqrt(2.0), np.atleast_1d(np.asarray(t, float)), sign=1)
    return np.stack([p1, p2, m, np.sin(phi), np.cos(phi)], axis=-1)


# ====================================================================== convergence order
def taylor_fixed_step(P, y0, T, n, order):
    """n steps of the truncated Taylor series of the given order (the kernels of the taylor method)."""
    h = T / n
    y = y0.copy()
    X = np.zeros((5, order + 1))
    out = np.empty(5)
    for _ in range(n):
        X[:, 0] = y
        taylor_coefficients(P, X, order)
        tk.evaluate(X, order, h, out)
        y = out.copy()
    return y


def dop853_fixed_step(P, y0, T, n):
    """n fixed DOP853 steps with the kernels of the dop853 method."""
    h = T / n
    y = y0.copy()
    K = np.empty((16, 5))
    tmp = np.empty(5)
    ynew = np.empty(5)
    for _ in range(n):
        rhs(y, P, K[0])
        for s in range(1, 12):
            dp.stage_input(y, K, s, h, tmp)
            rhs(tmp, P, K[s])
        dp.step_solution(y, K, h, ynew)
        y = ynew.copy()
    return y


def observed_orders(errs):
    errs = np.asarray(errs)
    return np.log2(errs[:-1] / errs[1:])


@pytest.mark.parametrize("order,ns", [(4, [16, 32, 64, 128]), (6, [16, 32, 64, 128]), (8, [8, 16, 32, 64]),
                                      (10, [8, 16, 32]), (12, [8, 16])])
def test_taylor_observed_order_at_fixed_step_within_10_percent(order, ns):
    """The truncated Taylor series of order p has global error O(h^p): halving h divides the
    error by 2^p (measured on the asymmetric parameter set against DOP853 at tol 1e-16, a
    different method; errors kept in [1e-13, 1e-2], away from round-off)."""
    P = ASYM.as_array()
    y0 = on_section(ASYM, [0.2], [0.1])[0]
    T = 2.0
    ref = final_state(ASYM, y0, T, "dop853", tol=1e-16)[0]
    errs = [np.abs(taylor_fixed_step(P, y0, T, n, order) - ref).max() for n in ns]
    assert all(1e-13 < e < 1e-2 for e in errs), errs
    slopes = observed_orders(errs)
    assert np.all(np.abs(slopes - order) <= 0.1 * order), slopes


def test_taylor_error_over_tolerance_stays_within_1em3_and_10():
    """The adaptive Taylor method (order from tol, Jorba-Zou step) against the exact homoclinic
    orbit R7 (mu = 0) and, for mu > 0, against DOP853 at tol 1e-16: the global error at T over
    tol stays within [1e-3, 10] for tol = 1e-8 .. 1e-14.  Fails if the order or the step size
    ignored tol (error << 1e-3 tol at loose tol) or were too optimistic (error > 10 tol)."""
    cases = []
    for t0, T in ((-6.0, 12.0), (-3.0, 6.0)):
        cases.append((model.FIGURE4, homoclinic_state(t0)[0], T, homoclinic_state(t0 + T)[0]))
    prm = model.FIGURE4.with_(mu=0.5)
    y0 = on_section(prm, [0.3], [0.2])[0]
    cases.append((prm, y0, 10.0, final_state(prm, y0, 10.0, "dop853", tol=1e-16)[0]))
    ratios = []
    for prm, y0, T, ref in cases:
        for k in range(8, 15):
            tol = 10.0 ** -k
            err = np.abs(final_state(prm, y0, T, "taylor", tol=tol)[0] - ref).max()
            ratios.append(err / tol)
    ratios = np.array(ratios)
    assert np.all((ratios >= 1e-3) & (ratios <= 10.0)), ratios.reshape(len(cases), -1)


def test_dop853_observed_order_at_fixed_step_on_the_real_model():
    """Eighth order on the real model (tests/kernels does a toy problem): each step halving
    divides the error by 2^p with p in [7.2, 8.8]; reference: Taylor at tol 1e-16."""
    P = ASYM.as_array()
    y0 = on_section(ASYM, [0.2], [0.1])[0]
    T = 2.0
    ref = final_state(ASYM, y0, T, "taylor", tol=1e-16)[0]
    errs = [np.abs(dop853_fixed_step(P, y0, T, n) - ref).max() for n in (4, 8, 16)]
    assert all(1e-13 < e < 1e-4 for e in errs), errs
    slopes = observed_orders(errs)
    assert np.all((slopes >= 7.2) & (slopes <= 8.8)), slopes


def test_dop853_adaptive_error_is_proportional_to_the_tolerance_on_the_real_model():
    """The adaptive DOP853 run (scipy's controller: error estimate ~ h^8, exponent -1/8) has a
    global error proportional to tol when the method is of order 8: the slope of log(error)
    against log(tol) over tol = 1e-6 .. 1e-13 is within 10 % of 1 and error/tol in [0.1, 30].
    A method of order q < 8 under the same controller gives error ~ tol^(q/8) (slope 0.875 for
    q = 7) and fails.  (The slope against the number of steps, -8 asymptotically, is biased by
    the start-up and last clipped steps: -8.9 .. -9.0 measured, so it is not used.)"""
    cases = [(model.FIGURE4, homoclinic_state(-6.0)[0], 12.0, homoclinic_state(6.0)[0]),
             (model.FIGURE4, homoclinic_state(-10.0)[0], 20.0, homoclinic_state(10.0)[0])]
    prm = model.FIGURE4.with_(mu=0.5)
    y0 = on_section(prm, [0.3], [0.2])[0]
    cases.append((prm, y0, 10.0, final_state(prm, y0, 10.0, "taylor", tol=1e-16)[0]))
    tols = 10.0 ** -np.arange(6, 14)
    for prm, y0, T, ref in cases:
        errs = np.array([np.abs(final_state(prm, y0, T, "dop853", tol=tol)[0] - ref).max() for tol in tols])
        slope = np.polyfit(np.log(tols), np.log(errs), 1)[0]
        assert 0.9 <= slope <= 1.1, (slope, errs)
        assert np.all((errs / tols >= 0.1) & (errs / tols <= 30)), errs / tols


# ====================================================================== long runs of the splittings
@pytest.mark.parametrize("method", ["split4", "split6", "split8"])
def test_splitting_energy_bounded_and_casimir_after_1e6_steps(method):
    """1e6 steps of dt = 0.05 on 4 chaotic orbits (mu = 0.5), run in chunks ending at 1e3, 1e4,
    1e5, 1e6 steps (the state carries over exactly).  No drift: the maximum energy error per
    decade grows at most like sqrt(steps) (the round-off random walk; a drift would be ~ steps),
    i.e. its log-log slope over the decades is <= 0.6 (0.5 plus the scatter of a random walk's
    maxima); Casimir error <= 5e-12 at the end.
    (1e7 steps: benchmarks/stress/stress_longrun.py.)"""
    prm = model.FIGURE4.with_(mu=0.5)
    y0 = on_section(prm, [-0.6, 0.2, 0.7, 0.0], [0.1, -0.3, 0.2, 0.0])
    H0 = model.energy(prm, y0)
    dt = 0.05
    y, n, ends, peaks = y0.copy(), 0, [10**3, 10**4, 10**5, 10**6], []
    for end in ends:
        r = sections.crossings(prm, states=y, n_crossings=100000, method=method, dt=dt, tmax=(end - n) * dt)
        assert np.all(r.status == STATUS_TMAX)
        offset = model.energy(prm, y) - H0           # chunk start relative to the true start
        dH = np.abs(np.nan_to_num(r.data[..., 4], nan=0.0) + offset[:, None])
        y, n = r.final.copy(), end
        dH_end = np.abs(model.energy(prm, y) - H0)
        peaks.append(max(dH.max(), dH_end.max()))
    slope = np.polyfit(np.log10(ends), np.log10(peaks), 1)[0]
    assert slope <= 0.6, (slope, peaks)
    assert np.abs(r.info[:, 2]).max() <= 5e-12
    assert np.abs(model.casimir(y) - 1).max() <= 5e-12


# ====================================================================== forward then backward
@njit
def _split_steps(y, P, dt, ids, fracs, n):
    for _ in range(n):
        drivers.split_step(y, P, dt, ids, fracs)


@pytest.mark.parametrize("method", ["split2", "split4", "split6", "split8"])
def test_splitting_forward_then_backward_returns_within_1e4_eps(method):
    """A symmetric composition satisfies Psi_{-dt} o Psi_dt = id: 1000 steps of dt then 1000 of
    -dt (drivers.split_step on the state) come back to the start within 1e4 machine epsilons
    (relative to max(1, |y|)), on regular (mu = 0.002) and chaotic (mu = 0.5) orbits, T = 10."""
    ids, fr = splitting.flow_sequence(splitting.SCHEMES[method][0], N_FLOWS)
    ids = np.ascontiguousarray(ids, np.int64)
    fr = np.ascontiguousarray(fr, np.float64)
    worst = 0.0
    for mu in (0.002, 0.5):
        prm = model.FIGURE4.with_(mu=mu)
        P = prm.as_array()
        for y0 in on_section(prm, [-0.6, 0.2, 0.7], [0.1, -0.3, 0.2]):
            y = y0.copy()
            _split_steps(y, P, 0.01, ids, fr, 1000)
            assert np.abs(y - y0).max() > 1e-3            # it moved
            _split_steps(y, P, -0.01, ids, fr, 1000)
            worst = max(worst, np.abs(y - y0).max() / EPS / max(1.0, np.abs(y0).max()))
    assert worst <= 1e4, worst


def reversed_system(prm):
    """docs/model.md R3 is carried into itself, with time reversed, by (p, M, g) -> (p, -M, -g) and
    lam -> -lam, r -> -r: f'(R y) = -R f(y) (checked bitwise in the test).  Integrating it forward
    is, operation by operation, integrating the original system with negative steps."""
    return prm.with_(lam=-prm.lam, xi=-prm.xi, eta=-prm.eta)


def R(y):
    z = np.array(y, dtype=float, copy=True)
    z[..., 2:] *= -1.0
    return z


@pytest.mark.parametrize("method", ["taylor", "dop853"])
def test_adaptive_forward_then_backward_returns_within_the_tolerance(method):
    """Forward T, then backward T (the time-reversed system): back at the start within
    10 tol T (the adaptive methods control the error per unit time; T = 10 on chaotic orbits,
    T = 100 on regular ones, away from the hyperbolic central point)."""
    prm = model.FIGURE4.with_(mu=0.5, chi=0.05, zeta=0.1, xi=0.1, eta=-0.2)
    rng = np.random.default_rng(3)
    y = np.column_stack([rng.normal(size=(6, 3)), np.sin(np.arange(6)), np.cos(np.arange(6))])
    prmR = reversed_system(prm)
    np.testing.assert_array_equal(model.rhs(prmR, R(y)), -R(model.rhs(prm, y)))
    for mu, T in ((0.5, 10.0), (0.002, 100.0)):
        p = prm.with_(mu=mu)
        y0 = on_section(p, [-0.6, 0.2, 0.7], [0.1, -0.3, 0.2])
        for tol in (1e-10, 1e-13):
            fwd = final_state(p, y0, T, method, tol=tol)
            back = R(final_state(reversed_system(p), R(fwd), T, method, tol=tol))
            err = np.abs(back - y0).max()
            assert np.abs(fwd - y0).max() > 1e-2
            assert err <= 10 * tol * T, (mu, tol, err / tol)


def test_taylor_return_map_backward_retraces_five_crossings():
    """drivers_tangent.return_map_taylor: five returns forward, then five backward (negative
    Taylor steps) land on the start within 1e-10 (tol 1e-15), and every crossing on the way
    back is the forward one."""
    prm = model.FIGURE4.with_(mu=0.3)
    P = prm.as_array()
    order = order_for_tolerance(1e-15)
    V0 = np.zeros((0, 5))
    for y0 in on_section(prm, [0.4, -0.5], [-0.2, 0.3]):
        path = [y0]
        y = y0
        for _ in range(5):
            out, Vout = np.empty(5), np.empty((0, 5))
            st, t = return_map_taylor(y, V0, P, -1.0, 0.0, 1.0, 1e3, order, 10**7, np.zeros(1, np.int64), out, Vout)
            assert st == STATUS_DONE and t > 0
            y = out.copy()
            path.append(y)
        for k in range(5, 0, -1):
            out, Vout = np.empty(5), np.empty((0, 5))
            st, t = return_map_taylor(y, V0, P, -1.0, 0.0, -1.0, 1e3, order, 10**7, np.zeros(1, np.int64), out, Vout)
            assert st == STATUS_DONE and t < 0
            assert np.abs(out - path[k - 1]).max() <= 1e-10, (k, np.abs(out - path[k - 1]).max())
            y = out.copy()


# ====================================================================== crossings under stress
def scipy_times(prm, y0, t_end, max_step=np.inf, t_fine=None):
    """Crossing times of phi = pi in (0, t_end] both ways from scipy's DOP853 with events
    (rtol = atol = 1e-13), and M at each (M > 0: upward, the crossings of direction +1: at
    phi = pi, d sin(phi - pi)/dt = M/b); with t_fine = (a, b), the stretch [a, b] is integrated
    with max_step (scipy also looks for sign changes at its step ends only).  The events do not
    change scipy's steps, so the upward crossings are those of a run with direction +1."""
    ev = lambda t, y: -y[3]  # noqa: E731  sin(phi - pi) = -g1
    ev.direction = 0

    def f(t, y):
        return model.rhs(prm, y)

    pieces = [(0.0, t_end, np.inf)] if t_fine is None else [(0.0, t_fine[0], np.inf),
                                                            (t_fine[0], t_fine[1], max_step),
                                                            (t_fine[1], t_end, np.inf)]
    y, out = np.asarray(y0, float), []
    for a, b, ms in pieces:
        if b <= a:
            continue
        s = solve_ivp(f, (a, b), y, method="DOP853", rtol=1e-13, atol=1e-13, events=ev, max_step=ms)
        out += [(t, ye[2]) for t, ye in zip(s.t_events[0], s.y_events[0]) if t > 1e-9 and ye[4] < 0]
        y = s.y[:, -1]
    out = np.array(out).reshape(-1, 2)
    return out[:, 0], out[:, 1]


#: a grazing pair: the body reaches phi = pi with small M, passes it and falls back.  On the
#: family y0(M0) = (0.3, 0.1, M0, sin(pi - 0.5), cos(pi - 0.5)) at mu = 2 the first approach
#: is tangent to phi = pi at M0 = GRAZE_M0 (t = 1.1087); M0 = GRAZE_M0 + 9.1e-4 (sep/0.05)^2
#: puts the two crossings (up, then down) sep apart around t = 1.109 - sep/2, 1.109 + sep/2.
GRAZE_M0 = 1.1389650065057384
GRAZE_PRM = model.FIGURE4.with_(mu=2.0)


def grazing_state(sep):
    phi = math.pi - 0.5
    return np.array([0.3, 0.1, GRAZE_M0 + 9.1e-4 * (sep / 0.05) ** 2, math.sin(phi), math.cos(phi)])


@functools.cache
def grazing_reference(sep):
    """scipy's crossing times of the grazing pair ``sep`` apart: (upward only, both ways); one
    computation per separation, shared by the methods' cases."""
    t, m = scipy_times(GRAZE_PRM, grazing_state(sep), 1.4, max_step=2e-4, t_fine=(0.9, 1.3))
    return t[m > 0], t


#: time accuracy of each splitting at dt = 0.05 on the grazing pair (about 10x the error
#: measured against scipy: the pair is found by every composition, located at its order)
SPLIT_GRAZE_ATOL = {"split2": 0.05, "split4": 5e-3, "split4_suzuki": 5e-5, "split6": 2e-7,
                    "split6_yoshida": 3e-6, "split8": 1e-8, "split8_s17": 1e-8, "split8_yoshida": 1e-8}


@pytest.mark.parametrize("method,kw,sep,atol", [
    ("taylor", dict(tol=1e-13), 0.1, 1e-8),
    ("taylor", dict(tol=1e-13), 0.02, 1e-8),
    ("dop853", dict(tol=1e-13), 0.02, 1e-8),
    ("dop853", dict(tol=1e-13), 0.005, 1e-8),
] + [(m, dict(dt=0.05), 0.005, a) for m, a in sorted(SPLIT_GRAZE_ATOL.items())])
def test_grazing_pair_of_crossings_inside_one_step_is_found(method, kw, sep, atol):
    """A crossing of phi = pi followed by the crossing back within the same integration step
    is found (both, at the reference times).  A search for a sign change of sin(phi - phi0)
    between the ends of a step alone misses the pair: the Taylor method's steps are ~0.14
    here, so pairs 0.1 apart fall inside one step at any tol, dop853 at tol 1e-13 pairs 0.02
    apart, split8 at dt 0.05 pairs 0.005 apart.  Before the fix (kernels.events.poly_step_roots,
    dense_step_roots, drivers._split_step_roots), in ordinary runs at mu = 2, 4, 8
    (taylor tol 1e-13 and split8 dt 0.05) 0.8e-3 .. 2.3e-3 of the crossings were lost this way,
    none at mu = 0.5 (benchmarks/stress/stress_crossings.py, part C); an orbit started on the
    section with a tiny M that falls back and crosses again within the first step lost that
    crossing too (the start counts as g = 0; part A).  Between the two roots M changes sign
    (dg/dt = cos(phi - phi0) M / b), so a step in which M changes sign while g keeps its sign (or
    starts at 0) must be searched at the root of M.  Reference: scipy DOP853 rtol = atol =
    1e-13 with max_step 2e-4 around the pair."""
    y0 = grazing_state(sep)
    ref_up, ref_both = grazing_reference(sep)
    assert len(ref_up) == 1 and len(ref_both) == 2 and abs(ref_both[1] - ref_both[0] - sep) < 0.1 * sep
    up = sections.crossings(GRAZE_PRM, states=y0, n_crossings=5, method=method, tmax=1.4, **kw)
    both = sections.crossings(GRAZE_PRM, states=y0, n_crossings=5, method=method, tmax=1.4, direction=0, **kw)
    assert up.count[0] == 1 and both.count[0] == 2, (up.orbit(0)[:, 0], both.orbit(0)[:, 0], ref_both)
    assert abs(up.orbit(0)[0, 0] - ref_up[0]) < atol
    np.testing.assert_allclose(both.orbit(0)[:, 0], ref_both, atol=atol)


def test_grazing_pair_covers_every_method():
    covered = {"taylor", "dop853"} | set(SPLIT_GRAZE_ATOL)
    assert covered == set(sections.METHODS)


def compare_with_scipy(prm, y0, methods, window, K=6, margin=0.05, t_atol=None):
    """Crossings of every orbit against scipy's DOP853 with events over (0, window - margin].
    Returns a list of (method, orbit index, y0, explorer times, scipy times) for every
    discrepancy: a missed, duplicated or spurious crossing or a time off by more than
    t_atol[method]."""
    P = prm.as_array()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        refs = [reference.scipy_crossings(P, y, K, t_max=window)[:, 0] for y in y0]
    bad = []
    for method, kw in methods:
        r = sections.crossings(prm, states=y0, n_crossings=K, method=method, tmax=window, **kw)
        for i, ref in enumerate(refs):
            got = r.orbit(i)[:, 0]
            assert np.all(np.isfinite(r.orbit(i)))
            a, b = comparable_crossings(got, ref, K, window, margin, t_atol[method])
            if len(a) != len(b) or (len(a) and np.abs(a - b).max() > t_atol[method]):
                bad.append((method, i, y0[i].tolist(), a, b))
    return bad


def comparable_crossings(got, ref, K, window, margin, tol):
    """The crossing times of two runs over the stretch where both are complete.

    A run that found all K crossings has seen every crossing up to its last one; a run that
    found fewer has seen every crossing up to the end of its window.  Both lists are cut at the
    earlier of the two horizons (the window less ``margin`` when neither run found K), plus
    ``tol`` so that a crossing at the horizon is kept by both.  A spurious crossing of either
    run, or one that the other missed, then changes one count and is reported: if scipy found
    none and the explorer found K, all K are compared with nothing."""
    h_got = got[-1] if len(got) >= K else np.inf
    h_ref = ref[-1] if len(ref) >= K else np.inf
    lim = min(h_got, h_ref)
    if not np.isfinite(lim):
        lim = window - margin
    return got[got <= lim + tol], ref[ref <= lim + tol]


def test_comparison_with_scipy_sees_spurious_and_missed_crossings():
    """Negative control of compare_with_scipy's window: an extra crossing of the explorer (K
    found, scipy fewer or none), a missed one and a shifted one are all seen."""
    K, W, m, tol = 3, 10.0, 0.05, 1e-8
    ref = np.array([1.0, 2.0, 3.0])
    for got, ok in (([1.0, 2.0, 3.0], True), ([1.0, 1.5, 2.0], False), ([1.0, 3.0], False),
                    ([1.0, 2.0 + 1e-6, 3.0], False)):
        a, b = comparable_crossings(np.array(got), ref, K, W, m, tol)
        assert (len(a) == len(b) and np.abs(a - b).max() <= tol) == ok, got
    for ref_short in (np.array([]), np.array([1.0])):     # scipy found fewer than K
        a, b = comparable_crossings(np.array([1.0, 2.0, 3.0]), ref_short, K, W, m, tol)
        assert len(a) == 3 and len(b) == len(ref_short)


def test_crossings_near_the_boundary_of_the_allowed_region_match_scipy():
    """112 orbits started on the section at 1 - eps of the allowed ellipse (eps = 1e-2 .. 1e-9:
    M -> 0 at phi = pi, grazing starts, slow or no returns) at mu = 0.03, 0.5, 2, 8; crossing
    times over a window of 10 time units (before chaotic divergence) against scipy's DOP853 with
    events (rtol = atol = 1e-13): no missed, duplicated or spurious crossing, times within 1e-8
    (taylor, dop853 at tol 1e-13) and 1e-6 (split8, dt 0.01).  Before the grazing-pair fix this
    failed for taylor at mu = 2 (a grazing pair inside one step, see the test above)."""
    th = np.linspace(0, 2 * np.pi, 7, endpoint=False) + 0.3
    TH, E = np.meshgrid(th, [1e-2, 1e-4, 1e-6, 1e-9])
    u, v = (1 - E.ravel()) * np.cos(TH.ravel()), (1 - E.ravel()) * np.sin(TH.ravel())
    methods = [("taylor", dict(tol=1e-13)), ("dop853", dict(tol=1e-13)), ("split8", dict(dt=0.01))]
    t_atol = {"taylor": 1e-8, "dop853": 1e-8, "split8": 1e-6}
    bad = []
    for mu in (0.03, 0.5, 2.0, 8.0):
        prm = model.FIGURE4.with_(mu=mu)
        bad += [(mu,) + b for b in compare_with_scipy(prm, on_section(prm, u, v), methods, 10.0, t_atol=t_atol)]
    assert not bad, bad


def test_orbits_that_stop_crossing_and_long_returns_match_scipy():
    """A heavy body that only rocks (mu = 8, eta = -1, small spin) never crosses; bodies that
    barely turn over (mu = 2 just above the turning energy) return after long times; both
    against scipy over 60 time units."""
    prm = model.FIGURE4.with_(mu=8.0, eta=-1.0)
    rock = np.array([[4.0, 0.0, 0.05, math.sin(0.3), math.cos(0.3)],
                     [3.0, 0.5, 0.2, math.sin(-0.5), math.cos(-0.5)]])
    for method, kw in (("taylor", dict(tol=1e-13)), ("dop853", dict(tol=1e-13)), ("split8", dict(dt=0.01))):
        r = sections.crossings(prm, states=rock, n_crossings=3, method=method, tmax=60.0, **kw)
        assert np.all(r.count == 0) and np.all(r.status == STATUS_TMAX)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert all(len(reference.scipy_crossings(prm.as_array(), y, 3, t_max=60.0)) == 0 for y in rock)
    # slow returns: points at 1 - 1e-6 of the ellipse at mu = 0.03 (the body barely turns over)
    prm = model.FIGURE4.with_(mu=0.03)
    th = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    y0 = on_section(prm, (1 - 1e-6) * np.cos(th), (1 - 1e-6) * np.sin(th))
    methods = [("taylor", dict(tol=1e-13)), ("dop853", dict(tol=1e-13)), ("split8", dict(dt=0.01))]
    bad = compare_with_scipy(prm, y0, methods, 60.0, K=4, t_atol={"taylor": 1e-7, "dop853": 1e-7, "split8": 1e-5})
    assert not bad, bad


@pytest.mark.parametrize("method", ["split2", "split4", "split8"])
def test_crossings_at_step_ends_are_counted_once(method):
    """Uniform rotation (mu = 0, p = 0; docs/model.md R6): the first crossing is placed within a few
    ulps before, on or after the end of step n (t = n dt), 41 shifts; every run reports every
    crossing exactly once (direction +1 and both) at the exact times."""
    prm = model.FIGURE4
    c = math.sqrt(2 * prm.b * 2.0)
    dt, n = 0.05, 37
    period = 2 * math.pi * prm.b / c
    for shift in np.arange(-20, 21) * 2e-16:
        phi = math.pi - c * (n * dt + shift) / prm.b
        y0 = np.array([0.0, 0.0, c, math.sin(phi), math.cos(phi)])
        t1 = (math.pi - math.atan2(y0[3], y0[4]) % (2 * math.pi)) * prm.b / c
        expect = t1 + period * np.arange(3)
        for direction in (1, 0):
            r = sections.crossings(prm, states=y0, n_crossings=3, method=method, dt=dt, direction=direction)
            assert r.count[0] == 3
            np.testing.assert_allclose(r.orbit(0)[:, 0], expect, atol=1e-12)


def test_crossings_at_taylor_step_ends_are_counted_once():
    """As above for the Taylor method: the start phase that puts the first crossing exactly at
    the end of step 3 is found by bisection (the steps of a uniform rotation depend only weakly
    and continuously on the phase), then shifted by -20 .. 20 ulps; each run reports the
    crossings once, at the exact times."""
    prm = model.FIGURE4
    c = math.sqrt(2 * prm.b * 2.0)
    period = 2 * math.pi * prm.b / c

    def start(t):
        phi = math.pi - c * t / prm.b
        return np.array([0.0, 0.0, c, math.sin(phi), math.cos(phi)])

    def gap(t):   # end of step 3 minus the crossing time
        res = sections.crossings(prm, states=start(t), n_crossings=3, method="taylor", tol=1e-13, max_steps=3)
        return res.info[0, 0] - t

    a, b = 1.0, 3.0
    assert gap(a) > 0 > gap(b)
    while b - a > 4e-16 * b:
        mid = 0.5 * (a + b)
        a, b = (mid, b) if gap(mid) > 0 else (a, mid)
    assert abs(gap(a)) < 1e-15
    for shift in np.arange(-20, 21) * 2e-16:
        y0 = start(a + shift)
        t1 = (math.pi - math.atan2(y0[3], y0[4]) % (2 * math.pi)) * prm.b / c
        for direction in (1, 0):
            r = sections.crossings(prm, states=y0, n_crossings=3, method="taylor", tol=1e-13, direction=direction)
            assert r.count[0] == 3
            np.testing.assert_allclose(r.orbit(0)[:, 0], t1 + period * np.arange(3), atol=1e-12)


@pytest.mark.parametrize("method", ["taylor", "dop853", "split8"])
def test_crossing_at_the_end_of_the_time_budget_is_counted_at_most_once(method):
    """The last step ends exactly at tmax: a crossing placed within +-20 ulps of tmax is
    reported once (if before tmax up to round-off) or not at all, never twice, at the exact
    time; one placed 1e-9 before (after) tmax is (is not) reported."""
    prm = model.FIGURE4
    c = math.sqrt(2 * prm.b * 2.0)
    tmax = 2.0
    for shift in list(np.arange(-20, 21) * 2e-16) + [-1e-9, 1e-9]:
        phi = math.pi - c * (tmax + shift) / prm.b
        y0 = np.array([0.0, 0.0, c, math.sin(phi), math.cos(phi)])
        t1 = (math.pi - math.atan2(y0[3], y0[4]) % (2 * math.pi)) * prm.b / c
        r = sections.crossings(prm, states=y0, n_crossings=3, method=method, tol=1e-13, dt=0.05, tmax=tmax, direction=0)
        assert r.count[0] <= 1
        if r.count[0]:
            assert abs(r.orbit(0)[0, 0] - t1) < 1e-12 and t1 <= tmax + 1e-12
        if abs(shift) > 1e-12:
            assert r.count[0] == (1 if shift < 0 else 0)


# ====================================================================== extreme parameters
#: refusals (ParameterError) allowed per extreme set: {name: {method: message fragment}}.
#: Empty: today every method integrates every set below.  A method that starts refusing one
#: fails the test until the refusal is recorded here (a refusal is not a free pass).
EXPECTED_REFUSALS: dict = {}

EXTREME = {
    "mu=50": (model.FIGURE4.with_(mu=50.0), 2.0),
    "lam=1e-3": (model.FIGURE4.with_(lam=1e-3, mu=0.5), 2.0),
    "lam=-1e-3": (model.FIGURE4.with_(lam=-1e-3, mu=0.5), 2.0),
    "a1=a2(1+1e-12)": (model.FIGURE4.with_(a1=0.5 * (1 + 1e-12), mu=0.5), 2.0),
    "h=1e6": (model.FIGURE4.with_(mu=0.5), 1e6),
    "h=1e6,mu=50": (model.FIGURE4.with_(mu=50.0), 1e6),
    "h=hmin+1e-12": (model.FIGURE4.with_(mu=2.0), -2.0 + 1e-12),
}


def energy_scale(prm, y):
    """Sum of the magnitudes of the terms of H (R3): the scale of its round-off."""
    P = prm.as_array()
    p1, p2, m, g1, g2 = np.moveaxis(np.asarray(y, float), -1, 0)
    kin = 0.5 * (p1 * p1 / P[0] + p2 * p2 / P[1] + m * m / P[2])
    return kin + abs(P[6] / P[3]) * np.abs((p1 - P[4]) * g2 - (p2 - P[5]) * g1) + P[6] * np.abs(P[7] * g1 + P[8] * g2)


@pytest.mark.parametrize("name", sorted(EXTREME))
def test_extreme_parameters_give_correct_numbers_or_a_refusal(name):
    """mu = 50, |lam| = 1e-3, a1 = a2 (1 + 1e-12), h = 1e6, h just above the minimum of the
    section: every method either refuses with ParameterError (only where EXPECTED_REFUSALS
    records it, with its message) or stores only finite crossings
    whose energy error, relative to the size of the terms of H, is within the method's error
    (taylor tol 1e-13: 1e-11; dop853 tol 1e-12: 1e-9; split8 and split4 at dt = the mean Taylor
    step / 10, i.e. resolving the orbit's time scale: 1e-8 and 1e-4)."""
    prm, h = EXTREME[name]
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h)
    u = np.array([-0.9, -0.3, 0.0, 0.5, 0.95])
    v = np.array([0.1, -0.4, 0.0, 0.2, 0.0])
    y0 = model.section_state(prm, c1 + r1 * u, c2 + r2 * v, h)
    scale = energy_scale(prm, y0)
    tay = sections.crossings(prm, states=y0, n_crossings=20, method="taylor", tol=1e-13, tmax=200.0, max_steps=10**6)
    dt = float(np.min(tay.info[:, 0] / np.maximum(tay.info[:, 1], 1))) / 10
    runs = {"taylor": (tay, 1e-11)}
    refused = {}
    for method, kw, bound in (("dop853", dict(tol=1e-12), 1e-9), ("split8", dict(dt=dt), 1e-8),
                              ("split4", dict(dt=dt), 1e-4)):
        try:
            runs[method] = (sections.crossings(prm, states=y0, n_crossings=20, method=method, tmax=200.0,
                                               max_steps=10**6, **kw),
                            bound)
        except ParameterError as exc:
            refused[method] = str(exc)
    assert sorted(refused) == sorted(EXPECTED_REFUSALS.get(name, {})), refused
    for method, fragment in EXPECTED_REFUSALS.get(name, {}).items():
        assert fragment in refused[method], refused[method]
    for method, (r, bound) in runs.items():
        for i in range(len(y0)):
            rows = r.orbit(i)
            assert np.all(np.isfinite(rows)), (method, i)
            assert r.status[i] != STATUS_NONFINITE, (method, i)
            if len(rows):
                rel = np.abs(rows[:, 4]).max() / scale[i]
                assert rel <= bound, (method, i, rel)
        assert np.all(np.isfinite(r.final)) and np.abs(r.info[:, 2]).max() < 1e-9


def test_empty_or_degenerate_region_is_refused_or_stays_put():
    """Below the minimum of the section the start is refused; at the minimum itself (an
    equilibrium: M = 0, p = c) the adaptive methods stay there (no crossing, no NaN)."""
    prm = model.FIGURE4.with_(mu=2.0)
    with pytest.raises(ParameterError, match="outside the allowed region"):
        sections.crossings(prm, -2.0 - 1e-12, [(-2.0, 0.0)], n_crossings=3)
    for method in ("taylor", "dop853"):
        r = sections.crossings(prm, -2.0, [(-2.0, 0.0)], n_crossings=3, method=method, tmax=50.0)
        assert r.count[0] == 0 and r.status[0] == STATUS_TMAX and np.all(np.isfinite(r.final))


# ====================================================================== threads
@pytest.mark.parametrize("method,kw", [("taylor", dict(tol=1e-12)), ("dop853", dict(tol=1e-12)),
                                       ("split6", dict(dt=0.05))])
def test_lyapunov_indicators_identical_for_1_and_2_threads(method, kw):
    prm = model.FIGURE4.with_(mu=0.5)
    c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
    y0 = model.section_state(prm, c1 + r1 * np.linspace(-0.9, 0.9, 12), c2 + 0.1 * r2, 2.0)
    a = lyapunov.indicators(prm, states=y0, tmax=200.0, method=method, history=5, threads=1, **kw)
    b = lyapunov.indicators(prm, states=y0, tmax=200.0, method=method, history=5, threads=2, **kw)
    for name in ("time", "mlce", "megno", "Y", "fli", "status", "steps", "final", "history"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


@njit(parallel=True)
def _thread_of_each_iteration(out):
    for i in prange(out.shape[0]):
        s = 0.0
        for k in range(2000):
            s += math.sin(1e-3 * k + i)
        out[i] = numba.get_thread_id() + 0.0 * s


def test_two_numba_threads_really_run():
    """The 1-against-2-threads tests mean something only if 2 threads run: with 2 threads
    asked, a parallel loop's iterations are spread over both (thread ids 0 and 1), also on a
    one-core machine (conftest raises NUMBA_NUM_THREADS to 2 there)."""
    old = get_num_threads()
    try:
        set_num_threads(2)
        assert get_num_threads() == 2
        ids = np.full(64, -1.0)
        _thread_of_each_iteration(ids)
        assert set(ids.astype(int).tolist()) == {0, 1}, ids
    finally:
        set_num_threads(old)


def test_fixed_points_and_separatrices_identical_for_1_and_2_threads():
    old = get_num_threads()
    out = []
    try:
        for n in (1, 2):
            set_num_threads(n)
            assert get_num_threads() == n
            fp = fixedpoints.find_fixed_point(model.FIGURE4.with_(mu=0.5), 2.0, (-0.2, 0.0))
            curve = fixedpoints.manifold(fp.params, fp.h, fp, iterations=2, max_points=200)
            br = fixedpoints.continue_branch(model.FIGURE4, 2.0, "mu", 0.0, 0.2, 0.1)
            out.append((fp.point, fp.jacobian, curve, np.array([p.point for p in br.orbits])))
    finally:
        set_num_threads(old)
    for x, y in zip(out[0], out[1]):
        np.testing.assert_array_equal(x, y)
