"""The system seam: the dispatched field is each system's field, and the shared DOP853 step takes
exactly the steps of the crossing driver's own copy of it (the W4 hot path keeps the step
written out, drivers.orbit_dop853)."""
import numpy as np

from explorer import model
from explorer._jit import njit
from explorer.integrate import drivers
from explorer.integrate import systems as sy
from explorer.kernels.clock import advance_time
from explorer.model import equations

PRM = model.FIGURE4.with_(mu=0.5)
P = PRM.as_array()


def test_the_dispatched_field_is_each_systems_field():
    rng = np.random.default_rng(3)
    y = rng.normal(size=10)
    for system, n, ref in ((sy.REDUCED, 5, None), (sy.TANGENT, 10, None), (sy.FULL, 7, None)):
        got = np.empty(n)
        sy.field(system, y[:n].copy(), P, got)
        want = np.empty(n)
        if system == sy.REDUCED:
            equations.rhs(y[:5].copy(), P, want)
        elif system == sy.TANGENT:
            equations.rhs(y[:5].copy(), P, want[:5])
            equations.rhs_tangent(y[:5].copy(), y[5:10].copy(), P, want[5:])
        else:
            equations.rhs_full(y[:7].copy(), P, want)
        np.testing.assert_array_equal(got, want)
        assert sy.DIMENSION[system] == n


@njit
def _plain_dop853(y0, P, T, rtol, atol, max_steps):
    """The bare loop over systems.dop853_step (REDUCED) from 0 to T: final state and steps."""
    K = np.empty((16, 5))
    y = y0.copy()
    ynew = np.empty(5)
    tmp = np.empty(5)
    h_abs = sy.dop853_first_step(sy.REDUCED, y, P, K, rtol, atol, T, tmp)
    t = 0.0
    tc = 0.0
    steps = 0
    while True:
        code, h, last, h_abs, steps = sy.dop853_step(sy.REDUCED, y, P, K, t, T, 1, h_abs, steps, max_steps, rtol,
                                                     atol, tmp, ynew, True)
        if code != sy.STEP_OK:
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
    count, status, t, dsteps = drivers.orbit_dop853(y0, P, 1.0, 0.0, 1, T, 1e-11, 1e-11, 10**6, cross, yout)
    assert count >= 2 and status == model_status_tmax() and code == 1  # crossings found on the way
    assert dsteps == steps
    np.testing.assert_array_equal(yout, y)   # bit for bit: the same arithmetic in the same order


def model_status_tmax():
    from explorer.kernels import Status

    return int(Status.TMAX)
