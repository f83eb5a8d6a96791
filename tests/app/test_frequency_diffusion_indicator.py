"""Frequency diffusion as an indicator of the registry (row ORBIT, docs/greene.md "Frequency
diffusion"): a sweep or a chaos map that asks for it stores, per seed, exactly the values of
``explorer.frequency_diffusion`` on the panel's section map around [lyapunov] center; a scene that
does not ask for it neither computes nor stores it."""
import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.image import imread

import explorer as ex
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
