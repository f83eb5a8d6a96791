"""`explorer serve --system module:attribute`: the page of a System's section map (docs/commands/serve.md,
"Your own system"), through the page's protocol (src/explorer/app/serve/settings.py).
Hénon–Heiles of tests/systems.py (its modules are those the other tests compile).  In chromium (a
server of its own, stopped at the end): orbits on the energy level, the MEGNO layer, and the
page, once its server stops, says the connection is lost."""
from __future__ import annotations

import importlib

import numpy as np
import pytest
from page_loop import settle
from systems import henon_heiles_map

import explorer as ex
from explorer.app import cli
from explorer.model import ParameterError

pytest.importorskip("panel", reason="panel is not installed (pip install panel)")

E = 1 / 8


def _energy(y, py, px):
    """Hénon–Heiles' H on x = 0 (lam = 1)."""
    return (px**2 + py**2) / 2 + y**2 / 2 - y**3 / 3


def test_serve_system_names_what_to_give_for_a_bare_system_and_refuses_chaplygins_options(capsys):
    from explorer.app.serve.command import page_from_args
    from explorer.app.serve.settings import SystemSettings

    for argv, said in ((["--system", "tests.systems:henon_heiles"], "System without a section"),
                       (["--system", "tests.systems:henon_heiles_map", "--mu", "0.5"], "--mu belongs to Chaplygin"),
                       (["--system", "tests.systems:HH_REVERSOR"], "not an explorer System or its section map")):
        assert cli.main(["serve", *argv]) == 2
        err = capsys.readouterr().err
        assert said in err and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    args = cli.build_parser().parse_args(["serve", "--system", "tests.systems:henon_heiles_map", "--h", "0.1",
                                          "--crossings", "30"])
    base, label, seeds = page_from_args(args)
    assert isinstance(base, SystemSettings) and seeds is None and label == "henon_heiles"
    assert base.fields() == {"lam": "1.0", "energy": "0.1", "tol": "1e-13", "crossings": "30"}


def test_a_systems_scene_gives_the_page_its_panel_crossings_and_seeds(tmp_path):
    from explorer.app.serve.command import page_from_args

    scene = tmp_path / "hh.toml"
    scene.write_text('name = "hh"\nsystem = "tests.systems:henon_heiles"\nsection = "x"\ndirection = 1\n'
                     'coords = ["y", "py"]\nsolve = "px"\n[energy]\nvalue = 0.125\n[sweep]\nparameter = "lam"\n'
                     'values = [0.5, 1.0]\n[seeds]\nkind = "points"\npoints = [[0.1, 0.1], [0.6, 0.45]]\n'
                     '[integration]\ncrossings = 50\n')
    base, label, seeds = page_from_args(cli.build_parser().parse_args(["serve", str(scene), "--panel", "1"]))
    assert label == "hh: lam = 1.0" and base.fields() == {"lam": "1.0", "energy": "0.125", "tol": "1e-13",
                                                          "crossings": "50"}
    assert base.seed_starts(seeds) == [(0.1, 0.1)]                       # (0.6, 0.45) is off the level


def test_one_seed_starts_runs_each_seed_kind_on_either_page():
    from explorer.analysis.seeds import seed_points
    from explorer.app.serve.settings import Settings, SystemSettings
    from explorer.io.scene import SeedSpec
    from explorer.io.scene.system import SystemSeeds

    chap, system = Settings(h=1.0), SystemSettings(henon_heiles_map(E))
    p1, p2, _dropped = seed_points(SeedSpec(), chap.params, chap.h, chap.phi0)
    assert chap.seed_starts(None) == list(zip(p1.tolist(), p2.tolist())) and len(p1) > 50   # a scene's default
    window = SystemSeeds(kind="random", n=20, window=(-0.6, 0.6, -0.6, 0.6))
    for page in (chap, system):                       # a System's [seeds] on Chaplygin's map too
        starts = page.seed_starts(window)
        assert 0 < len(starts) <= 20 and page.smap.allowed(np.array(starts)).all()
    c1, c2, r1, r2 = system.region                    # no scene: a grid of about 100 over the region box
    starts = np.array(system.seed_starts(None))
    assert 50 < len(starts) <= 100 and system.smap.allowed(starts).all()
    assert np.all(np.abs(starts - (c1, c2)) <= (r1, r2))
    with pytest.raises(ParameterError, match="no seed point on the section"):
        system.seed_starts(SystemSeeds(kind="points", points=((0.0, 1.0),)))   # (off the level)


def test_a_link_naming_a_system_imports_nothing_and_changes_nothing(monkeypatch):
    from explorer.app.serve.page import SectionPage
    from explorer.app.serve.settings import Settings, SystemSettings

    def refuse(name, *a, **kw):
        raise AssertionError(f"the page imported {name}")

    monkeypatch.setattr(importlib, "import_module", refuse)
    for base in (Settings(crossings=10), SystemSettings(henon_heiles_map(), crossings=10)):
        page = SectionPage(base, {"system": "tests.systems:henon_heiles", "module": "os:system"})
        try:
            assert page.settings == base and "system" not in page.url_query()
        finally:
            page.close()


def test_a_system_page_runs_the_maps_orbits_on_its_energy_level_and_refuses_points_outside():
    from explorer.app.serve import overlays
    from explorer.app.serve.page import SectionPage
    from explorer.app.serve.settings import SystemSettings

    smap = henon_heiles_map()
    page = SectionPage(SystemSettings(smap, crossings=40))
    try:
        assert tuple(page.inputs) == ("lam", "energy", "tol", "crossings") and not page.fields.mu_slider.visible
        assert page.click(0.1, 0.1) is not None
        settle(page)
        d = page.orbits.columns()
        rows = np.column_stack([np.asarray(d[k]) for k in ("t", "p1", "p2", "M", "dH")])
        assert rows.shape == (40, 5) and np.max(np.abs(_energy(rows[:, 1], rows[:, 2], rows[:, 3]) - E)) <= 1e-10
        ref = ex.crossings(smap.with_tol(page.settings.tol), [(0.1, 0.1)], n_crossings=40).data[0]
        np.testing.assert_array_equal(rows[:, 1:4], ref[:, [2, 4, 3]])      # (y, py, px): the map's iterates
        np.testing.assert_array_equal(rows[:, 0], ref[:, 0])                  # (one stream: its clock too)
        assert page.click(0.6, 0.45) is None and "has no solution for px" in page.message.text
        page.inputs["energy"].value = "0.1"                                   # the orbit reruns on E = 0.1
        settle(page)
        d = page.orbits.columns()
        assert page.settings.smap.energy_value == 0.1 and len(d["t"]) == 40
        assert np.max(np.abs(_energy(*(np.asarray(d[k]) for k in ("p1", "p2", "M"))) - 0.1)) <= 1e-10
        points, text = overlays.fixed_points(page.settings)                 # the searches ask the map
        assert any(fp.stable and abs(fp.point[1]) < 1e-9 for fp in points), text
    finally:
        page.close()


def test_a_system_page_with_an_empty_region_says_why_and_still_draws_its_figure():
    from explorer.app.serve.image import render
    from explorer.app.serve.page import SectionPage
    from explorer.app.serve.settings import SystemSettings

    page = SectionPage(SystemSettings(henon_heiles_map().with_value("energy", -0.1)))
    try:
        assert page.settings.region is None and "domain of the section map" in page.message.text
        assert page.click(0.1, 0.1) is None
        view = page.view()
        assert view.region is None and view.region_mask is None
        assert render(view, "png").startswith(b"\x89PNG")
    finally:
        page.close()


def test_explore_in_a_notebook_takes_a_systems_section_map():
    page = ex.explore(henon_heiles_map(), h=0.1, n_crossings=20).page
    try:
        assert page.settings.fields() == {"lam": "1.0", "energy": "0.1", "tol": "1e-13", "crossings": "20"}
        assert page.click(0.1, 0.1) is not None
        settle(page)
        d = page.orbits.columns()
        y, py, px = (np.asarray(d[k]) for k in ("p1", "p2", "M"))
        assert len(y) == 20 and np.max(np.abs(_energy(y, py, px) - 0.1)) <= 1e-10
    finally:
        page.close()
    with pytest.raises(ParameterError, match="mu belongs to Chaplygin"):
        ex.explore(henon_heiles_map(), mu=0.5)


def test_a_parameter_named_as_a_link_key_is_refused_naming_it():
    import sympy as sp

    from explorer.app.serve.settings import SystemSettings

    hh = henon_heiles_map().system
    (lam,), view = hh.parameters, sp.Symbol("view")
    sy = ex.System({s: f.subs(lam, view) for s, f in zip(hh.states, hh.rhs)}, parameters={view: 1.0},
                   energy=hh.energy.subs(lam, view), name="hh_view")
    x, y, px, py = sy.states
    with pytest.raises(ParameterError, match="parameter 'view'"):
        SystemSettings(ex.SectionMap(sy, E, section=x, direction=1, coords=(y, py), solve=px))


@pytest.fixture(scope="module")
def browser(launch_chromium):
    """Chromium (tests/app/browser_session.py)."""
    return launch_chromium()


def test_in_the_browser_a_systems_page_clicks_orbits_on_its_energy_level_and_draws_its_megno_layer(browser):
    """... and, its server stopped (Ctrl-C), the page says the connection is lost (Panel's disconnect
    notification, which the server sets for every page it serves)."""
    from test_serve import SET_BOX, TEXT, Served, _click, _open, _wait, browser_needed

    from explorer.app.serve.server import DISCONNECT_NOTICE

    if browser_needed.args[0]:
        pytest.skip(browser_needed.kwargs["reason"])
    served = Served("--system", "tests.systems:henon_heiles_map", "--crossings", "60", "--megno-resolution", "16",
                    "--megno-time", "50")
    page = None
    try:
        try:
            page = _open(browser, served.url + "?system=os:system")           # a link names no system
            _click(page, 0.1, 0.1)
            d = _wait(page, "() => { const d = Bokeh.documents[0].get_model_by_name('crossings').data;"
                            " return d.p1.length >= 60 && {p1: Array.from(d.p1), p2: Array.from(d.p2),"
                            " M: Array.from(d.M)}; }", 240_000, polling=100)
            y, py, px = (np.array(d[k]) for k in ("p1", "p2", "M"))
            assert len(y) == 60 and np.all(px > 0) and np.max(np.abs(_energy(y, py, px) - E)) <= 1e-10
            assert "henon_heiles: lam = 1, energy = 0.125" in page.evaluate(TEXT, "status")
            _click(page, 0.6, 0.45)                                              # H = 0.209 > E there
            _wait(page, "() => Bokeh.documents[0].get_model_by_name('message').text.includes('has no solution for px')")
            page.evaluate(SET_BOX, ["chaos layer", True])
            r = _wait(page, "() => { const d = Bokeh.documents[0].get_model_by_name('raster').data;"
                            " return d.complete.length && d.complete[0] && [Array.from(d.image[0]), d.x[0], d.y[0],"
                            " d.dw[0], d.dh[0]]; }", 240_000, polling=100)
            values = np.array(r[0], dtype=float).reshape(16, 16)
            u = (np.arange(16) + 0.5) / 16
            A, B = np.meshgrid(r[1] + r[3] * u, r[2] + r[4] * u)
            inside = henon_heiles_map().allowed(np.stack([A, B], axis=-1))
            assert np.isnan(values[~inside]).all() and np.isfinite(values[inside]).all() and inside.sum() > 50
            ref = ex.indicators(henon_heiles_map().with_tol(1e-13), np.column_stack([A[inside], B[inside]]),
                                tmax=50.0, which=("megno",))                   # (the page's tol, its default)
            np.testing.assert_array_equal(values[inside], ref.megno)           # <Y>(T) of each cell's orbit
            assert DISCONNECT_NOTICE not in page.evaluate("() => document.body.innerText")
        finally:
            code, err = served.interrupt()
        assert code in (0, 130) and "Traceback" not in err, err[-2000:]
        _wait(page, f"() => document.body.innerText.includes({DISCONNECT_NOTICE[:40]!r})", 30_000, polling=100)
    finally:
        if page is not None:
            page.close()
