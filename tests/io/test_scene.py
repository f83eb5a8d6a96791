"""explorer.scene: TOML scenes, validation with dotted keys, seeding, panel hashes."""
import ast
import dataclasses
import inspect
import math
import re
from pathlib import Path

import numpy as np
import pytest

from explorer import model
from explorer.analysis import sections
from explorer.io import scene
from explorer.io.scene import SceneError, SeedSpec, load_scene, parse_scene, seed_points


def _docs_example() -> str:
    """The full example of docs/scenes.md (its first TOML block)."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "scenes.md").read_text()
    return text.split("```toml\n", 1)[1].split("```", 1)[0]


BASE = 'name = "t"\n'


# ---------------------------------------------------------------- parsing
def test_the_full_example_of_docs_scenes_parses_with_every_key():
    text = _docs_example()
    s = parse_scene(text)
    assert s.name == "myscene" and s.text == text
    assert s.params == model.FIGURE4.with_(a1=1.0)
    assert s.h == 2.0
    assert s.sweep_parameter == "mu" and s.sweep_values == (0.002, 0.01, 0.03, 4.0, 8.0)
    assert s.seeds == SeedSpec(kind="grid", n=200, margin=0.98, seed=1,
                               lines=((-1.0, 0.0, 1.0, 0.0),), points=((0.1, 0.0),))
    i = s.integration
    assert (i.method, i.tol, i.dt, i.crossings, i.tmax, i.max_steps, i.direction) == \
        ("taylor", 1e-13, 0.05, 1000, 1e4, 10**9, 1)
    assert i.phi0 == math.pi
    assert s.compute == ("sections",)
    ly = s.lyapunov
    assert (ly.time, ly.threshold, ly.indicators, ly.center, ly.diffusion_iterates) == \
        (1000.0, 4.0, ("mlce", "megno", "fli"), (1.571, 0.0), 300)
    f = s.figure
    assert (f.layout, f.columns, f.share_scale, f.own_scale, f.marker_size, f.dpi) == \
        ("row", 3, True, (3, 4), 0.25, 200)
    assert (s.manifolds.draw, s.manifolds.period) == (False, 1)
    assert s.n_panels == 5


def test_minimal_scene_has_documented_defaults_and_one_panel():
    s = parse_scene(BASE)
    assert s.params == model.FIGURE4 and s.h == model.FIGURE4_H
    assert s.n_panels == 1 and s.panel(0) == (model.FIGURE4, model.FIGURE4_H, "")
    assert s.seeds == SeedSpec("grid", 200, 0.98, 0, None, None)
    assert s.integration == scene.IntegrationSpec()
    assert s.integration.phi0 == math.pi and s.integration.tol == sections.DEFAULT_TOL
    assert s.integration.effective_tmax == 100.0 * s.integration.crossings
    assert s.figure == scene.FigureSpec() and s.compute == ("sections",)


def test_preset_figure4_loads_with_the_figure4_scene():
    s = load_scene("figure4")
    assert s.name == "figure4" and s.text == scene.PRESETS["figure4"]
    assert s.sweep_parameter == "mu" and s.sweep_values == (0.002, 0.01, 0.03, 4.0, 8.0)
    for i, mu in enumerate(s.sweep_values):
        prm, h, label = s.panel(i)
        assert prm == model.FIGURE4.with_(mu=mu) and h == model.FIGURE4_H == 2.0
        assert label == f"mu = {mu!r}"
    assert s.seeds.used_dict() == {"kind": "grid", "n": 200, "margin": 0.98}
    assert (s.integration.method, s.integration.tol, s.integration.crossings) == ("taylor", 1e-13, 1000)
    assert (s.figure.layout, s.figure.share_scale, s.figure.own_scale) == ("row", True, (3, 4))
    assert s.integration.tmax == 10000.0


def test_load_scene_reads_a_toml_file(tmp_path):
    p = tmp_path / "my.toml"
    text = BASE + '[sweep]\nparameter = "h"\nvalues = [1.0, 3]\n'
    p.write_text(text, encoding="utf-8")
    s = load_scene(str(p))
    assert s.text == text and s.sweep_values == (1.0, 3.0)
    assert [s.panel(i)[1] for i in range(2)] == [1.0, 3.0] and s.panel(1)[2] == "h = 3.0"
    assert load_scene(p) == s


def test_missing_file_is_a_scene_error_naming_the_path(tmp_path):
    missing = tmp_path / "nope.toml"
    with pytest.raises(SceneError, match=re.escape(str(missing))) as ei:
        load_scene(str(missing))
    assert "\n" not in str(ei.value)


def test_toml_syntax_error_is_a_scene_error_with_the_line():
    with pytest.raises(SceneError) as ei:
        parse_scene('name = "t"\n[model]\nmu = = 1\n', source="x.toml")
    msg = str(ei.value)
    assert "TOML syntax error" in msg and "x.toml" in msg and "line 3" in msg and "\n" not in msg


def test_scene_error_is_a_parameter_error():
    assert issubclass(SceneError, model.ParameterError)


BAD = [
    # (id, toml body after name, dotted key that must be named)
    ("unknown_table", "[modle]\nmu = 1.0\n", "modle"),
    ("unknown_top_key", "nmae = 'x'\n", "nmae"),
    ("unknown_model_key", "[model]\nnu = 1.0\n", "model.nu"),
    ("unknown_energy_key", "[energy]\nE = 1.0\n", "energy.E"),
    ("unknown_sweep_key", "[sweep]\nparameter = 'mu'\nvalues = [1.0]\nvalue = 2\n", "sweep.value"),
    ("unknown_seeds_key", "[seeds]\nnn = 3\n", "seeds.nn"),
    ("unknown_integration_key", "[integration]\ntolerance = 1e-10\n", "integration.tolerance"),
    ("unknown_compute_key", "[compute]\nfractal = true\n", "compute.fractal"),
    ("unknown_lyapunov_key", "[lyapunov]\ntimes = 3\n", "lyapunov.times"),
    ("lyapunov_time_negative", "[lyapunov]\ntime = -3.0\n", "lyapunov.time"),
    ("lyapunov_bad_method", "[lyapunov]\nmethod = \"euler\"\n", "lyapunov.method"),
    ("lyapunov_threshold_low", "[lyapunov]\nthreshold = 1.0\n", "lyapunov.threshold"),
    ("unknown_figure_key", "[figure]\nsize = 3\n", "figure.size"),
    ("table_as_value", "model = 3\n", "model"),
    ("string_for_number", "[energy]\nh = '2'\n", "energy.h"),
    ("bool_for_number", "[model]\nmu = true\n", "model.mu"),
    ("bool_for_int", "[integration]\ncrossings = true\n", "integration.crossings"),
    ("float_for_crossings", "[integration]\ncrossings = 1000.0\n", "integration.crossings"),
    ("float_for_n", "[seeds]\nn = 200.0\n", "seeds.n"),
    ("nan_model", "[model]\nchi = nan\n", "model.chi"),
    ("inf_energy", "[energy]\nh = inf\n", "energy.h"),
    ("inf_sweep_value", "[sweep]\nparameter = 'mu'\nvalues = [0.5, inf]\n", "sweep.values[1]"),
    ("nonpositive_mass", "[model]\na1 = 0.0\n", "model.a1"),
    ("lam_zero", "[model]\nlam = 0\n", "model.lam"),
    ("negative_mu", "[model]\nmu = -1.0\n", "model.mu"),
    ("negative_crossings", "[integration]\ncrossings = -5\n", "integration.crossings"),
    ("zero_crossings", "[integration]\ncrossings = 0\n", "integration.crossings"),
    ("bad_method", "[integration]\nmethod = 'rk4'\n", "integration.method"),
    ("tol_too_large", "[integration]\ntol = 0.5\n", "integration.tol"),
    ("tol_too_small", "[integration]\ntol = 1e-20\n", "integration.tol"),
    ("dt_zero", "[integration]\ndt = 0.0\n", "integration.dt"),
    ("dt_negative", "[integration]\nmethod = 'split4'\ndt = -0.1\n", "integration.dt"),
    ("tmax_zero", "[integration]\ntmax = 0.0\n", "integration.tmax"),
    ("max_steps_zero", "[integration]\nmax_steps = 0\n", "integration.max_steps"),
    ("phi0_string", "[integration]\nphi0 = 'pi'\n", "integration.phi0"),
    ("bad_direction", "[integration]\ndirection = 2\n", "integration.direction"),
    ("direction_string", "[integration]\ndirection = '+'\n", "integration.direction"),
    ("margin_zero", "[seeds]\nmargin = 0.0\n", "seeds.margin"),
    ("margin_above_one", "[seeds]\nmargin = 1.5\n", "seeds.margin"),
    ("bad_kind", "[seeds]\nkind = 'hex'\n", "seeds.kind"),
    ("n_zero", "[seeds]\nn = 0\n", "seeds.n"),
    ("negative_seed", "[seeds]\nkind = 'random'\nseed = -1\n", "seeds.seed"),
    ("lines_missing", "[seeds]\nkind = 'lines'\n", "seeds.lines"),
    ("line_outside_unit_box", "[seeds]\nkind = 'lines'\nlines = [[-1.5, 0.0, 1.0, 0.0]]\n", "seeds.lines[0]"),
    ("line_wrong_length", "[seeds]\nkind = 'lines'\nlines = [[0.0, 0.0, 1.0]]\n", "seeds.lines[0]"),
    ("points_wrong_length", "[seeds]\nkind = 'points'\npoints = [[0.1, 0.0, 0.0]]\n", "seeds.points[0]"),
    ("points_all_outside", "[seeds]\nkind = 'points'\npoints = [[10.0, 0.0]]\n", "seeds.points"),
    ("empty_values", "[sweep]\nparameter = 'mu'\nvalues = []\n", "sweep.values"),
    ("values_missing", "[sweep]\nparameter = 'mu'\n", "sweep.values"),
    ("duplicate_values", "[sweep]\nparameter = 'mu'\nvalues = [0.5, 1.0, 0.5]\n", "sweep.values[2]"),
    ("duplicate_int_float", "[sweep]\nparameter = 'mu'\nvalues = [1, 1.0]\n", "sweep.values[1]"),
    ("sweep_unknown_parameter", "[sweep]\nparameter = 'nu'\nvalues = [1.0]\n", "sweep.parameter"),
    ("sweep_mu_negative", "[sweep]\nparameter = 'mu'\nvalues = [0.5, -0.1]\n", "sweep.values[1]"),
    ("sweep_lam_hits_zero", "[sweep]\nparameter = 'lam'\nvalues = [1.0, 0.0, -1.0]\n", "sweep.values[1]"),
    ("sweep_a2_zero", "[sweep]\nparameter = 'a2'\nvalues = [0.0]\n", "sweep.values[0]"),
    ("energy_below_region", "[energy]\nh = -1.0\n", "energy.h"),
    ("energy_below_region_in_mu_sweep", "[energy]\nh = -1.0\n[sweep]\nparameter = 'mu'\nvalues = [0.05, 0.2]\n",
     "energy.h"),
    ("sweep_h_below_region", "[sweep]\nparameter = 'h'\nvalues = [2.0, -1.0]\n", "sweep.values[1]"),
    ("sweep_eta_empties_one_panel", "[model]\nmu = 1.0\n[sweep]\nparameter = 'eta'\nvalues = [0.0, -5.0]\n",
     "sweep.values[1]"),
    ("compute_nothing", "[compute]\nsections = false\n", "compute.sections"),
    ("compute_not_bool", "[compute]\nsections = 1\n", "compute.sections"),
    ("bad_layout", "[figure]\nlayout = 'column'\n", "figure.layout"),
    ("columns_zero", "[figure]\nlayout = 'grid'\ncolumns = 0\n", "figure.columns"),
    ("own_scale_out_of_range", "[figure]\nown_scale = [1]\n", "figure.own_scale[0]"),
    ("own_scale_out_of_range_sweep", "[sweep]\nparameter = 'mu'\nvalues = [0.1, 0.2]\n[figure]\nown_scale = [0, 2]\n",
     "figure.own_scale[1]"),
    ("own_scale_duplicate", "[sweep]\nparameter = 'mu'\nvalues = [0.1, 0.2]\n[figure]\nown_scale = [1, 1]\n",
     "figure.own_scale[1]"),
    ("share_scale_not_bool", "[figure]\nshare_scale = 'yes'\n", "figure.share_scale"),
    ("marker_size_negative", "[figure]\nmarker_size = -1.0\n", "figure.marker_size"),
    ("dpi_zero", "[figure]\ndpi = 0\n", "figure.dpi"),
    ("description_not_string", "description = 3\n", "description"),
]


@pytest.mark.parametrize("body,key", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_scene_raises_scene_error_naming_the_key(body, key):
    with pytest.raises(SceneError) as ei:
        parse_scene(BASE + body)
    msg = str(ei.value)
    assert f"'{key}'" in msg, msg
    assert "\n" not in msg


@pytest.mark.parametrize("name", ["fig 4", "", "a/b", ".hidden", "x" * 200, "π"])
def test_bad_name_raises_scene_error_naming_name(name):
    with pytest.raises(SceneError, match="'name'"):
        parse_scene(f"name = {scene._toml_string(name)}\n")


def test_missing_name_and_non_string_name_raise():
    with pytest.raises(SceneError, match="'name'"):
        parse_scene("[energy]\nh = 2.0\n")
    with pytest.raises(SceneError, match="'name'"):
        parse_scene("name = 4\n")


def test_unknown_key_message_lists_the_allowed_keys():
    with pytest.raises(SceneError) as ei:
        parse_scene(BASE + "[seeds]\nnn = 3\n")
    assert str(ei.value) == ("scene: unknown key 'seeds.nn' (did you mean 'n'?) "
                             "(allowed: kind, n, margin, seed, lines, points)")


def test_range_message_names_range_and_value():
    with pytest.raises(SceneError) as ei:
        parse_scene(BASE + "[integration]\ntol = 0.5\n")
    assert str(ei.value) == "scene key 'integration.tol' must be in [1e-16, 0.01], got 0.5"


def test_integer_is_accepted_for_a_float_and_stored_as_float():
    s = parse_scene(BASE + "[energy]\nh = 3\n[model]\nmu = 1\n[integration]\ntmax = 500\n")
    assert type(s.h) is float and type(s.params.mu) is float and type(s.integration.tmax) is float


def test_dataclasses_validate_when_built_in_python():
    with pytest.raises(SceneError, match="'seeds.margin'"):
        SeedSpec(margin=0.0)
    with pytest.raises(SceneError, match="'integration.method'"):
        scene.IntegrationSpec(method="euler")
    with pytest.raises(SceneError, match="'figure.dpi'"):
        scene.FigureSpec(dpi=1.5)
    with pytest.raises(SceneError, match="'sweep.values\\[0\\]'"):
        scene.Scene(name="x", sweep_parameter="mu", sweep_values=(-1.0,))


def test_panel_index_out_of_range_raises_index_error():
    s = load_scene("figure4")
    for bad in (-1, 5, 1.0):
        with pytest.raises(IndexError):
            s.panel(bad)


def test_dict_and_toml_round_trips_give_the_same_scene():
    for s in (load_scene("figure4"), parse_scene(_docs_example()),
              parse_scene(BASE + 'description = "quote \\" tab\\t é"\n[seeds]\nkind = "lines"\n'
                          "lines = [[-1.0, 0.0, 1.0, 0.0], [0.0, -1, 0.0, 1]]\n[integration]\nphi0 = 1.25\n"),
              parse_scene(LYAP_FD + "diffusion_iterates = 40\n")):   # [lyapunov] center, a list in TOML
        assert scene.scene_from_dict(s.to_dict(), s.text) == s
        assert dataclasses.replace(parse_scene(s.to_toml()), text=s.text) == s


def test_section_kwargs_fit_crossings():
    for method in ("taylor", "split4"):
        spec = scene.IntegrationSpec(method=method, crossings=7, direction=0)
        kw = spec.section_kwargs()
        # the (params, h) form: phi0 and tol are the map's settings, the rest crossings' own keywords
        inspect.signature(sections.crossings).bind(model.FIGURE4, [(0.0, 0.0)], n_crossings=spec.crossings, **kw)
        res = sections.crossings(model.FIGURE4, 2.0, [(0.0, 0.0)], n_crossings=2, **dict(kw, tmax=None))
        assert res.settings["method"] == method and res.settings["direction"] == 0
        assert ("tol" in kw) == (method == "taylor") and ("dt" in kw) == (method != "taylor")
        assert kw["tmax"] == 700.0


def test_module_imports_no_numba_h5py_or_matplotlib():
    tree = ast.parse(inspect.getsource(scene))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            names.add(node.module.split(".")[0])
    assert not names & {"numba", "h5py", "matplotlib"}


# ---------------------------------------------------------------- panel hashes
SWEEP_SCENE = BASE + "[sweep]\nparameter = 'mu'\nvalues = [0.1, 0.5, 1.0]\n[integration]\ntol = 1e-12\n"


def _hashes(text):
    s = parse_scene(text)
    return [s.panel_hash(i) for i in range(s.n_panels)]


def test_panel_hashes_are_distinct_hex_sha256():
    h = _hashes(SWEEP_SCENE)
    assert len(set(h)) == 3 and all(re.fullmatch(r"[0-9a-f]{64}", x) for x in h)


def test_figure_name_and_description_changes_keep_panel_hashes():
    base = _hashes(SWEEP_SCENE)
    changed = SWEEP_SCENE.replace('name = "t"', 'name = "other"\ndescription = "words"') + \
        "[figure]\nlayout = 'grid'\ncolumns = 2\nshare_scale = false\nown_scale = [2]\nmarker_size = 1.0\ndpi = 100\n"
    assert _hashes(changed) == base


def test_changing_one_sweep_value_changes_exactly_that_panel_hash():
    base = _hashes(SWEEP_SCENE)
    new = _hashes(SWEEP_SCENE.replace("0.5,", "0.6,"))
    assert [a == b for a, b in zip(base, new)] == [True, False, True]


def test_reordering_sweep_values_moves_the_hashes_with_the_values():
    base = _hashes(SWEEP_SCENE)
    new = _hashes(SWEEP_SCENE.replace("[0.1, 0.5, 1.0]", "[1.0, 0.1, 0.5]"))
    assert new == [base[2], base[0], base[1]]


@pytest.mark.parametrize("change", [
    ("tol = 1e-12", "tol = 1e-11"),
    ("tol = 1e-12", "tol = 1e-12\ncrossings = 999"),
    ("tol = 1e-12", "tol = 1e-12\nphi0 = 1.0"),
    ("tol = 1e-12", "tol = 1e-12\ndirection = -1"),
    ("tol = 1e-12", "tol = 1e-12\nmethod = 'dop853'"),
    ("[integration]", "[seeds]\nn = 201\n[integration]"),
    ("[integration]", "[model]\nchi = 0.1\n[integration]"),
    ("[integration]", "[energy]\nh = 2.5\n[integration]"),
], ids=["tol", "crossings", "phi0", "direction", "method", "seeds_n", "model", "energy"])
def test_changing_a_shared_setting_changes_every_panel_hash(change):
    base = _hashes(SWEEP_SCENE)
    new = _hashes(SWEEP_SCENE.replace(*change))
    assert all(a != b for a, b in zip(base, new))


# every key that changes a panel's numbers changes its hash (issue 14, point 6): each pair is
# (base scene, changed scene) built from SWEEP_SCENE; the base already uses the key's table
SPLIT_SCENE = SWEEP_SCENE.replace("tol = 1e-12", "method = 'split4'\ndt = 0.05")
RANDOM_SCENE = SWEEP_SCENE + "[seeds]\nkind = 'random'\nn = 50\nseed = 1\n"
LYAP_SCENE = SWEEP_SCENE + "[compute]\nlyapunov = true\n[lyapunov]\ntime = 500.0\nmethod = 'taylor'\ntol = 1e-12\n"
LYAP_SPLIT = LYAP_SCENE.replace("method = 'taylor'\ntol = 1e-12", "method = 'split4'\ndt = 0.02")
LYAP_FD = LYAP_SCENE + "indicators = ['megno', 'frequency_diffusion']\ncenter = [0.0, 0.0]\n"
LYAP_FD_SPLIT = LYAP_SPLIT + "indicators = ['megno', 'frequency_diffusion']\ncenter = [0.0, 0.0]\n"
HASHED_CHANGES = {
    "tmax": (SWEEP_SCENE, SWEEP_SCENE.replace("tol = 1e-12", "tol = 1e-12\ntmax = 5000")),
    "max_steps": (SWEEP_SCENE, SWEEP_SCENE.replace("tol = 1e-12", "tol = 1e-12\nmax_steps = 1000")),
    "split_dt": (SPLIT_SCENE, SPLIT_SCENE.replace("dt = 0.05", "dt = 0.04")),
    "seeds_kind": (SWEEP_SCENE, SWEEP_SCENE + "[seeds]\nkind = 'random'\n"),
    "seeds_margin": (SWEEP_SCENE, SWEEP_SCENE + "[seeds]\nmargin = 0.9\n"),
    "seeds_seed": (RANDOM_SCENE, RANDOM_SCENE.replace("seed = 1", "seed = 2")),
    "lyapunov_time": (LYAP_SCENE, LYAP_SCENE.replace("time = 500.0", "time = 600.0")),
    "lyapunov_method": (LYAP_SCENE, LYAP_SCENE.replace("method = 'taylor'", "method = 'dop853'")),
    "lyapunov_tol": (LYAP_SCENE, LYAP_SCENE.replace("tol = 1e-12\n", "tol = 1e-11\n").replace(
        "[integration]\ntol = 1e-11", "[integration]\ntol = 1e-12")),
    "lyapunov_split_dt": (LYAP_SPLIT, LYAP_SPLIT.replace("dt = 0.02", "dt = 0.01")),
    "compute_lyapunov": (SWEEP_SCENE, LYAP_SCENE),
    "compute_separatrices": (SWEEP_SCENE, SWEEP_SCENE + "[compute]\nseparatrices = true\n"),
    "frequency_diffusion": (LYAP_SCENE, LYAP_FD),
    "diffusion_center": (LYAP_FD, LYAP_FD.replace("center = [0.0, 0.0]", "center = [0.0, 0.1]")),
    "diffusion_iterates": (LYAP_FD, LYAP_FD + "diffusion_iterates = 200\n"),
    # the tolerance of its section returns, whatever the method of the tangent indicators
    "diffusion_tol": (LYAP_FD_SPLIT, LYAP_FD_SPLIT + "tol = 1e-11\n"),
}


@pytest.mark.parametrize("name", sorted(HASHED_CHANGES))
def test_every_setting_that_changes_the_numbers_changes_every_panel_hash(name):
    base, changed = HASHED_CHANGES[name]
    assert parse_scene(base) != parse_scene(changed)  # the edit took effect
    assert all(a != b for a, b in zip(_hashes(base), _hashes(changed)))


def test_the_megno_threshold_alone_keeps_panel_hashes():
    """The threshold only classifies stored MEGNO values: no recomputation (the runner restamps
    the stored chaotic fraction instead, tests/analysis/test_sweep.py)."""
    changed = LYAP_SCENE.replace("[lyapunov]\n", "[lyapunov]\nthreshold = 6.0\n")
    assert parse_scene(changed).lyapunov.threshold == 6.0
    assert _hashes(changed) == _hashes(LYAP_SCENE)


def test_the_exact_key_and_an_adaptive_maps_threshold_change_its_hashes_an_exact_maps_threshold_does_not():
    """An adaptive map's computed cells depend on the class threshold (docs/scenes.md): a stored
    exact panel is never reused as an adaptive one, nor the other way; ``exact`` is refused unless a boolean."""
    adaptive = LYAP_SCENE + "map_resolution = 16\n"
    exact = adaptive + "exact = true\n"
    assert parse_scene(adaptive).lyapunov.adaptive and not parse_scene(exact).lyapunov.adaptive
    assert set(_hashes(adaptive)).isdisjoint(_hashes(exact))
    assert set(_hashes(adaptive)).isdisjoint(_hashes(adaptive.replace("[lyapunov]\n", "[lyapunov]\nthreshold = 6.0\n")))
    assert _hashes(exact) == _hashes(exact.replace("[lyapunov]\n", "[lyapunov]\nthreshold = 6.0\n"))
    assert _hashes(LYAP_SCENE + "exact = true\n") == _hashes(LYAP_SCENE)      # no map: nothing to refine
    with pytest.raises(SceneError, match=r"lyapunov\.exact"):
        parse_scene(adaptive + 'exact = "yes"\n')


def test_a_new_version_of_the_refinement_rule_changes_an_adaptive_maps_hashes_not_an_exact_maps(monkeypatch):
    """A stored adaptive map is not reused once chaos_map's rule has changed (its RULE_VERSION)."""
    from explorer.analysis import chaos_map

    adaptive = LYAP_SCENE + "map_resolution = 16\n"
    exact = adaptive + "exact = true\n"
    before = _hashes(adaptive), _hashes(exact)
    monkeypatch.setattr(chaos_map, "RULE_VERSION", chaos_map.RULE_VERSION + 1)
    assert set(_hashes(adaptive)).isdisjoint(before[0]) and _hashes(exact) == before[1]


def test_the_map_indicator_changes_an_adaptive_maps_hashes_and_class_not_an_exact_maps_hashes():
    """An adaptive map is refined and classified by its own indicator (docs/scenes.md, "Adaptive
    maps"): map_indicator enters its hashes; an exact map's cells are the same whatever it draws,
    so only its class (and an atlas of it, whose fractions are stored) changes."""
    from explorer.analysis.sweep import map_threshold, panel_class

    adaptive = LYAP_SCENE + "indicators = ['megno', 'fli']\nmap_resolution = 16\n"
    fli = adaptive + "map_indicator = 'fli'\n"
    assert parse_scene(fli).lyapunov.adaptive
    assert set(_hashes(adaptive)).isdisjoint(_hashes(fli))
    assert _hashes(adaptive + "exact = true\n") == _hashes(fli + "exact = true\n")
    ly = parse_scene(fli).lyapunov
    assert panel_class(ly, True) == ("fli", map_threshold(ly)) and map_threshold(ly) == 2 * math.log(500.0)
    assert panel_class(ly, False) == ("megno", 4.0) and panel_class(parse_scene(adaptive).lyapunov, True) == \
        ("megno", 4.0)


def test_the_diffusion_settings_alone_keep_panel_hashes_unless_it_is_asked_for():
    """[lyapunov] center and diffusion_iterates determine only frequency_diffusion: a scene that
    does not ask for it keeps its hashes (its panels are not recomputed)."""
    changed = LYAP_SCENE + "center = [1.5, 0.0]\ndiffusion_iterates = 50\n"
    assert parse_scene(changed).lyapunov.center == (1.5, 0.0)
    assert _hashes(changed) == _hashes(LYAP_SCENE)


@pytest.mark.parametrize("edit, key", [
    ("indicators = ['megno', 'frequency_diffusion']\n", "lyapunov.center"),   # required with it
    ("center = [1.5]\n", "lyapunov.center"),
    ("center = [1.5, 'a']\n", "lyapunov.center[1]"),
    ("center = 1.5\n", "lyapunov.center"),
    ("diffusion_iterates = 5\n", "lyapunov.diffusion_iterates"),
])
def test_bad_diffusion_settings_name_the_key(edit, key):
    with pytest.raises(SceneError, match=re.escape(f"'{key}'")):
        parse_scene(LYAP_SCENE + edit)


def test_the_diffusion_centre_must_lie_in_every_panels_allowed_region():
    # the centre's own orbit is followed (explorer.analysis.rotation): (10, 0) is outside every panel's region
    with pytest.raises(SceneError, match=re.escape("'lyapunov.center'")):
        parse_scene(LYAP_FD.replace("center = [0.0, 0.0]", "center = [10.0, 0.0]"))


def test_frequency_diffusion_refuses_the_negative_direction():
    text = LYAP_FD.replace("tol = 1e-12", "tol = 1e-12\ndirection = -1", 1)
    with pytest.raises(SceneError, match="'integration.direction'"):
        parse_scene(text)


def test_unused_settings_do_not_change_panel_hashes():
    base = _hashes(SWEEP_SCENE)
    # dt is unused by taylor; seed unused by grid; default tmax written out; int vs float
    same = SWEEP_SCENE.replace("tol = 1e-12", "tol = 1e-12\ndt = 0.01\ntmax = 100000\n") + \
        "[seeds]\nseed = 7\n[energy]\nh = 2\n"
    assert _hashes(same) == base


def test_panel_settings_are_json_plain_and_describe_the_panel():
    import json
    s = parse_scene(SWEEP_SCENE)
    st = s.panel_settings(1)
    assert json.loads(json.dumps(st)) == st
    assert st["params"]["mu"] == 0.5 and st["h"] == 2.0 and st["integration"]["tol"] == 1e-12
    assert "dt" not in st["integration"] and st["seeds"] == {"kind": "grid", "n": 200, "margin": 0.98}


def test_panel_seeds_use_the_panel_parameters_and_phi0():
    s = parse_scene(SWEEP_SCENE + "phi0 = 1.0\n")
    for i in range(s.n_panels):
        prm, h, _ = s.panel(i)
        got = s.panel_seeds(i)
        want = seed_points(s.seeds, prm, h, 1.0)
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])


def test_seeds_placed_on_a_section_map_lie_strictly_inside_its_allowed_region():
    from explorer.analysis.section_map import SectionMap

    smap = SectionMap(model.FIGURE4.with_(mu=0.03), 2.0)
    pts = SeedSpec(n=50).points_on(smap)
    assert 40 <= len(pts) <= 50 and smap.allowed(pts).all()      # about n points of a grid in the ellipse
    inside, outside = (0.1, 0.0), (50.0, 50.0)
    given = SeedSpec(kind="points", points=(inside, outside)).points_on(smap)
    assert given.tolist() == [list(inside)]                  # a given point outside the region is left out
