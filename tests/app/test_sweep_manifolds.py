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


# A System's scene (docs/scenes.md, "A scene of your own system"): Hénon–Heiles on x = 0 at E = 1/8
SYSTEM_SCENE = """
name = "hh_curves"
section = "x"
coords = ["y", "py"]
solve = "px"
[energy]
value = 0.125
[seeds]
kind = "points"
points = [[0.1, 0.1], [0.3, 0.0]]
[integration]
crossings = 20
"""
SADDLE_GUESS = (0.3, 0.3)
CURVES = f"[compute]\nseparatrices = true\n[manifolds]\ndraw = true\nguess = {list(SADDLE_GUESS)}\narclength = 0.5\n"


def _system_scene(text):
    from systems import henon_heiles

    return parse_scene(text, system=henon_heiles())


@pytest.fixture(scope="module")
def hh_curves():
    from explorer.app.system_sweep import panel_curves

    scene = _system_scene(SYSTEM_SCENE + CURVES)
    return scene, panel_curves(scene, 0)


def _distance_to_polyline(points, line):
    a, b = line[:-1], line[1:]
    d = b - a
    out = []
    for p in points:
        t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.einsum("ij,ij->i", d, d), 0.0, 1.0)
        out.append(np.min(np.linalg.norm(a + t[:, None] * d - p, axis=1)))
    return np.array(out)


def test_a_system_scenes_separatrices_and_manifolds_change_its_figure_settings_and_no_hash():
    plain, drawn = _system_scene(SYSTEM_SCENE), _system_scene(SYSTEM_SCENE + CURVES)
    assert drawn.separatrices and drawn.manifolds.draw and drawn.manifolds.guess == SADDLE_GUESS
    assert plain.product_hashes(0) == drawn.product_hashes(0) and plain.panel_hash(0) == drawn.panel_hash(0)
    assert '"separatrices":true' in drawn.figure_settings() and '"manifolds"' in drawn.figure_settings()
    assert plain.figure_settings() == _system_scene(SYSTEM_SCENE + "[manifolds]\narclength = 3.0\n").figure_settings()


def test_a_system_panels_separatrices_leave_its_hyperbolic_fixed_points_and_are_invariant(hh_curves):
    scene, drawn = hh_curves
    smap = scene.section_map(0)
    curves = drawn["curves"]
    assert "note" not in drawn and len(curves) % 4 == 0 and len(curves) >= 8
    saddles = np.array([c[0] for c in curves[::4]])
    for k, x in enumerate(saddles):
        assert all(np.array_equal(c[0], x) for c in curves[4 * k:4 * k + 4])   # four branches from one point
        res = smap(x)
        assert np.linalg.norm(res.point - x) < 1e-10 and abs(np.trace(res.jacobian)) > 2.0
    # Hénon–Heiles is reversible, (y, py) -> (y, -py) on x = 0, and has threefold symmetry: the
    # saddles come in mirror pairs (or lie on py = 0) and their orbits share one trace
    mirrored = saddles * [1.0, -1.0]
    assert all(np.min(np.linalg.norm(saddles - m, axis=1)) < 1e-8 for m in mirrored)
    traces = [np.trace(smap(x).jacobian) for x in saddles]
    assert np.ptp(traces) < 1e-8 * abs(traces[0])
    # a branch of W^u holds the preimages of its points, one of W^s the images (both nearer the saddle)
    for c, backward in ((curves[0], True), (curves[2], False)):
        pts = c[len(c) // 4:len(c) // 2:max(1, len(c) // 40)]
        img = smap.images(pts, 1, backward=backward)[:, 0]
        assert np.max(_distance_to_polyline(img, c)) < 1e-4


def test_a_system_panels_manifolds_are_the_branches_of_the_orbit_newton_finds_from_the_guess(hh_curves):
    _scene, drawn = hh_curves
    branches = drawn["manifolds"]
    assert sorted(k for k, _ in branches) == ["stable"] * 2 + ["unstable"] * 2
    assert len({tuple(b[0]) for _, b in branches}) == 1
    assert np.linalg.norm(branches[0][1][0] - SADDLE_GUESS) < 0.01
    for _, b in branches:
        assert 0.5 <= np.sum(np.linalg.norm(np.diff(b, axis=0), axis=1)) < 0.55


def test_a_system_sweep_draws_the_manifolds_over_its_section_and_says_why_there_are_none(tmp_path):
    scene = _system_scene(SYSTEM_SCENE + CURVES.replace("separatrices = true", "separatrices = false"))
    stem = tmp_path / "hh"
    report = run_sweep(scene, tmp_path / "hh.h5", figure=stem, progress=False)
    png = stem.with_suffix(".png")
    assert png in report.figure and '"manifolds"' in figures.png_text(png, FIGURE_SETTINGS_KEY)
    assert _pixels_near(png, figures.MANIFOLD_COLORS["stable"]) > 100
    from explorer.app.system_sweep import panel_curves

    elliptic = _system_scene(SYSTEM_SCENE + "[manifolds]\ndraw = true\nguess = [0.0, 0.0]\n")
    assert panel_curves(elliptic, 0) == {"note": "no manifolds: the orbit is not hyperbolic"}
