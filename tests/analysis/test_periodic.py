"""Periodic orbits of the section map (explorer.analysis.periodic): independent checks.

P^K(x) = x with scipy DOP853 (tests/reference.py), minimal period, trace against finite
differences, period 1 against find_fixed_point, the reversing symmetry of R3, deduplication,
continuation with the analytic bifurcations of solution I at mu = 0 (docs/model.md R6)."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import reference
from explorer import model
from explorer.analysis import fixedpoints as fpm
from explorer.analysis import periodic as pm
from explorer.analysis.section_map import SectionMap
from explorer.model import symmetry

PRM = model.FIGURE4.with_(mu=0.03)   # the Figure 4 scene at mu = 0.03 (docs/model.md R9)
H = 2.0


@pytest.fixture(scope="module")
def search2():
    return pm.search_periodic_orbits(PRM, H, 2)


@pytest.fixture(scope="module")
def search3():
    return pm.search_periodic_orbits(PRM, H, 3)


@pytest.fixture(scope="module")
def search4():
    return pm.search_periodic_orbits(PRM, H, 4)


def _independent_orbit(x, K):
    """K crossings of phi = pi from (p1, p2) with scipy DOP853 (rtol = atol = 1e-13)."""
    P = PRM.as_array()
    rows = reference.scipy_crossings(P, reference.state_on_section(P, x[0], x[1], H), K, rtol=1e-13, atol=1e-13)
    assert len(rows) == K
    return rows[:, 1:3], rows[:, 0]


def _elliptic(orbits):
    """The elliptic orbits, the one nearest the centre first (away from the region's boundary)."""
    return sorted([o for o in orbits if o.kind == "elliptic"], key=lambda o: np.min(np.abs(o.points[:, 0])))


@pytest.mark.parametrize("K", [2, 3])
def test_every_orbit_found_returns_to_itself_under_an_independent_scipy_integration(K, search2, search3):
    orbits = {2: search2, 3: search3}[K]
    assert orbits
    checked = 0
    for o in orbits:
        if np.max(np.abs(o.eigenvalues)) > 100:   # scipy's 1e-13 error grows like the multiplier
            continue
        pts, times = _independent_orbit(o.points[0], K)
        np.testing.assert_allclose(pts[-1], o.points[0], atol=1e-9)            # P^K(x) = x
        np.testing.assert_allclose(pts[:-1], o.points[1:], atol=1e-9)          # the K points
        np.testing.assert_allclose(np.diff(np.concatenate([[0.0], times])), o.return_times, rtol=1e-9)
        checked += 1
    assert checked >= 3


def test_multiple_shooting_orbit_of_period_6_returns_to_itself_under_scipy():
    orb = pm.find_periodic_orbit(PRM, H, (1.013197, 0.0), 6)
    assert orb.period == 6 and pm.MULTIPLE_SHOOTING_FROM <= 6
    assert orb.kind == "elliptic" and orb.symmetric
    pts, _ = _independent_orbit(orb.points[0], 6)
    np.testing.assert_allclose(pts[-1], orb.points[0], atol=1e-9)
    np.testing.assert_allclose(pts[:-1], orb.points[1:], atol=1e-9)


def test_single_and_multiple_shooting_converge_to_the_same_orbit():
    smap = SectionMap(PRM, H)
    a = pm._newton(smap, 6, np.array([1.0132, 0.0]), multiple=True)
    b = pm._newton(smap, 6, np.array([1.0132, 0.0]), multiple=False)
    np.testing.assert_allclose(a[0], b[0], atol=1e-10)
    np.testing.assert_allclose(pm._monodromy(a[2]), pm._monodromy(b[2]), rtol=1e-7, atol=1e-8)


def test_period_one_equals_find_fixed_point():
    for guess in [(0.05, 0.0), (1.58, 0.01), (-1.1, 0.0)]:
        fp = fpm.find_fixed_point(PRM, H, guess)
        orb = pm.find_periodic_orbit(PRM, H, guess, 1)
        np.testing.assert_allclose(orb.points[0], fp.point, atol=1e-12)
        assert orb.trace == pytest.approx(fp.trace, rel=1e-10, abs=1e-12)
        assert orb.det == pytest.approx(fp.det, abs=1e-12)
        assert orb.stable == fp.stable
        assert orb.return_times[0] == pytest.approx(fp.return_time, rel=1e-12)


@pytest.mark.cpu_dependent
def test_a_period_two_orbit_found_with_period_four_is_reported_with_its_minimal_period(search2):
    o2 = _elliptic(search2)[0]
    o4 = pm.find_periodic_orbit(PRM, H, o2.points[0], 4)
    assert o4.period == 2 and o4.points.shape == (2, 2)
    assert o4.same_orbit(o2)
    assert o4.trace == pytest.approx(o2.trace, abs=1e-8)
    kept = pm.find_periodic_orbit(PRM, H, o2.points[0], 4, reduce=False)
    assert kept.period == 4 and kept.trace == pytest.approx(o2.trace ** 2 - 2, abs=1e-7)  # tr(M^2) = tr^2 - 2


@pytest.mark.cpu_dependent
def test_search_of_period_four_reports_no_orbit_of_period_one_or_two(search2, search4):
    orbits = search4
    assert orbits and all(o.period == 4 for o in orbits)
    for o in orbits:
        assert pm._minimal_period(o.points, SectionMap(PRM, H)) == 4
        assert not any(o.same_orbit(o2) for o2 in search2)


def test_trace_matches_finite_differences_of_the_map_iterated_K_times(search3):
    smap = SectionMap(PRM, H)
    orb = _elliptic(search3)[0]

    def PK(x):
        for _ in range(3):
            x = smap(x, jacobian=False).point
        return x

    eps = 1e-6
    x0 = orb.points[0]
    fd = np.column_stack([(PK(x0 + eps * e) - PK(x0 - eps * e)) / (2 * eps) for e in np.eye(2)])
    np.testing.assert_allclose(orb.jacobian, fd, atol=1e-6)
    assert orb.trace == pytest.approx(np.trace(fd), abs=1e-6)
    assert orb.det == pytest.approx(1.0, abs=1e-9)
    assert orb.residue == pytest.approx((2 - orb.trace) / 4)
    assert (0 < orb.residue < 1) == (orb.kind == "elliptic")


@pytest.mark.cpu_dependent
def test_search_returns_each_orbit_once(search2, search3):
    for orbits in (search2, search3):
        for i, a in enumerate(orbits):
            assert len({tuple(np.round(p, 6)) for p in a.points}) == a.period   # K distinct points
            for b in orbits[i + 1:]:
                assert not a.same_orbit(b, 1e-5)


@pytest.mark.cpu_dependent
def test_asymmetric_orbits_come_with_their_mirror_image(search2, search3):
    for orbits in (search2, search3):
        assert any(not o.symmetric for o in orbits)
        for o in orbits:
            if not o.symmetric:
                assert sum(b.same_orbit(symmetry.reversor(o.points)) for b in orbits) == 1


def test_mirror_image_is_an_orbit_of_the_map_with_the_same_trace_under_scipy(search3):
    """G0 P G0 = P^-1 makes G0(orbit) an orbit: its points follow each other under scipy's map,
    its monodromy is G0 M^-1 G0 (same trace), its return times are the original's reversed, and
    Newton started from the reflected point converges to it."""
    o = next(x for x in search3 if not x.symmetric and not x.degenerate)
    m = pm.mirror_orbit(o)
    P = PRM.as_array()
    for j in range(3):
        np.testing.assert_allclose(reference.section_map_p(P, *m.points[j], H), m.points[(j + 1) % 3], atol=1e-9)
    G = np.diag([1.0, -1.0])
    np.testing.assert_allclose(m.jacobian, G @ np.linalg.inv(o.jacobian) @ G, rtol=1e-9, atol=1e-9)
    assert m.trace == pytest.approx(o.trace, abs=1e-9) and m.det == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(np.sort(m.return_times), np.sort(o.return_times), rtol=1e-12)
    n = pm.find_periodic_orbit(PRM, H, m.points[0], 3)
    assert n.same_orbit(m, 1e-9) and n.trace == pytest.approx(m.trace, abs=1e-8)
    np.testing.assert_allclose(n.return_times, m.return_times, rtol=1e-10)


#: a point on the period-3 resonant curve of the mu = 0.03 scene (|P^3(x) - x| < 1e-11 there)
RESONANT_CURVE_POINT = (-1.45876674, 0.95369106)


@pytest.mark.cpu_dependent
def test_an_orbit_on_a_resonant_curve_is_flagged_degenerate_and_is_not_isolated():
    """Newton from a guess moved 1e-4 along the null direction of (monodromy - I) stops at
    another point, again with P^3(x) = x to round-off: the orbit is not isolated, and its flag
    says so."""
    a = pm.find_periodic_orbit(PRM, H, RESONANT_CURVE_POINT, 3)
    null = np.linalg.svd(a.jacobian - np.eye(2))[2][-1]
    b = pm.find_periodic_orbit(PRM, H, a.points[0] + 1e-4 * null, 3)
    assert a.degenerate and b.degenerate and a.as_dict()["degenerate"]
    assert a.uncertainty > pm.ISOLATION_TOL and abs(a.residue) < 1e-6
    assert not a.same_orbit(b, 1e-5)           # two points of a continuum, not one orbit
    for o in (a, b):
        pts, _ = _independent_orbit(o.points[0], 3)
        np.testing.assert_allclose(pts[-1], o.points[0], atol=1e-8)    # both really return


def test_isolated_orbits_are_not_degenerate(search2, search3):
    for o in search2 + search3:
        if not o.degenerate:
            assert o.uncertainty < 1e-3 * pm.ISOLATION_TOL    # far from the threshold: no CPU can flip it


@pytest.mark.cpu_dependent
def test_degenerate_orbits_come_after_the_isolated_ones(search3):
    flags = [o.degenerate for o in search3]
    assert flags == sorted(flags)


def _isolated(orbits):
    return [o for o in orbits if not o.degenerate]


@pytest.mark.cpu_dependent
@pytest.mark.parametrize("K", [2, 3])
def test_the_same_isolated_orbits_come_out_when_the_seeds_move_by_1e_12(K, request):
    guesses = pm.periodic_guesses(PRM, H, K)
    rng = np.random.default_rng(K)
    base = _isolated(request.getfixturevalue(f"search{K}"))      # the default search starts from these guesses
    shift = 1e-12 * rng.choice([-1, 1], guesses.shape)
    moved = _isolated(pm.search_periodic_orbits(PRM, H, K, guesses=guesses + shift))
    assert len(base) == len(moved)
    for a, b in zip(base, moved):
        assert a.same_orbit(b, 1e-9) and a.trace == pytest.approx(b.trace, rel=1e-7, abs=1e-9)


#: isolated orbits of minimal period K at the Figure-4 scene, mu = 0.03, h = 2, with the default
#: search: the same on any x86-64 CPU (.ci/run runs this test with Numba compiling for the host
#: and for NUMBA_CPU_NAME=generic); symmetric orbits plus mirror pairs of asymmetric ones
ISOLATED_COUNTS = {1: 5, 2: 8, 3: 14, 4: 12}


@pytest.mark.cpu_dependent
@pytest.mark.parametrize("K", sorted(ISOLATED_COUNTS))
def test_isolated_orbit_count_per_period_is_the_same_on_any_cpu(K, request):
    orbits = request.getfixturevalue(f"search{K}") if K > 1 else pm.search_periodic_orbits(PRM, H, K)
    iso = _isolated(orbits)
    assert len(iso) == ISOLATED_COUNTS[K]
    assert sum(not o.symmetric for o in iso) % 2 == 0          # asymmetric orbits come in mirror pairs
    assert all(o.period == K and o.residual < 1e-11 for o in iso)


@pytest.mark.cpu_dependent
def test_two_guesses_on_different_points_of_one_orbit_give_one_orbit(search3):
    o = _elliptic(search3)[0]
    a = pm.find_periodic_orbit(PRM, H, o.points[0] + 1e-4, 3)
    b = pm.find_periodic_orbit(PRM, H, o.points[2] - 1e-4, 3)
    assert a.same_orbit(b) and not np.allclose(a.points[0], b.points[0])
    assert a.trace == pytest.approx(b.trace, abs=1e-8)          # the trace does not depend on the start


def _reduced_rhs(P):
    return lambda t, y: reference.rhs_numpy(t, y, P)


def _R(y):
    """The reversor of R3: (p1, p2, M, g1, g2) -> (p1, -p2, M, -g1, g2) (phi -> -phi)."""
    return np.array([y[0], -y[1], y[2], -y[3], y[4]])


@pytest.mark.parametrize("T", [3.0, 11.0])
def test_R3_is_reversible_under_p2_and_phi_sign_change_when_zeta_and_xi_vanish(T):
    P = model.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=0.0, mu=0.7, xi=0.0, eta=-0.25).as_array()
    phi = 0.7
    y0 = np.array([0.3, -0.4, 1.1, math.sin(phi), math.cos(phi)])
    f = _reduced_rhs(P)
    y1 = solve_ivp(f, (0, T), y0, method="DOP853", rtol=1e-12, atol=1e-12).y[:, -1]
    y2 = solve_ivp(f, (0, T), _R(y1), method="DOP853", rtol=1e-12, atol=1e-12).y[:, -1]
    np.testing.assert_allclose(y2, _R(y0), atol=1e-8)    # forward, reflect, forward = reflected start


def test_the_reversor_fails_when_xi_is_not_zero():
    P = model.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=0.0, mu=0.7, xi=0.3, eta=-0.25).as_array()
    y0 = np.array([0.3, -0.4, 1.1, math.sin(0.7), math.cos(0.7)])
    f = _reduced_rhs(P)
    y1 = solve_ivp(f, (0, 5.0), y0, method="DOP853", rtol=1e-12, atol=1e-12).y[:, -1]
    y2 = solve_ivp(f, (0, 5.0), _R(y1), method="DOP853", rtol=1e-12, atol=1e-12).y[:, -1]
    assert np.max(np.abs(y2 - _R(y0))) > 1e-3
    assert not symmetry.is_reversible(model.Params.from_array(P))


def test_section_map_is_reversed_by_G0():
    """G0 P G0 = P^-1 on phi = pi: P(G0(P(x))) = G0(x), with scipy's map."""
    P = PRM.with_(chi=0.1, eta=0.2).as_array()
    x = np.array([0.4, 0.3])
    y = reference.section_map_p(P, x[0], x[1], H)
    z = reference.section_map_p(P, y[0], -y[1], H)
    np.testing.assert_allclose(z, symmetry.reversor(x), atol=1e-10)


@pytest.mark.cpu_dependent
def test_symmetric_orbits_are_found_from_the_symmetry_lines_and_are_G0_invariant(search3):
    seeds = pm.symmetry_line_points(PRM, H, 3, n=96)
    assert len(seeds) >= 4
    symmetric = [o for o in search3 if o.symmetric]
    assert len(symmetric) >= 4
    for o in symmetric:
        g = symmetry.reversor(o.points)
        assert all(o.distance_to(p) < 1e-8 for p in g)
        # one of the K points is on p2 = 0 or the orbit has a seed from the second line
        assert np.min(np.abs(o.points[:, 1])) < 1e-9 or any(o.distance_to(s) < 1e-5 for s in seeds)
    # each seed lies on a symmetric orbit of period 3 (or 1) found by Newton
    for s in seeds[:6]:
        o = pm.find_periodic_orbit(PRM, H, s, 3)
        assert o.symmetric and o.period in (1, 3)


@pytest.mark.cpu_dependent
def test_continuation_of_solution_I_in_h_finds_the_tangent_and_the_touch_of_minus_two():
    """docs/model.md R6 at mu = 0: p = 0 is solution I for every h; with c = sqrt(2 b h) it is hyperbolic
    for lam b/a1 < c < lam b/a2 (c = 4: h = 4, trace +2) and beyond it the trace is 2 cos(w),
    w = sqrt(alpha beta) 2 pi b / c, which touches -2 (without crossing) where w = pi:
    c^2 - 8c + 32/3 = 0, c = 4 + 4/sqrt(3), h = c^2/4."""
    br = pm.continue_periodic(model.FIGURE4, 3.0, 1, "h", 3.0, 11.0, 0.5, (0.0, 0.0))
    assert br.stopped is None and len(br.orbits) == 17
    types = {b["type"]: b["value"] for b in br.bifurcations}
    assert set(types) == {"tangent", "touch -2"}
    assert types["tangent"] == pytest.approx(4.0, rel=1e-6)
    c = 4 + 4 / math.sqrt(3)
    assert types["touch -2"] == pytest.approx(c * c / 4, rel=1e-5)
    for v, o in zip(br.values, br.orbits):
        _, tr = fpm.analytic_eigenvalues_solution_I(model.FIGURE4, v)
        assert o.trace == pytest.approx(tr, abs=1e-8)


@pytest.mark.cpu_dependent
def test_continuation_reports_period_doubling_where_the_trace_crosses_minus_two():
    """The elliptic fixed point near (-1.155, 0) of the mu = 0.03 scene, followed in mu: its trace
    falls through -2; the bisected value is checked with find_fixed_point on either side."""
    br = pm.continue_periodic(PRM, H, 1, "mu", 0.03, 0.23, 0.05, (-1.155145, 0.0))
    assert br.stopped is None
    assert [b["type"] for b in br.bifurcations] == ["period-doubling"] and br.bifurcations[0]["refined"]
    mu_star = br.bifurcations[0]["value"]
    assert 0.13 < mu_star < 0.18
    before = fpm.find_fixed_point(PRM.with_(mu=mu_star - 1e-6), H, (-1.155145 - 0.1, 0.0))
    after = fpm.find_fixed_point(PRM.with_(mu=mu_star + 1e-6), H, before.point)
    assert before.trace > -2 > after.trace
    assert abs(before.trace + 2) < 1e-4 and abs(after.trace + 2) < 1e-4


@pytest.mark.cpu_dependent
def test_a_sampled_minimum_near_minus_two_is_refined_into_a_touch():
    """The fixed point near (-1.98, 0) followed in mu: the sampled trace has a minimum -1.989 near
    mu = 0.13; golden-section search finds that it touches -2 (to round-off) without crossing."""
    br = pm.continue_periodic(PRM, H, 1, "mu", 0.03, 0.23, 0.05, (-1.982035, 0.0))
    touches = [b for b in br.bifurcations if b["type"].startswith("touch")]
    assert len(touches) == 1 and touches[0]["type"] == "touch -2"
    assert abs(touches[0]["trace"] + 2) < 1e-6
    assert np.all(br.traces > -2)


def test_bad_input_is_refused_with_a_parameter_error():
    with pytest.raises(model.ParameterError, match="period"):
        pm.find_periodic_orbit(PRM, H, (0.1, 0.0), 0)
    with pytest.raises(model.ParameterError, match="outside the allowed region"):
        pm.find_periodic_orbit(PRM, H, (5.0, 0.0), 2)
    with pytest.raises(model.ParameterError, match="continuation parameter"):
        pm.continue_periodic(PRM, H, 1, "nope", 0, 1, 0.1, (0.0, 0.0))


def test_as_dict_has_the_json_shape(search2):
    d = search2[0].as_dict()
    for k in ("points", "trace", "residue", "eigenvalues", "stable", "symmetric", "period", "kind"):
        assert k in d
    assert len(d["points"]) == 2 and len(d["points"][0]) == 2


@pytest.mark.cpu_dependent
def test_every_isolated_orbit_comes_with_its_half_turn_partner_of_the_same_trace_and_period(search4):
    """docs/model.md, "Symmetries": T P = P^-1 T, so T(orbit) is an orbit with the same trace of the
    monodromy and the same period (the sum of its return times).  Period 4 at the mu = 0.03 scene:
    before the search completed its set with T, the partner of the orbit through (-1.8617, 0) was
    missing."""
    from explorer.analysis.halfturn import partner_points

    orbits = _isolated(search4)
    for o in orbits:
        image = partner_points(PRM, H, o.points).points
        partners = [b for b in orbits if b.same_orbit(image, 1e-7)]
        assert len(partners) == 1
        assert partners[0].trace == pytest.approx(o.trace, rel=1e-8, abs=1e-8)
        assert partners[0].total_time == pytest.approx(o.total_time, rel=1e-10)
