"""The body in the plane (docs/model.md R1, R2, ur25; Kozlov's falling body): explorer.trajectory."""
import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from explorer import model
from explorer.analysis import trajectory as tr
from explorer.app import cli, trajectory_figure
from explorer.model import equations

FIG4 = dict(model.FIGURE4.as_dict(), mu=0.5)
#: parameter sets of the full system (lam = 0 allowed); asymmetric ones as in conftest.PARAM_SETS
SETS = {
    "figure4_mu0.5": FIG4,
    "asym_lam_neg": dict(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=-0.15, mu=0.7, xi=0.3, eta=-0.25),
    "asym_lam_pos": dict(a1=0.8, a2=1.4, b=2.5, lam=1.6, chi=-0.3, zeta=0.25, mu=1.2, xi=-0.2, eta=0.4),
    "falling_lam0": dict(FIG4, lam=0.0),
    "falling_asym": dict(a1=0.8, a2=1.4, b=2.5, lam=0.0, chi=0.0, zeta=0.0, mu=1.2, xi=-0.2, eta=0.4),
}
START = (0.3, -0.4, 1.0, 2.0)  # p1, p2, M, phi


def _P(prm):
    return np.array([prm[n] for n in model.PARAM_NAMES])


# ---------------------------------------------------------------- independent reference (docs/model.md R1)
def r1_trig(t, u, P):
    """R1 verbatim, state (p1, p2, M, phi, x, y), written from docs/model.md (no project code)."""
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P
    p1, p2, m, phi, x, y = u
    s, c = math.sin(phi), math.cos(phi)
    return [(m / b) * (p2 - zeta) - mu * s - lam * p2 / a2,
            -(m / b) * (p1 - chi) - mu * c + lam * p1 / a1,
            (p1 - chi) * p2 / a2 - (p2 - zeta) * p1 / a1 - mu * (xi * c - eta * s),
            m / b,
            (p1 / a1) * c - (p2 / a2) * s,
            (p1 / a1) * s + (p2 / a2) * c]


def integrals_trig(u, P, t):
    """H (R1), p_x, p_y + mu t (R2) in the trig form."""
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P
    p1, p2, m, phi, x, y = u
    s, c = np.sin(phi), np.cos(phi)
    H = 0.5 * (p1 ** 2 / a1 + p2 ** 2 / a2 + m ** 2 / b) + mu * (y + xi * s + eta * c)
    px = p1 * c - p2 * s + lam * y + zeta * s - chi * c
    py = p1 * s + p2 * c - lam * x - zeta * c - chi * s
    return H, px, py + mu * t


# ---------------------------------------------------------------- the field and the integrals
@pytest.mark.parametrize("name", sorted(SETS))
def test_polynomial_field_equals_R1_and_integrals_have_the_right_rates(name):
    prm = SETS[name]
    P = _P(prm)
    rng = np.random.default_rng(1)
    for _ in range(50):
        p1, p2, m, phi, x, y = rng.normal(size=6) * 2
        u = np.array([p1, p2, m, phi, x, y])
        ypoly = tr.initial_state(prm, p1, p2, m, phi, x, y)
        d = np.empty(7)
        equations.rhs_full(ypoly, P, d)
        ref = r1_trig(0.0, u, P)
        np.testing.assert_allclose(d[[0, 1, 2, 5, 6]], np.array(ref)[[0, 1, 2, 4, 5]], rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(d[3:5], ref[3] * np.array([math.cos(phi), -math.sin(phi)]), atol=1e-13)
        # rates of H, p_x, p_y + mu t along the field (central differences in time): all zero
        eps = 1e-5
        up, um = u + eps * np.array(ref), u - eps * np.array(ref)
        rates = (np.array(integrals_trig(up, P, eps)) - np.array(integrals_trig(um, P, -eps))) / (2 * eps)
        np.testing.assert_allclose(rates, 0.0, atol=1e-7 * (1 + np.abs(u).max() ** 2))
        assert equations.energy_full(ypoly, P) == pytest.approx(integrals_trig(u, P, 0.0)[0], rel=1e-14, abs=1e-14)


def test_reduced_part_is_the_project_field_R3():
    prm = SETS["asym_lam_neg"]
    y = tr.initial_state(prm, 0.7, -0.2, 1.3, 0.4, 2.0, -1.0)
    d = np.empty(7)
    equations.rhs_full(y, _P(prm), d)
    np.testing.assert_allclose(d[:5], model.rhs(model.Params(**prm), y[:5]), rtol=1e-15, atol=1e-15)


# ---------------------------------------------------------------- integration
#: tolerance table (tol = 1e-12): max error of each integral relative to the size of its terms
#: (see trajectory.conservation), and T of the run.
CONSERVATION = {
    "figure4_mu0.5": (500.0, 1e-9, 1e-9, 1e-9),
    "asym_lam_neg": (500.0, 1e-9, 1e-9, 1e-9),
    "asym_lam_pos": (500.0, 1e-9, 1e-9, 1e-9),
    "falling_lam0": (150.0, 1e-9, 1e-9, 1e-9),
    "falling_asym": (150.0, 1e-9, 1e-9, 1e-9),
}


@pytest.mark.parametrize("name", sorted(CONSERVATION))
def test_energy_and_both_momentum_integrals_are_conserved(name):
    T, tol_H, tol_px, tol_py = CONSERVATION[name]
    prm = SETS[name]
    res = tr.trajectory(prm, tr.initial_state(prm, *START), T, 5001, 1e-12)
    assert res["status"] == "done" and res["n_filled"] == 5001
    c = tr.conservation(res)
    assert c["H_rel"] < tol_H and c["px_rel"] < tol_px and c["py_rel"] < tol_py, c
    assert c["casimir"] < 1e-9
    # the returned H, px, py are R1/R2 evaluated on the samples
    u = np.array([res["p1"], res["p2"], res["M"], res["phi"], res["x"], res["y"]])
    H, px, pyt = integrals_trig(u, _P(prm), res["t"])
    np.testing.assert_allclose(res["H"], H, rtol=1e-9, atol=1e-9 * np.abs(H).max())
    np.testing.assert_allclose(res["px"], px, atol=1e-9 * (1 + np.abs(px).max()))
    np.testing.assert_allclose(res["py"] + prm["mu"] * res["t"], pyt, atol=1e-9 * (1 + np.abs(pyt).max()))


@pytest.mark.parametrize("name", ["asym_lam_neg", "falling_lam0"])
def test_samples_and_unwrapped_phi_agree_with_scipy_on_the_trig_form(name):
    prm = SETS[name]
    P = _P(prm)
    T = 30.0
    start = (0.3, -0.4, 3.0, 7.0)  # phi0 = 7 > 2 pi: the branch is kept with phi_start
    res = tr.trajectory(prm, tr.initial_state(prm, *start), T, 301, 1e-13, phi_start=7.0)
    u0 = [start[0], start[1], start[2], start[3], 0.0, 0.0]
    sol = solve_ivp(r1_trig, (0, T), u0, method="DOP853", rtol=1e-13, atol=1e-13, t_eval=res["t"], args=(P,))
    ref = sol.y
    scale = 1 + np.abs(ref).max(axis=1)
    for i, key in enumerate(("p1", "p2", "M", "phi", "x", "y")):
        np.testing.assert_allclose(res[key], ref[i], atol=1e-8 * scale[i], err_msg=key)
    assert res["phi"][0] == 7.0 or abs(res["phi"][0] - 7.0) < 1e-15
    assert abs(res["phi"][-1] - res["phi"][0]) > 2 * math.pi  # the winding is tracked


def test_turning_points_are_roots_of_M_and_alternate():
    prm = SETS["falling_lam0"]
    res = tr.trajectory(prm, tr.initial_state(prm, *START), 40.0, 11, 1e-12)
    tt, d = res["turn_t"], res["turn_dir"]
    assert tt.size > 20 and np.all(np.diff(tt) > 0)
    assert np.all(d[1:] == -d[:-1])
    P = _P(prm)
    sol = solve_ivp(r1_trig, (0, 40.0), [START[0], START[1], START[2], START[3], 0, 0], method="DOP853",
                    rtol=1e-13, atol=1e-13, dense_output=True, args=(P,))
    for t in tt[::7]:
        m, mdot = sol.sol(t)[2], r1_trig(t, sol.sol(t), P)[2]
        assert abs(m) < 1e-8 * (1 + abs(mdot))


def test_a_stopped_run_reports_its_status_and_leaves_nan():
    prm = SETS["figure4_mu0.5"]
    res = tr.trajectory(prm, tr.initial_state(prm, *START), 100.0, 101, 1e-12, max_steps=50)
    assert res["status"] == "step budget exhausted"
    assert np.isnan(res["x"][-1]) and np.isfinite(res["x"][0])


# ---------------------------------------------------------------- drift and band (R2, ur25)
@pytest.mark.parametrize("name", ["figure4_mu0.5", "asym_lam_neg", "asym_lam_pos"])
def test_drift_is_plus_mu_over_lam_within_2e_4_relative(name):
    """ur25: the mean horizontal velocity over T = 1000 is +mu/lam (measured relative errors
    1.4e-6, 8.5e-7 and 1.2e-4 on the three sets: the finite-T remainder, bounded below)."""
    prm = SETS[name]
    d = tr.drift(prm, tr.initial_state(prm, *START, x=1.0, y=-2.0), 1000.0, 20001)
    pred = prm["mu"] / prm["lam"]
    assert d["predicted"] == pred and d["seed"] == -pred
    assert abs(d["rel_error"]) < 2e-4, d
    # the end-point estimate obeys the ur25 bound |(x(T) - x(0))/T - mu/lam| <= 2 max|p - s| / (|lam| T)
    assert abs(d["endpoint"] - pred) <= d["remainder_bound"]
    # the seed's sign is wrong for this R1: the measured velocity is far from -mu/lam
    assert abs(d["measured"] - d["seed"]) > 1.9 * abs(pred)


def test_x_and_y_follow_from_the_momentum_integrals_ur25():
    prm = SETS["asym_lam_neg"]
    P = _P(prm)
    res = tr.trajectory(prm, tr.initial_state(prm, *START, x=1.0, y=-2.0), 200.0, 2001, 1e-12)
    lam, chi, zeta, mu = P[3], P[4], P[5], P[6]
    c1, c2 = res["px"][0], res["py"][0]
    s, c = np.sin(res["phi"]), np.cos(res["phi"])
    x = mu * res["t"] / lam + ((res["p1"] - chi) * s + (res["p2"] - zeta) * c - c2) / lam
    y = c1 / lam - ((res["p1"] - chi) * c - (res["p2"] - zeta) * s) / lam
    np.testing.assert_allclose(res["x"], x, atol=1e-9 * (1 + np.abs(x).max()))
    np.testing.assert_allclose(res["y"], y, atol=1e-9 * (1 + np.abs(y).max()))


@pytest.mark.parametrize("name", ["figure4_mu0.5", "asym_lam_neg", "asym_lam_pos"])
def test_y_stays_in_the_predicted_band(name):
    prm = SETS[name]
    d = tr.drift(prm, tr.initial_state(prm, *START), 400.0, 8001)
    b = d["band"]
    assert b["inside"]
    assert b["centre"] - b["halfwidth_orbit"] - 1e-9 <= b["y_min"] <= b["y_max"] <= \
        b["centre"] + b["halfwidth_orbit"] + 1e-9
    # the a priori (energy) bound contains the orbit's band
    assert b["halfwidth_orbit"] <= b["halfwidth_energy"] * (1 + 1e-12)
    assert b["y_max"] - b["y_min"] > 0.1  # a real band, not a point


def test_drift_refuses_lam_zero():
    with pytest.raises(model.ParameterError, match="lam != 0"):
        tr.drift(SETS["falling_lam0"], tr.initial_state(FIG4, *START), 10.0)


# ---------------------------------------------------------------- Kozlov: the falling body, lam = 0
@pytest.mark.parametrize("name", ["falling_lam0", "falling_asym"])
def test_kozlov_amplitude_t_to_minus_half_and_frequency_t(name):
    prm = SETS[name]
    k = tr.kozlov(prm, tr.initial_state(prm, *START), 200.0)
    assert k["status"] == "done" and k["n_half_periods"] > 1000
    assert abs(k["amplitude_exponent"] + 0.5) < 0.05, k["amplitude_exponent"]   # within 10%
    assert abs(k["frequency_exponent"] - 1.0) < 0.10, k["frequency_exponent"]   # within 10%
    # frequency / t against the linearised ur17, Omega = mu t sqrt(|1/a2 - 1/a1| / b)
    assert k["freq_rate"] == pytest.approx(k["freq_rate_predicted"], rel=0.03)
    # phi_inf: pi/2 mod pi for a1 > a2, 0 mod pi for a1 < a2
    assert abs(k["phi_inf_mod_pi"] - k["phi_inf_predicted_mod_pi"]) < 0.02


def test_kozlov_refuses_other_cases():
    y0 = tr.initial_state(FIG4, *START)
    with pytest.raises(model.ParameterError, match="lam = 0"):
        tr.kozlov(FIG4, y0, 10.0)
    with pytest.raises(model.ParameterError, match="mu > 0"):
        tr.kozlov(dict(FIG4, lam=0.0, mu=0.0), y0, 10.0)
    with pytest.raises(model.ParameterError, match="a1 != a2"):
        tr.kozlov(dict(FIG4, lam=0.0, a2=1.0), y0, 10.0)


# ---------------------------------------------------------------- validation
def test_full_params_allow_lam_zero_and_validate_the_rest():
    assert tr.full_params(dict(lam=0.0))["lam"] == 0.0
    assert tr.full_params(None) == FIG4
    assert tr.full_params(model.FIGURE4)["mu"] == 0.0
    assert tr.full_params(_P(SETS["asym_lam_neg"])) == SETS["asym_lam_neg"]
    for bad, frag in ((dict(a1=0.0), "a1 must be > 0"), (dict(b=-1.0), "b must be > 0"),
                      (dict(mu=-0.1), "mu must be >= 0"), (dict(lam=float("nan")), "lam must be finite"),
                      (dict(xi=float("inf")), "xi must be finite"), (dict(kappa=1.0), "unknown parameter")):
        with pytest.raises(model.ParameterError, match=frag):
            tr.full_params(bad)


def test_bad_runs_are_parameter_errors():
    y0 = tr.initial_state(FIG4, *START)
    for args, frag in (((0.0, 11, 1e-12), "must be > 0"), ((-1.0, 11, 1e-12), "must be > 0"),
                       ((float("nan"), 11, 1e-12), "must be finite"), ((1.0, 1, 1e-12), "samples"),
                       ((1.0, 11, 0.0), "tol must be")):
        with pytest.raises(model.ParameterError, match=frag):
            tr.trajectory(FIG4, y0, *args)
    with pytest.raises(model.ParameterError, match="g1\\^2"):
        tr.trajectory(FIG4, [0, 0, 0, 1, 1, 0, 0], 1.0)
    with pytest.raises(model.ParameterError, match="M must be finite"):
        tr.initial_state(FIG4, 0, 0, float("nan"), 0)


# ---------------------------------------------------------------- figures (headless)
def _ink(fig):
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3]
    return float(np.mean(np.any(img < 250, axis=-1)))


def test_path_figure_renders_headless_with_glyphs_and_band(tmp_path):
    from explorer.app.figures import save_figure

    prm = SETS["figure4_mu0.5"]
    res = tr.trajectory(prm, tr.initial_state(prm, *START), 30.0, 1501)
    fig = trajectory_figure.path_figure(res, prm, glyphs=25)
    ax = fig.axes[0]
    assert len(ax.collections) >= 2 and len(ax.patches) >= 1  # glyphs, e1 segments; the band
    assert "lambda = 1" in ax.get_title() or r"\lambda = 1" in ax.get_title()
    assert _ink(fig) > 0.02
    png, pdf = save_figure(fig, tmp_path / "path")
    assert png.stat().st_size > 10_000 and pdf.stat().st_size > 2_000


def test_kozlov_figure_renders_headless(tmp_path):
    prm = SETS["falling_lam0"]
    k = tr.kozlov(prm, tr.initial_state(prm, *START), 60.0)
    fig = trajectory_figure.kozlov_figure(k, prm)
    assert len(fig.axes) == 2
    assert all(ax.get_xscale() == "log" and ax.get_yscale() == "log" for ax in fig.axes)
    assert "slope" in fig.axes[0].get_legend().get_texts()[1].get_text()
    assert _ink(fig) > 0.02
    fig2 = trajectory_figure.path_figure(k["result"], prm)  # lam = 0: no band
    assert _ink(fig2) > 0.02


# ---------------------------------------------------------------- CLI
def run_cli(args, capsys):
    code = cli.main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_json_drift_and_band(capsys):
    code, out, err = run_cli(["trajectory", "--tmax", "300", "--samples", "3001", "--no-figure", "--json"], capsys)
    assert code == 0, err
    doc = json.loads(out)
    assert doc["params"] == FIG4 and doc["status"] == "done"
    d = doc["drift"]
    assert d["predicted"] == 0.5 and d["seed"] == -0.5 and abs(d["rel_error"]) < 0.01
    assert d["band"]["inside"] is True
    assert doc["conservation"]["H_rel"] < 1e-9
    assert "kozlov" not in doc and "figures" not in doc


def test_cli_lam_zero_text_and_figures(tmp_path, capsys):
    stem = tmp_path / "fall"
    code, out, err = run_cli(["trajectory", "--lam", "0", "--tmax", "100", "--samples", "2001",
                              "--out", str(stem)], capsys)
    assert code == 0, err
    assert "amplitude ~ t^-0.5" in out and "frequency ~ t^1.0" in out
    for suffix in ("", "_kozlov"):
        for ext in (".png", ".pdf"):
            p = tmp_path / f"fall{suffix}{ext}"
            assert p.exists() and p.stat().st_size > 2_000


@pytest.mark.parametrize("args,fragment", [
    (["--a1", "-1"], "a1 must be > 0"),
    (["--b", "0"], "b must be > 0"),
    (["--mu", "-1"], "mu must be >= 0"),
    (["--p1", "nan"], "p1 must be finite"),
    (["--M", "inf"], "M must be finite"),
    (["--lam", "nan"], "lam must be finite"),
    (["--tmax", "0"], "must be > 0"),
    (["--tmax", "-5"], "must be > 0"),
    (["--samples", "1"], "samples must be"),
    (["--tol", "0"], "tol must be"),
    (["--phi", "abc"], "--phi"),
])
def test_cli_bad_input_is_one_line_exit_2(args, fragment, capsys):
    code, out, err = run_cli(["trajectory", "--no-figure"] + args, capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("explorer: error:") and fragment in lines[0], err
    assert "Traceback" not in err


def test_a_trajectory_is_a_frozen_result_readable_by_attribute_and_by_name():
    import dataclasses

    prm = tr.full_params()
    res = tr.trajectory(prm, tr.initial_state(prm, 0.5, 0.0, 2.0, 0.0), 5.0, 11)
    assert isinstance(res, tr.Trajectory) and res.status == "done"
    assert res["x"] is res.x and set(res.keys()) >= {"t", "x", "y", "phi", "turn_t", "status"}
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.status = "x"
    with pytest.raises(KeyError):
        res["nope"]
