"""The shared integration clock: compensated time sum and exact landing on the end time."""
import math

from explorer._jit import njit
from explorer.kernels.clock import advance_time, clip_step


@njit(cache=False)
def _sum(h, n):
    t, tc = 0.0, 0.0
    for _ in range(n):
        t, tc = advance_time(t, tc, h, False, 1e300)
    return t - tc


def test_compensated_clock_matches_exact_sum_after_a_million_steps():
    n, h = 10**6, 0.1
    exact = math.fsum([h] * n)
    assert abs(_sum(h, n) - exact) <= math.ulp(exact)
    naive = 0.0
    for _ in range(n):
        naive += h
    assert abs(naive - exact) > 100 * math.ulp(exact)  # the naive sum drifts: the test can fail


def test_last_step_is_clipped_and_lands_exactly_on_the_end():
    h, last = clip_step(9.95, 0.1, 10.0)
    assert last and h == 10.0 - 9.95
    assert advance_time(9.95, 1e-17, h, last, 10.0) == (10.0, 0.0)
    assert clip_step(1.0, 0.1, 10.0) == (0.1, False)
