"""A budget stops the section-map analyses (explorer.analysis.budget): the compiled return reads a
stop switch and releases the GIL, so a search that would run for minutes at mu = 1e6 (issue 32:
one return held the GIL for 40 s and froze `explorer serve`) ends within a step of its budget while
the main thread keeps running, and a cancelled search ends as soon as it is cancelled."""
from __future__ import annotations

import functools
import threading
import time

import numpy as np
import pytest

from explorer import model
from explorer._jit import NOJIT
from explorer.analysis import lyapunov, sections
from explorer.analysis.budget import Budget, BudgetExceeded, step_cap
from explorer.analysis.section_map import SectionMap
from explorer.integrate.tangent import return_map_taylor
from explorer.kernels import STATUS_CANCELLED, STATUS_DONE
from explorer.kernels.taylor import order_for_tolerance

#: a cancelled run must end this soon (s): a step takes microseconds, the uncancelled run minutes
CANCEL_SECONDS = 2.0

#: a circulation at which one return of the section map from p = 0 (on the edge of the region,
#: M about 0) takes minutes: 10^5 Taylor steps advance t by 0.35 of a time budget of 1000
HUGE_MU = 1e6


def test_a_set_switch_stops_the_return_at_once_and_a_clear_one_changes_nothing():
    prm = model.FIGURE4.with_(mu=0.3)
    y0 = model.section_state(prm, [0.2], [0.1], 2.0)[0]
    order = order_for_tolerance(1e-14)
    V0 = np.zeros((0, 5))
    outs = []
    for switch in (0, 1):
        out, Vout = np.empty(5), np.empty((0, 5))
        st, t = return_map_taylor(y0, V0, prm.as_array(), -1.0, 0.0, 1.0, 1e3, order, 10**7,
                                  np.full(1, switch, np.int64), out, Vout)
        outs.append((st, t, out.copy()))
    assert outs[0][0] == STATUS_DONE and outs[0][1] > 0
    assert outs[1][0] == STATUS_CANCELLED and outs[1][1] == 0.0


def test_outside_a_budget_the_section_map_gives_the_same_numbers_as_inside_one():
    prm = model.FIGURE4.with_(mu=0.3)
    smap = SectionMap(prm, 2.0)
    free = smap((0.2, 0.1))
    with Budget(60.0):
        held = smap((0.2, 0.1))
    np.testing.assert_array_equal(free.point, held.point)
    np.testing.assert_array_equal(free.jacobian, held.jacobian)


def _in_budget_thread(budget, fn, *args):
    """(thread, got): ``fn(*args)`` inside ``budget`` in a daemon thread, started; ``got`` then holds its
    "result" ("returned" or the BudgetExceeded message) and the perf_counter time it "ended"."""
    got: dict = {}

    def work():
        try:
            with budget:
                fn(*args)
            got["result"] = "returned"
        except BudgetExceeded as exc:
            got["result"] = str(exc)
        got["ended"] = time.perf_counter()

    thread = threading.Thread(target=work, daemon=True)
    thread.start()
    return thread, got


@pytest.mark.skipif(NOJIT, reason="plain Python holds the GIL and reads no switch mid-step (EXPLORER_NOJIT)")
def test_a_cancelled_return_at_a_huge_circulation_ends_at_once_and_leaves_the_main_thread_running():
    prm = model.FIGURE4.with_(mu=HUGE_MU)
    smap = SectionMap(prm, model.FIGURE4_H)
    SectionMap(model.FIGURE4, 2.0)((0.1, 0.0))          # compiled (or loaded) first
    x = (0.0, 0.0)
    budget = Budget()
    thread, got = _in_budget_thread(budget, smap, x)
    t0 = last = time.perf_counter()
    stall = 0.0
    while time.perf_counter() - t0 < 1.0 and thread.is_alive():      # the main thread wakes every ms
        time.sleep(0.001)
        now = time.perf_counter()
        stall, last = max(stall, now - last), now
    assert thread.is_alive(), "the return ended by itself: too short to tell"
    cancelled = time.perf_counter()
    budget.cancel()
    thread.join(10.0)
    assert not thread.is_alive() and "cancelled" in got["result"]
    assert got["ended"] - cancelled < 0.5                               # within a step, not minutes
    assert stall < 0.5, f"the main thread stalled {stall:.3f} s: the return holds the GIL"


def test_a_budget_ends_a_search_at_its_seconds_and_caps_the_crossing_batches():
    from explorer.app.serve.overlays import fixed_points, periodic_orbits, search_budget
    from explorer.app.serve.settings import Settings

    s = Settings(params=model.FIGURE4.with_(mu=HUGE_MU))
    for search in (fixed_points, periodic_orbits):
        t0 = time.perf_counter()
        with search_budget(1.0):
            _found, text = search(s)
        took = time.perf_counter() - t0
        assert "budget of 1 s" in text and took < 5.0, (search.__name__, text, took)
    with Budget(None, max_steps=10):
        assert step_cap(10**9) == 10
        prm = model.FIGURE4.with_(mu=0.3)
        c = sections.crossings(prm, 2.0, [(0.2, 0.1)], n_crossings=5)
        assert c.count[0] < 5                                             # 10 steps: not 5 returns
    assert step_cap(10**9) == 10**9
    b = Budget(None)
    b.cancel()
    with b, pytest.raises(BudgetExceeded):
        sections.crossings(model.FIGURE4, 2.0, [(0.2, 0.1)], n_crossings=5)


@pytest.mark.skipif(NOJIT, reason="plain Python holds the GIL and reads no switch mid-step (EXPLORER_NOJIT)")
@pytest.mark.parametrize("method", ["taylor", "dop853", "split4", "system"])
def test_a_cancel_ends_the_chaos_indicators_of_every_method_within_a_step(method):
    """The page's chaos layer runs lyapunov.indicators in a budget: a cancel (a closed tab, a new value) ends
    every orbit of the batch at its next step, the fixed-step and DOP853 loops and a System's included, and the
    call raises BudgetExceeded instead of returning a partial result."""
    from systems import henon_heiles

    if method == "system":
        args, kw = (henon_heiles(),), {"states": [[0.0, 0.1, 0.35, 0.0]] * 40}
    else:
        prm = model.FIGURE4.with_(mu=0.3)
        y0 = model.section_state(prm, np.linspace(-0.2, 0.2, 40), np.zeros(40), 2.0)
        args, kw = (prm,), {"states": y0, "method": method, "dt": 0.05}
    lyapunov.indicators(*args, tmax=1.0, **kw)                        # compiled (or loaded) first
    budget = Budget()
    thread, got = _in_budget_thread(budget, functools.partial(lyapunov.indicators, tmax=1e7, **kw), *args)
    thread.join(0.2)                                                   # (hours of steps uncancelled)
    assert thread.is_alive(), got
    cancelled = time.perf_counter()
    budget.cancel()
    thread.join(60.0)
    assert not thread.is_alive() and "cancelled" in got["result"], got
    assert got["ended"] - cancelled < CANCEL_SECONDS


@pytest.mark.skipif(NOJIT, reason="plain Python holds the GIL and reads no switch mid-step (EXPLORER_NOJIT)")
def test_a_cancelled_half_turn_raises_instead_of_giving_a_point_without_a_return():
    """half_turns marks a point with no return NaN; a cancel is not that: it raises BudgetExceeded."""
    smap = SectionMap(model.FIGURE4.with_(mu=HUGE_MU), model.FIGURE4_H)
    SectionMap(model.FIGURE4, 2.0).half_turns([(0.1, 0.0)], 1)        # compiled (or loaded) first
    budget = Budget()
    thread, got = _in_budget_thread(budget, smap.half_turns, [(0.0, 0.0)], 1)
    thread.join(0.2)
    assert thread.is_alive(), got
    budget.cancel()
    thread.join(60.0)
    assert not thread.is_alive() and "cancelled" in got["result"], got
