"""Greene's residue criterion on the standard map (explorer.analysis.greene): the literature's numbers.

Independent checks: the half-orbit orbits are periodic orbits of (S1) iterated by hand; their
residues against a second method, Newton and the monodromy product over the whole orbit in
80-bit long double (numpy.longdouble, written out here); the critical k of the golden-mean
curve and the residues there against Greene 1979 and MacKay 1983."""
import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import explorer as ex
from explorer.analysis import greene as gm
from explorer.analysis import greene_core
from explorer.analysis.maps import StandardMap

#: Greene 1979 (J. Math. Phys. 20, 1183) and MacKay 1983 (Physica D 7, 283): the golden-mean
#: circle of the standard map breaks at k_c = 0.971635406 (published to 9 digits)
K_C_PUBLISHED = 0.971635406
#: MacKay 1983: the residues of the golden convergents at k_c converge to R* = 0.2500888
R_STAR_PUBLISHED = 0.2500888
FIBONACCI = [1, 2, 3, 5, 8, 13, 21, 34, 55, 89, 144, 233, 377, 610, 987]

LD = np.longdouble
PI_LD = LD("3.14159265358979323846264338327950288")


def _long_double_residue(k, P, Q, p0):
    """The second method: Newton on the half orbit, then the product of all Q Jacobians along the
    full orbit, every operation in 80-bit long double (64-bit mantissa, 2^-64 ~ 5e-20)."""
    k = LD(k)
    even = Q % 2 == 0
    n = Q // 2 if even else (Q + 1) // 2
    p = LD(p0)
    for _ in range(40):
        th, pp, dth, dp = PI_LD, p, LD(0), LD(1)
        for _ in range(n):
            kc = k * np.cos(th)
            dp = dp + kc * dth
            pp = pp + k * np.sin(th)
            dth = dth + dp
            th = th + pp
        f, df = (th - PI_LD - PI_LD * P, dth) if even else (2 * th - pp - 2 * PI_LD - 2 * PI_LD * P, 2 * dth - dp)
        step = -f / df
        p += step
        if abs(step) < LD(1e-18) * abs(p):
            break
    th, pp = PI_LD, p
    a, b, c, d = LD(1), LD(0), LD(0), LD(1)
    for _ in range(Q):
        kc = k * np.cos(th)
        a, b, c, d = (1 + kc) * a + c, (1 + kc) * b + d, kc * a + c, kc * b + d
        pp = pp + k * np.sin(th)
        th = th + pp
    return float((2 - (a + d)) / 4), float(p)


def _chain(k, qmax):
    """The symmetric orbits on theta = pi of the golden convergents up to qmax, each from the last."""
    out, guess = [], None
    for P, Q in gm.convergents("golden", qmax):
        orb = gm.symmetric_orbit(StandardMap(k), P, Q, guess=guess)
        guess = orb.points[0, 1]
        out.append(orb)
    return out


def test_the_convergents_of_the_golden_mean_are_the_fibonacci_ratios():
    conv = gm.convergents("golden", 987)
    assert conv == [(FIBONACCI[i - 1], FIBONACCI[i]) for i in range(1, len(FIBONACCI))]
    assert gm.convergents(0.5 * (3 - math.sqrt(5)), 233) == [(Q - P, Q) for P, Q in conv if Q <= 233]
    assert gm.convergents(math.sqrt(2) - 1, 200) == [(1, 2), (2, 5), (5, 12), (12, 29), (29, 70), (70, 169)]


def test_noble_numbers_are_continued_fractions_ending_in_ones():
    g = gm.GOLDEN
    assert gm.rotation_value("noble:6") == pytest.approx(1 / (6 + g), rel=1e-15)
    assert gm.rotation_value("noble:5,2") == pytest.approx(1 / (5 + 1 / (2 + g)), rel=1e-15)
    assert gm.rotation_value("noble:1") == pytest.approx(g, rel=1e-15)
    assert gm.convergents("noble:6", 60) == [(1, 6), (1, 7), (2, 13), (3, 20), (5, 33), (8, 53)]
    with pytest.raises(ex.ParameterError, match="noble:A"):
        gm.rotation_value("noble:0")


@pytest.mark.parametrize("k", (0.5, K_C_PUBLISHED, 1.0))
def test_half_orbit_orbits_are_periodic_orbits_of_the_map_with_points_on_both_symmetry_lines(k):
    for orb in _chain(k, 89):
        P, Q = orb.p, orb.q
        x = orb.points[0].copy()
        assert x[0] == math.pi
        for _ in range(Q):          # (S1) by hand
            x[1] += k * math.sin(x[0])
            x[0] += x[1]
        assert abs(x[0] - math.pi - 2 * math.pi * P) < 1e-9 and abs(x[1] - orb.points[0, 1]) < 1e-9
        n = Q // 2 if Q % 2 == 0 else (Q + 1) // 2
        zn = orb.points[n] if n < Q else x
        if Q % 2 == 0:      # z_n on Fix(I0): theta = pi (P + 1)
            assert abs(zn[0] - math.pi * (P + 1)) < 1e-9
        else:               # z_n on Fix(I1): 2 theta - p = 2 pi (P + 1)
            assert abs(2 * zn[0] - zn[1] - 2 * math.pi * (P + 1)) < 1e-9
        assert abs(np.linalg.det(orb.monodromy) - 1.0) < 1e-9 * max(1.0, np.abs(orb.monodromy).max() ** 2)


def test_the_half_orbit_monodromy_equals_the_full_product_of_jacobians():
    m = StandardMap(0.9)
    for orb in _chain(0.9, 55):
        M = np.eye(2)
        for x in orb.points:
            M = m.jacobian(x) @ M
        np.testing.assert_allclose(orb.monodromy, M, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("k", (0.5, K_C_PUBLISHED, 1.0))
def test_residues_up_to_period_233_agree_with_the_long_double_full_orbit_to_1e_8(k):
    for orb in _chain(k, 233):
        R_ld, p_ld = _long_double_residue(k, orb.p, orb.q, orb.points[0, 1])
        assert abs(p_ld - orb.points[0, 1]) < 1e-13
        assert abs(orb.residue - R_ld) <= 1e-8 * max(1.0, abs(R_ld)), (orb.q, orb.residue, R_ld)


def test_residues_vanish_below_and_grow_without_bound_above_the_breakup():
    below = {o.q: o.residue for o in _chain(0.5, 233)}
    above = {o.q: o.residue for o in _chain(1.0, 233)}
    assert all(abs(below[q]) < 1e-9 for q in (89, 144, 233))            # R -> 0: the curve exists
    assert above[89] > 3 and above[144] > 20 and above[233] > 300         # R -> infinity: it is broken
    assert below[2] == pytest.approx(0.25 ** 2, rel=1e-12)                # R = k^2/4 for 1/2 (k = 0.5)


@pytest.mark.cpu_dependent
def test_greene_reproduces_greenes_critical_k_to_seven_digits_from_periods_up_to_233():
    r = ex.greene(ex.StandardMap(0.9), "golden", qmax=233)
    assert [c["q"] for c in r.convergents] == FIBONACCI[1:12]
    assert abs(r.critical - K_C_PUBLISHED) < 1e-8             # Greene 1979, MacKay 1983: 0.971635406
    assert abs(r.critical - K_C_PUBLISHED) <= r.uncertainty < 1e-7
    assert r.ratio == pytest.approx(-0.376, abs=0.01)          # k_n -> k_c geometrically


@pytest.fixture(scope="module")
def golden987():
    """Greene's criterion for the golden curve of the standard map, convergents up to q = 987."""
    return ex.greene(ex.StandardMap(0.9), "golden", qmax=987)


@pytest.mark.cpu_dependent
def test_greene_to_period_987_agrees_with_the_published_nine_digits(golden987):
    r = golden987
    assert abs(r.critical - K_C_PUBLISHED) < 1e-9             # 0.971635406 (MacKay 1983), 9 digits
    assert abs(r.critical - K_C_PUBLISHED) <= r.uncertainty + 5e-10   # within our error bar + rounding
    # the same curve seen as 1 - nu (the symmetry (theta, p) -> (-theta, -p) maps nu to 1 - nu)
    r2 = ex.greene(ex.StandardMap(0.9), "golden2", qmax=987)
    assert abs(r2.critical - r.critical) < 1e-10     # other orbits, other round-off: far below the error bar


@pytest.mark.cpu_dependent
def test_residues_at_the_critical_k_converge_to_mackays_limit(golden987):
    r = golden987
    # MacKay 1983: R* = 0.2500888
    dev = {c["q"]: abs(c["residue_at_critical"] - R_STAR_PUBLISHED) for c in r.convergents}
    assert dev[233] < 3e-4 and dev[987] < 6e-5
    assert dev[987] < dev[377] < dev[144] < dev[55]
    assert all(c["point_at_critical"][0] == pytest.approx(math.pi) for c in r.convergents)


def _covers_the_longer_chains(ks, least=4):
    """Each prefix of the k_n (at least ``least`` terms) has an uncertainty that covers the distance of
    its critical value to the whole chain's: [(prefix length, distance, uncertainty)] of those that do not."""
    full = greene_core.extrapolate(ks)[0]
    misses = []
    for m in range(least, len(ks)):
        crit, unc, _ = greene_core.extrapolate(ks[:m])
        if not abs(crit - full) <= unc:
            misses.append((m, abs(crit - full), unc))
    return misses


@pytest.mark.cpu_dependent
def test_the_uncertainty_of_every_shorter_golden_chain_covers_its_distance_to_the_chain_to_987(golden987):
    """docs/greene.md, "The criterion": the spread of the last three Aitken extrapolations bounds
    the error of the critical k; each chain q <= 5, 8, ..., 610 lies within it of the chain to q = 987,
    and that one within its own of the published 0.971635406 (plus its rounding)."""
    r = golden987
    ks = [c["param_n"] for c in r.convergents]
    assert greene_core.extrapolate(ks)[:2] == (r.critical, r.uncertainty)
    assert _covers_the_longer_chains(ks) == []
    assert abs(r.critical - K_C_PUBLISHED) <= r.uncertainty + 5e-10


#: mu_n of the convergents 5, 6, 11, 17, 28, 45, 73, 118, 191, 309, 500 of noble:5 on the section of
#: Figure 4's scene (right island): greene(SectionMap(FIGURE4.with_(mu=0.025), 2), "noble:5", qmax=500,
#: around=(1.58, 0)); mu_c = 0.0277404307 +- 2.3e-9 (docs/greene.md, "The noble curves")
NOBLE5_MU_N = [
    0.02589073949096207, 0.028922901486422573, 0.027516887895951865,
    0.027821284176752607, 0.027716505095889393, 0.027748788005883995,
    0.02773756506075876, 0.027741465189167903, 0.027740055515690438,
    0.02774056933836565, 0.027740379525330157,
]
#: mu_c of noble:5 from convergents up to q of about 600, computed independently of explorer
NOBLE5_MU_C_INDEPENDENT = 0.02774043


def test_the_uncertainty_of_the_noble5_chain_to_118_covers_the_longer_chains_and_the_independent_value():
    """The chain to q = 118 extrapolates to 0.027740459, 2.9e-8 from the chain to 500 and from the
    independent value: the difference of the last two extrapolations (8e-10) misses it, the spread of
    the last three (7.2e-7) covers it, and so does every shorter prefix's."""
    crit, unc, _ = greene_core.extrapolate(NOBLE5_MU_N[:8])
    longest, longest_unc, _ = greene_core.extrapolate(NOBLE5_MU_N)
    for reference in (longest, NOBLE5_MU_C_INDEPENDENT):
        assert 2e-8 < abs(crit - reference) <= unc
    assert abs(longest - NOBLE5_MU_C_INDEPENDENT) <= longest_unc
    assert _covers_the_longer_chains(NOBLE5_MU_N) == []


def test_extrapolation_of_a_geometric_sequence_is_its_limit_with_no_spread():
    ks = [1.0 + 0.5 * (-0.4) ** n for n in range(6)]
    crit, unc, ratio = greene_core.extrapolate(ks)
    assert crit == pytest.approx(1.0, abs=1e-15) and unc < 1e-15 and ratio == pytest.approx(-0.4, rel=1e-12)
    with pytest.raises(ex.ParameterError, match="at least 3"):
        greene_core.extrapolate(ks[:2])


def test_greene_bad_input_raises_parameter_error():
    with pytest.raises(ex.ParameterError, match="nu"):
        ex.greene(ex.StandardMap(0.9), 1.5)
    with pytest.raises(ex.ParameterError, match="nu"):
        ex.greene(ex.StandardMap(0.9), "platinum")
    with pytest.raises(ex.ParameterError, match="qmax"):
        ex.greene(ex.StandardMap(0.9), "golden", qmax=4)


# ---------------------------------------------------------------- the section map (Figure 4's scene)
def _section(mu):
    from explorer import model

    return ex.SectionMap(model.FIGURE4.with_(mu=mu), 2.0)


@pytest.mark.cpu_dependent
def test_section_half_orbit_orbits_are_newtons_periodic_orbits_with_the_same_residue():
    """The half-turn shooting on p2 = 0 and the monodromy from the first half (greene_section) against
    periodic.find_periodic_orbit (multiple shooting over all Q points, full product of Jacobians):
    the 1/6 and 3/20 orbits of the right island at mu = 0.025."""
    from explorer.analysis import greene_section as gs
    from explorer.analysis import periodic

    smap = _section(0.025)
    centre = gs.island_centre(smap, (1.58, 0.0))
    for P, Q in ((1, 6), (3, 20)):
        orb = gs.first_orbit(smap, P, Q, centre)
        assert abs(orb.rotation(smap, centre) * Q + P) < 1e-9          # turns clockwise, P/Q per return
        newton = periodic.find_periodic_orbit(smap, orb.points, Q)
        assert newton.period == Q
        np.testing.assert_allclose(newton.points, orb.points, atol=1e-9)
        assert orb.residue == pytest.approx(newton.residue, rel=1e-7, abs=1e-10)
        full = np.eye(2)
        for x in orb.points:
            full = smap.jacobian(x) @ full
        np.testing.assert_allclose(orb.monodromy, full, rtol=1e-7, atol=1e-9)


#: nu = 1/(6 + gamma), a noble rotation number of the right island at mu = 0.025, and its breakup
NOBLE_SECTION = dict(nu=1.0 / (6.0 + gm.GOLDEN), qmax=60, around=(1.58, 0.0))


def _bench_greene_section():
    """benchmarks/bench_greene_section.py as a module: its ``curve_orbit`` is the Birkhoff cross-check."""
    bench = Path(__file__).resolve().parents[2] / "benchmarks"
    sys.path.insert(0, str(bench))
    try:
        spec = importlib.util.spec_from_file_location("bench_greene_section", bench / "bench_greene_section.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(bench))
    return module


@pytest.fixture(scope="module")
def noble_breakup():
    return ex.greene(_section(0.025), NOBLE_SECTION["nu"], qmax=NOBLE_SECTION["qmax"], around=NOBLE_SECTION["around"])


@pytest.mark.cpu_dependent
def test_section_greene_finds_the_breakup_of_a_noble_curve_of_the_right_island(noble_breakup):
    """nu = 1/(6 + gamma): the k_n converge geometrically (ratio near -0.3, as on the standard map)
    and the residues at mu_c alternate around R*; the value itself is this project's own
    (benchmarks/RESULTS.md GREENE-SECTION; no published reference)."""
    r = noble_breakup
    assert [c["q"] for c in r.convergents] == [6, 7, 13, 20, 33, 53]
    # within its error bar of the value from q <= 139 (0.030339798, benchmarks/RESULTS.md)
    assert abs(r.critical - 0.030339798) <= r.uncertainty < 5e-5
    assert -0.5 < r.ratio < -0.2
    dev = [c["residue_at_critical"] - gm.CRITICAL_RESIDUE for c in r.convergents[-3:]]
    assert dev[0] * dev[1] < 0 and dev[1] * dev[2] < 0 and max(map(abs, dev)) < 0.01



@pytest.mark.cpu_dependent
def test_the_uncertainty_of_the_shorter_section_chains_covers_their_distance_to_the_longer(noble_breakup):
    """The chains to q = 20 and 33 of 1/(6 + gamma) lie within their uncertainty of the chain to 53."""
    assert _covers_the_longer_chains([c["param_n"] for c in noble_breakup.convergents]) == []

@pytest.mark.slow
def test_the_noble_curve_is_regular_just_below_greenes_breakup_and_not_just_above(noble_breakup):
    """The cross-check of Greene's mu_c on the section: the orbit of rotation number nu on p2 = 0
    (between the last two convergents' orbits) has a converged weighted-Birkhoff average 1 % below
    mu_c; 1 % above, the orbit the bisection ends on is not regular with rotation nu (not
    converged, or an island's other number).  Not ``cpu_dependent``: the two sides differ by five
    orders of magnitude in the average's convergence (differences about 1e-10 and 3e-5 over 10^4
    returns), which the last bits of a CPU cannot cross; the search it starts from, whose
    convergents and mu_c a CPU's rounding could move, is the test above, run on both targets."""
    from explorer.analysis import greene_section as gs

    curve_orbit = _bench_greene_section().curve_orbit
    r, nu = noble_breakup, NOBLE_SECTION["nu"]
    smap = _section(0.025)
    for factor, regular in ((0.99, True), (1.01, False)):
        m = smap.with_parameter(factor * r.critical)
        c = gs.island_centre(m, NOBLE_SECTION["around"])
        ends = [gs.section_symmetric_orbit(m, cv["q"], cv["point_at_critical"][0]).points[0, 0]
                for cv in r.convergents[-2:]]
        # 18 halvings of the bracket: the bisection's 600-return averages, not its depth, limit the start to
        # ~1e-7 of nu (24 halvings, the benchmark's, end 1.23e-7 from nu; 18 end 1.25e-7)
        rn = curve_orbit(m, nu, c, *ends, iterates=5000, steps=18)
        on_curve = rn.converged and abs(abs(rn.value) - nu) < 1e-6
        assert on_curve is regular, (factor, rn)


@pytest.mark.slow
@pytest.mark.cpu_dependent
def test_an_orbit_whose_turns_around_the_centre_are_undefined_is_skipped_not_fatal():
    """For [0; 6, 2, 1, ...] up to q = 150 the line scan meets, among the roots of the half-turn
    equation, an orbit whose rotation around the centre is not defined (its lift is unresolved):
    it is not an orbit of type P/Q around that centre and is passed over, and mu_c comes out as in
    the benchmark (0.0296312106, benchmarks/results/greene_section.json) within its uncertainty."""
    r = ex.greene(_section(0.025), "noble:6,2", qmax=150, around=(1.58, 0.0))
    assert [c["q"] for c in r.convergents][-1] == 134
    assert abs(r.critical - 0.0296312106) <= r.uncertainty < 2e-6


@pytest.mark.cpu_dependent
def test_the_left_island_is_the_half_turn_image_of_the_right_one_with_the_same_residues():
    """docs/greene.md, "The left island": the partner map T of the half-turn reversor (docs/model.md,
    "Symmetries") takes the right island's centre to the left one's and the right island's elliptic
    1/6 orbit (symmetric on p2 = 0 of phi = pi) onto the left island's (symmetric on p2 = 0 of phi = 0,
    the reversor's other line), with the same residue; the 1/7 orbits (odd period: a point on each
    line) are shot independently from the line p2 = 0 of phi = pi on both sides and have the same
    residue too.  Equal residues of every convergent give equal mu_c (benchmarks/RESULTS.md)."""
    from explorer.analysis import greene_section as gs
    from explorer.analysis.halfturn import partner_points

    smap = _section(0.025)
    right, left = gs.island_centre(smap, (1.58, 0.0)), gs.island_centre(smap, (-1.16, 0.0))
    np.testing.assert_allclose(partner_points(smap, right).points[0], left, atol=1e-9)
    # 1/6: the right island's orbit from its line, the left island's from the other line
    r6 = gs.section_symmetric_orbit(smap, 6, 1.7107)
    l6 = gs.section_symmetric_orbit(smap, 6, -1.7107, line=0.0)
    assert (r6.line, l6.line) == (math.pi, 0.0)
    assert abs(r6.rotation(smap, right) + 1 / 6) < 1e-9 and abs(l6.rotation(smap, left) + 1 / 6) < 1e-9
    assert 0 < r6.residue < 1 and l6.residue == pytest.approx(r6.residue, rel=1e-9)
    assert l6.line_start == pytest.approx(-r6.line_start, abs=1e-10)     # S(p1, 0, phi = pi) = (-p1, 0, phi = 0)
    images = partner_points(smap, r6.points).points                      # T maps the orbit onto the orbit
    assert max(np.min(np.linalg.norm(l6.points - y, axis=1)) for y in images) < 1e-8
    # 1/7: both orbits from the line p2 = 0 of phi = pi, different points of the two islands
    r7 = gs.section_symmetric_orbit(smap, 7, 1.7022)
    l7 = gs.section_symmetric_orbit(smap, 7, -1.6722)
    assert abs(l7.rotation(smap, left) + 1 / 7) < 1e-9 and abs(r7.rotation(smap, right) + 1 / 7) < 1e-9
    assert abs(l7.points[0, 0] + r7.points[0, 0]) > 0.01                  # not the mirror point
    assert l7.residue == pytest.approx(r7.residue, rel=1e-8)


@pytest.mark.cpu_dependent
def test_greene_around_the_left_island_uses_the_other_symmetry_line_and_finds_the_right_islands_mu_c():
    """Around the left island's elliptic point the elliptic orbits of even period sit on p2 = 0 of
    phi = 0 (island_line decides it from the 1/6 orbit nearest the centre on phi = pi, a hyperbolic
    one).  There the curve 1/(6 + gamma) breaks at the right island's mu_c, as the half-turn pairing
    demands: at the left island's mu_n and mu_c every convergent's orbit of the right island (shot
    from p2 = 0 of phi = pi, at the mirror point) has the left one's residue, so the right island's
    mu_n, hence mu_c, are the same (the right island's own greene: the CLI test and
    benchmarks/RESULTS.md, where the two agree to 1e-14).  The JSON points are on phi = pi in the
    left island."""
    from explorer.analysis import greene_section as gs

    left = ex.greene(_section(0.025), "noble:6", qmax=20, around=(-1.16, 0.0))
    assert left.line == 0.0 and [c["q"] for c in left.convergents] == [6, 7, 13, 20]
    assert abs(left.critical - 0.030339798) <= left.uncertainty < 1e-3
    for c in left.convergents:
        for mu, residue in ((c["param_n"], gm.CRITICAL_RESIDUE), (left.critical, c["residue_at_critical"])):
            right = gs.section_symmetric_orbit(_section(mu), c["q"], -c["line_start"])
            assert right.line == math.pi and right.residue == pytest.approx(residue, abs=1e-8)
    m = _section(left.critical)
    centre = gs.island_centre(m, (-1.16, 0.0))
    cv = left.convergents[-1]
    orb = gs.section_symmetric_orbit(m, cv["q"], cv["line_start"], line=left.line)
    np.testing.assert_allclose(orb.points[0], cv["point_at_critical"], atol=1e-9)      # the JSON point: on phi = pi
    assert abs(orb.rotation(m, centre) * 20 + 3) < 1e-6 and np.all(orb.points[:, 0] < 0)
