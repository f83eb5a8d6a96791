"""`explorer serve`: a new crossings per click alone reruns only an orbit stopped on its time budget
(docs/commands/serve.md).

Without a browser (a SectionPage in-process): raised, each orbit continues from where it stopped and
its rows are those of one uninterrupted run of the new count; lowered, each orbit's rows (drawn or
hidden) are cut to the new count with no computation, and raised again, the cut rows come back
without computation; an orbit stopped on its time budget (which grows with the count) reruns from
its start.  For Chaplygin's page and a System's.
"""
from __future__ import annotations

import numpy as np
import pytest
from page_loop import settle
from systems import henon_heiles_map

import explorer as ex
from explorer import model
from explorer.analysis import sections
from explorer.app.serve.orbits import OrbitRun
from explorer.app.serve.settings import Settings

pytest.importorskip("panel", reason="panel is not installed (pip install panel)")

N = 120
STARTS = ((0.3, 0.1), (-0.4, 0.2))


def _rows(page, ident) -> np.ndarray:
    """The orbit's rows in the page's store (drawn or hidden)."""
    run = page.orbits.runs[ident]
    return run.rows[:run.done]


def _progress(page, ident) -> tuple:
    return len(_rows(page, ident)), page.orbits.runs[ident].phase


@pytest.fixture
def computed(monkeypatch):
    """The crossings the orbits compute from now on (their blocks' rows, summed)."""
    got = {"rows": 0}

    def counted(self, _advance=OrbitRun.advance):
        rows = _advance(self)
        got["rows"] += len(rows)
        return rows
    monkeypatch.setattr(OrbitRun, "advance", counted)
    return got


def _set_crossings(page, k: int) -> None:
    page.inputs["crossings"].value = str(k)
    settle(page)
    assert page.settings.crossings == k


def test_raising_the_crossings_continues_each_orbit_and_lowering_cuts_it_without_computing(computed):
    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.5), crossings=N)
    page = SectionPage(s)
    page.orbits.pause_box.value = False                   # (a click would pause the orbit before it)
    try:
        runs = [page.click(*p) for p in STARTS]
        settle(page)
        page.orbits.hide(runs[1].ident)                 # (a hidden orbit's rows are cut and continued too)
        ref = sections.crossings(s.params, s.h, list(STARTS), n_crossings=2 * N, **s.section_kwargs())
        computed["rows"] = 0
        _set_crossings(page, 2 * N)
        assert computed["rows"] == 2 * N                  # N more per orbit: none reran
        for i, run in enumerate(runs):
            np.testing.assert_array_equal(_rows(page, run.ident), ref.orbit(i))
            assert page.orbits.runs[run.ident].phase == "done"
        computed["rows"] = 0
        _set_crossings(page, N // 2)
        _set_crossings(page, 2 * N)                       # (the cut rows come back)
        _set_crossings(page, N // 2)
        assert computed["rows"] == 0
        for i, run in enumerate(runs):
            np.testing.assert_array_equal(_rows(page, run.ident), ref.orbit(i)[:N // 2])
            assert _progress(page, run.ident) == (N // 2, "done")
        assert len(page.orbits.shown.data["orbit"]) == N // 2 and not len(page.orbits.live.data["orbit"])
        assert page.url_query()["crossings"] == str(N // 2)
    finally:
        page.close()


def test_a_systems_page_continues_and_cuts_its_orbits_too(computed):
    from explorer.app.serve.page import SectionPage
    from explorer.app.serve.settings import SystemSettings

    smap = henon_heiles_map()
    page = SectionPage(SystemSettings(smap, crossings=40))
    try:
        run = page.click(0.1, 0.1)
        settle(page)
        computed["rows"] = 0
        _set_crossings(page, 80)
        assert computed["rows"] == 40
        ref = ex.crossings(smap.with_tol(page.settings.tol), [(0.1, 0.1)], n_crossings=80).data[0]
        rows = _rows(page, run.ident)
        np.testing.assert_array_equal(rows[:, 1:4], ref[:, [2, 4, 3]])          # (y, py, px): the map's iterates
        np.testing.assert_array_equal(rows[:, 0], ref[:, 0])
        computed["rows"] = 0
        _set_crossings(page, 25)
        assert computed["rows"] == 0
        np.testing.assert_array_equal(_rows(page, run.ident), rows[:25])
    finally:
        page.close()


#: an orbit's time budget per crossing here: about half the time between two crossings at mu = 0.5
#: (9.8), so that an orbit stops on its budget (100 per crossing by default) about half way
TMAX_PER_CROSSING = 5.0


def test_an_orbit_stopped_on_its_time_budget_reruns_from_its_start_when_the_crossings_grow(computed, monkeypatch):
    """The budget grows with the crossings per click (tmax = 100 K by default): an orbit that stopped
    on it cannot continue where it stopped, it reruns from its start at the new count."""
    from explorer.app.serve.page import SectionPage
    from explorer.kernels import STATUS_NAMES, STATUS_TMAX

    iter_crossings = sections.iter_crossings
    monkeypatch.setattr(sections, "iter_crossings", lambda *a, n_crossings, **kw: iter_crossings(
        *a, n_crossings=n_crossings, tmax=TMAX_PER_CROSSING * n_crossings, **kw))
    s = Settings(params=model.FIGURE4.with_(mu=0.5), crossings=N)
    page = SectionPage(s)
    try:
        run = page.click(*STARTS[0])
        settle(page)
        done, status = _progress(page, run.ident)
        assert status == STATUS_NAMES[STATUS_TMAX] and 0 < done < N
        ref = sections.crossings(s.params, s.h, [STARTS[0]], n_crossings=2 * N, tmax=TMAX_PER_CROSSING * 2 * N,
                                 **s.section_kwargs())
        assert int(ref.count[0]) > done                  # (the longer budget reaches further)
        computed["rows"] = 0
        _set_crossings(page, 2 * N)
        assert computed["rows"] == int(ref.count[0])     # every row again, from the start
        np.testing.assert_array_equal(_rows(page, run.ident), ref.orbit(0))
        assert _progress(page, run.ident) == (int(ref.count[0]), STATUS_NAMES[STATUS_TMAX])
    finally:
        page.close()
