"""Scenes of a System (docs/scenes.md, "A scene of your own system"): `system = "module:attribute"`,
the section parsed against the system's symbols only, what is refused and how it is named."""
import textwrap

import pytest
import sympy as sp

from explorer.io.scene import Scene, SceneError, SystemScene, load_scene, parse_scene, resolve_system
from explorer.model import ParameterError

MODULE = "h4_scene_systems"

SOURCE = '''
import sympy as sp
import explorer as ex

x, y, px, py, lam = sp.symbols("x y px py lam")
hh = ex.System({x: px, y: py, px: -x - 2*lam*x*y, py: -y - lam*(x**2 - y**2)}, parameters={lam: 1.0},
               energy=(px**2 + py**2)/2 + (x**2 + y**2)/2 + lam*(x**2*y - y**3/3), name="henon_heiles")
no_energy = ex.System({x: px, y: py, px: -x, py: -y}, name="oscillators")


def make_hh():
    return hh.with_(lam=0.75)


not_a_system = 42
'''

SCENE = textwrap.dedent(f"""\
    name = "hh"
    system = "{MODULE}:hh"
    section = "x"
    direction = 1
    coords = ["y", "py"]
    solve = "px"
    [energy]
    value = 0.125
    [sweep]
    parameter = "lam"
    values = [0.5, 1.0]
    [seeds]
    kind = "points"
    points = [[0.1, 0.1], [-0.1, 0.2], [0.1, 0.9]]
    """)


@pytest.fixture(autouse=True)
def systems_module(tmp_path_factory, monkeypatch):
    folder = tmp_path_factory.getbasetemp() / "h4_scene_systems_dir"
    folder.mkdir(exist_ok=True)
    (folder / f"{MODULE}.py").write_text(SOURCE)
    (folder / "h4_raises.py").write_text("raise RuntimeError('broken on purpose')\n")
    monkeypatch.syspath_prepend(str(folder))
    return folder


def test_a_scene_naming_module_attribute_sweeps_that_systems_parameter_on_its_section_map():
    scene = parse_scene(SCENE)
    assert isinstance(scene, SystemScene) and scene.system.name == "henon_heiles"
    x = sp.Symbol("x")
    assert scene.section == x and scene.coords == ("y", "py") and scene.solve == "px" and scene.direction == 1
    assert scene.n_panels == 2
    for i, lam in enumerate((0.5, 1.0)):
        system, energy, label = scene.panel(i)
        assert energy == 0.125 and label == f"lam = {lam!r}"
        assert list(system.parameters.values()) == [lam]
        smap = scene.section_map(i)
        assert smap.energy_value == 0.125 and smap.system.parameters == system.parameters
    # the point (0.1, 0.9) lies outside the energy surface: counted, not seeded
    from explorer.analysis.sweep import system_seed_points

    pts, dropped = system_seed_points(scene.seeds, scene.section_map(0))
    assert pts.tolist() == [[0.1, 0.1], [-0.1, 0.2]] and dropped == 1


def test_the_energy_can_be_the_swept_value_and_parameters_set_the_systems_values():
    text = SCENE.replace('parameter = "lam"', 'parameter = "energy"').replace("[0.5, 1.0]", "[0.1, 0.125]")
    scene = parse_scene(text + "[parameters]\nlam = 0.8\n")
    assert [scene.panel(i)[1] for i in range(2)] == [0.1, 0.125]
    assert all(list(scene.panel(i)[0].parameters.values()) == [0.8] for i in range(2))


def test_system_given_beside_the_scene_replaces_its_system_as_a_callable_or_an_object(tmp_path):
    path = tmp_path / "hh.toml"
    path.write_text(SCENE.replace(f"{MODULE}:hh", "nowhere:at_all"))
    scene = load_scene(path, system=f"{MODULE}:make_hh")    # a callable returning a System
    assert scene.system.name == "henon_heiles" and list(scene.system.parameters.values()) == [0.75]
    obj = resolve_system(f"{MODULE}:hh")
    assert load_scene(path, system=obj).system is obj


def test_a_chaplygin_scene_is_unchanged_and_refuses_a_system_beside_it():
    assert isinstance(load_scene("figure4"), Scene)
    with pytest.raises(SceneError, match="--system needs a scene of a System"):
        load_scene("figure4", system=f"{MODULE}:hh")


@pytest.mark.parametrize("value, message", [
    ("hh", "must be 'module:attribute'"),
    ("a:b:c", "must be 'module:attribute'"),
    ("not a module:hh", "must be 'module:attribute'"),
    ("h4_no_such_module:hh", "no module named 'h4_no_such_module'"),
    (f"{MODULE}:missing", f"module {MODULE} has no attribute 'missing'"),
    (f"{MODULE}:not_a_system", "is a int, not an explorer System"),
    ("h4_raises:hh", "importing h4_raises failed: RuntimeError: broken on purpose"),
])
def test_a_bad_module_attribute_is_refused_naming_the_value(value, message):
    with pytest.raises(ParameterError, match="--system") as err:
        parse_scene(SCENE, system=value)
    assert message in str(err.value) and value in str(err.value) and "\n" not in str(err.value)
    with pytest.raises(SceneError, match="scene key 'system'"):
        parse_scene(SCENE.replace(f"{MODULE}:hh", value))


def test_the_section_is_read_as_arithmetic_of_the_systems_symbols_and_nothing_is_evaluated(tmp_path):
    marker = tmp_path / "evaluated"
    for section in (f"__import__('pathlib').Path('{marker}').touch()", "x + z", "x**2", "lambda: x", "x +"):
        with pytest.raises(SceneError, match="scene key 'section'"):
            parse_scene(SCENE.replace('section = "x"', f'section = "{section}"'))
    assert not marker.exists()
    scene = parse_scene(SCENE.replace('section = "x"', 'section = "2*x - 0.0*lam"'))
    assert scene.section_map(0).section.a.tolist() == [2.0, 0.0, 0.0, 0.0]


@pytest.mark.parametrize("edit, key", [
    (('parameter = "lam"', 'parameter = "mu"'), "sweep.parameter"),
    (("value = 0.125", "h = 0.125"), "energy.h"),
    (('coords = ["y", "py"]', 'coords = ["y", "q"]'), "coords"),
    (('solve = "px"', 'solve = "y"'), "solve"),
    (("direction = 1", "direction = 0"), "direction"),
    (('kind = "points"', 'kind = "grid"'), "seeds.window"),
    (("[seeds]", "[model]\nmu = 1.0\n[seeds]"), "model"),
    (("[0.5, 1.0]", "[0.5, 0.5]"), "sweep.values[1]"),
    (("[seeds]", "[lyapunov]\nindicators = [\"frequency_diffusion\"]\n[seeds]"), "lyapunov.center"),
    (("[seeds]", "[lyapunov]\nindicators = [\"lyapunov\"]\n[seeds]"), "lyapunov.indicators[0]"),
    (("[seeds]", "[lyapunov]\nmap_indicator = \"fli\"\n[seeds]"), "lyapunov.map_indicator"),
    (("[seeds]", "[compute]\nsections = false\nlyapunov = true\nseparatrices = true\n[seeds]"),
     "compute.separatrices"),
    (("[seeds]", "[lyapunov]\nexact = 1\n[seeds]"), "lyapunov.exact"),
])
def test_a_bad_system_scene_is_refused_naming_the_key(edit, key):
    with pytest.raises(SceneError, match=key.replace("[", r"\[").replace(".", r"\.")):
        parse_scene(SCENE.replace(*edit))


def test_a_system_without_an_energy_is_refused_naming_what_is_missing():
    text = SCENE.replace(f"{MODULE}:hh", f"{MODULE}:no_energy").replace('[sweep]\nparameter = "lam"\n'
                                                                        'values = [0.5, 1.0]\n', "")
    with pytest.raises(SceneError, match="has no energy"):
        parse_scene(text)


def test_the_panel_hash_follows_the_numbers_not_the_drawing():
    base = parse_scene(SCENE)
    assert base.panel_hash(0) != base.panel_hash(1)      # lam differs
    assert parse_scene(SCENE + "[figure]\ndpi = 100\n").panel_hash(0) == base.panel_hash(0)
    assert parse_scene(SCENE.replace("value = 0.125", "value = 0.12")).panel_hash(0) != base.panel_hash(0)
    assert parse_scene(SCENE.replace("direction = 1", "direction = -1")).panel_hash(0) != base.panel_hash(0)


def test_a_systems_map_is_adaptive_unless_exact_and_only_an_adaptive_maps_hashes_name_its_rule():
    """As Chaplygin's (docs/scenes.md): an exact panel is never reused as an adaptive one; an adaptive
    map's hashes follow the threshold (it picks the cells computed), an exact map's keep the keys of
    the numbers alone."""
    text = SCENE.replace('kind = "points"', 'window = [-0.45, 0.65, -0.52, 0.52]\nkind = "points"')
    adaptive = text + "[compute]\nlyapunov = true\n[lyapunov]\nmap_resolution = 8\n"
    exact = adaptive + "exact = true\n"

    def hashes(t):
        s = parse_scene(t)
        return [h for i in range(s.n_panels) for h in (s.panel_hash(i), s.product_hashes(i)["indicators"])]

    assert parse_scene(adaptive).lyapunov.adaptive and not parse_scene(exact).lyapunov.adaptive
    assert set(hashes(adaptive)).isdisjoint(hashes(exact))
    retold = "[lyapunov]\nthreshold = 6.0\n"
    assert set(hashes(adaptive)).isdisjoint(hashes(adaptive.replace("[lyapunov]\n", retold)))
    assert hashes(exact) == hashes(exact.replace("[lyapunov]\n", retold))
    assert set(parse_scene(exact).product_settings(0)["indicators"]["lyapunov"]) == {"time", "tol", "indicators"}


ATLAS = SCENE.replace("[seeds]", '[atlas]\nparameter = "energy"\nvalues = [0.0625, 0.125]\n'
                      '[compute]\nsections = false\nlyapunov = true\n[seeds]')


def test_an_atlas_crosses_the_swept_parameter_with_the_energy_cell_by_cell():
    scene = parse_scene(ATLAS)
    assert scene.is_atlas and scene.n_cells == 4 and scene.n_panels == 2
    system, energy, label = scene.cell(1)                     # row 0 (lam = 0.5), column 1
    (lam,) = system.parameters
    assert system.parameters[lam] == 0.5 and energy == 0.125 and label == "lam = 0.5, energy = 0.125"
    system, energy, _ = scene.cell(2)                          # row 1 (lam = 1.0), column 0
    assert system.parameters[lam] == 1.0 and energy == 0.0625
    assert scene.cell_map(2).energy_value == 0.0625 and scene.cell_map(2).system.parameters[lam] == 1.0
    with pytest.raises(IndexError):
        scene.cell(4)
    assert parse_scene(ATLAS + "[figure]\ndpi = 100\n").atlas_hash() == scene.atlas_hash()
    for edit in (("0.0625", "0.0626"), ("[0.5, 1.0]", "[0.5, 0.9]"),
                 ("[compute]", "[lyapunov]\ntime = 10.0\n[compute]")):
        assert parse_scene(ATLAS.replace(*edit)).atlas_hash() != scene.atlas_hash(), edit


@pytest.mark.parametrize("edit, key", [
    (("sections = false", "sections = true"), "compute"),
    (('parameter = "energy"', 'parameter = "lam"'), "atlas.parameter"),
    (('parameter = "energy"', 'parameter = "mu"'), "atlas.parameter"),
    (("[0.0625, 0.125]", "[0.0625, 0.0625]"), "atlas.values[1]"),
    (("lyapunov = true", "lyapunov = true\nseparatrices = true"), "compute.separatrices"),
    (("[seeds]", "[manifolds]\ndraw = true\n[seeds]"), "manifolds.draw"),
])
def test_a_bad_system_atlas_is_refused_naming_the_key(edit, key):
    with pytest.raises(SceneError, match=key.replace("[", r"\[").replace(".", r"\.")):
        parse_scene(ATLAS.replace(*edit))


def test_a_systems_frequency_diffusion_hashes_follow_its_center_and_iterates():
    """As Chaplygin's (docs/scenes.md): [lyapunov] center and diffusion_iterates enter the indicators'
    hashes when frequency_diffusion is asked for, and a scene without it keeps its hashes."""
    text = SCENE + "[compute]\nlyapunov = true\n[lyapunov]\ntime = 10.0\n"
    fd = text + 'indicators = ["frequency_diffusion"]\ncenter = [0.0, 0.0]\ndiffusion_iterates = 50\n'

    def hashes(t):
        return parse_scene(t).product_hashes(0)["indicators"]

    assert parse_scene(fd).lyapunov.frequency_diffusion == {"center": [0.0, 0.0], "iterates": 50, "tol": 1e-12}
    assert hashes(text) == hashes(text + "center = [0.1, 0.0]\ndiffusion_iterates = 60\n")
    assert len({hashes(fd), hashes(text), hashes(fd.replace("[0.0, 0.0]", "[0.1, 0.0]")),
                hashes(fd.replace("= 50", "= 60"))}) == 4


def test_a_systems_seeds_placed_on_its_section_map_are_the_points_of_its_domain():
    import explorer as ex
    from explorer.io.scene.system import SystemSeeds
    from explorer.model import classic

    hh = classic.henon_heiles()
    x, y, px, py = hh.states
    smap = ex.SectionMap(hh, 1 / 8, section=x, direction=1, coords=(y, py), solve=px)
    grid = SystemSeeds(window=(-0.6, 0.8, -0.6, 0.6), n=100).points_on(smap)
    assert 40 < len(grid) < 100 and smap.allowed(grid).all()        # the grid's points off the level left out
    given = SystemSeeds(kind="points", points=((0.1, 0.0), (2.0, 2.0))).points_on(smap)
    assert given.tolist() == [[0.1, 0.0]]
