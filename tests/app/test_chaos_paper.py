"""The paper figures of the chaotic-fraction curve against mu (preset fraction_curve) and the
MEGNO raster map (preset megno_map), headless, on reduced settings (figures --quick) and redrawn
from a complete stored panel; the quick fraction curve, atlas and MEGNO map are checked in
tests/app/test_paper.py, on the figures its whole --quick run draws.  Their bounds on the chaotic
fractions (below 0.05 or 0.2 where the flow is integrable, above 0.5 or 0.8 where it is chaotic,
between 0.05 and 0.95 at mu = 0.03) leave room far beyond the few orbits a last-bit change can
reclassify, so they are not marked cpu_dependent (not rerun for the generic CPU,
tests/generic_cpu.py)."""
import matplotlib

matplotlib.use("Agg")

import numpy as np
from matplotlib.image import imread

from explorer.app import paper
from explorer.io import scene as sc


def test_fraction_curve_preset_has_41_values_and_1600_seeds_each():
    s = sc.load_scene("fraction_curve")
    v = np.array(s.sweep_values)
    assert len(v) == 41 and v[0] == 0.0 and v[1] == 1e-3 and v[-1] == 10.0
    r = v[2:] / v[1:-1]
    assert np.allclose(r, r.mean(), rtol=2e-3)                     # log-spaced
    assert s.lyapunov.early_stop and "sections" not in s.compute
    assert min(len(s.panel_seeds(i)[0]) for i in (0, 20, 40)) >= 1600


def _check_raster_png(path):
    img = imread(path)
    h, w = img.shape[:2]
    assert w > h                                                   # the colour bar beside the map
    gray = np.all(np.abs(img[..., :3] - 0.8) < 0.02, axis=-1)
    assert gray.mean() > 0.01                                      # the forbidden corners
    colourful = (img[..., :3].max(axis=-1) - img[..., :3].min(axis=-1)) > 0.3
    assert colourful.mean() > 0.1                                  # the map itself
    return img


def test_megno_map_is_redrawn_from_a_complete_stored_panel(monkeypatch, tmp_path):
    small = sc.PRESETS["megno_map"].replace("map_resolution = 512", "map_resolution = 24").replace(
        "time = 1000.0", "time = 50.0").replace("separatrices = true", "separatrices = false").replace(
        "dpi = 300", "dpi = 80")
    monkeypatch.setitem(sc.PRESETS, "megno_map", small)
    scene, path, reduced, summary = paper.ensure_sweep("megno_map", results_dir=tmp_path, quick=False)
    assert not reduced and "(1 computed" in summary
    o = paper.make("megno_map", out_dir=tmp_path / "figs", results_dir=tmp_path, quick=True)
    assert not o.data["reduced"] and o.data["resolution"] == 24 and o.data["store"].endswith("megno_map.h5")
    img = _check_raster_png(tmp_path / "figs" / "megno_map.png")
    o2 = paper.make("megno_map", out_dir=tmp_path / "figs2", results_dir=tmp_path, quick=False)
    assert o2.data["orbits"] == o.data["orbits"]
    np.testing.assert_array_equal(imread(tmp_path / "figs2" / "megno_map.png"), img)
