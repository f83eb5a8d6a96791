"""Crossings of the section phi = phi0: exact solutions, an independent reference,
conservation, observed order, direction handling, budgets, thread determinism."""
import functools
import math
import warnings

import numpy as np
import pytest
from conftest import PARAM_SETS

import reference
from explorer import model
from explorer.analysis import sections
from explorer.analysis.section_map import SectionMap
from explorer.kernels import (
    STATUS_DONE,
    STATUS_MAX_STEPS,
    STATUS_NONFINITE,
    STATUS_STEP_UNDERFLOW,
    STATUS_TMAX,
    STATUS_UNRESOLVED,
)
from explorer.model import exact

#: each method with the setting used for "tight" checks (one-step error <= 1e-9)
TIGHT = {"taylor": dict(tol=1e-15), "dop853": dict(tol=1e-14), "split8": dict(dt=0.01),
         "split6": dict(dt=0.005), "split4": dict(dt=0.0005), "split2": dict(dt=4e-6),
         "split4_suzuki": dict(dt=0.001), "split6_yoshida": dict(dt=0.002),
         "split8_s17": dict(dt=0.01), "split8_yoshida": dict(dt=0.005)}
ALL_METHODS = sorted(TIGHT)
#: the direction test compares a method only with itself and counts crossings: split2's tight
#: step (4e-6, for the 1e-9 comparisons with scipy) would take 15 million steps per orbit there
LOOSE = {**TIGHT, "split2": dict(dt=1e-4)}


def test_every_method_has_a_tight_setting():
    """The tests parametrised over ALL_METHODS cover every method the package offers."""
    assert set(ALL_METHODS) == set(sections.METHODS)


def fig4_seeds(prm, h, n, p2_frac=0.0, span=0.9):
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h)
    p1 = c1 + r1 * np.linspace(-span, span, n)
    p2 = np.full(n, c2 + p2_frac * r2)
    return p1, p2


# ---------------------------------------------------------------- exact solutions
@pytest.mark.parametrize("method", ALL_METHODS)
def test_crossing_time_matches_exact_uniform_rotation(method):
    """docs/model.md R6/R9: at mu = 0 with p = 0 the body turns uniformly (M = c) and crosses every 2 pi b / c.
    20 crossings; split2's tight step takes 1.1e6 steps a period, so it runs 5 (5.5e6 steps, more
    than any other method takes for 20): the time bound is relative to the last time, so a
    relative error d of the period is d at any count."""
    prm = model.FIGURE4
    h = 2.0
    c = math.sqrt(2 * prm.b * h)
    n = 5 if method == "split2" else 20
    res = sections.crossings(prm, h, [(0.0, 0.0)], n_crossings=n, method=method, **TIGHT[method])
    assert res.status[0] == STATUS_DONE
    t = res.orbit(0)[:, 0]
    expect = 2 * math.pi * prm.b / c * np.arange(1, n + 1)
    assert np.abs(t - expect).max() <= 1e-11 * expect.max()
    np.testing.assert_allclose(res.orbit(0)[:, 1:3], 0.0, atol=1e-12)
    np.testing.assert_allclose(res.orbit(0)[:, 3], c, rtol=1e-13)


@pytest.mark.parametrize("method", ALL_METHODS)
@pytest.mark.parametrize("sign", [1, -1])
def test_crossing_times_match_the_homoclinic_solution(method, sign):
    """docs/model.md R7: start on the homoclinic orbit of solution I at t = -20 and compare every
    crossing of phi = pi over (-20, 20) with the exact times."""
    prm = model.FIGURE4
    c = 2 * math.sqrt(2.0)
    P = prm.as_array()
    t_start = -20.0
    p1, p2, m, phi = exact.homoclinic(P, c, np.array([t_start]), sign=sign)
    y0 = np.array([p1[0], p2[0], m[0], math.sin(phi[0]), math.cos(phi[0])])
    expect = exact.homoclinic_crossing_times(P, c, math.pi, t_start, 20.0, sign=sign) - t_start
    res = sections.crossings(prm, states=y0, n_crossings=len(expect), method=method, tmax=40.0, **TIGHT[method])
    got = res.orbit(0)[:, 0]
    assert len(got) == len(expect) >= 5
    # the orbit is exponentially unstable near the saddle: 1e-8 as in the reference test
    assert np.abs(got - expect).max() < 1e-8


# ---------------------------------------------------------------- independent reference
@functools.cache
def scipy_one_step_maps(name, h=2.0):
    """scipy's one-step maps of the six seeds of a parameter set: computed once per set and
    shared by every method's case (the reference does not depend on the method)."""
    prm = PARAM_SETS[name]
    p1, p2 = fig4_seeds(prm, h, 6, p2_frac=0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return tuple(reference.scipy_one_step_map(prm.as_array(), model.section_state(prm, p1[i], p2[i], h)[0],
                                                  t_max=30.0) for i in range(len(p1)))


@pytest.mark.parametrize("method", ALL_METHODS)
def test_one_step_map_matches_scipy_reference(method, param_set):
    """One-step section map (start on the section, next crossing) against scipy's DOP853
    with events at rtol = atol = 1e-13: error <= 1e-9 on Figure 4 and asymmetric sets."""
    name, prm = param_set
    h = 2.0
    p1, p2 = fig4_seeds(prm, h, 6, p2_frac=0.2)
    res = sections.crossings(prm, h, np.column_stack([p1, p2]), n_crossings=1, method=method, tmax=30.0,
                             **TIGHT[method])
    checked = 0
    for i, ref in enumerate(scipy_one_step_maps(name, h)):
        if ref is None:
            assert res.count[i] == 0
            continue
        assert res.count[i] == 1
        err = np.abs(res.data[i, 0, :4] - ref[:4]).max()
        assert err <= 1e-9, (i, err)
        checked += 1
    assert checked >= 4


def test_dop853_and_taylor_agree_far_better_than_the_reference_tolerance():
    prm = PARAM_SETS["figure4_mu0.5"]
    p1, p2 = fig4_seeds(prm, 2.0, 8, p2_frac=0.1, span=0.8)
    a = sections.crossings(prm, 2.0, np.column_stack([p1, p2]), n_crossings=3, method="taylor", tol=1e-16)
    b = sections.crossings(prm, 2.0, np.column_stack([p1, p2]), n_crossings=3, method="dop853", tol=1e-15)
    assert np.abs(a.data[..., :4] - b.data[..., :4]).max() < 1e-11


# ---------------------------------------------------------------- conservation
@pytest.mark.parametrize("method", ["split2", "split4", "split6", "split8"])
def test_splitting_keeps_casimir_to_round_off_and_energy_bounded(method):
    prm = PARAM_SETS["asym_lam_neg"]
    p1, p2 = fig4_seeds(prm, 2.0, 4, p2_frac=0.1)
    res = sections.crossings(prm, 2.0, np.column_stack([p1, p2]), n_crossings=300, method=method, dt=0.02)
    assert np.all(res.status == STATUS_DONE)
    # Casimir after ~1e5 steps (1.5e6 rotations): a random walk of round-off, ~eps sqrt(n)
    assert np.abs(res.info[:, 2]).max() < 2e-12
    dH = np.abs(res.data[..., 4])
    # bounded: the late error is not larger than the early error (no drift)
    early = dH[:, :100].max()
    late = dH[:, 200:].max()
    assert late < 3 * early + 1e-13


@pytest.mark.parametrize("method,tol,bound", [("taylor", 1e-13, 1e-11), ("dop853", 1e-13, 1e-10)])
def test_adaptive_methods_keep_energy_to_tolerance(method, tol, bound):
    prm = PARAM_SETS["figure4_mu0.5"]
    p1, p2 = fig4_seeds(prm, 2.0, 4, p2_frac=0.1)
    res = sections.crossings(prm, 2.0, np.column_stack([p1, p2]), n_crossings=200, method=method, tol=tol)
    assert np.all(res.status == STATUS_DONE)
    assert np.abs(res.data[..., 4]).max() < bound
    assert np.abs(res.info[:, 2]).max() < bound  # Casimir monitored where not kept


@pytest.mark.parametrize("kw,F", [
    (dict(mu=0.0, chi=0.2, zeta=-0.1, lam=-0.9), model.chaplygin_integral),
    (dict(a1=0.7, a2=0.7, mu=0.9, xi=0.3, eta=-0.25), model.kozlov_integral),
    (dict(a1=1.0, a2=1.0, lam=1.3, chi=1.3 * 0.25, zeta=1.3 * 0.3, mu=0.9, xi=0.3, eta=-0.25), model.case3_integral),
])
@pytest.mark.parametrize("method", ["taylor", "split8"])
def test_extra_integral_is_conserved_along_integrated_orbits(kw, F, method):
    prm = model.FIGURE4.with_(**kw)
    p1, p2 = fig4_seeds(prm, 2.0, 3, p2_frac=0.3, span=0.6)
    y0 = model.section_state(prm, p1, p2, 2.0)
    res = sections.crossings(prm, states=y0, n_crossings=100, method=method, tol=1e-14, dt=0.01)
    F0 = F(prm, y0)
    for i in range(3):
        rows = res.orbit(i)
        assert len(rows) > 10
        ycross = model.section_state(prm, rows[:, 1], rows[:, 2], model.energy(prm, y0[i]))
        assert np.abs(F(prm, ycross) - F0[i]).max() < 1e-9


def test_hess_invariant_relation_f_equals_zero_is_kept():
    base = model.Params(a1=1.5, a2=0.6, b=1.7, lam=0.9, mu=0.8)
    prm = base.with_(eta=model.hess_eta(base))
    # a state with F = M + eta p1 - lam b/a2 = 0
    p1, p2, phi = 0.3, -0.2, 1.0
    m = prm.lam * prm.b / prm.a2 - prm.eta * p1
    y0 = np.array([p1, p2, m, math.sin(phi), math.cos(phi)])
    assert abs(model.hess_function(prm, y0)) < 1e-15
    res = sections.crossings(prm, states=y0, n_crossings=20, method="taylor", tol=1e-15, tmax=400.0)
    final = res.final[0]
    assert res.count[0] >= 5
    assert abs(model.hess_function(prm, final)) < 1e-10


# ---------------------------------------------------------------- observed order
@pytest.mark.parametrize("method,order,dts", [
    ("split2", 2, [2.0**-5, 2.0**-6, 2.0**-7]),
    ("split4", 4, [2.0**-3, 2.0**-4, 2.0**-5]),
    ("split6", 6, [2.0**-2, 2.0**-3, 2.0**-4]),
    ("split8", 8, [2.0**-2, 2.0**-3, 2.0**-4]),
    ("split4_suzuki", 4, [2.0**-3, 2.0**-4, 2.0**-5]),
    ("split6_yoshida", 6, [2.0**-2, 2.0**-3, 2.0**-4]),
    ("split8_s17", 8, [2.0**-2, 2.0**-3, 2.0**-4]),
    ("split8_yoshida", 8, [2.0**-2, 2.0**-3, 2.0**-4]),
])
def test_observed_order_of_splitting_on_the_real_model(method, order, dts):
    """Step halving on the real model (asymmetric parameters), error of the state at a fixed
    time against the Taylor method at tol 1e-16: slope within 10% of the nominal order."""
    prm = PARAM_SETS["asym_lam_neg"]
    y0 = model.section_state(prm, [0.2], [0.1], 2.0)
    T = 4.0
    # K = 50 crossings cannot happen before T: every run stops at its time budget T
    ref = sections.crossings(prm, states=y0, n_crossings=50, method="taylor", tol=1e-16, tmax=T)
    assert ref.status[0] == STATUS_TMAX and ref.info[0, 0] == T
    ref = ref.final[0]
    errs = []
    for dt in dts:
        run = sections.crossings(prm, states=y0, n_crossings=50, method=method, dt=dt, tmax=T)
        assert run.info[0, 0] == T
        fin = run.final[0]
        errs.append(np.abs(fin - ref).max())
    errs = np.array(errs)
    assert np.all(errs > 1e-13) and np.all(errs < 1e-2), errs
    slopes = np.log2(errs[:-1] / errs[1:])
    assert np.all(np.abs(slopes - order) <= 0.1 * order), slopes


# ---------------------------------------------------------------- direction, start, budgets
@pytest.mark.parametrize("method", ALL_METHODS)
def test_direction_and_start_point(method):
    prm = PARAM_SETS["figure4_mu0.5"]
    p1, p2 = fig4_seeds(prm, 2.0, 3, p2_frac=0.1, span=0.5)
    kw = LOOSE[method]
    up = sections.crossings(prm, 2.0, np.column_stack([p1, p2]), n_crossings=4, method=method, **kw)
    # the start point (on the section) is not a crossing
    assert np.all(up.data[:, 0, 0] > 0.5)
    # crossings with direction -1 starts the body turning backwards (M < 0 from the
    # energy) and finds its crossings with dphi/dt < 0
    back = sections.crossings(prm, 2.0, np.column_stack([p1, p2]), n_crossings=4, method=method, direction=-1,
                              tmax=60.0, **kw)
    assert np.all(back.count == 4) and np.all(back.data[:, :, 3] < 0) and np.all(back.data[:, 0, 0] > 0.5)
    # with M > 0 the body never crosses backwards: direction -1 finds nothing
    y0 = model.section_state(prm, p1, p2, 2.0)
    down = sections.crossings(prm, states=y0, n_crossings=4, method=method, direction=-1, tmax=60.0, **kw)
    assert np.all(down.count == 0) and np.all(down.status == STATUS_TMAX)
    both = sections.crossings(prm, states=y0, n_crossings=4, method=method, direction=0, **kw)
    np.testing.assert_allclose(both.data, up.data, atol=1e-12)
    # the reversed body (M < 0) crosses only with direction -1
    y0r = model.section_state(prm, p1, p2, 2.0, direction=-1)
    rev = sections.crossings(prm, states=y0r, n_crossings=2, method=method, direction=-1, **kw)
    assert np.all(rev.count == 2) and np.all(rev.data[:, :, 3] < 0)


@pytest.mark.parametrize("method", ALL_METHODS)
def test_other_section_angle_matches_reference(method):
    prm = PARAM_SETS["asym_lam_pos"]
    phi0 = 0.9
    h = 2.0
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h, phi0)
    y0 = model.section_state(prm, [c1 + 0.3 * r1], [c2 - 0.2 * r2], h, phi0)
    res = sections.crossings(prm, states=y0, n_crossings=1, method=method, phi0=phi0, **TIGHT[method])
    ref = _scipy_one_step_map_at(prm, tuple(y0[0]), phi0)
    assert np.abs(res.data[0, 0, :4] - ref[:4]).max() < 1e-9


@functools.cache
def _scipy_one_step_map_at(prm, y0, phi0):
    """scipy's one-step map of one start, once for every method's case."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return reference.scipy_one_step_map(prm.as_array(), np.array(y0), phi0=phi0)


@pytest.mark.parametrize("method", ["taylor", "dop853", "split4"])
def test_orbit_that_never_crosses_is_reported(method):
    """A heavy body that only rocks (never turns over) does not cross phi = pi: the run stops at
    its time budget with zero crossings instead of looping forever."""
    prm = model.FIGURE4.with_(mu=8.0, eta=-1.0)
    # near phi = 0 with a small spin: the body rocks and never reaches phi = pi
    y0 = np.array([4.0, 0.0, 0.05, math.sin(0.3), math.cos(0.3)])
    res = sections.crossings(prm, states=y0, n_crossings=3, method=method, tmax=50.0, tol=1e-12, dt=0.01)
    assert res.count[0] == 0 and res.status[0] == STATUS_TMAX
    assert res.info[0, 0] == pytest.approx(50.0, abs=0.02)


def test_step_budget_is_reported():
    prm = PARAM_SETS["figure4_mu0.5"]
    res = sections.crossings(prm, 2.0, [(0.1, 0.0)], n_crossings=100, method="split4", dt=0.01, max_steps=1000)
    assert res.status[0] == STATUS_MAX_STEPS and res.count[0] < 100
    res = sections.crossings(prm, 2.0, [(0.1, 0.0)], n_crossings=100, method="taylor", max_steps=50)
    assert res.status[0] == STATUS_MAX_STEPS


#: how each method stops an orbit whose numbers overflow: the Taylor coefficients produce inf/NaN
#: (non-finite state); DOP853's first step, chosen from |f| ~ 1e300, lies below the round-off of t
#: (step size underflow); the splitting methods do not start it, as no fixed step resolves its
#: motion (dt x model.max_rate ~ 1e148 > pi: step does not resolve the motion).  None may report
#: a crossing.
NONFINITE_FLAG = ({m: STATUS_UNRESOLVED for m in ALL_METHODS} | {"taylor": STATUS_NONFINITE,
                                                                 "dop853": STATUS_STEP_UNDERFLOW})


@pytest.mark.parametrize("method", ALL_METHODS)
def test_nonfinite_state_is_reported_per_orbit_and_the_rest_is_unaffected(method):
    """An orbit whose numbers overflow mid-run (p1 = 1e150: finite energy, but p1^2 M and the
    Taylor coefficients overflow) is stopped and flagged by every method, with its own status;
    nothing non-finite is stored and the other orbits of the batch give exactly what they
    give alone."""
    prm = PARAM_SETS["figure4_mu0.5"]
    good = model.section_state(prm, [0.1, -0.3], [0.0, 0.2], 2.0)
    bad = good[0].copy()
    bad[0] = 1e150
    y0 = np.vstack([good[0], bad, good[1]])
    kw = dict(tol=1e-12, dt=0.01, tmax=20.0)
    res = sections.crossings(prm, states=y0, n_crossings=5, method=method, **kw)
    ref = sections.crossings(prm, states=good, n_crossings=5, method=method, **kw)
    np.testing.assert_array_equal(res.data[[0, 2]], ref.data)
    np.testing.assert_array_equal(res.status[[0, 2]], ref.status)
    assert res.count[1] == 0 and np.all(np.isnan(res.data[1]))
    assert res.status[1] == NONFINITE_FLAG[method], res.status_name(1)


def test_start_with_infinite_energy_is_refused():
    y0 = np.array([0.1, 0.0, 1e200, 0.0, -1.0])
    with pytest.raises(model.ParameterError, match="finite energy"):
        sections.crossings(model.FIGURE4, states=y0, n_crossings=2)


# ---------------------------------------------------------------- determinism
@pytest.mark.parametrize("method", ["taylor", "dop853", "split8"])
def test_results_are_identical_whatever_the_thread_count(method):
    prm = PARAM_SETS["figure4_mu0.5"]
    p1, p2 = fig4_seeds(prm, 2.0, 16, p2_frac=0.05)
    a = sections.crossings(prm, 2.0, np.column_stack([p1, p2]), n_crossings=30, method=method, threads=1)
    b = sections.crossings(prm, 2.0, np.column_stack([p1, p2]), n_crossings=30, method=method, threads=2)
    np.testing.assert_array_equal(a.data, b.data)
    np.testing.assert_array_equal(a.status, b.status)
    np.testing.assert_array_equal(a.final, b.final)


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize("kw,fragment", [
    (dict(method="rk4"), "method must be one of"),
    (dict(tol=0.0), "tol must be"), (dict(tol=float("nan")), "tol must be"),
    (dict(method="split4", dt=-0.1), "dt must be"), (dict(tmax=-1.0), "tmax must be"),
    (dict(direction=2), "direction must be"), (dict(max_steps=0), "max_steps must be"),
    (dict(threads=0), "threads must be"), (dict(threads=2.0), "threads must be an integer"),
    (dict(threads=10**6), r"threads must be <= \d+ \(NUMBA_NUM_THREADS"),
])
def test_bad_settings_are_refused_with_their_name(kw, fragment):
    prm = model.FIGURE4
    y0 = model.section_state(prm, [0.1], [0.0], 2.0)
    with pytest.raises(model.ParameterError, match=fragment):
        sections.crossings(prm, states=y0, n_crossings=3, **kw)


def test_nonfinite_or_misshapen_start_is_refused():
    with pytest.raises(model.ParameterError, match="y0 must be finite"):
        sections.crossings(model.FIGURE4, states=[0.0, np.nan, 1.0, 0.0, -1.0], n_crossings=2)
    with pytest.raises(model.ParameterError, match="shape"):
        sections.crossings(model.FIGURE4, states=[0.0, 1.0, 0.0, -1.0], n_crossings=2)
    with pytest.raises(model.ParameterError, match="crossings must be"):
        sections.crossings(model.FIGURE4, states=[0.0, 0.0, 1.0, 0.0, -1.0], n_crossings=0)


def test_propagate_gives_the_state_at_t_as_scipys_reference_integration_and_from_a_map_the_same():
    """propagate(params, states=y0, t=...) is the flow at exactly t: equal to scipy's DOP853 at rtol
    1e-12 on R3 (tests/reference.py, independent of the project's code) within 1e-9; from a
    SectionMap and its section points the same states; an orbit that would pass more than
    PROPAGATE_CROSSINGS crossings is refused, not truncated."""
    from scipy.integrate import solve_ivp

    prm = PARAM_SETS["figure4_mu0.5"]
    smap = SectionMap(prm, 2.0, tol=1e-14)
    pts = np.array([[0.1, 0.0], [-0.3, 0.2]])
    y0 = smap.states(pts)
    got = sections.propagate(prm, states=y0, t=7.5, tol=1e-14)
    for i in range(2):
        ref = solve_ivp(reference.rhs_numpy, (0.0, 7.5), y0[i], args=(prm.as_array(),), method="DOP853",
                        rtol=1e-12, atol=1e-12).y[:, -1]
        np.testing.assert_allclose(got[i], ref, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(sections.propagate(smap, pts, t=7.5), got)
    with pytest.raises(model.ParameterError, match="shorter times"):
        sections.propagate(prm, states=y0, t=100.0 * sections.PROPAGATE_CROSSINGS)


def test_propagate_refuses_a_system_pointing_to_its_flow_and_iter_crossings_of_a_system_needs_its_section():
    """docs/systems.md: a System's states at a time are explorer.flow's; iter_crossings streams a System
    (tests/analysis/test_system_sections.py) and a System's map
    (tests/analysis/test_system_section_map.py); the refusals come before any integration."""
    from systems import henon_heiles

    hh = henon_heiles()
    with pytest.raises(model.ParameterError, match=r"propagate is for Chaplygin's model.*explorer\.flow\(system"):
        sections.propagate(hh, states=[[0.0, 0.1, 0.3, 0.0]], t=1.0)
    with pytest.raises(model.ParameterError, match=r"section is missing"):
        sections.iter_crossings(hh, states=[[0.0, 0.1, 0.3, 0.0]], n_crossings=4)
