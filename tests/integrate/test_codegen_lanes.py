"""The SIMD crossings driver of a System (explorer.integrate.codegen_lanes, docs/systems.md "Crossings"):
every orbit's rows, counts, statuses, final states and step counts equal the scalar driver's bit for
bit, in a full group of lanes, a partial one, on any hyperplane and direction, for every way an orbit
stops, and whatever the number of threads."""
import numpy as np
import pytest
from systems import henon_heiles, pole, x, y

import explorer as ex
from explorer.integrate.simd import LANES
from explorer.kernels import Status

E = 1.0 / 8.0


@pytest.fixture(scope="module")
def hh():
    return henon_heiles()


def starts(n):
    """n states on x = 0 at E = 1/8 with px > 0, (y, py) spread over the section: regular and chaotic."""
    yy = np.linspace(-0.35, 0.45, n)
    pyy = 0.15 * np.sin(np.arange(n))
    return np.column_stack([np.zeros(n), yy, np.sqrt(2*E - pyy**2 - yy**2 + 2*yy**3/3), pyy])


def assert_same(a, b):
    for name in ("data", "count", "status", "final", "info"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name, strict=True)
    assert a.settings == b.settings


def both(system, **kw):
    return (ex.crossings(system, driver="lanes", **kw), ex.crossings(system, driver="scalar", **kw))


@pytest.mark.parametrize("n", [LANES, 13])
def test_each_lane_gives_the_scalar_drivers_rows_bit_for_bit(hh, n):
    lanes, scalar = both(hh, states=starts(n), n_crossings=60, section=x, direction=+1, threads=1)
    assert_same(lanes, scalar)
    assert np.all(lanes.count == 60) and np.all(lanes.status == Status.DONE)
    assert np.nanmax(np.abs(lanes.data[..., 5])) <= 1e-12          # E - E0: a physical row, not NaN


def test_orbits_cut_by_the_time_or_the_step_budget_stop_as_on_the_scalar_driver(hh):
    Y0 = starts(13)
    for kw in (dict(tmax=385.0), dict(max_steps=1110)):
        lanes, scalar = both(hh, states=Y0, n_crossings=60, section=x, direction=+1, threads=1, **kw)
        assert_same(lanes, scalar)
        status = set(lanes.status.tolist())
        assert Status.DONE in status and (Status.TMAX if "tmax" in kw else Status.MAX_STEPS) in status


def test_a_tilted_section_crossed_downwards_gives_the_scalar_rows(hh):
    lanes, scalar = both(hh, states=starts(11), n_crossings=30, section=x + y - 0.1, direction=-1, threads=1)
    assert_same(lanes, scalar)
    assert np.nanmax(np.abs(lanes.data[..., 1] + lanes.data[..., 2] - 0.1)) <= 1e-14


def test_orbits_stopped_by_a_pole_give_the_scalar_statuses():
    system, _, w = pole()
    Y0 = np.array([[0.0, 0.0], [-1.0, 0.0], [-0.5, 1.0], [1.0, 0.0], [-2.0, 0.0]])
    lanes, scalar = both(system, states=Y0, n_crossings=1, section=w - 1, direction=+1, tmax=5.0, threads=1)
    assert_same(lanes, scalar)
    assert {Status.NONFINITE, Status.STEP_UNDERFLOW, Status.DONE} <= set(lanes.status.tolist())


def test_the_lanes_rows_do_not_depend_on_the_number_of_threads(hh):
    Y0 = starts(13)
    one = ex.crossings(hh, states=Y0, n_crossings=40, section=x, direction=+1, driver="lanes", threads=1)
    two = ex.crossings(hh, states=Y0, n_crossings=40, section=x, direction=+1, driver="lanes", threads=2)
    assert_same(one, two)


def test_blocks_resumed_from_their_carry_give_one_runs_rows_on_both_drivers(hh):
    """The drivers' carry (t, its compensation, s, steps, E0) and limits (target, room) continue an orbit
    across blocks bit for bit, as the engine streams its orbits (docs/architecture.md, Streaming): the
    blocks' rows, the final states and the carry after the last block are those of one run."""
    from explorer.analysis import system_sections as ss
    from explorer.integrate import codegen, layout

    mod = codegen.load(hh)
    Y0, K, n = starts(11), 40, 11
    sec = ss.linear_section(hh, x)
    P, keep, cols = hh.parameter_array(), ss.every_crossing(4), np.arange(4)
    order = ex.crossings(hh, states=Y0[:1], n_crossings=1, section=x).settings["order"]

    def run(worker, Y, carry, target, room):
        limits = np.column_stack([target, room]).astype(np.int64)
        m = len(Y)
        out = (np.full((m, int(room.max()), 6), np.nan), np.zeros(m, np.int64), np.zeros(m, np.int64),
               np.zeros((m, 4)), np.zeros((m, 3)))
        worker(np.zeros(1, np.int64), Y, P, sec.a, sec.b, keep, cols, 1, 1e4, order, 10**9, carry, limits, *out,
               False)
        return out

    for worker in (mod.crossings_lanes_worker, mod.crossings_taylor_worker):
        carry = np.empty((n, layout.N_CARRY))
        mod.crossings_start(Y0, P, sec.a, sec.b, carry)
        whole = run(worker, Y0, carry.copy(), np.full(n, K), np.full(n, K))
        rows, Y, done = [[] for _ in range(n)], Y0.copy(), np.zeros(n, np.int64)
        for block in (7, 13, 40):                      # a step may add crossings past a block's target
            target = np.minimum(block, K - done)
            data, count, status, final, _info = run(worker, Y, carry, target, np.full(n, K) - done)
            for i in range(n):
                rows[i].append(data[i, :count[i]])
            Y, done = final, done + count
        assert np.array_equal(done, whole[1]) and np.all(status == Status.DONE)
        for i in range(n):
            np.testing.assert_array_equal(np.concatenate(rows[i]), whole[0][i, :whole[1][i]], strict=True)
        np.testing.assert_array_equal(Y, whole[3], strict=True)
