"""`explorer serve`: what the page tells and shows after a change (issue 32, items 2-6).

Without a browser (a SectionPage in-process): a refused value does not poison later edits of other
fields; the status line follows a change that drops every start; successes and errors have their
own colours; at mu = 1.5 the fixed-point overlay lists its hyperbolic points at once and draws
their separatrices without a "no return" failure; readability (separatrices on the MEGNO layer, its
colour bar, start markers, unique SVG ids, the exported scene's overlays); phi0 and the zoom window
in the link; the first 20 orbits have 20 colours.  In chromium: at 1280 x 720 the export buttons
are in view; after a change of mu the view follows the new region, and Reset goes
back to it (not to the first window).  (A page whose server stops says so:
test_serve_system.py::test_in_the_browser_a_systems_page_clicks_orbits_on_its_energy_level_and_draws_its_megno_layer,
which stops its own server.)
"""
from __future__ import annotations

import math
import time

import pytest
import test_serve
from page_loop import poll, settle
from test_serve import SERVED, TO_SCREEN, _click, _link, _open, _set_field, _wait, browser_needed

from explorer import model
from explorer.app.serve.settings import FIELDS, Settings

#: chromium and the served page (`--mu 0.03`), as in test_serve.py (one per pytest process:
#: tests/app/browser_session.py)
browser = test_serve.browser
served = test_serve.served


def _page(settings, args=None):
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage

    return SectionPage(settings, args or {})


def _poll_until(page, cond, timeout=240.0):
    t0 = time.time()
    while time.time() - t0 < timeout:
        poll(page)
        if cond():
            return
        time.sleep(0.02)
    raise AssertionError(f"timed out; overlay: {page.overlays.text.text!r}; message: {page.message.text!r}")


def test_a_refused_value_does_not_poison_later_edits_of_other_fields():
    page = _page(SERVED)
    try:
        page.inputs["h"].value = "1e300"
        assert "not applied: h must be in" in page.message.text and page.settings.h == SERVED.h
        page.inputs["mu"].value = "0.5"                       # another field: applied, not refused for h
        assert page.settings.params.mu == 0.5 and page.settings.h == SERVED.h
        assert page.message.text == "" and page.inputs["h"].value == repr(SERVED.h)   # the fields show what applies
    finally:
        page.close()


def test_the_status_line_follows_a_change_that_drops_every_start():
    page = _page(SERVED)
    try:
        c1, c2, r1, _r2 = SERVED.region
        assert page.click(c1 + 0.9 * r1, c2) is not None
        assert "1 orbit(s)" in page.orbits.status.text
        page.inputs["h"].value = "0.7"                        # a smaller region: the start is outside it
        assert page.settings.h == 0.7 and page.orbits.starts == []
        assert "dropped" in page.message.text
        assert page.orbits.status.text.startswith("0 orbit(s), 0 running") and "h = 0.7" in page.orbits.status.text
    finally:
        page.close()


def test_successes_and_errors_are_shown_in_their_own_colours():
    from explorer.app.serve.style import MESSAGE_ERROR_COLOR, MESSAGE_OK_COLOR

    page = _page(Settings(params=model.FIGURE4.with_(mu=0.03), crossings=20))
    try:
        page.inputs["tol"].value = "0.5"
        assert "not applied" in page.message.text and page.message.styles["color"] == MESSAGE_ERROR_COLOR
        page.inputs["tol"].value = repr(page.settings.tol)
        assert page.run_seeds() > 0
        assert "orbits started" in page.message.text and page.message.styles["color"] == MESSAGE_OK_COLOR
        page.click(50.0, 50.0)                                # outside the region: an error again
        assert "outside" in page.message.text and page.message.styles["color"] == MESSAGE_ERROR_COLOR
    finally:
        page.close()


def test_at_mu_1_5_the_overlay_lists_the_hyperbolic_fixed_points_at_once_and_draws_their_separatrices():
    page = _page(Settings(params=model.FIGURE4.with_(mu=1.5)), {"separatrices": "1"})
    try:
        _poll_until(page, lambda: page.overlays.fixed.data["p1"] != [])
        kinds = page.overlays.fixed.data["kind"]
        assert kinds.count("hyperbolic") >= 5                  # the five saddles at mu = 1.5
        assert page.overlays.text.text.count("hyperbolic") == kinds.count("hyperbolic")   # each listed
        assert "growing the separatrices" in page.overlays.text.text         # ... while the curves grow
        _poll_until(page, lambda: "separatrix branches" in page.overlays.text.text)
        text = page.overlays.text.text
        assert "failed" not in text and "no return" not in text, text
        assert text.count("hyperbolic") == kinds.count("hyperbolic")                      # still listed
        assert len(page.overlays.curves.data["xs"]) >= 4
    finally:
        page.close()


RANGE = ("() => { const f = Bokeh.documents[0].get_model_by_name('section');"
         " return [f.x_range.start, f.x_range.end, f.y_range.start, f.y_range.end]; }")


#: every button that exports, which must be in view at 1280 x 720 without scrolling
EXPORT_BUTTONS = ("Scene (TOML)", "Figure (PNG)", "Figure (SVG)", "Export scene", "Export figure")


#: the section's canvas in the page: width, height, top, bottom (CSS pixels)
CANVAS = ("() => { const r = Bokeh.index.all_views().find(v => v.model.name === 'section').el"
          ".getBoundingClientRect(); return [r.width, r.height, r.top, r.bottom]; }")
#: whether the check box whose label is the text is ticked (its Bokeh model)
BOX_ON = ("(text) => [...Bokeh.documents[0].all_models].find(m => m.type === 'CheckboxGroup' && "
          "m.labels[0] === text).active.includes(0)")


@browser_needed
def test_at_1280_by_720_the_export_buttons_are_in_view_then_the_view_follows_a_new_region_and_reset_goes_back(
        served, browser):
    page = _open(browser, served.url)
    try:
        page.set_viewport_size({"width": 1280, "height": 720})
        _wait(page, "() => window.innerWidth === 1280 && window.innerHeight === 720 && Bokeh.documents[0].is_idle")
        for name in EXPORT_BUTTONS:                            # (the layout does not depend on timing)
            box = page.get_by_role("button", name=name).bounding_box()
            assert box is not None and box["y"] >= 0 and box["y"] + box["height"] <= 720, (name, box)
        _the_orbit_list_is_beside_the_figure_in_view(page, 1280, 720)
        # every field says what it sets (a tooltip icon of its own, drawn)
        from explorer.app.serve.page_fields import LABELS

        tips = page.evaluate(TOOLTIPS)
        assert sorted(t for t, n in tips if n == 1) == sorted(LABELS[f] for f in FIELDS), tips
        # the figure sized to the window: as wide as the controls leave it, bounded by its height
        narrow = page.evaluate(CANVAS)
        assert narrow[3] <= 720 and 0.9 * 660 <= narrow[0] <= 1280 - 230, narrow
        # a check box's label is clickable: its text ticks it (the server has it: the link says so)
        page.get_by_text("colour orbits by MEGNO", exact=True).click()
        _wait(page, "() => window.location.search.includes('colour=megno')")
        assert page.evaluate(BOX_ON, "colour orbits by MEGNO")
        _set_field(page, "mu", "1.5")
        _wait(page, "() => window.location.search.includes('mu=1.5')")
        c1, c2, r1, r2 = Settings(params=SERVED.params.with_(mu=1.5), crossings=SERVED.crossings).region
        x0, x1, y0, y1 = page.evaluate(RANGE)
        assert x0 < c1 - r1 and x1 > c1 + r1 and y0 < c2 - r2 and y1 > c2 + r2     # the whole new region
        assert x1 - x0 < 1.5 * 2 * r1 or y1 - y0 < 1.5 * 2 * r2                    # and not much more
        box = page.evaluate(test_serve.TO_SCREEN, [c1, c2])
        page.mouse.move(*box)
        page.mouse.wheel(0, -600)                              # zoom in
        _wait(page, f"() => ({RANGE})()[1] - ({RANGE})()[0] < {0.9 * (x1 - x0)}")
        page.locator(".bk-tool-icon-reset").first.click()
        _wait(page, f"() => Math.abs(({RANGE})()[0] - {x0}) < 1e-9 && Math.abs(({RANGE})()[1] - {x1}) < 1e-9")
        page.set_viewport_size({"width": 1400, "height": 900})
        _wait(page, "() => window.innerWidth === 1400 && window.innerHeight === 900 && Bokeh.documents[0].is_idle")
        _the_orbit_list_is_beside_the_figure_in_view(page, 1400, 900)
        page.set_viewport_size({"width": 1800, "height": 1100})      # a larger window: a larger figure
        _wait(page, f"() => window.innerWidth === 1800 && ({CANVAS})()[0] > {narrow[0] + 300}")
        wide = page.evaluate(CANVAS)
        assert wide[3] <= 1100 and abs(wide[0] / wide[1] - narrow[0] / narrow[1]) < 0.02, (narrow, wide)
    finally:
        page.close()


#: the orbit list's chooser and table, and the figure: [left, top, right, bottom] of each
LIST_BOXES = ("() => ['orbit', 'orbit-list', 'section'].map(k => [...Bokeh.index.all_views()].find(v => "
              "v.model.name === k || v.model.title === k)).map(v => { const r = v.el.getBoundingClientRect(); "
              "return [r.left, r.top, r.right, r.bottom]; })")
#: [title, number of drawn tooltip icons] of each widget with a description
TOOLTIPS = ("() => [...Bokeh.index.all_views()].filter(v => v.model.description).map(v => [v.model.title, "
            "[...v.shadow_el.querySelectorAll('.bk-description')].filter(e => e.getBoundingClientRect().width > 0)"
            ".length])")


def _the_orbit_list_is_beside_the_figure_in_view(page, width, height):
    """The list's chooser and the top of its table right of the figure, inside the window, with
    room for rows."""
    chooser, table, figure = page.evaluate(LIST_BOXES)
    assert chooser[0] >= figure[2] - 1 and table[0] >= figure[2] - 1, (chooser, table, figure)
    assert chooser[2] <= width and table[2] <= width and chooser[3] <= table[1] <= height - 200, (chooser, table)


def _luminance(colour: str) -> float:
    """WCAG relative luminance of "#rrggbb"."""
    c = [int(colour[i:i + 2], 16) / 255.0 for i in (1, 3, 5)]
    r, g, b = (v / 12.92 if v <= 0.03928 else ((v + 0.055) / 1.055) ** 2.4 for v in c)
    return 0.2126 * r + 0.7152 * g + 0.0722 * b


def _contrast(a: str, b: str) -> float:
    la, lb = sorted((_luminance(a), _luminance(b)))
    return (lb + 0.05) / (la + 0.05)


def test_the_separatrices_stand_out_on_every_colour_of_the_megno_layer_and_it_has_a_colour_bar():
    from explorer.app.serve.style import ALLOWED_COLOR, megno_palette

    page = _page(SERVED)
    try:
        casing, line = (r.glyph.line_color for r in page.overlays.separatrix_lines)
        for background in [*megno_palette(), ALLOWED_COLOR]:           # WCAG's 3:1 for graphics
            assert max(_contrast(line, background), _contrast(casing, background)) >= 3.0, background
        assert not page.chaos.colour_bar.visible
        page.chaos.layer.value = True
        assert page.chaos.colour_bar.visible and page.url_query()["megno"] == "1"
        page.chaos.layer.value = False
        assert not page.chaos.colour_bar.visible
    finally:
        page.close()


def test_on_the_chaos_layer_every_dot_has_a_casing_and_a_negative_megno_is_explained():
    from explorer.app.serve.style import DOT_CASING, POINT_SIZE, megno_kind

    page = _page(SERVED, {"megno": "1"})
    try:
        casings, dots = page.orbits.casings, (page.orbits.points, page.orbits.live_points)
        assert all(c.visible for c in casings) and DOT_CASING[0] > POINT_SIZE          # the layer on: cased
        for casing, dot in zip(casings, dots):        # the same rows, drawn under the dots on their canvas
            assert casing.data_source is dot.data_source and casing.level == dot.level
            assert page.section.figure.renderers.index(casing) < page.section.figure.renderers.index(dot)
        assert _contrast(DOT_CASING[1], DOT_CASING[2]) > 15                  # a white disc, a dark edge
        page.chaos.layer.value = False
        poll(page)
        assert not any(c.visible for c in casings)
    finally:
        page.close()
    assert megno_kind(2.0) == "regular-like" and megno_kind(8.0) == "chaotic-like"
    assert "stable periodic orbit" in megno_kind(-0.05) and "stopped early" in megno_kind(math.nan)


def test_scene_seeds_mark_every_start_and_update_the_status_line_once_not_once_per_seed():
    page = _page(SERVED)
    try:
        updates, update = [], page.orbits.update_status
        page.orbits.update_status = lambda *a, **k: (updates.append(1), update(*a, **k))
        n = page.run_seeds()
        assert n > 50 and updates == [1]                      # (the list's table is rebuilt with it)
        assert len(page.orbits.start_source.data["orbit"]) == n and f"{n} orbit(s), {n} running" in \
            page.orbits.status.text
    finally:
        page.close()


def test_start_markers_can_be_hidden_and_shown_again():
    page = _page(SERVED)
    try:
        c1, c2, r1, _r2 = SERVED.region
        page.click(c1 + 0.3 * r1, c2)
        assert page.orbits.start_marks.visible and len(page.orbits.start_source.data["p1"]) == 1
        page.orbits.starts_box.value = False
        assert not page.orbits.start_marks.visible and len(page.orbits.start_source.data["p1"]) == 1   # hidden, kept
        page.orbits.starts_box.value = True
        assert page.orbits.start_marks.visible
    finally:
        page.close()


def test_the_exported_svg_names_each_element_once_and_the_scene_records_the_overlays_that_were_on():
    import dataclasses
    import xml.etree.ElementTree as ET

    import numpy as np

    from explorer.app.serve.image import render
    from explorer.io.scene import parse_scene as load_scene_text

    page = _page(SERVED, {"separatrices": "1", "periodic": "1"})
    try:
        c1, c2, r1, _r2 = SERVED.region
        page.click(c1 + 0.3 * r1, c2)
        page.click(c1 - 0.3 * r1, c2)
        arc = np.column_stack([np.linspace(c1, c1 + 0.1, 5), np.full(5, c2)])
        view = dataclasses.replace(page.exports.view(), separatrices=[arc, arc + 0.01],
                                   manifolds=[("unstable", arc), ("unstable", arc + 0.02), ("stable", arc + 0.03),
                                              ("stable", arc + 0.04)])
        ids = [e.get("id") for e in ET.fromstring(render(view, "svg")).iter() if e.get("id")]
        assert len(ids) == len(set(ids)), sorted(i for i in ids if ids.count(i) > 1)
        assert sum(i.startswith("manifold-unstable") for i in ids) == 2
        scene = load_scene_text(page.scene().to_toml())
        assert "separatrices" in scene.compute and "periodic" in scene.description
        plain = _page(SERVED)
        plain.click(c1 + 0.3 * r1, c2)
        assert "separatrices" not in load_scene_text(plain.scene().to_toml()).compute
        plain.close()
    finally:
        page.close()


def test_the_section_angle_is_a_field_and_the_zoom_window_is_in_the_link():
    from explorer.app.serve.settings import Window, format_window, parse_window

    page = _page(SERVED)
    try:
        region0 = page.settings.region
        page.inputs["phi0"].value = "0.5"                     # the section phi = 0.5
        assert page.settings.phi0 == 0.5 and page.url_query()["phi0"] == "0.5"
        assert "φ = 0.5" in page.title.object and page.settings.region != region0
        w = Window(-0.3, 0.2 / 3, -0.25, 0.1)
        page.section._on_ranges(type("E", (), {"x0": w.x0, "x1": w.x1, "y0": w.y0, "y1": w.y1})())   # a zoom
        link = page.url_query()
        assert parse_window(link["view"]) == w and format_window(w) == link["view"]          # exactly
        again = _page(SERVED, link)                            # the link reopens the same angle and window
        try:
            assert again.settings == page.settings and again.section.window == w
            assert (again.section.figure.x_range.start, again.section.figure.x_range.end) == (w.x0, w.x1)
        finally:
            again.close()
        for bad in ("1,2,3", "1,0,0,1", "nan,1,0,1", "0,1e300,0,1"):
            with pytest.raises(model.ParameterError, match="view"):
                parse_window(bad)
        odd = _page(SERVED, {"view": "1,0,0,1", "mu": "0.5"})
        assert odd.settings.params.mu == 0.5 and "(the rest applies): view must" in odd.message.text
        odd.close()
    finally:
        page.close()


def test_the_first_twenty_orbits_each_have_a_colour_of_their_own():
    from explorer.app.serve.orbits import COLORS

    page = _page(Settings(params=model.FIGURE4.with_(mu=0.03), crossings=1))
    try:
        c1, c2, r1, _r2 = page.settings.region
        for k in range(20):
            assert page.click(c1 + (-0.9 + 0.09 * k) * r1, c2) is not None
        colours = [COLORS[c] for *_x, c in page.orbits.starts]
        assert len(set(colours)) == 20, colours
        assert page.orbits.start_source.data["c"] == [c for *_x, c in page.orbits.starts]   # the crosses carry them
    finally:
        page.close()


def test_the_mu_slider_applies_its_value_through_the_field_and_follows_the_field():
    """Its range follows mu (0 to the 1-2-5 number at or above 2 mu): about 1-2 % of mu a pixel, and
    any mu it can show; a drag applies while it moves (every SLIDE_SECONDS), its range changes at the
    release only (the handle stays under the pointer)."""
    import param

    from explorer.app.serve.page_fields import SLIDE_SECONDS

    page = _page(SERVED)
    try:
        slider = page.fields.mu_slider
        assert slider.value == SERVED.params.mu == 0.03
        assert (slider.end - slider.start) / slider.width <= 0.001                  # a pixel: 0.00045 of mu
        slider.value = 0.0412                             # a drag, not released: applies within SLIDE_SECONDS
        t0 = time.monotonic()
        settle(page)
        assert page.settings.params.mu == 0.0412 and page.inputs["mu"].value == "0.0412"
        assert time.monotonic() - t0 >= 0.9 * SLIDE_SECONDS and slider.end == 0.1   # (its range kept mid-drag)
        with param.parameterized.edit_constant(slider):
            slider.value_throttled = 0.09                 # released at 0.09: applied, the range follows
        assert page.settings.params.mu == 0.09 and page.url_query()["mu"] == "0.09"
        assert slider.end == 0.2 and slider.value == 0.09
        page.inputs["mu"].value = "0.25"                  # the field moves the slider
        assert page.settings.params.mu == 0.25 and slider.value == 0.25 and slider.end == 0.5
        page.inputs["mu"].value = "1e6"                   # far beyond: the slider reads it, not its old end
        assert page.settings.params.mu == 1e6 and slider.value == 1e6 < slider.end
    finally:
        page.close()


@pytest.fixture(scope="module")
def bare_page(served, browser):
    """One page opened at the served page's bare address (no query), for the two tests below: the
    first click on it (the link's test, which runs first), then a click held on it."""
    page = _open(browser, served.url)
    yield page
    page.close()


@browser_needed
def test_a_page_opened_at_a_bare_address_writes_the_whole_link_with_the_first_click(bare_page):
    """Opened with no query, the first click puts every field and the start in the address, not
    the start alone (a link copied from it reopens the orbit at the page's values, whatever the
    receiving server's defaults are); the address is replaced, not pushed: no history entry."""
    import json
    from urllib.parse import parse_qs

    from explorer.app.serve.settings import FIELDS

    page = bare_page
    assert page.evaluate("() => Bokeh.documents[0].get_model_by_name('starts').data.orbit.length") == 0   # no click yet
    history = page.evaluate("() => window.history.length")
    c1, c2, r1, _r2 = SERVED.region
    _click(page, c1 + 0.5 * r1, c2)
    query = _wait(page, "() => { const q = new URLSearchParams(window.location.search);"
                        f" return q.get('orbits') && {json.dumps(list(FIELDS))}.every(n => q.has(n))"
                        " ? window.location.search : null; }")
    link = {k: v[0] for k, v in parse_qs(query.lstrip("?")).items()}
    assert link["mu"] == repr(SERVED.params.mu) and link["crossings"] == str(SERVED.crossings)
    assert len(link["orbits"].split(";")) == 1
    assert page.evaluate("() => window.history.length") == history    # replaced: Back leaves the page


def test_a_links_unknown_keys_are_named_and_leave_the_address_and_an_overlong_link_is_said_not_applied():
    """(In the browser, the address a served page writes keeps the token and drops the unknown keys:
    test_serve.py::test_a_bad_token_gets_no_app_and_ctrl_c_ends_the_server_cleanly.)"""
    from explorer.app.serve.settings import MAX_LINK_CHARS, screen_link

    kept, said = screen_link({"mu": "0.5", "foo": "1", "zzz": "", "token": "t"}, ("mu", "token"))
    assert kept == {"mu": "0.5", "token": "t"} and said == ["unknown keys 'foo', 'zzz' (removed)"]
    kept, said = screen_link({"mu": "0.5", "junk": "a" * MAX_LINK_CHARS}, ("mu",))
    assert kept == {} and "none of it applies" in said[0]
    page = _page(Settings(params=model.FIGURE4.with_(mu=0.03), crossings=1), {"mu": "0.5", "foo": "bar"})
    try:
        assert page.settings.params.mu == 0.5 and "unknown key 'foo'" in page.message.text   # the rest applies
        assert "foo" not in _link(page) and _link(page)["mu"] == "0.5"                     # the link lacks it
    finally:
        page.close()


def test_a_one_megabyte_link_gets_the_page_not_a_connection_reset(served):
    """The server reads a request whose address is 1 MB (asked of /liveness, which builds no page; the
    page then says it ignores such a link: the test above)."""
    import urllib.request

    with urllib.request.urlopen(served.url.rstrip("/") + "/liveness?junk=" + "a" * 1_000_000, timeout=60) as r:
        assert r.status == 200


#: how long the slow click holds the button (ms): past Bokeh's press threshold (300 ms), after
#: which Bokeh reports a press and its release (PressUp) instead of a tap
SLOW_CLICK_MS = 600


@browser_needed
def test_a_click_held_past_bokehs_press_threshold_starts_an_orbit_too(bare_page):
    """A button held 300 ms or more without moving is a press for Bokeh, not a tap: a slow click,
    or a quick one whose button-up reaches a busy browser after Bokeh's press timer (one of three
    rapid clicks was lost so at load 9-11).  Its release starts an orbit at the place of the click
    like a tap; before the fix nothing started.  (On the page of the test above: one start more
    than it had, at the place held.)"""
    page = bare_page
    c1, c2, r1, r2 = SERVED.region
    before = page.evaluate("() => Bokeh.documents[0].get_model_by_name('starts').data.orbit.length")
    x, y = page.evaluate(TO_SCREEN, [c1 + 0.4 * r1, c2 + 0.1 * r2])
    page.mouse.move(x, y)
    page.mouse.down()
    page.wait_for_timeout(SLOW_CLICK_MS)
    page.mouse.up()
    p1, p2 = _wait(page, "() => { const d = Bokeh.documents[0].get_model_by_name('starts').data;"
                         f" return d.orbit.length === {before + 1} && [d.p1[{before}], d.p2[{before}]]; }}")
    assert abs(p1 - (c1 + 0.4 * r1)) < 0.01 * r1 and abs(p2 - (c2 + 0.1 * r2)) < 0.01 * r2
