"""The system seam: each system's field is its equations; the shared DOP853 step takes
exactly the steps of the crossing driver's own copy of it (the W4 hot path keeps the step
written out, drivers.orbit_dop853); the Taylor and splitting steps carry a deviation vector
without touching the orbit, and that vector is the flow's derivative."""
import numpy as np

from explorer import model
from explorer._jit import njit
from explorer.integrate import _systems_generated as sg
from explorer.integrate import drivers
from explorer.integrate.systems import STEP_OK
from explorer.kernels import taylor as tk
from explorer.kernels.clock import advance_time
from explorer.model import equations

PRM = model.FIGURE4.with_(mu=0.5)
P = PRM.as_array()


def test_each_systems_field_is_its_equations():
    rng = np.random.default_rng(3)
    y = rng.normal(size=10)
    for field, n in ((sg.field_reduced, 5), (sg.field_tangent, 10), (sg.field_full, equations.FULL_DIM)):
        got = np.empty(n)
        field(y[:n].copy(), P, got)
        want = np.empty(n)
        if n == 5:
            equations.rhs(y[:5].copy(), P, want)
        elif n == 10:
            equations.rhs(y[:5].copy(), P, want[:5])
            equations.rhs_tangent(y[:5].copy(), y[5:10].copy(), P, want[5:])
        else:
            equations.rhs_full(y[:n].copy(), P, want)
        np.testing.assert_array_equal(got, want)


@njit
def _plain_dop853(y0, P, T, rtol, atol, max_steps):
    """The bare loop over dop853_step_reduced from 0 to T: final state and steps."""
    K = np.empty((16, 5))
    y = y0.copy()
    ynew = np.empty(5)
    tmp = np.empty(5)
    h_abs = sg.dop853_first_step_reduced(y, P, K, rtol, atol, T, tmp)
    t = 0.0
    tc = 0.0
    steps = 0
    while True:
        code, h, last, h_abs, steps = sg.dop853_step_reduced(y, P, K, t, T, 1, h_abs, steps, max_steps, rtol,
                                                             atol, tmp, ynew, True)
        if code != STEP_OK:
            return y, steps, code
        t, tc = advance_time(t, tc, h, last, T)  # Kahan-compensated, as the driver
        for i in range(5):
            y[i] = ynew[i]
            K[0, i] = K[12, i]


def test_the_shared_step_and_the_crossing_drivers_copy_take_the_same_steps():
    y0 = model.section_state(PRM, [0.3], [0.1], 2.0)[0]
    T = 37.3
    y, steps, code = _plain_dop853(y0, P, T, 1e-11, 1e-11, 10**6)
    cross = np.full((10**4, 5), np.nan)
    yout = np.empty(5)
    carry = np.empty((1, drivers.N_CARRY))
    drivers.start_carry(y0[None, :], P, 1.0, 0.0, carry)
    count, status, t, dsteps = drivers.orbit_dop853(y0, P, 1.0, 0.0, 1, T, 1e-11, 1e-11, 10**6, cross, yout,
                                                    carry[0], 10**4, 10**4)
    assert count >= 2 and status == model_status_tmax() and code == 1  # crossings found on the way
    assert dsteps == steps
    np.testing.assert_array_equal(yout, y)   # bit for bit: the same arithmetic in the same order


def model_status_tmax():
    from explorer.kernels import Status

    return int(Status.TMAX)


def _plain_taylor(taylor_step, z0, P, T, order, max_steps):
    """The bare loop over a system's taylor_step from 0 to T: final state, steps, times, code."""
    n = z0.shape[0]
    X = np.empty((n, order + 1))
    z = z0.copy()
    znew = np.empty(n)
    factor = tk.safety_factor(order)
    times = []
    t = 0.0
    tc = 0.0
    steps = 0
    while True:
        X[:, 0] = z
        code, h, last, steps = taylor_step(X, P, t, T, 1, order, factor, steps, max_steps, znew)
        if code != STEP_OK:
            return z, steps, np.array(times), code
        t, tc = advance_time(t, tc, h, last, T)
        times.append(t)
        z[:] = znew


def _plain_split(split_step, z0, P, dt, nsteps, flow_ids, fracs):
    """The bare loop over a system's split_step: final state, code."""
    z = z0.copy()
    znew = np.empty(z.shape[0])
    steps = 0
    while steps < nsteps:
        code, steps = split_step(z, P, dt, flow_ids, fracs, steps, 10**9, znew)
        if code != STEP_OK:
            return z, code
        z[:] = znew
    return z, 1


def test_a_deviation_vector_never_changes_the_orbit_or_its_taylor_steps():
    """The Taylor indicators' step is chosen from the orbit's own rows, whose recurrence is R3's: with one
    or two deviation vectors their orbits end where the Taylor crossings' orbits end, after as many steps,
    bit for bit."""
    from explorer.analysis import lyapunov, sections

    y0 = model.section_state(PRM, [0.3, 0.5], [0.1, 0.0], 2.0)
    c = sections.crossings(PRM, states=y0, n_crossings=1000, method="taylor", tmax=41.7, direction=0, tol=1e-12)
    for which in (("megno",), ("megno", "sali")):
        r = lyapunov.indicators(PRM, states=y0, tmax=41.7, method="taylor", tol=1e-12, which=which)
        assert np.all(r.steps > 100)
        np.testing.assert_array_equal(r.steps, c.info[:, 1])
        np.testing.assert_array_equal(r.final[:, :5], c.final)
        assert np.all(np.isfinite(r.deviation[:, 0])) and np.all(np.linalg.norm(r.deviation[:, 0], axis=-1) > 0)


def test_the_backward_system_retraces_the_forward_orbit():
    """The backward system is R3 in reversed time: its Taylor steps from the forward run's end state
    over the same span come back to the start (to the tolerance of order 17), and its first
    coefficients are the forward ones with the odd orders negated, exactly."""
    y0 = model.section_state(PRM, [0.3], [0.1], 2.0)[0]
    y, ns, _t, code = _plain_taylor(sg.taylor_step_reduced, y0, P, 7.3, 17, 10**5)
    back, nb, _tb, code_b = _plain_taylor(sg.taylor_step_backward, y, P, 7.3, 17, 10**5)
    assert code == code_b == 1 and ns > 10 and nb > 10
    assert np.max(np.abs(back - y0)) < 1e-11
    assert np.max(np.abs(y - y0)) > 0.1                          # the orbit did move
    X = np.zeros((5, 8))
    Xb = np.zeros((5, 8))
    X[:, 0] = Xb[:, 0] = y0
    sg.taylor_coefficients_reduced(P, X, 7)
    sg.taylor_coefficients_backward(P, Xb, 7)
    np.testing.assert_array_equal(Xb, X * (-1.0) ** np.arange(8))


def test_split_steps_of_tangent_carry_reduceds_orbit_and_its_derivative():
    from explorer.integrate import methods

    prep = methods.get("split6").prepare(dt=0.02)
    y0 = model.section_state(PRM, [0.3], [0.1], 2.0)[0]
    v0 = np.array([0.3, -0.2, 0.1, 0.05, -0.04])
    y, cy = _plain_split(sg.split_step_reduced, y0, P, 0.02, 400, prep.flow_ids, prep.fracs)
    z, cz = _plain_split(sg.split_step_tangent, np.concatenate([y0, v0]), P, 0.02, 400, prep.flow_ids, prep.fracs)
    assert cy == cz == 1
    np.testing.assert_array_equal(z[:5], y)
    e = 1e-6
    yp, _ = _plain_split(sg.split_step_reduced, y0 + e * v0, P, 0.02, 400, prep.flow_ids, prep.fracs)
    ym, _ = _plain_split(sg.split_step_reduced, y0 - e * v0, P, 0.02, 400, prep.flow_ids, prep.fracs)
    fd = (yp - ym) / (2 * e)
    np.testing.assert_allclose(z[5:], fd, rtol=1e-6, atol=1e-6 * np.linalg.norm(fd))


def test_a_taylor_step_budget_and_a_nonfinite_state_end_the_loop_with_their_codes():
    from explorer.kernels import Status

    y0 = model.section_state(PRM, [0.3], [0.1], 2.0)[0]
    _, steps, _, code = _plain_taylor(sg.taylor_step_reduced, y0, P, 1e3, 15, 7)
    assert steps == 7 and code == int(Status.MAX_STEPS)
    bad = y0.copy()
    bad[2] = np.nan
    _, steps, _, code = _plain_taylor(sg.taylor_step_reduced, bad, P, 1e3, 15, 7)
    assert steps == 0 and code == int(Status.NONFINITE)
