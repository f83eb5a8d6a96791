"""kernels.events: root isolation and refinement of event polynomials inside one step.

The step searches must find every crossing of the section inside a step, also when the
end values of the event function have one sign (a crossing and the turn back, two turns),
never report the start of a step, and keep the half-open convention of ``sign_change``."""
import numpy as np
import pytest

from explorer.kernels import dop853 as dp
from explorer.kernels import events as ev


def scratch(order):
    return (np.empty(ev.MAX_STEP_ROOTS), np.empty((ev.MAX_STEP_ROOTS, 4)), np.empty(order + 1),
            np.empty((ev.ISOLATE_STACK, 5)))


def poly_from_roots(roots, scale=1.0):
    """Power-basis coefficients (increasing powers) of scale * prod (x - r)."""
    return np.ascontiguousarray(np.polynomial.polynomial.polyfromroots(roots) * scale)


def step_roots(c, h, direction, g_old=None, g_new=None):
    order = len(c) - 1
    roots, brackets, work, stack = scratch(order)
    pv = np.polynomial.polynomial.polyval
    g_old = pv(0.0, c) if g_old is None else g_old
    g_new = pv(h, c) if g_new is None else g_new
    n = ev.poly_step_roots(c, order, h, g_old, g_new, direction, roots, brackets, work, stack)
    return roots[:n].copy()


def test_taylor_shift_is_the_expansion_about_the_new_point():
    rng = np.random.default_rng(1)
    c = np.ascontiguousarray(rng.normal(size=17) / np.arange(1, 18) ** 2)
    out = np.empty_like(c)
    for m in (0.0, 0.07, -0.3, 1.1):
        ev.taylor_shift(c, 16, m, out)
        x = np.linspace(-0.5, 0.5, 11)
        np.testing.assert_allclose(np.polynomial.polynomial.polyval(x, out),
                                   np.polynomial.polynomial.polyval(m + x, c), rtol=1e-13, atol=1e-15)


def test_exclusion_and_monotonicity_bounds_never_discard_a_root():
    """Random polynomials and intervals: whenever no_root_within says 'no root', the
    polynomial has no real root there; whenever monotone_within says 'monotone', p' has none."""
    rng = np.random.default_rng(2)
    P = np.polynomial.polynomial
    checked = 0
    for _ in range(3000):
        deg = int(rng.integers(2, 12))
        d = np.ascontiguousarray(rng.normal(size=deg + 1) * rng.uniform(0.1, 10.0) ** -np.arange(deg + 1))
        r = float(rng.uniform(0.01, 3.0))
        x = np.linspace(-r, r, 4001)
        if ev.no_root_within(d, deg, r):
            checked += 1
            v = P.polyval(x, d)
            assert np.all(v > 0) or np.all(v < 0)
            # sampling alone can miss two roots inside one cell: no real root in [-r, r] either
            assert not real_roots_within(d, r), (d.tolist(), r)
        if ev.monotone_within(d, deg, r):
            dv = P.polyval(x, P.polyder(d))
            assert np.all(dv > 0) or np.all(dv < 0)
            assert not real_roots_within(P.polyder(d), r), (d.tolist(), r)
    assert checked > 300


def real_roots_within(c, r):
    """The real roots (|imaginary part| <= 1e-9 of the modulus) of the polynomial with
    coefficients c (increasing powers) in [-r, r], from the companion matrix."""
    z = np.polynomial.polynomial.polyroots(c)
    real = np.abs(z.imag) <= 1e-9 * np.maximum(1.0, np.abs(z))
    return [float(v) for v in z.real[real] if abs(v) <= r]


def test_real_roots_within_sees_a_pair_hidden_between_samples():
    """Negative control of the check above: two roots 1e-6 apart between two of the 4001
    samples of [-1, 1] (both samples positive) are found."""
    a = 0.1234567
    c = np.polynomial.polynomial.polyfromroots([a, a + 1e-6])
    x = np.linspace(-1.0, 1.0, 4001)
    assert np.all(np.polynomial.polynomial.polyval(x, c) > 0)
    assert len(real_roots_within(c, 1.0)) == 2


@pytest.mark.parametrize("sep", [0.3, 1e-2, 1e-4, 1e-6])
def test_a_pair_of_roots_inside_one_step_is_found_in_both_directions(sep):
    """g = (x - a)(x - a - sep) (a crossing down then up, as a body that passes phi0 and turns
    back): both ends positive, the pair is found, each root with its direction, to the
    accuracy its conditioning allows (|g'| = sep at the roots: error ~ eps / sep)."""
    a = 0.31
    c = poly_from_roots([a, a + sep], 1.0)
    atol = max(1e-14, 1e-15 / sep)
    both = step_roots(c, 1.0, 0)
    np.testing.assert_allclose(both, [a, a + sep], rtol=0, atol=atol)
    np.testing.assert_allclose(step_roots(c, 1.0, +1), [a + sep], atol=atol)
    np.testing.assert_allclose(step_roots(c, 1.0, -1), [a], atol=atol)


def test_four_roots_inside_one_step_come_out_sorted():
    r = [0.05, 0.0501, 0.4, 0.93]
    c = poly_from_roots(r, -2.0)
    np.testing.assert_allclose(step_roots(c, 1.0, 0), r, atol=1e-12)


def test_ordinary_steps_take_the_fast_path_and_match_the_end_value_test():
    """A monotone step: exactly the sign change of the end values (and poly_root_in's root)."""
    c = np.ascontiguousarray([-0.2, 1.0, 0.1, -0.05, 0.001])
    order = 4
    got = step_roots(c, 0.5, +1)
    assert len(got) == 1
    assert got[0] == ev.poly_root_in(c, order, 0.0, 0.5, c[0], np.polynomial.polynomial.polyval(0.5, c))
    assert len(step_roots(c, 0.1, +1)) == 0           # no sign change in (0, 0.1]
    assert len(step_roots(c, 0.5, -1)) == 0           # wrong direction


def test_start_on_the_section_is_not_a_crossing():
    """The step starts on the root (g_old = 0 by the caller's bookkeeping) and turns back: only
    the return is reported."""
    c = poly_from_roots([0.0, 0.2], 1.0) + np.array([1e-18, 0, 0])
    np.testing.assert_allclose(step_roots(c, 1.0, 0, g_old=0.0), [0.2], atol=1e-14)
    np.testing.assert_allclose(step_roots(c, 1.0, +1, g_old=0.0), [0.2], atol=1e-14)
    assert len(step_roots(c, 1.0, -1, g_old=0.0)) == 0


def test_a_root_at_the_step_end_fires_once():
    c = poly_from_roots([0.3, 1.0], 1.0)      # roots at 0.3 and exactly at the end h = 1
    got = step_roots(c, 1.0, 0, g_new=0.0)
    np.testing.assert_allclose(got, [0.3, 1.0], atol=1e-14)
    # the next step starts at g = 0: nothing more
    c2 = poly_from_roots([0.0], 1.0)
    assert len(step_roots(c2, 0.5, 0, g_old=0.0)) == 0


def test_a_tangency_does_not_hang_and_reports_no_crossing():
    c = poly_from_roots([0.4, 0.4], 1.0)      # double root: touches zero, no sign change
    got = step_roots(c, 1.0, 0)
    assert len(got) in (0, 2)                 # decided at the depth limit by the end values
    if len(got):
        np.testing.assert_allclose(got, [0.4, 0.4], atol=1e-6)


def test_dense_power_basis_reproduces_the_nested_continuous_extension():
    rng = np.random.default_rng(3)
    Fg = np.ascontiguousarray(rng.normal(size=7))
    coef = np.empty(8)
    ev.dense_power_basis(Fg, 0.37, coef)
    for th in np.linspace(0, 1, 17):
        assert abs(np.polynomial.polynomial.polyval(th, coef) - dp.dense_eval_scalar(Fg, 0.37, th)) < 1e-14


def test_dense_step_roots_finds_a_pair_inside_the_step():
    """Continuous extension of g(theta) = (theta - 0.5)(theta - 0.52): F chosen by solving the
    nested form's linear system; both roots, refined on the nested form."""
    target = poly_from_roots([0.5, 0.52], 1.0)
    # the map Fg -> power coefficients (minus the constant) is linear: build its matrix
    A = np.zeros((8, 7))
    coef = np.empty(8)
    for k in range(7):
        e = np.zeros(7)
        e[k] = 1.0
        ev.dense_power_basis(e, 0.0, coef)
        A[:, k] = coef
    want = np.zeros(8)
    want[:3] = target
    Fg = np.ascontiguousarray(np.linalg.lstsq(A, want - np.eye(8)[0] * target[0], rcond=None)[0])
    g_old = target[0]
    g_new = dp.dense_eval_scalar(Fg, g_old, 1.0)
    roots, brackets, work, stack = scratch(7)
    n = ev.dense_step_roots(Fg, g_old, g_old, g_new, 0, roots, brackets, np.empty(8), work, stack)
    np.testing.assert_allclose(roots[:n], [0.5, 0.52], atol=1e-12)
