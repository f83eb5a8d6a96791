"""`explorer serve`: the explorer in the browser (src/explorer/app/serve, docs/commands/serve.md).

Without a browser: the page's values are validated, starts survive the URL exactly, the worker's
blocks are those of one uninterrupted run and a cancelled orbit hands out nothing more, a click
pauses the running orbit and Resume completes it as one uninterrupted run, the exported scene
reruns to the same crossings.

With a real browser (Debian's chromium driven by Playwright; skipped with the reason when either
is missing): the served page is opened, three clicks on the section give orbits whose crossings in
the page's data equal ``explorer orbit --json`` for the same starts, a change of mu redraws the
region, a bad value shows a message and computes nothing, a click elsewhere pauses the running
orbit and Resume completes it, a link reopens the same view, a wrong
token gets no app, and Ctrl-C ends the server cleanly.  A screenshot is saved (in
$EXPLORER_TEST_ARTEFACTS, else pytest's temporary directory) and its pixels checked.
"""
from __future__ import annotations

import dataclasses
import importlib.util
import json
import os
import signal
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from page_loop import poll, poll_until, settle

from explorer import model
from explorer.analysis import sections
from explorer.analysis.system_sections import DRIVER_THREADS
from explorer.app.serve import export, tasks
from explorer.app.serve import settings as settings_mod
from explorer.app.serve.orbits import FIRST_BLOCK, OrbitRun, Worker
from explorer.app.serve.settings import Settings, format_starts, parse_starts
from explorer.app.serve.tasks import Session
from explorer.model import ParameterError

#: the browser (Debian: apt-get install chromium); EXPLORER_CHROMIUM points elsewhere
CHROMIUM = os.environ.get("EXPLORER_CHROMIUM", "/usr/bin/chromium")
#: chromium's switches for a headless run that reaches nothing but the test's server
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
#: crossings per click in the browser tests (small: the test checks identity, not speed)
CROSSINGS = 150
#: a cold numba cache compiles the crossing kernels at the first click: allow for it
FIRST_ORBIT_TIMEOUT_MS = 240_000
REPO = Path(__file__).resolve().parents[2]
#: how long a started server may take to answer its first request (s): a bound on a hang, not a speed
#: goal -- on a loaded 2-core machine with a cold kernel cache a start took over 120 s
SERVER_START_TIMEOUT = 600.0
#: how long a request for the page may take (s): the server builds the session's page then (the
#: first one of a server imports and builds more); a bound on a hang -- under load one took over 10 s
PAGE_TIMEOUT = 120.0
#: the settings of the served page (`--mu 0.03 --crossings CROSSINGS`) and its region (c1, c2, r1, r2)
SERVED = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=CROSSINGS)


# ---------------------------------------------------------------- without a browser
def test_page_values_are_validated_like_the_command_line():
    base = Settings()
    s = base.with_fields({"mu": "0.5", "h": " 2.5 ", "method": "dop853", "tol": "1e-12", "crossings": "300"})
    assert (s.params.mu, s.h, s.method, s.tol, s.crossings) == (0.5, 2.5, "dop853", 1e-12, 300)
    bad = {"a1": "-1", "mu": "abc", "lam": "0", "tol": "0.5", "h": "nan", "crossings": "2.5", "method": "rk4",
           "b": "1e999", "dt": "0"}
    for name, text in bad.items():
        with pytest.raises(ParameterError, match=name):
            base.with_fields({name: text})
    with pytest.raises(ParameterError, match="unknown field"):
        base.with_fields({"/etc/passwd": "1"})
    with pytest.raises(ParameterError, match="crossings"):
        base.with_fields({"crossings": str(settings_mod.MAX_CROSSINGS + 1)})


def test_the_section_angle_accepts_multiples_of_pi():
    base = Settings()
    for text, value in (("pi", np.pi), (" -pi ", -np.pi), ("2pi", 2 * np.pi), ("pi/2", np.pi / 2),
                        ("0.5*π", 0.5 * np.pi), ("1.25", 1.25)):
        assert base.with_fields({"phi0": text}).phi0 == value, text
    for text in ("pix", "pi/0", "two pi"):
        with pytest.raises(ParameterError, match="phi0"):
            base.with_fields({"phi0": text})


def test_the_mu_slider_writes_its_value_without_float_noise():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    import param

    from explorer.app.serve.page import SectionPage

    page = SectionPage(Settings())
    try:
        slider = page.fields.mu_slider
        with param.edit_constant(slider):
            slider.value_throttled = 0.49800000000000005                          # a drag's end, as sent
        assert page.inputs["mu"].value == "0.498" and page.settings.params.mu == 0.498
        assert page.url_query()["mu"] == "0.498"
    finally:
        page.close()


def test_the_servers_echo_of_an_apply_leaves_a_field_the_user_is_typing_into_alone():
    """On a slow link the server's echo of an applied value (its text as the page writes it) can
    arrive after the user typed on: it must not write into that field (the texts would join)."""
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    page = _served_page(Settings())
    mu, h = page.inputs["mu"], page.inputs["h"]
    try:
        h.value_input = h.value = "2.00"                 # (Enter: value and value_input the same)
        mu.value_input = mu.value = "0.040"
        mu.value_input = "0.05"                          # typed on before the echo of 0.040
        writes = []
        mu.param.watch(lambda e: writes.append(e.new), "value")
        settle(page)                                    # the echo: both applied, written as the page writes them
        assert page.settings.params.mu == 0.04 and page.settings.h == 2.0
        assert writes == [] and h.value == "2.0"       # the typed-into field is left alone, the other shown
        mu.value = "0.05"                                # (Enter)
        settle(page)
        assert page.settings.params.mu == 0.05 and page.url_query()["mu"] == "0.05"
        page.fields.step(1, "mu")                        # the stepper writes into it as before
        settle(page)
        assert mu.value == "0.06" and page.settings.params.mu == 0.06
    finally:
        page.close()


def test_a_value_change_reruns_the_orbits_under_their_own_ids():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=50)
    c1, c2, r1, _r2 = s.region
    page = SectionPage(s)
    try:
        ids = [page.click(c1 + f * r1, c2).ident for f in (0.3, -0.3)]
        page.inputs["mu"].value = "0.031"
        assert [i for i, *_ in page.orbits.starts] == ids
        settle(page)
        assert len(page.orbits.columns()["t"]) == 2 * s.crossings
        assert all(r.status != "running" for r in page.orbits.runs.values())
        assert sorted(set(np.asarray(page.orbits.columns()["orbit"]).tolist())) == sorted(ids)
        assert page.click(c1, c2).ident == max(ids) + 1                        # a new click: a new id
    finally:
        page.close()


def test_a_link_with_a_refused_value_applies_the_rest_and_names_what_it_refused():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage

    page = SectionPage(Settings(), {"mu": "0.5", "h": "1e300", "crossings": "300", "orbits": "0.1,0.0"})
    try:
        assert page.settings.params.mu == 0.5 and page.settings.crossings == 300 and page.settings.h == Settings().h
        assert [s[1:3] for s in page.orbits.starts] == [(0.1, 0.0)]                 # the start runs
        said = page.message.text
        assert "h must be in" in said and "mu" not in said.split("h must be in")[0]
    finally:
        page.close()


def test_the_overlay_marks_the_fixed_points_and_draws_their_separatrices(monkeypatch):
    """What the overlay draws once its searches are done.  Their wall-clock budgets (30 s and 60 s,
    which keep a hostile page from holding the server: tests/app/test_serve_hostile.py) are lifted
    here, so that a slow or loaded machine gets the whole answer too (under load the budget ran out
    before the separatrices were grown and the test read an empty overlay)."""
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.analysis.fixedpoints import find_fixed_point
    from explorer.app.serve import overlays
    from explorer.app.serve.page import SectionPage

    monkeypatch.setattr(overlays, "FIXED_SECONDS", 3600.0)
    monkeypatch.setattr(overlays, "PERIODIC_SECONDS", 3600.0)
    page = SectionPage(Settings(params=model.FIGURE4.with_(mu=0.5)), {"separatrices": "1"})
    try:
        t0 = time.time()
        while "separatrix branches" not in page.overlays.text.text:   # (points first)
            assert time.time() - t0 < 1200, page.overlays.text.text
            poll(page)
            time.sleep(0.02)
        fp = find_fixed_point(page.settings.params, page.settings.h, (-0.2, 0.0))   # solution I, hyperbolic
        fixed = page.overlays.fixed.data
        found = list(zip(fixed["p1"], fixed["p2"], fixed["kind"]))
        assert any(abs(a - fp.point[0]) < 1e-8 and abs(b - fp.point[1]) < 1e-8 and k == "hyperbolic"
                   for a, b, k in found)
        assert len(page.overlays.curves.data["xs"]) >= 2 and "separatrix" in page.overlays.text.text
        assert page.url_query()["separatrices"] == "1"
        page.overlays.overlay.value = False                         # off: the overlay goes
        assert page.overlays.fixed.data["p1"] == [] and page.overlays.curves.data["xs"] == []
        page.overlays.periodic_box.value = True                     # periodic orbits: each period's points, K of them
        t0 = time.time()
        while not page.overlays.periodic.data["p1"]:
            assert time.time() - t0 < 1200, page.overlays.text.text
            poll(page)
            time.sleep(0.05)
        periods = np.array(page.overlays.periodic.data["period"])
        assert periods.size and set(periods) <= {1, 2, 3, 4} and "periodic orbits K=1" in page.overlays.text.text
        for k in set(periods.tolist()):
            assert (periods == k).sum() % k == 0
    finally:
        page.close()


def test_a_session_holds_a_bounded_number_of_crossings(monkeypatch):
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage

    monkeypatch.setattr(settings_mod, "MAX_SESSION_CROSSINGS", 1000)
    big = 500
    page = SectionPage(Settings(crossings=big))
    try:
        assert page.click(0.1, 0.1) is not None and page.click(0.2, 0.1) is not None
        assert page.click(0.3, 0.1) is None and "at most" in page.message.text      # a third would not fit
        page.inputs["crossings"].value = str(big + 1)                                 # nor more per click
        assert "not applied" in page.message.text and page.settings.crossings == big
        link = SectionPage(Settings(), {"crossings": str(big), "orbits": "0.1,0;0.2,0;0.3,0"})
        assert link.orbits.starts == [] and "link ignored" in link.message.text               # nor a link
        link.close()
    finally:
        page.close()


def test_starts_survive_the_url_bit_for_bit():
    rng = np.random.default_rng(1)
    starts = [tuple(map(float, rng.normal(size=2) / 3)) for _ in range(5)]
    assert parse_starts(format_starts(starts)) == starts
    s = Settings(params=model.FIGURE4.with_(mu=0.1 / 3), h=2.0 / 3 + 1)
    assert Settings().with_fields(s.fields()) == s
    for text in ("1,2,3", "a,b", "1;", "nan,0"):
        with pytest.raises(ParameterError, match="orbits"):
            parse_starts(text)


def _collect(worker_blocks, loop, timeout=120.0):
    t0 = time.time()
    while time.time() - t0 < timeout:
        poll(loop)
        if worker_blocks["finished"]:
            return
        time.sleep(0.01)
    raise AssertionError("the worker did not finish")


def test_worker_blocks_are_one_uninterrupted_run_and_cancelled_orbits_hand_out_nothing():
    s = Settings(params=model.FIGURE4.with_(mu=0.5), crossings=700)
    got: dict = {"rows": {}, "finished": False, "sizes": []}

    def on_block(ident, rows, done, status):
        got["rows"].setdefault(ident, []).append(rows)
        got["sizes"].append(len(rows))
        if status != "running" and ident == 2:
            got["finished"] = True

    loop = Session()                                 # (blocks come on the session's loop: poll)
    w = Worker(loop, on_block)
    try:
        first = w.submit(0.3, 0.1, s)
        w.cancel()                                   # before or after its first block: nothing more comes
        poll(loop)
        n_before = len(got["rows"].get(first.ident, []))
        second = w.submit(-0.4, 0.2, s)
        _collect(got, loop)
        assert len(got["rows"].get(first.ident, [])) == n_before <= 1
        rows = np.concatenate(got["rows"][second.ident])
        assert len(set(got["sizes"])) > 1          # the blocks had different sizes
    finally:
        loop.close()
    ref = sections.crossings(s.params, s.h, [(-0.4, 0.2)], n_crossings=s.crossings, **s.section_kwargs())
    np.testing.assert_array_equal(rows, ref.orbit(0))


def test_a_fixed_step_orbit_cut_into_step_blocks_gives_the_rows_of_one_uninterrupted_run():
    s = Settings(params=model.FIGURE4.with_(mu=0.5), method="split4", crossings=40)
    run = OrbitRun(1, 0.3, 0.1, s)
    parts, cut = [], 0
    while not run.finished:
        run.steps = 37                               # blocks end at 37 steps, mostly before a crossing
        rows = run.advance()
        cut += len(rows) == 0
        parts.append(rows)
    assert cut > 0 and run.status == "done"
    ref = sections.crossings(s.params, s.h, [(0.3, 0.1)], n_crossings=s.crossings, **s.section_kwargs())
    np.testing.assert_array_equal(np.concatenate(parts), ref.orbit(0))


def test_the_indicators_of_an_orbit_rerun_while_they_were_computed_are_not_the_reruns(monkeypatch):
    from explorer.app.serve import orbits

    s = Settings(params=model.FIGURE4.with_(mu=0.5), crossings=20)
    asked, release, got = [], threading.Event(), []

    def indicators(settings, p1, p2):            # the first (the old run's) waits until the rerun is queued
        asked.append(p1)
        if len(asked) == 1:
            assert release.wait(60)
        return float(len(asked)), p1

    monkeypatch.setattr(orbits, "orbit_indicators", indicators)
    loop = Session()
    w = Worker(loop, lambda *b: None, on_indicators=lambda *i: got.append(i))
    try:
        old = w.submit(0.3, 0.1, s)
        poll_until(loop, lambda: asked, 120, "no indicators were asked")
        rerun = w.submit(-0.4, 0.2, s, ident=old.ident)
        release.set()
        poll_until(loop, lambda: not loop.running("orbits"), 120, "the rerun did not finish")
    finally:
        loop.close()
    assert got == [(old.ident, 2.0, -0.4)] and rerun.indicators == (2.0, -0.4) and old.indicators is None


def _cpu_over(seconds: float) -> float:
    """The cores this process used over the next ``seconds``."""
    c0, t0 = time.process_time(), time.monotonic()
    time.sleep(seconds)
    return (time.process_time() - c0) / (time.monotonic() - t0)


#: a fixed step that finds no crossing in the 10^9 steps of an orbit's step budget
TINY_DT = Settings(params=model.FIGURE4.with_(mu=0.03), method="split2", dt=1e-12)


def test_a_cancelled_fixed_step_orbit_stops_within_a_block_and_was_said_with_its_estimate_up_front():
    notices, blocks = [], []
    loop = Session()
    w = Worker(loop, lambda *b: blocks.append(b), on_notice=lambda ident, text: notices.append((ident, text)))
    try:
        run = w.submit(0.5, 0.0, TINY_DT)
        poll_until(loop, lambda: notices, 240, "no estimate was said")
        assert notices[0][0] == run.ident and "1e+09 steps" in notices[0][1]
        w.cancel()
        t0 = time.monotonic()
        while _cpu_over(0.5) > 0.2:                  # (this process's cores, over half a second)
            assert time.monotonic() - t0 < 5.0, "the cancelled orbit kept a core busy"
        assert not blocks                            # no crossing: nothing handed out
    finally:
        loop.close()


#: crossings per click of the pause tests: an orbit of about a second, so that a second click
#: comes while the first still runs (the first block is ready in milliseconds)
PAUSE_CROSSINGS = 30_000


def _idle(page) -> bool:
    """The page's status line counts no orbit running."""
    return " 0 running" in page.orbits.status.text


def _hand_in(page, ident: int, rows: np.ndarray, status: str = "done") -> None:
    """A block of orbit ``ident`` handed to the page as the worker hands one out (orbits.Worker._hand_out)."""
    run = page.orbits.runs[ident]
    run.rows, run.status = np.concatenate([run.rows, rows]), status
    run.done = len(run.rows)
    page.orbits._on_block(ident, rows, run.done, status)


def _orbit_rows(page, ident) -> np.ndarray:
    d = page.orbits.columns()
    mine = np.asarray(d["orbit"]) == ident
    return np.column_stack([np.asarray(d[k])[mine] for k in ("t", "p1", "p2", "M", "dH")])


def _click_while_running(page, a, b):
    """Click at a, then at b as soon as a's first crossings are on the page; returns both ids."""
    first = page.click(*a).ident
    _poll_until(page, lambda: len(_orbit_rows(page, first)) > 0)
    return first, page.click(*b).ident


def test_a_click_pauses_the_running_orbit_and_resume_completes_it_bit_for_bit():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=PAUSE_CROSSINGS)
    c1, c2, r1, r2 = s.region
    a, b = (c1 + 0.3 * r1, c2), (c1 - 0.5 * r1, c2 + 0.2 * r2)
    page = SectionPage(s)
    try:
        assert page.orbits.pause_box.value and page.url_query()["pause"] == "1"            # on by default
        first, second = _click_while_running(page, a, b)
        settle(page)
        assert len(_orbit_rows(page, second)) == s.crossings and _idle(page)
        held = len(_orbit_rows(page, first))
        assert 0 < held < s.crossings and page.orbits.worker.paused() == [first]          # paused mid-orbit
        assert "1 running" not in page.orbits.status.text and "1 paused" in page.orbits.status.text
        time.sleep(0.3)
        poll(page)
        assert len(_orbit_rows(page, first)) == held                               # and it stays there
        assert len(parse_starts(page.url_query()["orbits"])) == 2                  # both starts in the link
        assert page.orbit_list.resume() == 1 and page.orbits.worker.paused() == []
        assert "paused" not in page.orbits.status.text
        settle(page)
        assert page.orbits.runs[first].status != "running" and _idle(page)
        for ident, (p1, p2) in ((first, a), (second, b)):        # as one uninterrupted run, bit for bit
            ref = sections.crossings(s.params, s.h, [(p1, p2)], n_crossings=s.crossings, **s.section_kwargs())
            np.testing.assert_array_equal(_orbit_rows(page, ident), ref.orbit(0))
        assert page.orbit_list.resume() == 0                                                   # nothing left to resume

        # a paused orbit is undone like any other
        third, fourth = _click_while_running(page, a, b)
        assert page.orbits.worker.paused() == [third]
        page.orbit_list.undo()
        page.orbit_list.undo()
        assert page.orbits.worker.paused() == [] and _idle(page) and len(page.orbits.starts) == 2
        poll(page)
        assert set(np.asarray(page.orbits.columns()["orbit"]).tolist()) == {first, second}
        assert "paused" not in page.orbits.status.text

        # Clear lets paused orbits go
        _click_while_running(page, a, b)
        page.orbit_list.clear()
        assert page.orbits.worker.paused() == [] and "paused" not in page.orbits.status.text

        # a new value restarts paused orbits with the other starts: all run, none paused
        _click_while_running(page, a, b)
        assert len(page.orbits.worker.paused()) == 1
        page.inputs["crossings"].value = "300"
        assert page.settings.crossings == 300 and page.orbits.worker.paused() == [] and len(page.orbits.starts) == 2
        settle(page)
        assert len(page.orbits.columns()["t"]) == 2 * 300 and _idle(page)
        assert "paused" not in page.orbits.status.text
    finally:
        page.close()


def test_with_the_box_unticked_a_click_leaves_the_running_orbits_running():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=PAUSE_CROSSINGS)
    c1, c2, r1, r2 = s.region
    a, b = (c1 + 0.3 * r1, c2), (c1 - 0.5 * r1, c2 + 0.2 * r2)
    page = SectionPage(s, {"pause": "0"})                        # the box, off through the link
    try:
        assert not page.orbits.pause_box.value and page.url_query()["pause"] == "0"
        first, second = _click_while_running(page, a, b)
        assert page.orbits.worker.paused() == [] and "paused" not in page.orbits.status.text
        settle(page)
        assert len(page.orbits.columns()["t"]) == 2 * s.crossings and _idle(page)
        for ident, (p1, p2) in ((first, a), (second, b)):        # both complete, no Resume needed
            ref = sections.crossings(s.params, s.h, [(p1, p2)], n_crossings=s.crossings, **s.section_kwargs())
            np.testing.assert_array_equal(_orbit_rows(page, ident), ref.orbit(0))
    finally:
        page.close()


def test_the_exported_scene_reruns_the_sessions_orbits(tmp_path):
    from explorer.app.runner import run_sweep
    from explorer.io import scene as scene_mod
    from explorer.io.store import read_store

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=40)
    starts = [(0.3, 0.1), (-0.5, 0.2), (50.0, 0.0)]           # the last is outside the region: dropped
    path = export.write_scene(tmp_path, export.session_scene(s, starts))
    assert os.path.dirname(path) == str(tmp_path)
    sc = scene_mod.load_scene(path)
    assert sc.seeds.points == tuple(starts[:2])
    run_sweep(sc, tmp_path / "out.h5", draw=False, progress=False)
    panel = read_store(tmp_path / "out.h5").panels[0]
    for i, (p1, p2) in enumerate(starts[:2]):
        ref = sections.crossings(s.params, s.h, [(p1, p2)], n_crossings=s.crossings, **s.section_kwargs())
        np.testing.assert_array_equal(panel.orbit(i), ref.orbit(0))
    with pytest.raises(ParameterError, match="no orbit"):
        export.session_scene(s, [(50.0, 0.0)])


# ---------------------------------------------------------------- the served page in a browser
def _browser_problem() -> str | None:
    if not (os.path.exists(CHROMIUM) and os.access(CHROMIUM, os.X_OK)):
        return f"no chromium at {CHROMIUM} (Debian: apt-get install chromium)"
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "playwright for Python is not installed (pip install playwright; no `playwright install`)"
    try:
        import panel  # noqa: F401
    except ImportError:
        return "panel is not installed (pip install panel)"
    return None


#: on CI (.ci/run installs chromium and the test extras) a missing browser is a failure, not a
#: skip: the page must have been tested in a real browser for the run to count
_PROBLEM = _browser_problem()
if _PROBLEM is not None and os.environ.get("CI") == "true":
    raise RuntimeError(f"CI=true but the browser tests cannot run: {_PROBLEM}")
browser_needed = pytest.mark.skipif(_PROBLEM is not None, reason=str(_PROBLEM))


class Served:
    """``python -m explorer serve ...`` (or ``command``; ``entry`` in place of ``-m explorer``) in a
    subprocess; ``url`` is its first line."""

    def __init__(self, *args, timeout=SERVER_START_TIMEOUT, command="serve", extra=(), entry=("-m", "explorer")):
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.proc = subprocess.Popen([sys.executable, *entry, command, "--port", "0", *args, *extra],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                                     cwd=REPO)
        t0 = time.time()
        self.url = self.proc.stdout.readline().strip()
        if not self.url.startswith("http://"):
            self.proc.kill()
            raise AssertionError(f"serve printed {self.url!r}; stderr: {self.proc.stderr.read()[-2000:]}")
        port = self.url.split("/")[2].rsplit(":", 1)[1]
        while time.time() - t0 < timeout:     # until the server answers (on loopback: any --host binds it)
            try:
                urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=5).close()
                return
            except urllib.error.HTTPError:
                return
            except OSError:
                time.sleep(0.2)
        raise AssertionError("serve did not answer")

    def interrupt(self, timeout=30.0):
        """Ctrl-C; returns (exit status, stderr)."""
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        return self.proc.returncode, self.proc.stderr.read()


@pytest.fixture(scope="module")
def served(default_server):
    """The served page (SERVED; ``export_dir``: its --export-dir): one server for every module of
    this pytest process that uses it (tests/app/browser_session.py), stopped with Ctrl-C at the end."""
    return default_server


@pytest.fixture(scope="module")
def browser(launch_chromium):
    """Chromium (a Playwright context): one for the consecutive browser modules of this pytest
    process (tests/app/browser_session.py)."""
    return launch_chromium()


READY = ("() => window.Bokeh && Bokeh.documents.length > 0 && Bokeh.documents[0].is_idle && "
         "Bokeh.documents[0].get_model_by_name('region') !== null && "
         "Bokeh.index.all_views().some(v => v.model.name === 'section' && v.frame.bbox.width > 100)")
#: page coordinates of the section point (p1, p2), from the figure's own scales
TO_SCREEN = """([x, y]) => { const v = Bokeh.index.all_views().find(v => v.model.name === 'section');
  const r = v.el.getBoundingClientRect();
  return [r.left + v.frame.x_scale.compute(x), r.top + v.frame.y_scale.compute(y)]; }"""
DATA = "(name) => { const d = Bokeh.documents[0].get_model_by_name(name).data; const o = {};" \
       " for (const k of Object.keys(d)) o[k] = Array.from(d[k]); return o; }"
TEXT = "(name) => Bokeh.documents[0].get_model_by_name(name).text"
#: tick or untick the check box whose label starts with the text (its Bokeh model, as a click does)
SET_BOX = "([text, on]) => { const m = [...Bokeh.documents[0].all_models].find(m => m.type === 'CheckboxGroup' &&" \
          " String(m.labels[0]).startsWith(text)); m.active = on ? [0] : []; }"


#: what a page says, for a failed wait: its message, status and readout lines, its link, then its
#: address as the browser shows it, and whether BokehJS calls the document idle
SAID = ("() => { const d = Bokeh.documents[0];"
        " return ['message', 'status', 'readout', 'link'].map(n => (m => m ? m.text : null)(d.get_model_by_name(n)))"
        ".concat([window.location.search, d.is_idle]); }")


#: how often a wait evaluates its expression in the page (ms): on a timer, not on every animation
#: frame ("raf": a frame requested 60 times a second while a test waits, which costs chromium's
#: renderer about three times the CPU of this timer on an idle page)
WAIT_POLLING_MS = 20


def _wait(page, expression, timeout=60_000, polling=WAIT_POLLING_MS):
    """page.wait_for_function, failing with what the page says (its message, status and readout
    lines); returns the expression's truthy value (as JSON): the state waited for, read in the
    same call."""
    try:
        return page.wait_for_function(expression, timeout=timeout, polling=polling).json_value()
    except Exception as exc:
        try:
            said = page.evaluate(SAID)
        except Exception:  # noqa: BLE001 - the page has no app (e.g. a refused token)
            said = None
        raise AssertionError(f"waited {timeout} ms for {expression[:200]}; the page says {said}") from exc


def _open(browser, url):
    page = browser.new_page()
    page.goto(url)
    _wait(page, READY)
    return page


def _link(page) -> dict:
    """The page's link ({name: text}): what a served page writes into the browser's address."""
    from urllib.parse import parse_qsl

    return dict(parse_qsl(page.link.text, keep_blank_values=True))


def _click(page, p1, p2):
    x, y = page.evaluate(TO_SCREEN, [p1, p2])
    page.mouse.click(x, y)


def _wait_crossings(page, n, timeout=FIRST_ORBIT_TIMEOUT_MS):
    _wait(page, f"() => Bokeh.documents[0].get_model_by_name('crossings').data.p1.length >= {n}",
                           timeout=timeout)


def _orbit_args(s: Settings, p1, p2) -> list:
    """The ``explorer orbit`` arguments of the start (p1, p2) at the page's settings ``s``."""
    args = ["orbit", "--p1", repr(float(p1)), "--p2", repr(float(p2)), "--h", repr(float(s.h)), "--method", s.method,
            "--tol", repr(float(s.tol)), "--dt", repr(float(s.dt)), "--crossings", str(s.crossings),
            "--phi0", repr(float(s.phi0)), "--direction", {1: "+", -1: "-", 0: "both"}[s.direction]]
    return args + [a for n in model.PARAM_NAMES for a in (f"--{n}", repr(float(getattr(s.params, n))))]


def _orbit_json(settings: Settings, p1, p2) -> np.ndarray:
    """The crossings ``explorer orbit --json`` prints for the start (p1, p2) at ``settings``: the command's
    own output (cli.main, as ``python -m explorer`` runs it), in this process (not a Python start of its own:
    the command line, not the process, is what the page is compared with)."""
    import contextlib
    import io

    from explorer.app import cli

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert cli.main([*_orbit_args(settings, p1, p2), "--json"]) == 0
    return np.array(json.loads(out.getvalue())["crossings"], dtype=np.float64).reshape(-1, 5)


def _set_field(page, field, text):
    from explorer.app.serve.page_fields import LABELS

    box = page.get_by_label(LABELS[field], exact=True)
    box.fill(text)
    box.press("Enter")


@browser_needed
def test_clicked_orbits_in_the_page_equal_explorer_orbit_json(served, browser, tmp_path):
    page = _open(browser, served.url)
    region = page.evaluate(DATA, "region")
    s = SERVED
    c1, c2, r1, r2 = s.region
    assert region["x"] == [c1] and region["width"] == [2 * r1]
    targets = [(c1 + 0.5 * r1, c2), (c1 - 0.3 * r1, c2 + 0.2 * r2), (c1 + 0.1 * r1, c2 - 0.6 * r2)]
    t0 = time.perf_counter()
    _click(page, *targets[0])
    _wait_crossings(page, 1)
    first = time.perf_counter() - t0
    for p in targets[1:]:
        _click(page, *p)
    _wait(page, "() => Bokeh.documents[0].get_model_by_name('starts').data.orbit.length === 3")
    page.get_by_role("button", name="Resume").click()           # (a click pauses the orbits still running)
    _wait_crossings(page, 3 * CROSSINGS)
    starts = page.evaluate(DATA, "starts")
    data = page.evaluate(DATA, "crossings")
    assert len(starts["orbit"]) == 3
    for ident, p1, p2, target in zip(starts["orbit"], starts["p1"], starts["p2"], targets):
        assert abs(p1 - target[0]) < 0.01 * r1 and abs(p2 - target[1]) < 0.01 * r2   # the click landed there
        mine = np.array(data["orbit"]) == ident
        rows = np.column_stack([np.array(data[k])[mine] for k in ("t", "p1", "p2", "M", "dH")])
        np.testing.assert_array_equal(rows, _orbit_json(s, p1, p2))       # bit for bit
    # the screenshot: an artefact, and not blank (the white region, gray outside, coloured crossings)
    where = Path(os.environ.get("EXPLORER_TEST_ARTEFACTS", tmp_path))
    where.mkdir(parents=True, exist_ok=True)
    shot = where / "serve.png"
    page.screenshot(path=str(shot))
    import matplotlib.image

    img = matplotlib.image.imread(str(shot))[..., :3]
    assert img.std() > 0.05
    saturated = (img.max(axis=2) - img.min(axis=2)) > 0.3          # coloured pixels: the orbits
    assert saturated.sum() > 100
    print(f"first crossings {first * 1e3:.0f} ms after the click; screenshot {shot}")
    # a link reopens the same view
    _wait(page, "() => (new URLSearchParams(window.location.search).get('orbits') || '')"
                           ".split(';').length === 3", timeout=60_000)      # the URL follows the page
    again = _open(browser, page.url)
    _wait_crossings(again, 3 * CROSSINGS)
    assert again.evaluate(DATA, "starts")["p1"] == starts["p1"]
    np.testing.assert_array_equal(np.array(again.evaluate(DATA, "crossings")["t"]).size, 3 * CROSSINGS)
    again.close()
    page.close()


@browser_needed
def test_a_change_of_mu_redraws_the_region_and_keeps_the_starts(served, browser):
    page = _open(browser, served.url)
    c1, c2, r1, r2 = SERVED.region
    _click(page, c1 + 0.2 * r1, c2)
    _wait_crossings(page, CROSSINGS)
    _set_field(page, "mu", "0.5")
    new = Settings(params=model.FIGURE4.with_(mu=0.5), crossings=CROSSINGS).region
    _wait(page, f"() => Bokeh.documents[0].get_model_by_name('region').data.x[0] === {new[0]!r}",
                           timeout=60_000)
    region = page.evaluate(DATA, "region")
    assert region["width"] == [2 * new[2]] and region["height"] == [2 * new[3]]
    assert len(page.evaluate(DATA, "starts")["orbit"]) == 1             # the start is kept and runs again
    _wait_crossings(page, CROSSINGS)
    _wait(page, "() => window.location.search.includes('mu=0.5&')", timeout=60_000)
    # the crossings per click lowered, then raised again: the orbit is cut, then its rows come back
    _wait(page, f"() => ({TEXT})('status').includes('0 running, {CROSSINGS} crossings drawn')")
    before = page.evaluate(DATA, "crossings")["t"]
    for k in (CROSSINGS // 3, CROSSINGS):
        _set_field(page, "crossings", str(k))
        _wait(page, f"() => ({TEXT})('status').includes('0 running, {k} crossings drawn')")
        _wait(page, f"() => Bokeh.documents[0].get_model_by_name('crossings').data.t.length === {k}")
        assert page.evaluate(DATA, "crossings")["t"] == before[:k]
    page.close()


@browser_needed
def test_the_link_reaches_the_address_when_panels_own_writes_are_lost(browser):
    """The address follows the page through Bokeh's dispatch, not Panel's own writer: a server
    whose Panel loses every message it writes itself (tests/app/lossy_panel_serve.py; panel 1.9's
    queue loses one now and then when the socket is busy, and twice in the browser loops the
    address kept two of three clicked starts for good, docs/tests.md).  Three clicks, then the
    address holds the three starts, and a field typed in reaches it too."""
    lossy = Served("--crossings", str(CROSSINGS), "--mu", "0.03",
                   entry=(str(Path(__file__).with_name("lossy_panel_serve.py")),))
    try:
        page = _open(browser, lossy.url)
        c1, c2, r1, r2 = SERVED.region
        for k in range(3):
            _click(page, c1 + (0.2 * k - 0.3) * r1, c2 + 0.1 * r2)
        _wait(page, "() => Bokeh.documents[0].get_model_by_name('starts').data.orbit.length === 3")
        _wait(page, "() => (new URLSearchParams(window.location.search).get('orbits') || '')"
                    ".split(';').length === 3", timeout=60_000)
        _set_field(page, "mu", "0.04")
        _wait(page, "() => new URLSearchParams(window.location.search).get('mu') === '0.04'", timeout=60_000)
        page.close()
    finally:
        code, err = lossy.interrupt()
    assert code in (0, 130) and "Traceback" not in err, err[-2000:]


@browser_needed
def test_on_a_slow_connection_the_page_ends_with_every_row_of_the_server(browser):
    """Every frame the server writes takes 30 ms (tests/app/slow_socket_serve.py): the page's
    messages overlap its next callbacks.  After clicks, a change of mu and one of the crossings per
    click made while orbits stream,
    the page's rows are the server's, none lost (panel's ``unlocked`` lost an orbit's last rows
    here, docs/commands/serve.md) and none twice."""
    slow = Served("--crossings", str(CROSSINGS), "--mu", "0.03",
                  entry=(str(Path(__file__).with_name("slow_socket_serve.py")),))
    try:
        page = _open(browser, slow.url)
        c1, c2, r1, _r2 = SERVED.region
        at_05 = Settings(params=model.FIGURE4.with_(mu=0.5), crossings=CROSSINGS)
        for k in range(2):                                  # mu 0.03 -> 0.5, then back
            starts = [(c1 + (0.15 + 0.05 * k) * r1, c2), (c1 - (0.15 + 0.05 * k) * r1, c2)]
            assert all(SERVED.admissible(*p) and at_05.admissible(*p) for p in starts)
            mu = "0.5" if k % 2 == 0 else "0.03"
            m = CROSSINGS + 10 * (k + 1)                    # (the round's final status is its own)
            for p in starts:
                _click(page, *p)
                time.sleep(0.05)
            _set_field(page, "mu", mu)                      # while they stream: both run again
            # the page shows the new mu before the crossings are typed: a field typed into while the
            # server's echo of the last change is on its way can end as the two texts joined
            _wait(page, f"() => ({TEXT})('status').includes('mu = {mu},')", timeout=FIRST_ORBIT_TIMEOUT_MS)
            _set_field(page, "crossings", str(m))           # and again, with more crossings
            n = len(starts) * m
            # (the page lags the server by up to seconds here: only this status says it has caught up)
            _wait(page, f"() => ({TEXT})('status').includes('0 running, {n} crossings drawn; mu = {mu},')",
                  timeout=FIRST_ORBIT_TIMEOUT_MS)
            _wait_crossings(page, n, timeout=60_000)
            time.sleep(1.0)                                  # nothing more arrives
            rows = page.evaluate(DATA, "crossings")
            assert len(rows["p1"]) == n and sorted(set(rows["orbit"])) == sorted(
                page.evaluate(DATA, "starts")["orbit"]), (k, len(rows["p1"]))
            assert page.evaluate(DATA, "live")["p1"] == []
            for orbit in set(rows["orbit"]):                  # each orbit's rows once, in time order
                t = np.array(rows["t"])[np.array(rows["orbit"]) == orbit]
                assert t.size == m and np.all(np.diff(t) > 0)
            page.get_by_role("button", name="Clear").click()
            _wait(page, "() => Bokeh.documents[0].get_model_by_name('crossings').data.p1.length === 0")
        page.close()
    finally:
        code, err = slow.interrupt()
    assert code in (0, 130) and "Traceback" not in err, err[-2000:]


#: in the browser, from the page's start: the dots (arcs) drawn while a click's first crossings are
#: live and the crossings source still holds the ``window.__before`` rows of the clicks before, in
#: all and on the section's primary canvas (Bokeh's layer of the glyphs and images, where the older
#: orbits' dots are; the live layer is on the overlay canvas)
CANVASES = """window.__before = -1;
window.__dots = {live: 0, live_on_primary: 0, primary: 0};
(() => {
const arc = CanvasRenderingContext2D.prototype.arc;
let v = null, live = null, rows = null;        // (looked up once the page is there, not per dot)
CanvasRenderingContext2D.prototype.arc = function(...a) {
  if (!v && window.Bokeh && Bokeh.documents.length) {
    v = Bokeh.index.all_views().find(v => v.model.name === 'section') || null;
    live = Bokeh.documents[0].get_model_by_name('live');
    rows = Bokeh.documents[0].get_model_by_name('crossings');
  }
  if (v) {
    const primary = this.canvas === v.canvas_view.primary.canvas, c = window.__dots;
    if (primary) c.primary++;
    if (live.data.p1.length > 0 && rows.data.p1.length === window.__before) {
      c.live++;
      if (primary) c.live_on_primary++;
    }
  }
  return arc.apply(this, a); };
})();"""


@browser_needed
def test_a_clicks_first_crossings_are_drawn_without_redrawing_the_older_orbits(served, browser):
    """The first crossings of a click beside earlier orbits go to the live layer, on Bokeh's overlay
    canvas: the browser draws them without redrawing the older orbits' dots (what made them take
    150-250 ms to appear beside 10,000-40,000 crossings; benchmarks/bench_serve.py).  An orbit of
    CROSSINGS is done within the first 0.25 s: its last block goes to the live layer too.  With
    the live renderer on the primary canvas this fails (every dot there counted)."""
    page = browser.new_page()
    page.add_init_script(CANVASES)
    page.goto(served.url)
    _wait(page, READY)
    c1, c2, r1, r2 = SERVED.region
    _click(page, c1 + 0.3 * r1, c2)
    _wait_crossings(page, CROSSINGS)
    _wait(page, "() => Bokeh.documents[0].get_model_by_name('live').data.p1.length === 0")
    for k in range(1, 4):      # (a browser too busy to paint before the rows settle, 0.25 s: again)
        page.wait_for_timeout(400)                                         # (not a double tap)
        page.evaluate(f"() => {{ window.__before = {k * CROSSINGS}; }}")
        _click(page, c1 - (0.2 * k) * r1, c2 + 0.1 * r2)
        _wait_crossings(page, (k + 1) * CROSSINGS)
        _wait(page, "() => Bokeh.documents[0].get_model_by_name('live').data.p1.length === 0")
        if page.evaluate("() => window.__dots.live") > 0:
            break
    dots = page.evaluate("() => window.__dots")
    assert dots["primary"] >= CROSSINGS and dots["live"] >= 1 and dots["live_on_primary"] == 0, dots
    page.close()


@browser_needed
def test_a_bad_value_shows_a_message_and_computes_nothing(served, browser):
    page = _open(browser, served.url)
    before = page.evaluate(DATA, "region")
    good = SERVED.fields()
    for field, text in (("a1", "-1"), ("mu", "<img src=x onerror=alert(1)>"), ("tol", "0.5"), ("crossings", "1e9")):
        _set_field(page, field, text)
        _wait(page, f"() => ({TEXT})('message').includes({json.dumps(field)})", timeout=60_000)
        assert "not applied" in page.evaluate(TEXT, "message")
        assert page.locator("img[src=x]").count() == 0            # shown as text, not HTML
        assert page.evaluate(DATA, "region") == before
        assert page.evaluate(DATA, "crossings")["p1"] == []
        _set_field(page, field, good[field])           # back: the message goes
        _wait(page, f"() => ({TEXT})('message') === ''", timeout=60_000)
    page.close()
    assert served.proc.poll() is None                       # the server keeps running
    assert urllib.request.urlopen(served.url, timeout=PAGE_TIMEOUT).status == 200


@pytest.fixture(scope="module")
def _token_server_box():
    """Holds the module's ``serve --token s3cret`` (:func:`token_served`); Ctrl-C ends one still
    running cleanly at the end of the module."""
    box: dict = {}
    yield box
    s = box.get("server")
    if s is not None and s.proc.poll() is None:
        code, err = s.interrupt()
        assert code in (0, 130) and "Traceback" not in err, err[-2000:]


@pytest.fixture
def token_served(_token_server_box):
    """``explorer serve --token s3cret``: one server for the token tests, started again if a test
    stopped it (test_a_bad_token_gets_no_app_and_ctrl_c_ends_the_server_cleanly, which comes last)."""
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    s = _token_server_box.get("server")
    if s is None or s.proc.poll() is not None:
        s = _token_server_box["server"] = Served("--token", "s3cret")
    return s


def test_bad_tokens_leave_the_server_serving_the_right_one(token_served):
    s = token_served
    bare = s.url.split("?")[0]
    bad = ["", "wrong", "s3cre", "s3cret0", "S3CRET", "%00", "s3cret%20", "x" * 5000, "%E2%98%83"] * 4
    for token in bad:
        with pytest.raises(urllib.error.HTTPError) as exc:
            urllib.request.urlopen(f"{bare}?token={token}", timeout=10)
        assert exc.value.code in (403, 414, 431), token[:20]
    body = urllib.request.urlopen(s.url, timeout=PAGE_TIMEOUT).read().decode("utf-8", "replace")
    assert s.proc.poll() is None and "bokeh" in body.lower()
    # (Ctrl-C ends this server cleanly: the next test, or the module's end)


@browser_needed
def test_a_bad_token_gets_no_app_and_ctrl_c_ends_the_server_cleanly(browser, token_served):
    s = token_served
    try:
        assert s.url.endswith("?token=s3cret")
        bare = s.url.split("?")[0]
        for url in (bare, bare + "?token=wrong", bare + "?token="):
            with pytest.raises(urllib.error.HTTPError) as exc:
                urllib.request.urlopen(url, timeout=10)
            assert exc.value.code == 403
        page = browser.new_page()
        page.goto(bare + "?token=wrong")
        page.wait_for_timeout(500)
        assert page.evaluate("() => !window.Bokeh || Bokeh.documents.length === 0")
        page.close()
        page = _open(browser, s.url + "&foo=bar&mu=0.04")     # the address: the token first, then the link
        _wait(page, "() => /^[?]token=s3cret&mu=0[.]04&/.test(window.location.search)"
                    " && !window.location.search.includes('foo')")
        page.close()
        assert urllib.request.urlopen(s.url, timeout=PAGE_TIMEOUT).status == 200
    finally:
        code, err = s.interrupt()
    assert code in (0, 130) and "Traceback" not in err, err[-2000:]


@pytest.mark.skipif(importlib.util.find_spec("panel") is None, reason="panel is not installed (pip install panel)")
def test_a_non_loopback_host_gets_a_token_that_every_page_request_needs():
    from explorer.app.serve import server

    s = Served("--host", "0.0.0.0")
    try:
        head, _, token = s.url.partition("?token=")
        assert len(token) >= 24
        port = head.rstrip("/").rsplit(":", 1)[1]
        local = f"http://127.0.0.1:{port}/"
        with pytest.raises(urllib.error.HTTPError) as exc:
            urllib.request.urlopen(local, timeout=10)
        assert exc.value.code == 403
        assert urllib.request.urlopen(f"{local}?token={token}", timeout=PAGE_TIMEOUT).status == 200
    finally:
        code, err = s.interrupt()
    assert code in (0, 130) and "Traceback" not in err, err[-2000:]
    assert server.is_loopback("127.0.0.1") and server.is_loopback("::1") and server.is_loopback("localhost")
    assert not server.is_loopback("0.0.0.0") and not server.is_loopback("192.168.1.2")
    assert server.token_matches("abc", {"token": [b"abc"]}) and not server.token_matches("abc", {"token": [b"abd"]})
    assert not server.token_matches("abc", {}) and not server.token_matches("abc", None)


def test_the_megno_raster_is_refined_and_marks_chaos_and_order():
    from explorer.app.serve import raster

    s = Settings(params=model.FIGURE4.with_(mu=0.03), tol=1e-10)
    c1, c2, r1, r2 = s.region
    w = settings_mod.Window(c1 - r1, c1 + r1, c2 - r2, c2 + r2)
    images = []
    for im in raster.rasters(s, w):
        images.append(im)
        if im.n == raster.RESOLUTIONS[1] and im.complete:
            break
    assert [im.n for im in images if im.complete] == list(raster.RESOLUTIONS[:2])
    final = images[-1].values
    P1, P2 = w.centres(final.shape[0])
    outside = model.section_M2(s.params, P1, P2, s.h) <= 0
    assert np.isnan(final[outside]).all() and np.isfinite(final[~outside]).all()
    # the chaotic sea (MEGNO grows) and regular islands (MEGNO near 2) are both on the map
    assert np.nanmax(final) > 8 and np.nanmin(np.abs(final - 2)) < 0.3


@browser_needed
def test_the_megno_layer_appears_coarse_first_and_follows_the_zoom(served, browser):
    page = _open(browser, served.url)
    page.evaluate(SET_BOX, ["chaos layer", True])
    raster_n = "() => { const d = Bokeh.documents[0].get_model_by_name('raster').data; return d.n.length ? d.n[0] : 0 }"
    _wait(page, f"() => ({raster_n})() >= 16", timeout=120_000)
    _wait(page, "() => window.location.search.includes('megno=1')", timeout=60_000)
    x, y = page.evaluate(TO_SCREEN, [0.0, 0.0])
    page.mouse.move(x, y)
    page.mouse.wheel(0, -400)                                   # zoom in (the wheel zoom is active)
    ranges = ("() => { const f = Bokeh.documents[0].get_model_by_name('section');"
              " return [f.x_range.start, f.x_range.end, f.y_range.start, f.y_range.end]; }")
    _wait(page, f"() => {{ const r = ({ranges})(); const d = Bokeh.documents[0]"
                           ".get_model_by_name('raster').data; return d.x.length && d.x[0] === r[0] "
                           "&& Math.abs(d.x[0] + d.dw[0] - r[1]) < 1e-12 && d.y[0] === r[2]; }", timeout=60_000)
    x0, x1, _y0, _y1 = page.evaluate(ranges)
    assert x1 - x0 < 4.0                                         # zoomed in: narrower than the region
    # the layer's other indicator: its colour bar's label and the link follow the choice
    # (Panel's select: options are labels or [value, label] pairs, whatever its model's type)
    page.evaluate("() => { const fd = o => String(Array.isArray(o) ? o[1] : o).startsWith('frequency diffusion'); "
                  "const m = [...Bokeh.documents[0].all_models].find(m => Array.isArray(m.options) && "
                  "m.options.some(fd)); const o = m.options.find(fd); m.value = Array.isArray(o) ? o[0] : o; }")
    _wait(page, "() => Bokeh.documents[0].get_model_by_name('megno-colour-bar').title.includes('ν1 − ν2') "
                "&& window.location.search.includes('indicator=frequency_diffusion')", timeout=60_000)
    page.evaluate(SET_BOX, ["chaos layer", False])
    _wait(page, "() => Bokeh.documents[0].get_model_by_name('raster').data.x.length === 0",
                           timeout=60_000)
    page.close()


def test_explore_in_a_notebook_renders_and_streams_the_clicked_orbit(monkeypatch):
    pn = pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    import explorer as ex
    from explorer.app.serve import overlays

    monkeypatch.setattr(overlays, "READOUT_SECONDS", 3600.0)   # the readout whole on a loaded machine too
    app = ex.explore(mu=0.5, n_crossings=60)
    try:
        root = pn.panel(app).get_root()                 # what a notebook cell renders
        assert root.select_one({"name": "section"}) is not None
        page = app.page
        assert page.click(0.3, 0.1) is not None
        t0 = time.time()
        while len(page.orbits.columns()["t"]) < 60 and time.time() - t0 < 120:
            poll(page)
            time.sleep(0.01)
        ref = sections.crossings(page.settings.params, page.settings.h, [(0.3, 0.1)], n_crossings=60)
        got = np.column_stack([np.asarray(page.orbits.columns()[k]) for k in ("t", "p1", "p2", "M", "dH")])
        np.testing.assert_array_equal(got, ref.orbit(0))
        # the orbit's chaos indicators colour its points on demand
        from explorer.analysis import lyapunov
        from explorer.app.serve.orbits import INDICATOR_TIME

        while not any(r.indicators for r in page.orbits.runs.values()) and time.time() - t0 < 120:
            poll(page)
            time.sleep(0.01)
        (megno, mlce), = [r.indicators for r in page.orbits.runs.values()]
        ind = lyapunov.indicators(page.settings.params, states=ex.section_state(page.settings.params, [0.3], [0.1],
                                                                         page.settings.h), tmax=INDICATOR_TIME)
        assert (megno, mlce) == (float(ind.megno[0]), float(ind.mlce[0]))
        assert np.all(np.asarray(page.orbits.columns()["megno"]) == megno) and "<Y> =" in page.orbits.status.text
        page.orbits.colour_box.value = True
        assert page.orbits.points.glyph.fill_color["field"] == "megno" and page.url_query()["colour"] == "megno"
        page.orbit_list.undo()
        assert len(page.orbits.columns()["t"]) == 0 and page.url_query()["orbits"] == ""
        with pytest.raises(ParameterError, match="a1"):
            ex.explore(a1=-1.0)
    finally:
        app.close()


@browser_needed
def test_rapid_clicks_undo_clear_and_export_keep_the_page_and_the_server_consistent(served, browser):
    from explorer.io import scene as scene_mod

    page = _open(browser, served.url)
    c1, c2, r1, r2 = SERVED.region
    for i in range(20):                                   # 20 clicks, 50 ms apart (double taps among them)
        x, y = page.evaluate(TO_SCREEN, [c1 + (-0.9 + 0.09 * i) * r1, c2 + 0.05 * r2])
        page.mouse.click(x, y)
        page.wait_for_timeout(50)
    _wait(page, "() => Bokeh.documents[0].get_model_by_name('starts').data.orbit.length === 20")
    page.get_by_role("button", name="Resume").click()           # each click paused the orbits still running
    _wait_crossings(page, 20 * CROSSINGS)
    starts = page.evaluate(DATA, "starts")
    assert len(starts["orbit"]) == 20 and len(set(starts["p1"])) == 20
    data = page.evaluate(DATA, "crossings")
    assert sorted(set(data["orbit"])) == sorted(starts["orbit"])
    assert all(data["orbit"].count(i) == CROSSINGS for i in starts["orbit"])
    page.get_by_role("button", name="Undo").click()
    _wait(page, "() => Bokeh.documents[0].get_model_by_name('starts').data.orbit.length === 19",
                           timeout=60_000)
    assert len(page.evaluate(DATA, "crossings")["t"]) == 19 * CROSSINGS
    page.get_by_role("button", name="Export scene").click()
    _wait(page, f"() => ({TEXT})('message').includes('(the orbits, sweep format)')", timeout=120_000)
    files = list(Path(served.export_dir).glob("browser-session-*.toml"))
    assert len(files) == 1
    assert [list(p) for p in scene_mod.load_scene(str(files[0])).seeds.points] == \
        [[a, b] for a, b in zip(starts["p1"][:19], starts["p2"][:19])]
    from explorer.io.store import read_store

    stored = read_store(str(files[0].with_suffix(".h5"))).panels[0]          # the page's orbits, bit for bit
    for i, ident in enumerate(starts["orbit"][:19]):
        mine = np.array(data["orbit"]) == ident
        rows = np.column_stack([np.array(data[k])[mine] for k in ("t", "p1", "p2", "M", "dH")])
        np.testing.assert_array_equal(stored.orbit(i), rows)
    page.get_by_role("button", name="Clear").click()
    _wait(page, "() => Bokeh.documents[0].get_model_by_name('crossings').data.t.length === 0",
                           timeout=60_000)
    _wait(page, "() => /[?&]orbits=(&|$)/.test(window.location.search)", timeout=60_000)  # the link too
    page.close()
    assert urllib.request.urlopen(served.url, timeout=PAGE_TIMEOUT).status == 200


#: the browser pause test's orbits: fixed steps of split2 at dt = 1e-3, about 0.7 ms of CPU a crossing
#: (taylor's: microseconds), so that an orbit of these 2,000 (1.4 CPU-s) runs longer than one of
#: 2 x PAUSE_CROSSINGS taylor crossings (0.95 CPU-s): the first is still running when the second click
#: lands, while the browser gets 4,000 rows
BROWSER_PAUSE = dataclasses.replace(SERVED, method="split2", dt=1e-3, crossings=2000)


@browser_needed
def test_in_the_browser_a_click_elsewhere_pauses_the_running_orbit_and_resume_completes_it(served, browser):
    s = BROWSER_PAUSE
    n = s.crossings
    page = _open(browser, f"{served.url}?method={s.method}&dt={s.dt!r}&crossings={n}")   # (a link sets them)
    _wait(page, f"() => window.location.search.includes('method={s.method}&') && "
                f"window.location.search.includes('dt={s.dt!r}&') && window.location.search.includes('crossings={n}')",
          timeout=60_000)
    c1, c2, r1, r2 = SERVED.region
    _click(page, c1 + 0.3 * r1, c2)
    _wait_crossings(page, 1)
    _click(page, c1 - 0.5 * r1, c2 + 0.2 * r2)                # elsewhere: the first orbit pauses
    _wait(page, f"() => ({TEXT})('status').includes('0 running, 1 paused')", timeout=120_000)
    starts = page.evaluate(DATA, "starts")
    orbit = np.array(page.evaluate(DATA, "crossings")["orbit"])
    first, second = starts["orbit"]
    assert 0 < np.sum(orbit == first) < n and np.sum(orbit == second) == n
    page.get_by_role("button", name="Resume").click()
    _wait_crossings(page, 2 * n, timeout=120_000)
    assert "paused" not in page.evaluate(TEXT, "status")
    data = page.evaluate(DATA, "crossings")
    mine = np.array(data["orbit"]) == first
    rows = np.column_stack([np.array(data[k])[mine] for k in ("t", "p1", "p2", "M", "dH")])
    ref = sections.crossings(s.params, s.h, [(starts["p1"][0], starts["p2"][0])], n_crossings=n, **s.section_kwargs())
    np.testing.assert_array_equal(rows, ref.orbit(0))          # paused and resumed: one uninterrupted run
    page.close()


# ---------------------------------------------------------------- `explorer explore`: serve, then the browser
class _FakeServer:
    """What server.run needs of a Bokeh server, serving nothing (the loop returns at once)."""

    def __init__(self):
        self.io_loop = self
        self.started = self.stopped = False

    def start(self):
        self.started = True

    def stop(self):
        self.stopped = True

    def add_callback(self, callback):      # run on the loop, which never runs here
        pass


def _explore_in_process(monkeypatch, capsys, argv, browser):
    """Run ``explorer <argv>`` with the Bokeh server replaced and ``webbrowser.get`` returning
    ``browser`` (an exception class: raised instead); returns (status, stdout lines, stderr)."""
    import webbrowser

    from explorer.app import cli
    from explorer.app.serve import server

    fake = _FakeServer()
    monkeypatch.setattr(server, "make_server", lambda base, **kw: (fake, server.url_of(kw["host"], 5999, kw["token"])))
    monkeypatch.setattr(server, "warm_up_and_freeze", lambda settings: None)
    monkeypatch.setenv("DISPLAY", ":0")

    def get(*_a):
        if isinstance(browser, type):
            raise browser("no runnable browser")
        return browser
    monkeypatch.setattr(webbrowser, "get", get)
    code = cli.main(argv)
    time.sleep(0.2)                         # the browser is opened in a thread
    out, err = capsys.readouterr()
    assert fake.started and fake.stopped
    return code, out.splitlines(), err


class _Browser:
    def __init__(self):
        self.opened = []

    def open(self, url, *a, **kw):
        self.opened.append(url)
        return True


def test_the_server_freezes_what_is_alive_after_its_warm_up():
    """After loading the kernels the server moves every object alive out of the cyclic garbage
    collector's sight: a full collection no longer walks them in front of a click's crossings;
    what a session creates afterwards is collected as before."""
    import gc
    import weakref

    from explorer.app.serve import server

    gc.unfreeze()
    try:
        server.warm_up_and_freeze(SERVED)
        frozen = gc.get_freeze_count()
        assert frozen > 10_000                              # the modules and kernels at least
        class Cycle:
            pass
        a, b = Cycle(), Cycle()
        a.other, b.other = b, a                             # a cycle made after the freeze
        alive = weakref.ref(a)
        del a, b
        gc.collect()
        assert alive() is None and gc.get_freeze_count() == frozen
    finally:
        gc.unfreeze()


def test_explore_prints_the_url_first_and_opens_it_in_the_browser(monkeypatch, capsys):
    b = _Browser()
    code, out, err = _explore_in_process(monkeypatch, capsys, ["explore", "--mu", "0.03"], b)
    assert code == 0 and out[0] == "http://127.0.0.1:5999/" and b.opened == [out[0]] and err == ""
    b = _Browser()                                      # --no-browser: the URL only, as serve
    code, out, err = _explore_in_process(monkeypatch, capsys, ["explore", "--no-browser"], b)
    assert code == 0 and out == ["http://127.0.0.1:5999/"] and b.opened == [] and err == ""
    code, out, _err = _explore_in_process(monkeypatch, capsys, ["serve"], b)       # serve opens nothing
    assert code == 0 and out == ["http://127.0.0.1:5999/"] and b.opened == []


def test_explore_without_a_browser_prints_the_url_like_serve(monkeypatch, capsys):
    import webbrowser

    code, out, err = _explore_in_process(monkeypatch, capsys, ["explore", "--token", "t0k"], webbrowser.Error)
    assert code == 0 and out == ["http://127.0.0.1:5999/?token=t0k"] and "no web browser" in err
    monkeypatch.delenv("DISPLAY")                        # a terminal without a display: no browser either
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.delenv("BROWSER", raising=False)
    from explorer.app.serve import server

    if os.name == "posix" and sys.platform != "darwin":
        assert server.web_browser() is None


def test_explore_and_serve_share_one_definition_of_their_options():
    import argparse

    from explorer.app.commands import explore
    from explorer.app.serve import command

    def options(add):
        p = argparse.ArgumentParser()
        sub = p.add_subparsers()
        return {a.dest: (a.default, a.type, a.option_strings) for a in add(sub)._actions if a.dest != "help"}
    serve, expl = options(command.COMMAND.add_parser), options(explore.COMMAND.add_parser)
    assert set(expl) - set(serve) == {"no_browser"}
    assert {k: v for k, v in expl.items() if k != "no_browser"} == serve


@pytest.mark.skipif(importlib.util.find_spec("panel") is None, reason="panel is not installed (pip install panel)")
def test_explore_no_browser_serves_the_page_of_serve():
    s = Served("--mu", "0.03", command="explore", extra=("--no-browser",))
    try:
        page = urllib.request.urlopen(s.url, timeout=PAGE_TIMEOUT).read().decode("utf-8", "replace")
        assert "bokeh" in page.lower() and "explorer" in page
    finally:
        code, err = s.interrupt()
    assert code in (0, 130) and "Traceback" not in err, err[-2000:]


def test_the_scene_seeds_button_starts_the_sweeps_seeds_at_the_current_settings():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.analysis.seeds import seed_points
    from explorer.app.serve.page import SectionPage
    from explorer.app.serve.settings import page_settings
    from explorer.io import scene as scene_mod

    sc = scene_mod.load_scene("figure4")
    base, _label, _seeds = page_settings(sc, None, 1, crossings=5)
    page = SectionPage(base, {"mu": "0.5"}, seeds=sc.seeds)
    try:
        assert page.run_seeds() == len(page.orbits.starts) > 0
        p1, p2, _ = seed_points(sc.seeds, page.settings.params, page.settings.h)
        assert [(a, b) for _i, a, b, _c in page.orbits.starts] == list(zip(p1.tolist(), p2.tolist()))
        assert page.settings.params.mu == 0.5 and "orbits started" in page.message.text
        assert len(parse_starts(page.url_query()["orbits"])) == len(p1)           # kept in the link
    finally:
        page.close()


def test_scene_seeds_the_map_refuses_start_no_orbit_and_the_message_says_so(monkeypatch):
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=5)
    c1, c2, r1, _r2 = s.region
    page = SectionPage(s)
    monkeypatch.setattr(Settings, "seed_starts", lambda _s, _seeds: [(c1, c2), (c1 + 3 * r1, c2)])  # (outside)
    try:
        assert page.run_seeds() == 1 == len(page.orbits.runs)
        assert page.message.text == "scene seeds: 1 of 2 started (the map refuses the others)"
    finally:
        page.close()


def _poll_until(page, cond, timeout=240.0):
    t0 = time.time()
    while not cond() and time.time() - t0 < timeout:
        poll(page, 0.02)  # (the page's own loop runs only while polled: no sleep between polls)
    assert cond(), (page.message.text, page.orbits.status.text)
    for _ in range(10):          # then what the page scheduled meanwhile (the flush after a first block)
        if not poll(page):
            break


def test_an_orbits_megno_reaches_its_rows_whether_live_or_settled():
    """The MEGNO of an orbit known while its first crossings are still on the live layer: the
    server's rows, the live rows and, once they settle, the page's crossings all carry it (each
    row in the browser is in one of the two sources, patched where it is)."""
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=40)
    c1, c2, r1, _r2 = s.region
    page = SectionPage(s)
    try:
        older = page.click(c1 + 0.3 * r1, c2).ident
        _poll_until(page, lambda: len(page.orbits.shown.data["t"]) == s.crossings
                    and page.orbits.runs[older].indicators)
        page.orbits.runs[older + 1] = OrbitRun(older + 1, c1, c2, s, paused=True)   # a second orbit, by hand:
        rows = np.column_stack([np.arange(1.0, 5.0), np.full(4, c1), np.full(4, c2), np.ones(4), np.zeros(4)])
        _hand_in(page, older + 1, rows, "running")                            # its first block
        page.orbits._flush()                                # (its flush, by hand: the loop runs the next one)
        assert len(page.orbits.live.data["t"]) == 4                # live, not yet settled
        hand = page.orbits.worker._hand_indicators
        hand(page.orbits.runs[older], 2.5, 0.01)                   # the older orbit's rows: settled
        hand(page.orbits.runs[older + 1], 7.0, 0.2)                # the newer one's: live
        np.testing.assert_array_equal(page.orbits.shown.data["megno"], np.full(s.crossings, 2.5))
        assert page.orbits.live.data["megno"] == [7.0] * 4
        assert poll(page)                                  # the next flush settles them
        assert page.orbits.live.data["megno"] == []
        np.testing.assert_array_equal(page.orbits.shown.data["megno"],
                                      np.r_[np.full(s.crossings, 2.5), np.full(4, 7.0)])
        np.testing.assert_array_equal(page.orbits.shown.data["megno"], page.orbits.columns()["megno"])
    finally:
        page.close()


def test_picking_an_orbits_crossing_shows_its_mlce_megno_and_rotation_number():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.analysis import lyapunov, rotation
    from explorer.analysis.fixedpoints import find_fixed_point
    from explorer.app.serve.orbits import INDICATOR_TIME
    from explorer.app.serve.overlays import elliptic_center
    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=40)
    page = SectionPage(s)
    try:
        starts = [(0.3, 0.1), (1.3, 0.05)]             # the second in the island of the elliptic point (1.58, 0)
        for p in starts:
            page.click(*p)
        page.orbit_list.resume()                                  # (the second click paused the first if it still ran)
        _poll_until(page, lambda: len(page.orbits.columns()["t"]) == 2 * s.crossings)
        d = page.orbits.columns()
        second = np.asarray(d["orbit"]) == page.orbits.starts[1][0]
        k = int(np.flatnonzero(second)[17])                     # a crossing of the second orbit, not its start
        assert page.orbit_list.pick(float(d["p1"][k]) + 1e-9, float(d["p2"][k])) == page.orbits.starts[1][0]
        _poll_until(page, lambda: "rotation number" in page.orbit_list.text.text)
        r, _text = page.orbits.runs[page.orbits.starts[1][0]].readout
        y0 = model.section_state(s.params, [starts[1][0]], [starts[1][1]], s.h)
        ind = lyapunov.indicators(s.params, states=y0, tmax=INDICATOR_TIME, method=s.method, tol=s.tol)
        assert (r["megno"], r["mlce"]) == (float(ind.megno[0]), float(ind.mlce[0]))          # the same numbers
        fp = elliptic_center(s, starts[1])
        assert fp.stable and fp.point == pytest.approx(find_fixed_point(s.params, s.h, starts[1]).point, abs=0)
        ref = rotation.rotation_number(s.params, s.h, starts[1], center=fp.point, tol=s.tol)
        assert r["rotation"].value == ref.value and f"{ref.value:.10g}" in page.orbit_list.text.text
        assert f"{float(ind.mlce[0]):.4g}" in page.orbit_list.text.text and "orbit 2" in page.orbit_list.text.text
        assert page.orbit_list.pick(50.0, 50.0) is None and "no crossing within" in page.message.text     # nowhere near
        import threading

        before = threading.active_count()
        for run in page.orbits.runs.values():                      # no readout known: a pick computes it
            run.readout = None
        for _ in range(20):                                         # rapid picks: one readout thread, the last pick
            page.orbit_list.pick(float(d["p1"][k]), float(d["p2"][k]))
        assert threading.active_count() <= before
        _poll_until(page, lambda: page.orbits.runs[page.orbits.starts[1][0]].readout)
        page.click_mode.value = "pick an orbit"                  # the switch: a tap picks instead of starting
        from bokeh.events import Tap

        page._on_tap(Tap(page.section.figure, sx=1.0, sy=1.0, x=float(d["p1"][0]), y=float(d["p2"][0])))
        assert len(page.orbits.starts) == 2 and page.orbit_list.picked == int(d["orbit"][0])
        page.orbit_list.undo()
        page.orbit_list.undo()
        assert page.orbit_list.text.text == "" and page.orbits.runs == {}
    finally:
        page.close()


@browser_needed
def test_shift_click_on_a_crossing_in_the_browser_shows_that_orbits_readout(served, browser):
    page = _open(browser, served.url)
    c1, c2, r1, r2 = SERVED.region
    _click(page, c1 + 0.4 * r1, c2 + 0.1 * r2)
    _wait_crossings(page, CROSSINGS)
    data = page.evaluate(DATA, "crossings")
    x, y = page.evaluate(TO_SCREEN, [data["p1"][CROSSINGS // 2], data["p2"][CROSSINGS // 2]])
    page.keyboard.down("Shift")
    page.mouse.click(x, y)
    page.keyboard.up("Shift")
    _wait(page, f"() => ({TEXT})('readout').includes('rotation number')", timeout=FIRST_ORBIT_TIMEOUT_MS)
    assert len(page.evaluate(DATA, "starts")["orbit"]) == 1                   # picked, nothing started
    assert f"orbit {data['orbit'][0]} from" in page.evaluate(TEXT, "readout")
    page.close()


# ---------------------------------------------------------------- faults: the server keeps serving, memory returns
#: the shared executors' bound: the page's workers, its loop, the generated drivers' threads
POOL_THREADS = tasks.WORKERS + 1 + DRIVER_THREADS


def _threads():
    """(threads outside the shared executors of app/serve/tasks.py and of the generated drivers
    (analysis/system_sections.py), threads of those executors):
    the page may start no thread of its own per task; the executors are bounded (tasks.WORKERS) and
    keep as many threads as calls ever ran at once (a cancelled task's last block may still be
    finishing beside its successor's), so only the first count must stay flat."""
    import threading

    pool = [t for t in threading.enumerate()
            if t.name.startswith(("explorer-serve", "explorer-page-loop", "explorer-driver"))]
    return threading.active_count() - len(pool), len(pool)


#: clicks of the memory test, crossings per click, and clicks between two Clears (a session holds
#: at most settings.MAX_STARTS orbits, so the 500 clicks are 10 rounds of 50 clicks and a Clear)
CLICKS, CLICK_CROSSINGS, ROUND = 500, 20, 50
#: growth of the Python heap (tracemalloc: numpy arrays included; after gc.collect, Bokeh's models
#: hold reference cycles) allowed from the end of the second round to the end of the last, 8
#: rounds = 400 clicks later: 16 kB, 40 bytes a click.  A round holds 50 x 20 rows x 8 columns x
#: 8 bytes = 64 kB of crossings, all dropped by Clear; a leak of one crossing row per click (64 B)
#: would show as 25 kB, of one orbit's rows (1.3 kB) as 500 kB, of its indicators' tuple as
#: 400 x ~100 B: each past the bound.  Measured: 1 kB.
HEAP_GROWTH_BOUND = 16 * 1024
#: the round from which tracemalloc traces (it costs ~1.1 CPU-s a round): the second, whose end is the
#: baseline.  The growth is then what was allocated after round 0 and is alive at the end, less what
#: round 1 left alive at the baseline: never less than with tracing from the first click (which also
#: subtracted what round 0 left and was freed after the baseline), so every leak that showed still shows
TRACE_FROM = 1


def test_five_hundred_clicks_leave_the_session_with_bounded_memory_and_threads(monkeypatch):
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    import gc
    import tracemalloc

    from explorer.app.serve import orbits
    from explorer.app.serve.page import SectionPage

    monkeypatch.setattr(orbits, "INDICATOR_TIME", 20.0)        # the indicators still run, shorter
    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=CLICK_CROSSINGS)
    c1, c2, r1, r2 = s.region
    rng = np.random.default_rng(7)
    page = SectionPage(s)
    poll(page)                                                    # (the thread that runs the page's own loop)
    others0 = _threads()[0]
    try:
        heap, paused = [], 0
        for _round in range(CLICKS // ROUND):
            if _round == TRACE_FROM:
                tracemalloc.start()
            for _ in range(ROUND):
                u, v = rng.uniform(-0.9, 0.9, 2)
                assert page.click(c1 + u * r1 * np.sqrt(1 - v * v), c2 + v * r2 * 0.9) is not None
            paused += len(page.orbits.worker.paused())  # each click paused the orbits still running ...
            page.orbit_list.resume()                                           # ... and Resume continues them
            _poll_until(page, lambda: _idle(page) and all(r.indicators for r in page.orbits.runs.values())
                        and len(page.orbits.columns()["t"]) == ROUND * CLICK_CROSSINGS)   # (the cheap checks first)
            assert sorted(np.unique(page.orbits.columns()["orbit"])) == sorted(i for i, *_ in page.orbits.starts)
            page.orbit_list.clear()
            poll(page)
            assert len(page.orbits.columns()["t"]) == 0 and page.orbits.starts == []
            assert page.orbits.runs == {}                           # (running, paused or stopped)
            gc.collect()                                            # (Bokeh's models hold reference cycles)
            heap.append(tracemalloc.get_traced_memory()[0])           # (0 before TRACE_FROM)
        # no thread per click: the orbits and their indicators run in the shared executor (tasks.py)
        others, pool = _threads()
        assert others <= others0 and pool <= POOL_THREADS, (others0, others, pool)
        assert paused > 0                                          # paused orbits were held, and let go
        growth = heap[-1] - heap[1]
        print(f"heap after each round (kB): {[h // 1024 for h in heap]}; growth {growth / 1024:.0f} kB; "
              f"{paused} orbits paused in all")
        assert growth < HEAP_GROWTH_BOUND, heap
        page.close()                                               # the tab is gone: its work ends
        assert not page.session.busy()
    finally:
        tracemalloc.stop()
        page.close()


def test_fifty_clicks_and_five_megno_toggles_start_no_thread_of_their_own():
    """The page's work runs in the executors shared by every session (tasks.py): no other thread
    appears, whatever the number of clicks and toggles, and the executors stay within their bound."""
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")

    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=CLICK_CROSSINGS)
    c1, c2, r1, r2 = s.region
    rng = np.random.default_rng(3)
    page = SectionPage(s, megno_resolution=16, megno_time=5.0)
    try:
        poll(page)                                         # (the thread that runs the page's own loop)
        others0, most = _threads()[0], 0
        for k in range(50):
            u, v = rng.uniform(-0.9, 0.9, 2)
            assert page.click(c1 + u * r1 * np.sqrt(1 - v * v), c2 + v * r2 * 0.9) is not None
            if k % 10 == 0:
                page.chaos.layer.value = not page.chaos.layer.value               # the MEGNO layer on, then off, ...
            poll(page)
            others, pool = _threads()
            most = max(most, others)
            assert pool <= POOL_THREADS, pool
        page.orbit_list.resume()
        settle(page)
        assert len(page.orbits.columns()["t"]) == 50 * CLICK_CROSSINGS and _idle(page)
        assert most <= others0, (others0, most)
    finally:
        page.close()


def test_a_value_changed_during_the_megno_raster_restarts_it_for_the_new_value():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve import raster
    from explorer.app.serve.page import SectionPage

    page = SectionPage(Settings(params=model.FIGURE4.with_(mu=0.03), tol=1e-10), {"megno": "1"})
    shown = []
    show = page.chaos.show_image
    page.chaos.show_image = lambda im: (shown.append((page.settings.params.mu, im)), show(im))
    try:
        _poll_until(page, lambda: bool(page.chaos.raster_source.data["n"]))          # the old raster is on
        page.inputs["mu"].value = "0.5"                                        # changed while it runs
        new = 0.5                                       # (an image the older task handed in later would show here)
        assert page.settings.params.mu == 0.5
        # the new value's first complete raster, as the page was handed it: the state the wait is
        # for, read from the record of what was shown (the page may show a finer one by then)
        def complete_at_first_resolution():
            return [im for g, im in shown if g == new and im.complete and im.n == raster.RESOLUTIONS[0]]

        _poll_until(page, lambda: bool(complete_at_first_resolution()))
        ref = next(im for im in raster.rasters(page.settings, page.section.window) if im.complete)
        np.testing.assert_array_equal(complete_at_first_resolution()[0].values, ref.values)  # the new value's
        after = [im for g, im in shown if g == new]
        assert after and all(im.window == page.section.window for im in after)
        page.chaos.layer.value = False
        assert page.chaos.raster_source.data["n"] == []
    finally:
        page.close()


@browser_needed
def test_a_client_that_leaves_mid_orbit_leaves_the_server_serving_the_next(served, browser):
    page = _open(browser, served.url)
    _set_field(page, "crossings", "200000")                 # an orbit of several seconds
    _wait(page, "() => window.location.search.includes('crossings=200000')", timeout=60_000)
    c1, c2, r1, r2 = SERVED.region
    _click(page, c1 + 0.3 * r1, c2)
    _wait_crossings(page, 1)
    assert page.evaluate(DATA, "crossings")["p1"].__len__() < 200000     # mid-orbit
    page.close()                                            # the tab goes, its orbit still running
    other = _open(browser, served.url)                      # a second client: a page and an orbit
    _click(other, c1 - 0.3 * r1, c2 + 0.1 * r2)
    _wait_crossings(other, CROSSINGS)
    starts = other.evaluate(DATA, "starts")
    data = other.evaluate(DATA, "crossings")
    rows = np.column_stack([np.array(data[k]) for k in ("t", "p1", "p2", "M", "dH")])
    np.testing.assert_array_equal(rows, _orbit_json(SERVED, starts["p1"][0], starts["p2"][0]))
    other.close()
    assert served.proc.poll() is None


# ---------------------------------------------------------------- the view as PNG and SVG
def _svg_orbits(svg: bytes) -> dict:
    """{orbit id: [fill colours of its points]} of an exported SVG (each orbit is one group)."""
    import xml.etree.ElementTree as ET

    root = ET.fromstring(svg)
    out = {}
    for g in root.iter("{http://www.w3.org/2000/svg}g"):
        gid = g.get("id", "")
        if gid.startswith("orbit-"):
            styles = [u.get("style", "") for u in g.iter() if u.tag.endswith("use")]
            out[int(gid.split("-")[1])] = [st.split("fill:")[1].split(";")[0].strip() for st in styles if "fill:" in st]
    return out


def test_the_view_exports_as_svg_with_one_group_per_orbit_and_as_png_in_the_orbits_colours(tmp_path):
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    import io

    import matplotlib.colors
    import matplotlib.image

    from explorer.app.serve.orbits import COLORS
    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=300)
    c1, c2, r1, r2 = s.region
    page = SectionPage(s, export_dir=str(tmp_path))
    try:
        for u in (0.5, -0.3, 0.1):
            page.click(c1 + u * r1, c2 + 0.1 * r2)
        page.orbit_list.resume()                                  # (each click paused the orbits still running)
        _poll_until(page, lambda: len(page.orbits.columns()["t"]) == 3 * s.crossings)
        svg = page.exports.download("svg").getvalue()
        groups = _svg_orbits(svg)                                        # parses as XML
        assert sorted(groups) == sorted(i for i, *_ in page.orbits.starts)      # one group per orbit
        for ident, _a, _b, c in page.orbits.starts:
            n_inside = int(np.sum(np.asarray(page.orbits.columns()["orbit"]) == ident))
            assert len(groups[ident]) == n_inside                       # a point per crossing
            assert set(groups[ident]) == {COLORS[c]}                     # in the orbit's colour
        img = matplotlib.image.imread(io.BytesIO(page.exports.download("png").getvalue()))[..., :3]
        for _i, _a, _b, c in page.orbits.starts:                                # each orbit's colour is on the picture
            rgb = np.array(matplotlib.colors.to_rgb(COLORS[c]))
            assert np.sum(np.abs(img - rgb).max(axis=2) < 0.05) > 50, COLORS[c]
        gray = np.array(matplotlib.colors.to_rgb("0.8"))
        assert np.sum(np.abs(img - gray).max(axis=2) < 0.02) > 1000        # the forbidden region
        page.orbits.colour_box.value = True  # coloured by MEGNO: not the orbit colours
        _poll_until(page, lambda: all(r.indicators for r in page.orbits.runs.values()))
        assert all(set(v) != {COLORS[c]} for (_i, _a, _b, c), v in zip(page.orbits.starts, _svg_orbits(
            page.exports.download("svg").getvalue()).values()))
        page.exports.export_figure()                                              # into --export-dir, PNG and SVG
        _poll_until(page, lambda: "figure written" in page.message.text, timeout=60)
        assert sorted(p.suffix for p in tmp_path.iterdir()) == [".png", ".svg"]
    finally:
        page.close()


@browser_needed
def test_the_figure_downloads_from_the_page_as_svg(served, browser, tmp_path):
    page = _open(browser, served.url)
    c1, c2, r1, r2 = SERVED.region
    _click(page, c1 + 0.6 * r1, c2)
    _wait_crossings(page, CROSSINGS)
    ident = page.evaluate(DATA, "starts")["orbit"][0]
    with page.expect_download(timeout=120_000) as dl:
        page.get_by_role("button", name="Figure (SVG)").click()
    path = tmp_path / "view.svg"
    dl.value.save_as(str(path))
    groups = _svg_orbits(path.read_bytes())
    assert list(groups) == [ident] and len(groups[ident]) == CROSSINGS
    page.close()


def test_a_million_crossings_are_drawn_as_a_density_image_of_the_visible_window():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve import density
    from explorer.app.serve.orbits import COLORS
    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=4000)
    c1, c2, r1, r2 = s.region
    page = SectionPage(s)
    try:
        for u in (-0.5, 0.5):
            page.click(c1 + u * r1, c2)
        page.orbit_list.resume()                                  # (the second click paused the first if it still ran)
        settle(page)
        assert _idle(page) and len(page.orbits.columns()["t"]) == 2 * s.crossings
        assert not page.density_image.dense and page.orbits.points.visible
        assert page.density_image.density.data["image"] == []
        # 10^6 more crossings of the two orbits (points spread over the region), as the worker hands them in
        rng = np.random.default_rng(3)
        n = 500_000
        for ident, _a, _b, _c in page.orbits.starts:
            a, r = rng.uniform(0, 2 * np.pi, n), np.sqrt(rng.uniform(0, 1, n))
            rows = np.column_stack([np.arange(n, dtype=float), c1 + r1 * r * np.cos(a), c2 + r2 * r * np.sin(a),
                                    np.ones(n), np.zeros(n)])
            _hand_in(page, ident, rows)
        poll(page)
        assert len(page.orbits.columns()["t"]) > density.THRESHOLD and page.density_image.dense
        assert not page.orbits.points.visible
        assert len(page.orbits.shown.data["t"]) == 0                                   # nothing of it for the browser
        image = page.density_image.density.data["image"][0]
        assert image.dtype == np.uint32
        assert page.density_image.density.data["n"] == [len(page.orbits.columns()["t"])]
        rgba = image.view(np.uint8).reshape(*image.shape, 4)
        drawn = {"#%02x%02x%02x" % tuple(px) for px in rgba[rgba[..., 3] > 0][:, :3]}
        assert drawn == {COLORS[c] for *_x, c in page.orbits.starts}                    # the orbits' colours
        assert (rgba[..., 3] > 0).mean() > 0.3                                   # the region is covered
        # zoom: re-aggregated for the new window, in well under a second
        class Ranges:
            x0, x1, y0, y1 = c1 - 0.1 * r1, c1 + 0.1 * r1, c2 - 0.1 * r2, c2 + 0.1 * r2
        t0 = time.perf_counter()
        page.section._on_ranges(Ranges)
        took = time.perf_counter() - t0
        assert page.density_image.density.data["x"] == [Ranges.x0]
        assert page.density_image.density.data["dw"] == [Ranges.x1 - Ranges.x0]
        assert page.section.window == settings_mod.Window(Ranges.x0, Ranges.x1, Ranges.y0, Ranges.y1)
        print(f"density image of {len(page.orbits.columns()['t'])} crossings re-aggregated in {took * 1e3:.0f} ms")
        assert took < 2.0
        page.orbit_list.undo()                                                              # one orbit less: redrawn
        assert page.density_image.dense
        assert page.density_image.density.data["n"] == [len(page.orbits.columns()["t"])] == [n + s.crossings]
        page.orbit_list.undo()  # below the threshold: glyphs again
        assert not page.density_image.dense and page.orbits.points.visible
        assert page.density_image.density.data["image"] == []
        np.testing.assert_array_equal(page.orbits.shown.data["p1"], page.orbits.columns()["p1"])   # the rows, back
    finally:
        page.close()


def _glyphs_and_image(page):
    """(orbit ids drawn as glyphs, orbit ids in the density image), checking that every crossing is
    in exactly one of the two: the glyphs at most GLYPH_BUDGET crossings of the newest orbits, whole
    (the next older orbit would not fit), the image all the others (its n, its colours)."""
    from explorer.app.serve import density
    from explorer.app.serve.orbits import COLORS

    orbit = np.asarray(page.orbits.shown.data["orbit"])
    np.testing.assert_array_equal(np.sort(orbit), page.orbits.columns()["orbit"])   # the browser holds every row
    first = page.orbits.glyph_filter.args["first"]
    drawn = orbit >= first                                                      # what the browser's filter keeps
    ids = [i for i, *_ in page.orbits.starts]
    glyphs, image = [i for i in ids if i >= first], [i for i in ids if i < first]
    assert ids == sorted(ids) and glyphs == ids[len(image):]                    # the newest orbits
    assert np.count_nonzero(drawn) <= density.GLYPH_BUDGET
    if image:                                                                   # whole orbits, as many as fit
        assert np.count_nonzero(orbit >= image[-1]) > density.GLYPH_BUDGET
        assert page.density_image.density.data["n"] == [np.count_nonzero(~drawn)]            # every other crossing
        assert np.count_nonzero(drawn) + page.density_image.density.data["n"][0] == len(orbit)
        picture = page.density_image.density.data["image"][0]
        rgba = picture.view(np.uint8).reshape(*picture.shape, 4)
        if not page.orbits.colour_box.value:
            colours = {"#%02x%02x%02x" % tuple(px) for px in rgba[rgba[..., 3] > 0][:, :3]}
            assert colours == {COLORS[c] for i, _a, _b, c in page.orbits.starts if i in image}
    else:
        assert first == 0 and page.density_image.density.data["image"] == [] and len(orbit) <= density.GLYPH_BUDGET
    return glyphs, image


def test_past_the_glyph_budget_the_newest_orbits_are_glyphs_and_the_older_ones_in_the_density_image():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve import density
    from explorer.app.serve.page import SectionPage

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=20)
    c1, c2, r1, r2 = s.region
    page = SectionPage(s)
    rng = np.random.default_rng(5)

    def more(ident, n, status="done"):   # n more crossings of orbit ident (over the region)
        a, r = rng.uniform(0, 2 * np.pi, n), np.sqrt(rng.uniform(0, 1, n))
        rows = np.column_stack([np.arange(n, dtype=float), c1 + r1 * r * np.cos(a), c2 + r2 * r * np.sin(a),
                                np.ones(n), np.zeros(n)])
        _hand_in(page, ident, rows, status)

    try:
        page.orbits.pause_box.value = False
        for u in (-0.6, -0.3, 0.0, 0.3, 0.6):
            page.click(c1 + u * r1, c2)
        settle(page)
        assert _idle(page) and len(page.orbits.columns()["t"]) == 5 * s.crossings
        ids = [i for i, *_ in page.orbits.starts]
        assert _glyphs_and_image(page) == (ids, [])                              # under the budget: as today
        budget = density.GLYPH_BUDGET                  # (the orbits' sizes as parts of it)
        for ident, part in zip(ids, (0.45, 0.3, 0.4, 0.25, 0.35)):
            more(ident, int(part * budget))
        poll(page)
        assert len(page.orbits.columns()["t"]) > density.GLYPH_BUDGET
        assert _glyphs_and_image(page) == (ids[3:], ids[:3])
        newest = page.orbits.runs[ids[-1]]             # as if the newest ran and this were its first block:
        page.orbits.hide(newest.ident)                 # (its rows off the browser's sources ...
        newest.hidden = False                          # ... and none sent yet)
        newest.sent = 0
        shown, status = len(page.orbits.shown.data["t"]), page.orbits.status.text
        more(ids[-1], int(0.45 * budget), "running")
        page.orbits._flush()                            # its first crossings go alone, to the live layer:
        assert len(page.orbits.live.data["t"]) == newest.done and len(page.orbits.shown.data["t"]) == shown
        np.testing.assert_array_equal(page.orbits.live.data["p1"], page.orbits.columns()["p1"][shown:])
        assert page.orbits.glyph_filter.args["first"] == ids[3]  # nothing else moves
        assert page.orbits.status.text == status
        older = np.count_nonzero(np.asarray(page.orbits.columns()["orbit"]) < ids[3])
        assert page.density_image.density.data["n"] == [older]
        assert poll(page)                              # the next flush (scheduled): they settle, and
        assert len(page.orbits.live.data["t"]) == 0            # one orbit more is in the image
        assert _glyphs_and_image(page) == (ids[4:], ids[:4])
        class Ranges:
            x0, x1, y0, y1 = c1 - 0.5 * r1, c1 + 0.5 * r1, c2 - 0.5 * r2, c2 + 0.5 * r2
        page.section._on_ranges(Ranges)                                                  # zoom: a new image, same split
        assert page.density_image.density.data["x"] == [Ranges.x0] and _glyphs_and_image(page) == (ids[4:], ids[:4])
        page.orbits.colour_box.value = True                                             # by MEGNO: the image too
        by_megno = page.density_image.density.data["image"][0]
        assert _glyphs_and_image(page) == (ids[4:], ids[:4])
        page.orbits.colour_box.value = False
        assert not np.array_equal(page.density_image.density.data["image"][0], by_megno)
        page.orbit_list.undo()  # older orbits back to glyphs
        assert _glyphs_and_image(page) == (ids[1:4], ids[:1])
        page.orbit_list.undo()
        page.orbit_list.undo()                                                              # under the budget again
        assert _glyphs_and_image(page) == (ids[:2], [])
        for ident in ids[:2]:
            more(ident, int(0.6 * budget))
        poll(page)
        assert _glyphs_and_image(page) == (ids[1:2], ids[:1])
        page.orbit_list.clear()
        assert _glyphs_and_image(page) == ([], []) and page.density_image.density.data["image"] == []
    finally:
        page.close()


#: in the browser: (rows of the crossings source, rows its glyph renderer draws through its CDSView)
DRAWN = """() => { const v = Bokeh.index.all_views().find(v => v.model.name === 'section');
  const r = [...v.renderer_views.values()].find(r => r.model.data_source && r.model.data_source.name === 'crossings');
  return [r.model.data_source.data.p1.length, r.model.view.indices.count]; }"""


@browser_needed
def test_past_the_glyph_budget_the_browser_draws_the_newest_orbit_and_the_image_the_older(served, browser):
    from explorer.app.serve import density

    page = _open(browser, served.url)
    per_orbit = int(0.6 * density.GLYPH_BUDGET)
    _set_field(page, "crossings", str(per_orbit))
    _wait(page, f"() => window.location.search.includes('crossings={per_orbit}')", timeout=60_000)
    c1, c2, r1, r2 = SERVED.region
    _click(page, c1 + 0.3 * r1, c2)
    _wait_crossings(page, per_orbit)
    assert page.evaluate(DRAWN) == [per_orbit, per_orbit]                     # under the budget: all dots
    page.wait_for_timeout(400)                                              # (not a double tap)
    _click(page, c1 - 0.6 * r1, c2 + 0.2 * r2)
    _wait_crossings(page, 2 * per_orbit)
    dens = "() => { const d = Bokeh.documents[0].get_model_by_name('density').data; return d.n.length ? d.n[0] : 0 }"
    _wait(page, f"() => ({dens})() === {per_orbit}", timeout=60_000)        # the older orbit: the image
    assert page.evaluate(DRAWN) == [2 * per_orbit, per_orbit]                 # the newer: dots, the rows all there
    page.get_by_role("button", name="Undo").click()                         # the older orbit: dots again
    _wait(page, f"() => ({dens})() === 0 && ({DRAWN})()[1] === {per_orbit}", timeout=60_000)
    page.close()


@browser_needed
def test_past_the_threshold_the_browser_shows_a_density_image_that_follows_the_zoom(served, browser):
    from explorer.app.serve import density
    from explorer.app.serve.page_orbits import PAUSE_LABEL

    page = _open(browser, served.url)
    per_orbit = density.THRESHOLD // 2 + 5000
    _set_field(page, "crossings", str(per_orbit))
    _wait(page, f"() => window.location.search.includes('crossings={per_orbit}')", timeout=60_000)
    page.evaluate(SET_BOX, [PAUSE_LABEL, False])                 # both orbits run together
    _wait(page, "() => window.location.search.includes('pause=0')", timeout=60_000)
    c1, c2, r1, r2 = SERVED.region
    _click(page, c1 + 0.3 * r1, c2)
    _click(page, c1 - 0.6 * r1, c2 + 0.2 * r2)
    dens = "() => { const d = Bokeh.documents[0].get_model_by_name('density').data; return d.n.length ? d.n[0] : 0 }"
    _wait(page, f"() => ({dens})() === {2 * per_orbit}", timeout=120_000)
    assert "(as a density image)" in page.evaluate(TEXT, "status")
    assert page.evaluate(DATA, "crossings")["p1"] == []          # the rows stay in the server
    x, y = page.evaluate(TO_SCREEN, [c1, c2])
    ranges = ("() => { const f = Bokeh.documents[0].get_model_by_name('section');"
              " return [f.x_range.start, f.x_range.end]; }")
    times = []
    for step in range(3):                                  # zoom in three times: a new image for each window
        t0 = time.perf_counter()
        page.mouse.move(x, y)
        page.mouse.wheel(0, -300)
        _wait(page, f"() => {{ const r = ({ranges})(); const d = Bokeh.documents[0].get_model_by_name('density')"
                    ".data; return d.x.length && d.x[0] === r[0] && Math.abs(d.x[0] + d.dw[0] - r[1]) < 1e-12; }",
              timeout=60_000)
        times.append(time.perf_counter() - t0)
    print(f"{2 * per_orbit} crossings as a density image: zoom -> new image on screen in "
          f"{', '.join(f'{t * 1e3:.0f}' for t in times)} ms")
    page.get_by_role("button", name="Clear").click()
    _wait(page, "() => Bokeh.documents[0].get_model_by_name('density').data.n.length === 0", timeout=60_000)
    page.close()


def test_picking_a_hyperbolic_fixed_point_draws_its_grown_stable_and_unstable_manifolds(tmp_path):
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.analysis.manifolds import manifolds
    from explorer.app.figures import MANIFOLD_COLORS
    from explorer.app.serve.overlays import MANIFOLD_ARCLENGTH
    from explorer.app.serve.page import SectionPage

    page = SectionPage(Settings(params=model.FIGURE4.with_(mu=0.03)), {"separatrices": "1"})
    try:
        _poll_until(page, lambda: "hyperbolic" in page.overlays.fixed.data["kind"], timeout=120)
        k = page.overlays.fixed.data["kind"].index("hyperbolic")
        saddle = (page.overlays.fixed.data["p1"][k], page.overlays.fixed.data["p2"][k])
        assert page.orbit_list.pick(saddle[0] + 1e-9, saddle[1]) is None          # a mark, not an orbit
        _poll_until(page, lambda: len(page.overlays.manifold_source.data["xs"]) == 4, timeout=120)
        m = page.overlays.manifold_source.data
        ref = manifolds(page.settings.params, page.settings.h, saddle, arclength=MANIFOLD_ARCLENGTH)
        assert m["kind"] == [b.kind for b in ref] == ["unstable", "unstable", "stable", "stable"]
        assert m["color"] == [MANIFOLD_COLORS[b.kind] for b in ref]
        for x, y, b in zip(m["xs"], m["ys"], ref):                     # the analysis' branches, point for point
            np.testing.assert_array_equal(np.column_stack([x, y]), b.points)
            assert np.hypot(x[0] - saddle[0], y[0] - saddle[1]) < 1e-3  # each grows out of the saddle
            assert np.sum(np.hypot(np.diff(x), np.diff(y))) > 0.5 * MANIFOLD_ARCLENGTH
        assert "W^u red, W^s blue" in page.overlays.text.text
        svg = page.exports.download("svg").getvalue().decode()
        assert 'id="manifold-unstable' in svg and 'id="manifold-stable' in svg
        page.inputs["mu"].value = "0.05"                                   # a new value: the manifolds go
        _poll_until(page, lambda: page.overlays.manifold_source.data["xs"] == [])
    finally:
        page.close()


class _FakeDoc:
    """A served page's document without a server (its work runs on the page's own loop)."""

    def on_session_destroyed(self, _f):
        pass

    def on_event(self, _event, *_callbacks):     # (the connection is never lost here)
        pass


def _served_page(settings: Settings, **kw):
    """A SectionPage as served (its callbacks wait for the page's loop: settle), with no server."""
    from explorer.app.serve.page import SectionPage

    return SectionPage(settings, doc=_FakeDoc(), **kw)


def test_a_served_click_sends_its_cross_with_its_first_crossings_and_later_blocks_at_most_every_flush_interval():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve import page as page_mod
    from explorer.app.serve import page_orbits

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=40_000)
    c1, c2, r1, _r2 = s.region
    doc = _FakeDoc()
    page = page_mod.SectionPage(s, doc=doc)
    page.orbits.pause_box.value = False
    flushes = []          # (start, crosses, rows in crossings, rows in live, status) after each flush with rows
    flush = page.orbits._flush

    def rows():
        return len(page.orbits.shown.data["p1"]), len(page.orbits.live.data["p1"])

    def traced():
        before, start = rows(), time.monotonic()       # (when it takes the queued blocks)
        flush()
        if rows() != before:
            flushes.append((start, len(page.orbits.start_source.data["orbit"]), *rows(), page.orbits.status.text,
                            _link(page)["orbits"]))
    page.orbits._flush = traced
    try:
        page.click(c1 + 0.3 * r1, c2)
        # the cross and the link wait for the first crossings (sent in the same callback, just after
        # them: off the path from the click to them)
        assert page.orbits.start_source.data["orbit"] == [] and rows() == (0, 0) and _link(page)["orbits"] == ""
        status = page.orbits.status.text
        settle(page)
        assert len(page.orbits.shown.data["p1"]) == s.crossings
        np.testing.assert_array_equal(np.asarray(page.orbits.columns()["p1"]),
                                      np.asarray(page.orbits.shown.data["p1"]))
        # the first rows alone on the live layer (the status line unchanged), with the cross; the
        # next flush moves them to the crossings, with what came meanwhile
        # (with the orbit's next blocks if they were there already when the flush ran)
        assert flushes[0][1:3] == (1, 0) and flushes[0][3] >= FIRST_BLOCK and flushes[0][4] == status
        # the click's start is in the link with its first crossings: a reload from then on keeps it
        assert settings_mod.parse_starts(flushes[0][5]) == [(c1 + 0.3 * r1, c2)]
        assert flushes[1][2] > flushes[0][3] and flushes[1][3] == 0 and flushes[1][4] != status
        # between the first flush and the last, FLUSH_SECONDS at least (the last block goes at once)
        assert len(flushes) >= 3, flushes
        gaps = np.diff([t for t, *_x in flushes])[:-1]
        assert gaps.min() >= page_orbits.FLUSH_SECONDS - 0.01, gaps
    finally:
        page.close()


def test_a_short_orbit_joins_its_first_crossings_on_the_live_layer_until_they_settle():
    """An orbit done within FLUSH_SECONDS of its first crossings (its last block is sent at once):
    its rows go to the live layer too, and all of them move to the crossings together, once,
    FLUSH_SECONDS after the first, with the status line; nothing is lost or doubled."""
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve import page as page_mod
    from explorer.app.serve import page_orbits

    s = Settings(params=model.FIGURE4.with_(mu=0.03), crossings=40)       # blocks of 16 and 24
    c1, c2, r1, _r2 = s.region
    doc = _FakeDoc()
    page = page_mod.SectionPage(s, doc=doc)
    seen = []             # (time, rows in crossings, rows in live, status) after each flush
    flush = page.orbits._flush

    def traced():
        flush()
        seen.append((time.monotonic(), len(page.orbits.shown.data["p1"]), len(page.orbits.live.data["p1"]),
                     page.orbits.status.text))
    page.orbits._flush = traced
    try:
        status = page.orbits.status.text
        page.click(c1 + 0.3 * r1, c2)
        settle(page)
        firsts = [x for x in seen if x[2] > 0]      # the first block (with the last if it was there)
        assert firsts[0][1] == 0 and firsts[0][2] in (FIRST_BLOCK, s.crossings) and firsts[0][3] == status
        assert any(x[1:3] == (0, s.crossings) for x in seen)                  # the last one joins it
        settled = [x for x in seen if x[1] > 0]
        assert settled[0][1:3] == (s.crossings, 0) and settled[0][3] != status  # all at once, with the status
        assert settled[0][0] - firsts[0][0] >= page_orbits.FLUSH_SECONDS - page_orbits.SETTLE_SLACK
        np.testing.assert_array_equal(page.orbits.shown.data["p1"], page.orbits.columns()["p1"])
        assert len(page.orbits.columns()["p1"]) == s.crossings
    finally:
        page.close()
