"""`explorer sweep --system module:attribute`: a System's scene swept through the CLI, its panels
in the store equal to explorer.crossings of the section map at each swept value (docs/scenes.md,
"A scene of your own system")."""
import textwrap

import numpy as np
import pytest

import explorer as ex
from explorer.app import cli
from explorer.io import store
from explorer.io.scene import load_scene

MODULE = "h4_sweep_systems"
SOURCE = '''
import sympy as sp
import explorer as ex

x, y, px, py, lam = sp.symbols("x y px py lam")
hh = ex.System({x: px, y: py, px: -x - 2*lam*x*y, py: -y - lam*(x**2 - y**2)}, parameters={lam: 1.0},
               energy=(px**2 + py**2)/2 + (x**2 + y**2)/2 + lam*(x**2*y - y**3/3), name="henon_heiles")
'''
POINTS = [[0.1, 0.1], [-0.1, 0.2], [0.3, 0.0]]
CROSSINGS = 40
LAMS = (0.5, 1.0)
E = 0.125
SCENE = textwrap.dedent(f"""\
    name = "hh_sweep"
    section = "x"
    direction = 1
    coords = ["y", "py"]
    solve = "px"
    [energy]
    value = {E}
    [sweep]
    parameter = "lam"
    values = [{LAMS[0]}, {LAMS[1]}]
    [seeds]
    kind = "points"
    points = {POINTS}
    [integration]
    crossings = {CROSSINGS}
    tol = 1e-13
    """)


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    (tmp_path / f"{MODULE}.py").write_text(SOURCE)
    (tmp_path / "hh.toml").write_text(SCENE)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    return tmp_path


def run(args, capsys):
    code = cli.main(args)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def swept(workdir, capsys):
    code, out, err = run(["sweep", "hh.toml", "--system", f"{MODULE}:hh", "--out", "res/hh.h5", "--quiet"], capsys)
    assert code == 0, err
    return workdir, out


def test_swept_panels_equal_the_crossings_of_the_section_map_at_each_value_and_conserve_the_energy(swept):
    workdir, out = swept
    assert "2 panels (2 computed" in out
    data = store.read_store(workdir / "res" / "hh.h5")
    assert sorted(data.panels) == [0, 1]
    hh = load_scene(workdir / "hh.toml", system=f"{MODULE}:hh").system
    x, y, px, py = hh.states
    for i, lam in enumerate(LAMS):
        pd = data.panels[i]
        assert pd.settings["map"]["columns"] == ["t", "y", "py", "px", "dE"]
        smap = ex.SectionMap(hh.with_(lam=lam), E, section=x, direction=+1, coords=(y, py), solve=px)
        ref = ex.crossings(smap, POINTS, n_crossings=CROSSINGS, tol=1e-13)
        assert np.all(ref.count == CROSSINGS) and np.all(pd.count == CROSSINGS)
        rows = np.concatenate([pd.orbit(k) for k in range(len(POINTS))])
        np.testing.assert_array_equal(rows, ref.data[..., [0, 2, 4, 3, 5]].reshape(-1, 5))
        np.testing.assert_array_equal(pd.y0, smap.states(POINTS))
        assert np.max(np.abs(rows[:, 4])) < 1e-12        # E - E0 at every crossing
        assert np.all(rows[:, 0] > 0) and np.all(rows[:, 3] > 0)    # t > 0; px > 0 crossing x = 0 upwards
    assert (workdir / "res" / "hh.png").exists()


def test_a_rerun_finds_every_panel_stored(swept, capsys):
    workdir, _ = swept
    code, out, err = run(["sweep", "hh.toml", "--system", f"{MODULE}:hh", "--out", "res/hh.h5", "--quiet"], capsys)
    assert code == 0, err
    assert "2 panels (0 computed, 2 already stored)" in out


@pytest.mark.parametrize("value", ["nocolon", "h4_not_a_module:hh", f"{MODULE}:nothing"])
def test_a_bad_system_name_exits_2_with_one_line(workdir, capsys, value):
    code, out, err = run(["sweep", "hh.toml", "--system", value, "--out", "res/x.h5", "--quiet"], capsys)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("explorer: error: --system") and value in lines[0]
    assert "Traceback" not in err


def test_a_system_scene_without_a_system_exits_2_naming_the_key(workdir, capsys):
    code, _, err = run(["sweep", "hh.toml", "--out", "res/x.h5", "--quiet"], capsys)
    assert code == 2 and "scene key 'system'" in err and len(err.strip().splitlines()) == 1
