"""A System's section map is an area-preserving map of the protocol (docs/systems.md, "The map
protocol"): its Jacobian against central differences of the map and the invariant area form of
the section, the inverse, the images, the parameters, the domain, pickling and the reversors."""
import pickle

import numpy as np
import pytest
from systems import henon_heiles, henon_heiles_without_reversor, px, py, x, y

import explorer as ex
from explorer.analysis.maps import AreaPreservingMap
from explorer.model import ParameterError

E = 1.0 / 8.0
# Hénon–Heiles' reversor (x, y, px, py) -> (-x, y, px, -py) (systems.HH_REVERSOR) keeps x = 0 and
# px > 0, inducing (y, py) -> (y, -py) on the section
POINTS = [(0.1, 0.1), (-0.2, 0.15), (0.35, -0.05), (0.0, 0.3)]


@pytest.fixture(scope="module")
def smap():
    return ex.SectionMap(henon_heiles(), E, section=x, direction=+1, coords=(y, py), solve=px)


def central_differences(m, x0, step=1e-6):
    J = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = step
        J[:, j] = (m(np.add(x0, e), jacobian=False).point - m(np.subtract(x0, e), jacobian=False).point) / (2 * step)
    return J


def test_the_map_answers_the_protocol(smap):
    assert isinstance(smap, AreaPreservingMap)
    assert smap.parameters == ("lam", "energy") and smap.parameter == "lam" and smap.parameter_value == 1.0
    assert smap.periods == (0.0, 0.0) and smap.orbit_fields() == {"system": smap}


def test_the_jacobian_agrees_with_central_differences_and_preserves_the_area_dy_dpy(smap):
    for p in POINTS:
        r = smap(p)
        assert np.max(np.abs(r.jacobian - central_differences(smap, p))) <= 1e-7
        assert abs(np.linalg.det(r.jacobian) - 1.0) <= 1e-10      # x = 0: the area form is dy ^ dpy
        assert np.max(np.abs(r.point - smap(p, jacobian=False).point)) <= 1e-13
        assert r.time > 0 and np.array_equal(r.point, r.state[[1, 3]]) and abs(r.state[0]) <= 1e-15 and r.state[2] > 0


def test_on_a_tilted_section_the_jacobian_preserves_the_restricted_symplectic_form():
    # on x = 0.1 - y with px from H: dx ^ dpx + dy ^ dpy = rho dy ^ dpy, rho = 1 - dpx/dpy = (px + py)/px,
    # so det DP(x) = rho(x) / rho(P(x)), which differs from 1.  The reversor does not map this section
    # to itself (it acts on no map here): the system is smap's, its generated code compiled once
    tilted = ex.SectionMap(henon_heiles(), E, section=x + y - 0.1, direction=-1, coords=(y, py), solve=px)

    def rho(s):
        return (s[2] + s[3]) / s[2]

    dets = []
    for p in [(0.05, 0.1), (0.2, -0.1)]:
        r = tilted(p)
        assert np.max(np.abs(r.jacobian - central_differences(tilted, p))) <= 1e-7
        assert abs(np.linalg.det(r.jacobian) * rho(r.state) / rho(tilted.state(p)) - 1.0) <= 1e-10
        dets.append(np.linalg.det(r.jacobian))
    assert max(abs(d - 1.0) for d in dets) > 1e-3


def test_the_inverse_undoes_the_map_and_its_jacobian_is_the_inverse_matrix(smap):
    for p in POINTS:
        fwd = smap(p)
        back = smap(fwd.point, backward=True)
        assert np.max(np.abs(back.point - p)) <= 1e-11
        assert np.max(np.abs(smap.inverse(smap(p, jacobian=False).point) - p)) <= 1e-11
        assert back.time == pytest.approx(-fwd.time, rel=1e-12)
        assert np.max(np.abs(back.jacobian @ fwd.jacobian - np.eye(2))) <= 1e-9


def test_iterate_and_images_agree_and_a_point_outside_has_nan_images(smap):
    it = smap.iterate(POINTS[0], 5)
    img = smap.images([POINTS[0], (0.1, 0.6), POINTS[1]], 5)
    assert np.max(np.abs(img[0] - it[1:])) == 0.0
    assert np.all(np.isnan(img[1])) and np.all(np.isfinite(img[2]))
    back = smap.images(it[-1:], 5, backward=True)[0]
    for k in range(5):    # preimage k + 1 of the last point is point 4 - k
        assert np.max(np.abs(back[k] - it[4 - k])) <= 1e-10
    assert smap.iterate(POINTS[0], 0).tolist() == [list(POINTS[0])]


def test_the_domain_is_where_the_energy_level_has_a_root_on_the_directions_branch(smap):
    assert smap.in_domain((0.1, 0.1)) and not smap.in_domain((0.1, 0.6)) and not smap.in_domain((np.nan, 0.0))
    assert "px" in smap.describe_domain() and "E = 0.125" in smap.describe_domain()
    with pytest.raises(ParameterError, match="no solution for px"):
        smap((0.1, 0.6))
    with pytest.raises(ParameterError, match="two finite numbers"):
        smap((0.1, 0.2, 0.3))


def grid(a0, a1, b0, b1, n=31):
    return np.stack(np.meshgrid(np.linspace(a0, a1, n), np.linspace(b0, b1, n), indexing="ij"), axis=-1)


def test_allowed_is_in_domain_point_by_point_and_on_x_0_the_region_where_h_is_below_e(smap):
    G = grid(-1.0, 2.0, -0.7, 0.7)
    mask = smap.allowed(G)
    assert mask.shape == G.shape[:2] and mask.dtype == bool and 0 < mask.sum() < mask.size
    assert mask.tolist() == [[smap.in_domain(p) for p in row] for row in G]
    Y, P = G[..., 0], G[..., 1]
    H = P**2 / 2 + Y**2 / 2 - Y**3 / 3                     # H(0, y, 0, py) at lam = 1
    clear = np.abs(H - E) > 1e-12
    assert np.array_equal(mask[clear], (H < E)[clear])
    # on the boundary the root is px = 0: the flow is tangent to the section, not allowed
    edge = [(0.0, 0.5), (0.0, -0.5)]
    assert not smap.allowed(edge).any() and not any(smap.in_domain(p) for p in edge)
    assert smap.allowed([[np.nan, 0.0], [0.1, np.inf], [0.1, 0.1]]).tolist() == [False, False, True]
    with pytest.raises(ParameterError, match="pairs"):
        smap.allowed([0.1, 0.2, 0.3])


def test_on_a_tilted_section_allowed_is_in_domain_point_by_point():
    tilted = ex.SectionMap(henon_heiles(), E, section=x + y - 0.1, direction=-1, coords=(y, py), solve=px)
    G = grid(-0.8, 1.0, -0.7, 0.7)
    mask = tilted.allowed(G)
    assert 0 < mask.sum() < mask.size
    assert mask.tolist() == [[tilted.in_domain(p) for p in row] for row in G]
    tilted.states(G[mask])                                  # every allowed point lifts
    # on x = 0.1 - y: px = +-sqrt(D), D = 2 (E - V(0.1 - y, y)) - py^2, crossed with px + py < 0
    Y, P = G[..., 0], G[..., 1]
    X = 0.1 - Y
    D = 2 * (E - (X**2 + Y**2) / 2 - X**2 * Y + Y**3 / 3) - P**2
    r = np.sqrt(np.maximum(D, 0.0))
    clear = (np.abs(D) > 1e-12) & ((D < 0) | (np.abs(P - r) > 1e-12))
    assert np.array_equal(mask[clear], ((D > 0) & (P < r))[clear]) and clear.mean() > 0.99


def test_with_value_sets_a_parameter_or_the_energy_level(smap):
    low = smap.with_value("energy", 1.0 / 12.0)
    half = smap.with_parameter(0.5)
    assert low.energy_value == 1.0 / 12.0 and low.system is smap.system and low.tol == smap.tol
    assert half.parameter_value == 0.5 and half.energy_value == E and smap.parameter_value == 1.0
    s = half.state((0.1, 0.1))
    H = (s[2]**2 + s[3]**2)/2 + (s[0]**2 + s[1]**2)/2 + 0.5*(s[0]**2*s[1] - s[1]**3/3)
    assert abs(H - E) <= 1e-15
    with pytest.raises(ParameterError, match="no parameter 'mu'.*lam, energy"):
        smap.with_value("mu", 1.0)


def test_the_map_pickles_and_maps_the_same_after_a_round_trip(smap):
    back = pickle.loads(pickle.dumps(smap))
    assert type(back) is type(smap) and back.energy_value == E and back.coords == smap.coords
    a, b = smap(POINTS[0]), back(POINTS[0])
    assert np.array_equal(a.point, b.point) and np.array_equal(a.jacobian, b.jacobian)
    assert len(back.reversors) == 1


def test_the_declared_reversor_induces_an_involution_that_conjugates_the_map_to_its_inverse(smap):
    (R,) = smap.reversors
    assert np.array_equal(smap.reflection.M, R.M)
    for p in POINTS:
        assert np.array_equal(R(p), [p[0], -p[1]])
        # R P R P (x) = x
        assert np.max(np.abs(R(smap(R(smap(p, jacobian=False).point), jacobian=False).point) - p)) <= 1e-11
    line = smap.symmetry_line_points(5)
    assert line.shape == (5, 2) and np.all(line[:, 1] == 0.0) and all(smap.in_domain(p) for p in line)


def test_a_reversor_that_flips_the_direction_does_not_act_on_the_map_and_what_needs_one_says_so():
    time_reversal = {x: x, y: y, px: -px, py: -py}       # a reversor of the flow: px > 0 becomes px < 0
    hh = henon_heiles()
    flipped = ex.SectionMap(ex.System(dict(zip(hh.states, hh.rhs)), parameters=dict(hh.parameters), energy=hh.energy,
                                      name=hh.name, reversor=time_reversal),
                            E, section=x, direction=+1, coords=(y, py), solve=px)
    assert flipped.reversors == () and flipped.reflection is None
    with pytest.raises(ParameterError, match="Greene needs a reversor of the map: henon_heiles has no reversor "
                                             "that maps the section x = 0, crossed with direction \\+1"):
        flipped.require_reversor("Greene")
    bare = ex.SectionMap(henon_heiles_without_reversor(), E, section=x, direction=+1, coords=(y, py), solve=px)
    with pytest.raises(ParameterError, match="henon_heiles declares no reversor"):
        bare.require_reversor("Greene")


def test_an_analysis_of_a_map_refuses_a_bare_system_naming_the_section_map():
    with pytest.raises(ParameterError, match="find_fixed_point takes a map: give the System's section map"):
        ex.find_fixed_point(henon_heiles(), (0.1, 0.0))
