"""Chaos indicators of a System and of its section map (docs/systems.md, "Chaos indicators"): the
deviation vectors against scipy's solve_ivp of the hand-written variational equations, MEGNO, mLCE,
SALI and GALI_2 on regular and chaotic Hénon–Heiles orbits and on two harmonic oscillators, the
Lorenz exponent, the SIMD lanes against the scalar driver and thread independence, and the refusals."""
import numpy as np
import pytest
import sympy as sp
from systems import henon_heiles, px, py, x, y

import explorer as ex
from explorer.analysis.lyapunov import regular_bound
from explorer.analysis.system_indicators import default_vectors
from explorer.kernels import Status
from explorer.model import ParameterError

ALL = ("mlce", "megno", "fli", "sali", "gali2")


def on_x0(E, yy, pyy=0.0):
    """The state on x = 0 at energy E with px > 0 (lam = 1)."""
    return [0.0, yy, np.sqrt(2*E - pyy**2 - yy**2 + 2*yy**3/3), pyy]


# (x, y, px, py): a regular orbit at E = 1/12, a chaotic one at E = 1/6, and the GALI test orbits of
# ChaosTools.jl (test/chaosdetection/gali_tests.jl): chaotic at E = 1/8, regular at E = 0.118
REGULAR = on_x0(1/12, 0.1)
CHAOTIC = on_x0(1/6, -0.1)
CHAOTIC_CT = [0.0, -0.25, 0.42081, 0.0]
REGULAR_CT = [0.0, 0.483, 0.27898039, 0.0]


@pytest.fixture(scope="module")
def hh():
    return henon_heiles()


@pytest.fixture(scope="module")
def four(hh):
    """The four orbits over T = 1000 with every indicator (two deviation vectors)."""
    return ex.indicators(hh, states=[REGULAR, CHAOTIC, CHAOTIC_CT, REGULAR_CT], tmax=1000.0, which=ALL, history=6)


def variational_rhs(_, z):
    """Hénon–Heiles (lam = 1) with two deviation vectors: its Jacobian written by hand."""
    X, Y, PX, PY = z[:4]
    J = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [-1 - 2*Y, -2*X, 0, 0], [-2*X, -1 + 2*Y, 0, 0]], float)
    return np.concatenate([[PX, PY, -X - 2*X*Y, -Y - (X**2 - Y**2)], J @ z[4:8], J @ z[8:12]])


@pytest.mark.parametrize("start", [REGULAR, CHAOTIC], ids=["regular", "chaotic"])
def test_deviation_vectors_agree_with_scipy_on_the_hand_written_variational_equations(hh, start):
    from scipy.integrate import solve_ivp

    T = 40.0
    v0 = np.array([0.3, -0.5, 0.7, 0.2])
    w0 = np.array([-0.4, 0.1, 0.2, 0.6])
    res = ex.indicators(hh, states=[start], tmax=T, which=ALL, v0=v0, w0=w0)
    z0 = np.concatenate([start, v0 / np.linalg.norm(v0), w0 / np.linalg.norm(w0)])
    sol = solve_ivp(variational_rhs, (0.0, T), z0, method="DOP853", rtol=1e-13, atol=1e-13)
    zT = sol.y[:, -1]
    v, w = zT[4:8], zT[8:12]
    assert res.status[0] == Status.DONE and res.time[0] == T
    assert np.max(np.abs(res.final[0] - zT[:4])) < 1e-10
    # the renormalised vectors are the directions of the linear flow's; mLCE T its log-stretch
    assert np.max(np.abs(res.deviation[0, 0] - v / np.linalg.norm(v))) < 1e-9
    assert np.max(np.abs(res.deviation[0, 1] - w / np.linalg.norm(w))) < 1e-9
    assert abs(res.mlce[0] * T - np.log(np.linalg.norm(v))) < 1e-9
    assert res.fli[0] >= np.log(np.linalg.norm(v)) - 1e-9


@pytest.mark.cpu_dependent   # a classification by thresholds (tests/conftest.py)
def test_a_regular_orbit_has_megno_near_2_small_exponent_and_sali_gali2_away_from_0(four):
    T = 1000.0
    for i in (0, 3):
        assert 1.5 < four.megno[i] < 2.3
        assert 0.0 <= four.mlce[i] < regular_bound(T)
        assert four.sali[i] > 1e-2 and four.gali2[i] > 1e-2


@pytest.mark.cpu_dependent   # a classification by thresholds (tests/conftest.py)
def test_a_chaotic_orbit_has_megno_growing_as_half_the_exponent_times_t_and_sali_gali2_fall_to_0(four):
    T = 1000.0
    for i in (1, 2):
        assert four.mlce[i] > 0.02
        assert four.megno[i] > 10.0   # 23 to 78 over start perturbations of 1e-13
        assert abs(four.megno[i] - four.mlce[i] * T / 2) < 0.2 * four.mlce[i] * T / 2   # Cincotta & Simó 2000
        assert four.sali[i] < 1e-8 and four.gali2[i] < 1e-8
    assert np.all(four.status == Status.DONE) and np.all(four.time == T)


def test_the_energy_error_is_reported_and_small(four):
    assert np.all(four.energy_error < 1e-12)


def test_the_last_history_row_is_the_result_row(four):
    assert four.history_t[-1] == 1000.0
    last = four.history[:, -1]
    np.testing.assert_array_equal(last[:, 1], four.mlce)
    np.testing.assert_array_equal(last[:, 2], four.megno)


def test_two_harmonic_oscillators_rotate_the_deviation_vectors_so_megno_and_the_exponent_stay_0(hh):
    # lam = 0: x and y oscillate with frequency 1, the flow is a rotation in (x, px) and (y, py): the
    # deviation vectors keep their lengths and their angle (an isochronous motion: <Y> -> 0)
    lin = hh.with_(lam=0.0)
    res = ex.indicators(lin, states=[REGULAR, CHAOTIC], tmax=500.0, which=ALL)
    assert np.all(np.abs(res.megno) < 1e-10) and np.all(np.abs(res.mlce) < 1e-12)
    assert np.all(np.abs(res.fli) < 1e-10)
    np.testing.assert_allclose(res.sali, np.sqrt(2.0), atol=1e-10)   # |v +- w| of orthonormal v, w
    np.testing.assert_allclose(res.gali2, 1.0, atol=1e-10)


@pytest.mark.cpu_dependent   # a classification by thresholds (tests/conftest.py)
def test_the_lorenz_system_without_energy_has_the_published_exponent_and_a_nan_energy_error():
    # sigma = 10, rho = 28, beta = 8/3: lambda_1 = 0.9056 (Viswanath 1998; Sprott 2003, Chaos and
    # Time-Series Analysis, Table A.1); the mean finite-time exponent of three orbits over T = 2000
    X, Y, Z, s, r, b = sp.symbols("X Y Z sigma rho beta")
    lorenz = ex.System({X: s*(Y - X), Y: X*(r - Z) - Y, Z: X*Y - b*Z}, parameters={s: 10.0, r: 28.0, b: 8/3},
                       name="lorenz")
    res = ex.indicators(lorenz, states=[[1.0, 1.0, 1.0], [-5.0, 3.0, 20.0], [0.1, 0.0, 0.0]], tmax=2000.0,
                        tol=1e-10, which=("mlce", "megno"))
    assert abs(np.mean(res.mlce) - 0.9056) < 0.02
    assert np.all(np.abs(res.megno - res.mlce * 2000.0 / 2) < 0.05 * res.mlce * 2000.0 / 2)
    assert np.all(np.isnan(res.energy_error)) and np.all(np.isnan(res.sali))
    assert res.final.shape == (3, 3) and res.deviation.shape == (3, 2, 3)


def _driver_run(hh, driver, threads, states, **kw):
    """system_indicators on ``driver`` (the SIMD lanes or the scalar driver) with every indicator."""
    from explorer.analysis.system_indicators import system_indicators

    args = dict(tmax=300.0, method=None, tol=None, history=4, v0=None, w0=None, max_steps=10**9, which=ALL,
                early_stop=False, early_sali=1e-8, early_megno=8.0, early_time=0.0)
    return system_indicators(hh, states=states, threads=threads, driver=driver, **dict(args, **kw))


#: 13 orbits (a full group of SIMD lanes and a partial one), regular and chaotic
THIRTEEN = [REGULAR, CHAOTIC, CHAOTIC_CT, REGULAR_CT] + [on_x0(1/8, v) for v in np.linspace(-0.3, 0.45, 9)]


@pytest.fixture(scope="module", params=[{}, dict(early_stop=True, max_steps=865)],
                ids=["full", "early-stop-and-budget"])
def driver_runs(hh, request):
    """The 13 orbits with every indicator on the scalar driver (2 threads) and on the SIMD lanes (1 and 2
    threads); with early stops and a step budget, lanes take new orbits at different steps."""
    runs = {(d, th): _driver_run(hh, d, th, THIRTEEN, **request.param) for d, th in
            [("scalar", 2), ("lanes", 1), ("lanes", 2)]}
    return request.param, runs


def _assert_identical(got, ref):
    for key in ("time", "Y", "status", "steps", "final", "history", "deviation", "early"):
        np.testing.assert_array_equal(got[key], ref[key], err_msg=key, strict=True)
    for name in ALL:
        np.testing.assert_array_equal(got["values"][name], ref["values"][name], err_msg=name, strict=True)


def test_each_lane_gives_the_scalar_drivers_indicators_bit_for_bit(driver_runs):
    from explorer.integrate.simd import LANES

    kw, runs = driver_runs
    assert LANES < len(THIRTEEN) < 2 * LANES
    _assert_identical(runs["lanes", 1], runs["scalar", 2])
    if kw:
        status = set(runs["scalar", 2]["status"].tolist())
        assert np.any(runs["scalar", 2]["early"] > 0) and {Status.DONE, Status.MAX_STEPS} <= status


def test_indicators_of_a_system_are_identical_with_one_and_two_threads(driver_runs):
    _, runs = driver_runs
    _assert_identical(runs["lanes", 2], runs["lanes", 1])


def test_the_section_map_lifts_its_points_to_the_states_of_the_flow(hh):
    smap = ex.SectionMap(hh, 1/8, section=x, direction=+1, coords=(y, py), solve=px)
    points = [(0.1, 0.1), (-0.1, 0.2)]
    a = ex.indicators(smap, points, tmax=200.0, which=("megno",))
    b = ex.indicators(hh, states=smap.states(points), tmax=200.0, tol=smap.tol, which=("megno",))
    np.testing.assert_array_equal(a.megno, b.megno)
    np.testing.assert_array_equal(a.final, b.final)
    assert a.settings["energy"] == 1/8 and a.settings["coords"] == ["y", "py"]
    assert np.all(np.isnan(a.sali))


def test_the_maps_indicators_are_the_systems_at_the_maps_tol_and_another_tol_is_the_map_with_tol(hh):
    smap = ex.SectionMap(hh, 1/8, section=x, direction=+1, coords=(y, py), solve=px)
    points = [(0.1, 0.1), (-0.1, 0.2), (0.3, 0.0)]
    loose = smap.with_tol(1e-10)
    res = ex.indicators(loose, points, tmax=300.0, which=ALL)
    flow = ex.indicators(hh, states=loose.states(points), tmax=300.0, tol=1e-10, which=ALL)
    for name in ALL:
        np.testing.assert_array_equal(res.values[name], flow.values[name], err_msg=name)
    for name in ("time", "status", "steps", "final", "deviation", "energy_error"):
        np.testing.assert_array_equal(getattr(res, name), getattr(flow, name), err_msg=name)
    tight = ex.indicators(smap, points, tmax=300.0, which=ALL)
    assert res.settings["tol"] == 1e-10 and tight.settings["tol"] == smap.tol == 1e-15
    assert res.settings["order"] < tight.settings["order"]
    assert not np.array_equal(res.final, tight.final) and np.max(np.abs(res.final - tight.final)) < 1e-6


def test_one_deviation_vector_gives_the_first_vector_of_two_to_rounding(hh, four):
    # which without sali, gali2: System.variational(1), another generated recurrence of the same equations
    one = ex.indicators(hh, states=[REGULAR, REGULAR_CT], tmax=1000.0, which=("mlce", "megno", "fli"))
    for name in ("mlce", "megno", "fli"):
        np.testing.assert_allclose(one.values[name], four.values[name][[0, 3]], rtol=1e-9)
    np.testing.assert_allclose(one.final, four.final[[0, 3]], atol=1e-11)
    assert np.all(np.isnan(one.deviation[:, 1]))


def test_an_orbit_out_of_steps_ends_with_max_steps_at_the_time_it_reached(hh):
    res = ex.indicators(hh, states=[REGULAR], tmax=1000.0, which=("megno",), max_steps=50)
    assert res.status_of(0) == Status.MAX_STEPS and res.steps[0] == 50 and 0.0 < res.time[0] < 1000.0
    assert np.isfinite(res.megno[0])


@pytest.mark.cpu_dependent   # a classification by thresholds (tests/conftest.py)
def test_early_stop_ends_a_chaotic_orbit_by_sali_and_not_a_regular_one(hh):
    res = ex.indicators(hh, states=[CHAOTIC_CT, REGULAR], tmax=2000.0, which=("megno", "sali"), early_stop=True)
    assert res.early[0] > 0 and res.time[0] < 2000.0
    assert res.early[1] == 0 and res.time[1] == 2000.0


def test_the_default_deviation_vectors_are_unit_orthogonal_and_generic():
    for n in (2, 3, 4, 7):
        v, w = default_vectors(n)
        assert abs(np.linalg.norm(v) - 1) < 1e-15 and abs(np.linalg.norm(w) - 1) < 1e-15 and abs(v @ w) < 1e-14
        assert np.all(v != 0) and len(set(np.abs(v))) == n


@pytest.mark.parametrize("kw, words", [
    (dict(phi0=0.1), "phi0"), (dict(dt=0.05), "dt"), (dict(h=2.0), "h"), (dict(method="dop853"), "method"),
    (dict(which=("megno", "lyapunov")), "mlce, megno"), (dict(which="frequency_diffusion"), "frequency_diffusion"),
    (dict(v0=[1.0, 0.0]), "v0"), (dict(w0=[0.0, 0.0, 0.0, 0.0]), "w0"), (dict(tmax=-1.0), "tmax"),
    (dict(tol=1.0), "tol"),
])
def test_a_bad_request_is_refused_with_a_message_naming_the_parameter(hh, kw, words):
    with pytest.raises(ParameterError, match=words):
        ex.indicators(hh, states=[REGULAR], **kw)


def test_an_unknown_keyword_is_a_type_error_as_for_any_function(hh):
    with pytest.raises(TypeError, match="colour"):
        ex.indicators(hh, states=[REGULAR], colour=1)


def test_states_of_the_wrong_shape_and_states_beside_a_map_are_refused(hh):
    with pytest.raises(ParameterError, match="states"):
        ex.indicators(hh, states=[[0.0, 0.1, 0.2]])
    smap = ex.SectionMap(hh, 1/8, section=x, direction=+1, coords=(y, py), solve=px)
    with pytest.raises(ParameterError, match="states"):
        ex.indicators(smap, states=[REGULAR])


def test_a_tol_beside_a_systems_map_is_refused_naming_tol_and_pointing_to_with_tol_as_for_its_crossings(hh):
    smap = ex.SectionMap(hh, 1/8, section=x, direction=+1, coords=(y, py), solve=px)
    with pytest.raises(ParameterError, match=r"tol belong\(s\) to the map.*smap\.with_tol\(tol\)") as ind:
        ex.indicators(smap, [(0.1, 0.1)], tmax=10.0, tol=smap.tol)
    with pytest.raises(ParameterError) as cross:
        ex.crossings(smap, [(0.1, 0.1)], n_crossings=3, tol=smap.tol)
    assert str(ind.value).replace("indicators", "crossings", 1) == str(cross.value)   # the same words


def test_an_orbit_escaping_in_finite_time_stops_at_its_blow_up_with_the_step_underflow_or_non_finite_status(hh):
    # x = px = 0 stays so: y'' = -y + y**2, which from (y, py) = (1.2, 0.5) escapes, py = sqrt(2E - y**2 +
    # 2 y**3 / 3) > 0 for y > 1, to y = infinity at t* = the integral of dy / py from 1.2 (a finite time)
    from scipy.integrate import quad

    E = 0.5**2 / 2 + 1.2**2 / 2 - 1.2**3 / 3
    t_star = quad(lambda yy: 1.0 / np.sqrt(2*E - yy**2 + 2*yy**3/3), 1.2, np.inf, epsabs=1e-13, epsrel=1e-13)[0]
    res = ex.indicators(hh, states=[[0.0, 1.2, 0.0, 0.5]], tmax=10.0, which=("megno",))
    assert res.status_of(0) in (Status.STEP_UNDERFLOW, Status.NONFINITE)
    assert abs(res.time[0] - t_star) < 1e-10 and t_star < 10.0    # y ~ 6 / (t* - t)**2 near t*


def test_the_example_of_docs_systems_md_chaos_indicators_runs():
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "systems.md").read_text()
    if "## Chaos indicators" not in page:
        pytest.skip("docs/systems.md has no section 'Chaos indicators' yet")
    block = page.split("## Chaos indicators", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    namespace = {}
    exec(compile(block, "docs/systems.md", "exec"), namespace)   # its own asserts check the result
    assert namespace["res"].megno.shape == (2,) and namespace["megno"].shape == (2,)
