"""`explorer serve`: the orbit list and the stepper beside the fields (issue 32, item 2).

Without a browser (a SectionPage in-process): the list lists every orbit with its colour, start,
crossings so far and state (running, paused, done); choosing one selects it as a pick does (its
readout, its highlight on the section, its row marked) and a pick marks its row; hiding an orbit
takes its rows off every source the page draws (and off the figure exports, not off the scene),
while it keeps computing, and showing it puts back the uninterrupted run bit for bit; delete
removes one orbit from the page, the session and the link; a step of the stepper applies a value
through the field, refused as the command line refuses it.  In chromium: the list is on the page,
choosing an orbit there highlights it, and *hide* takes its dots off.
"""
from __future__ import annotations

import re

import numpy as np
import pytest
import test_serve
from page_loop import settle
from test_serve import SERVED, _click, _open, _poll_until, _wait, _wait_crossings, browser_needed

from explorer import model
from explorer.analysis import sections
from explorer.app.serve.settings import Settings, parse_starts
from explorer.model import ParameterError

#: chromium and the served page (`--mu 0.03`), as in test_serve.py (its module-scoped fixtures)
browser = test_serve.browser
served = test_serve.served
#: crossings of an orbit long enough that a second click comes while it still runs (in-process the page
#: computes only while polled, and an orbit's first block is 16 crossings)
LONG = 5_000
ROW = re.compile(r"<tr data-orbit='(\d+)' style='([^']*)'>(.*?)</tr>")
CELL = re.compile(r"<td[^>]*>(.*?)</td>")


def _page(settings, args=None):
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage

    return SectionPage(settings, args or {})


def _table(page) -> dict:
    """The list as the page shows it: {orbit id: (row style, [cell texts])}."""
    return {int(i): (style, CELL.findall(cells)) for i, style, cells in ROW.findall(page.orbit_list.table.text)}


def _rows(page, ident) -> np.ndarray:
    """The orbit's rows in the page's store (drawn or hidden)."""
    run = page.orbits.runs[ident]
    return run.rows[:run.done]


def _drawn(page, ident) -> int:
    """How many rows of orbit ``ident`` the browser's sources hold (dots, live layer, starts)."""
    return sum(int(np.count_nonzero(np.asarray(src.data["orbit"]) == ident))
               for src in (page.orbits.shown, page.orbits.live, page.orbits.start_source))


def _hidden(page) -> set:
    """The ids of the hidden orbits."""
    return {i for i, r in page.orbits.runs.items() if r.hidden}


def test_the_list_shows_every_orbit_with_its_colour_start_crossings_and_state():
    from explorer.app.serve.orbits import COLORS

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=LONG)
    c1, c2, r1, r2 = s.region
    page = _page(s)
    try:
        assert page.orbit_list.table.text == ""                                   # no orbit, no table
        first = page.click(c1 + 0.3 * r1, c2).ident
        while not len(_rows(page, first)):                                        # (no poll more: it runs on)
            test_serve.poll(page)
        second = page.click(c1 - 0.5 * r1, c2 + 0.2 * r2).ident                    # pauses the first
        _poll_until(page, lambda: len(_rows(page, second)) == LONG and " 0 running" in page.orbits.status.text)
        table = _table(page)
        assert list(table) == [first, second]                                     # every orbit, in click order
        for ident, p1, p2, c in page.orbits.starts:
            _style, cells = table[ident]
            assert f"background:{COLORS[c]}" in cells[0] and cells[1] == str(ident)
            assert cells[2] == f"({p1:.6g}, {p2:.6g})"
            assert cells[3] == str(len(_rows(page, ident)))                       # crossings so far, as on the page
        assert table[first][1][4] == "paused" and 0 < len(_rows(page, first)) < LONG
        assert table[second][1][4] == "done"
        page.orbit_list.resume()
        assert _table(page)[first][1][4] == "running"
        settle(page)
        assert all(r.status != "running" for r in page.orbits.runs.values())
        assert _table(page)[first][1][3:] == [str(LONG), "done"]
    finally:
        page.close()


def test_choosing_an_orbit_selects_it_as_a_pick_does_and_a_pick_marks_its_row():
    from explorer.app.serve.page_orbit_list import SELECTED_BACKGROUND

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=40)
    page = _page(s)
    try:
        for p in ((0.3, 0.1), (1.3, 0.05)):
            page.click(*p)
        page.orbit_list.resume()
        _poll_until(page, lambda: len(page.orbits.columns()["t"]) == 2 * s.crossings)
        one, two = (i for i, *_ in page.orbits.starts)
        lst = page.orbit_list
        assert lst.filter.group == 0 and lst.hide_button.disabled       # nothing selected yet
        lst.choice.value = two                                                    # chosen in the list
        assert page.orbit_list.picked == two and "orbit 2 from (1.3, 0.05)" in page.orbit_list.text.text
        _poll_until(page, lambda: page.orbits.runs[two].readout and "rotation number" in page.orbit_list.text.text)
        # the highlight: the browser's filter keeps exactly this orbit's rows of the drawn dots
        assert lst.filter.group == two and lst.marks.data_source is page.orbits.shown
        kept = np.asarray(page.orbits.shown.data["orbit"]) == lst.filter.group
        np.testing.assert_array_equal(np.asarray(page.orbits.shown.data["p1"])[kept], _rows(page, two)[:, 1])
        assert lst.marks.glyph.size > page.orbits.points.glyph.size                      # larger, outlined
        assert SELECTED_BACKGROUND in _table(page)[two][0] and SELECTED_BACKGROUND not in _table(page)[one][0]
        assert not lst.hide_button.disabled and not lst.delete_button.disabled
        shown_by_list = page.orbit_list.text.text
        # a pick (Shift + click) of the other orbit: the list follows it
        d = page.orbits.columns()
        k = int(np.flatnonzero(np.asarray(d["orbit"]) == one)[5])
        assert page.orbit_list.pick(float(d["p1"][k]), float(d["p2"][k])) == one
        assert lst.choice.value == one and lst.filter.group == one
        assert SELECTED_BACKGROUND in _table(page)[one][0] and SELECTED_BACKGROUND not in _table(page)[two][0]
        lst.choice.value = two                                                    # back: the same readout, at once
        assert page.orbit_list.text.text == shown_by_list
        lst.choice.value = 0                                                      # none
        assert page.orbit_list.picked is None and page.orbit_list.text.text == "" and lst.filter.group == 0
    finally:
        page.close()


def test_a_hidden_orbit_leaves_every_drawn_source_keeps_computing_and_comes_back_bit_for_bit():
    import tomllib

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=LONG)
    c1, c2, r1, r2 = s.region
    a, b = (c1 + 0.3 * r1, c2), (c1 - 0.5 * r1, c2 + 0.2 * r2)
    page = _page(s, {"pause": "0"})                          # both run to their end
    try:
        first = page.click(*a).ident
        _poll_until(page, lambda: len(_rows(page, first)) > 0)
        page.orbit_list.toggle(first)                       # hidden while it runs
        assert _drawn(page, first) == 0 and first not in page.orbits.columns()["orbit"]
        assert "hidden" in _table(page)[first][1][4]
        second = page.click(*b).ident
        settle(page)
        assert all(r.status != "running" for r in page.orbits.runs.values())
        assert _drawn(page, first) == 0 and first not in page.orbits.columns()["orbit"]   # its later rows: hidden too
        assert set(np.asarray(page.orbits.shown.data["orbit"]).tolist()) == {second}
        assert _table(page)[first][1][3:] == [str(LONG), "done, hidden"]         # it went on computing
        assert page.orbit_list.pick(*a) != first                                             # not pickable while hidden
        view = page.exports.view()                                                # the figures: the view ...
        assert [o[0] for o in view.orbits] == [second] and len(view.starts) == 1
        assert len(tomllib.loads(page.scene().to_toml())["seeds"]["points"]) == 2   # ... the scene: the session
        page.orbit_list.toggle(first)                                             # shown again
        rows = _rows(page, first)
        ref = sections.crossings(s.params, s.h, [a], n_crossings=s.crossings, **s.section_kwargs())
        np.testing.assert_array_equal(rows, ref.orbit(0))                         # the uninterrupted run
        assert _drawn(page, first) == LONG + 1 and "hidden" not in _table(page)[first][1][4]
        page.orbit_list.toggle(second)
        page.inputs["crossings"].value = "50"                                     # a new value: still hidden
        hidden_again = page.orbits.starts[1][0]
        settle(page)
        assert all(r.status != "running" for r in page.orbits.runs.values())
        assert _hidden(page) == {hidden_again} and _drawn(page, hidden_again) == 0
        assert len(_rows(page, hidden_again)) == 50
    finally:
        page.close()


def test_delete_removes_one_orbit_from_the_page_the_session_and_the_link():
    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=40)
    starts = [(0.3, 0.1), (1.3, 0.05), (0.5, -0.2)]
    page = _page(s)
    try:
        for p in starts:
            page.click(*p)
        page.orbit_list.resume()
        _poll_until(page, lambda: len(page.orbits.columns()["t"]) == 3 * s.crossings)
        one, two, three = (i for i, *_ in page.orbits.starts)
        page.orbit_list.choice.value = two
        assert not page.orbit_list.delete_button.disabled
        page.orbit_list.delete(page.orbit_list.picked)                                       # what *delete* does
        assert [i for i, *_ in page.orbits.starts] == [one, three] and _drawn(page, two) == 0
        assert list(_table(page)) == [one, three] and page.orbit_list.picked is None
        assert parse_starts(page.url_query()["orbits"]) == [starts[0], starts[2]]
        assert "2 orbit(s)" in page.orbits.status.text
        page.orbit_list.undo()                                                               # Undo: still the newest
        assert [i for i, *_ in page.orbits.starts] == [one] and list(_table(page)) == [one]
    finally:
        page.close()


def test_the_hidden_orbits_are_in_the_link_and_a_page_from_it_keeps_them_hidden():
    """Which orbits are hidden is in the link (``hidden``: their positions among its ``orbits``),
    so a reload keeps them hidden; a malformed ``hidden`` is ignored and said, the rest applies."""
    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=40)
    starts = [(0.3, 0.1), (1.3, 0.05), (0.5, -0.2)]
    page = _page(s, {"pause": "0"})
    try:
        for p in starts:
            page.click(*p)
        one, two, three = (i for i, *_ in page.orbits.starts)
        assert page.url_query()["hidden"] == ""
        page.orbit_list.toggle(two)
        page.orbit_list.toggle(three)
        assert test_serve._link(page)["hidden"] == "2,3"                             # the link follows at once
        page.orbit_list.toggle(three)
        assert test_serve._link(page)["hidden"] == "2" == page.url_query()["hidden"]
        link = page.url_query()
    finally:
        page.close()
    again = _page(s, link)                                                        # a reload of that link
    try:
        settle(again)
        assert all(r.status != "running" for r in again.orbits.runs.values())
        ids = [i for i, *_ in again.orbits.starts]
        assert _hidden(again) == {ids[1]} and _drawn(again, ids[1]) == 0
        assert len(_rows(again, ids[1])) == s.crossings                 # computed all the same
        assert [_drawn(again, i) for i in (ids[0], ids[2])] == [s.crossings + 1] * 2
        assert "done, hidden" in _table(again)[ids[1]][1][4] and again.url_query()["hidden"] == "2"
    finally:
        again.close()
    for bad in ("4", "x", "0", "1,,2"):
        page = _page(s, {**link, "hidden": bad})
        try:
            assert page.message.text.startswith("link ignored in part (the rest applies): hidden"), bad
            assert len(page.orbits.starts) == 3 and not _hidden(page) and page.url_query()["hidden"] == ""
        finally:
            page.close()


def test_a_step_applies_its_value_through_the_field_refused_as_the_command_line_refuses_it():
    page = _page(SERVED)
    f = page.fields
    try:
        assert f.step_field.value == "mu" and f.step_size.value == pytest.approx(1e-4)
        f.step(+1)
        assert page.settings.params.mu == 0.0301 and page.inputs["mu"].value == "0.0301"
        f.step(-1)
        f.step(-1)
        assert page.settings.params.mu == 0.0299
        page.inputs["h"].value = "2.5"                                            # the last field edited ...
        assert f.step_field.value == "h" and page.settings.h == 2.5
        f.step_size.value = 0.25
        f.step(+1)                                                                # ... is the one stepped
        assert page.settings.h == 2.75
        f.step_field.value = "crossings"
        f.step_size.value = 10.0
        f.step(+1)
        assert page.settings.crossings == SERVED.crossings + 10
        f.step_field.value = "a1"
        f.step_size.value = 5.0                                                   # a1 = 1 - 5: refused ...
        before = page.settings
        f.step(-1)
        with pytest.raises(ParameterError) as refused:                            # ... as the command line's checks
            SERVED.with_fields({"a1": page.inputs["a1"].value})
        assert page.message.text == f"not applied: {refused.value}" and page.settings == before
        f.step(-1)                                                                # the same step again: said again
        assert page.message.text == f"not applied: {refused.value}"
        f.step_size.value = 0.5
        f.step(-1)                                                                # from the value that applies
        assert page.settings.params.a1 == SERVED.params.a1 - 0.5 and page.message.text == ""
    finally:
        page.close()


# ---------------------------------------------------------------- in chromium
def _orbit_1(hidden: bool) -> str:
    """A wait's expression: the page's one orbit hidden (its dots and start off the page, the list
    saying so) or shown (all its dots and its start on the page, the list not saying hidden)."""
    drawn = "n === 0 && s === 0 && said" if hidden else f"n >= {SERVED.crossings} && s === 1 && !said"
    return ("() => { const d = Bokeh.documents[0], n = d.get_model_by_name('crossings').data.p1.length,"
            " s = d.get_model_by_name('starts').data.p1.length,"
            f" said = d.get_model_by_name('orbit-list').text.includes('hidden'); return {drawn}; }}")


@pytest.fixture(scope="module")
def chosen(served, browser):
    """One served page with one orbit clicked, computed and chosen in the list (selected: highlighted,
    its readout shown), for the two tests below: the first hides it and shows it again (the page is
    as it was), the second hides it and reloads the link."""
    page = _open(browser, served.url)
    try:
        c1, c2, r1, _r2 = SERVED.region
        _click(page, c1 + 0.3 * r1, c2)
        _wait_crossings(page, SERVED.crossings)
        _wait(page, "() => Bokeh.documents[0].get_model_by_name('orbit-list').text.includes(\"data-orbit='1'\")")
        page.locator("select").filter(has_text="(none)").select_option(index=1)
        _wait(page, "() => Bokeh.documents[0].get_model_by_name('selected-orbit').group === 1 && "
                    "Bokeh.documents[0].get_model_by_name('readout').text.startsWith('orbit 1')")
        yield page
    finally:
        page.close()


@browser_needed
def test_in_the_browser_the_list_selects_and_hides_an_orbit(chosen):
    page = chosen
    page.get_by_role("button", name="hide", exact=True).click()
    _wait(page, _orbit_1(True))
    page.get_by_role("button", name="show", exact=True).click()
    _wait(page, _orbit_1(False), polling=100)


@browser_needed
def test_in_the_browser_a_hidden_orbit_stays_hidden_after_a_reload(chosen):
    page = chosen
    page.get_by_role("button", name="hide", exact=True).click()
    # the link with the orbit hidden, and the page without its dots: one state, read where it was waited for
    link = _wait(page, "() => { const d = Bokeh.documents[0], q = new URLSearchParams(location.search);"
                       " return q.get('hidden') === '1' && d.get_model_by_name('crossings').data.p1.length === 0"
                       " && d.get_model_by_name('orbit-list').text.includes('hidden') && location.href; }")
    page.goto(link)                                                 # a reload of that link
    # the orbit computed to its end on the server (the list says so) and not one dot of it drawn
    seen = _wait(page, "() => { const d = window.Bokeh && Bokeh.documents[0]; if (!d) return false;"
                       " const list = d.get_model_by_name('orbit-list'); if (!list) return false;"
                       " return list.text.includes('done, hidden') && {crossings:"
                       " d.get_model_by_name('crossings').data.p1.length, live:"
                       " d.get_model_by_name('live').data.p1.length, starts:"
                       " d.get_model_by_name('starts').data.p1.length, list: list.text,"
                       " hidden: new URLSearchParams(location.search).get('hidden')}; }",
                 timeout=test_serve.FIRST_ORBIT_TIMEOUT_MS, polling=100)
    assert (seen["crossings"], seen["live"], seen["starts"], seen["hidden"]) == (0, 0, 0, "1"), seen
    assert f">{SERVED.crossings}</td>" in seen["list"]


def test_a_readout_that_arrives_while_a_block_computes_stays_on_its_orbit():
    """The worker hands a block computed on a copy of the run back to the run: a readout the page kept on the
    run meanwhile (OrbitList._keep) is not overwritten by the copy's."""
    import copy

    from explorer.app.serve.orbits import OrbitRun, Worker

    worker = Worker(None, lambda *_a: None)
    run = worker.runs[1] = OrbitRun(1, 0.3, 0.1, settings=None, marked=False)
    work = copy.copy(run)                               # the block's copy, taken before the readout came
    run.readout = ({"megno": 2.0}, "orbit 1 from (0.3, 0.1): ...")
    run.marked = True                                   # (OrbitsLayer.mark_starts meanwhile)
    work.done = 3
    worker._hand_out(run, work, np.zeros((0, 5)), None)
    assert run.done == 3 and run.readout == ({"megno": 2.0}, "orbit 1 from (0.3, 0.1): ...") and run.marked
