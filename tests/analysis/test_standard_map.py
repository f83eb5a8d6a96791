"""Chirikov's standard map (explorer.analysis.maps.StandardMap) and the map protocol.

Independent checks: the map (S1) written out in numpy, the Jacobian against central finite
differences, det DT = 1 (area preservation), T^-1 T = id, the reversors I0, I1 are
involutions with R T R = T^-1 and T = I1 I0, and both the standard map and the section map
implement the protocol."""
import math

import numpy as np
import pytest

import explorer as ex
from explorer import model
from explorer.analysis.maps import AreaPreservingMap, StandardMap
from explorer.analysis.section_map import SectionMap

RNG = np.random.default_rng(35)
POINTS = np.column_stack([RNG.uniform(-7, 7, 40), RNG.uniform(-4, 4, 40)])
KS = (0.0, 0.3, 0.971635406, 2.5, -1.2)


def _by_hand(x, k):
    """(S1) p' = p + k sin(theta), theta' = theta + p' (docs/greene.md, Chirikov 1979 eq. 4.1)."""
    p = x[1] + k * math.sin(x[0])
    return np.array([x[0] + p, p])


@pytest.mark.parametrize("k", KS)
def test_the_map_is_s1_and_its_jacobian_has_determinant_one(k):
    m = StandardMap(k)
    for x in POINTS:
        r = m(x)
        np.testing.assert_allclose(r.point, _by_hand(x, k), rtol=0, atol=1e-14)
        h = 1e-6
        fd = np.column_stack([(_by_hand(x + h * e, k) - _by_hand(x - h * e, k)) / (2 * h) for e in np.eye(2)])
        np.testing.assert_allclose(r.jacobian, fd, rtol=0, atol=1e-8)
        assert abs(np.linalg.det(r.jacobian) - 1.0) < 1e-13        # area preservation
        assert r.time == 1.0


@pytest.mark.parametrize("k", KS)
def test_the_inverse_undoes_the_map_and_its_jacobian_is_the_inverse_matrix(k):
    m = StandardMap(k)
    for x in POINTS:
        y = m(x).point
        np.testing.assert_allclose(m.inverse(y), x, rtol=0, atol=1e-13)
        back = m(y, backward=True)
        np.testing.assert_allclose(back.jacobian @ m.jacobian(x), np.eye(2), atol=1e-12)
    orbit = m.iterate(POINTS[0], 12)   # short: at k = 2.5 round-off grows like exp(n)
    np.testing.assert_allclose(m.iterate(orbit[-1], 12, backward=True)[::-1], orbit, atol=1e-9)


@pytest.mark.parametrize("k", KS)
def test_the_reversors_are_involutions_that_reverse_the_map(k):
    m = StandardMap(k)
    T = lambda x: m(x, jacobian=False).point   # noqa: E731
    for R in m.reversors:
        np.testing.assert_allclose(R(R(POINTS)), POINTS, atol=1e-13)
        for x in POINTS:
            np.testing.assert_allclose(R(T(R(x))), m.inverse(x), atol=1e-12)     # R T R = T^-1
    for x in POINTS:
        np.testing.assert_allclose(m.i1(m.i0(x)), T(x), atol=1e-13)               # T = I1 I0


@pytest.mark.parametrize("k", (0.4, 1.3))
def test_the_symmetry_lines_are_the_reversors_fixed_sets(k):
    m = StandardMap(k)
    p = np.linspace(-3, 3, 13)
    for theta0 in m.I0_LINES:
        line = np.column_stack([np.full_like(p, theta0), p])
        assert np.allclose(StandardMap.wrap(m.i0(line)), StandardMap.wrap(line), atol=1e-13)
    line1 = np.column_stack([p / 2, p])
    np.testing.assert_allclose(m.i1(line1), line1, atol=1e-14)


def test_fixed_points_elliptic_at_pi_hyperbolic_at_zero():
    m = StandardMap(0.8)
    np.testing.assert_allclose(m(np.array([math.pi, 0.0])).point, [math.pi, 0.0], atol=1e-15)
    assert np.trace(m.jacobian([math.pi, 0.0])) == pytest.approx(2 - 0.8)    # elliptic: |tr| < 2
    assert np.trace(m.jacobian([0.0, 0.0])) == pytest.approx(2 + 0.8)        # hyperbolic


def test_standard_map_and_section_map_implement_the_protocol():
    m = ex.StandardMap(0.5)
    s = SectionMap(model.FIGURE4.with_(mu=0.5), 2.0)
    for obj in (m, s):
        assert isinstance(obj, AreaPreservingMap)
    assert m.with_parameter(0.7).parameter_value == 0.7 and m.parameter == "k"
    s2 = s.with_parameter(0.75)
    assert s2.parameter == "mu" and s2.parameter_value == 0.75 and s2.h == s.h and s.parameter_value == 0.5


def test_bad_points_and_parameters_raise_parameter_error():
    with pytest.raises(ex.ParameterError, match="k"):
        StandardMap(float("nan"))
    with pytest.raises(ex.ParameterError, match="theta, p"):
        StandardMap(1.0)([1.0, 2.0, 3.0])


def test_the_mirror_image_of_an_orbit_is_refused_naming_the_missing_linear_reversor():
    """The standard map's reversors I0, I1 are not linear: mirror_orbit, exact for a linear one, says so."""
    from explorer.analysis import periodic as pr

    orb = pr.find_periodic_orbit(StandardMap(1.2), (3.1, 0.1), 1)
    with pytest.raises(model.ParameterError, match="reflection"):
        pr.mirror_orbit(orb)
