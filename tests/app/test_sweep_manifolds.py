"""[manifolds] in a scene: W^u and W^s drawn over each panel of a sweep's section figure, drawing
only (the figure's settings change, no product hash does), and bad values refused."""
import numpy as np
import pytest

from explorer.app import figures
from explorer.app.runner import FIGURE_SETTINGS_KEY, panel_manifolds, run_sweep
from explorer.io.scene import SceneError, parse_scene

SCENE = """
name = "wm"
[model]
mu = 0.03
[seeds]
kind = "grid"
n = 6
[integration]
tol = 1e-12
crossings = 3
tmax = 100.0
"""
DRAW = "[manifolds]\ndraw = true\narclength = 2.0\n"


def _rgb(hex_colour):
    return np.array([int(hex_colour[k:k + 2], 16) for k in (1, 3, 5)], float) / 255.0


def _pixels_near(png, hex_colour, tol=0.12):
    import matplotlib.image as mpimg

    img = mpimg.imread(png)[..., :3]
    return int(np.count_nonzero(np.linalg.norm(img - _rgb(hex_colour), axis=-1) < tol))


def test_manifold_keys_change_the_figure_settings_and_no_hash_of_the_numbers():
    plain, drawn = parse_scene(SCENE), parse_scene(SCENE + DRAW)
    assert drawn.manifolds.draw and drawn.manifolds.arclength == 2.0
    assert plain.product_hashes(0) == drawn.product_hashes(0) and plain.panel_hash(0) == drawn.panel_hash(0)
    assert plain.figure_settings() != drawn.figure_settings()
    longer = parse_scene(SCENE + DRAW.replace("2.0", "3.0"))
    assert longer.figure_settings() != drawn.figure_settings()
    # not drawn: its other keys change nothing (figures of scenes without [manifolds] keep their settings)
    idle = parse_scene(SCENE + "[manifolds]\narclength = 3.0\nperiod = 2\n")
    assert idle.figure_settings() == plain.figure_settings()
    assert parse_scene(drawn.to_toml()).manifolds == drawn.manifolds


def test_a_sweep_with_manifolds_redraws_without_recomputing_and_draws_both_colours(tmp_path):
    out, stem = tmp_path / "s.h5", tmp_path / "fig"
    (tmp_path / "a.toml").write_text(SCENE)
    (tmp_path / "b.toml").write_text(SCENE + DRAW)
    first = run_sweep(tmp_path / "a.toml", out, figure=stem, draw=True, progress=False)
    png = stem.with_suffix(".png")
    assert first.computed == (0,) and png in first.figure
    before = {c: _pixels_near(png, figures.MANIFOLD_COLORS[c]) for c in ("unstable", "stable")}
    second = run_sweep(tmp_path / "b.toml", out, figure=stem, draw=True, progress=False)
    assert second.computed == () and second.crossings == 0        # the sections are not recomputed ...
    assert png in second.figure                                    # ... the figure is redrawn
    after = {c: _pixels_near(png, figures.MANIFOLD_COLORS[c]) for c in ("unstable", "stable")}
    for c in ("unstable", "stable"):
        assert after[c] > before[c] + 100, (c, before, after)
    assert '"manifolds"' in figures.png_text(png, FIGURE_SETTINGS_KEY)
    assert run_sweep(tmp_path / "b.toml", out, figure=stem, draw=True, progress=False).figure == ()


def test_panel_manifolds_are_branches_of_the_saddle_and_say_why_when_there_are_none():
    s = parse_scene(SCENE + DRAW)
    branches, note = panel_manifolds(s, 0)
    assert note == "" and sorted(k for k, _ in branches) == ["stable"] * 2 + ["unstable"] * 2
    start = {tuple(np.round(b[0], 12)) for _, b in branches}
    assert len(start) == 1                                         # all four leave the same saddle
    for _, b in branches:
        assert 2.0 <= np.sum(np.linalg.norm(np.diff(b, axis=0), axis=1)) < 2.1
    far = parse_scene(SCENE + DRAW + "guess = [40.0, 40.0]\n")     # Newton cannot start there
    branches, note = panel_manifolds(far, 0)
    assert branches == [] and note.startswith("no manifolds: ")


def test_section_panels_draw_each_branch_in_its_colour():
    from explorer import model

    line = np.array([[0.0, 0.0], [0.5, 0.1]])
    fig = figures.section_panels([{"points": None, "params": model.FIGURE4, "h": 2.0,
                                   "manifolds": [("unstable", line), ("stable", -line)]}])
    got = {ln.get_gid(): ln.get_color() for ln in fig.axes[0].lines if ln.get_gid()}
    assert got == {"manifold-unstable": figures.MANIFOLD_COLORS["unstable"],
                   "manifold-stable": figures.MANIFOLD_COLORS["stable"]}
    with pytest.raises(ValueError, match="manifold 0"):
        figures.section_panels([{"points": None, "params": model.FIGURE4, "h": 2.0, "manifolds": [("neither", line)]}])


@pytest.mark.parametrize("text, key", [
    ("draw = 1", "manifolds.draw"), ("arclength = 0.0", "manifolds.arclength"),
    ("guess = [0.0]", "manifolds.guess"), ("period = 0", "manifolds.period"),
    ("max_points = 2", "manifolds.max_points"), ("color = 'red'", "manifolds.color")])
def test_bad_manifold_values_are_refused_naming_the_key(text, key):
    with pytest.raises(SceneError, match=key.replace(".", r"\.")):
        parse_scene(SCENE + "[manifolds]\n" + text + "\n")


def test_an_atlas_scene_refuses_drawn_manifolds():
    atlas = parse_scene("name = 'a'\n[sweep]\nparameter = 'mu'\nvalues = [0.1]\n[atlas]\nparameter = 'h'\n"
                        "values = [2.0]\n[compute]\nsections = false\nlyapunov = true\n")
    assert atlas.is_atlas
    assert "draw = false" in atlas.to_toml()
    with pytest.raises(SceneError, match="manifolds.draw"):
        parse_scene(atlas.to_toml().replace("draw = false", "draw = true"))
