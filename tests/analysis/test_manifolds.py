"""Invariant manifolds, homoclinic points and lobes (explorer.analysis.manifolds, transport).

Invariance by an independent path (backward integration of the section map), agreement with a
tighter start, the reversor mapping W^u onto W^s, the exact separatrix R7 at mu = 0, budgets and
the region's edge; Green's theorem on known areas; the turnstile's lobes against Melnikov."""
import math

import numpy as np
import pytest

from explorer import model
from explorer.analysis import fixedpoints as fpm
from explorer.analysis import manifolds as mf
from explorer.analysis import melnikov as mk
from explorer.analysis import transport as tr
from explorer.analysis.section_map import SectionMap
from explorer.model.symmetry import reversor

H = model.FIGURE4_H           # docs/model.md R9: Figure 4, h = 2
MU = 0.03                     # the central saddle near (-0.011, 0), trace 9.03


@pytest.fixture(scope="module")
def saddle():
    fp = fpm.find_fixed_point(model.FIGURE4.with_(mu=MU), H, (0.0, 0.0))
    return mf.saddle(fp.params, fp.h, fp)


@pytest.fixture(scope="module")
def wu(saddle):
    return mf.grow_branch(saddle, sign=1, arclength=3.0)


def test_section_map_preserves_area_so_lobe_areas_are_invariant():
    sm = SectionMap(model.FIGURE4.with_(mu=MU), H)
    for x in ([0.3, 0.2], [-0.5, 0.1], [1.2, -0.4]):
        assert abs(np.linalg.det(sm.jacobian(x)) - 1.0) < 1e-10


def test_saddle_has_the_figure4_multiplier_and_starts_within_tolerance(saddle, wu):
    assert saddle.point[0] == pytest.approx(-0.011, abs=1e-3)
    assert saddle.multiplier + 1.0 / saddle.multiplier == pytest.approx(9.03, abs=0.01)
    # the linear start error |a| s0^2 / 2 is the requested tolerance
    assert 0.5 * wu.curvature * wu.start_distance ** 2 == pytest.approx(mf.DEFAULT_START_TOL, rel=1e-6)
    assert wu.status == "arclength" and 3.0 <= wu.arclength < 3.0 + mf.DEFAULT_MAX_GAP
    gaps = np.linalg.norm(np.diff(wu.points, axis=0), axis=1)
    assert gaps[1:].max() <= mf.DEFAULT_MAX_GAP


def test_preimages_of_unstable_points_lie_on_the_branch(saddle, wu):
    """P^-1 by backward integration (not the forward batch that grew the branch)."""
    L = math.log(saddle.multiplier)
    idx = np.flatnonzero(wu.sigma > wu.sigma[1] + 2 * L)[::97][:4]
    assert idx.size >= 3
    for i in idx:
        back = saddle.smap.inverse(wu.points[i])
        assert np.linalg.norm(back - wu.at([wu.sigma[i] - L])[0]) < 1e-9
        assert wu.distance(back) < 1e-10


def test_a_tighter_start_gives_the_same_manifold(saddle):
    loose = mf.grow_branch(saddle, sign=-1, arclength=2.0, start_tol=1e-8)
    tight = mf.grow_branch(saddle, sign=-1, arclength=2.0, start_tol=1e-13)
    assert loose.start_distance > 30 * tight.start_distance
    for x in loose.points[len(loose.points) // 3::40]:
        assert tight.distance(x) < 1e-8


def test_the_reversor_maps_the_unstable_onto_the_stable_manifold(saddle, wu):
    """W^s integrated backward in time (no use of the reversor) is G0 W^u."""
    ws = mf.grow_branch(saddle, stable=True, sign=1, arclength=1.5, integrate_backward=True)
    assert ws.status == "arclength"
    for x in ws.points[5::25]:
        assert wu.distance(reversor(x)) < 1e-9


def test_a_stable_branch_of_a_saddle_on_the_symmetry_line_is_the_reflection_of_the_unstable_one(saddle, wu):
    """W^s = G0 W^u branch by branch for a fixed point on p2 = 0 of a reversible map: grow_branch's
    stable branch is mirror_branch of its unstable one, bit for bit, and lies within 1e-9 of W^s
    integrated backward in time (no reversor); its points away from the saddle are maps of its
    own earlier points under P^-1 = G0 P G0 (its curve maps as the grown one would); a saddle
    the reversor does not fix (xi != 0, or a point of a period-2 orbit) is not mirrored."""
    assert mf.mirrors(saddle)
    ws = mf.grow_branch(saddle, stable=True, sign=1, arclength=3.0)
    mirror = mf.mirror_branch(wu)
    assert ws.kind == mirror.kind == "stable" and ws.mirror_of is not None
    assert np.array_equal(ws.points, mirror.points) and np.array_equal(ws.sigma, mirror.sigma)
    assert np.array_equal(ws.points, reversor(wu.points))
    back = mf.grow_branch(saddle, stable=True, sign=1, arclength=3.0, integrate_backward=True)
    for x in back.points[5::25]:
        assert ws.distance(x) < 1e-9
    L = math.log(saddle.multiplier)
    i = int(np.flatnonzero(ws.sigma > ws.sigma[1] + 2 * L)[0])
    assert np.linalg.norm(saddle.smap.inverse(ws.at([ws.sigma[i] - L])[0]) - ws.points[i]) < 1e-9
    # a longer branch continues from the mirrored one as from the grown one
    longer = mf.grow_branch(saddle, stable=True, sign=1, arclength=4.0, resume=ws)
    assert np.array_equal(longer.points, mf.mirror_branch(mf.grow_branch(saddle, sign=1, arclength=4.0)).points)
    # manifolds() reflects the unstable branches it grew
    branches = mf.manifolds(saddle.smap, saddle.point, arclength=1.0)
    assert [(b.kind, b.sign) for b in branches] == [("unstable", 1), ("unstable", -1), ("stable", 1), ("stable", -1)]
    assert all(np.array_equal(s.points, reversor(u.points)) for u, s in zip(branches[:2], branches[2:]))
    # ... each stable branch reflects the very unstable branch returned beside it (grown once), in
    # whichever order the kinds are asked for; a held branch of other settings is refused
    swapped = mf.manifolds(saddle.smap, saddle.point, arclength=1.0, kinds=("stable", "unstable"))
    assert [(b.kind, b.sign) for b in swapped] == [("stable", 1), ("stable", -1), ("unstable", 1), ("unstable", -1)]
    assert all(s.mirror_of is u and np.array_equal(s.points, t.points) for s, u, t in
               zip(swapped[:2], swapped[2:], branches[2:]))
    held = mf.grow_branch(saddle, stable=True, sign=1, arclength=3.0, unstable=wu)
    assert held.mirror_of is wu and np.array_equal(held.points, ws.points)
    with pytest.raises(model.ParameterError, match="unstable"):
        mf.grow_branch(saddle, stable=True, sign=-1, arclength=3.0, unstable=wu)
    skew = fpm.find_fixed_point(model.FIGURE4.with_(mu=MU, xi=0.01), H, (0.0, 0.0))
    assert not mf.mirrors(mf.saddle(skew.params, skew.h, skew))
    with pytest.raises(model.ParameterError, match="mirror_branch"):
        mf.mirror_branch(ws)


def test_branches_coincide_with_the_exact_separatrix_at_mu_0():
    prm = model.FIGURE4.with_(mu=0.0)
    fp = fpm.find_fixed_point(prm, H, (0.0, 0.0))
    sd = mf.saddle(fp.params, fp.h, fp)
    c = mk.check_params(prm, H)
    branches = [mf.grow_branch(sd, stable=s, sign=g, arclength=4.0) for s in (False, True) for g in (1, -1)]
    for b in branches:   # every point on the level F0 = c of R6/R7
        y = model.section_state(prm, b.points[:, 0], b.points[:, 1], H)
        assert np.max(np.abs(mk.F0(prm, y) - c)) < 1e-10
    # R7's orbits cross the section on the branches (no splitting: W^u = W^s)
    for sign in (1, -1):
        for g0 in (0.5, 2.0, 4.0):
            xc, _, _ = mk.separatrix_point(prm, H, g0, sign)
            assert min(b.distance(xc) for b in branches[:2]) < 1e-9
            assert min(b.distance(xc) for b in branches[2:]) < 1e-9


def test_a_longer_branch_continued_from_a_shorter_one_is_the_branch_grown_from_the_start(saddle, wu):
    """turnstile doubles a branch's length by continuing it: the same points, bit for bit, as a
    growth from the start, with only the new part computed; another setting or saddle starts over."""
    fresh = mf.grow_branch(saddle, sign=1, arclength=6.0)
    longer = mf.grow_branch(saddle, sign=1, arclength=6.0, resume=wu)
    assert wu.target == 3.0 and longer.status == fresh.status == "arclength"
    assert np.array_equal(longer.points.view(np.uint8), fresh.points.view(np.uint8))
    assert np.array_equal(longer.sigma, fresh.sigma) and longer.evaluations == fresh.evaluations
    other = mf.grow_branch(saddle, sign=1, arclength=6.0, start_tol=1e-8, resume=wu)   # another setting
    assert np.array_equal(other.points, mf.grow_branch(saddle, sign=1, arclength=6.0, start_tol=1e-8).points)


#: a branch maps at most this many points per point it keeps (those of its last generation past the cut)
EVALS_PER_POINT = 2


def test_a_branch_refines_only_up_to_its_cut_so_it_maps_about_the_points_it_keeps():
    """Points past the cut at ``arclength`` are dropped, so they are not refined (docs/manifolds.md): at
    mu = 1.5 the central saddle's last generation is stretched far past the page's arclength 4, and
    refining all of it took the whole point budget (20,000 images for about 400 points kept)."""
    prm = model.FIGURE4.with_(mu=1.5)
    for b in mf.manifolds(prm, 2.0, (0.0185, 0.0), arclength=4.0, kinds=("unstable",)):
        assert b.status == "arclength" and b.arclength >= 4.0
        assert b.evaluations <= EVALS_PER_POINT * len(b.points), (b.sign, b.evaluations, len(b.points))


def test_growth_stops_at_budgets_with_a_status(saddle):
    b = mf.grow_branch(saddle, arclength=50.0, max_points=60)
    assert b.status == "max_points" and len(b.points) <= 61
    b = mf.grow_branch(saddle, arclength=50.0, max_time=0.0)
    assert b.status == "max_time" and b.arclength < 50.0
    with pytest.raises(model.ParameterError, match="arclength"):
        mf.grow_branch(saddle, arclength=-1.0)


@pytest.mark.cpu_dependent
def test_growth_stops_where_points_have_no_return(saddle):
    """A time budget just above the saddle's return time: the branch ends at the first point
    that needs longer ("edge"), and every point kept has its image."""
    T = abs(saddle.smap(saddle.point, jacobian=False).time)
    short = mf.saddle(model.FIGURE4.with_(mu=MU), H, fpm.find_fixed_point(model.FIGURE4.with_(mu=MU), H, (0.0, 0.0)),
                      tmax=1.05 * T)
    b = mf.grow_branch(short, sign=1, arclength=20.0)
    assert b.status == "edge" and b.arclength < 20.0 and len(b.points) > 20
    assert np.all(np.isfinite(b.points))


def test_a_non_hyperbolic_orbit_is_refused():
    c, s = math.cos(0.3), math.sin(0.3)    # an elliptic monodromy (rotation by 0.3)
    J = np.array([[c, -s], [s, c]])
    fp = fpm.FixedPoint(points=np.zeros((1, 2)), period=1, jacobian=J, eigenvalues=np.linalg.eigvals(J), trace=2 * c,
                        det=1.0, return_times=np.array([6.0]), residual=0.0, iterations=0, symmetric=False,
                        map_jacobians=np.array([J]), params=model.FIGURE4.with_(mu=MU), h=H)
    with pytest.raises(model.ParameterError, match="not hyperbolic"):
        mf.saddle(fp.params, fp.h, fp)


@pytest.fixture(scope="module")
def tangle(saddle, wu):
    bu = mf.grow_branch(saddle, sign=1, arclength=6.0)
    bs = mf.grow_branch(saddle, stable=True, sign=1, arclength=6.0)
    return bu, bs, mf.homoclinic_points(bu, bs)


@pytest.mark.cpu_dependent
def test_primary_homoclinic_point_is_on_the_symmetry_line(saddle, tangle):
    bu, bs, hs = tangle
    assert hs
    for hp in hs:
        assert hp.residual < 1e-10
        assert bu.distance(hp.point) < 1e-10 and bs.distance(hp.point) < 1e-10
        # the reversor maps the tangle to itself: the mirror of an intersection is one
        assert any(np.linalg.norm(reversor(hp.point) - q.point) < 1e-9 for q in hs) or \
            abs(hp.point[1]) < 1e-10
    on_line = [hp for hp in hs if abs(hp.sigma_u - hp.sigma_s) < 1e-6]
    assert on_line and all(abs(hp.point[1]) < 1e-10 for hp in on_line)
    h0 = min(on_line, key=lambda hp: hp.sigma_u)
    # splitting angle: the tangents of W^u and W^s = G0 W^u at a point of p2 = 0 are mirror images
    t = (bu.at([h0.sigma_u + 1e-6])[0] - bu.at([h0.sigma_u - 1e-6])[0])
    mirror = 2 * math.atan(abs(t[1] / t[0]))
    assert h0.angle == pytest.approx(min(mirror, math.pi - mirror), abs=1e-6)
    orbit = mf.homoclinic_orbit(saddle.smap, h0.point, 6)
    assert np.linalg.norm(orbit[0] - saddle.point) < 1e-3 and np.linalg.norm(orbit[-1] - saddle.point) < 1e-3


def test_green_area_is_exact_on_polygons():
    assert tr.polygon_area([[0, 0], [1, 0], [0, 1]]) == pytest.approx(0.5, abs=1e-15)
    L_shape = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]
    assert tr.polygon_area(L_shape) == pytest.approx(3.0, abs=1e-15)
    assert tr.polygon_area(L_shape[::-1]) == pytest.approx(-3.0, abs=1e-15)


def test_green_area_of_an_ellipse_converges_and_its_error_estimate_holds():
    a, b = 2.0, 0.5
    exact = math.pi * a * b

    def ring(n):
        t = 2 * math.pi * np.arange(n) / n
        return np.column_stack([a * np.cos(t), b * np.sin(t)])

    errs = [abs(tr.polygon_area(ring(n)) - exact) for n in (16, 32, 64)]
    assert errs[0] / errs[1] == pytest.approx(4.0, rel=0.05) and errs[1] / errs[2] == pytest.approx(4.0, rel=0.05)
    area, err = tr.richardson_area(ring(32), ring(64))
    assert abs(area - exact) <= err and err < errs[2]


@pytest.mark.cpu_dependent
def test_turnstile_lobes_have_equal_areas_and_match_melnikov(saddle, tangle):
    """Flux = lobe area; at first order 2 lam mu |J| (docs/manifolds.md): within O(mu^2)."""
    bu, bs, hs = tangle
    lb = tr.lobes(bu, bs, points=hs)
    assert len(lb) == 2
    a1, a2 = lb
    assert a1.area * a2.area < 0                       # opposite orientation, one lobe each side
    assert abs(abs(a1.area) - abs(a2.area)) <= 3 * (a1.error + a2.error) + 1e-9
    prm0 = model.FIGURE4.with_(mu=0.0)
    A, B, _, _ = mk.fit_harmonics(prm0, mk.check_params(prm0, H), 1)
    predicted = 2.0 * prm0.lam * MU * math.hypot(A, B)
    assert abs(a1.area) / predicted == pytest.approx(1.0, abs=10 * MU ** 2)


@pytest.mark.cpu_dependent
def test_flux_curve_ratio_to_melnikov_tends_to_one(tangle):
    """At mu = 1e-3 (continued from mu = 0) the ratio is closer to 1 than at mu = 0.03."""
    (row,) = tr.flux_curve(model.FIGURE4, H, [1e-3])
    assert row["status"] == "ok"
    bu, bs, hs = tangle
    prm0 = model.FIGURE4.with_(mu=0.0)
    A, B, _, _ = mk.fit_harmonics(prm0, mk.check_params(prm0, H), 1)
    ratio_03 = abs(tr.lobes(bu, bs, points=hs)[0].area) / (2.0 * MU * math.hypot(A, B))
    assert abs(row["ratio"] - 1.0) < abs(ratio_03 - 1.0) < 1e-3
    assert abs(row["ratio"] - 1.0) < 1e-6
    on_line = max((p for p in hs if abs(p.point[1]) < 1e-9), key=lambda p: abs(p.point[0]))   # (1.788, 0)
    for mu, angle in ((row["mu"], row["angle"]), (MU, on_line.angle)):
        assert 0.0 < angle < 2.0 * mu   # the splitting angle at the primary point on p2 = 0 is O(mu)


@pytest.mark.cpu_dependent
@pytest.mark.parametrize("mu", [0.05, 0.1])
def test_mean_transit_time_is_accessible_area_over_flux(mu):
    """Meiss 1992: <min(T, N)> over the entry set = A(points of R leaving within N) / flux, within
    the sampling error; the entry set's Monte Carlo area is the lobe area."""
    fp = fpm.follow(model.FIGURE4, H, "mu", 0.0, mu, (0.0, 0.0))
    t = tr.turnstile(mf.saddle(fp.params, fp.h, fp), arclength=6.0)
    lb = t["lobes"]
    phi = abs(lb[0].area)
    h0 = min((lb[0].start, lb[0].end), key=lambda p: abs(p.point[1]))
    r = tr.exit_times(t["unstable"], t["stable"], h0, samples=1500, max_iter=100)
    assert r["entry"] > 50
    assert abs(r["flux_mc"] - phi) < 3 * r["flux_mc_sem"]
    expected = r["accessible_area"] / phi
    assert abs(r["mean"] - expected) < 3 * math.hypot(r["sem"], r["accessible_sem"] / phi)
    t_s, surv = r["survival"]
    assert np.all(np.diff(surv) <= 0) and surv[0] <= 1.0


def test_inside_follows_the_even_odd_rule():
    square = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], float)
    got = tr.inside(square, [[1, 1], [3, 1], [-0.5, 1], [1, 2.5], [np.nan, 1]])
    assert got.tolist() == [True, False, False, False, False]


@pytest.mark.parametrize("guess, maps", [((-1.8408, 0.0), 2), ((0.2909, 0.0), 4)])
def test_manifolds_of_a_period_2_orbit_are_mapped_onto_each_other(guess, maps):
    """Period 2 (trace 9.96, and -6.80: negative multipliers, so F = P^4 keeps each branch):
    P maps W^u at the orbit's first point onto W^u at its second."""
    from explorer.analysis.periodic import find_periodic_orbit

    orb = find_periodic_orbit(model.FIGURE4.with_(mu=MU), H, guess, 2)
    s0, s1 = mf.saddle(orb.params, orb.h, orb, index=0), mf.saddle(orb.params, orb.h, orb, index=1)
    assert s0.maps == s1.maps == maps
    assert s0.multiplier == pytest.approx(s1.multiplier, rel=1e-8)
    b0 = mf.grow_branch(s0, sign=1, arclength=0.3)
    b1 = [mf.grow_branch(s1, sign=s, arclength=2.0) for s in (1, -1)]
    for x in b0.points[3::15]:
        y = s0.smap(x, jacobian=False).point
        assert min(b.distance(y) for b in b1) < 1e-9


def test_stable_manifold_without_the_reversor_is_invariant():
    """xi != 0: no reversor, W^s by backward integration point by point; its forward images
    move down the branch by one generation, x(sigma) -> x(sigma - L)."""
    prm = model.FIGURE4.with_(mu=MU, xi=0.05)
    from explorer.model.symmetry import is_reversible

    assert not is_reversible(prm)
    sd = mf.saddle(prm, H, fpm.find_fixed_point(prm, H, (0.0, 0.0)))
    ws = mf.grow_branch(sd, stable=True, sign=1, arclength=0.6)
    assert ws.status == "arclength"
    L = math.log(sd.multiplier)
    for i in range(len(ws.points) - 1, len(ws.points) // 2, -23):
        y = sd.smap(ws.points[i], jacobian=False).point
        assert np.linalg.norm(y - ws.at([ws.sigma[i] - L])[0]) < 1e-9


@pytest.mark.cpu_dependent
def test_a_flux_needs_both_lobes_with_equal_areas(tangle):
    """At mu = 0.5 the flux is a pair of lobes of equal area: one lobe alone, or two of different
    areas, is refused with the reason."""
    bu, bs, hs = tangle
    lb = tr.lobes(bu, bs, points=hs)
    assert tr.turnstile_check(lb, 6.0) == "ok"
    assert tr.turnstile_check(lb[:1], 6.0).startswith("no pair of lobes")
    wrong = tr.Lobe(lb[1].start, lb[1].end, 5.7, 1e-6, lb[1].boundary)
    assert tr.turnstile_check([lb[0], wrong], 6.0).startswith("the two lobes differ")


def test_manifolds_of_a_point_are_those_of_the_orbit_newton_finds_from_it(saddle):
    """ex.manifolds(params, h, (p1, p2)): the orbit is found from the point first; its branches
    start at that orbit's point and coincide with the branches grown from the FixedPoint."""
    prm = model.FIGURE4.with_(mu=MU)
    got = mf.manifolds(prm, H, (0.05, 0.02), arclength=1.0, signs=(1,))
    assert [b.kind for b in got] == ["unstable", "stable"]
    assert np.linalg.norm(got[0].points[0] - saddle.point) < 1e-10
    ref = mf.grow_branch(saddle, sign=1, arclength=1.5)
    for x in got[0].points[5::20]:
        assert ref.distance(x) < 1e-9
    with pytest.raises(model.ParameterError, match="point"):
        mf.manifolds(prm, H, (0.0, 0.0, 0.0))
    with pytest.raises(model.ParameterError, match="h is missing"):
        mf.manifolds(prm, orbit=(0.0, 0.0))


@pytest.mark.cpu_dependent
def test_heteroclinic_points_lie_on_both_manifolds_and_go_from_one_saddle_to_the_other():
    """Period-2 saddle orbit x0 = (-1.84, 0), x1 = (-0.32, 0) (F = P^2): each point of W^u(x0) and
    W^s(x1) is within 1e-10 of both branches, its backward F-iterates approach x0 and its forward
    ones x1 (and not the other way round)."""
    from explorer.analysis.periodic import find_periodic_orbit

    orb = find_periodic_orbit(model.FIGURE4.with_(mu=MU), H, (-1.8408, 0.0), 2)
    s0, s1 = mf.saddle(orb.params, orb.h, orb, index=0), mf.saddle(orb.params, orb.h, orb, index=1)
    assert s0.maps == 2
    bu = mf.grow_branch(s0, sign=1, arclength=3.0, start_tol=1e-8)
    bs = mf.grow_branch(s1, stable=True, sign=-1, arclength=3.0, start_tol=1e-8)
    hs = mf.heteroclinic_points(bu, bs)
    assert len(hs) >= 2
    x0, x1 = orb.points
    for hp in hs:
        assert hp.residual < 1e-10
        assert bu.distance(hp.point) < 1e-10 and bs.distance(hp.point) < 1e-10
        fwd = s0.smap.iterate(hp.point, 2 * 5)[2::2]              # F^1 ... F^5 (F = P^2)
        back = s0.smap.iterate(hp.point, 2 * 5, backward=True)[2::2]
        d_fwd, d_back = np.linalg.norm(fwd - x1, axis=1), np.linalg.norm(back - x0, axis=1)
        assert d_fwd[-1] < 1e-3 and d_back[-1] < 1e-3
        assert np.all(np.diff(d_fwd[-3:]) < 0) and np.all(np.diff(d_back[-3:]) < 0)
        assert np.linalg.norm(fwd[-1] - x0) > 0.5 and np.linalg.norm(back[-1] - x1) > 0.5
    with pytest.raises(model.ParameterError, match="two different saddle points"):
        mf.heteroclinic_points(bu, mf.grow_branch(s0, stable=True, sign=1, arclength=0.5))


@pytest.mark.cpu_dependent
def test_flux_curve_stops_where_the_followed_point_is_not_a_saddle_and_says_why():
    """Followed from the left island's centre (elliptic): the first row says why there is no
    flux, the curve stops there (the next mu is not computed) and reports it as the destruction."""
    rows = tr.flux_curve(model.FIGURE4, H, [0.01, 0.02], guess=(-1.17, 0.0))
    assert len(rows) == 1 and rows[0]["flux"] is None and rows[0]["trace"] < 2.0
    assert rows[0]["reason"] == tr.REASON_NO_SADDLE and rows[0]["status"].startswith("elliptic")
    assert rows.destruction == 0.01 and rows.stop_reason == rows[0]["status"]
    assert rows.trace_two is None                   # no saddle before it to interpolate from


@pytest.mark.cpu_dependent
def test_a_turnstile_torn_by_the_section_edge_is_reported_with_the_eye_flux():
    """mu = 0.5: W^u of the central saddle reaches the section's edge, where the first return
    jumps (the orbit grazes phi = phi0 with M = 0): the branch is cut there, no pair of lobes has
    unbroken arcs and the row says so, with the eye's entry-set flux instead."""
    (row,) = tr.flux_curve(model.FIGURE4, H, [0.5], arclength=9.0, max_arclength=9.0, exit_samples=1500)
    assert row["reason"] == tr.REASON_TORN and row["status"].startswith("torn") and row["flux"] is None
    assert row["eye_flux"] > 5 * row["eye_error"] > 0
    fp = fpm.follow(model.FIGURE4, H, "mu", 0.0, 0.5, (0.0, 0.0))
    sd = mf.saddle(fp.params, fp.h, fp)
    bu = mf.grow_branch(sd, sign=1, arclength=9.0)
    st = bu.first_tear
    assert math.isfinite(st)
    k = int(np.searchsorted(bu.sigma, st))
    a, b = bu.points[k], bu.points[k + 1]
    assert np.linalg.norm(a - b) > 10 * mf.DEFAULT_MAX_GAP and bu.sigma[k + 1] - bu.sigma[k] <= 2 * mf.MIN_DSIGMA
    pa, pb = bu.at([bu.sigma[k] - bu.curve.L, bu.sigma[k + 1] - bu.curve.L])   # one map before: the same point
    assert np.linalg.norm(pa - pb) < 1e-8
    ta, tb = (abs(sd.smap(x, jacobian=False).time) for x in (pa, pb))
    assert abs(ta - tb) > 0.1                                    # ... whose return time jumps
    ms = model.section_M2(fp.params, np.array([a[0], b[0]]), np.array([a[1], b[1]]), H, math.pi)
    assert min(ms) < 1e-6                                        # one side lands on the section's edge


@pytest.mark.cpu_dependent
@pytest.mark.slow
def test_overlapping_lobes_are_not_the_flux_and_the_eye_flux_says_so():
    """mu = 0.3: the turnstile's arcs cross again between their ends, the two lobes still have
    equal signed areas but overlap, and the flux into the eye (Monte Carlo) differs from them
    (at mu = 0.05 and 0.1, simple turnstiles, it equals the lobe area:
    test_mean_transit_time_is_accessible_area_over_flux)."""
    (over,) = tr.flux_curve(model.FIGURE4, H, [0.3], arclength=12.0, max_arclength=12.0, exit_samples=2000)
    assert over["reason"] == tr.REASON_SECONDARY and over["flux"] is None
    a, b = over["lobes"]
    assert a["secondary"] > 0 and abs(a["area"] - b["area"]) < 1e-5
    assert abs(over["eye_flux"] - a["area"]) > 5 * over["eye_error"]


@pytest.mark.cpu_dependent
def test_flux_curve_stops_where_the_central_saddle_turns_elliptic_and_brackets_it():
    """Figure 4: the central saddle turns elliptic between mu = 2.9 (trace > 2) and 3 (trace < 2);
    the curve stops at 3 and interpolates the trace to 2 inside the bracket."""
    rows = tr.flux_curve(model.FIGURE4, H, [2.9, 3.0, 3.1], arclength=0.5, max_arclength=0.5, exit_samples=0)
    assert len(rows) == 2 and rows[0]["trace"] > 2.0 > rows[1]["trace"]
    assert rows[1]["reason"] == tr.REASON_NO_SADDLE and rows.destruction == 3.0
    assert 2.9 < rows.trace_two < 3.0
