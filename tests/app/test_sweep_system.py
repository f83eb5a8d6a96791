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
    code, out, err = run(["sweep", "hh.toml", "--system", f"{MODULE}:hh", "--out", "res/hh.h5", "--quiet",
                          "--no-figure"], capsys)   # (a System's figures: the notebook walk-through below)
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
        ref = ex.crossings(smap.with_tol(1e-13), POINTS, n_crossings=CROSSINGS)
        assert np.all(ref.count == CROSSINGS) and np.all(pd.count == CROSSINGS)
        rows = np.concatenate([pd.orbit(k) for k in range(len(POINTS))])
        np.testing.assert_array_equal(rows, ref.data[..., [0, 2, 4, 3, 5]].reshape(-1, 5))
        np.testing.assert_array_equal(pd.y0, smap.states(POINTS))
        assert np.max(np.abs(rows[:, 4])) < 1e-12        # E - E0 at every crossing
        assert np.all(rows[:, 0] > 0) and np.all(rows[:, 3] > 0)    # t > 0; px > 0 crossing x = 0 upwards


def test_a_rerun_finds_every_panel_stored(swept, capsys):
    workdir, _ = swept
    code, out, err = run(["sweep", "hh.toml", "--system", f"{MODULE}:hh", "--out", "res/hh.h5", "--quiet",
                          "--no-figure"], capsys)
    assert code == 0, err
    assert "2 panels (0 computed, 2 already stored)" in out


@pytest.mark.slow
def test_two_worker_processes_store_the_same_panels(swept, capsys):
    """The System's panels travel to joblib workers (pickled with the System) and come back the same."""
    workdir, _ = swept
    code, _, err = run(["sweep", "hh.toml", "--system", f"{MODULE}:hh", "--out", "res/j2.h5", "--quiet", "--jobs", "2",
                        "--no-figure"], capsys)
    assert code == 0, err
    one, two = (store.read_store(workdir / "res" / name) for name in ("hh.h5", "j2.h5"))
    for i in (0, 1):
        for k in ("seeds", "y0", "count", "status", "final", "info", "offsets", "crossings"):
            np.testing.assert_array_equal(getattr(one.panels[i], k), getattr(two.panels[i], k), err_msg=k)


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


MAP_SCENE = textwrap.dedent(f"""\
    name = "hh_map"
    system = "{MODULE}:hh"
    section = "x"
    coords = ["y", "py"]
    solve = "px"
    [energy]
    value = {E}
    [seeds]
    kind = "grid"
    n = 4
    window = [-0.45, 0.65, -0.52, 0.52]
    [compute]
    sections = false
    lyapunov = true
    [lyapunov]
    time = 40.0
    tol = 1e-12
    map_resolution = 6
    indicators = ["fli"]
    map_indicator = "fli"
    """)


def test_a_chaos_map_stores_the_indicators_of_the_raster_cells_on_the_energy_surface_and_draws_them(workdir, capsys):
    (workdir / "map.toml").write_text(MAP_SCENE)
    code, out, err = run(["sweep", "map.toml", "--out", "res/map.h5", "--quiet"], capsys)
    assert code == 0, err
    pd = store.read_store(workdir / "res" / "map.h5").panels[0]
    scene = load_scene(workdir / "map.toml")
    smap = scene.section_map(0)
    cells = (np.arange(6) + 0.5) / 6
    A, B = np.meshgrid(-0.45 + 1.1 * cells, -0.52 + 1.04 * cells)
    on_surface = [p for p in zip(A.ravel(), B.ravel()) if 0.5 * p[1] ** 2 + 0.5 * p[0] ** 2 - p[0] ** 3 / 3 < E]
    np.testing.assert_allclose(pd.seeds, np.array(on_surface), rtol=0, atol=1e-15)   # the cells with H(0, y, 0, py) < E
    ref = ex.indicators(smap.with_tol(1e-12), pd.seeds, tmax=40.0, which=("megno", "fli"))
    np.testing.assert_array_equal(pd.extra["megno"], ref.values["megno"])
    np.testing.assert_array_equal(pd.extra["fli"], ref.values["fli"])
    assert pd.attrs["map_resolution"] == 6 and np.all(pd.extra["lyapunov_status"] == 0)
    assert (workdir / "res" / "map_map.png").exists()


def test_a_systems_chaos_raster_names_its_axes_by_the_coords_and_draws_no_ellipse():
    from explorer.app.chaos_raster import chaos_rasters

    grid = (2, -1.0, 1.0, -1.0, 1.0)
    m = {"seeds": np.array([[-0.5, -0.5], [0.5, 0.5]]), "values": np.array([2.0, 8.0]), "grid": grid,
         "params": None, "h": E, "axes": ("y", "py"), "label": "lam = 1.0"}
    ax = chaos_rasters([m]).axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("$y$", "$p_{y}$") and not ax.patches


def test_the_notebook_walk_through_sweeps_a_system_object_and_draws_its_megno_map(tmp_path):
    """docs/systems.md's walk-through: a System defined in Python (no module), the scene's system
    replaced by it, sections and a MEGNO map over two values of lam, every figure drawn."""
    import sympy as sp

    x, y, px, py, lam = sp.symbols("x y px py lam")
    hh = ex.System({x: px, y: py, px: -x - 2*lam*x*y, py: -y - lam*(x**2 - y**2)}, parameters={lam: 1.0},
                   energy=(px**2 + py**2)/2 + (x**2 + y**2)/2 + lam*(x**2*y - y**3/3), name="henon_heiles")
    text = SCENE.replace("[integration]", "[compute]\nlyapunov = true\n[lyapunov]\ntime = 20.0\nmap_resolution = 4\n"
                         "[integration]")
    text = text.replace('kind = "points"', 'kind = "points"\nwindow = [-0.45, 0.65, -0.52, 0.52]')
    (tmp_path / "hh.toml").write_text('system = "not_imported:hh"\n' + text)
    scene = ex.load_scene(tmp_path / "hh.toml", system=hh)
    assert scene.system is hh
    report = ex.run_sweep(scene, tmp_path / "hh.h5", figure=tmp_path / "hh", progress=False)
    assert report.computed == (0, 1) and len(report.fractions) == 2 and report.max_dh < 1e-12
    assert {p.name for p in report.figure} >= {"hh.png", "hh_map.png", "hh_fraction.png"}
    data = ex.read_store(tmp_path / "hh.h5")
    assert all(len(data.panels[i].extra["lyapunov_seeds"]) == len(data.panels[i].extra["megno"]) for i in (0, 1))


ADAPTIVE_SCENE = textwrap.dedent(f"""\
    name = "hh_adaptive"
    section = "x"
    coords = ["y", "py"]
    solve = "px"
    [energy]
    value = {E}
    [seeds]
    window = [-0.45, 0.65, -0.52, 0.52]
    [compute]
    sections = false
    lyapunov = true
    [lyapunov]
    time = 100.0
    map_resolution = 32
    """)


@pytest.mark.parametrize("indicator", ["megno", "fli"])
def test_a_systems_megno_map_is_adaptive_its_computed_cells_the_exact_maps_bit_for_bit_its_mask_stored(tmp_path,
                                                                                                     monkeypatch,
                                                                                                     indicator):
    """docs/scenes.md, "Adaptive maps", for a System, of MEGNO and of FLI: the stored map's computed
    cells (``map_computed``) are the exact panel's same cells bit for bit, the others filled (the map's
    indicator only), cells off the energy surface left out, the cells classified by the map's own
    indicator (``class_indicator``) mostly as the exact map's, and the summary counts the cells computed."""
    from systems import henon_heiles

    from explorer.analysis import sweep
    from explorer.app.runner import format_report
    from explorer.io.scene import parse_scene

    monkeypatch.setattr(sweep, "MAP_COARSE", 8)         # a 32-cell map from a lattice of 8 a side
    text = ADAPTIVE_SCENE + f'indicators = ["megno", "fli"]\nmap_indicator = "{indicator}"\n'
    exact = sweep.build_spec(parse_scene(text + "exact = true\n", system=henon_heiles()), [0], chunk_orbits=0)
    got: dict = {}
    sweep.run(exact, lambda panel, arrays: got.update(arrays))
    assert "map_computed" not in got
    scene = parse_scene(text, system=henon_heiles())
    report = ex.run_sweep(scene, tmp_path / "a.h5", progress=False)
    pd = store.read_store(tmp_path / "a.h5").panels[0]
    np.testing.assert_array_equal(pd.seeds, exact.panels[0].seeds)          # the cells on the energy surface
    done = pd.extra["map_computed"]
    assert 0.2 < done.mean() < 0.9                                          # many cells were filled
    for k in ("megno", "fli", "lyapunov_status"):
        np.testing.assert_array_equal(pd.extra[k][done], got[k][done], err_msg=k)
    assert np.isfinite(pd.extra[indicator]).all() and (pd.extra["megno"][done] > 4).any()
    thr = sweep.map_threshold(scene.lyapunov)
    same = sweep.classify(pd.extra, indicator, thr)[0] == sweep.classify(got, indicator, thr)[0]
    # a 32^2 raster from a lattice of 8 a side at T = 100, whose MEGNO classes are speckled: 94-96 % of the
    # cells (MEGNO), 99.5 % (FLI); 99.7 % for MEGNO at 256^2, T = 1000 (docs/scenes.md)
    assert same.mean() >= 0.9 and pd.attrs["class_indicator"] == indicator
    assert f"map cells computed {int(done.sum())} of {len(done)}" in format_report(report)


def test_a_systems_frequency_diffusion_is_that_of_its_seeds_on_the_panels_section_map_and_its_map_adaptive(
        tmp_path, monkeypatch):
    """docs/scenes.md, "A scene of your own system": [lyapunov] indicators = ["frequency_diffusion"] of
    a System's scene stores explorer.frequency_diffusion of each seed on the panel's section map (its
    returns at [lyapunov] tol, around ``center``, N = ``diffusion_iterates``) bit for bit, for seeds
    and, its map adaptive as the others, for the computed cells of a map of it (the rest filled)."""
    from systems import henon_heiles

    from explorer.analysis import sweep
    from explorer.io.scene import parse_scene

    monkeypatch.setattr(sweep, "MAP_COARSE", 4)         # a 16-cell map from a lattice of 4 a side
    hh = henon_heiles()
    x, y, px, py = hh.states
    smap = ex.SectionMap(hh, E, section=x, direction=1, coords=(y, py), solve=px, tol=1e-12)
    fd = 'indicators = ["frequency_diffusion"]\ncenter = [0.0, 0.0]\ndiffusion_iterates = 50\n'
    base = ADAPTIVE_SCENE.replace("time = 100.0", "time = 10.0")
    seeded = base.replace("map_resolution = 32\n", fd).replace("[seeds]\n", f"[seeds]\npoints = {POINTS}\n"
                                                                         'kind = "points"\n')
    ex.run_sweep(parse_scene(seeded, system=hh), tmp_path / "s.h5", progress=False)
    pd = store.read_store(tmp_path / "s.h5").panels[0]
    np.testing.assert_array_equal(pd.seeds, POINTS)
    np.testing.assert_array_equal(pd.extra["frequency_diffusion"],
                                  ex.frequency_diffusion(smap, POINTS, center=(0.0, 0.0), iterates=50))
    assert np.isfinite(pd.extra["megno"]).all()
    mapped = base.replace("map_resolution = 32", "map_resolution = 16") + fd \
        + 'map_indicator = "frequency_diffusion"\n'
    ex.run_sweep(parse_scene(mapped, system=hh), tmp_path / "m.h5", progress=False)
    pd = store.read_store(tmp_path / "m.h5").panels[0]
    done = pd.extra["map_computed"]
    assert 0.2 < done.mean() < 1 and pd.attrs["class_indicator"] == "frequency_diffusion"
    np.testing.assert_array_equal(pd.extra["frequency_diffusion"][done],
                                  ex.frequency_diffusion(smap, pd.seeds[done], center=(0.0, 0.0), iterates=50))
    assert np.isfinite(pd.extra["frequency_diffusion"][~done]).all()                 # the filled cells


def test_a_systems_frequency_diffusion_without_a_center_is_refused_naming_it(workdir, capsys):
    (workdir / "fd.toml").write_text(SCENE + '[compute]\nlyapunov = true\n[lyapunov]\nindicators = '
                                             '["frequency_diffusion"]\n')
    code, _out, err = run(["sweep", "fd.toml", "--system", f"{MODULE}:hh", "--out", "res/fd.h5", "--quiet"], capsys)
    assert code == 2 and "lyapunov.center" in err and len(err.strip().splitlines()) == 1


ATLAS_T = 100.0
ATLAS_SCENE = SCENE.replace("[integration]", f"""[atlas]
parameter = "energy"
values = [{1 / 12!r}, 0.125, 0.001]
[compute]
sections = false
lyapunov = true
[lyapunov]
time = {ATLAS_T}
tol = 1e-12
[integration]""")


def test_an_atlas_of_a_system_computes_each_cells_indicators_on_that_cells_section_map():
    from systems import henon_heiles

    from explorer.analysis import sweep
    from explorer.analysis.lyapunov import chaotic_fraction
    from explorer.analysis.sweep import build_system_atlas_spec
    from explorer.io.scene import parse_scene

    scene = parse_scene(ATLAS_SCENE, system=henon_heiles())
    spec = build_system_atlas_spec(scene, chunk_orbits=0)
    assert [p.index for p in spec.panels] == [0, 1, 3, 4]     # E = 0.001 lies below every seed: cells 2, 5 left out
    got: dict = {}
    sweep.run(spec, lambda panel, arrays: got.setdefault(panel.index, arrays))
    x, y, px, py = scene.system.states
    for i in got:
        system, energy, _label = scene.cell(i)
        smap = ex.SectionMap(system, energy, section=x, direction=+1, coords=(y, py), solve=px)
        ref = ex.indicators(smap.with_tol(1e-12), POINTS, tmax=ATLAS_T)
        np.testing.assert_array_equal(got[i]["megno"], ref.values["megno"])
        np.testing.assert_array_equal(got[i]["lyapunov_status"], ref.status)
    # lam = 0.5 at E = 1/12 is lam = 1 at E = 1/48 (q -> lam q, H -> lam^2 H), below E = 1/12 where Hénon and
    # Heiles (1964) found every orbit regular
    assert chaotic_fraction(got[0]["megno"], scene.lyapunov.threshold, got[0]["lyapunov_status"] == 0)[0] == 0.0


def test_an_atlas_cell_seeded_by_its_map_takes_the_raster_cells_on_that_cells_energy_surface():
    from systems import henon_heiles

    from explorer.analysis.sweep import build_system_atlas_spec
    from explorer.io.scene import parse_scene

    text = ATLAS_SCENE.replace("tol = 1e-12", "tol = 1e-12\nmap_resolution = 3")
    text = text.replace('kind = "points"', 'kind = "points"\nwindow = [-0.45, 0.65, -0.52, 0.52]')
    scene = parse_scene(text, system=henon_heiles())
    spec = build_system_atlas_spec(scene, chunk_orbits=0)
    centres = (np.arange(3) + 0.5) / 3
    A, B = np.meshgrid(-0.45 + 1.1 * centres, -0.52 + 1.04 * centres)
    for panel in spec.panels:
        system, energy, _label = scene.cell(panel.index)
        (lam,) = system.parameters.values()
        inside = [(a, b) for a, b in zip(A.ravel(), B.ravel()) if 0.5 * b**2 + 0.5 * a**2 - lam * a**3 / 3 < energy]
        np.testing.assert_allclose(panel.seeds, np.array(inside), rtol=0, atol=1e-15)   # H(0, y, 0, py) < E
        assert panel.grid == (3, -0.45, 0.65, -0.52, 0.52)
    assert 2 not in [p.index for p in spec.panels]     # lam = 0.5, E = 0.001: no cell centre on the surface
    assert scene.lyapunov.adaptive and len(spec.chunks) == len(spec.panels)   # each map refined in one task


def test_a_systems_atlas_is_swept_stored_and_resumed_by_explorer_sweep(workdir, capsys):
    from explorer.io.store import atlas as atlas_store

    (workdir / "atlas.toml").write_text(f'system = "{MODULE}:hh"\n' + ATLAS_SCENE)
    args = ["sweep", "atlas.toml", "--out", "res/atlas.h5", "--quiet", "--no-figure"]
    code, out, err = run(args, capsys)
    assert code == 0, err
    data = atlas_store.read_atlas(workdir / "res" / "atlas.h5")
    assert data.done.all() and np.isnan(data.fraction[:, 2]).all()   # E = 0.001: no seed on the surface (gray)
    assert data.fraction[0, 0] == 0.0        # lam = 0.5, E = 1/12: all regular (Henon & Heiles 1964)
    code, out, err = run(args, capsys)
    assert code == 0 and "0 computed" in out, out
