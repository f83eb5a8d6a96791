"""Chaos indicators: tangent dynamics against finite differences, regular and chaotic orbits,
agreement between integrators, a known map's exponent, the CLI."""
import json
import math

import numpy as np
import pytest
from conftest import PARAM_SETS, random_states

from explorer import model
from explorer._jit import njit
from explorer.analysis import lyapunov, sections
from explorer.app import cli
from explorer.integrate import _lanes_generated as generated
from explorer.integrate import _tangent_lanes_generated as generated_tangent
from explorer.kernels import STATUS_DONE
from explorer.kernels import tangent as tg
from explorer.model import equations

FD = 1e-6


def field_fd(P, y, v):
    out_p = np.empty(5)
    out_m = np.empty(5)
    equations.rhs(y + FD * v, P, out_p)
    equations.rhs(y - FD * v, P, out_m)
    return (out_p - out_m) / (2 * FD)


@pytest.mark.parametrize("name", sorted(PARAM_SETS))
def test_variational_field_is_the_jacobian_of_the_field(name):
    P = PARAM_SETS[name].as_array()
    rng = np.random.default_rng(1)
    for y in random_states(PARAM_SETS[name], 10, seed=3):
        v = rng.normal(size=5)
        dv = np.empty(5)
        equations.rhs_tangent(y, v, P, dv)
        np.testing.assert_allclose(dv, field_fd(P, y, v), atol=1e-8)


@pytest.mark.parametrize("k", range(4))
@pytest.mark.parametrize("t", [0.05, 0.7])
def test_tangent_map_of_each_subflow_matches_finite_differences(k, t):
    P = PARAM_SETS["asym_lam_neg"].as_array()
    y = random_states(PARAM_SETS["asym_lam_neg"], 1, seed=4)[0]
    v = np.array([0.3, -0.7, 0.5, 0.2, 0.4])
    yp, ym = y + FD * v, y - FD * v
    equations.apply_flow(k, yp, P, t)
    equations.apply_flow(k, ym, P, t)
    fd = (yp - ym) / (2 * FD)
    yy, vv = y.copy(), v.copy()
    equations.apply_flow_tangent(k, yy, vv, P, t)
    np.testing.assert_allclose(vv, fd, atol=1e-8)
    y2 = y.copy()
    equations.apply_flow(k, y2, P, t)
    np.testing.assert_array_equal(yy, y2)  # the orbit itself is advanced by the same flow


def test_tangent_taylor_series_matches_finite_differences_of_the_series():
    from explorer.kernels import taylor

    P = PARAM_SETS["asym_lam_pos"].as_array()
    y = random_states(PARAM_SETS["asym_lam_pos"], 1, seed=5)[0]
    v = np.array([0.1, 0.4, -0.3, 0.6, -0.2])
    order, h = 25, 0.1
    XD = np.zeros((10, order + 1))   # the orbit and the vector (generated from explorer.model.chaplygin)
    XD[:5, 0], XD[5:, 0] = y, v
    generated_tangent.tangent_coefficients(P, XD, order)
    X, D = XD[:5], XD[5:]
    out = {}
    for sgn in (1, -1):
        Z = np.zeros((5, order + 1))
        Z[:, 0] = y + sgn * FD * v
        generated.taylor_coefficients(P, Z, order)
        out[sgn] = np.empty(5)
        taylor.evaluate(Z, order, h, out[sgn])
    dv = np.empty(5)
    taylor.evaluate(D, order, h, dv)
    np.testing.assert_allclose(dv, (out[1] - out[-1]) / (2 * FD), atol=1e-7)
    # and the state part is exactly the plain recurrence
    X2 = np.zeros((5, order + 1))
    X2[:, 0] = y
    generated.taylor_coefficients(P, X2, order)
    np.testing.assert_array_equal(X, X2)


@pytest.mark.parametrize("method,kw", [("taylor", dict(tol=1e-15)), ("dop853", dict(tol=1e-13)),
                                       ("split8", dict(dt=1 / 64)), ("split4", dict(dt=1 / 256))])
def test_stretch_over_a_time_unit_matches_finite_differences_of_the_flow(method, kw):
    """ln |delta(t)| from the tangent dynamics against central differences of the flow, t = 2."""
    prm = PARAM_SETS["figure4_mu0.5"]
    y0 = model.section_state(prm, [0.2], [0.3], 2.0)
    v0 = lyapunov.deviation_vector(prm, y0)
    T = 2.0
    r = lyapunov.indicators(prm, states=y0, tmax=T, method=method, **kw)
    ends = []
    for sgn in (1, -1):
        c = sections.crossings(prm, states=y0 + sgn * FD * v0, n_crossings=50, method=method, tmax=T, direction=0,
                               phi0=0.123, **kw)
        assert c.info[0, 0] == pytest.approx(T)
        ends.append(c.final[0])
    growth = np.linalg.norm((ends[0] - ends[1]) / (2 * FD))
    assert r.mlce[0] * T == pytest.approx(math.log(growth), abs=2e-6)


def test_deviation_vector_is_tangent_to_energy_shell_and_casimir():
    prm = PARAM_SETS["asym_lam_neg"]
    y = random_states(prm, 20, seed=6)
    v = lyapunov.deviation_vector(prm, y)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0)
    np.testing.assert_allclose(np.sum(v * model.energy_gradient(prm, y), axis=1), 0.0, atol=1e-14)
    np.testing.assert_allclose(v[:, 3] * y[:, 3] + v[:, 4] * y[:, 4], 0.0, atol=1e-14)
    # the analytic gradient is the gradient of model.energy
    for yi in y[:3]:
        g = np.array([(model.energy(prm, yi + 1e-6 * e) - model.energy(prm, yi - 1e-6 * e)) / 2e-6 for e in np.eye(5)])
        np.testing.assert_allclose(model.energy_gradient(prm, yi), g, atol=1e-8)


REGULAR = ([0.6, 0.0, -0.5, 1.8], [0.5, 1.0, 0.8, 0.1])


@pytest.mark.parametrize("method,kw", [("taylor", dict(tol=1e-12)), ("split6", dict(dt=0.05))])
def test_regular_orbits_of_the_integrable_case_have_small_exponent_and_megno_2(method, kw):
    """Chaplygin's case mu = 0 is integrable: chi(T) <= 3 ln T / T and <Y> -> 2 +- 0.2 (T = 1e4)."""
    prm = model.FIGURE4
    y0 = model.section_state(prm, *REGULAR, 2.0)
    T = 1e4
    r = lyapunov.indicators(prm, states=y0, tmax=T, method=method, **kw)
    assert np.all(r.status == STATUS_DONE)
    assert np.all(r.mlce <= lyapunov.regular_bound(T))
    np.testing.assert_allclose(r.megno, 2.0, atol=0.2)


def test_kozlov_case_is_regular_too():
    prm = model.Params(a1=0.7, a2=0.7, b=1.7, lam=1.3, mu=0.9, xi=0.3, eta=-0.25)
    c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
    y0 = model.section_state(prm, [c1 + 0.3 * r1, c1 - 0.4 * r1], [c2 + 0.2 * r2, c2 - 0.1 * r2], 2.0)
    r = lyapunov.indicators(prm, states=y0, tmax=1e4, method="taylor", tol=1e-12)
    assert np.all(r.mlce <= lyapunov.regular_bound(1e4))
    # quasi-periodic orbits: <Y> -> 2 from either side (measured 1.998, 1.999); a stable
    # periodic orbit would give 0, a chaotic one grows like chi T / 2
    assert np.all((r.megno > 1.8) & (r.megno < 2.2)), r.megno


def test_megno_tends_to_0_on_a_stable_periodic_orbit_and_to_2_on_the_tori_around_it():
    """Cincotta & Simo (2000): <Y> -> 0 on a stable periodic orbit (the deviation vector, tangent
    to the energy shell, only rotates), -> 2 on a torus (the shear between neighbouring tori
    makes it grow linearly), ~ chi T/2 on a chaotic orbit (tested below).  At mu = 0 solution II
    of R6, (sqrt 2, 0) on the section, is an exact stable periodic orbit: <Y> -> 0 while the
    torus through (1.7, 0) is at 2.  Inside the island of the elliptic point (1.582201141, 0) at
    mu = 0.03 the torus through (1.5, 0) has <Y> ~ 0 for T = 4000 and climbs towards 2 only
    later than the wider torus through (1.4, 0): the closer a torus to the periodic orbit, the
    weaker the shear and the longer <Y> stays near 0 (as the 0.29 reported inside an island)."""
    prm = model.FIGURE4
    y0 = model.section_state(prm, [math.sqrt(2.0), 1.7], [0.0, 0.0], 2.0)
    r = lyapunov.indicators(prm, states=y0, tmax=16000.0, method="taylor", tol=1e-13)
    assert abs(r.megno[0]) < 1e-3 and abs(r.megno[1] - 2.0) < 0.05, r.megno
    prm = model.FIGURE4.with_(mu=0.03)
    y0 = model.section_state(prm, [1.582201141, 1.5, 1.4], [0.0, 0.0, 0.0], 2.0)
    Y = np.array([lyapunov.indicators(prm, states=y0, tmax=T, method="taylor", tol=1e-13).megno
                  for T in (4000.0, 64000.0)])
    assert np.all(np.abs(Y[:, 0]) < 0.01) and abs(Y[1, 0]) < abs(Y[0, 0]), Y[:, 0]    # the periodic orbit
    assert np.all(Y[1, 1:] > Y[0, 1:]) and np.all(Y[:, 1] < Y[:, 2]), Y                # the tori, inner slower
    assert Y[0, 1] < 0.1 and Y[1, 2] > 1.5, Y


CHAOTIC = ([0.0, 0.3, -0.4, 0.2], [0.3, -0.2, 0.1, 0.5])


def test_chaotic_orbits_have_a_positive_converged_exponent_that_integrators_agree_on():
    """mu = 0.5 (Figure 4's chaotic sea): chi > 0, stable between T/2 and T, the same from
    DOP853 (variational equations) and from split8 (exact tangent maps), and <Y> ~ chi T/2.
    Held orbit by orbit: the finite-time exponents of one chaotic orbit fluctuate by
    ~ 1/sqrt(T) (measured: integrators 4-16 % apart, T/2 against T 0.4-8 %), so each orbit
    within 20 % (integrators) and 10 % (T/2), and the mean of the four within 10 %."""
    prm = PARAM_SETS["figure4_mu0.5"]
    y0 = model.section_state(prm, *CHAOTIC, 2.0)
    T = 2e4
    d = lyapunov.indicators(prm, states=y0, tmax=T, method="dop853", tol=1e-12, history=8)
    s = lyapunov.indicators(prm, states=y0, tmax=T, method="split8", dt=0.05)
    assert np.all(d.mlce > 0.1)
    # the history ends at T with the final values
    np.testing.assert_allclose(d.history[:, -1, 1], d.mlce)
    mean_d, mean_s = d.mlce.mean(), s.mlce.mean()
    assert abs(mean_d - mean_s) < 0.1 * mean_d
    assert np.all(np.abs(d.mlce - s.mlce) < 0.2 * d.mlce), (d.mlce, s.mlce)
    d_half = lyapunov.indicators(prm, states=y0, tmax=T / 2, method="dop853", tol=1e-12)
    assert abs(d_half.mlce.mean() - mean_d) < 0.1 * mean_d
    assert np.all(np.abs(d_half.mlce - d.mlce) < 0.1 * d.mlce), (d_half.mlce, d.mlce)
    np.testing.assert_allclose(d.megno, d.mlce * T / 2, rtol=0.15)


@njit
def _standard_map_exponent(K, x, p, n):
    acc = np.zeros(tg.N_ACC)
    v = np.array([1.0, 0.0])
    for i in range(n):
        # p' = p + K sin x, x' = x + p'; tangent: dp' = dp + K cos x dx, dx' = dx + dp'
        c = K * math.cos(x)
        dp = v[1] + c * v[0]
        dx = v[0] + dp
        p = p + K * math.sin(x)
        x = x + p
        v[0] = dx
        v[1] = dp
        tg.accumulate(acc, float(i), float(i + 1), tg.renormalize(v, 2))
    out = np.empty(tg.N_RES)
    tg.result(acc, out)
    return out


def test_indicator_kernels_give_the_standard_map_exponent():
    """Chirikov's standard map, K = 10: lambda ~ ln(K/2) = 1.609 (1.620 measured at 2e5 iterations)."""
    out = _standard_map_exponent(10.0, 0.3, 0.1, 200000)
    assert out[tg.RES_MLCE] == pytest.approx(math.log(5.0), rel=0.02)


def test_lyapunov_cli_json(capsys):
    code = cli.main(["lyapunov", "--p1", "0", "--p2", "0.3", "--mu", "0.5", "--tmax", "500", "--json"])
    out, _ = capsys.readouterr()
    assert code == 0
    doc = json.loads(out)
    assert {"mlce", "megno", "time", "fli", "history"} <= set(doc)
    assert doc["time"] == 500.0 and doc["mlce"] > 0.05 and doc["megno"] > 10


@pytest.mark.parametrize("args,fragment", [
    (["--p1", "0", "--p2", "0", "--tmax", "-1"], "tmax must be"),
    (["--p1", "9", "--p2", "0"], "outside the allowed region"),
    (["--p1", "0", "--p2", "0", "--method", "rk4"], "method must be"),
    (["--p1", "0", "--p2", "0", "--lam", "0"], "lam must be nonzero"),
])
def test_lyapunov_cli_bad_input(args, fragment, capsys):
    code = cli.main(["lyapunov"] + args)
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1 and fragment in err


def test_lyapunov_cli_reports_an_orbit_that_stopped_without_inventing_numbers(capsys, monkeypatch):
    """An orbit stopped at t = 0 (here: a step budget of zero steps) has no estimate: the JSON
    gives null, never 0.0, and stderr says why in one line; one stopped later gives the
    estimates over the time it reached and says so."""
    real = lyapunov.indicators

    def budget(steps):
        def run(*args, **kw):
            kw["max_steps"] = steps
            return real(*args, **kw)
        return run

    monkeypatch.setattr(lyapunov, "indicators", budget(0))
    code = cli.main(["lyapunov", "--p1", "0", "--p2", "0.3", "--mu", "0.5", "--tmax", "50", "--json"])
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert code == 0 and doc["status"] == "step budget exhausted" and doc["time"] == 0.0
    assert doc["mlce"] is None and doc["megno"] is None and doc["fli"] is None
    assert len(err.strip().splitlines()) == 1 and "no estimate" in err
    monkeypatch.setattr(lyapunov, "indicators", budget(200))
    code = cli.main(["lyapunov", "--p1", "0", "--p2", "0.3", "--mu", "0.5", "--tmax", "1e4", "--json"])
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert 0 < doc["time"] < 1e4 and math.isfinite(doc["mlce"])
    assert "the estimates cover [0, " in err and "step budget exhausted" in err


def test_every_indicator_of_the_registry_is_a_declared_attribute_of_the_result_read_from_its_values():
    """No attribute magic: each registry name is declared on the class (visible to an IDE) and
    returns that indicator's column, and an unknown name is an AttributeError."""
    prm = model.FIGURE4.with_(mu=0.5)
    res = lyapunov.indicators(prm, states=model.section_state(prm, [0.1], [0.0], 2.0), tmax=5.0)
    for name in lyapunov.INDICATOR_NAMES:
        assert name in vars(lyapunov.Indicators), name
        assert getattr(res, name) is res.values[name]
    with pytest.raises(AttributeError):
        res.no_such_indicator  # noqa: B018
