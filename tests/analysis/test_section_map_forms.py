"""One argument order: every analysis of the section map takes the system first, a SectionMap
or (params, h), and gives the same numbers either way; a setting of the map given beside it is
refused."""
import math

import numpy as np
import pytest

from explorer import model
from explorer.analysis import fixedpoints as fpm
from explorer.analysis import halfturn, lyapunov, sections
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
    assert new.period_time == old.period_time
    new_b = fpm.continue_branch(smap, "mu", 0.03, 0.05, 0.01, (0.0, 0.0))
    old_b = fpm.continue_branch(PRM, H, "mu", 0.03, 0.05, 0.01, (0.0, 0.0), phi0=PHI0, tol=TOL)
    assert len(new_b.points) == len(old_b.points) >= 2
    for a, b in zip(new_b.points, old_b.points):
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
    same(pm.symmetry_line_points(smap, 2, 8), pm.symmetry_line_points(PRM, H, 2, 8, phi0=PHI0, tol=TOL))


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


def test_saddles_and_manifolds_are_the_same_from_a_section_map():
    smap = SectionMap(PRM, H)
    fp = fpm.find_fixed_point(smap, (0.0, 0.0))
    old = mf.saddle(fp)
    for new in (mf.saddle(smap, fp), mf.saddle(fp, smap)):
        same(new.point, old.point)
        same(new.e_unstable, old.e_unstable)
        assert new.multiplier == old.multiplier
        assert (new.smap.tol, new.smap.h, new.smap.phi0) == (old.smap.tol, old.smap.h, old.smap.phi0)
    new_b = mf.manifolds(smap, fp, arclength=0.2, kinds=("unstable",), signs=(1,))[0]
    old_b = mf.manifolds(fp, arclength=0.2, kinds=("unstable",), signs=(1,))[0]
    same(new_b.points, old_b.points)


def test_indicators_from_a_section_map_use_its_method_and_tolerance_unless_given(smap):
    pts = np.array([[-0.2, 0.1], [0.3, 0.0]])
    states = model.section_state(PRM, pts[:, 0], pts[:, 1], H, PHI0)
    new = lyapunov.indicators(smap, pts, 20.0)
    old = lyapunov.indicators(PRM, states, 20.0, tol=smap.tol)
    assert new.settings == old.settings and new.settings["tol"] == smap.tol
    assert new.method == smap.method
    for name in lyapunov.DEFAULT_INDICATORS:
        same(getattr(new, name), getattr(old, name))
    # a tolerance given explicitly is the indicators' own, as in the (params, states) form
    own = lyapunov.indicators(smap, pts, 20.0, tol=1e-10)
    same(own.megno, lyapunov.indicators(PRM, states, 20.0, tol=1e-10).megno)
    assert own.settings["tol"] == 1e-10
    one = lyapunov.indicators(smap, (-0.2, 0.1), 20.0)
    same(one.megno, new.megno[:1])
    with pytest.raises(model.ParameterError, match=r"\(p1, p2\) pairs"):
        lyapunov.indicators(smap, np.zeros((2, 5)), 20.0)


def test_a_setting_of_the_map_beside_it_is_refused(smap):
    with pytest.raises(model.ParameterError, match="belong"):
        fpm.find_fixed_point(smap, (0.0, 0.0), tol=1e-12)
    with pytest.raises(model.ParameterError, match="return budget"):
        fpm.find_fixed_point(SectionMap(PRM, H, tmax=10.0), (0.0, 0.0))


def test_section_crossings_from_a_section_map_are_those_of_the_older_form_and_the_maps_iterates(smap):
    p1, p2 = [-0.2, 0.3], [0.1, 0.0]
    new = sections.section_crossings(smap, p1, p2, 4)
    old = sections.section_crossings(PRM, p1, p2, H, 4, phi0=PHI0, tol=TOL, method="taylor")
    named = sections.section_crossings(PRM, p1, p2, h=H, n_crossings=4, phi0=PHI0, tol=TOL)
    for res in (old, named):
        same(new.data, res.data)
        same(new.status, res.status)
    assert new.settings == old.settings
    blocks = list(sections.iter_section_crossings(smap, p1, p2, 4, block=2))
    same(np.concatenate([b.rows(0) for b in blocks]), new.orbit(0))
    # the rows are P's iterates: the same section, energy and tolerance as the map's own steps
    it = smap.iterate((p1[0], p2[0]), 4)[1:]
    np.testing.assert_allclose(new.orbit(0)[:, 1:3], it, rtol=0, atol=1e-9)


def test_section_crossings_refuse_a_setting_of_the_map_beside_it(smap):
    for kw in (dict(tol=1e-12), dict(phi0=0.0), dict(method="dop853"), dict(direction=-1)):
        with pytest.raises(model.ParameterError, match="belong"):
            sections.section_crossings(smap, [0.0], [0.0], 3, **kw)
    with pytest.raises(model.ParameterError, match="belong"):
        sections.section_crossings(smap, [0.0], [0.0], h=H, n_crossings=3)
    with pytest.raises(model.ParameterError, match="return budget"):
        sections.section_crossings(SectionMap(PRM, H, tmax=10.0), [0.0], [0.0], 3)
    with pytest.raises(model.ParameterError, match="n_crossings is missing"):
        sections.section_crossings(PRM, [0.0], [0.0], H)
