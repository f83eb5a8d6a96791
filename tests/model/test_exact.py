"""Tests of the closed-form solutions (explorer.exact) against the independent
plain-numpy / scipy reference (tests/reference.py).  docs/model.md labels R3, R5,
R6, R7, R9."""
import numpy as np
import pytest

import reference as ref
from explorer.model.exact import (
    chaplygin_F,
    homoclinic,
    homoclinic_crossing_times,
    uniform_rotation,
    uniform_rotation_crossing_times,
)

# Figure-4 parameters (R9) with mu = 0: P = [a1, a2, b, lam, chi, zeta, mu, xi, eta]
P4 = np.array([1.0, 0.5, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
C4 = 2.0 * np.sqrt(2.0)  # c = sqrt(2 b h) for h = 2; unstable band 2 < c < 4
CS = [2.05, 2.5, C4, 3.5, 3.95]


def hstate(P, c, t, **kw):
    p1, p2, M, phi = homoclinic(P, c, t, **kw)
    return np.array([p1, p2, M, np.sin(phi), np.cos(phi)]), phi


# ---------------------------------------------------------------------------
# homoclinic orbit R7
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("c", CS)
@pytest.mark.parametrize("sign", [1, -1])
def test_homoclinic_solves_R6(c, sign):
    kw = dict(sign=sign, t0=0.7, phi_at_t0=0.3)
    t = np.linspace(-25.0, 25.0, 1501)
    h = 1e-5
    y, phi = hstate(P4, c, t, **kw)
    yp, php = hstate(P4, c, t + h, **kw)
    ym, phm = hstate(P4, c, t - h, **kw)
    dydt = (yp - ym) / (2 * h)
    res = np.abs(dydt - ref.rhs_numpy(0.0, y, P4))
    assert res.max() <= 1e-8, res.max(axis=1)
    # dphi/dt = M/b with the continuous phi
    assert np.abs((php - phm) / (2 * h) - y[2] / P4[2]).max() <= 1e-8
    # the orbit is a genuine excursion, not the fixed point
    assert np.abs(y[0]).max() > 0.1


@pytest.mark.parametrize("c", CS)
@pytest.mark.parametrize("sign", [1, -1])
def test_homoclinic_integrals(c, sign):
    t = np.linspace(-40.0, 40.0, 4001)
    y, _ = hstate(P4, c, t, sign=sign, t0=-1.5)
    assert np.abs(ref.energy_numpy(y, P4) - c * c / (2 * P4[2])).max() <= 1e-12
    assert np.abs(chaplygin_F(P4, y) - c).max() <= 1e-12


@pytest.mark.parametrize("c", CS)
def test_homoclinic_limits_and_centre(c):
    t0 = 0.4
    lam, b, a1 = P4[3], P4[2], P4[0]
    for sign in (1, -1):
        p1, p2, M, phi = homoclinic(P4, c, np.array([-1e4, -200.0, 200.0, 1e4]),
                                    sign=sign, t0=t0, phi_at_t0=1.0)
        assert np.all(np.isfinite(p1 + p2 + M + phi))
        assert np.abs(p1).max() <= 1e-12 and np.abs(p2).max() <= 1e-12
        assert np.abs(M - c).max() <= 1e-12
        # centre of the orbit
        p1c, p2c, Mc, phic = homoclinic(P4, c, t0, sign=sign, t0=t0, phi_at_t0=1.0)
        assert p2c == 0.0 and sign * p1c > 0.0
        assert Mc == pytest.approx(2 * lam * b / a1 - c, abs=1e-13)
        assert phic == 1.0
    # exponential approach at the rate of the linearisation of I:
    # sqrt(b1 b2)/(2 b) = sqrt((c/b - lam/a2)(lam/a1 - c/b))
    rate = np.sqrt((c / b - lam / P4[1]) * (lam / a1 - c / b))
    p1, p2, M, _ = homoclinic(P4, c, t0 + np.array([-80.0, -40.0, 40.0, 80.0]), t0=t0)
    r = np.hypot(p1, p2)
    assert r[0] / r[1] == pytest.approx(np.exp(-40 * rate), rel=1e-4)
    assert r[3] / r[2] == pytest.approx(np.exp(-40 * rate), rel=1e-4)
    # c - M = |p|^2/(2 lam) (F = c): quadratically small
    assert np.all(np.abs(M - c) <= r**2 / (2 * lam) + 4e-16 * c)


def test_homoclinic_phi_continuous_and_phase_shift():
    c = C4
    t = np.linspace(-60.0, 60.0, 200001)
    _, _, M, phi = homoclinic(P4, c, t, phi_at_t0=0.0)
    dphi = np.diff(phi)
    assert np.all(dphi > 0.0)  # M > 0: monotone
    assert np.abs(dphi).max() < 10 * (c / P4[2]) * (t[1] - t[0])
    # total phase defect across the orbit: -4 arctan(d1/d2)
    b1, b2 = 2 * (c - 2.0), 2 * (4.0 - c)
    shift = phi[-1] - phi[0] - (c / P4[2]) * (t[-1] - t[0])
    assert shift == pytest.approx(-4 * np.arctan(np.sqrt(b1 / b2)), abs=1e-10)


@pytest.mark.parametrize(
    "P, c, word",
    [
        (P4, 1.9, "c"),
        (P4, 4.0, "c"),
        (np.array([1.0, 0.5, 2.0, 1.0, 0.0, 0.0, 0.1, 0.0, 0.0]), C4, "mu"),
        (np.array([1.0, 0.5, 2.0, 1.0, 0.1, 0.0, 0.0, 0.0, 0.0]), C4, "chi"),
        (np.array([1.0, 0.5, 2.0, 1.0, 0.0, 0.1, 0.0, 0.0, 0.0]), C4, "zeta"),
        (np.array([1.0, 0.5, 2.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), C4, "lam"),
        (np.array([0.5, 1.0, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), C4, "a1 > a2"),
    ],
)
def test_homoclinic_validates_range(P, c, word):
    with pytest.raises(ValueError, match=word):
        homoclinic(P, c, 0.0)
    with pytest.raises(ValueError, match=word):
        homoclinic_crossing_times(P, c, np.pi, 0.0, 1.0)


def test_homoclinic_crossing_times_need_positive_M():
    # band lam b/a1 = 2 < c < lam b/a2 = 10, but M(t0) = 4 - c < 0 for c = 5
    P = np.array([1.0, 0.2, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    homoclinic(P, 5.0, 0.0)  # the orbit exists
    with pytest.raises(ValueError, match="M"):
        homoclinic_crossing_times(P, 5.0, np.pi, -10.0, 10.0)


@pytest.mark.parametrize("c", [2.3, C4, 3.7])
def test_homoclinic_crossing_times_hit_the_section(c):
    t0, ph0 = 0.7, 0.3
    ts = homoclinic_crossing_times(P4, c, np.pi, -30.0, 30.0, t0=t0, phi_at_t0=ph0)
    _, _, M, phi = homoclinic(P4, c, ts, t0=t0, phi_at_t0=ph0)
    k = (phi - np.pi) / (2 * np.pi)
    assert np.abs(k - np.round(k)).max() <= 1e-14
    # consecutive integers: none missed
    assert np.array_equal(np.diff(np.round(k)), np.ones(len(ts) - 1))
    assert np.all(np.diff(ts) > 0) and ts[0] >= -30.0 and ts[-1] <= 30.0
    # the count is fixed by phi at the ends
    _, _, _, ends = homoclinic(P4, c, np.array([-30.0, 30.0]), t0=t0, phi_at_t0=ph0)
    n = np.floor((ends[1] - np.pi) / (2 * np.pi)) - np.ceil((ends[0] - np.pi) / (2 * np.pi)) + 1
    assert len(ts) == n
    assert np.all(M > 0)


# ---------------------------------------------------------------------------
# uniform rotation
# ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "P, c",
    [
        (P4, C4),
        (P4, 5.0),
        (np.array([1.0, 0.5, 2.0, 1.0, 0.3, -0.2, 0.0, 0.4, 0.1]), 2.7),
        (np.array([1.3, 0.7, 1.5, -0.8, -0.1, 0.25, 0.0, 0.0, 0.0]), -1.2),
    ],
)
def test_uniform_rotation_solves_R3(P, c):
    t = np.linspace(0.0, 10.0, 11)
    p1, p2, M, phi = uniform_rotation(P, c, t, phi0=0.5)
    assert phi[0] == 0.5
    y = np.array([p1, p2, M, np.sin(phi), np.cos(phi)])
    w = c / P[2]
    expected = np.array([0 * t, 0 * t, 0 * t, w * y[4], -w * y[3]])
    assert np.abs(ref.rhs_numpy(0.0, y, P) - expected).max() <= 1e-13
    if P[4] == 0.0 and P[5] == 0.0:
        assert np.all(p1 == 0.0) and np.all(p2 == 0.0)
    # (p, M) are constant along this solution, so F(y(t)) = F(y(0)) held by construction and
    # proved nothing; the relative equilibrium is checked instead against its closed form
    # p_i = c s_i / (c - lam b / a_i), M = c (written here independently of exact.py)
    a1, a2, b, lam, chi, zeta = P[:6]
    np.testing.assert_allclose(p1, c * chi / (c - lam * b / a1), rtol=1e-15, atol=0)
    np.testing.assert_allclose(p2, c * zeta / (c - lam * b / a2), rtol=1e-15, atol=0)
    np.testing.assert_array_equal(M, np.full_like(t, c))


def test_uniform_rotation_rejects_mu():
    P = P4.copy()
    P[6] = 0.1
    with pytest.raises(ValueError, match="mu"):
        uniform_rotation(P, C4, 0.0)


def test_scipy_crossings_uniform_rotation():
    y0 = ref.state_on_section(P4, 0.0, 0.0, 2.0)
    assert y0[2] == pytest.approx(C4, rel=1e-15)
    n = 12
    out = ref.scipy_crossings(P4, y0, n)
    assert out.shape == (n, 5)
    tk = uniform_rotation_crossing_times(P4, C4, n)
    assert np.allclose(tk, 2 * np.pi * P4[2] * np.arange(1, n + 1) / C4, rtol=1e-15)
    assert np.abs(out[:, 0] - tk).max() <= 1e-10
    assert np.abs(out[:, 1:3]).max() == 0.0
    assert np.abs(out[:, 3] - C4).max() <= 1e-12
    assert np.abs(out[:, 4]).max() <= 1e-12


@pytest.mark.parametrize("dg1", [0.0, 1e-15, -1e-15])
def test_scipy_crossings_start_on_section_is_not_a_crossing(dg1):
    y0 = ref.state_on_section(P4, 0.0, 0.0, 2.0)
    y0[3] += dg1  # start on, or within round-off of, the section
    out = ref.scipy_crossings(P4, y0, 2)
    assert len(out) == 2
    assert out[0, 0] == pytest.approx(2 * np.pi * P4[2] / C4, abs=1e-10)
    # (g1, g2) = (0, -1) exactly
    y1 = np.array([0.0, 0.0, C4, 0.0, -1.0])
    out1 = ref.scipy_crossings(P4, y1, 1)
    assert out1[0, 0] == pytest.approx(2 * np.pi * P4[2] / C4, abs=1e-10)
    step = ref.scipy_one_step_map(P4, y0)
    assert step[0] == pytest.approx(out[0, 0], abs=1e-12)


def test_scipy_crossings_direction():
    y0 = ref.state_on_section(P4, 0.0, 0.0, 2.0)
    none = ref.scipy_crossings(P4, y0, 3, direction=-1, t_max=60.0)
    assert none.shape == (0, 5)
    assert ref.scipy_one_step_map(P4, y0, direction=-1, t_max=60.0) is None
    both = ref.scipy_crossings(P4, y0, 3, direction=0, t_max=60.0)
    assert np.abs(both[:, 0] - uniform_rotation_crossing_times(P4, C4, 3)).max() <= 1e-10
    # a body turning the other way (M < 0) crosses with direction -1 only
    y_neg = y0.copy()
    y_neg[2] = -C4
    neg = ref.scipy_crossings(P4, y_neg, 3, direction=-1)
    assert np.abs(neg[:, 0] - uniform_rotation_crossing_times(P4, -C4, 3)).max() <= 1e-10
    assert ref.scipy_crossings(P4, y_neg, 3, direction=+1, t_max=60.0).shape == (0, 5)


def test_scipy_crossings_other_section_and_t_max():
    phi0 = 1.0
    y0 = np.array([0.0, 0.0, C4, np.sin(phi0), np.cos(phi0)])
    out = ref.scipy_crossings(P4, y0, 5, phi0=phi0)
    assert np.abs(out[:, 0] - uniform_rotation_crossing_times(P4, C4, 5)).max() <= 1e-10
    # the pi-shifted section phi0 + pi is reached first, at half a turn
    out_pi = ref.scipy_crossings(P4, y0, 1, phi0=phi0 + np.pi)
    assert out_pi[0, 0] == pytest.approx(np.pi * P4[2] / C4, abs=1e-10)
    # time budget: fewer rows
    T = 2 * np.pi * P4[2] / C4
    assert len(ref.scipy_crossings(P4, y0, 10, phi0=phi0, t_max=3.5 * T)) == 3


@pytest.mark.parametrize("c", [2.3, C4, 3.7])
@pytest.mark.parametrize("sign", [1, -1])
def test_scipy_crossings_follow_homoclinic(c, sign):
    t0, ph0, t_start, t_end = 0.7, 0.3, -20.0, 20.0
    y0, _ = hstate(P4, c, t_start, sign=sign, t0=t0, phi_at_t0=ph0)
    ts = homoclinic_crossing_times(P4, c, np.pi, t_start, t_end, sign=sign,
                                   t0=t0, phi_at_t0=ph0)
    assert len(ts) >= 5
    out = ref.scipy_crossings(P4, y0, len(ts) + 5, t0=t_start, t_max=t_end)
    assert len(out) == len(ts)
    assert np.abs(out[:, 0] - ts).max() <= 1e-8
    p1, p2, M, _ = homoclinic(P4, c, out[:, 0], sign=sign, t0=t0, phi_at_t0=ph0)
    assert np.abs(out[:, 1] - p1).max() <= 1e-8
    assert np.abs(out[:, 2] - p2).max() <= 1e-8
    assert np.abs(out[:, 3] - M).max() <= 1e-8
    assert np.abs(out[:, 4]).max() <= 1e-12
    # no crossing with phi decreasing (M > 0 along the orbit)
    assert len(ref.scipy_crossings(P4, y0, 3, direction=-1, t0=t_start, t_max=t_end)) == 0


# ---------------------------------------------------------------------------
# the reference itself: energy / F conservation, section states
# ---------------------------------------------------------------------------
def test_reference_rhs_conserves_H_and_F():
    from scipy.integrate import solve_ivp

    # mu = 0 with s != 0: H and Chaplygin's F (R5.1) conserved
    P = np.array([1.0, 0.5, 2.0, 1.0, 0.3, -0.2, 0.0, 0.4, 0.1])
    y0 = np.array([0.4, -0.3, 1.1, np.sin(0.2), np.cos(0.2)])
    sol = solve_ivp(lambda t, y: ref.rhs_numpy(t, y, P), (0, 30), y0, method="DOP853",
                    rtol=1e-12, atol=1e-12)
    assert np.abs(ref.energy_numpy(sol.y, P) - ref.energy_numpy(y0, P)).max() <= 1e-9
    assert np.abs(chaplygin_F(P, sol.y) - chaplygin_F(P, y0)).max() <= 1e-9
    # mu != 0: H conserved, F is not
    P = np.array([1.0, 0.5, 2.0, 1.0, 0.3, -0.2, 0.7, 0.4, 0.1])
    sol = solve_ivp(lambda t, y: ref.rhs_numpy(t, y, P), (0, 30), y0, method="DOP853",
                    rtol=1e-12, atol=1e-12)
    assert np.abs(ref.energy_numpy(sol.y, P) - ref.energy_numpy(y0, P)).max() <= 1e-9
    assert np.abs(chaplygin_F(P, sol.y) - chaplygin_F(P, y0)).max() > 1e-3
    assert np.abs(sol.y[3] ** 2 + sol.y[4] ** 2 - 1).max() <= 1e-9


def test_state_on_section():
    # R9 at phi0 = pi with mu != 0
    P = np.array([1.0, 0.5, 2.0, 1.0, 0.1, 0.05, 0.3, 0.2, 0.15])
    p1, p2, h = 0.3, -0.4, 2.0
    y = ref.state_on_section(P, p1, p2, h)
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P
    M9 = np.sqrt(2 * b * (h - 0.5 * (p1**2 / a1 + p2**2 / a2) - (mu / lam) * (p1 - chi) + mu * eta))
    assert y[2] == pytest.approx(M9, rel=1e-13)
    assert ref.energy_numpy(y, P) == pytest.approx(h, abs=1e-14)
    # other phi0
    y = ref.state_on_section(P, p1, p2, h, phi0=0.8)
    assert ref.energy_numpy(y, P) == pytest.approx(h, abs=1e-14) and y[2] > 0
    assert (y[3], y[4]) == (np.sin(0.8), np.cos(0.8))
    with pytest.raises(ValueError):
        ref.state_on_section(P4, 3.0, 0.0, 2.0)
    with pytest.raises(ValueError):
        ref.scipy_one_step_map(P4, np.array([0.0, 0.0, C4, 1.0, 0.0]))


def test_one_step_map_mu_positive_conserves_H():
    P = np.array([1.0, 0.5, 2.0, 1.0, 0.0, 0.0, 0.2, 0.0, 0.0])
    y = ref.state_on_section(P, 0.1, 0.2, 2.0)
    h0 = ref.energy_numpy(y, P)
    for _ in range(5):
        row = ref.scipy_one_step_map(P, y)
        assert row is not None and row[0] > 0
        y = np.array([row[1], row[2], row[3], np.sin(np.pi), np.cos(np.pi)])
        assert abs(ref.energy_numpy(y, P) - h0) <= 1e-11
