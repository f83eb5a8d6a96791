"""The analyses of a map run on any area-preserving map of the protocol (docs/greene.md).

Every test function here runs twice, on Chirikov's standard map ``StandardMap(k)`` (explicit,
compiled) and on the section map of Figure 4's scene (``SectionMap``, an integration per
application), through the same calls: periodic orbits and their symmetric search, residues,
continuation, rotation numbers, manifolds, homoclinic points, lobes and exit times.  Each
asserts a property that could fail on either map; where the standard map has an analytic or
published value it is asserted as well (the residues of its fixed points and period-2 orbits in
closed form, the period doubling of its elliptic point at k = 4, the linear rotation number
acos(1 - k/2)/2 pi)."""
import dataclasses
import math

import numpy as np
import pytest

import explorer as ex
from explorer import model
from explorer.analysis import fixedpoints as fpm
from explorer.analysis import manifolds as mf
from explorer.analysis import periodic as pr
from explorer.analysis import rotation as ro
from explorer.analysis import transport as tr
from explorer.analysis.maps import difference

#: the standard map's parameter: below the golden curve's breakup k_c = 0.9716 the map has no
#: chaotic sea, above it the separatrix of (0, 0) has a visible turnstile; 1.2 has both islands
#: and a lobe area of order 0.06 (cheap to resolve)
K = 1.2
#: Figure 4's scene (h = 2) at mu = 0.03: the central saddle near (-0.011, 0) (trace 9.03) and the
#: elliptic point of the right island near (1.58, 0) (trace 1.56)
MU = 0.03


@dataclasses.dataclass
class Case:
    """One map and where its landmarks are."""

    name: str
    system: object
    elliptic: tuple          # a guess of an elliptic fixed point
    hyperbolic: tuple        # a guess of a hyperbolic fixed point
    stable_sign: int         # the branch of W^s that meets W^u (sign +1 of the saddle) first
    #: the saddle whose W^s meets W^u: the same point for the section map; for the lifted standard map
    #: the separatrix of (0, 0) goes to (2 pi, 0), the same point of the cylinder
    shift: tuple = (0.0, 0.0)


def _standard():
    return Case("standard", ex.StandardMap(K), (math.pi, 0.1), (0.1, 0.0), -1, (2.0 * math.pi, 0.0))


def _section():
    return Case("section", ex.SectionMap(model.FIGURE4.with_(mu=MU), model.FIGURE4_H), (1.58, 0.0), (0.0, 0.0), 1)


@pytest.fixture(scope="module", params=["standard", "section"])
def case(request):
    return _standard() if request.param == "standard" else _section()


def test_what_only_a_section_map_has_is_refused_or_answered_for_another_map(case):
    """symmetry_line_points: the half-turn seeds of a section map, the line points of the standard
    map (on Fix I0 and Fix I1); flux_curve (it follows a section map's saddle in mu) refuses another
    map with a ParameterError naming what to use."""
    m = case.system
    seeds = pr.symmetry_line_points(m, 2, n=8)
    assert seeds.ndim == 2 and seeds.shape[1] == 2 and len(seeds) >= 1
    if case.name == "standard":
        assert len(seeds) == 32 and all(
            min(np.max(np.abs(difference(m, R(x), x))) for R in m.reversors) < 1e-12 for x in seeds)
        with pytest.raises(model.ParameterError, match="grow_branch"):
            tr.flux_curve(m, [0.1])


def _fd_jacobian(system, x, step=1e-6):
    """DP(x) by central differences of the map's image (no tangent dynamics)."""
    J = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = step
        J[:, j] = (system(x + e, jacobian=False).point - system(x - e, jacobian=False).point) / (2 * step)
    return J


def _returns(system, orb, tol):
    """The orbit's points map onto each other in order, and P^K(x_0) = x_0 (on the map's cylinder)."""
    pts = orb.points
    K_ = orb.period
    for i in range(K_):
        assert np.max(np.abs(difference(system, system(pts[i], jacobian=False).point, pts[(i + 1) % K_]))) < tol
    assert np.max(np.abs(difference(system, system.iterate(pts[0], K_)[-1], pts[0]))) < tol


# ------------------------------------------------------------------ periodic orbits and residues
def test_fixed_points_return_to_themselves_with_the_residue_of_a_finite_difference_jacobian(case):
    m = case.system
    ell = fpm.find_fixed_point(m, case.elliptic)
    hyp = fpm.find_fixed_point(m, case.hyperbolic)
    for fp in (ell, hyp):
        _returns(m, fp, 1e-10)
        J = _fd_jacobian(m, fp.point)
        assert fp.residue == pytest.approx((2.0 - np.trace(J)) / 4.0, abs=1e-6)
        assert fp.det == pytest.approx(1.0, abs=1e-9)       # area preservation
    assert 0.0 < ell.residue < 1.0 and hyp.residue < 0.0
    if case.name == "standard":   # (pi, 0): trace 2 - k, R = k/4; (0, 0): trace 2 + k, R = -k/4
        np.testing.assert_allclose(m.wrap(ell.point), [math.pi, 0.0], atol=1e-12)
        np.testing.assert_allclose(difference(m, hyp.point, [0.0, 0.0]), [0.0, 0.0], atol=1e-12)
        assert ell.residue == pytest.approx(K / 4, abs=1e-14) and hyp.residue == pytest.approx(-K / 4, abs=1e-14)


@pytest.mark.cpu_dependent
def test_the_period_2_search_finds_symmetric_orbits_whose_residues_are_the_product_of_their_jacobians(case):
    """Every orbit the search (seeds on the symmetry lines, then a grid) finds returns to itself,
    is symmetric under a reversor of the map, and has residue (2 - tr M)/4 with M the product of
    finite-difference Jacobians along it.  Standard map: the 1/2 orbits in closed form (the orbit
    (0, pi), (pi, pi): tr = 2 - k^2, R = k^2/4; the pair theta_1 = -theta_0 with
    4 theta_0 + k sin theta_0 = 2 pi: R = -c (1 + c/4), c = k cos theta_0)."""
    m = case.system
    orbs = [o for o in pr.search_periodic_orbits(m, 2, grid=4, line=12, max_guesses=6) if not o.degenerate]
    assert len(orbs) >= 2
    for o in orbs:
        assert o.period == 2
        _returns(m, o, 1e-9)
        M = np.eye(2)
        for x in o.points:
            M = _fd_jacobian(m, x) @ M
        assert o.residue == pytest.approx((2.0 - np.trace(M)) / 4.0, abs=1e-6 * max(1.0, abs(o.residue)))
        assert o.symmetric
        assert any(np.max(np.abs(difference(m, np.sort(ex_reduce(m, R(o.points)), axis=0),
                                            np.sort(ex_reduce(m, o.points), axis=0)))) < 1e-8 for R in m.reversors)
    if case.name == "standard":
        theta0 = _solve(lambda t: 4 * t + K * math.sin(t) - 2 * math.pi, 1.0, 2.0)
        c = K * math.cos(theta0)
        expected = sorted([K * K / 4, -c * (1 + c / 4)])
        got = sorted({round(o.residue, 9) for o in orbs})
        np.testing.assert_allclose(got, expected, atol=1e-12)


def ex_reduce(m, x):
    from explorer.analysis.maps import reduce

    return reduce(m, x)


def _solve(f, a, b):
    for _ in range(200):
        c = 0.5 * (a + b)
        a, b = (c, b) if f(a) * f(c) > 0 else (a, c)
    return 0.5 * (a + b)


def test_a_multiple_shooting_orbit_of_period_5_returns_to_itself(case):
    """K = 5 is solved by multiple shooting over the five points (periodic.MULTIPLE_SHOOTING_FROM)."""
    m = case.system
    orbs = [o for o in pr.search_periodic_orbits(m, 5, grid=4, line=16, max_guesses=4) if not o.degenerate]
    assert orbs
    for o in orbs:
        assert o.period == 5 and pr.MULTIPLE_SHOOTING_FROM <= 5
        _returns(m, o, 1e-9)
        assert o.det == pytest.approx(1.0, abs=1e-8)


def test_the_half_orbit_method_finds_newtons_orbit_with_the_residue_of_the_full_product(case):
    """greene.symmetric_orbit (one unknown on a symmetry line, the monodromy from the first half
    orbit and the reversor) against find_periodic_orbit (multiple shooting over all points, the
    product of all Jacobians): a symmetric orbit of period 5 of each map."""
    from explorer.analysis import greene as gm

    m = case.system
    if case.name == "standard":
        half = gm.symmetric_orbit(m, 1, 5)
    else:   # the search's symmetric orbit of period 5 with a point on p2 = 0
        seed = next(o for o in pr.search_periodic_orbits(m, 5, grid=4, line=16, max_guesses=4)
                    if o.symmetric and not o.degenerate and np.min(np.abs(o.points[:, 1])) < 1e-9)
        half = gm.symmetric_orbit(m, 1, 5, guess=seed.points[np.argmin(np.abs(seed.points[:, 1])), 0])
    newton = pr.find_periodic_orbit(m, half.points, 5)
    assert newton.period == 5
    np.testing.assert_allclose(difference(m, newton.points, half.points), 0.0, atol=1e-9)
    assert half.residue == pytest.approx(newton.residue, rel=1e-7, abs=1e-10)
    M = np.eye(2)
    for x in half.points:
        M = m.jacobian(x) @ M
    assert half.residue == pytest.approx((2.0 - np.trace(M)) / 4.0, rel=1e-7, abs=1e-10)


def test_continuation_follows_the_elliptic_point_and_finds_where_it_turns_hyperbolic(case):
    """Each continued orbit is a fixed point of the map at its own parameter value.  Standard map:
    (pi, 0) has trace 2 - k, so it period-doubles at k = 4 exactly."""
    m = case.system
    if case.name == "standard":
        br = pr.continue_periodic(m, 1, "k", 3.5, 4.5, 0.25, (math.pi, 0.0))
        (bif,) = br.bifurcations
        assert bif["type"] == "period-doubling" and bif["value"] == pytest.approx(4.0, abs=1e-7)
        np.testing.assert_allclose(br.traces, 2.0 - br.values, atol=1e-12)
    else:
        br = pr.continue_periodic(m, 1, "mu", MU, MU + 0.02, 0.01, fpm.find_fixed_point(m, case.elliptic))
        assert br.stopped is None and len(br.orbits) == 3
    for v, o in zip(br.values, br.orbits):
        at = m.with_parameter(v)
        _returns(at, o, 1e-9)
    # follow: the same fixed point at the end of the branch
    end = fpm.follow(m, m.parameter, br.values[0], br.values[-1], br.orbits[0].points[0])
    assert np.max(np.abs(difference(m, end.point, br.orbits[-1].points[0]))) < 1e-9


# ------------------------------------------------------------------ rotation numbers
def test_rotation_number_near_the_elliptic_point_converges_to_its_linear_frequency(case):
    """Weighted Birkhoff: an orbit 1e-3 from the elliptic point lies on a KAM curve; its average
    converges (WB_N = WB_2N to 1e-10) to acos(tr/2)/2 pi up to O(1e-3^2).  Standard map:
    tr = 2 - k."""
    m = case.system
    c = fpm.find_fixed_point(m, case.elliptic).point
    r = ro.rotation_number(m, c + np.array([1e-3, 0.0]), center=c, iterates=1000)
    tr_ = np.trace(m.jacobian(c))
    assert r.converged and r.status == "done"
    assert abs(r.value) == pytest.approx(math.acos(tr_ / 2.0) / (2.0 * math.pi), abs=1e-5)
    if case.name == "standard":
        assert abs(r.value) == pytest.approx(math.acos(1.0 - K / 2.0) / (2.0 * math.pi), abs=1e-5)
    # the profile's orbits are the same orbits: its first point's number is this one
    prof = ro.rotation_profile(m, c + np.array([1e-3, 0.0]), c + np.array([2e-3, 0.0]), n=2, center=c,
                               iterates=1000)
    assert prof.rotation[0] == pytest.approx(r.value, abs=1e-13) and bool(np.all(prof.converged))
    # farther from the centre the frequency moves away from the linear one by O(r^2): the twist
    assert abs(abs(prof.rotation[1]) - abs(prof.rotation[0])) > 0.0


# ------------------------------------------------------------------ manifolds, homoclinic points, lobes
@pytest.fixture(scope="module")
def tangle(case):
    m = case.system
    fp = fpm.find_fixed_point(m, case.hyperbolic)
    fp = dataclasses.replace(fp, points=np.asarray(case.hyperbolic) + difference(m, fp.points, case.hyperbolic))
    sd = mf.saddle(m, fp)
    far = mf.saddle(m, dataclasses.replace(fp, points=fp.points + np.asarray(case.shift))) if any(case.shift) else sd
    length = 8.0 if case.name == "standard" else 6.0
    bu = mf.grow_branch(sd, sign=1, arclength=length)
    bs = mf.grow_branch(far, stable=True, sign=case.stable_sign, arclength=length)
    return sd, bu, bs, mf.homoclinic_points(bu, bs)


def test_preimages_of_unstable_manifold_points_lie_on_the_branch(case, tangle):
    """The map's own inverse (not the batch that grew the branch) takes points of W^u one
    generation back along it."""
    sd, bu, _, _ = tangle
    L = math.log(sd.multiplier)
    idx = np.flatnonzero(bu.sigma > bu.sigma[1] + 2 * L)[::97][:4]
    assert idx.size >= 3 and bu.status == "arclength"
    for i in idx:
        back = case.system.inverse(bu.points[i])
        assert np.linalg.norm(back - bu.at([bu.sigma[i] - L])[0]) < 1e-9
        assert bu.distance(back) < 1e-10


@pytest.mark.cpu_dependent
def test_homoclinic_points_lie_on_both_branches_and_one_on_a_symmetry_line(case, tangle):
    """Every intersection found is on both manifolds to 1e-10; the primary one of the reversible
    maps is a fixed point of a reversor (Section map: p2 = 0; standard map: theta = pi or
    2 theta - p = 0 mod 2 pi)."""
    _, bu, bs, hs = tangle
    m = case.system
    assert len(hs) >= 2
    for hp in hs:
        assert hp.residual < 1e-10
        assert bu.distance(hp.point) < 1e-10 and bs.distance(hp.point) < 1e-10
    on_line = [hp for hp in hs
               if min(np.max(np.abs(difference(m, R(hp.point), hp.point))) for R in m.reversors) < 1e-9]
    assert on_line
    if case.name == "standard":   # Greene's line theta = pi carries one (the I0 line of the separatrix)
        assert any(abs(hp.point[0] - math.pi) < 1e-9 for hp in hs)


@pytest.mark.cpu_dependent
def test_the_two_lobes_of_the_turnstile_have_equal_areas(case, tangle):
    """Area preservation: the lobes bounded by adjacent primary intersections have equal areas
    (MacKay, Meiss & Percival 1984), to their error estimates."""
    _, bu, bs, hs = tangle
    lb = tr.lobes(bu, bs, points=hs)
    assert len(lb) == 2
    assert tr.turnstile_check(lb, bu.arclength, points=hs) == "ok"
    a, b = abs(lb[0].area), abs(lb[1].area)
    assert a > 1e-3 and abs(a - b) < 3 * (lb[0].error + lb[1].error) + 1e-9 * a


@pytest.mark.cpu_dependent
def test_mean_exit_time_is_accessible_area_over_flux_within_the_sampling_error(case, tangle):
    """Meiss 1992: over the entry set of a region R, <min(T, N)> = A(points leaving within N)/flux,
    both from the samples, within three standard errors."""
    _, bu, bs, hs = tangle
    h0 = min(hs, key=lambda hp: min(np.max(np.abs(difference(case.system, R(hp.point), hp.point)))
                                    for R in case.system.reversors))
    r = tr.exit_times(bu, bs, h0, samples=600, max_iter=60)
    assert r["entry"] > 30
    phi = r["flux_mc"]
    expected = r["accessible_area"] / phi
    err = math.hypot(r["sem"], expected * math.hypot(r["accessible_sem"] / r["accessible_area"],
                                                     r["flux_mc_sem"] / phi))
    assert abs(r["mean"] - expected) < 3 * err


# ------------------------------------------------------------------ frequency diffusion
def test_frequency_diffusion_is_tiny_on_a_kam_curve_and_large_on_a_chaotic_orbit(case):
    """log10 |nu1 - nu2| of the two halves' weighted-Birkhoff rotation numbers: below -10 on the
    orbit 1e-2 from the elliptic point (a KAM curve, super-convergence); on the standard map at
    k = 1.2 above -6 for an orbit started next to the saddle (0, 0), in the chaotic sea (theta's own
    rotation, center=None)."""
    m = case.system
    c = fpm.find_fixed_point(m, case.elliptic).point
    if case.name == "standard":
        fd = ro.frequency_diffusion(m, [[math.pi, 0.3], [1e-3, 1e-3]], center=None, iterates=1000)
        assert fd[0] < -10 and fd[1] > -6
    else:
        (fd,) = ro.frequency_diffusion(m, [c + np.array([1e-2, 0.0])], center=c, iterates=1000)
        assert fd < -10


@pytest.mark.slow
@pytest.mark.cpu_dependent
def test_frequency_diffusion_ranks_orbits_as_megno_does_across_an_island_edge():
    """Figure 4's scene at mu = 0.1, 12 orbits on p2 = 0 from the right island's elliptic point
    out through its edge into the chaotic sea: the two indicators classify every orbit alike
    alike but at the sticky edge (frequency diffusion above -4 only where MEGNO is above 4) and
    their Spearman rank correlation is positive (within each class the ranks are noise:
    docs/greene.md, "Frequency diffusion")."""
    from explorer.analysis import lyapunov as ly

    sm = ex.SectionMap(model.FIGURE4.with_(mu=0.1), model.FIGURE4_H)
    c = fpm.find_fixed_point(sm, (1.58, 0.0)).point
    X = np.column_stack([np.linspace(1.58, 1.87, 12), np.zeros(12)])
    N = 200
    fd = ro.frequency_diffusion(sm, X, center=c, iterates=N)
    megno = ly.indicators(sm, X, tmax=2 * N * 6.0).values["megno"]
    assert np.all(np.isfinite(fd)) and np.all(np.isfinite(megno))
    chaotic = megno > 4.0
    assert 2 <= chaotic.sum() <= 10
    # a drifting frequency is chaos: every orbit with fd > -4 has MEGNO > 4 (and every orbit MEGNO
    # calls regular has fd < -4); the converse fails at the island's edge, where a sticky chaotic
    # orbit (MEGNO > 4, p1 = 1.844) keeps its frequency to 4e-5 over 2N = 400 returns
    assert np.all(chaotic[fd > -4.0]) and np.all(fd[~chaotic] < -4.0)
    assert np.sum(chaotic & (fd <= -4.0)) <= 2

    def rank(v):
        r = np.empty(len(v))
        r[np.argsort(v)] = np.arange(len(v))
        return r

    rho = np.corrcoef(rank(fd), rank(megno))[0, 1]
    print(f"Spearman rank correlation of frequency diffusion and MEGNO: {rho:.3f}")
    assert rho > 0.3          # measured 0.60
