"""What a sweep rerun recomputes and what a sweep prints (issue 25 items 3, 5, 7; issue 20 item 3).

Sections and indicators of a panel are separate products, each with its own hash; the figure
records its drawing settings; the map grid seeds only the indicators; dropped seeds are counted."""
import h5py
import numpy as np
import pytest

from explorer import model
from explorer.app import cli
from explorer.app.runner import FIGURE_SETTINGS_KEY, format_report, run_sweep
from explorer.io import store

BOTH = """
name = "both"
[sweep]
parameter = "mu"
values = [0.1, 0.6]
[seeds]
kind = "grid"
n = 12
[integration]
tol = 1e-12
crossings = 6
tmax = 200.0
[compute]
sections = true
lyapunov = true
[lyapunov]
time = 60.0
"""


def scene_file(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def run(tmp_path, text, out, **kw):
    kw.setdefault("draw", False)
    return run_sweep(scene_file(tmp_path, text), out, progress=False, **kw)


def panel_arrays(path, names):
    data = store.read_store(path)
    return {i: {k: (pd.crossings if k == "crossings" else pd.extra[k]).copy() for k in names}
            for i, pd in data.panels.items()}


def test_a_changed_figure_setting_redraws_the_figure_without_recomputing(tmp_path):
    text = BOTH.replace("lyapunov = true", "lyapunov = false")
    out, stem = tmp_path / "b.h5", tmp_path / "fig"
    first = run(tmp_path, text, out, figure=stem, draw=True)
    assert first.figure and first.computed == (0, 1)
    same = run(tmp_path, text, out, figure=stem, draw=True)
    assert same.computed == () and same.figure == ()            # nothing changed: nothing redrawn
    bigger = run(tmp_path, text + "[figure]\nmarker_size = 3.0\n", out, figure=stem, draw=True)
    assert bigger.computed == () and bigger.crossings == 0      # nothing recomputed ...
    assert stem.with_suffix(".png") in bigger.figure            # ... but the figure is redrawn
    from explorer.app.figures import png_text

    assert '"marker_size":3.0' in png_text(stem.with_suffix(".png"), FIGURE_SETTINGS_KEY)
    assert run(tmp_path, text + "[figure]\nmarker_size = 3.0\n", out, figure=stem, draw=True).figure == ()


def test_a_changed_lyapunov_time_recomputes_only_the_indicators_and_new_crossings_keep_them(tmp_path):
    out = tmp_path / "b.h5"
    first = run(tmp_path, BOTH, out)
    assert first.products == {"sections": (0, 1), "indicators": (0, 1)}
    before = panel_arrays(out, ("crossings", "megno"))
    longer = run(tmp_path, BOTH.replace("time = 60.0", "time = 90.0"), out)
    assert longer.products == {"sections": (), "indicators": (0, 1)} and longer.crossings == 0
    after = panel_arrays(out, ("crossings", "megno"))
    for i in (0, 1):
        np.testing.assert_array_equal(after[i]["crossings"], before[i]["crossings"])
        assert not np.array_equal(after[i]["megno"], before[i]["megno"])
    text = BOTH.replace("time = 60.0", "time = 90.0").replace("crossings = 6", "crossings = 8")
    more = run(tmp_path, text, out)
    assert more.products == {"sections": (0, 1), "indicators": ()} and more.indicator_orbits == 0
    final = panel_arrays(out, ("crossings", "megno"))
    data = store.read_store(out)
    for i in (0, 1):
        np.testing.assert_array_equal(final[i]["megno"], after[i]["megno"])    # kept, not recomputed
        assert len(final[i]["crossings"]) > len(after[i]["crossings"])
        assert data.panels[i].attrs["hash"] == more_scene_hash(text, i)        # the panel is whole
        assert "chaotic_fraction" in data.panels[i].attrs
    assert run(tmp_path, text, out).computed == ()


def more_scene_hash(text, i):
    from explorer.io.scene import parse_scene

    return parse_scene(text).panel_hash(i)


def test_a_store_with_one_hash_per_panel_is_read_as_whole_when_that_hash_matches(tmp_path):
    """A store written before products had their own hashes (attribute ``hash`` only)."""
    out = tmp_path / "old.h5"
    run(tmp_path, BOTH, out)
    with h5py.File(out, "r+") as f:
        for grp in f["panels"].values():
            del grp.attrs["sections_hash"], grp.attrs["indicators_hash"]
    assert run(tmp_path, BOTH, out).computed == ()        # nothing rewritten: still one hash a panel
    changed = run(tmp_path, BOTH.replace("time = 60.0", "time = 90.0"), out)
    assert changed.products == {"sections": (0, 1), "indicators": (0, 1)}   # one hash: cannot tell which


def test_the_map_grid_seeds_the_indicators_and_the_sections_keep_the_scene_seeds(tmp_path):
    out = tmp_path / "m.h5"
    text = BOTH.replace("time = 60.0", "time = 30.0\nmap_resolution = 10")
    rep = run(tmp_path, text, out, figure=tmp_path / "m", draw=True)
    assert rep.computed == (0, 1)
    data = store.read_store(out)
    for i in (0, 1):
        pd = data.panels[i]
        prm, h = model.FIGURE4.with_(mu=(0.1, 0.6)[i]), 2.0
        assert 8 <= pd.n_orbits <= 16                              # [seeds] n = 12, not the 10 x 10 grid
        grid = pd.extra["lyapunov_seeds"]
        assert 50 < len(grid) <= 100 and pd.extra["megno"].shape == (len(grid),)
        assert np.all(model.section_M2(prm, grid[:, 0], grid[:, 1], h, np.pi) > 0)
        assert pd.attrs["map_resolution"] == 10
    assert (tmp_path / "m_map.png").exists()
    assert run(tmp_path, text, out).computed == ()


@pytest.mark.parametrize("compute,orbits", [("", "orbits 1,"),
                                            ("[compute]\nsections = false\nlyapunov = true\n[lyapunov]\ntime = 20.0\n",
                                             "chaos indicators of 1 orbits")])
def test_seeds_outside_the_allowed_region_are_counted_printed_and_stored(tmp_path, capsys, compute, orbits):
    text = ('name = "pts"\n[seeds]\nkind = "points"\npoints = [[5.0, 0.0], [0.0, 0.0]]\n'
            "[integration]\ncrossings = 3\n" + compute)
    out = tmp_path / "p.h5"
    code = cli.main(["sweep", str(scene_file(tmp_path, text)), "--out", str(out), "--no-figure", "--quiet"])
    stdout = capsys.readouterr().out
    assert code == 0 and orbits in stdout
    assert "seeds outside the allowed region (dropped, not integrated): 1" in stdout
    assert store.read_store(out).panels[0].attrs["seeds_dropped"] == 1


def test_an_indicator_only_sweep_prints_the_measured_indicator_energy_error(tmp_path):
    text = BOTH.replace("sections = true", "sections = false")
    rep = run(tmp_path, text, tmp_path / "i.h5")
    report = format_report(rep)
    assert "over all crossings" not in report and "crossings" not in report
    assert rep.indicator_orbits == sum(store.read_store(tmp_path / "i.h5").panels[i].n_orbits for i in (0, 1))
    assert 0.0 < rep.indicator_dh < 1e-8          # measured (never exactly 0 after a T = 60 integration)
    assert f"energy error at the end of the indicator integrations max |H - H0| {rep.indicator_dh:.1e}" in report


@pytest.mark.parametrize("parameter,label", [("mu", r"$\mu$"), ("h", "$h$"), ("a1", "$a_1$"), ("other", "other")])
def test_the_fraction_plot_labels_its_axis_with_the_parameter_symbol(parameter, label):
    from explorer.app.figures import fraction_curve

    fig = fraction_curve([0.0, 0.5, 1.0], [0.1, 0.2, 0.3], [0.01, 0.01, 0.01], parameter=parameter)
    assert fig.axes[0].get_xlabel() == label


@pytest.mark.parametrize("mu,expect", [(0.0, "(p1/2)^2 + (p2/1.41421)^2"), (0.5, "((p1 + 0.5)/2.06155)^2")])
def test_the_allowed_region_is_printed_with_each_sign_once(mu, expect):
    text = model.describe_region(model.FIGURE4.with_(mu=mu), 2.0)
    assert expect in text and "- -" not in text and "-0)" not in text and "+ -" not in text


@pytest.mark.parametrize("command", [["fixedpoint"], ["periodic", "-K", "1"]])
def test_continuation_prints_the_parameter_without_binary_round_off(command, capsys):
    """0 + 3 x 0.1 is 0.30000000000000004 in binary: printed as 0.3 (10 significant digits)."""
    assert cli.main(command + ["--guess", "0,0", "--continue", "mu", "0", "0.3", "0.1"]) == 0
    rows = capsys.readouterr().out.splitlines()[1:5]
    assert [r.split(",")[0] for r in rows] == ["0", "0.1", "0.2", "0.3"]


def test_every_command_and_scene_table_has_the_same_default_splitting_step():
    from explorer.io.scene import IntegrationSpec, LyapunovSpec

    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices
    defaults = {name: sub[name].get_default("dt") for name in ("orbit", "lyapunov")}
    assert defaults["orbit"] == defaults["lyapunov"] == IntegrationSpec().dt == LyapunovSpec().dt


def test_streamed_sections_keep_the_stored_indicators_and_equal_unstreamed_ones(tmp_path, monkeypatch):
    """New crossings of a streamed panel (rows written block by block) keep the stored indicators."""
    from explorer.analysis import sweep

    text = BOTH.replace("crossings = 6", "crossings = 300").replace("tmax = 200.0", "tmax = 3000.0")
    plain, streamed = tmp_path / "plain.h5", tmp_path / "streamed.h5"
    run(tmp_path, text.replace("crossings = 300", "crossings = 600"), plain)
    run(tmp_path, text, streamed)
    before = panel_arrays(streamed, ("megno",))
    monkeypatch.setattr(sweep, "STREAM_BYTES", 300 * 16 * 40)   # 600 crossings: blocks of 300
    rep = run(tmp_path, text.replace("crossings = 300", "crossings = 600"), streamed)
    assert rep.products == {"sections": (0, 1), "indicators": ()}
    data, ref = store.read_store(streamed), store.read_store(plain)
    for i in (0, 1):
        assert data.panels[i].attrs["block"] < 600                      # it was streamed
        np.testing.assert_array_equal(data.panels[i].crossings, ref.panels[i].crossings)
        np.testing.assert_array_equal(data.panels[i].extra["megno"], before[i]["megno"])
        np.testing.assert_array_equal(data.panels[i].extra["megno"], ref.panels[i].extra["megno"])


@pytest.mark.parametrize("old,new,changed", [
    ("time = 60.0", "time = 61.0", {"indicators"}),
    ("time = 60.0", "time = 60.0\nmap_resolution = 20", {"indicators"}),
    ("time = 60.0", "time = 60.0\nthreshold = 3.0", set()),
    ("crossings = 6", "crossings = 7", {"sections"}),
    ("tol = 1e-12", "tol = 1e-11", {"sections"}),
    ("n = 12", "n = 13", {"sections", "indicators"}),
    ("values = [0.1, 0.6]", "values = [0.2, 0.6]", {"sections", "indicators"}),
    ("[lyapunov]", "separatrices = true\n[lyapunov]", {"sections"}),
    ("time = 60.0", "time = 60.0\n[figure]\nmarker_size = 2.0\ndpi = 100", set()),
])
def test_each_product_hash_changes_exactly_with_its_own_settings(old, new, changed):
    from explorer.io.scene import parse_scene

    a, b = parse_scene(BOTH), parse_scene(BOTH.replace(old, new))
    differ = {k for k, v in a.product_hashes(0).items() if b.product_hashes(0)[k] != v}
    assert differ == changed
    figure_changed = a.figure_settings() != b.figure_settings()
    assert figure_changed == ("marker_size" in new or "threshold" in new)


def test_update_panel_replaces_the_indicators_keeps_the_crossings_and_does_not_grow(tmp_path):
    path = tmp_path / "s.h5"
    rng = np.random.default_rng(1)
    n, k = 30, 400
    data = rng.normal(size=(n, k, 5))
    arrays = {"seeds": rng.normal(size=(n, 2)), "y0": rng.normal(size=(n, 5)), "count": np.full(n, k),
              "status": np.zeros(n, np.int8), "final": rng.normal(size=(n, 5)), "info": rng.normal(size=(n, 3)),
              "data": data, "megno": np.full(n, 2.0), "sali": np.ones(n)}
    store.commit_panel(path, 0, arrays, {"settings": {"a": 1}, "chaotic_fraction": 0.5}, {"scene_name": "t"})
    rows = store.read_store(path).panels[0].crossings.copy()
    sizes = []
    for j in range(3):
        grid = rng.normal(size=(50, 2))
        store.update_panel(path, 0, {"megno": np.full(50, 3.0 + j), "lyapunov_seeds": grid},
                           {"chaotic_fraction": 0.1 * j}, remove=("sali",))
        sizes.append(path.stat().st_size)
        pd = store.read_store(path).panels[0]
        np.testing.assert_array_equal(pd.crossings, rows)
        assert pd.extra["megno"].shape == (50,) and pd.extra["megno"][0] == 3.0 + j and "sali" not in pd.extra
        assert pd.attrs["chaotic_fraction"] == 0.1 * j and pd.attrs["settings"] == '{"a":1}' and pd.complete
    assert sizes[2] <= sizes[0] * 1.01
    before = path.read_bytes()
    with pytest.raises(ValueError, match=r"megno must have shape \(50,\)"):
        store.update_panel(path, 0, {"megno": np.ones(30)}, {})          # 30 rows for the 50 kept grid seeds
    with pytest.raises(ValueError, match="replaces only"):
        store.update_panel(path, 0, {"crossings": rows}, {})
    assert path.read_bytes() == before


def test_a_panel_whose_file_was_lost_is_recomputed_alone_and_a_format_1_store_is_continued(tmp_path):
    """Store format 2 (docs/store.md): the rerun of a sweep whose store lost one panel file computes
    that panel only (the MEGNO threshold changed too: the other panel's fraction is restamped from
    its stored indicators); a format-1 store (every panel inside the one file) is continued and
    converted."""
    out = tmp_path / "b.h5"
    run(tmp_path, BOTH, out)
    before = panel_arrays(out, ("crossings", "megno"))
    with h5py.File(out, "r") as f:
        lost = f["panels"].get("001", getlink=True).filename
    (tmp_path / lost).unlink()
    again = run(tmp_path, BOTH + "threshold = 3.0\n", out)
    assert again.computed == (1,) and again.restamped == (0,)
    after = panel_arrays(out, ("crossings", "megno"))
    for k in ("crossings", "megno"):
        np.testing.assert_array_equal(after[0][k], before[0][k])
        np.testing.assert_array_equal(after[1][k], before[1][k])    # the same numbers, computed again
    assert store.read_store(out).panels[0].attrs["class_threshold"] == 3.0

    old = tmp_path / "old.h5"                 # the same store in format 1
    with h5py.File(out, "r") as s, h5py.File(old, "w") as d:
        d.attrs.update(s.attrs)
        d.attrs["format_version"] = 1
        panels = d.create_group("panels")
        for name in s["panels"]:
            s.copy(s["panels"][name], panels, name=name)
    assert run(tmp_path, BOTH + "threshold = 3.0\n", old).computed == ()
    rep = run(tmp_path, BOTH.replace("values = [0.1, 0.6]", "values = [0.1, 0.6, 0.9]") + "threshold = 3.0\n", old)
    assert rep.computed == (2,)
    data = store.read_store(old)
    assert data.attrs["format_version"] == store.FORMAT_VERSION and sorted(data.panels) == [0, 1, 2]
    np.testing.assert_array_equal(data.panels[1].crossings, before[1]["crossings"])


ADAPTIVE = """
name = "adaptive"
[sweep]
parameter = "mu"
values = [0.03, 0.01]
[compute]
sections = false
lyapunov = true
[lyapunov]
time = 40.0
map_resolution = 24
"""


def test_an_interrupted_adaptive_map_stores_no_half_panel_and_the_rerun_equals_an_uninterrupted_run(tmp_path,
                                                                                                 monkeypatch):
    """docs/scenes.md, "Adaptive maps": a map panel is committed whole (mask beside the values) or
    not at all; a Ctrl-C in the middle of panel 1's refinement keeps panel 0, and the rerun
    computes panel 1 alone, to the same numbers as a run that was never interrupted."""
    from explorer.analysis import sweep
    from explorer.app.interrupt import Interrupted

    monkeypatch.setattr(sweep, "MAP_COARSE", 4)
    ref = run(tmp_path, ADAPTIVE, tmp_path / "ref.h5")
    assert len(ref.map_cells) == 2
    assert all(0 < done < cells for _label, done, cells in ref.map_cells)
    assert "map cells computed" in format_report(ref)
    want = panel_arrays(tmp_path / "ref.h5", ("megno", "map_computed"))
    for i, (_label, done, cells) in enumerate(ref.map_cells):
        assert want[i]["map_computed"].sum() == done and len(want[i]["megno"]) == cells
    calls = []
    ask = sweep._MapCells._compute    # every batch of cells an adaptive map computes

    def interrupted_in_panel_1(self, y0, **kw):
        calls.append(self.panel.index)
        if self.panel.index == 1 and calls.count(1) == 2:   # panel 1's second level
            raise KeyboardInterrupt
        return ask(self, y0, **kw)

    monkeypatch.setattr(sweep._MapCells, "_compute", interrupted_in_panel_1)
    out = tmp_path / "cut.h5"
    with pytest.raises(Interrupted):
        run(tmp_path, ADAPTIVE, out)
    assert sorted(store.panel_product_hashes(out)) == [0]          # panel 1: nothing of it stored
    monkeypatch.setattr(sweep._MapCells, "_compute", ask)
    assert run(tmp_path, ADAPTIVE, out).computed == (1,)
    got = panel_arrays(out, ("megno", "map_computed"))
    for i in (0, 1):
        for k in ("megno", "map_computed"):
            np.testing.assert_array_equal(got[i][k], want[i][k], err_msg=f"panel {i} {k}")
