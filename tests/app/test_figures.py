"""explorer.figures: the paper-style section figure (seed Figure 4, docs/model.md R9), checked on
the rendered pixels (Agg backend) and on the files written."""
import math
import os
import subprocess
import sys

import matplotlib  # a run-time dependency: missing it is a failure, not a skip
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402

from explorer import model
from explorer.app import figures  # noqa: E402

H = model.FIGURE4_H
MUS = (0.0, 0.5, 2.0)


def ellipse_points(params, h, n, seed=0):
    """n random points uniformly inside the allowed ellipse of the section phi = pi."""
    c1, c2, r1, r2 = model.allowed_ellipse(params, h)
    rng = np.random.default_rng(seed)
    r = np.sqrt(rng.uniform(0.0, 0.98, n))
    t = rng.uniform(0.0, 2 * np.pi, n)
    return np.column_stack([c1 + r1 * r * np.cos(t), c2 + r2 * r * np.sin(t)])


def fig4_panels(n=3000):
    out = []
    for i, mu in enumerate(MUS):
        prm = model.FIGURE4.with_(mu=mu)
        out.append(dict(points=ellipse_points(prm, H, n, seed=i), params=prm, h=H, label=f"mu = {mu:g}"))
    return out


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """The three Figure-4 panels (last one on its own scale), saved as PNG and PDF."""
    panels = fig4_panels()
    fig = figures.section_panels(panels, own_scale=[-1], title="lam = 1, h = 2")
    out = tmp_path_factory.mktemp("fig") / "sub" / "fig4"
    png, pdf = figures.save_figure(fig, out)
    return dict(fig=fig, panels=panels, png=png, pdf=pdf, img=mpimg.imread(png))


# ---------------------------------------------------------------- pixel helpers
def panel_pixels(fig, img, ax, inset=9):
    """RGB pixels inside the axes of ``ax`` (spines excluded) and their pixel-centre
    coordinates in display units (origin bottom-left, as matplotlib's transforms).
    ``inset`` pixels are left out at each side (spines and inward ticks)."""
    assert img.shape[:2] == (int(fig.bbox.height), int(fig.bbox.width))
    bb = ax.get_window_extent()
    x0, x1 = int(math.ceil(bb.x0)) + inset, int(math.floor(bb.x1)) - inset
    y0, y1 = int(math.ceil(bb.y0)) + inset, int(math.floor(bb.y1)) - inset
    nrow = img.shape[0]
    rgb = img[nrow - y1:nrow - y0, x0:x1, :3]
    ys = (nrow - np.arange(nrow - y1, nrow - y0) - 0.5)[:, None] * np.ones((1, x1 - x0))
    xs = (np.arange(x0, x1) + 0.5)[None, :] * np.ones((y1 - y0, 1))
    return rgb, xs, ys


def classify(rgb):
    gray = np.all(np.abs(rgb - 0.8) < 0.03, axis=-1)
    white = np.all(rgb > 0.98, axis=-1)
    dark = np.all(rgb < 0.3, axis=-1)
    return gray, white, dark


# ---------------------------------------------------------------- files
def test_png_and_pdf_written(rendered):
    png, pdf = rendered["png"], rendered["pdf"]
    assert png.name == "fig4.png" and pdf.name == "fig4.pdf"
    assert png.is_file() and pdf.is_file()
    img = rendered["img"]
    assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 3 * img.shape[0]
    assert pdf.read_bytes()[:5] == b"%PDF-"
    # atomic writes leave no temporary files behind
    assert sorted(p.name for p in png.parent.iterdir()) == ["fig4.pdf", "fig4.png"]


def test_each_panel_has_gray_white_and_points(rendered):
    fig, img = rendered["fig"], rendered["img"]
    assert len(fig.axes) == 3
    for ax in fig.axes:
        rgb, _, _ = panel_pixels(fig, img, ax)
        gray, white, dark = classify(rgb)
        n = gray.size
        assert gray.sum() > 0.05 * n, "forbidden region (gray) missing"
        assert white.sum() > 0.05 * n, "allowed region (white) missing"
        assert dark.sum() > 0.01 * n, "section points (dark) missing"


def test_gray_is_exactly_the_forbidden_region(rendered):
    """Gray pixels lie where M^2 < 0, white and dark pixels where M^2 >= 0 (model.section_M2),
    away from the boundary line."""
    fig, img = rendered["fig"], rendered["img"]
    for ax, p in zip(fig.axes, rendered["panels"]):
        rgb, xs, ys = panel_pixels(fig, img, ax)
        gray, white, dark = classify(rgb)
        inv = ax.transData.inverted()
        inside = {}
        for dx, dy in [(0, 0), (3, 0), (-3, 0), (0, 3), (0, -3)]:
            d = inv.transform(np.column_stack([xs.ravel() + dx, ys.ravel() + dy]))
            inside[dx, dy] = (model.section_M2(p["params"], d[:, 0], d[:, 1], p["h"], math.pi) >= 0.0).reshape(xs.shape)
        surely_in = np.logical_and.reduce(list(inside.values()))
        surely_out = ~np.logical_or.reduce(list(inside.values()))
        assert surely_in.sum() > 1000 and surely_out.sum() > 1000
        assert gray[surely_in].mean() < 1e-3
        assert not white[surely_out].any() and not dark[surely_out].any()
        assert gray[surely_out].mean() > 0.999
        assert (white | dark)[surely_in].mean() > 0.5


def test_empty_points_and_empty_region(tmp_path):
    prm = model.FIGURE4.with_(mu=0.5)
    panels = [dict(points=np.empty((0, 2)), params=prm, h=H, label="mu = 0.5"),
              dict(points=None, params=prm, h=-5.0, label="h = -5")]
    assert model.allowed_ellipse(prm, -5.0) is None
    fig = figures.section_panels(panels, dpi=100)
    png, _ = figures.save_figure(fig, tmp_path / "empty")
    img = mpimg.imread(png)
    rgb, _, _ = panel_pixels(fig, img, fig.axes[0])
    gray, white, dark = classify(rgb)
    assert gray.mean() > 0.05 and white.mean() > 0.3 and dark.mean() < 0.005
    rgb, _, _ = panel_pixels(fig, img, fig.axes[1])
    gray, white, _ = classify(rgb)
    assert gray.mean() > 0.9 and white.sum() == 0
    assert any(t.get_text() == "no allowed region" for t in fig.axes[1].texts)
    # the empty panel borrows the scale of the other
    assert fig.axes[1].get_xlim() == fig.axes[0].get_xlim()


# ---------------------------------------------------------------- scales and labels
def test_share_scale_and_own_scale(rendered):
    ax0, ax1, ax2 = rendered["fig"].axes
    assert ax0.get_xlim() == ax1.get_xlim() and ax0.get_ylim() == ax1.get_ylim()
    assert ax2.get_xlim() != ax0.get_xlim() and ax2.get_ylim() != ax0.get_ylim()
    p = rendered["panels"]
    b0, b1, b2 = (figures.region_limits(q["params"], q["h"]) for q in p)
    np.testing.assert_allclose(ax0.get_xlim(), (min(b0[0][0], b1[0][0]), max(b0[0][1], b1[0][1])))
    np.testing.assert_allclose(ax0.get_ylim(), (min(b0[1][0], b1[1][0]), max(b0[1][1], b1[1][1])))
    np.testing.assert_allclose(ax2.get_xlim(), b2[0])
    np.testing.assert_allclose(ax2.get_ylim(), b2[1])
    # 5% margin around the ellipse of the own-scale panel
    c1, c2, r1, r2 = model.allowed_ellipse(p[2]["params"], H)
    np.testing.assert_allclose(b2, ((c1 - 1.1 * r1, c1 + 1.1 * r1), (c2 - 1.1 * r2, c2 + 1.1 * r2)))
    for ax in (ax0, ax1, ax2):
        assert ax.get_aspect() == 1.0
        assert ax.get_xlabel() == "$p_1$" and ax.get_ylabel() == "$p_2$"


def test_without_share_scale_every_panel_fits_its_region():
    panels = [dict(points=None, params=model.FIGURE4.with_(mu=mu), h=H) for mu in MUS]
    fig = figures.section_panels(panels, share_scale=False)
    for ax, q in zip(fig.axes, panels):
        np.testing.assert_allclose((ax.get_xlim(), ax.get_ylim()), figures.region_limits(q["params"], H))
    assert fig.axes[0].get_xlim() != fig.axes[1].get_xlim()


def test_titles_use_mathtext(rendered):
    titles = [ax.get_title() for ax in rendered["fig"].axes]
    assert titles == [r"$\mu = 0$", r"$\mu = 0.5$", r"$\mu = 2$"]
    assert rendered["fig"].get_suptitle() == r"$\lambda = 1$, $h = 2$"


@pytest.mark.parametrize("text, expected", [
    ("mu = 0.5", r"$\mu = 0.5$"),
    ("lam = 1", r"$\lambda = 1$"),
    ("h = 2", r"$h = 2$"),
    ("mu=0.5, h = 2", r"$\mu = 0.5$, $h = 2$"),
    ("mu = 2 (fixed point stable)", r"$\mu = 2$ (fixed point stable)"),
    ("a2 = 1/2", r"$a_2 = 1/2$"),
    ("phi0 = pi", r"$\varphi_0 = \pi$"),
    ("tol = 1e-13", r"$\mathrm{tol} = 10^{-13}$"),
    ("no allowed region", "no allowed region"),
    ("emu = 3", "emu = 3"),
    (r"$\mu$ = 1", r"$\mu$ = 1"),
])
def test_mathtext_label(text, expected):
    assert figures.mathtext_label(text) == expected


# ---------------------------------------------------------------- layout, curves
def test_grid_layout_and_curves():
    prm = model.FIGURE4
    curve = np.column_stack([np.linspace(-1, 1, 50), np.linspace(-1, 1, 50) ** 2])
    panels = [dict(points=None, params=prm.with_(mu=0.1 * k), h=H) for k in range(5)]
    panels[0]["curves"] = [curve]
    fig = figures.section_panels(panels, layout="grid", columns=2, separatrices={1: [curve[::-1]]})
    assert len(fig.axes) == 5
    rows = sorted({round(ax.get_position().y0, 3) for ax in fig.axes})
    cols = sorted({round(ax.get_position().x0, 3) for ax in fig.axes})
    assert len(rows) == 3 and len(cols) == 2
    for k in (0, 1):
        lines = [ln for ln in fig.axes[k].get_lines() if len(ln.get_xdata()) == 50]
        assert len(lines) == 1
    assert not [ln for ln in fig.axes[2].get_lines() if len(ln.get_xdata()) == 50]
    assert [ax.get_title() for ax in fig.axes][1] == r"$\mu = 0.1$"   # default label from params
    with pytest.raises(ValueError, match="layout"):
        figures.section_panels(panels, layout="column")
    with pytest.raises(ValueError, match="own_scale"):
        figures.section_panels(panels, own_scale=[7])
    with pytest.raises(ValueError, match="panel 0: points"):
        figures.section_panels([dict(points=np.zeros((4, 3)), params=prm, h=H)])


# ---------------------------------------------------------------- size of the PDF
def test_pdf_with_many_points_stays_small(tmp_path):
    prm = model.FIGURE4.with_(mu=0.5)
    pts = ellipse_points(prm, H, 200_000, seed=5)
    fig = figures.section_panels([dict(points=pts, params=prm, h=H, label="mu = 0.5")])
    png, pdf = figures.save_figure(fig, tmp_path / "big.png")     # a .png suffix is taken as the stem
    assert png == tmp_path / "big.png" and pdf == tmp_path / "big.pdf"
    data = pdf.read_bytes()
    assert len(data) < 3_000_000
    assert b"/Subtype /Image" in data          # the points went in as a raster image


def test_a_saved_figure_is_laid_out_once_and_drawn_once_per_file_the_pdf_as_savefig_writes_it(tmp_path, monkeypatch):
    """save_figure's contract (figures.save_figure, how `explorer figures` writes every figure):
    making the figure draws nothing (_trim_height lays it out only), saving draws it twice, once
    per file; the PDF is byte for byte the one matplotlib's savefig writes, the PNG has the
    figure's size in pixels, and the figure keeps its layout engine."""
    from matplotlib.figure import Figure

    panels = fig4_panels(100)[1:]

    def make():
        return figures.section_panels(panels, own_scale=[-1], title="lam = 1, h = 2", dpi=40)

    plain = make()
    plain.savefig(tmp_path / "plain.pdf", format="pdf", dpi=40, facecolor="white", metadata={"CreationDate": None})
    draws = []
    real = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, renderer: draws.append(renderer) or real(self, renderer))
    fig = make()
    assert draws == [] and fig.get_size_inches().tolist() == plain.get_size_inches().tolist()
    engine = fig.get_layout_engine()
    png, pdf = figures.save_figure(fig, tmp_path / "fig")
    assert len(draws) == 2
    assert pdf.read_bytes() == (tmp_path / "plain.pdf").read_bytes()
    assert mpimg.imread(png).shape[:2] == (round(fig.bbox.height), round(fig.bbox.width))
    assert fig.get_layout_engine() is engine


def test_save_is_atomic_on_failure(tmp_path, rendered):
    fig = figures.section_panels([dict(points=None, params=model.FIGURE4, h=H)], dpi=60)
    png, pdf = figures.save_figure(fig, tmp_path / "a" / "b" / "x")
    old = png.read_bytes()

    class Boom(RuntimeError):
        pass

    def broken(*args, **kwargs):
        raise Boom()

    fig.savefig = broken
    with pytest.raises(Boom):
        figures.save_figure(fig, tmp_path / "a" / "b" / "x")
    assert png.read_bytes() == old
    assert sorted(p.name for p in png.parent.iterdir()) == ["x.pdf", "x.png"]


# ---------------------------------------------------------------- imports and backend
def _run(code, **env_changes):
    env = dict(os.environ)
    env.pop("MPLBACKEND", None)
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    env.update(env_changes)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


def test_import_is_light_and_figures_are_drawn_headless_leaving_matplotlibs_settings_alone(tmp_path):
    """No display, no backend configured: a figure is drawn and saved as PNG and PDF without
    pyplot and without choosing a backend, every rcParam (the backend's included) as before;
    a user's pyplot afterwards gets what it would have got without us (the configured svg)."""
    code = (
        "import sys\n"
        "import explorer.app.figures as f, explorer.model as m\n"
        "assert 'matplotlib' not in sys.modules and 'numba' not in sys.modules\n"
        "import matplotlib\n"
        "before = matplotlib.rcParams.copy()\n"
        "fig = f.section_panels([dict(points=None, params=m.FIGURE4, h=2.0)], dpi=50)\n"
        f"png, pdf = f.save_figure(fig, {str(tmp_path / 'fig')!r})\n"
        "assert png.stat().st_size > 1000 and pdf.stat().st_size > 1000\n"
        "assert 'numba' not in sys.modules and 'matplotlib.pyplot' not in sys.modules\n"
        "assert matplotlib.rcParams.copy() == before\n"
        "import matplotlib.pyplot as plt\n"
        "print(plt.get_backend())\n")
    assert _run(code, MPLCONFIGDIR=str(tmp_path)).lower() == "agg"        # matplotlib's own headless choice
    assert _run(code, MPLCONFIGDIR=str(tmp_path), MPLBACKEND="svg").lower() == "svg"
