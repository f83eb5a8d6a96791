"""Two-parameter atlas (a scene with [atlas]): the chaotic fraction per cell of [sweep] x [atlas],
through the sweep's task map, stored as fractions only and drawn as a heat map."""
import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.image import imread

from explorer.analysis import lyapunov, sweep
from explorer.analysis.lyapunov import chaotic_fraction
from explorer.app import runner
from explorer.io.scene import SceneError, load_scene, parse_scene
from explorer.io.store.atlas import read_atlas

SCENE = """
name = "atlas_test"
[sweep]
parameter = "mu"
values = [0.0, 1.0]
[atlas]
parameter = "h"
values = [2.0, 4.0, 6.0]
[seeds]
n = 24
[compute]
sections = false
lyapunov = true
[lyapunov]
time = 60.0
indicators = ["megno"]
[figure]
dpi = 80
"""


def test_atlas_scene_cells_and_round_trip():
    s = parse_scene(SCENE)
    assert s.is_atlas and s.n_cells == 6 and s.n_panels == 2
    prm, h, label = s.cell(4)                   # row 1 (mu = 1), column 1 (h = 4)
    assert prm.mu == 1.0 and h == 4.0 and label == "mu = 1.0, h = 4.0"
    assert parse_scene(s.to_toml()).atlas_hash() == s.atlas_hash()
    assert parse_scene(SCENE.replace("time = 60.0", "time = 61.0")).atlas_hash() != s.atlas_hash()
    assert load_scene("atlas").n_cells >= 100


@pytest.mark.parametrize("old,new,key", [
    ('parameter = "h"', 'parameter = "mu"', "atlas.parameter"),
    ('parameter = "h"', 'parameter = "nu"', "atlas.parameter"),
    ("values = [2.0, 4.0, 6.0]", "values = [2.0, 2.0]", r"atlas.values\[1\]"),
    ("values = [2.0, 4.0, 6.0]", 'values = ["a"]', r"atlas.values\[0\]"),
    ("sections = false", "sections = true", "compute"),
    ('[sweep]\nparameter = "mu"\nvalues = [0.0, 1.0]\n', "", "sweep.parameter"),
])
def test_bad_atlas_keys_name_the_key(old, new, key):
    with pytest.raises(SceneError, match=key):
        parse_scene(SCENE.replace(old, new, 1))


def test_atlas_cells_are_the_task_map_of_their_indicators():
    s = parse_scene(SCENE)
    spec = sweep.build_atlas_spec(s, chunk_orbits=10)
    assert [p.index for p in spec.panels] == list(range(6)) and not spec.sections
    i = 5
    pos = [p.index for p in spec.panels].index(i)
    parts = [sweep.task(spec, k) for k, c in enumerate(spec.chunks) if c[0] == pos]
    megno = np.concatenate([p["megno"] for p in parts])
    prm, h, _ = s.cell(i)
    ind = lyapunov.indicators(prm, states=spec.panels[pos].y0, tmax=60.0, tol=s.lyapunov.tol, which=("megno",))
    np.testing.assert_array_equal(megno, ind.megno)


@pytest.mark.cpu_dependent
def test_run_atlas_stores_fractions_only_and_draws_a_heat_map(tmp_path):
    path = tmp_path / "a.toml"
    path.write_text(SCENE)
    rep = runner.run_sweep(str(path), out=tmp_path / "a.h5", figure=tmp_path / "a", progress=False)
    assert rep.n_panels == 6 and len(rep.computed) == 6 and rep.crossings == 0
    a = read_atlas(tmp_path / "a.h5")
    assert a.fraction.shape == (2, 3) and a.row_parameter == "mu" and a.column_parameter == "h"
    assert np.all(a.orbits > 15)
    assert np.all(a.fraction[0] < 0.1) and a.fraction[1].max() > 0.5     # integrable at mu = 0
    # the fraction of a cell is the one of its seeds' MEGNO
    s = load_scene(str(path))
    spec = sweep.build_atlas_spec(s, chunk_orbits=0)
    prm, h, _ = s.cell(4)
    m = lyapunov.indicators(prm, states=spec.panels[4].y0, tmax=60.0, tol=s.lyapunov.tol, which=("megno",)).megno
    assert a.fraction[1, 1] == chaotic_fraction(m, 4.0)[0]
    img = imread(tmp_path / "a.png")
    assert img.shape[1] > img.shape[0]
    colourful = (img[..., :3].max(axis=-1) - img[..., :3].min(axis=-1)) > 0.3
    assert colourful.mean() > 0.05                                       # the chaotic cells and the colour bar
    # a second run recomputes nothing
    rep2 = runner.run_sweep(str(path), out=tmp_path / "a.h5", figure=tmp_path / "a", progress=False)
    assert rep2.computed == ()


def test_an_atlas_of_maps_is_adaptive_by_default_and_exact_on_request(tmp_path, monkeypatch):
    """With [lyapunov] map_resolution each cell's fraction is that of its map's cells: adaptive
    (the fraction of map cells computed stored per cell and named in the title) unless exact.  At
    16 x 16 cells from a lattice of 4 a side islands smaller than the lattice are filled as the
    sea around them: the fractions agree within 6 points here (docs/scenes.md, "Adaptive maps")."""
    monkeypatch.setattr(sweep, "MAP_COARSE", 4)
    text = SCENE.replace('indicators = ["megno"]', 'indicators = ["megno"]\nmap_resolution = 16')
    stored = {}
    for key, scene in (("adaptive", text), ("exact", text.replace("map_resolution", "exact = true\nmap_resolution"))):
        path = tmp_path / f"{key}.toml"
        path.write_text(scene)
        runner.run_sweep(str(path), out=tmp_path / f"{key}.h5", draw=False, progress=False)
        stored[key] = read_atlas(tmp_path / f"{key}.h5")
    a, e = stored["adaptive"], stored["exact"]
    assert a.hash != e.hash and e.computed is None
    assert np.all((a.computed > 0) & (a.computed <= 1)) and np.any(a.computed < 0.5)
    np.testing.assert_array_equal(a.orbits, e.orbits)                # every allowed map cell counted
    assert np.all(np.abs(a.fraction - e.fraction) <= 0.06) and np.all(e.fraction[1] > 0.5)
    assert "of map cells computed, adaptive" in runner.atlas_seeding(parse_scene(text), a)


def test_the_atlas_title_counts_the_seeds_a_points_scene_gives_each_cell():
    text = ('name = "s"\n[sweep]\nparameter = "mu"\nvalues = [0.1, 0.2]\n'
            '[atlas]\nparameter = "h"\nvalues = [2.0, 3.0]\n'
            '[seeds]\nkind = "points"\npoints = [[0.1, 0.0], [0.2, 0.0], [0.3, 0.0]]\n'
            '[compute]\nsections = false\nlyapunov = true\n')
    assert runner.atlas_seeding(parse_scene(text), None) == "3 seeds per cell"
    assert runner.atlas_seeding(parse_scene(text.replace('kind = "points"', 'kind = "grid"\nn = 50')), None) \
        == "50 seeds per cell"


def test_an_atlas_of_fli_maps_classifies_each_cell_by_fli_and_says_so(tmp_path, monkeypatch):
    """docs/scenes.md, "Two-parameter atlas": with map_indicator = "fli" each cell's adaptive map is
    refined and classified by FLI at 2 ln T; the file names the indicator and threshold, the heat map's
    colour bar says FLI, and the atlas hash differs from the MEGNO map atlas's."""
    import math

    from explorer.app.atlas_figure import atlas_heatmap

    monkeypatch.setattr(sweep, "MAP_COARSE", 4)
    megno = SCENE.replace("values = [0.0, 1.0]", "values = [1.0]").replace("values = [2.0, 4.0, 6.0]",
                                                                          "values = [2.0, 4.0]")
    megno = megno.replace('indicators = ["megno"]', 'indicators = ["megno", "fli"]\nmap_resolution = 16')
    text = megno.replace("map_resolution = 16", 'map_resolution = 16\nmap_indicator = "fli"')
    path = tmp_path / "fli.toml"
    path.write_text(text)
    runner.run_sweep(str(path), out=tmp_path / "fli.h5", draw=False, progress=False)
    a = read_atlas(tmp_path / "fli.h5")
    thr = 2 * math.log(60.0)
    assert a.indicator == "fli" and a.threshold == thr and np.all(a.computed < 1)
    scene = parse_scene(text)
    spec = sweep.build_atlas_spec(scene, chunk_orbits=0)
    for pos, panel in enumerate(spec.panels):
        arrays = sweep.task(spec, [k for k, c in enumerate(spec.chunks) if c[0] == pos][0])
        assert a.fraction.flat[panel.index] == sweep.panel_fraction(arrays, "fli", thr)[0]
    fig = atlas_heatmap(a)
    assert f"FLI > {thr:.3g}" in fig.axes[1].get_ylabel()
    assert scene.atlas_hash() != parse_scene(megno).atlas_hash()
