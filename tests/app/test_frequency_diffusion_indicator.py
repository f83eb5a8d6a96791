"""Frequency diffusion as an indicator of the registry (row ORBIT, docs/greene.md "Frequency
diffusion"): a sweep or a chaos map that asks for it stores, per seed, exactly the values of
``explorer.frequency_diffusion`` on the panel's section map around [lyapunov] center; a scene that
does not ask for it neither computes nor stores it.  The browser's chaos layer (``explorer serve``,
in process: no browser) set to it shows exactly the function's values around the page's elliptic
point, and the choice of indicator changes the layer's values, scale, label and link."""
import matplotlib
from page_loop import poll

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.image import imread

import explorer as ex
from explorer import model
from explorer.analysis import sweep
from explorer.app import runner
from explorer.io import store
from explorer.io.scene import load_scene, parse_scene

#: Figure 4's model at mu = 0.1; the centre near the right island's elliptic point (1.571, 0)
CENTER = (1.571, 0.0)
#: N of the indicator: 2N = 20 returns per orbit keeps the tests to seconds
ITERATES = 10

MAP_SCENE = f"""
name = "fd_map"
[model]                          # Figure 4's model and energy but mu
mu = 0.1
[compute]
sections = false
lyapunov = true
[lyapunov]
time = 20.0
indicators = ["megno", "frequency_diffusion"]
center = [{CENTER[0]}, {CENTER[1]}]
diffusion_iterates = {ITERATES}
map_resolution = 2
map_indicator = "frequency_diffusion"
[figure]
dpi = 50
"""


def _direct(params, h, seeds, tol):
    sm = ex.SectionMap(params, h, tol=tol)
    return ex.frequency_diffusion(sm, seeds, center=CENTER, iterates=ITERATES)


@pytest.mark.cpu_dependent
def test_a_chaos_map_of_frequency_diffusion_stores_the_values_of_the_function_and_is_drawn(tmp_path):
    path = tmp_path / "fd_map.toml"
    path.write_text(MAP_SCENE)
    runner.run_sweep(str(path), out=tmp_path / "m.h5", figure=tmp_path / "m", progress=False)
    scene = load_scene(str(path))
    pd = store.read_store(tmp_path / "m.h5").panels[0]
    fd = pd.extra["frequency_diffusion"]
    assert fd.dtype == np.float64 and fd.shape == (len(pd.seeds),) and len(fd) == 4
    prm, h, _ = scene.panel(0)
    want = _direct(prm, h, pd.seeds, scene.lyapunov.tol)
    np.testing.assert_array_equal(fd, want)           # the same numbers, through the store
    assert np.isfinite(fd).mean() > 0.5 and np.all(fd[np.isfinite(fd)] <= 1.0)
    img = imread(tmp_path / "m_map.png")             # drawn with the indicator's own colour scale
    colourful = (img[..., :3].max(axis=-1) - img[..., :3].min(axis=-1)) > 0.3
    assert colourful.mean() > 0.05


def test_a_sweep_computes_frequency_diffusion_only_when_asked_and_as_the_function_does():
    base = MAP_SCENE.replace("map_resolution = 2\nmap_indicator = \"frequency_diffusion\"\n", "").replace(
        "mu = 0.1", "mu = 0.1\n[sweep]\nparameter = 'mu'\nvalues = [0.1, 0.2]\n[seeds]\nkind = 'points'\n"
        "points = [[1.6, 0.0], [-0.3, 0.2]]\n")
    asked = parse_scene(base)
    spec = sweep.build_spec(asked, [0, 1], chunk_orbits=1, product="indicators")   # one orbit a chunk
    want = {pos: _direct(ex.Params.from_array(p.P), p.h, p.seeds, asked.lyapunov.tol)   # all orbits at once
            for pos, p in enumerate(spec.panels)}
    for i in range(len(spec.chunks)):
        pos, a, b = spec.chunks[i]
        out = sweep.task(spec, i, threads=1)
        np.testing.assert_array_equal(out["frequency_diffusion"], want[pos][a:b])
        assert np.isfinite(out["megno"]).all()
    not_asked = parse_scene(base.replace('"megno", "frequency_diffusion"', '"megno"'))
    spec = sweep.build_spec(not_asked, [0], chunk_orbits=0, product="indicators")
    assert "frequency_diffusion" not in sweep.task(spec, 0)


# ---------------------------------------------------------------- the browser's chaos layer, in process
#: the chaos layer's raster in these tests: 8 x 8 cells (two batches of frequency diffusion's)
LAYER_N = 8


#: the longest a page's computation may take here (s): a bound on a hang, not a speed; long, as
#: the generic-CPU rerun runs these tests at the lowest priority beside the suite (tests/generic_cpu.py)
POLL_TIMEOUT = 1800.0


def _poll_until(page, cond, timeout=POLL_TIMEOUT):
    import time

    t0 = time.time()
    while not cond() and time.time() - t0 < timeout:
        poll(page)
        time.sleep(0.02)
    assert cond(), page.message.text


def _layer_page(args):
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage
    from explorer.app.serve.settings import Settings

    # the link's layer box after the small raster is set (the page's own load_url, again: the box on)
    page = SectionPage(Settings(params=model.FIGURE4.with_(mu=0.1)), {k: v for k, v in args.items() if k != "megno"})
    page.chaos.resolutions, page.chaos.iterates = (LAYER_N,), ITERATES
    page.chaos.load_url(args)
    return page


def _complete(page):
    d = page.chaos.raster_source.data
    return bool(d["n"]) and d["complete"][0] and d["n"][0] == LAYER_N


def _inside_seeds(page):
    """The cells of the layer's raster inside the allowed region: (mask (n, n), their centres (k, 2))."""
    s = page.settings
    P1, P2 = page.section.window.centres(LAYER_N)
    inside = model.section_M2(s.params, P1, P2, s.h, s.phi0) > 0.0
    return inside, np.column_stack([P1[inside], P2[inside]])


def test_the_browsers_frequency_diffusion_layer_shows_the_functions_values_around_the_pages_elliptic_point():
    """The page's chaos layer set to frequency diffusion (as a link sets it, off the event loop
    through the layer's task): every cell inside the region holds exactly the value of
    ``explorer.frequency_diffusion`` for the cell's centre on the page's section map, around the
    elliptic fixed point of the page's settings, which the colour bar names; the link keeps the
    choice."""
    page = _layer_page({})
    try:
        page.chaos.indicator.value = "frequency_diffusion"
        page.chaos.layer.value = True
        _poll_until(page, lambda: _complete(page))
        settings, point, elliptic = page.chaos.center
        assert settings == page.settings and elliptic
        sm = ex.SectionMap(page.settings.params, page.settings.h, phi0=page.settings.phi0, tol=page.settings.tol)
        np.testing.assert_allclose(sm.iterate(point, 1)[-1], point, atol=1e-9)  # a fixed point of the map ...
        assert abs(np.trace(sm.jacobian(point))) < 2.0                          # ... and elliptic
        inside, seeds = _inside_seeds(page)
        want = ex.frequency_diffusion(sm, seeds, center=point, iterates=ITERATES)
        got = np.asarray(page.chaos.raster_source.data["image"][0])
        assert len(seeds) > 32                                                  # more than one batch
        np.testing.assert_array_equal(got[inside], want)                        # bit for bit
        assert np.isnan(got[~inside]).all() and np.isfinite(got[inside]).mean() > 0.8
        title = page.chaos.colour_bar.title
        assert "ν1 − ν2" in title and f"{point[0]:.4g}" in title and "elliptic" in title
        q = page.url_query()
        assert q["indicator"] == "frequency_diffusion" and q["megno"] == "1"
        again = _layer_page(q)                                   # the link reopens the same layer
        try:
            assert again.chaos.indicator.value == "frequency_diffusion" and again.chaos.layer.value
        finally:
            again.close()
    finally:
        page.close()


@pytest.mark.cpu_dependent
def test_choosing_the_chaos_layers_indicator_changes_its_values_scale_and_label():
    from explorer.app.serve import raster
    from explorer.app.serve.style import MEGNO_HIGH, MEGNO_LOW

    page = _layer_page({"megno": "1"})
    try:
        _poll_until(page, lambda: _complete(page))
        megno = np.asarray(page.chaos.raster_source.data["image"][0])
        ref = list(raster.rasters(page.settings, page.section.window, resolutions=(LAYER_N,)))[-1]
        np.testing.assert_array_equal(megno, ref.values)
        assert page.chaos.colour_bar.title.startswith("⟨Y⟩") and (page.chaos.mapper.low, page.chaos.mapper.high) == (
            MEGNO_LOW, MEGNO_HIGH)
        assert page.url_query()["indicator"] == "megno"
        assert page.overlays_on()[-1] == "megno"
        page.chaos.indicator.value = "frequency_diffusion"               # the choice: a new raster
        assert page.chaos.raster_source.data["n"] == []                       # (MEGNO's values gone at once)
        _poll_until(page, lambda: _complete(page) and page.chaos.center is not None)
        fd = np.asarray(page.chaos.raster_source.data["image"][0])
        inside = np.isfinite(megno)
        assert np.isfinite(fd[inside]).mean() > 0.8 and np.nanmax(fd) <= 0.5      # log10 |nu1 - nu2|, not <Y>
        # the same orbits, another indicator: the cells MEGNO calls regular drift less in frequency
        regular, chaotic = inside & (megno < 3.0), inside & (megno > 8.0)
        assert regular.sum() >= 3 and chaotic.sum() >= 10
        assert np.nanmedian(fd[regular]) < np.nanmedian(fd[chaotic]) - 1.0
        assert "ν1 − ν2" in page.chaos.colour_bar.title and page.chaos.mapper.low < -10
        assert page.url_query()["indicator"] == "frequency_diffusion"
        assert page.overlays_on()[-1] == "frequency_diffusion"           # the exported scene says which
        page.chaos.indicator.value = "megno"                             # and back
        _poll_until(page, lambda: _complete(page) and np.array_equal(page.chaos.raster_source.data["image"][0], megno,
                                                                     equal_nan=True))
    finally:
        page.close()
    bad = _layer_page({"indicator": "lyapunov"})                         # a link's unknown indicator
    try:
        assert "applies): indicator must be one of" in bad.message.text and bad.chaos.indicator.value == "megno"
    finally:
        bad.close()
