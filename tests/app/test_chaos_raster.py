"""High-resolution chaos maps: a scene of indicators only stores no crossings but its grid
geometry, and is drawn as a raster (forbidden region gray, colour bar) that can be redrawn from
the store; headless pixel checks as the other figure tests."""
import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.image import imread

from explorer.app import runner
from explorer.io import store
from explorer.io.scene import SceneError, load_scene

SCENE = """
name = "map_test"
[model]
a1 = 1.0
a2 = 0.5
b = 2.0
lam = 1.0
mu = 0.03
[energy]
h = 2.0
[compute]
sections = false
lyapunov = true
[lyapunov]
time = 100.0
indicators = ["megno"]
map_resolution = 20
map_indicator = "megno"
[figure]
dpi = 60
"""


@pytest.mark.cpu_dependent
def test_an_indicator_only_map_stores_no_crossings_and_is_drawn_as_a_raster(tmp_path):
    path = tmp_path / "map_test.toml"
    path.write_text(SCENE)
    rep = runner.run_sweep(str(path), out=tmp_path / "m.h5", figure=tmp_path / "m", progress=False)
    assert rep.crossings == 0
    pd = store.read_store(tmp_path / "m.h5").panels[0]
    assert pd.arrays["crossings"].shape[0] == 0
    assert "megno" in pd.extra and "lyapunov_early" not in pd.extra
    assert int(pd.attrs["map_resolution"]) == 20 and len(pd.attrs["map_p1"]) == 2
    # every seed is a cell centre of the raster inside the allowed region
    n = len(pd.extra["megno"])
    assert 0.6 * 400 < n < 400
    img = imread(tmp_path / "m_map.png")
    h, w = img.shape[:2]
    assert w > h                                         # the colour bar is beside the map
    gray = np.all(np.abs(img[..., :3] - 0.8) < 0.02, axis=-1)
    assert gray.mean() > 0.01                            # the forbidden corners
    colourful = (img[..., :3].max(axis=-1) - img[..., :3].min(axis=-1)) > 0.3
    assert colourful.mean() > 0.15                       # the map itself
    # redrawn from the store alone: the same image
    (tmp_path / "m_map.png").unlink()
    runner.draw_figure(load_scene(str(path)), tmp_path / "m.h5", tmp_path / "m")
    np.testing.assert_array_equal(imread(tmp_path / "m_map.png"), img)


def test_an_indicator_only_map_stores_each_indicator_asked_for_and_gali2_beside_sali(tmp_path):
    """The store's side of the map above, with SALI asked for: the panel holds MEGNO, SALI and GALI_2
    (the same two deviation vectors) per cell and no crossings.  Which arrays a sweep stores does not
    depend on the CPU, so this is not marked cpu_dependent: the generic-CPU rerun (tests/generic_cpu.py)
    runs the raster above on the one-vector indicators only."""
    path = tmp_path / "map_sali.toml"
    path.write_text(SCENE.replace('indicators = ["megno"]\nmap_resolution = 20',
                                  'indicators = ["megno", "sali"]\nmap_resolution = 8'))
    rep = runner.run_sweep(str(path), out=tmp_path / "s.h5", progress=False)
    assert rep.crossings == 0
    pd = store.read_store(tmp_path / "s.h5").panels[0]
    assert pd.arrays["crossings"].shape[0] == 0
    assert {"megno", "sali", "gali2"} <= set(pd.extra) and "lyapunov_early" not in pd.extra
    n = len(pd.extra["megno"])
    assert 0 < n < 64 and len(pd.extra["sali"]) == len(pd.extra["gali2"]) == n


@pytest.mark.parametrize("text,key", [
    ('indicators = ["megno", "lyap"]', "lyapunov.indicators[1]"),
    ('indicators = ["megno"]\nmap_resolution = 8\nmap_indicator = "sali"', "lyapunov.map_indicator"),
    ('method = "split6"\nindicators = ["sali"]', "lyapunov.method"),
    ('map_resolution = -1', "lyapunov.map_resolution"),
    ('early_stop = "yes"', "lyapunov.early_stop"),
])
def test_bad_lyapunov_keys_name_the_key(tmp_path, text, key):
    path = tmp_path / "bad.toml"
    path.write_text(SCENE.replace('indicators = ["megno"]\nmap_resolution = 20\nmap_indicator = "megno"', text))
    with pytest.raises(SceneError, match=key.replace("[", r"\[").replace("]", r"\]")):
        load_scene(str(path))


def test_an_orbit_stopped_early_is_drawn_at_the_chaotic_end_and_a_megno_scale_saturates_at_the_stop_level():
    """An early-stopped orbit is chaotic, its <Y> at the stop is not its <Y> at T: it is drawn at the
    scale's dark end (the largest value of the orbits run to T, which ignores it; with the stop's level
    known, a MEGNO scale ends there, so cells filled from stopped ones are dark too)."""
    from explorer.app.chaos_raster import chaos_rasters

    seeds = np.array([[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]])
    m = dict(seeds=seeds, values=np.array([2.0, 30.0, 5.0, 400.0]), grid=(2, 0.0, 1.0, 0.0, 1.0),
             stopped=np.array([False, False, True, True]), label="stopped")
    fig = chaos_rasters([m], indicator="megno")
    im = fig.axes[0].images[0]
    img = np.ma.filled(im.get_array(), np.nan)
    assert im.norm.vmax == 30.0
    assert img[1, 0] == 30.0 and img[1, 1] == 30.0 and img[0, 0] == 2.0
    assert "50.0% stopped early" in " ".join(t.get_text() for t in fig.axes[0].texts)
    # stopped at <Y> > 5 (the scene's early_megno): the scale saturates there, filled cells alike
    im = chaos_rasters([dict(m, stop_level=5.0)], indicator="megno").axes[0].images[0]
    assert im.norm.vmax == 5.0 and np.ma.filled(im.get_array(), np.nan)[1, 1] == 5.0
