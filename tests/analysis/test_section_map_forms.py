"""One rule for the system argument: every analysis takes the system first, a SectionMap or
(params, h), and gives the same numbers either way; a setting of the map given beside it is
refused; counts and times after the points are keyword-only."""
import inspect
import math
import warnings

import numpy as np
import pytest

from explorer import model
from explorer.analysis import fixedpoints as fpm
from explorer.analysis import halfturn, lyapunov, section_map, sections
from explorer.analysis import manifolds as mf
from explorer.analysis import periodic as pm
from explorer.analysis import rotation as rm
from explorer.analysis.section_map import SectionMap

PRM = model.FIGURE4.with_(mu=0.03)   # the Figure 4 scene at mu = 0.03 (docs/model.md R9)
H = 2.0
TOL = 1e-14                          # not the default: the map's tolerance must be the one used
PHI0 = math.pi


@pytest.fixture(scope="module")
def smap():
    return SectionMap(PRM, H, phi0=PHI0, tol=TOL)


def same(a, b):
    np.testing.assert_array_equal(np.asarray(a, float), np.asarray(b, float))


def test_fixed_points_and_their_continuation_are_the_same_from_a_section_map(smap):
    new = fpm.find_fixed_point(smap, (0.0, 0.0))
    old = fpm.find_fixed_point(PRM, H, (0.0, 0.0), phi0=PHI0, tol=TOL)
    same(new.point, old.point)
    same(new.jacobian, old.jacobian)
    assert new.return_time == old.return_time
    new_b = fpm.continue_branch(smap, "mu", 0.03, 0.05, 0.01, (0.0, 0.0))
    old_b = fpm.continue_branch(PRM, H, "mu", 0.03, 0.05, 0.01, (0.0, 0.0), phi0=PHI0, tol=TOL)
    assert len(new_b.orbits) == len(old_b.orbits) >= 2
    for a, b in zip(new_b.orbits, old_b.orbits):
        same(a.point, b.point)


def test_periodic_orbits_and_their_continuation_are_the_same_from_a_section_map(smap):
    guess = (1.013197, 0.0)
    new = pm.find_periodic_orbit(smap, guess, 6)
    old = pm.find_periodic_orbit(PRM, H, guess, 6, phi0=PHI0, tol=TOL)
    same(new.points, old.points)
    same(new.map_jacobians, old.map_jacobians)
    new_c = pm.continue_periodic(smap, 6, "mu", 0.03, 0.035, 0.005, new.points)
    old_c = pm.continue_periodic(PRM, H, 6, "mu", 0.03, 0.035, 0.005, old.points, phi0=PHI0, tol=TOL)
    assert len(new_c.orbits) == len(old_c.orbits) >= 1
    same(new_c.traces, old_c.traces)
    same(pm.symmetry_line_points(smap, 2, n=8), pm.symmetry_line_points(PRM, H, 2, n=8, phi0=PHI0, tol=TOL))


def test_rotation_numbers_are_the_same_from_a_section_map(smap):
    kw = dict(center=(math.sqrt(2.0), 0.0), iterates=200)
    new = rm.rotation_number(smap, (1.2, 0.0), **kw)
    old = rm.rotation_number(PRM, H, (1.2, 0.0), phi0=PHI0, tol=TOL, **kw)
    assert new.value == old.value or (math.isnan(new.value) and math.isnan(old.value))


def test_half_turn_partners_are_the_same_from_a_section_map(smap):
    pts = np.array([[0.3, 0.0], [-0.2, 0.1]])
    new = halfturn.partner_points(smap, pts)
    old = halfturn.partner_points(PRM, H, pts, phi0=PHI0, tol=TOL)
    same(new.points, old.points)
    same(new.times, old.times)
    assert np.isfinite(new.points).all()


def test_saddles_and_manifolds_are_the_same_from_a_section_map_and_from_params_h():
    smap = SectionMap(PRM, H)
    fp = fpm.find_fixed_point(smap, (0.0, 0.0))
    new = mf.saddle(smap, fp)
    old = mf.saddle(PRM, H, fp)
    same(new.point, old.point)
    same(new.e_unstable, old.e_unstable)
    same(new.e_stable, old.e_stable)
    assert new.multiplier == old.multiplier
    assert (new.smap.tol, new.smap.h, new.smap.phi0) == (old.smap.tol, old.smap.h, old.smap.phi0)
    new_b = mf.manifolds(smap, fp, arclength=0.2, kinds=("unstable",), signs=(1,))[0]
    old_b = mf.manifolds(PRM, H, fp, arclength=0.2, kinds=("unstable",), signs=(1,))[0]
    same(new_b.points, old_b.points)
    # the options of grow_branch are manifolds' own keywords (visible, no **kw)
    assert "max_points" in inspect.signature(mf.manifolds).parameters
    with pytest.raises(TypeError):
        mf.manifolds(smap, fp, arclength=0.2, no_such_option=1)


def test_indicators_from_a_map_use_its_tolerance_and_refuse_one_beside_it(smap):
    pts = np.array([[-0.2, 0.1], [0.3, 0.0]])
    states = model.section_state(PRM, pts[:, 0], pts[:, 1], H, PHI0)
    new = lyapunov.indicators(smap, pts, tmax=20.0)
    old = lyapunov.indicators(PRM, states=states, tmax=20.0, tol=smap.tol)
    pair = lyapunov.indicators(PRM, H, pts, tmax=20.0, tol=TOL, phi0=PHI0)
    for res in (old, pair):
        assert new.settings == res.settings and res.settings["tol"] == smap.tol
        for name in lyapunov.DEFAULT_INDICATORS:
            same(getattr(new, name), getattr(res, name))
    assert new.method == smap.method
    # the method is the function's own choice of integrator, beside the map too
    assert lyapunov.indicators(smap, pts, tmax=20.0, method="dop853").method == "dop853"
    with pytest.raises(model.ParameterError, match="belong"):
        lyapunov.indicators(smap, pts, tmax=20.0, tol=1e-10)
    one = lyapunov.indicators(smap, (-0.2, 0.1), tmax=20.0)
    same(one.megno, new.megno[:1])
    with pytest.raises(model.ParameterError, match=r"\(p1, p2\) pairs"):
        lyapunov.indicators(smap, np.zeros((2, 5)), tmax=20.0)


def test_a_setting_of_the_map_beside_it_is_refused(smap):
    with pytest.raises(model.ParameterError, match="belong"):
        fpm.find_fixed_point(smap, (0.0, 0.0), tol=1e-12)
    with pytest.raises(model.ParameterError, match="belong"):
        fpm.find_fixed_point(smap, (0.0, 0.0), h=2.0)
    # the map's return budget is the one the analyses of the map use
    short = SectionMap(PRM, H, tmax=1e-3)
    with pytest.raises(model.ParameterError, match="no periodic orbit"):
        fpm.find_fixed_point(short, (0.0, 0.0))
    # an analysis with a time budget of its own refuses a map whose return budget would be ignored
    with pytest.raises(model.ParameterError, match="return budget"):
        pm.search_periodic_orbits(SectionMap(PRM, H, tmax=10.0), 1)


def test_crossings_from_a_section_map_are_those_of_the_params_h_forms_and_the_maps_iterates(smap):
    pts = np.array([[-0.2, 0.1], [0.3, 0.0]])
    new = sections.crossings(smap, pts, n_crossings=4)
    pair = sections.crossings(PRM, H, pts, n_crossings=4, phi0=PHI0, tol=TOL)
    named = sections.crossings(PRM, pts, h=H, n_crossings=4, phi0=PHI0, tol=TOL)
    for res in (pair, named):
        same(new.data, res.data)
        same(new.status, res.status)
        assert new.settings == res.settings
    blocks = list(sections.iter_crossings(smap, pts, n_crossings=4, block=2))
    same(np.concatenate([b.rows(0) for b in blocks if 0 in b.index]), new.orbit(0))
    # the rows are P's iterates: the same section, energy and tolerance as the map's own steps
    it = smap.iterate(pts[0], 4)[1:]
    np.testing.assert_allclose(new.orbit(0)[:, 1:3], it, rtol=0, atol=1e-9)


def test_the_params_h_form_of_crossings_defaults_to_the_crossings_tolerance():
    """(params, h) builds the map at the default of crossings (DEFAULT_TOL), not the map's own:
    one default per purpose (docs/api.md)."""
    res = sections.crossings(PRM, H, [(0.1, 0.0)], n_crossings=2)
    assert res.settings["tol"] == sections.DEFAULT_TOL != SectionMap.__init__.__kwdefaults__["tol"]


def test_crossings_refuse_a_setting_of_the_map_beside_it(smap):
    for kw in (dict(tol=1e-12), dict(phi0=0.0), dict(h=H)):
        with pytest.raises(model.ParameterError, match="belong"):
            sections.crossings(smap, [(0.0, 0.0)], n_crossings=3, **kw)
    with pytest.raises(model.ParameterError, match="return budget"):
        sections.crossings(SectionMap(PRM, H, tmax=10.0), [(0.0, 0.0)], n_crossings=3)
    with pytest.raises(TypeError, match="n_crossings"):
        sections.crossings(PRM, H, [(0.0, 0.0)])
    with pytest.raises(model.ParameterError, match="h is missing"):
        fpm.find_fixed_point(PRM)


def test_counts_and_times_after_the_points_are_keyword_only(smap):
    y0 = model.section_state(PRM, [0.1], [0.0], H)
    with pytest.raises(TypeError):
        sections.crossings(PRM, H, [(0.1, 0.0)], 3)
    with pytest.raises(TypeError):
        lyapunov.indicators(smap, [(0.1, 0.0)], 20.0)
    with pytest.raises(TypeError):
        lyapunov.indicators(PRM, states=y0, T=20.0)
    with pytest.raises(TypeError):
        pm.symmetry_line_points(smap, 2, 8)


@pytest.mark.parametrize("name", ["crossings", "iter_crossings", "propagate", "indicators"])
def test_the_flows_states_are_a_keyword_and_states_by_position_are_refused_by_name(name):
    """After params the next positional is always h: the flow's full states are only ever
    ``states=`` (docs/api.md, "The system argument"); ``f(params, states)`` is refused, naming
    ``states=``."""
    fn = {"crossings": sections.crossings, "iter_crossings": sections.iter_crossings,
          "propagate": sections.propagate, "indicators": lyapunov.indicators}[name]
    kw = {"crossings": {"n_crossings": 2}, "iter_crossings": {"n_crossings": 2}, "propagate": {"t": 3.0},
          "indicators": {"tmax": 5.0}}[name]
    y0 = model.section_state(PRM, [0.1, -0.2], [0.0, 0.1], H)

    def numbers(res):
        res = list(res)[-1] if name == "iter_crossings" else res
        return res if name == "propagate" else (res.megno if name == "indicators" else res.data)

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        new = numbers(fn(PRM, states=y0, **kw))
    assert np.all(np.isfinite(new))
    with pytest.raises(model.ParameterError, match="states="):
        numbers(fn(PRM, y0, **kw))
    # the energy next to params makes a map; states= beside a map, or beside h, is refused by name
    with pytest.raises(model.ParameterError, match="states"):
        fn(section_map.SectionMap(PRM, H), states=y0, **kw)
    with pytest.raises(model.ParameterError, match="states"):
        fn(PRM, H, states=y0, **kw)
    assert "states" in inspect.signature(fn).parameters


def test_any_other_map_object_passes_through_the_rule_unchanged():
    """A map that is not a SectionMap (the map protocol of Greene's issue) reaches the analysis
    as it is, its own settings untouched."""
    seen = []

    @section_map.system_first
    def analysis(system, point, *, n=1):
        seen.append(system)
        return point

    class OtherMap:
        pass

    m = OtherMap()
    assert analysis(m, (0.1, 0.2), n=3) == (0.1, 0.2) and seen[-1] is m
    analysis(PRM, H, (0.0, 0.0), tol=1e-13)
    assert isinstance(seen[-1], SectionMap) and seen[-1].tol == 1e-13 and seen[-1].h == H


def test_a_fixed_point_is_the_periodic_orbit_of_period_one_and_a_branch_of_them_a_periodic_branch(smap):
    """One type each: find_fixed_point gives the PeriodicOrbit find_periodic_orbit finds with
    K = 1 (every field equal), with the point's shorthands; a branch's members are its
    ``orbits``."""
    fp = fpm.find_fixed_point(smap, (0.0, 0.0))
    orb = pm.find_periodic_orbit(smap, (0.0, 0.0), 1)
    assert isinstance(fp, pm.PeriodicOrbit) and fp.period == 1
    same(fp.points, orb.points)
    same(fp.map_jacobians, orb.map_jacobians)
    assert fp.return_time == orb.return_times[0] and fp.point is not None
    same(fp.point, orb.points[0])
    br = fpm.continue_branch(smap, "mu", 0.03, 0.04, 0.01, fp.point)
    assert isinstance(br, pm.PeriodicBranch) and all(isinstance(o, fpm.FixedPoint) for o in br.orbits)
