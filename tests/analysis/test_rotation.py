"""Rotation numbers by weighted Birkhoff averages (explorer.analysis.rotation).

Against the integrable case mu = 0 (docs/model.md R6: the (p1, p2, M) motion is periodic, and the
rotation number per return follows from its period and the angle phi advanced in it, computed
here by an independent scipy integration), and against the periodic orbits of
explorer.analysis.periodic at mu = 0.03 (plateaus m/K at island chains)."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from explorer import model
from explorer.analysis import periodic as pm
from explorer.analysis import rotation as rm

H = 2.0


def test_weighted_birkhoff_average_converges_super_fast_on_a_quasiperiodic_sequence():
    alpha = (math.sqrt(5) - 1) / 2
    n = np.arange(2000)
    f = 0.3 + np.cos(2 * np.pi * (0.1 + alpha * n)) + 0.5 * np.sin(4 * np.pi * (0.1 + alpha * n))
    assert rm.weighted_birkhoff(f, 1000) == pytest.approx(0.3, abs=1e-13)
    assert abs(np.mean(f[:1000]) - 0.3) > 1e-5          # the plain average is far slower
    w = rm.birkhoff_weights(100)
    assert w.sum() == pytest.approx(1.0) and w[0] == 0.0 and np.all(w >= 0)


def _rotation_mu0_independent(p1, h=H):
    """Rotation number per return of the section map at mu = 0 around solution II (sqrt 2, 0)
    for the orbit through (p1, 0): from R6, integrated with scipy (not the project's code).
    The (p1, p2, M) motion is periodic with period tau (two returns of p2 to 0 in the same
    direction); phi advances Phi = int_0^tau M/b dt in it.  With the circle coordinate
    2 pi (phi advanced)/Phi the section map is the rotation by 2 pi/Phi of a turn, in the
    direction in which (p1, p2) circles the fixed point."""
    a1, a2, b, lam = 1.0, 0.5, 2.0, 1.0
    M0 = math.sqrt(2 * b * (h - 0.5 * p1 * p1 / a1))

    def f(t, y):
        q1, q2, M, _ = y
        return [q2 * M / b - lam * q2 / a2, -q1 * M / b + lam * q1 / a1, (1 / a2 - 1 / a1) * q1 * q2, M / b]

    dp2 = -p1 * M0 / b + lam * p1 / a1
    sigma = 1.0 if (p1 - math.sqrt(2.0)) * dp2 > 0 else -1.0   # counter-clockwise around (sqrt 2, 0)?

    def ev(t, y):
        return y[1]

    ev.direction = 1.0 if dp2 > 0 else -1.0
    sol = solve_ivp(f, (0, 200), [p1, 0.0, M0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13, events=ev)
    te = [t for t in sol.t_events[0] if t > 1e-6]
    tau = te[0]
    Phi = sol.y_events[0][[i for i, t in enumerate(sol.t_events[0]) if t > 1e-6][0]][3]
    return sigma * 2 * math.pi / Phi, tau    # turns per return through the flow (not reduced mod 1)


@pytest.mark.parametrize("p1", [1.5, 1.6, 1.7])
def test_rotation_number_at_mu0_equals_the_period_quadrature_of_R6(p1):
    prm = model.FIGURE4.with_(mu=0.0)
    expected, _ = _rotation_mu0_independent(p1)
    # (the slow rotation near the parabolic point, 1/40 turn per return at p1 = 1.5, needs many returns)
    r = rm.rotation_number(prm, H, (p1, 0.0), center=(math.sqrt(2.0), 0.0), iterates=4000)
    assert r.converged
    assert r.value == pytest.approx(expected - round(expected), abs=1e-11)
    assert r.turns == pytest.approx(expected, abs=1e-11)


@pytest.mark.parametrize("p1", [1.8, 1.9, 1.97])
def test_rotation_number_is_lifted_through_the_flow_out_to_the_edge_of_the_region(p1):
    """Beyond p1 ~ 1.75 (the region's edge is p1 = 2) single returns turn by more than half a
    turn around (sqrt 2, 0), some more and some less: wrapping each return's increment to
    (-pi, pi] gave -0.007 for -0.429 at p1 = 1.8, -0.015 for -0.385 at 1.9, -0.03 for 0.327 at
    1.97.  Lifted through the flow (sub-sections) it equals the scipy quadrature of R6, to
    the accuracy of 1,000 returns on these slowly converging orbits (near the separatrix of
    solution I at p1 ~ 1.82 and the edge)."""
    prm = model.FIGURE4.with_(mu=0.0)
    expected, _ = _rotation_mu0_independent(p1)
    r = rm.rotation_number(prm, H, (p1, 0.0), center=(math.sqrt(2.0), 0.0), iterates=500)
    assert r.status == "done"
    assert r.value == pytest.approx(expected - math.ceil(expected - 0.5), abs=1e-6)
    assert r.turns == pytest.approx(expected, abs=1e-6)


@pytest.mark.cpu_dependent
def test_orbits_whose_angle_turns_back_get_no_rotation_number():
    """At mu = 0 the orbit through (0, 1.3) has F = c < 2 (R6) and reaches M = 0: phi turns back,
    the section map is not a flow in phi, and the rotation is refused with status "turned"."""
    r = rm.rotation_number(model.FIGURE4.with_(mu=0.0), H, (0.0, 1.3), center=(math.sqrt(2.0), 0.0), iterates=100)
    assert r.status == "turned" and math.isnan(r.value) and not r.converged


PRM = model.FIGURE4.with_(mu=0.03)
CENTER = (1.582201141, 0.0)   # elliptic fixed point of the Figure 4 scene at mu = 0.03


@pytest.fixture(scope="module")
def centre():
    """The elliptic fixed point near CENTER, refined by Newton once for the module."""
    return pm.find_periodic_orbit(PRM, H, CENTER, 1).points[0]


def test_rotation_center_defaults_to_the_fixed_point_found_from_the_start(centre):
    r = rm.rotation_number(PRM, H, (1.58, 0.0), iterates=200)
    np.testing.assert_allclose(r.center, centre, atol=1e-12)


@pytest.mark.cpu_dependent
def test_island_chain_plateau_equals_m_over_K_of_the_periodic_orbit_found(centre):
    """The period-8 chain (the period-6 plateau, -1/6: the profile test below)."""
    K = 8
    orb = pm.find_periodic_orbit(PRM, H, (1.154444, 0.0), K)
    assert orb.period == K and orb.kind == "elliptic"
    m_over_K = rm.orbit_rotation(orb.points, centre)
    assert abs(m_over_K * K - round(m_over_K * K)) < 1e-12     # an integer m
    r = rm.rotation_number(PRM, H, orb.points[0] + np.array([0.002, 0.0]), center=centre, iterates=3000)
    assert r.converged and r.value == pytest.approx(m_over_K, abs=1e-9)


@pytest.mark.cpu_dependent
def test_chaotic_orbit_does_not_converge_and_the_profile_has_the_plateaus(centre):
    r = rm.rotation_number(PRM, H, (0.5, 0.0), center=centre, iterates=1000)
    assert not r.converged and r.difference > 1e-8
    prof = rm.rotation_profile(PRM, H, (1.01, 0.0), (1.02, 0.0), n=3, center=centre, iterates=500)
    assert prof.points.shape == (3, 2) and prof.s[-1] == 1.0
    assert any(abs(v + 1 / 6) < 1e-8 for v in prof.rotation)       # the period-6 island


def _run_sizes(monkeypatch):
    """The orbits of each run of the rotation lift (flow_lift.run), as they are asked for."""
    from explorer.analysis import flow_lift

    sizes = []
    real = flow_lift.run

    def counting(params, Y0, **kw):
        sizes.append(Y0.shape[0])
        return real(params, Y0, **kw)

    monkeypatch.setattr(flow_lift, "run", counting)
    return sizes


def test_sub_sections_integrate_only_the_orbits_still_unresolved_and_each_keeps_its_own_value(centre, monkeypatch):
    """A start one ulp from the centre has no angle around it at the integration's accuracy and is
    refined up to MAX_SUBSECTIONS; the deeper sub-sections integrate the centre and that orbit alone,
    and every other orbit gets the value it gets alone (an orbit's crossings do not depend on the
    others in its run)."""
    from explorer.analysis import flow_lift

    sizes = _run_sizes(monkeypatch)
    next_to_it = (np.nextafter(centre[0], 2.0), centre[1])
    prof = rm.rotation_profile(PRM, H, next_to_it, (1.45, 0.0), n=4, center=centre, iterates=40)
    monkeypatch.undo()
    assert prof.status[0] == "unresolved" and math.isnan(prof.rotation[0])
    assert sizes.count(2) >= flow_lift.MAX_SUBSECTIONS // 2      # the deepest level: the centre and one orbit
    assert max(sizes) == 1 + 4
    for i in range(1, 4):
        alone = rm.rotation_number(PRM, H, prof.points[i], center=centre, iterates=40)
        assert alone.status == prof.status[i]
        assert np.array_equal([alone.value, alone.turns], [prof.rotation[i], prof.turns[i]], equal_nan=True)


def test_a_start_at_the_centre_itself_is_unresolved_without_sub_sections(centre, monkeypatch):
    """Its angle around the centre is undefined: the returns (one run) say so, no sub-section is
    integrated for it, and the other orbits' values are those they get without it."""
    sizes = _run_sizes(monkeypatch)
    prof = rm.rotation_profile(PRM, H, centre, (1.45, 0.0), n=3, center=centre, iterates=40)
    monkeypatch.undo()
    assert prof.status[0] == "unresolved" and math.isnan(prof.rotation[0])
    assert sizes[0] == 1 + 3 and max(sizes[1:], default=0) <= 1 + 2   # after the returns: the others only
    for i in (1, 2):
        alone = rm.rotation_number(PRM, H, prof.points[i], center=centre, iterates=40)
        assert alone.status == prof.status[i] == "done" and alone.value == prof.rotation[i]


def test_rotation_refuses_points_outside_the_allowed_region():
    with pytest.raises(model.ParameterError, match="allowed region"):
        rm.rotation_number(PRM, H, (3.0, 0.0), center=CENTER)
    with pytest.raises(model.ParameterError, match="allowed region"):
        rm.rotation_profile(PRM, H, (1.0, 0.0), (3.0, 0.0), n=5, center=CENTER)
