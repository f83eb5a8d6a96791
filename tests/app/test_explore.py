"""explorer.explore: the interactive explorer, driven headless (Agg canvas, synthesised mouse
and key events, the timer callback called by hand) and the command's no-display path."""
import math
import os
import subprocess
import sys

import matplotlib  # a run-time dependency: missing it is a failure, not a skip
import numpy as np
import pytest

matplotlib.use("Agg")
from matplotlib.backend_bases import KeyEvent, MouseEvent  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from explorer import model
from explorer.analysis import sections
from explorer.app import cli, explore
from explorer.io import store  # noqa: E402

H = model.FIGURE4_H
MU_CHAOTIC = model.FIGURE4.with_(mu=0.5)     # (0.3, 0.1) lies in the chaotic sea (<Y> ~ 66 at t = 1000)
MU_REGULAR = model.FIGURE4.with_(mu=0.002)   # (0.2, 0.75) lies on an invariant curve (<Y> ~ 1.9)


def make(params=MU_CHAOTIC, h=H, tmp_path=None, **kw):
    kw.setdefault("indicators", False)  # the tangent kernels are tested in test_lyapunov
    fig = Figure(figsize=explore.FIGSIZE)
    FigureCanvasAgg(fig)
    ex = explore.Explorer(params, h, fig=fig, out_dir=str(tmp_path or "."), **kw)
    fig.canvas.draw()  # final axes positions (equal aspect) before events are synthesised
    return ex


def click(ex, p1, p2, button=1):
    """A real button-press event at data point (p1, p2), through the canvas's callbacks."""
    x, y = ex.ax.transData.transform((p1, p2))
    ev = MouseEvent("button_press_event", ex.fig.canvas, x, y, button=button)
    ex.fig.canvas.callbacks.process("button_press_event", ev)
    return ev


def key(ex, k):
    ev = KeyEvent("key_press_event", ex.fig.canvas, k, 10, 10)
    ex.fig.canvas.callbacks.process("key_press_event", ev)


def run_timer(ex, limit=10_000):
    """Call the timer's callbacks (what the GUI event loop does) until nothing runs."""
    ticks = 0
    while ex.running and ticks < limit:
        for func, args, kwargs in ex._timer.callbacks:
            func(*args, **kwargs)
        ticks += 1
    assert not ex.running
    return ticks


@pytest.mark.parametrize("method,params,seed,extra", [
    ("taylor", MU_CHAOTIC, (0.3, 0.1), {"tol": 1e-13}),
    ("dop853", MU_REGULAR, (0.2, 0.75), {"tol": 1e-12}),
    ("split4", MU_REGULAR, (0.2, 0.75), {"dt": 0.05}),
])
def test_click_inside_draws_the_crossings_of_section_crossings(tmp_path, method, params, seed, extra):
    K, chunk = 45, 10  # 4 full chunks and a partial one
    ex = make(params, tmp_path=tmp_path, method=method, chunk=chunk, max_crossings=K, **extra)
    click(ex, *seed)
    assert len(ex.orbits) == 1 and len(ex.seeds) == 1
    orbit = ex.orbits[0]
    p1, p2 = orbit.seed
    assert abs(p1 - seed[0]) < 1e-2 and abs(p2 - seed[1]) < 1e-2  # the click, through the transforms
    ticks = run_timer(ex)
    assert ticks == math.ceil(K / chunk)
    got = orbit.crossings
    ref = sections.section_crossings(params, [p1], [p2], H, K, method=method, **extra).orbit(0)
    assert got.shape == ref.shape == (K, 5)
    assert orbit.main.status == 0 and not orbit.running
    # Time is continuous across chunks (absolute, increasing, one crossing per return).
    assert np.all(np.diff(got[:, 0]) > 0)
    # Each chunk restarts sections.crossings from the state where the previous one stopped,
    # with time reset to 0 and dH measured from the chunk's start; the explorer adds both back.
    # Taylor's step size depends on the state alone and the splitting step is fixed, so the
    # chunked states are those of one long run and only the time sum is split (round-off);
    # DOP853's step-size controller restarts at each chunk, which changes the steps by
    # round-off-sized amounts (on a regular orbit the differences stay tiny).  Hence 1e-9.
    np.testing.assert_allclose(got[:, :4], ref[:, :4], rtol=0, atol=1e-9)
    np.testing.assert_allclose(got[:, 4], ref[:, 4], rtol=0, atol=1e-11)
    # the drawn points are the crossings
    x, y = ex.view.lines[orbit.number].get_data()
    np.testing.assert_array_equal(np.column_stack([x, y]), got[:, 1:3])
    first, _msg = ex.status_lines()
    assert f"{K}/{K} crossings" in first and "max|dH|" in first


def test_click_outside_the_region_adds_nothing_and_says_why(tmp_path):
    ex = make(tmp_path=tmp_path)
    c1, c2, r1, r2 = model.allowed_ellipse(ex.params, ex.h)
    x0, x1 = ex.ax.get_xlim()
    y0, y1 = ex.ax.get_ylim()
    p1, p2 = x0 + 0.01 * (x1 - x0), y1 - 0.01 * (y1 - y0)  # a gray corner of the axes
    assert model.section_M2(ex.params, p1, p2, ex.h) < 0
    click(ex, p1, p2)
    assert ex.orbits == [] and ex.seeds == []
    assert "outside the allowed region" in ex.message and "M^2" in ex.message
    assert "outside the allowed region" in ex.status_text.get_text()
    assert not ex.running
    # clicks outside the section axes (widgets, margins) and other buttons do nothing
    click(ex, c1, c2, button=3)
    assert ex.orbits == []


def test_changing_mu_redraws_the_region_and_keeps_the_seeds(tmp_path):
    ex = make(tmp_path=tmp_path, chunk=5, max_crossings=20)
    c1, c2, r1, r2 = model.allowed_ellipse(ex.params, ex.h)
    inner, outer = (c1 + 0.1 * r1, c2), (c1 - 0.95 * r1, c2)
    click(ex, *inner)
    click(ex, *outer)
    ex.step()  # running, part of the crossings drawn
    assert ex.running and len(ex.orbits) == 2
    width0, center0 = ex.region_patch.get_width(), ex.region_patch.get_center()

    ex.mu_slider.set_val(1.0)  # the slider's own callback path
    e = model.allowed_ellipse(ex.params, ex.h)
    assert ex.params.mu == 1.0
    assert ex.region_patch.get_width() == pytest.approx(2 * e[2]) != pytest.approx(width0)
    assert tuple(ex.region_patch.get_center()) == pytest.approx((e[0], e[1]))
    assert tuple(ex.region_patch.get_center()) != pytest.approx(tuple(center0))
    assert ex.boundary_patch.get_width() == ex.region_patch.get_width()
    assert ex.orbits == [] and not ex.running and len(ex.seeds) == 2
    assert "seeds kept" in ex.message and "mu = 1" in ex.ax.get_title().replace("\\mu", "mu").replace("$", "")

    # the outer seed (in p1 < c1) falls outside when the region shifts to negative p1 ... or not:
    # whichever seeds are admissible at mu = 1 are re-run, the others reported
    admissible = [model.is_admissible(ex.params, *s, ex.h) for s in ex.seeds]
    key(ex, "r")
    assert len(ex.orbits) == sum(admissible)
    assert [o.seed for o in ex.orbits] == [s for s, ok in zip(ex.seeds, admissible) if ok]
    run_timer(ex)
    assert all(o.main.count == 20 for o in ex.orbits)

    # an energy that drops the outer seed: reported, not run
    ex.set_param("h", 0.5)
    assert model.is_admissible(ex.params, *inner, 0.5) and not model.is_admissible(ex.params, *outer, 0.5)
    key(ex, "r")
    assert [o.seed for o in ex.orbits] == [ex.seeds[0]]
    assert ex.seeds[0] == pytest.approx(inner, abs=1e-2)  # the click, through the transforms
    assert "1 outside the allowed region" in ex.message
    assert len(ex.seed_bad_line.get_xdata()) == 1 and len(ex.seed_ok_line.get_xdata()) == 1


def test_text_box_sets_any_parameter_and_refuses_bad_values(tmp_path):
    ex = make(tmp_path=tmp_path)
    ex.textbox.set_val("a1=1.2, h=2.5")  # set_val submits, as Enter does
    assert ex.params.a1 == 1.2 and ex.h == 2.5 and ex.h_slider.val == 2.5
    assert "a1 = 1.2" in ex.message and "h = 2.5" in ex.message
    before = (ex.params, ex.h)
    ex.textbox.set_val("a1=-1")
    assert (ex.params, ex.h) == before and "a1 must be > 0" in ex.message
    ex.textbox.set_val("mu=0.1, nope=3")
    assert (ex.params, ex.h) == before and "unknown parameter 'nope'" in ex.message
    with pytest.raises(model.ParameterError):
        ex.set_param("lam", 0.0)
    ex.set_param("mu", 25.0)  # beyond the slider's range: the slider grows
    assert ex.mu_slider.valmax >= 25.0 and ex.mu_slider.val == 25.0


def test_key_w_writes_a_store_with_one_panel_of_the_orbits(tmp_path):
    ex = make(tmp_path=tmp_path, chunk=10, max_crossings=30)
    for p in ((0.3, 0.1), (-1.0, 0.4)):
        click(ex, *p)
    run_timer(ex)
    key(ex, "w")
    files = sorted(tmp_path.glob("explore-*.h5"))
    assert len(files) == 1, ex.message
    data = store.read_store(files[0])
    assert list(data.panels) == [0]
    panel = data.panels[0]
    assert panel.n_orbits == 2 and panel.complete
    np.testing.assert_array_equal(panel.count, [30, 30])
    np.testing.assert_array_equal(panel.status, [0, 0])
    for i, o in enumerate(ex.orbits):
        np.testing.assert_array_equal(panel.orbit(i), o.crossings)
        np.testing.assert_array_equal(panel.seeds[i], o.seed)
        np.testing.assert_array_equal(panel.y0[i], o.main.y0)
    assert panel.params == ex.params.as_dict() and panel.attrs["h"] == H
    assert panel.attrs["method"] == "taylor" and panel.attrs["crossings_requested"] == 30
    assert panel.settings["integration"]["chunk"] == 10
    assert "explore" in panel.attrs["label"]
    # an orbit still running is written with its crossings so far and a named status
    click(ex, 0.0, 0.0)
    ex.step()
    path = ex.save_h5(tmp_path / "running.h5")
    panel = store.read_store(path).panels[0]
    assert panel.status[-1] == explore.STATUS_RUNNING
    assert panel.status_names[explore.STATUS_RUNNING] == explore.RUNNING_NAME
    assert 0 < panel.count[-1] < 30


def test_key_s_saves_a_png_of_the_section(tmp_path):
    import matplotlib.image as mpimg

    ex = make(tmp_path=tmp_path, chunk=20, max_crossings=40)
    click(ex, 0.3, 0.1)
    run_timer(ex)
    key(ex, "s")
    files = list(tmp_path.glob("explore-*.png"))
    assert len(files) == 1, ex.message
    img = mpimg.imread(files[0])
    assert img.ndim == 3 and img.shape[0] > 300 and img.shape[1] > 300
    assert "saved" in ex.message
    assert not list(tmp_path.glob("*.tmp-*"))  # atomic write left nothing behind


def test_key_c_clears_orbits_and_seeds(tmp_path):
    ex = make(tmp_path=tmp_path)
    click(ex, 0.3, 0.1)
    key(ex, "c")
    assert ex.orbits == [] and ex.seeds == [] and not ex.running
    assert len(ex.ax.lines) == 2  # only the two seed markers remain (empty)


def test_keys_typed_into_the_text_box_are_not_commands(tmp_path):
    ex = make(tmp_path=tmp_path)
    click(ex, 0.3, 0.1)
    ex.textbox.begin_typing()
    key(ex, "c")
    assert len(ex.orbits) == 1
    ex.textbox.stop_typing()
    key(ex, "c")
    assert ex.orbits == []


def test_key_x_colours_by_megno(tmp_path):
    ex = make(MU_REGULAR, tmp_path=tmp_path, chunk=10, max_crossings=10, indicators=True)
    click(ex, 0.2, 0.75)
    run_timer(ex)
    o = ex.orbits[0]
    assert o.megno is not None and abs(o.megno - 2.0) < 0.3, o.indicator_note  # quasi-periodic: <Y> -> 2
    assert "regular-like" in ex.status_lines()[0]
    key(ex, "x")
    assert ex.color_by_indicator and ex.cax.get_visible()
    assert matplotlib.colors.to_rgba(ex.view.lines[o.number].get_color()) == pytest.approx(ex.cmap(ex.norm(o.megno)))
    key(ex, "x")
    own = matplotlib.colors.to_rgba(o.color)
    assert matplotlib.colors.to_rgba(ex.view.lines[o.number].get_color()) == pytest.approx(own)


def test_key_p_draws_separatrices_of_the_hyperbolic_point(tmp_path):
    ex = make(model.FIGURE4.with_(mu=0.03), tmp_path=tmp_path)
    key(ex, "p")
    assert ex.show_separatrices and "hyperbolic" in ex.message
    assert len(ex._sep_artists) >= 5  # 4 branches and a marker
    # a parameter change recomputes them once the parameters rest (timer); here by hand
    ex.set_param("mu", 0.05)
    assert ex._sep_artists == [] and "recomputing" in ex.message
    ex.refresh_separatrices()
    assert len(ex._sep_artists) >= 5 and "hyperbolic" in ex.message
    key(ex, "p")
    assert not ex.show_separatrices and ex._sep_artists == []


def test_key_o_marks_the_periodic_orbits_with_their_stability(tmp_path):
    ex = make(model.FIGURE4.with_(mu=0.03), tmp_path=tmp_path)
    key(ex, "o")
    assert ex.show_periodic and "K=1:" in ex.message and "K=4:" in ex.message
    n_markers = len([a for a in ex.view.periodic_artists if hasattr(a, "get_marker")])
    assert n_markers >= 10                                  # one marker line per orbit
    ex.set_param("mu", 0.05)
    assert not ex.show_periodic and ex.view.periodic_artists == [] and "press o" in ex.message
    key(ex, "o")
    key(ex, "o")
    assert not ex.show_periodic and ex.view.periodic_artists == []


def test_separatrix_polylines_are_broken_at_unresolved_jumps():
    c = np.array([[0.0, 0.0], [0.01, 0.0], [0.5, 0.0], [0.51, 0.0]])
    out = explore.break_jumps(c, 0.1)
    assert out.shape == (5, 2) and np.isnan(out[2]).all()
    np.testing.assert_array_equal(out[[0, 1, 3, 4]], c)


def test_from_args_takes_the_scene_panel_and_overrides(tmp_path):
    args = cli.build_parser().parse_args(["explore", "figure4", "--panel", "3", "--xi", "0.1",
                                          "--max-crossings", "100", "--out-dir", str(tmp_path)])
    fig = Figure()
    FigureCanvasAgg(fig)
    ex = explore.from_args(args, fig=fig)
    assert ex.params.mu == 4.0 and ex.params.xi == 0.1 and ex.h == 2.0
    assert ex.max_crossings == 100 and ex.chunk == 50 and ex.method == "taylor"
    assert ex.label == "figure4[3]"
    bad = cli.build_parser().parse_args(["explore", "figure4", "--panel", "9"])
    with pytest.raises(model.ParameterError, match="--panel must be in"):
        explore.from_args(bad, fig=fig)


def test_explore_without_a_display_is_one_line_and_exit_2(capsys):
    code = cli.main(["explore"])  # in this process matplotlib runs Agg: no window possible
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err == "explorer: error: explore needs a display (set DISPLAY or use a GUI backend)\n"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="DISPLAY is an X11/Wayland notion")
@pytest.mark.parametrize("backend", [None, "TkAgg"])
def test_explore_command_without_display_in_a_subprocess(backend, tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MPLBACKEND")}
    env["MPLCONFIGDIR"] = str(tmp_path)  # no user matplotlibrc choosing a backend
    if backend:
        env["MPLBACKEND"] = backend
    r = subprocess.run([sys.executable, "-m", "explorer", "explore"], env=env, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2, r.stderr
    assert r.stdout == ""
    assert r.stderr == "explorer: error: explore needs a display (set DISPLAY or use a GUI backend)\n"


def test_an_integration_error_stops_the_orbits_and_is_reported(tmp_path, monkeypatch):
    ex = make(tmp_path=tmp_path)
    click(ex, 0.3, 0.1)

    def broken(*args, **kwargs):
        raise RuntimeError("kernel exploded")

    monkeypatch.setattr(sections, "crossings", broken)
    for func, args, kwargs in ex._timer.callbacks:  # the GUI loop must survive
        func(*args, **kwargs)
    assert not ex.running and ex.orbits[0].main.status == explore.STATUS_FAILED
    assert "integration failed" in ex.message and "kernel exploded" in ex.message
    path = ex.save_h5(tmp_path / "failed.h5")
    panel = store.read_store(path).panels[0]
    assert panel.status_names[int(panel.status[0])] == explore.FAILED_NAME
