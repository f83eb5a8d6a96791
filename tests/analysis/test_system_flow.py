"""A System's orbits at given times, ex.flow (docs/systems.md, "The flow at given times"): Arenstorf's
periodic orbit closing after its period, samples against scipy's DOP853 dense output, samples that
change no step, the last sample equal to the crossings' final state, the SIMD lanes equal to the scalar
driver, thread independence, statuses and the refusals."""
import numpy as np
import pytest
from systems import pole

import explorer as ex
from explorer._jit import max_threads
from explorer.kernels import Status
from explorer.model import ParameterError, classic

T = classic.ARENSTORF_PERIOD
# regular orbits of Hénon–Heiles at E = 1/8 on x = 0 from (y, py) (a chaotic one separates from any reference)
E = 1.0 / 8.0
POINTS = [(0.1, 0.1), (-0.1, 0.2), (0.3, 0.0)]


@pytest.fixture(scope="module")
def arenstorf():
    return classic.pcr3bp(classic.ARENSTORF_MU)


@pytest.fixture(scope="module")
def hh():
    return classic.henon_heiles()


def hh_starts():
    return np.array([[0.0, yy, np.sqrt(2*E - pyy**2 - yy**2 + 2*yy**3/3), pyy] for yy, pyy in POINTS])


def test_arenstorfs_orbit_sampled_at_0_half_and_one_period_closes_after_its_period(arenstorf):
    """Hairer, Nørsett & Wanner I, II.0: the orbit is periodic with period T, and symmetric about the
    x-axis (at T/2 it crosses y = 0 at right angles: y = vx = 0)."""
    start = np.array(classic.ARENSTORF_STATE)
    res = ex.flow(arenstorf, states=[start], times=[0.0, T / 2, T], tol=1e-15)
    assert res.states.shape == (1, 3, 4) and res.status_of(0) == Status.DONE
    assert np.array_equal(res.t, [0.0, T / 2, T])
    assert np.array_equal(res.states[0, 0], start)                        # t = 0 is the start exactly
    assert np.max(np.abs(res.states[0, 2] - start)) <= 1e-10
    assert abs(res.states[0, 1, 1]) <= 1e-10 and abs(res.states[0, 1, 2]) <= 1e-10
    assert res.energy_error[0, 0] == 0.0 and np.max(res.energy_error) <= 1e-12   # the Jacobi constant


def test_henon_heiles_samples_agree_with_dop853_dense_output(hh):
    from scipy.integrate import solve_ivp

    from explorer.integrate import codegen

    mod = codegen.load(hh)
    P = hh.parameter_array()

    def f(_, yy):
        dy = np.empty(len(yy))
        mod.rhs(yy, P, dy)
        return dy

    rng = np.random.default_rng(8)
    times = np.sort(np.concatenate([[0.0, 0.0], rng.uniform(0.0, 40.0, 60), [40.0, 40.0]]))
    Y0 = hh_starts()
    res = ex.flow(hh, states=Y0, times=times, tol=1e-15)
    assert np.all(res.status == Status.DONE)
    worst = 0.0
    for i in range(3):
        sol = solve_ivp(f, (0.0, 40.0), Y0[i], method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True)
        worst = max(worst, np.max(np.abs(sol.sol(times).T - res.states[i])))
    print(f'worst {worst:.2e} energy {np.max(res.energy_error):.2e}')
    assert worst <= 1e-10, worst
    assert np.max(res.energy_error) <= 1e-13


def test_the_samples_do_not_change_the_steps(hh):
    """One sample or a thousand: the same steps, so the same state at the last time bit for bit."""
    Y0 = hh_starts()
    one = ex.flow(hh, states=Y0, times=[30.0])
    many = ex.flow(hh, states=Y0, times=np.linspace(0.0, 30.0, 1000))
    assert np.array_equal(one.steps, many.steps) and np.all(one.steps > 10)
    assert np.array_equal(one.states[:, -1], many.states[:, -1])


def test_the_last_sample_equals_the_crossings_final_state_at_tmax_bit_for_bit(hh):
    """The same steps and the same clipping onto the last time as the crossings' onto tmax (Hénon–Heiles on a
    section its orbits never reach, a tmax inside a step)."""
    x = hh.states[0]
    tmax = 37.3
    res = ex.flow(hh, states=hh_starts(), times=[1.0, tmax / 3, tmax], tol=1e-14)
    c = ex.crossings(hh, states=hh_starts(), n_crossings=1, section=x - 100.0, direction=1, tmax=tmax, tol=1e-14)
    assert np.all(c.status == Status.TMAX) and np.all(c.info[:, 0] == tmax) and np.all(res.steps > 10)
    assert np.array_equal(res.states[:, -1], c.final) and np.array_equal(res.steps, c.info[:, 1])


def test_the_flow_is_identical_with_one_and_two_threads(hh):
    if max_threads() < 2:
        pytest.skip("one thread only")
    Y0 = np.repeat(hh_starts(), 3, axis=0) * np.linspace(0.9, 1.0, 9)[:, None]
    times = np.linspace(0.0, 20.0, 50)
    for driver in ("scalar", "lanes"):
        a = ex.flow(hh, states=Y0, times=times, threads=1, driver=driver)
        b = ex.flow(hh, states=Y0, times=times, threads=2, driver=driver)
        assert np.array_equal(a.states, b.states) and np.array_equal(a.energy_error, b.energy_error)
        assert np.array_equal(a.steps, b.steps) and np.array_equal(a.status, b.status)


def test_the_simd_lanes_give_the_scalar_drivers_samples_bit_for_bit(hh):
    """Regular orbits, two that escape (status STEP_UNDERFLOW), repeated times and step budgets."""
    rng = np.random.default_rng(2)
    Y0 = np.vstack([np.repeat(hh_starts(), 4, axis=0) * np.linspace(0.9, 1.0, 12)[:, None],
                    [[0.0, 0.0, 0.8, 0.3], [0.0, 1.2, 0.5, 0.0]]])
    times = np.sort(np.concatenate([[0.0, 0.0], rng.uniform(0.0, 60.0, 100), [30.0, 30.0, 60.0, 60.0]]))
    for max_steps in (7, 10**9):
        a = ex.flow(hh, states=Y0, times=times, max_steps=max_steps, driver="scalar")
        b = ex.flow(hh, states=Y0, times=times, max_steps=max_steps, driver="lanes")
        for k in ("states", "energy_error", "status", "steps"):
            assert np.array_equal(getattr(a, k), getattr(b, k), equal_nan=True), k
    assert set(a.status[-2:]) <= {Status.STEP_UNDERFLOW, Status.NONFINITE} and np.all(a.status[:-2] == Status.DONE)


def test_an_orbit_out_of_steps_has_the_budget_status_and_nan_beyond(hh):
    res = ex.flow(hh, states=hh_starts()[:1], times=[0.0, 0.1, 100.0], max_steps=5)
    assert res.status_of(0) == Status.MAX_STEPS and res.steps[0] == 5
    assert np.all(np.isfinite(res.states[0, :2])) and np.all(np.isnan(res.states[0, 2]))
    assert np.isnan(res.energy_error[0, 2])


def test_a_system_without_energy_has_nan_energy_errors():
    # ds/dt = 1, dw/dt = 1/s from (1, 0), away from the pole at s = 0: s = 1 + t, w = ln(1 + t)
    system, _, _ = pole()
    res = ex.flow(system, states=[[1.0, 0.0]], times=[0.0, 1.0, np.e - 1], tol=1e-15)
    assert np.all(np.isnan(res.energy_error))
    assert np.allclose(res.states[0], [[1.0, 0.0], [2.0, np.log(2.0)], [np.e, 1.0]], rtol=0.0, atol=1e-14)


@pytest.mark.parametrize("times", [None, [], [[0.0, 1.0]], [1.0, 0.5], [-1.0, 2.0], [0.0, np.nan], [0.0, np.inf],
                                   "soon"])
def test_bad_times_are_refused_naming_times(hh, times):
    with pytest.raises(ParameterError, match="times"):
        ex.flow(hh, states=hh_starts(), times=times)


def test_a_bad_request_is_refused_naming_the_parameter(hh):
    with pytest.raises(ParameterError, match="states"):
        ex.flow(hh, states=[[0.0, 0.1]], times=[1.0])
    with pytest.raises(ParameterError, match="tol"):
        ex.flow(hh, states=hh_starts(), times=[1.0], tol=1.0)
    with pytest.raises(ParameterError, match="driver"):
        ex.flow(hh, states=hh_starts(), times=[1.0], driver="gpu")
    with pytest.raises(ParameterError, match="System"):
        ex.flow(ex.FIGURE4, states=hh_starts(), times=[1.0])


def test_the_example_of_docs_systems_md_flow_runs():
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "systems.md").read_text()
    if "## The flow at given times" not in page:
        pytest.skip("docs/systems.md has no section 'The flow at given times' yet")
    block = page.split("## The flow at given times", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    namespace = {}
    exec(compile(block, "docs/systems.md", "exec"), namespace)   # its own asserts check the result
    assert namespace["res"].states.shape == (1, 301, 4)
