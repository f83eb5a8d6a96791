"""Fixed and periodic points, rotation numbers and manifolds of a System's section map
(docs/systems.md, "The map analyses"): Hénon–Heiles at E = 1/8 (lam = 1) on x = 0, px > 0, in
(y, py).  The periodic orbits are checked against scipy's DOP853 (they close after their return
time), their residues against central differences of the map, the rotation numbers against the
linear rotation number of the elliptic point, the manifolds against the map itself."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from systems import henon_heiles, px, py, x, y

import explorer as ex
from explorer.analysis import manifolds as mf
from explorer.analysis import periodic as pr
from explorer.analysis import rotation as ro

E = 1.0 / 8.0
#: the fixed points on py = 0 (Fix of the reversor (y, py) -> (y, -py)): seen on a scan of the line
ELLIPTIC_GUESS = (0.3, 0.0)
HYPERBOLIC_GUESS = (-0.18, 0.0)


@pytest.fixture(scope="module")
def smap():
    return ex.SectionMap(henon_heiles(), E, section=x, direction=+1, coords=(y, py), solve=px)


@pytest.fixture(scope="module")
def elliptic(smap):
    return ex.find_fixed_point(smap, ELLIPTIC_GUESS)


@pytest.fixture(scope="module")
def hyperbolic(smap):
    return ex.find_fixed_point(smap, HYPERBOLIC_GUESS)


def hh_rhs(t, s):
    X, Y, PX, PY = s
    return [PX, PY, -X - 2*X*Y, -Y - (X**2 - Y**2)]


def central_differences(m, x0, step=1e-6):
    J = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = step
        J[:, j] = (m(x0 + e, jacobian=False).point - m(x0 - e, jacobian=False).point) / (2 * step)
    return J


def test_the_fixed_points_on_the_symmetry_line_are_periodic_orbits_that_close_under_dop853(smap, elliptic,
                                                                                            hyperbolic):
    for fp in (elliptic, hyperbolic):
        assert abs(fp.point[1]) <= 1e-12 and fp.symmetric and fp.residual <= 1e-9
        s0 = smap.state(fp.point)
        sol = solve_ivp(hh_rhs, (0.0, fp.return_time), s0, method="DOP853", rtol=1e-13, atol=1e-13)
        assert np.max(np.abs(sol.y[:, -1] - s0)) <= 1e-9      # the orbit closes after its return time
        assert fp.det == pytest.approx(1.0, abs=1e-10)
        J = central_differences(smap, fp.point)
        assert fp.residue == pytest.approx((2.0 - np.trace(J)) / 4.0, abs=1e-6)
    assert elliptic.stable and abs(elliptic.trace) < 2.0 and 0.0 < elliptic.residue < 1.0
    assert np.allclose(np.abs(elliptic.eigenvalues), 1.0, atol=1e-10)
    assert not hyperbolic.stable and hyperbolic.trace > 2.0
    assert np.prod(np.real(hyperbolic.eigenvalues)) == pytest.approx(1.0, abs=1e-10)
    orb = pr.find_periodic_orbit(smap, ELLIPTIC_GUESS, 1)
    assert np.max(np.abs(orb.points[0] - elliptic.point)) <= 1e-10


def test_a_fixed_point_prints_the_system_its_parameters_the_energy_and_the_section(elliptic):
    text = repr(elliptic)
    for part in ("henon_heiles(lam=1.0)", f"energy={E!r}", "section=x", "direction=+1", "coords=(y, py)"):
        assert part in text and part in str(elliptic)
    assert "params=" not in text and "h=nan" not in text and "phi0=" not in text     # Chaplygin's fields


def test_a_period_2_orbit_is_found_by_newton_and_returns_to_itself(smap, elliptic):
    # period 2 of the elliptic point's island chain is not known here: a period-1 start gives the
    # period-1 orbit again (reduced to its minimal period), the unreduced one has the squared trace
    orb = pr.find_periodic_orbit(smap, elliptic.point, 2, reduce=False)
    assert orb.period == 2 and np.max(np.abs(orb.points - elliptic.point)) <= 1e-9
    assert orb.trace == pytest.approx(elliptic.trace ** 2 - 2.0, abs=1e-8)     # tr M^2 = tr^2 - 2 det
    assert pr.find_periodic_orbit(smap, elliptic.point, 2).period == 1


def test_the_symmetric_seeds_are_the_fixed_points_on_the_reversors_line(smap, elliptic, hyperbolic):
    """Seeds of period 1: the roots, on the fixed line py = 0 of each half of the section, of the
    distance to that line after one half turn; each is a fixed point of the map on py = 0, and both
    fixed points are among them."""
    seeds = pr.symmetry_line_points(smap, 1, n=24)
    assert len(seeds) >= 2 and np.max(np.abs(seeds[:, 1])) <= 1e-12
    assert np.max(np.abs(smap.images(seeds, 1)[:, 0] - seeds)) <= 1e-9
    for fp in (elliptic, hyperbolic):
        assert np.min(np.linalg.norm(seeds - fp.point, axis=1)) <= 1e-9


def test_the_search_finds_the_fixed_points_and_their_copies_under_the_threefold_symmetry(smap, elliptic, hyperbolic):
    """Seeds on the symmetry lines and grid minima over the domain: both fixed points, and the orbits
    that Hénon–Heiles' rotation by 2 pi/3 in (x, y) makes of them, which cross x = 0 elsewhere with the
    same multipliers; every orbit found returns to itself, and an asymmetric one comes with its image
    under the reversor (y, py) -> (y, -py)."""
    found = pr.search_periodic_orbits(smap, 1, grid=6, line=12, max_guesses=12)
    for fp in (elliptic, hyperbolic):
        assert any(o.distance_to(fp.point) <= 1e-8 for o in found)
        copies = [o for o in found if o.distance_to(fp.point) > 1e-3 and abs(o.trace - fp.trace) <= 1e-8]
        assert copies, f"no copy of the orbit through {fp.point} (trace {fp.trace})"
    R = smap.reflection
    for o in found:
        assert o.period == 1 and np.max(np.abs(smap(o.points[0], jacobian=False).point - o.points[0])) <= 1e-9
        assert o.symmetric == o.same_orbit(R(o.points), 1e-9)
        if not o.symmetric:
            assert any(m.same_orbit(R(o.points), 1e-9) and m.trace == pytest.approx(o.trace, abs=1e-9)
                       for m in found if m is not o)


def test_the_seeds_run_on_the_threads_given_and_are_the_same_on_one_or_two(smap, monkeypatch):
    from explorer.analysis import system_section_map as ssm

    seen = []

    def spy(*args, **kw):
        seen.append(kw["threads"])
        return crossings(*args, **kw)

    crossings = ssm.system_crossings
    monkeypatch.setattr(ssm, "system_crossings", spy)
    one = smap.symmetric_seeds(1, 12, threads=1), smap.grid_seeds(1, 6, threads=1)
    assert set(seen) == {1}
    seen.clear()
    two = smap.symmetric_seeds(1, 12, threads=2), smap.grid_seeds(1, 6, threads=2)
    assert 2 in seen and set(seen) <= {1, 2}           # a lone orbit runs on one thread
    assert all(np.array_equal(a, b) and len(a) for a, b in zip(one, two))


def test_the_search_budget_is_eight_typical_returns_near_the_linear_period_2pi(smap, elliptic, hyperbolic):
    """Near the origin Hénon–Heiles is two oscillators of frequency 1: returns take about 2 pi."""
    from explorer.analysis.system_section_map import SEARCH_RETURNS

    assert smap.typical_return_time == pytest.approx(2.0 * math.pi, rel=0.15)
    assert smap.search_tmax == SEARCH_RETURNS * smap.typical_return_time
    assert max(elliptic.return_time, hyperbolic.return_time) < smap.search_tmax


def test_what_a_systems_map_lacks_is_refused_naming_it(smap):
    """The map answers the protocol's questions or names what it lacks: no angle coordinate (a centre
    is needed), no generating function (not a twist map), no guess for its half-turn shooting."""
    from explorer.analysis import cantorus
    from explorer.analysis import greene as gm

    with pytest.raises(ex.ParameterError, match="angle coordinate"):
        ro.frequency_diffusion(smap, [ELLIPTIC_GUESS], center=None, iterates=10)
    with pytest.raises(ex.ParameterError, match="angle coordinate"):
        cantorus.cantorus_flux(smap)
    with pytest.raises(ex.ParameterError, match="no generating function"):
        smap.generating_function(0.0, 0.1)
    with pytest.raises(ex.ParameterError, match="needs guess"):
        gm.symmetric_orbit(smap, 1, 5)
    assert smap.own_indicators(ELLIPTIC_GUESS, {"tmax": 1.0}) is None      # its flow's: explorer.indicators


def test_the_elliptic_point_is_continued_in_the_energy(smap, elliptic):
    br = pr.continue_periodic(smap, 1, "energy", E, E + 0.01, 0.005, elliptic.points)
    assert br.stopped is None and np.allclose(br.values, [E, E + 0.005, E + 0.01])
    for v, o in zip(br.values, br.orbits):
        at = smap.with_value("energy", v)
        assert np.max(np.abs(at(o.points[0], jacobian=False).point - o.points[0])) <= 1e-10
    assert br.traces[0] == pytest.approx(elliptic.trace, abs=1e-9) and len(set(np.round(br.traces, 6))) == 3


def test_rotation_numbers_around_the_elliptic_point_tend_to_its_linear_value(smap, elliptic):
    linear = math.acos(elliptic.trace / 2.0) / (2.0 * math.pi)
    values = []
    for d in (0.06, 0.03, 0.01):
        r = ro.rotation_number(smap, (elliptic.point[0] + d, 0.0), center=elliptic, iterates=300)
        assert r.status == "done" and 0.0 < r.value < 1.0
        values.append(r.value)
    # an invariant curve: the averages over N and 2N returns agree
    assert ro.rotation_number(smap, (elliptic.point[0] + 0.03, 0.0), center=elliptic, iterates=300).difference < 1e-8
    errors = [abs(v - linear) for v in values]
    assert errors[0] > errors[1] > errors[2] and errors[2] < 2e-3


def test_a_manifold_of_the_hyperbolic_point_lies_on_the_energy_level_and_is_invariant(smap, hyperbolic):
    unstable, stable = mf.manifolds(smap, hyperbolic, arclength=0.15, signs=(1,))
    P = unstable.points[1:]
    S = smap.states(P)                     # every point on the section at energy E
    H = (S[:, 2]**2 + S[:, 3]**2)/2 + (S[:, 0]**2 + S[:, 1]**2)/2 + (S[:, 0]**2*S[:, 1] - S[:, 1]**3/3)
    assert np.max(np.abs(H - E)) <= 1e-14 and np.all(S[:, 0] == 0.0) and np.all(S[:, 2] > 0.0)
    for k in (len(P) // 3, len(P) // 2):
        image = smap(P[k], jacobian=False).point        # W^u is invariant: P maps it into itself
        assert unstable.distance(image) <= 1e-8
        pre = smap.inverse(stable.points[k + 1])        # W^s (the reversor's image of W^u) under P^-1
        assert stable.distance(pre) <= 1e-8
