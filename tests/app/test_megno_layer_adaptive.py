"""The page's MEGNO layer refines its finest raster by docs/chaos_map.md's rule (raster.rasters, adaptive;
docs/commands/serve.md, "Chaos layer"): its computed cells are the exact raster's bit for bit, the
filled ones agree in class, a coarse raster is shown first, and the link's ``megno=exact`` computes
every cell.  In process, no browser."""
import numpy as np
import pytest
from page_loop import settle

from explorer import model
from explorer.app.serve import raster
from explorer.app.serve.settings import Settings, Window

N = 64
T = raster.RASTER_TIME
RESOLUTIONS = (16, N)


@pytest.fixture(scope="module")
def window_settings():
    s = Settings(params=model.FIGURE4.with_(mu=0.03), tol=1e-10)
    c1, c2, r1, r2 = s.region
    return s, Window(c1 - r1, c1 + r1, c2 - r2, c2 + r2)


@pytest.fixture(scope="module")
def adaptive(window_settings):
    return list(raster.rasters(*window_settings, resolutions=RESOLUTIONS, time=T, adaptive=True))


@pytest.fixture(scope="module")
def exact(window_settings):
    return list(raster.rasters(*window_settings, resolutions=(N,), time=T))[-1]


def test_computed_cells_are_the_exact_rasters_bit_for_bit_and_the_filled_agree_in_class(adaptive, exact):
    final = adaptive[-1]
    inside = np.isfinite(exact.values)
    computed = final.computed
    assert final.complete and final.n == N and 0 < computed.sum() < 0.9 * inside.sum()
    assert not computed[~inside].any() and np.isnan(final.values[~inside]).all()
    np.testing.assert_array_equal(final.values[computed], exact.values[computed])
    filled = inside & ~computed
    assert np.isfinite(final.values[filled]).all()
    chaotic, chaotic_exact = final.values[inside] > 4.0, exact.values[inside] > 4.0
    assert 0.2 < chaotic_exact.mean() < 0.8              # both classes on the map: agreement means something
    assert np.mean(chaotic == chaotic_exact) >= 0.97
    assert abs(chaotic.mean() - chaotic_exact.mean()) <= 0.02


def test_the_coarse_raster_comes_first_and_partial_images_keep_computed_values_and_no_hole(adaptive, window_settings):
    coarse = [im for im in adaptive if im.n == RESOLUTIONS[0]]
    assert coarse[-1].complete and not any(im.complete for im in adaptive[len(coarse):-1])
    ref = list(raster.rasters(*window_settings, resolutions=RESOLUTIONS[:1], time=T))[-1]
    np.testing.assert_array_equal(coarse[-1].values, ref.values)           # the exact coarse raster
    final = adaptive[-1]
    k = N // RESOLUTIONS[0]
    shown = np.kron(ref.values, np.ones((k, k)))
    for im in adaptive[len(coarse):]:
        assert im.n == N and (im.computed <= final.computed).all()           # a computed cell stays computed
        np.testing.assert_array_equal(im.values[im.computed], final.values[im.computed])
        assert np.isfinite(im.values[np.isfinite(final.values) & np.isfinite(shown)]).all()   # never a hole


def test_a_link_with_megno_exact_computes_every_cell_and_keeps_it_in_the_link():
    pytest.importorskip("panel", reason="panel is not installed (pip install panel)")
    from explorer.app.serve.page import SectionPage

    n, t = 32, 50.0
    page = SectionPage(Settings(params=model.FIGURE4.with_(mu=0.03), tol=1e-10))
    try:
        page.chaos.resolutions, page.chaos.time = (16, n), t
        page.chaos.load_url({"megno": "exact"})
        assert page.url_query()["megno"] == "exact" and page.chaos.layer.value and page.chaos.exact
        settle(page)
        d = page.chaos.raster_source.data
        assert d["n"] == [n] and d["complete"] == [True]
        exact = list(raster.rasters(page.settings, page.section.window, resolutions=(n,), time=t))[-1]
        np.testing.assert_array_equal(d["image"][0], exact.values)
        adaptive = list(raster.rasters(page.settings, page.section.window, (16, n), t, adaptive=True))[-1]
        assert (np.isfinite(exact.values) & ~adaptive.computed).any()      # (which the exact link computed)
        page.chaos.load_url({"megno": "1"})
        assert page.url_query()["megno"] == "1" and not page.chaos.exact
    finally:
        page.close()
