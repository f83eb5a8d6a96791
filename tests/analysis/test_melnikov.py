"""The Melnikov integral ur23 along R7 (docs/model.md R8), ur24, and the splitting measured on the section."""
import json
import math

import numpy as np
import pytest
from conftest import PARAM_SETS, random_states
from scipy import integrate

from explorer import model
from explorer.analysis import melnikov
from explorer.app import cli, melnikov_figure
from explorer.model import exact

FIG4 = model.FIGURE4
H = model.FIGURE4_H
C = math.sqrt(2 * FIG4.b * H)
#: a second scene (lam != 1, b != 2, xi, eta != 0), c inside the band and below 2 lam b/a1
OTHER = model.Params(a1=1.5, a2=0.6, b=1.3, lam=0.8, xi=0.25, eta=0.4)
OTHER_C = 1.1
OTHER_H = OTHER_C ** 2 / (2 * OTHER.b)


# ---------------------------------------------------------------- the bracket R8
def _bracket_R8(prm, y):
    """docs/model.md R8: {F0, H1} = -((p - s), gamma)/lam - (xi g2 - eta g1), gamma = (g1, g2)."""
    p1, p2 = y[..., model.P1] - prm.chi, y[..., model.P2] - prm.zeta
    g1, g2 = y[..., model.G1], y[..., model.G2]
    return -(p1 * g1 + p2 * g2) / prm.lam - (prm.xi * g2 - prm.eta * g1)


def _grad_F0(prm, y, seed_typo=False):
    """grad of F0 = M + |p - s|^2/(2 lam) (R6), or of the seed's M^2 + |p|^2/(2 lam)."""
    g = np.zeros_like(y)
    s = (0.0, 0.0) if seed_typo else (prm.chi, prm.zeta)
    g[..., model.P1] = (y[..., model.P1] - s[0]) / prm.lam
    g[..., model.P2] = (y[..., model.P2] - s[1]) / prm.lam
    g[..., model.M] = 2.0 * y[..., model.M] if seed_typo else 1.0
    return g


def _homoclinic_states(prm, c, t, g0, sign=1):
    """States (..., 5) of the orbit (sign, g0) of R7, centred at t = 0 with phi(0) = g0."""
    p1, p2, M, phi = exact.homoclinic(prm.with_(mu=0.0).as_array(), c, t, sign, 0.0, g0)
    return np.stack([p1, p2, M, np.sin(phi), np.cos(phi)], axis=-1)


@pytest.mark.parametrize("name", sorted(PARAM_SETS))
def test_bracket_formula_equals_first_order_rate_of_F0_along_the_field(name):
    """R8 against grad F0 . (f(mu) - f(0))/mu from the field model.rhs (R3, affine in mu)."""
    prm = PARAM_SETS[name]
    y = random_states(prm, 200, seed=3)
    formula = _bracket_R8(prm, y)
    for mu in (1.0, 0.37, 1e-3):
        df = (model.rhs(prm.with_(mu=mu), y) - model.rhs(prm.with_(mu=0.0), y)) / mu
        field = np.sum(_grad_F0(prm, y) * df, axis=-1)
        np.testing.assert_allclose(field, formula, rtol=1e-9, atol=1e-9 * (1 + np.abs(formula).max()))
    # F0 is conserved by the unperturbed field (mu = 0), so dF0/dt = mu {F0, H1} exactly
    f0 = model.rhs(prm.with_(mu=0.0), y)
    assert np.max(np.abs(np.sum(_grad_F0(prm, y) * f0, axis=-1))) < 1e-12
    f = model.rhs(prm, y)
    np.testing.assert_allclose(np.sum(_grad_F0(prm, y) * f, axis=-1), prm.mu * formula,
                               rtol=1e-12, atol=1e-12)


def test_integrand_is_the_bracket_along_the_orbit_when_xi_eta_vanish():
    """Without the (xi, eta)-term the regularised integrand is the bare bracket R8 on R7."""
    t = np.linspace(-20, 20, 81)
    for s in (1, -1):
        y = _homoclinic_states(FIG4, C, t, 0.3, s)
        np.testing.assert_allclose(melnikov.integrand(FIG4, C, t, 0.3, s), _bracket_R8(FIG4, y),
                                   rtol=1e-12, atol=1e-14)


def test_seed_F0_with_M_squared_is_not_an_integral():
    prm = FIG4
    y = random_states(prm, 50, seed=5)
    rate = np.sum(_grad_F0(prm, y, seed_typo=True) * model.rhs(prm, y), axis=-1)
    assert np.max(np.abs(rate)) > 0.1
    # and along the homoclinic orbit it changes by O(1), while F0 (R6) stays
    t = np.linspace(-20, 20, 401)
    y = _homoclinic_states(prm, C, t, 0.3)
    Fs = y[..., model.M] ** 2 + (y[..., model.P1] ** 2 + y[..., model.P2] ** 2) / (2.0 * prm.lam)
    F = melnikov.F0(prm, y)
    assert np.ptp(F) < 1e-12 and np.ptp(Fs) > 1.0


# ---------------------------------------------------------------- quadrature
def _quad_sum(f, edges):
    """Sum of adaptive quadratures over consecutive intervals (round-off warnings silenced)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", integrate.IntegrationWarning)
        return sum(integrate.quad(f, a, b, epsabs=1e-15, epsrel=1e-13, limit=200)[0]
                   for a, b in zip(edges[:-1], edges[1:]))


def test_quadrature_converged_two_windows_and_two_methods():
    g0 = np.array([0.3, 1.0, 2.2, 4.0])
    for prm, c in ((FIG4.with_(xi=0.3, eta=-0.2), C), (OTHER, OTHER_C)):
        for s in (1, -1):
            a = melnikov.melnikov_integral(prm, c, g0, s, window=40.0)
            b = melnikov.melnikov_integral(prm, c, g0, s, window=50.0)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-10)
            q = np.array([melnikov.melnikov_integral(prm, c, g, s, window=50.0, method="quad") for g in g0[:2]])
            np.testing.assert_allclose(a[:2], q, rtol=0, atol=1e-10)
    # the test can fail: a window of 5 e-folds is visibly too short
    short = melnikov.melnikov_integral(FIG4, C, 1.0, 1, window=5.0)
    assert abs(short - melnikov.melnikov_integral(FIG4, C, 1.0, 1)) > 1e-4


def test_regularised_integrand_equals_limit_between_section_crossings():
    """The (xi, eta)-term does not decay: J is the limit of the integral of the bare bracket R8
    between crossings of phi = pi; the (1 - M/c) form must give the same number."""
    prm = FIG4.with_(xi=0.3, eta=-0.2)
    P0 = prm.as_array()
    g0, s = 0.7, 1
    tc = exact.homoclinic_crossing_times(P0, C, math.pi, -90.0, 90.0, s, 0.0, g0)
    lo, hi = tc[0], tc[-1]
    assert lo < -80 and hi > 80

    def bare(t):
        return float(_bracket_R8(prm, _homoclinic_states(prm, C, t, g0, s)))

    total = _quad_sum(bare, np.linspace(lo, hi, 200))
    J = melnikov.melnikov_integral(prm, C, g0, s)
    assert abs(total - J) < 1e-9
    # between crossings of phi = 0 (another section) as well; but not between arbitrary times
    t0 = exact.homoclinic_crossing_times(P0, C, 0.0, -90.0, 90.0, s, 0.0, g0)
    total0 = _quad_sum(bare, np.linspace(t0[0], t0[-1], 200))
    assert abs(total0 - J) < 1e-9
    off = _quad_sum(bare, np.linspace(lo, tc[-1] + 1.0, 200))
    assert abs(off - J) > 1e-3


def test_J_is_proportional_to_sin_g0_when_xi_eta_vanish():
    for prm, c in ((FIG4, C), (OTHER.with_(xi=0.0, eta=0.0), OTHER_C)):
        A, B, C0, res = melnikov.fit_harmonics(prm, c, 1)
        assert res < 1e-10 and abs(B) < 1e-12 and abs(C0) < 1e-12 and abs(A) > 0.1
        g0 = np.linspace(0, 2 * math.pi, 37)
        J = melnikov.melnikov_integral(prm, c, g0, 1)
        assert np.max(np.abs(J - A * np.sin(g0))) < 1e-10
        # the other separatrix (p -> -p): J changes sign
        np.testing.assert_allclose(melnikov.melnikov_integral(prm, c, g0, -1), -J, rtol=0, atol=1e-12)


def test_general_xi_eta_is_a_first_harmonic():
    A, B, C0, res = melnikov.fit_harmonics(OTHER, OTHER_C, -1)
    assert res < 1e-10 and abs(C0) < 1e-12 and abs(B) > 0.1


@pytest.mark.parametrize("prm,c", [(FIG4, C), (FIG4.with_(xi=0.3, eta=-0.2), C), (OTHER, OTHER_C),
                                   (OTHER, 0.75), (OTHER, 1.7)])
def test_corrected_closed_form_matches_quadrature(prm, c):
    cf = melnikov.closed_form(prm, c)
    for s, key in ((1, "sin_plus"), (-1, "sin_minus")):
        A, B, _, _ = melnikov.fit_harmonics(prm, c, s)
        scale = max(1e-3, abs(A), abs(B))
        assert abs(A - cf[key]) < 1e-9 * scale and abs(B - cf["cos"]) < 1e-9 * scale


@pytest.mark.parametrize("prm,c", [(FIG4.with_(xi=0.3, eta=-0.2), C), (OTHER, OTHER_C)])
def test_ur24_as_printed_does_not_hold(prm, c):
    u = melnikov.ur24(prm, c)
    cf = melnikov.closed_form(prm, c)
    hc = melnikov.homoclinic_constants(prm, c)
    # same prefactors and angular dependence, but about half the size:
    bS, pS = hc.beta * hc.S, math.pi * hc.S
    assert u["AQ"] / cf["AQ"] == pytest.approx((1 - math.exp(-2 * bS)) / (2 * (1 - math.exp(-pS))), rel=1e-12)
    assert u["AR"] / cf["AR"] == pytest.approx((1 + math.exp(-2 * bS)) / (2 * (1 + math.exp(-pS))), rel=1e-12)
    out = melnikov.amplitudes(prm, c * c / (2 * prm.b))
    assert out["ur24_holds"] is False
    assert 0.4 < out["ur24_ratio"] < 0.6


# ---------------------------------------------------------------- splitting on the section
def test_separatrix_point_is_on_the_unperturbed_separatrix():
    for g0 in (0.5, math.pi, 4.0):
        for s in (1, -1):
            x, tc, n = melnikov.separatrix_point(FIG4, H, g0, s)
            y = model.section_state(FIG4, [x[0]], [x[1]], H)[0]
            assert abs(melnikov.F0(FIG4, y) - C) < 1e-12
            assert abs(np.linalg.norm(n) - 1) < 1e-14
    x, tc, _ = melnikov.separatrix_point(FIG4, H, math.pi, 1)
    assert abs(tc) < 1e-14 and abs(x[1]) < 1e-14 and x[0] > 0


def _richardson(rows):
    """Linear extrapolation mu -> 0 of the ratio from the two smallest mu."""
    r = sorted(rows, key=lambda q: q["mu"])
    m1, m2 = r[0]["mu"], r[1]["mu"]
    return (m2 * r[0]["ratio"] - m1 * r[1]["ratio"]) / (m2 - m1)


@pytest.mark.parametrize("sign", [1, -1])
def test_measured_splitting_approaches_mu_J(sign):
    rows = melnikov.melnikov_table(FIG4, H, (1e-4, 3e-4, 1e-3, 3e-3), (0.5 * math.pi,), (sign,))
    err = [abs(r["ratio"] - 1) for r in rows]
    assert err[0] < 0.05 and err[0] < 2e-3
    assert all(a < b for a, b in zip(err[:-1], err[1:]))            # decreasing with mu
    assert all(0.3 < e / r["mu"] < 3 for e, r in zip(err, rows))      # O(mu)
    assert abs(_richardson(rows) - 1) < 1e-4
    assert all(np.sign(r["measured"]) == np.sign(r["predicted"]) for r in rows)


def test_measured_splitting_with_centre_of_mass_offset_checks_J_R():
    prm = FIG4.with_(xi=0.3, eta=-0.2)
    for g0, s in ((0.0, 1), (2.5, -1)):
        rows = melnikov.melnikov_table(prm, H, (1e-4, 3e-4), (g0,), (s,))
        assert abs(rows[0]["ratio"] - 1) < 5e-3
        assert abs(_richardson(rows) - 1) < 1e-4
    rows = melnikov.melnikov_table(OTHER, OTHER_H, (1e-4, 3e-4), (0.7,), (1, -1))
    for s in (1, -1):
        r = [q for q in rows if q["sign"] == s]
        assert abs(r[0]["ratio"] - 1) < 0.01 and abs(_richardson(r) - 1) < 1e-4


def test_no_splitting_at_the_symmetric_point():
    """g0 = pi is the centre of the lobe (p2 = 0): J(pi) = 0 and the manifolds intersect there."""
    r = melnikov.measured_splitting(FIG4, H, 1e-3, math.pi, 1)
    assert abs(r["predicted"]) < 1e-15 and abs(r["measured"]) < 1e-9


# ---------------------------------------------------------------- figure and CLI
def test_figure_has_three_panels():
    fig = melnikov_figure.melnikov_figure(mus=(1e-4, 1e-3), n_measured=4)
    assert len(fig.axes) == 3
    assert len(fig.axes[0].lines) >= 7


def run_cli(args, capsys):
    code = cli.main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_json_keys(capsys):
    code, out, err = run_cli(["melnikov", "--json"], capsys)
    assert code == 0, err
    doc = json.loads(out)
    assert set(doc) >= {"amplitude_plus", "amplitude_minus", "ur24", "ur24_holds", "c", "h",
                        "sin_plus", "cos_plus", "sin_minus", "cos_minus"}
    assert doc["c"] == pytest.approx(2 * math.sqrt(2), rel=1e-15) and doc["h"] == 2.0
    assert doc["ur24_holds"] is False
    assert doc["amplitude_plus"] == pytest.approx(-doc["amplitude_minus"], rel=1e-12)
    assert doc["amplitude_plus"] == pytest.approx(melnikov.closed_form(FIG4, C)["sin_plus"], rel=1e-10)
    code, out, _ = run_cli(["melnikov", "--json", "--xi", "0.3", "--eta", "-0.2"], capsys)
    doc = json.loads(out)
    assert abs(doc["cos_plus"]) > 0.1 and doc["cos_plus"] == pytest.approx(doc["cos_minus"], rel=1e-12)


@pytest.mark.cpu_dependent
def test_cli_text_and_splitting(capsys):
    code, out, err = run_cli(["melnikov", "--splitting", "--mus", "1e-4,1e-3"], capsys)
    assert code == 0, err
    assert "does NOT hold" in out and "sign,g0,mu,measured,mu*J,ratio" in out


@pytest.mark.parametrize("args,fragment", [
    (["--h", "5"], "lam b/a1 < c < lam b/a2"),
    (["--h", "0.5"], "lam b/a1 < c < lam b/a2"),
    (["--a1", "0.4"], "a1 > a2"),
    (["--lam", "-1"], "lam > 0"),
    (["--chi", "0.1"], "chi = zeta = 0"),
    (["--zeta", "-0.2"], "chi = zeta = 0"),
    (["--h", "-1"], "h must be finite and > 0"),
    (["--splitting", "--mus", "1e-3,x"], "--mus must be"),
])
def test_cli_bad_input_is_one_line_exit_2(args, fragment, capsys):
    code, out, err = run_cli(["melnikov"] + args, capsys)
    assert code == 2 and out == ""
    assert err.startswith("explorer: error: ") and fragment in err and err.count("\n") == 1
