"""The compiled drivers Python calls release the GIL while they run (docs/architecture.md,
Parallelism): ``explorer serve`` integrates in a worker thread while its event loop, in the same
process, answers the browser (issue 22)."""
from __future__ import annotations

import threading
import time

import pytest

from explorer import model
from explorer._jit import NOJIT
from explorer.analysis import lyapunov, sections

MU = 0.03


def _longest_stall(work) -> tuple[float, float]:
    """(longest gap between the main thread's wake-ups, total time) while ``work`` runs in a
    thread; the main thread wakes every millisecond when it can take the GIL."""
    done = threading.Event()
    thread = threading.Thread(target=lambda: (work(), done.set()))
    t0 = last = time.perf_counter()
    longest = 0.0
    thread.start()
    while not done.is_set():
        time.sleep(0.001)
        now = time.perf_counter()
        longest, last = max(longest, now - last), now
    thread.join()
    return longest, time.perf_counter() - t0


@pytest.mark.skipif(NOJIT, reason="plain Python holds the GIL (EXPLORER_NOJIT)")
@pytest.mark.parametrize("what", ["crossings", "indicators"])
def test_a_driver_running_in_a_thread_leaves_the_main_thread_running(what):
    params = model.FIGURE4.with_(mu=MU)
    y0 = model.section_state(params, [0.3], [0.1], 2.0)
    if what == "crossings":
        def work(n):
            sections.crossings(params, states=y0, n_crossings=n)
    else:
        def work(n):
            lyapunov.indicators(params, states=y0, tmax=2.0 * n)
    work(10)                                   # compiled (or loaded) first
    n = 5_000
    for _ in range(6):                         # a call long enough to tell (x4 until it takes 0.3 s)
        stall, took = _longest_stall(lambda: work(n))
        if took > 0.3:
            break
        n *= 4
    assert took > 0.3, f"the call took {took:.3f} s: too short to tell"
    # with the GIL held, the main thread would sleep through the whole call
    assert stall < 0.5 * took, f"the main thread stalled {stall:.3f} s of a {took:.3f} s call"
