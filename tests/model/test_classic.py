"""The classic systems of explorer.model.classic (docs/classic.md), each checked against numbers
computed elsewhere: Hénon & Heiles 1964, Arenstorf's orbit as given by Hairer, Nørsett & Wanner,
the normal modes of the double pendulum, and scipy's DOP853 on the pendulum's Lagrangian."""
import math

import numpy as np
import pytest
import sympy as sp

import explorer as ex
from explorer.model import classic

#: crossings per orbit of the Hénon–Heiles sections
HH_CROSSINGS = 150


# ---------------------------------------------------------------------------------------------- Hénon–Heiles
@pytest.fixture(scope="module")
def hh():
    return classic.henon_heiles()


def _energy_curve_ends(E):
    """The ends y_lo < 0 < y_hi of the section x = 0 at energy E: roots of y^2 - 2y^3/3 = 2E."""
    r = np.roots([-2.0 / 3.0, 1.0, 0.0, -2.0 * E])
    r = np.sort(r[np.abs(r.imag) < 1e-6].real)        # at E = 1/6 the double root y = 1 (the saddle)
    return r[r < 0].max(), r[r > 0].min()


@pytest.fixture(scope="module")
def hh_sections(hh):
    """The sections x = 0, px > 0 at E = 1/12, 1/8, 1/6 (as Hénon & Heiles 1964): 12 orbits each,
    from py = 0 across the section and from y = 0 up and down, HH_CROSSINGS crossings each."""
    x, y, px, py = hh.states
    out = {}
    for E in classic.HENON_HEILES_ENERGIES:
        lo, hi = _energy_curve_ends(E)
        pts = [(v, 0.0) for v in np.linspace(0.95 * lo, 0.95 * hi, 8)]
        pts += [(0.0, v) for v in (-0.3, -0.1, 0.1, 0.3)]
        smap = ex.SectionMap(hh, E, section=x, direction=+1, coords=(y, py), solve=px)
        out[E] = ex.crossings(smap, pts, n_crossings=HH_CROSSINGS)
    return out


def test_henon_heiles_equations_are_those_of_the_issue_and_hamiltons_of_its_energy(hh):
    x, y, px, py = hh.states
    lam = next(iter(hh.parameters))
    expected = [px, py, -x - 2 * lam * x * y, -y - lam * (x**2 - y**2)]
    assert all(sp.simplify(f - e) == 0 for f, e in zip(hh.rhs, expected))
    assert sp.simplify(hh.energy - ((px**2 + py**2) / 2 + (x**2 + y**2) / 2 + lam * (x**2 * y - y**3 / 3))) == 0


def test_henon_heiles_energy_is_conserved_to_1e_12_at_every_crossing_of_the_three_sections(hh_sections):
    for E, res in hh_sections.items():
        assert np.all(res.count == HH_CROSSINGS), (E, res.count)
        assert np.nanmax(np.abs(res.data[..., 5])) <= 1e-12, E          # the E - E0 column


def test_henon_heiles_section_points_lie_on_x_0_with_px_positive_inside_the_energy_curve(hh_sections):
    for E, res in hh_sections.items():
        t, x, y, px, py = (res.data[..., k] for k in range(5))
        lo, hi = _energy_curve_ends(E)
        assert np.all(np.abs(x) <= 1e-13) and np.all(px > 0)
        # inside the curve py^2 + y^2 - 2y^3/3 = 2E (the section's boundary, px = 0 on it)
        assert np.all(py**2 + y**2 - 2 * y**3 / 3 <= 2 * E + 1e-12)
        assert np.all((lo - 1e-6 <= y) & (y <= hi + 1e-6))   # not the branch beyond the saddle
        assert np.all(np.diff(t, axis=1) > 0)


def test_henon_heiles_scales_with_lam_as_its_hamiltonian(hh):
    """H_lam(q/lam, p/lam) = H_1(q, p)/lam^2: the orbit of lam = 0.5 from 2 Y0 is twice the orbit of
    lam = 1 from Y0, at the same times (a runtime parameter value, the same compiled code)."""
    x = hh.states[0]
    Y0 = np.array([[0.0, 0.1, math.sqrt(2 / 8 - 0.1**2 + 2 * 0.1**3 / 3), 0.0]])
    one = ex.crossings(hh, states=Y0, n_crossings=30, section=x, direction=+1)
    half = ex.crossings(hh.with_(lam=0.5), states=2 * Y0, n_crossings=30, section=x, direction=+1)
    np.testing.assert_allclose(half.data[..., 0], one.data[..., 0], rtol=1e-12)
    np.testing.assert_allclose(half.data[..., 1:5], 2 * one.data[..., 1:5], rtol=0, atol=1e-11)


#: Hénon & Heiles 1964 (Astron. J. 69, 73), Fig. 7: the relative area of the section covered by curves
#: at E = 1/12, 1/8 and 1/6, read off the figure (its points at E = 0.082, 0.125 and 0.166; read to 0.01)
HH_1964_CURVE_AREA = {1 / 12: 1.00, 1 / 8: 0.70, 1 / 6: 0.085}
#: how far a fraction of ours may lie from those: the figure's points scatter about the line Hénon & Heiles
#: drew through them by up to 0.08 (0.50 against 0.42 at E = 0.14), and a proportion p from n points has
#: the standard error sqrt(p (1 - p) / n), 0.07 to 0.09 for the few tens of points an orbit-by-orbit
#: computation of 1964 could afford (the paper does not say how many)
HH_1964_TOLERANCE = 0.15


def _section_grid(E, n):
    """The points of an n x n grid over the box of the section x = 0 at energy E that lie inside its
    energy curve (uniform in area, as the relative areas of Hénon & Heiles 1964)."""
    lo, hi = _energy_curve_ends(E)
    top = math.sqrt(2 * E)                              # the largest |py|, at y = 0
    Y, P = np.meshgrid(np.linspace(lo, hi, n + 2)[1:-1], np.linspace(-top, top, n + 2)[1:-1])
    inside = P**2 + Y**2 - 2 * Y**3 / 3 < 0.999 * 2 * E
    return np.column_stack([Y[inside], P[inside]])


def test_henon_heiles_own_criterion_gives_the_relative_areas_of_their_fig_7(hh):
    """Hénon & Heiles 1964, Sec. 3: a point P and a point P' at 1e-7 from it in (y, py), 25 returns of both
    to the section; P lies on a curve when mu = sum_i |P_i P'_i|^2 < 1e-4, else in the ergodic region.
    That criterion, with explorer's section map, on a 20 x 20 grid (about 300 points, uniform in area):
    the area covered by curves is Fig. 7's within HH_1964_TOLERANCE at E = 1/12, 1/8 and 1/6."""
    x, y, px, py = hh.states
    for E, published in HH_1964_CURVE_AREA.items():
        smap = ex.SectionMap(hh, E, section=x, direction=+1, coords=(y, py), solve=px)
        pts = _section_grid(E, 20)
        near = pts + np.column_stack([np.where(pts[:, 0] > 0, -1e-7, 1e-7), np.zeros(len(pts))])  # inside
        a, b = (ex.crossings(smap, p, n_crossings=25) for p in (pts, near))
        assert np.all(a.count == 25) and np.all(b.count == 25)
        mu = np.sum((a.data[..., 2] - b.data[..., 2])**2 + (a.data[..., 4] - b.data[..., 4])**2, axis=1)
        area = np.mean(mu < 1e-4)
        assert abs(area - published) <= HH_1964_TOLERANCE, (E, area, published)


def test_henon_heiles_chaotic_fraction_grows_with_the_energy_as_henon_and_heiles_found():
    """MEGNO <Y> > 4 at t = 1000 on a 12 x 12 grid of each section (about 120 orbits, uniform in area)
    against Hénon & Heiles 1964, Fig. 7 (HH_1964_CURVE_AREA): no chaos at E = 1/12, their chaotic share
    1 - 0.085 at E = 1/6 within HH_1964_TOLERANCE.  At E = 1/8 their 25 returns count among the curves
    the orbits that stick to the islands for longer (test_henon_heiles_own_criterion_...: 0.17 of the
    area by their criterion), which t = 1000 shows chaotic: our share is at least theirs, 0.30, and
    below 0.7 (the islands of their Fig. 5 remain)."""
    hh = classic.henon_heiles()
    x, y, px, py = hh.states
    fraction = {}
    for E in classic.HENON_HEILES_ENERGIES:
        smap = ex.SectionMap(hh, E, section=x, direction=+1, coords=(y, py), solve=px, tol=1e-13)
        ind = ex.indicators(smap, _section_grid(E, 12), tmax=1000.0, which=("megno",))
        fraction[E], _, n = ex.chaotic_fraction(ind.megno, 4.0)
        assert n > 100
    f12, f8, f6 = (fraction[E] for E in classic.HENON_HEILES_ENERGIES)
    assert f12 <= 1 - HH_1964_CURVE_AREA[1 / 12] + 0.05, fraction
    assert abs(f6 - (1 - HH_1964_CURVE_AREA[1 / 6])) <= HH_1964_TOLERANCE, fraction
    assert 1 - HH_1964_CURVE_AREA[1 / 8] <= f8 <= 0.7, fraction
    assert f12 < f8 < f6


def test_henon_heiles_largest_lyapunov_exponents_are_the_printed_ones_of_two_chaotic_orbits(hh):
    """Kallrath, Schlöder & Bock 1993 (Celest. Mech. Dyn. Astron. 56, 353), Tables I and II: the
    Hénon–Heiles orbits from (x, y, px, py) = (0, 0, sqrt(0.1275), -0.35) (E = 0.125) and
    (0, 0, 0.3, -0.41) (E = 0.12905) have the largest Lyapunov exponents 0.044 and 0.053, printed to
    two figures and finite-time values; the finite-time scatter at t = 10^4 is about 0.01, hence the
    tolerance 0.015.  MEGNO grows as lambda t / 2 on them (Cincotta & Simó 2000)."""
    starts = np.array([(0.0, 0.0, math.sqrt(0.1275), -0.35), (0.0, 0.0, 0.3, -0.41)])
    T = 1e4
    ind = ex.indicators(hh, states=starts, tmax=T, which=("mlce", "megno"))
    assert np.all(np.abs(ind.mlce - np.array([0.044, 0.053])) <= 0.015), ind.mlce
    np.testing.assert_allclose(ind.megno, ind.mlce * T / 2, rtol=0.25)


# ---------------------------------------------------------------------------------------------- PCR3BP
@pytest.fixture(scope="module")
def pcr():
    return classic.pcr3bp()


def _jacobi(s, mu):
    x, y, vx, vy = s
    r1 = math.hypot(x + mu, y)
    r2 = math.hypot(x - 1 + mu, y)
    return x * x + y * y + 2 * (1 - mu) / r1 + 2 * mu / r2 - vx * vx - vy * vy


def test_arenstorf_orbit_closes_after_its_period_to_1e_10(pcr):
    """Hairer, Nørsett & Wanner, Solving ODEs I, II.0 (0.1)-(0.2): mu = 0.012277471 and the start
    (0.994, 0, 0, -2.0015851063790825...) give a periodic orbit of period T = 17.0652165601579625...
    The flow's state at T (its last step clipped onto T, as the crossings' onto tmax:
    tests/analysis/test_system_flow.py) is the start again."""
    res = ex.flow(pcr, states=[classic.ARENSTORF_STATE], times=[classic.ARENSTORF_PERIOD], tol=1e-15)
    assert res.status_of(0) is ex.Status.DONE and res.t[-1] == classic.ARENSTORF_PERIOD
    assert np.max(np.abs(res.states[0, -1] - np.array(classic.ARENSTORF_STATE))) <= 1e-10


def test_jacobi_constant_is_conserved_to_1e_12_relative_over_ten_periods(pcr):
    """At 331 times over eleven periods (30 a period), by the flow's energy column and by hand."""
    times = np.linspace(0.0, 11 * classic.ARENSTORF_PERIOD, 331)
    res = ex.flow(pcr, states=[classic.ARENSTORF_STATE], times=times, tol=1e-15)
    C0 = _jacobi(classic.ARENSTORF_STATE, classic.ARENSTORF_MU)
    assert res.status_of(0) is ex.Status.DONE
    assert np.max(res.energy_error[0]) <= 1e-12 * abs(C0)                  # |C - C0|
    # the energy the system declares is the Jacobi constant, by hand at the samples
    C = [_jacobi(s, classic.ARENSTORF_MU) for s in res.states[0]]
    np.testing.assert_allclose(C, C0, rtol=1e-12)


def test_a_section_map_on_the_jacobi_level_lifts_arenstorfs_start(pcr):
    """The energy of pcr3bp is C itself: SectionMap(pcr, C0, section=y, direction=-1 (vy < 0),
    coords=(x, vx), solve=vy) lifts (0.994, 0) to Arenstorf's printed vy0 = -2.0015851063790825..."""
    x, y, vx, vy = pcr.states
    C0 = _jacobi(classic.ARENSTORF_STATE, classic.ARENSTORF_MU)
    smap = ex.SectionMap(pcr, C0, section=y, direction=-1, coords=(x, vx), solve=vy)
    np.testing.assert_allclose(smap.states([(0.994, 0.0)])[0], classic.ARENSTORF_STATE, rtol=0, atol=1e-14)


# ---------------------------------------------------------------------------------------------- double pendulum
def _lagrangian_rhs(m1, m2, l1, l2, g):
    """d(th1, th2, w1, w2)/dt from the Lagrangian L = T - V of two pendula, written here from the
    mass matrix M(th) and the forces (not from explorer's Hamiltonian): M dw/dt = f."""

    def rhs(t, s):
        th1, th2, w1, w2 = s
        c, sn = math.cos(th1 - th2), math.sin(th1 - th2)
        M = np.array([[(m1 + m2) * l1**2, m2 * l1 * l2 * c], [m2 * l1 * l2 * c, m2 * l2**2]])
        f = np.array([-m2 * l1 * l2 * sn * w2**2 - (m1 + m2) * g * l1 * math.sin(th1),
                      m2 * l1 * l2 * sn * w1**2 - m2 * g * l2 * math.sin(th2)])
        return [w1, w2, *np.linalg.solve(M, f)]

    return rhs


def _momenta(s, m1, m2, l1, l2, g):
    """(th1, th2, p1, p2) from (th1, th2, w1, w2): p = M(th) w."""
    th1, th2, w1, w2 = s
    c = math.cos(th1 - th2)
    return np.array([th1, th2, (m1 + m2) * l1**2 * w1 + m2 * l1 * l2 * c * w2, m2 * l2**2 * w2 + m2 * l1 * l2 * c * w1])


def test_double_pendulum_conserves_its_energy_to_1e_12_relative_at_a_finite_amplitude():
    """|E - E0| <= 1e-12 |E0| at every crossing (E0 about -20: the potential (m1 + m2) g l1 = 29.4)."""
    dp = classic.double_pendulum(m1=1.0, m2=2.0, l1=1.0, l2=0.7, g=9.81)
    th1 = dp.states[0]
    starts = np.array([(1.2, -0.8, 0.0, 0.0), (0.3, 2.0, 0.5, -0.2)])
    res = ex.crossings(dp, states=starts, n_crossings=150, section=th1, direction=+1)
    E0 = np.array([float(dp.energy.subs(dict(zip(dp.states, s))).subs(dp.parameters)) for s in starts])
    assert np.all(res.count == 150) and np.all(np.abs(E0) > 10)
    assert np.all(np.nanmax(np.abs(res.data[..., 5]), axis=1) <= 1e-12 * np.abs(E0))


@pytest.mark.parametrize("branch", [-1, +1])
def test_small_oscillations_have_the_normal_mode_frequencies_of_equal_pendula(branch):
    """Equal masses m and lengths l: omega^2 = (g/l)(2 -+ sqrt 2), the modes th2/th1 = +-sqrt 2
    (linearised Lagrangian, det(K - omega^2 M) = 0).  An orbit started at rest on a mode with
    amplitude eps has the frequency omega (1 + c eps^2 + ...): measured from 40 crossings of
    th1 = 0 within 1e-6 at eps = 1e-4, and within 1e-10 after removing the eps^2 term (Richardson,
    eps = 1e-3 and 1e-4)."""
    m, ell, g = 2.0, 0.5, 9.81
    dp = classic.double_pendulum(m1=m, m2=m, l1=ell, l2=ell, g=g)
    th1 = dp.states[0]
    omega = math.sqrt(g / ell * (2 + branch * math.sqrt(2)))
    mode = np.array([1.0, -branch * math.sqrt(2)])

    def measured(eps):
        res = ex.crossings(dp, states=[(eps * mode[0], eps * mode[1], 0.0, 0.0)], n_crossings=40, section=th1,
                           direction=+1, tol=1e-15)
        t = res.data[0, :, 0]
        return 2 * math.pi * (len(t) - 1) / (t[-1] - t[0])

    w3, w4 = measured(1e-3), measured(1e-4)
    assert abs(w4 / omega - 1) <= 1e-6
    assert abs((100 * w4 - w3) / 99 / omega - 1) <= 1e-10


def test_double_pendulum_agrees_with_scipy_on_the_lagrangian_at_a_finite_amplitude():
    """Crossings of th1 = 0 (upwards) against scipy's DOP853 at rtol = atol = 1e-12 with events, on the
    equations of the Lagrangian written in the test; unequal masses and lengths."""
    from scipy.integrate import solve_ivp

    prm = dict(m1=1.0, m2=2.0, l1=1.0, l2=0.7, g=9.81)
    dp = classic.double_pendulum(**prm)
    start = (0.6, -0.4, 0.0, 0.0)                       # at rest: p = w = 0
    res = ex.crossings(dp, states=[start], n_crossings=12, section=dp.states[0], direction=+1, tol=1e-15)

    def event(t, s):
        return s[0]

    event.direction = 1
    ref = solve_ivp(_lagrangian_rhs(**prm), (0.0, res.data[0, -1, 0] + 0.5), start, method="DOP853", rtol=1e-12,
                    atol=1e-12, events=event)
    t_ref, s_ref = ref.t_events[0][:12], ref.y_events[0][:12]
    assert len(t_ref) == 12
    np.testing.assert_allclose(res.data[0, :, 0], t_ref, rtol=0, atol=1e-9)
    states = np.array([_momenta(s, **prm) for s in s_ref])
    np.testing.assert_allclose(res.data[0, :, 1:5], states, rtol=0, atol=1e-9)


# ---------------------------------------------------------------------------------------------- reversors
#: each classic system, its usual section (coordinate, direction, coords, solved), a level, a point
#: of the section and the reflection its reversor induces there
USUAL_MAPS = {
    "henon_heiles": (classic.henon_heiles, (0, +1, (1, 3), 2), 1 / 8, (0.2, 0.1), (1.0, -1.0)),
    "pcr3bp": (classic.pcr3bp, (1, +1, (0, 2), 3), 3.0, (0.3, 0.1), (1.0, -1.0)),
    "double_pendulum": (classic.double_pendulum, (0, +1, (1, 3), 2), -2.0, (0.2, 0.1), (-1.0, 1.0)),
}


@pytest.mark.parametrize("name", list(USUAL_MAPS))
def test_each_classic_systems_reversor_reflects_its_usual_section_map_and_reverses_it(name):
    """The declared reversor maps the usual section and its direction to itself as a reflection R of
    the coords, and R P R P p = p: R conjugates the map to its inverse (the integrated return is
    checked where the suite already compiles the system's crossings: not the pcr3bp's)."""
    make, (cut, direction, coords, solve), level, p, flips = USUAL_MAPS[name]
    system = make()
    s = system.states
    smap = ex.SectionMap(system, level, section=s[cut], direction=direction, coords=(s[coords[0]], s[coords[1]]),
                         solve=s[solve])
    (R,) = smap.reversors
    assert smap.reflection is not None
    assert np.array_equal(R(np.array(p)), np.array(p) * np.array(flips))
    if name != "pcr3bp":
        back = R(smap(R(smap(p, jacobian=False).point), jacobian=False).point)
        assert np.max(np.abs(back - np.array(p))) <= 1e-11
