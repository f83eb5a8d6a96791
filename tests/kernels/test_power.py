"""The step size's power (kernels.power): within its error bound of the exact power over the
whole normal range, the scalar and the vector (lanes) code give the same doubles, and values
outside the normal range take libm's pow."""
import math

import numpy as np
import pytest

from explorer._jit import njit
from explorer.integrate import simd
from explorer.kernels import power
from explorer.kernels.taylor_order import MAX_ORDER, MIN_ORDER


def _arguments(n, seed):
    rng = np.random.default_rng(seed)
    x = np.ldexp(rng.uniform(1.0, 2.0, n), rng.integers(-1022, 1024, n))
    x[:6] = [power.TINY, power.HUGE, 1.0, np.nextafter(2.0, 0.0), math.sqrt(2.0), np.nextafter(math.sqrt(2.0), 3.0)]
    return x


@njit(cache=False)
def _scalar(x, e, out):
    for i in range(x.shape[0]):
        out[i] = power.radius_power(x[i], e)


@njit(cache=False)
def _vector(x, e, out):
    for i in range(0, x.shape[0], simd.LANES):
        simd.vstore(out, i, simd.vradius_power_core(simd.vload(x, i), e))


@pytest.mark.parametrize("order", [MIN_ORDER, 5, 15, 16, 27, MAX_ORDER])
def test_radius_power_is_within_its_error_bound_of_the_exact_power(order):
    """Relative error < POWER_REL_ERR for both exponents of the order (1/p, 1/(p-1)) over the
    positive normal doubles; libm's pow (< 1 ulp) stands for the exact power."""
    x = _arguments(64 * 1024, order)
    out = np.empty_like(x)
    for e in (1.0 / order, 1.0 / (order - 1)):
        _scalar(x, e, out)
        rel = np.abs(out - x ** e) / x ** e
        assert rel.max() < power.POWER_REL_ERR


@pytest.mark.parametrize("order", [MIN_ORDER, 15, MAX_ORDER])
def test_the_lanes_power_is_the_scalar_power_bit_for_bit(order):
    x = _arguments(8 * 4096, order + 1)
    s, v = np.empty_like(x), np.empty_like(x)
    for e in (1.0 / order, 1.0 / (order - 1)):
        _scalar(x, e, s)
        _vector(x, e, v)
        np.testing.assert_array_equal(s, v)


def test_values_outside_the_normal_range_take_libms_pow():
    e = 1.0 / 15
    for x in (0.0, 5e-324, 1e-310, math.inf):
        assert power.radius_power(x, e) == x ** e
    assert math.isnan(power.radius_power(math.nan, e))
