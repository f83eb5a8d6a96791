"""One rule for the system argument: every analysis takes the system first, a SectionMap or
(params, h), and gives the same numbers either way; a setting of the map given beside it is
refused; counts and times after the points are keyword-only; the older call forms still work,
with a DeprecationWarning, and give the same numbers."""
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
    with pytest.warns(DeprecationWarning, match="return_time"):
        assert new.period_time == new.return_time
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


def test_saddles_and_manifolds_are_the_same_from_a_section_map_and_from_the_older_orbit_first_forms():
    smap = SectionMap(PRM, H)
    fp = fpm.find_fixed_point(smap, (0.0, 0.0))
    new = mf.saddle(smap, fp)
    for old_args in ((fp,), (fp, smap), (fp, PRM, H)):
        with pytest.warns(DeprecationWarning, match=r"saddle\(system, orbit"):
            old = mf.saddle(*old_args)
        same(new.point, old.point)
        same(new.e_unstable, old.e_unstable)
        assert new.multiplier == old.multiplier
        assert (new.smap.tol, new.smap.h, new.smap.phi0) == (old.smap.tol, old.smap.h, old.smap.phi0)
    same(mf.saddle(PRM, H, fp).e_stable, new.e_stable)
    new_b = mf.manifolds(smap, fp, arclength=0.2, kinds=("unstable",), signs=(1,))[0]
    with pytest.warns(DeprecationWarning, match="manifolds"):
        old_b = mf.manifolds(fp, arclength=0.2, kinds=("unstable",), signs=(1,))[0]
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


def test_the_older_indicator_forms_warn_and_give_the_same_numbers():
    states = model.section_state(PRM, [-0.2], [0.1], H)
    ref = lyapunov.indicators(PRM, states=states, tmax=20.0)
    with pytest.warns(DeprecationWarning, match="tmax"):
        old = lyapunov.indicators(PRM, states=states, T=20.0)
    same(old.megno, ref.megno)
    with pytest.warns(DeprecationWarning, match="tmax"), \
            pytest.warns(DeprecationWarning, match="with the states by position is deprecated"):
        old = lyapunov.indicators(PRM, states, 20.0)
    same(old.megno, ref.megno)


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


#: what every call of the (p1, p2) forms says: they go in the next release (docs/api.md)
GOING = r"section_crossings\(system, p1, p2, \.\.\.\) is deprecated and will be removed"


def test_section_crossings_from_a_section_map_are_those_of_the_params_h_forms_and_the_maps_iterates(smap):
    p1, p2 = [-0.2, 0.3], [0.1, 0.0]
    with pytest.warns(DeprecationWarning, match=GOING):
        new = sections.section_crossings(smap, p1, p2, n_crossings=4)
        pair = sections.section_crossings(PRM, H, p1, p2, n_crossings=4, phi0=PHI0, tol=TOL)
        named = sections.section_crossings(PRM, p1, p2, h=H, n_crossings=4, phi0=PHI0, tol=TOL)
        with pytest.warns(DeprecationWarning, match=r"section_crossings\(params, p1, p2, h, n_crossings\)"):
            old = sections.section_crossings(PRM, p1, p2, H, 4, phi0=PHI0, tol=TOL, method="taylor")
        with pytest.warns(DeprecationWarning, match="given by position"):
            positional = sections.section_crossings(smap, p1, p2, 4)
    for res in (pair, named, old, positional):
        same(new.data, res.data)
        same(new.status, res.status)
        assert new.settings == res.settings
    with pytest.warns(DeprecationWarning, match="iter_" + GOING):
        blocks = list(sections.iter_section_crossings(smap, p1, p2, n_crossings=4, block=2))
    same(np.concatenate([b.rows(0) for b in blocks]), new.orbit(0))
    with pytest.warns(DeprecationWarning):
        old_blocks = list(sections.iter_section_crossings(PRM, p1, p2, H, 4, block=2, phi0=PHI0, tol=TOL))
    same(np.concatenate([b.rows(0) for b in old_blocks]), new.orbit(0))
    # the rows are P's iterates: the same section, energy and tolerance as the map's own steps
    it = smap.iterate((p1[0], p2[0]), 4)[1:]
    np.testing.assert_allclose(new.orbit(0)[:, 1:3], it, rtol=0, atol=1e-9)


def test_the_params_h_form_of_section_crossings_defaults_to_the_crossings_tolerance():
    """(params, h) builds the map at the default of crossings (DEFAULT_TOL), not the map's own:
    one default per purpose (docs/api.md)."""
    with pytest.warns(DeprecationWarning, match=GOING):
        res = sections.section_crossings(PRM, H, [0.1], [0.0], n_crossings=2)
    assert res.settings["tol"] == sections.DEFAULT_TOL != SectionMap.__init__.__kwdefaults__["tol"]


def test_section_crossings_refuse_a_setting_of_the_map_beside_it(smap):
    for kw in (dict(tol=1e-12), dict(phi0=0.0), dict(h=H)):
        with pytest.raises(model.ParameterError, match="belong"):
            sections.section_crossings(smap, [0.0], [0.0], n_crossings=3, **kw)
    with pytest.raises(model.ParameterError, match="return budget"):
        sections.section_crossings(SectionMap(PRM, H, tmax=10.0), [0.0], [0.0], n_crossings=3)
    with pytest.raises(TypeError, match="n_crossings"):
        sections.section_crossings(PRM, H, [0.0], [0.0])
    with pytest.raises(model.ParameterError, match="h is missing"):
        fpm.find_fixed_point(PRM)


def test_crossings_take_the_count_by_keyword_and_warn_when_given_by_position():
    y0 = model.section_state(PRM, [0.1], [0.0], H)
    ref = sections.crossings(PRM, states=y0, n_crossings=3)
    with pytest.warns(DeprecationWarning, match="n_crossings="), \
            pytest.warns(DeprecationWarning, match="with the states by position is deprecated"):
        old = sections.crossings(PRM, y0, 3)
    same(old.data, ref.data)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sections.crossings(PRM, states=y0, n_crossings=1)


@pytest.mark.parametrize("name", ["crossings", "iter_crossings", "propagate", "indicators"])
def test_the_flows_states_are_a_keyword_and_the_older_positional_form_warns_with_the_same_numbers(name):
    """After params the next positional is always h: the flow's full states are only ever
    ``states=`` (docs/api.md, "The system argument"); ``f(params, states)`` still works, warned."""
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
    with pytest.warns(DeprecationWarning, match=r"states=states"):
        old = numbers(fn(PRM, y0, **kw))
    same(old, new)
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


def test_a_deprecation_warning_names_the_callers_line():
    with pytest.warns(DeprecationWarning) as rec:
        sections.section_crossings(PRM, [0.1], [0.0], H, 2)
    assert {r.filename for r in rec} == {__file__}


def test_a_fixed_point_is_the_periodic_orbit_of_period_one_and_a_branch_of_them_a_periodic_branch(smap):
    """One type each: find_fixed_point gives the PeriodicOrbit find_periodic_orbit finds with
    K = 1 (every field equal), with the point's shorthands; a branch's members are its
    ``orbits`` (``points`` warns)."""
    fp = fpm.find_fixed_point(smap, (0.0, 0.0))
    orb = pm.find_periodic_orbit(smap, (0.0, 0.0), 1)
    assert isinstance(fp, pm.PeriodicOrbit) and fp.period == 1
    same(fp.points, orb.points)
    same(fp.map_jacobians, orb.map_jacobians)
    assert fp.return_time == orb.return_times[0] and fp.point is not None
    same(fp.point, orb.points[0])
    br = fpm.continue_branch(smap, "mu", 0.03, 0.04, 0.01, fp.point)
    assert isinstance(br, pm.PeriodicBranch) and all(isinstance(o, fpm.FixedPoint) for o in br.orbits)
    with pytest.warns(DeprecationWarning, match="orbits"):
        assert br.points == br.orbits
