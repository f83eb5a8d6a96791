"""The figures of the seed paper (explorer.paper, `python -m explorer figures`) and the seed's
typos that no other test covers (docs/errata.md lists every erratum with its test)."""
import math

import numpy as np
import pytest
from conftest import random_states
from matplotlib.image import imread
from test_chaos_paper import _check_raster_png

import reference
from explorer import model
from explorer.app import cli, paper
from explorer.model import exact

PRM = paper.CHAPLYGIN            # lam = 1, b = 2, a1 = 1, a2 = 1/2, mu = chi = zeta = 0
C1, C2 = 2.0, 4.0                # lam b / a1, lam b / a2


# ====================================================================== the whole --quick run
@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    """Every figure on reduced settings, headless, into a temporary directory."""
    root = tmp_path_factory.mktemp("paper")
    out = paper.generate(None, out_dir=root / "figs", results_dir=root / "res", quick=True, quiet=True,
                         raise_errors=True)
    return root, {o.name: o for o in out}


def _png_ok(path):
    import matplotlib.image as mpimg

    img = mpimg.imread(path)
    assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 300
    assert float(np.std(img[..., :3])) > 0.02          # not blank


def test_every_figure_is_written_as_png_and_pdf(quick):
    root, out = quick
    assert list(out) == list(paper.FIGURES)
    for name, o in out.items():
        assert o.status == "written", o.line()        # every figure, none "not available"
        png, pdf = (root / "figs" / f"{name}.png"), (root / "figs" / f"{name}.pdf")
        assert [p.name for p in o.paths] == [png.name, pdf.name]
        _png_ok(png)
        assert pdf.read_bytes()[:5] == b"%PDF-" and pdf.stat().st_size > 5000


def test_the_breakup_figures_two_sections_share_one_window(quick):
    """The sections just below and just above mu_c are drawn on the same axes limits (the first
    panel's window), so the eye compares like with like."""
    _root, out = quick
    below, above = out["breakup"].data["section_limits"]
    assert below == above == tuple(out["breakup"].data["window"])


# ---------------------------------------------------------------- the chaotic fraction against mu, the atlas
# (quick: reduced presets; the bounds leave room beyond any last-bit change, tests/app/test_chaos_paper.py)
def test_fraction_curve_quick_figure(quick):
    tmp_path, out = quick
    o = out["fraction_curve"]
    assert o.status == "written" and o.data["reduced"]
    assert len(o.data["values"]) == 41
    fr = np.asarray(o.data["fraction"])
    assert fr[0] < 0.05 and fr[-1] > 0.5                          # integrable at mu = 0, chaotic at mu = 10
    img = imread(tmp_path / "figs" / "fraction_curve.png")
    assert img.shape[0] > 200 and img.shape[1] > 300 and float(np.std(img[..., :3])) > 0.02
    assert (tmp_path / "figs" / "fraction_curve.pdf").read_bytes()[:5] == b"%PDF-"


def test_atlas_quick_figure_is_a_heat_map_of_every_cell(quick):
    tmp_path, out = quick
    o = out["atlas"]
    assert o.status == "written" and o.data["reduced"] and tuple(o.data["shape"]) == (16, 12)
    fr = np.asarray(o.data["fraction"])
    ok = np.isfinite(fr)
    assert ok.mean() > 0.9 and np.all((fr[ok] >= 0) & (fr[ok] <= 1))
    assert fr[0][ok[0]].max() < 0.2 and np.nanmax(fr) > 0.8     # regular at mu = 0, chaotic at large mu
    img = imread(tmp_path / "figs" / "atlas.png")
    colourful = (img[..., :3].max(axis=-1) - img[..., :3].min(axis=-1)) > 0.3
    assert img.shape[1] > 300 and colourful.mean() > 0.1
    # a rerun redraws from the stored atlas: nothing recomputed, the same fractions
    again = paper.make("atlas", out_dir=tmp_path / "figs-again", results_dir=tmp_path / "res", quick=True)
    np.testing.assert_array_equal(np.asarray(again.data["fraction"]), fr)


def test_megno_map_quick_figure_is_a_raster(quick):
    """The quick MEGNO map (64 x 64, T = 200, mu = 0.03), checked on the figure the --quick run drew
    (it lived in tests/app/test_chaos_paper.py, which computed and drew the same figure again)."""
    root, out = quick
    o = out["megno_map"]
    assert o.status == "written" and o.data["reduced"] and o.data["resolution"] == 64
    assert 0.6 * 64 ** 2 < o.data["orbits"] < 64 ** 2
    assert 0.05 < o.data["fraction"] < 0.95                        # mu = 0.03: islands and a stochastic layer
    _check_raster_png(root / "figs" / "megno_map.png")


# ---------------------------------------------------------------- Figure 2
def test_figure2_curves_are_integrated_closed_and_keep_H_and_F(quick):
    _root, out = quick
    panels = out["figure2"].data["panels"]
    assert [p["h"] for p in panels] == list(paper.FIGURE2_ENERGIES)
    h1, h2 = paper.critical_h(PRM)
    assert panels[0]["h"] < h1 < panels[1]["h"] < h2 < panels[2]["h"]   # the seed's three intervals
    for p in panels:
        h = p["h"]
        assert len(p["curves"]) >= 5
        for cur in p["curves"]:
            y = cur["y"]
            assert len(y) > 20
            assert np.abs(paper.chaplygin_H(PRM, y) - h).max() < 1e-11 * max(1.0, h)
            assert np.abs(paper.chaplygin_F(PRM, y) - cur["c"]).max() < 1e-11 * max(1.0, abs(cur["c"]))
            assert cur["closure"] < 1e-9                      # one full period, back at the start
            assert abs(cur["start"][1]) == 0.0 and abs(cur["half"][1]) < 1e-12
        # no curve drawn twice: the other meridian point of each curve is not a start
        starts = [(c["c"], c["start"]) for c in p["curves"]]
        for cur in p["curves"]:
            assert not any(c == cur["c"] and np.linalg.norm(s - cur["half"]) < 1e-6 for c, s in starts)
    # separatrices: none below the band, R7's two loops inside it, III's four arcs above it
    assert [len(p["separatrices"]) for p in panels] == [0, 2, 4]
    for p, c_sep in ((panels[1], math.sqrt(2 * PRM.b * 2.0)), (panels[2], 0.5 * 6.0 + 2.0)):
        for s in p["separatrices"]:
            assert np.abs(paper.chaplygin_H(PRM, s) - p["h"]).max() < 1e-10
            assert np.abs(paper.chaplygin_F(PRM, s) - c_sep).max() < 1e-10


def test_figure2_draws_its_3d_grid_light_and_thin(quick):
    """The 3D axes' grid in the colour and width the figure names (set through rcParams when each
    axis is made, matplotlib's public way for 3D axes), on every axis of every panel."""
    from explorer.app.paper import figure2

    _root, out = quick
    fig = figure2._draw_figure2(PRM, out["figure2"].data["panels"], paper.critical_h(PRM), dpi=50,
                                elev=24.0, azim=-55.0)
    fig.draw_without_rendering()
    grids = [axis.gridlines for ax in fig.axes if ax.name == "3d" for axis in (ax.xaxis, ax.yaxis, ax.zaxis)]
    assert len(grids) == 3 * len(paper.FIGURE2_ENERGIES)
    for g in grids:
        np.testing.assert_array_equal(g.get_color(), [figure2.GRID_COLOR])
        assert list(g.get_linewidth()) == [figure2.GRID_WIDTH]


def test_figure2_critical_levels_and_curves_in_every_interval():
    """Critical values of F on the ellipsoid: the poles I for every h, II above b lam^2/(2 a1^2),
    III above b lam^2/(2 a2^2), in the order of Figure 3 (I- < I+ < III < II at h = 6)."""
    for h, kinds in ((0.5, ["I-", "I+"]), (2.0, ["I-", "I+", "II"]), (6.0, ["I-", "I+", "III", "II"])):
        levels, crit = paper._figure2_levels(PRM, h, 6)
        assert [k for _, k in crit] == kinds
        for c, k in crit:
            if k in ("II", "III"):
                assert paper.branch_h(k, c, PRM) == pytest.approx(h)
        for (a, _), (b, _) in zip(crit[:-1], crit[1:]):
            assert sum(a < c < b for c in levels) >= 2


# ---------------------------------------------------------------- Figure 3
def test_figure3_draws_the_branches_dashed_where_unstable():
    """The analytic branches only (check=False: nothing integrated, nothing a CPU could change)."""
    d = paper.figure3_figure(check=False)
    ax = d.fig.axes[0]
    lines = {}
    for ln in ax.lines:
        if ln.get_gid():
            lines.setdefault(ln.get_gid(), []).append(ln)
    assert {k: len(v) for k, v in lines.items()} == {"I-stable": 2, "I-unstable": 1, "II": 1, "III": 1}
    for gid, dashed in (("I-stable", False), ("I-unstable", True), ("II", False), ("III", True)):
        for ln in lines[gid]:
            assert (ln.get_linestyle() == "--") is dashed, gid
    # the dashed arc of I is exactly the band lam b/a1 < c < lam b/a2; the lines start at the tangency
    x = lines["I-unstable"][0].get_xdata()
    assert x.min() == pytest.approx(C1) and x.max() == pytest.approx(C2)
    for gid, cj in (("II", C1), ("III", C2)):
        x, y = lines[gid][0].get_xdata(), lines[gid][0].get_ydata()
        assert x.min() == pytest.approx(cj)
        # tangent to the parabola h = c^2/(2b) at c = lam b/a_j: same value and slope
        assert y[0] == pytest.approx(cj ** 2 / (2 * PRM.b))
        assert (y[1] - y[0]) / (x[1] - x[0]) == pytest.approx(cj / PRM.b)
        np.testing.assert_allclose(y, paper.branch_h(gid, x, PRM))
    # ur21 with its 1/2: h = lam c/a_j - lam^2 b/(2 a_j^2)
    assert paper.branch_h("II", 3.0, PRM) == 3.0 - 1.0 and paper.branch_h("III", 5.0, PRM) == 10.0 - 4.0
    # the admissible region is shaded gray
    assert any(c.get_gid() == "admissible" for c in ax.collections)


def test_admissible_region_is_the_minimum_of_H_on_F_equal_c():
    """Brute force: min over a (p1, p2) grid of H with M = c - |p|^2/(2 lam), against the
    piecewise formula (parabola of I up to lam b/a1, then the line of II)."""
    g = np.linspace(-4, 4, 801)
    P1, P2 = np.meshgrid(g, g)
    for c in (-1.0, 0.5, 1.9, 2.0, 2.5, 3.3, 4.0, 5.5):
        M = c - (P1 ** 2 + P2 ** 2) / (2 * PRM.lam)
        H = paper.chaplygin_H(PRM, np.stack([P1, P2, M], axis=-1))
        want = float(paper.admissible_hmin(c, PRM))
        assert H.min() >= want - 1e-12
        assert H.min() == pytest.approx(want, abs=2e-4)
        # attained on I (c <= lam b/a1) or on II, never on III
        branch = "I" if c <= C1 else "II"
        assert want == pytest.approx(float(paper.branch_h(branch, c, PRM)))
        if c > C2:
            assert paper.branch_h("III", c, PRM) > want


@pytest.mark.cpu_dependent
def test_figure3_check_agrees_with_the_drawn_classification_in_every_region():
    recs = paper.figure3_check()
    assert all(r["agree"] is not False for r in recs)
    regions = {("I", "below"): False, ("I", "band"): False, ("I", "above"): False, ("II", ""): False,
               ("III", ""): False}
    for r in recs:
        if r["agree"] is None:
            continue
        if r["branch"] == "I":
            key = ("I", "below" if r["c"] < C1 else "band" if r["c"] < C2 else "above")
            assert r["stable"] is (key[1] != "band")
        else:
            key = (r["branch"], "")
            assert r["stable"] is (r["branch"] == "II")
            assert r["analytic_error"] < 1e-12 and r["residual"] < 1e-12
        regions[key] = True
    assert all(regions.values()), regions
    # both methods for I inside and outside the band
    mono = [r for r in recs if r["method"] == "monodromy" and r["agree"]]
    assert {r["stable"] for r in mono} == {True, False}
    for r in mono:
        assert r["value"] == pytest.approx(r["trace_analytic"], rel=1e-6, abs=1e-6)


def test_figure3_check_refuses_a_wrong_classification(monkeypatch):
    from explorer.app.paper import chaplygin

    monkeypatch.setattr(chaplygin, "branch_stable", lambda branch, c, params: True)  # where figure3_check looks
    with pytest.raises(paper.CheckError, match="III at c"):
        paper.figure3_check(samples={"III": (5.0,)})


def test_figure3_marks_the_checked_points(quick):
    _root, out = quick
    recs = [r for r in out["figure3"].data["checks"] if r["agree"]]
    assert len(recs) >= 15


# ---------------------------------------------------------------- tangle (docs/manifolds.md)
def test_tangle_lobes_are_equal_and_the_flux_matches_melnikov(quick):
    _, out = quick
    d = out["tangle"].data
    a = [lb["signed_area"] for lb in d["lobes"]]
    assert len(a) == 2 and a[0] * a[1] < 0 and abs(abs(a[0]) - abs(a[1])) < 1e-5
    assert all(r["status"] == "ok" and abs(r["ratio"] - 1.0) < 1e-4 for r in d["flux"])


# ---------------------------------------------------------------- homoclinic
def test_homoclinic_exact_and_integrated_crossing_times_agree(quick):
    _root, out = quick
    d = out["homoclinic"].data
    for s in (1, -1):
        r = d[s]
        assert r["count_exact"] == r["count_integrated"] >= 6
        assert r["max_dt"] < 1e-8
        assert np.abs(r["y"][:, :3] - r["exact"]).max() < 1e-8          # the dense samples too
        np.testing.assert_allclose(r["cross_integrated"], r["cross_exact"], atol=1e-8)
    # the two separatrices are p -> -p of each other
    np.testing.assert_allclose(d[-1]["exact"][:, :2], -d[1]["exact"][:, :2], atol=0)


# ---------------------------------------------------------------- continuation, work-precision
def test_continuation_finds_the_stability_change(quick):
    _root, out = quick
    d = out["continuation"].data
    assert len(d["bifurcations"]) == 1 and d["bifurcations"][0] == pytest.approx(
        reference.figure4_stability_change_mu(), abs=1e-4)   # scipy's DOP853 alone, bisected
    assert d["trace"][0] == pytest.approx(d["trace_mu0"], rel=1e-6)
    assert np.all((np.abs(d["trace"]) < 2) == (d["mu"] > d["bifurcations"][0]))
    assert np.max(np.abs(d["p2"])) < 1e-9
    assert d["trace_min"] is not None and abs(d["trace_min"][1] + 2) < 1e-6


def test_work_precision_draws_every_row(quick, tmp_path):
    _root, out = quick
    bench = paper.find_benchmark()
    if bench is None:
        assert out["work_precision"].status == "not available"
        return
    d = out["work_precision"].data
    import json

    rows = json.loads(bench.read_text())["rows"]
    assert d["n_rows"] == len(rows) == sum(d["groups"].values())
    assert any("scipy" in g for g in d["groups"]) and any("heyoka" in g for g in d["groups"])
    # missing input: a clear message, not a failure
    o = paper.generate(["work_precision"], out_dir=tmp_path, benchmark=tmp_path / "none.json", quiet=True)[0]
    assert o.status == "not available" and "results_w4.json" in o.message


# ---------------------------------------------------------------- the periodic-orbit figure
def test_the_periodic_figure_draws_isolated_orbits_of_every_period_each_returning_to_itself(quick):
    """The quick periodic figure (periods 1-3 at the Figure-4 scene, mu = 0.03) finds orbits of
    every period, and each drawn orbit closes under the section map to its own residual.  (This
    replaces a test of tests/app/test_cli_periodic.py that drew the figure a second time through
    `figures --only periodic` and asserted only the labels "K=1:" and "K=3:" of its line; the
    count per period on any CPU is proven by tests/analysis/test_periodic.py's cpu_dependent tests.)"""
    _root, out = quick
    o = out["periodic"]
    assert "K=1:" in o.message and "K=3:" in o.message
    d = o.data
    assert sorted(d["counts"]) == [1, 2, 3] and all(d["counts"][K] >= 1 for K in (1, 3)), d["counts"]
    for K, orbits in d["orbits"].items():
        assert len(orbits) == d["counts"][K]
        for orb in orbits:
            assert orb["period"] == K and orb["residual"] < 1e-9, orb


def test_the_periodic_figures_profile_starts_at_the_elliptic_points_linear_rotation_number(quick):
    """The rotation profile starts next to the elliptic point (at the point itself the angle around it
    is undefined) at its linear rotation number: trace = 2 cos(2 pi rho) (to 1e-9; the quick figure's 300
    returns leave its two halves 1.2e-10 apart, just short of the 1e-10 that counts as converged)."""
    from explorer.analysis.fixedpoints import find_fixed_point
    from explorer.app.paper.periodic import CENTER_GUESS

    d = quick[1]["periodic"].data
    fp = find_fixed_point(model.FIGURE4.with_(mu=0.03), model.FIGURE4_H, CENTER_GUESS)
    assert np.array_equal(d["center"], fp.point) and abs(fp.trace) < 2.0
    assert abs(d["rotation"][0]) == pytest.approx(math.acos(fp.trace / 2.0) / (2.0 * math.pi), abs=1e-9)


def test_the_periodic_legend_lies_below_its_panel_with_a_colour_per_period_and_a_marker_per_kind_drawn():
    """The legend hides no orbit: it is drawn below the section's axes, inside the figure (the
    constrained layout makes room for it), and lists the periods and only the kinds drawn."""
    from explorer.app.paper._common import _new_figure, _rc
    from explorer.app.paper.periodic import FIGSIZE, WIDTH_RATIOS, period_legend

    with _rc():
        fig = _new_figure(FIGSIZE, dpi=100)
        ax, _bx = fig.subplots(1, 2, gridspec_kw={"width_ratios": WIDTH_RATIOS})
        ax.plot([0.0, 1.0], [0.0, 1.0], "o")
        ax.set_xlabel("$p_1$")
        leg = period_legend(ax, {K: f"C{K}" for K in range(1, 9)}, {"elliptic", "degenerate"})
        fig.canvas.draw()
    box, panel, page = leg.get_window_extent(), ax.get_window_extent(), fig.bbox
    assert box.y1 <= panel.y0 and box.y0 >= page.y0 and page.x0 <= box.x0 < box.x1 <= page.x1, (box, panel)
    assert [t.get_text() for t in leg.get_texts()] == [f"K = {K}" for K in range(1, 9)] + [
        "elliptic", "degenerate (not isolated)"]


# ---------------------------------------------------------------- sweeps: reuse of stores
def test_quick_sweeps_are_reused_on_a_second_run(quick):
    root, out = quick
    for name, preset in paper.SWEEP_FIGURES.items():
        assert out[name].data["reduced"] is True
        scene, path, reduced, summary = paper.ensure_sweep(preset, results_dir=root / "res", quick=True)
        assert reduced and paper.store_complete(scene, path)
        assert "(0 computed" in summary


def test_a_complete_full_store_is_used_even_under_quick(monkeypatch, tmp_path):
    from explorer.io import scene as sc

    small = sc.PRESETS["figure4"].replace("n = 200", "n = 12").replace("crossings = 1000", "crossings = 20").replace(
        "separatrices = true", "separatrices = false").replace("tmax = 10000.0", "tmax = 400.0")
    monkeypatch.setitem(sc.PRESETS, "figure4", small)
    scene, path, reduced, summary = paper.ensure_sweep("figure4", results_dir=tmp_path, quick=False)
    assert not reduced and path.name == "figure4.h5" and "(5 computed" in summary
    scene, path, reduced, summary = paper.ensure_sweep("figure4", results_dir=tmp_path, quick=True)
    assert not reduced and path.name == "figure4.h5" and "(0 computed" in summary
    paths, msg, data = paper.figure4_figure(tmp_path / "figs", results_dir=tmp_path, quick=True)
    assert "reduced" not in msg and all(p.exists() for p in paths)


def test_cli_figures_only_figure3(tmp_path, capsys):
    code = cli.main(["figures", "--only", "figure3", "--out-dir", str(tmp_path / "f"), "--results-dir",
                     str(tmp_path / "r"), "--quiet"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert out.startswith("figure3: ") and "all agree" in out
    assert (tmp_path / "f" / "figure3.png").exists() and (tmp_path / "f" / "figure3.pdf").exists()
    assert not (tmp_path / "r").exists()       # no sweep for figure3


def test_cli_figures_unknown_name_is_one_line_exit_2(capsys):
    code = cli.main(["figures", "--only", "nope"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("explorer: error: unknown figure 'nope'")
    assert all(n in lines[0] for n in paper.FIGURES)


# ====================================================================== errata (docs/errata.md)
def r1_field(u, P, *, torque_extra=0.0, gyro_swapped=False, chi_sign=1.0):
    """R1 in the trig form (p1, p2, M, phi, x, y), written from docs/model.md; optional seed variants:
    ``gyro_swapped``: ur1 as printed (a1 omega v2, -a2 omega v1); ``chi_sign = -1``: ur7 as
    printed (-chi dH/dM in dp2/dt); ``torque_extra``: added to dM/dt."""
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P
    p1, p2, m, phi, x, y = u
    s, c = math.sin(phi), math.cos(phi)
    w = m / b
    if gyro_swapped:   # a1 dv1/dt = a1 w v2 - ...: dp1/dt = (a1/a2) w p2
        dp1 = w * (a1 / a2) * p2 - w * zeta - mu * s - lam * p2 / a2
        dp2 = -w * (a2 / a1) * p1 + w * chi - mu * c + lam * p1 / a1
    else:
        dp1 = w * (p2 - zeta) - mu * s - lam * p2 / a2
        dp2 = -w * p1 + chi_sign * w * chi - mu * c + lam * p1 / a1
    dm = (p1 - chi) * p2 / a2 - (p2 - zeta) * p1 / a1 - mu * (xi * c - eta * s) + torque_extra
    return np.array([dp1, dp2, dm, w, (p1 / a1) * c - (p2 / a2) * s, (p1 / a1) * s + (p2 / a2) * c])


def rate(fun, u, f, eps=1e-6):
    g = np.array([(fun(u + eps * e) - fun(u - eps * e)) / (2 * eps) for e in np.eye(len(u))])
    return float(g @ f)


def h_full(u, P):
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P
    p1, p2, m, phi, x, y = u
    return 0.5 * (p1 ** 2 / a1 + p2 ** 2 / a2 + m ** 2 / b) + mu * (y + xi * math.sin(phi) + eta * math.cos(phi))


ASYM = model.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=-0.15, mu=0.7, xi=0.3, eta=-0.25)


def _states(n=10, seed=11):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, 6)) * 1.5


def test_ur1_gyroscopic_terms_as_printed_do_not_conserve_energy():
    """ur1 prints a1 dv1/dt = a1 omega v2 ..., a2 dv2/dt = -a2 omega v1 ...: the energy then
    changes at the rate 2 (a1 - a2) omega v1 v2; with a2 omega v2 and -a1 omega v1 (R1) it is kept."""
    P = ASYM.as_array()
    for u in _states():
        assert abs(rate(lambda z: h_full(z, P), u, r1_field(u, P))) < 1e-8
        wrong = rate(lambda z: h_full(z, P), u, r1_field(u, P, gyro_swapped=True))
        v1, v2, om = u[0] / P[0], u[1] / P[1], u[2] / P[2]
        assert wrong == pytest.approx(2 * (P[0] - P[1]) * om * v1 * v2, rel=1e-6, abs=1e-9)


def test_ur2_torque_needs_xi_not_zeta():
    """ur2 prints M1 - zeta Q2 + eta Q1 = dU/dphi.  With U = mu (y + xi sin phi + eta cos phi)
    (Q1 = mu sin phi, Q2 = mu cos phi) the torque -M1 + xi Q2 - eta Q1 of ur1 is then
    -dU/dphi + (xi - zeta) Q2 and the energy is not conserved; with xi (R10) it is R1's."""
    P = ASYM.as_array()
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P
    for u in _states():
        phi = u[3]
        Q1, Q2 = mu * math.sin(phi), mu * math.cos(phi)
        dU = mu * (xi * math.cos(phi) - eta * math.sin(phi))
        for coef, ok in ((xi, True), (zeta, False)):
            M1 = dU + coef * Q2 - eta * Q1
            torque = -M1 + xi * Q2 - eta * Q1
            extra = torque - (-mu * (xi * math.cos(phi) - eta * math.sin(phi)))
            r = rate(lambda z: h_full(z, P), u, r1_field(u, P, torque_extra=extra))
            assert (abs(r) < 1e-8) is ok


def test_ur7_chi_term_of_dp2_has_the_wrong_sign():
    """ur7 prints dp2/dt = ... - chi dH/dM; R1 (and ur1) have + chi omega.  With the printed
    sign the energy changes at the rate -2 chi (M/b)(p2/a2)."""
    P = ASYM.with_(mu=0.0).as_array()
    for u in _states():
        assert abs(rate(lambda z: h_full(z, P), u, r1_field(u, P))) < 1e-8
        r = rate(lambda z: h_full(z, P), u, r1_field(u, P, chi_sign=-1.0))
        assert r == pytest.approx(-2 * P[4] * (u[2] / P[2]) * (u[1] / P[1]), rel=1e-6, abs=1e-9)


def test_ur10_p_y_as_printed_is_not_an_integral():
    """R2: p_y = p1 sin phi + p2 cos phi - lam x - zeta cos phi - chi sin phi = c2 - mu t.
    The seed prints p2 sin phi (for p1), lam sin phi (for chi) and + mu t: each is wrong."""
    P = ASYM.as_array()
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P

    def p_y(u, first="p1", last="chi"):
        p1, p2, m, phi, x, y = u
        s, c = math.sin(phi), math.cos(phi)
        return ((p1 if first == "p1" else p2) * s + p2 * c - lam * x - zeta * c
                - (chi if last == "chi" else lam) * s)

    for u in _states():
        f = r1_field(u, P)
        assert rate(p_y, u, f) == pytest.approx(-mu, abs=1e-8)                  # dp_y/dt = -mu: c2 - mu t
        assert abs(rate(p_y, u, f) - mu) > 1.0                                  # not + mu t
        assert abs(rate(lambda z: p_y(z, first="p2"), u, f) + mu) > 1e-3
        assert abs(rate(lambda z: p_y(z, last="lam"), u, f) + mu) > 1e-3
        px = lambda z: (z[0] * math.cos(z[3]) - z[1] * math.sin(z[3]) + lam * z[5]  # noqa: E731
                        + zeta * math.sin(z[3]) - chi * math.cos(z[3]))
        assert abs(rate(px, u, f)) < 1e-8                                       # p_x as printed is right


def test_ur11_a_squared_is_a_typo_for_a2():
    """ur11 prints p2^2/a^2: with a2^2 in place of a2 the reduced energy is not conserved."""
    prm = model.FIGURE4.with_(mu=0.5)
    for y in random_states(prm, 10, seed=3):
        f = model.rhs(prm, y)
        typo = lambda z: model.energy(prm, z) + 0.5 * z[1] ** 2 * (1 / prm.a2 ** 2 - 1 / prm.a2)  # noqa: E731
        g = np.array([(typo(y + 1e-6 * e) - typo(y - 1e-6 * e)) / 2e-6 for e in np.eye(5)])
        assert abs(g @ f) > 1e-3 * (1 + abs(y[1]))


def test_ur16_hamiltonian_as_printed_has_gamma2_for_gamma1():
    """ur16 prints H = ... - (mu/lam)((p1 - chi) g2 + p2 g2) + mu eta g2; R3 has
    -(mu/lam)((p1 - chi) g2 - (p2 - zeta) g1): the printed H is not conserved by the field."""
    base = model.Params(a1=1.5, a2=0.6, b=1.7, lam=0.9, mu=0.8)
    prm = base.with_(eta=model.hess_eta(base))

    def seed_H(z):
        p1, p2, m, g1, g2 = z
        return (0.5 * (p1 ** 2 / prm.a1 + p2 ** 2 / prm.a2 + m ** 2 / prm.b)
                - prm.mu / prm.lam * ((p1 - prm.chi) * g2 + p2 * g2) + prm.mu * prm.eta * g2)

    for y in random_states(prm, 10, seed=4):
        f = model.rhs(prm, y)
        g = np.array([(seed_H(y + 1e-6 * e) - seed_H(y - 1e-6 * e)) / 2e-6 for e in np.eye(5)])
        assert abs(g @ f) > 1e-3
        gH = np.array([(model.energy(prm, y + 1e-6 * e) - model.energy(prm, y - 1e-6 * e)) / 2e-6
                       for e in np.eye(5)])
        assert abs(gH @ f) < 1e-8


def test_ur18_as_printed_does_not_keep_the_integrals_ur19():
    """ur18 prints dp1/dt = p2 M - lam p2/a2 (no /b) and dp2/dt = -p1 M/b + lam p1/a2 (a2 for
    a1): H and F of ur19 are not integrals of it; they are of R6 (= R3 at mu = 0)."""
    a1, a2, b, lam = PRM.a1, PRM.a2, PRM.b, PRM.lam

    def seed(y):
        p1, p2, m = y
        return np.array([p2 * m - lam * p2 / a2, -p1 * m / b + lam * p1 / a2, (1 / a2 - 1 / a1) * p1 * p2])

    def r6(y):
        return paper.r6_rhs(PRM, y)

    def grads(y):
        p1, p2, m = y
        return np.array([p1 / a1, p2 / a2, m / b]), np.array([p1 / lam, p2 / lam, 1.0])

    rng = np.random.default_rng(5)
    for y in rng.normal(size=(10, 3)):
        gH, gF = grads(y)
        assert abs(gH @ r6(y)) < 1e-13 and abs(gF @ r6(y)) < 1e-13
        assert max(abs(gH @ seed(y)), abs(gF @ seed(y))) > 1e-3


def test_ur21_needs_the_half():
    """ur21 prints h = c lam/a_j - b lam^2/a_j^2; the energy of II, III (ur20) is
    h = lam c/a_j - lam^2 b/(2 a_j^2) (the seed's own text after ur21, and Figure 3's labels)."""
    for branch, a in (("II", PRM.a1), ("III", PRM.a2)):
        for c in (4.5, 6.0):
            y = paper.relative_equilibrium(branch, c, PRM)
            assert paper.chaplygin_F(PRM, y) == pytest.approx(c, rel=1e-14)
            h = float(paper.chaplygin_H(PRM, y))
            assert h == pytest.approx(PRM.lam * c / a - PRM.lam ** 2 * PRM.b / (2 * a * a), rel=1e-14)
            assert abs(h - (c * PRM.lam / a - PRM.b * PRM.lam ** 2 / a ** 2)) > 0.5
            assert np.max(np.abs(paper.r6_rhs(PRM, y))) < 1e-13        # a permanent rotation


def test_ur22_M_needs_d1_squared_d2_squared():
    """ur22 prints M = c - 2 B d1 d2 / E; with it the orbit leaves the level H = c^2/(2b)
    (R7 has 2 B d1^2 d2^2)."""
    P = PRM.as_array()
    c = 2.5
    t = np.linspace(-10, 10, 201)
    p1, p2, M, _ = exact.homoclinic(P, c, t)
    b1, b2 = 2 * (c - C1), 2 * (C2 - c)
    B = b1 + b2
    d1, d2 = math.sqrt(b1 / B), math.sqrt(b2 / B)
    E = 2 * B * d1 ** 2 * d2 ** 2 / (c - M)           # E from the correct M
    M_seed = c - 2 * B * d1 * d2 / E
    y = np.column_stack([p1, p2, M])
    assert np.abs(paper.chaplygin_H(PRM, y) - c * c / (2 * PRM.b)).max() < 1e-12
    ys = np.column_stack([p1, p2, M_seed])
    assert np.abs(paper.chaplygin_H(PRM, ys) - c * c / (2 * PRM.b)).max() > 0.1
    assert np.abs(paper.chaplygin_F(PRM, ys) - c).max() > 0.1


def test_R7_second_separatrix_flips_p1_and_p2():
    """README finding: flipping p1 alone (R7's "p1 = +-...") does not solve R6; p -> -p does."""
    P = PRM.as_array()
    c = 2.0 * math.sqrt(2.0)
    t = np.linspace(-8, 8, 161)
    dt = 1e-5

    def residual(s1, s2):
        def state(tt):
            p1, p2, M, _ = exact.homoclinic(P, c, tt)
            return np.column_stack([s1 * p1, s2 * p2, M])
        dy = (state(t + dt) - state(t - dt)) / (2 * dt)
        f = np.array([paper.r6_rhs(PRM, y) for y in state(t)])
        return np.abs(dy - f).max()

    assert residual(1, 1) < 1e-8 and residual(-1, -1) < 1e-8
    assert residual(-1, 1) > 0.1


def test_ur17_has_a_duplicated_term_and_the_sign_of_R2():
    """ur17 (lam = 0): b phi'' = b dM/dt / b of R1 with p - s expressed by p_x = pi1,
    p_y = pi2 - mu t (R2).  The printed formula carries an extra -(mu/b)(xi cos phi - eta cos phi)
    (the term is printed twice, once mistyped) and, with R2's sign of mu t, its terms linear in
    mu t change sign."""
    P = dict(a1=1.3, a2=0.6, b=1.7, lam=0.0, chi=0.2, zeta=-0.15, mu=0.7, xi=0.3, eta=-0.25)
    a1, a2, b, lam, chi, zeta, mu, xi, eta = (P[n] for n in model.PARAM_NAMES)
    k = 1 / a2 - 1 / a1

    def ur17(phi, t, pi1, pi2, printed):
        s2, c2 = math.sin(2 * phi), math.cos(2 * phi)
        s, c = math.sin(phi), math.cos(phi)
        lin = (mu * t / b) * (k * (pi1 * c2 + pi2 * s2) - chi * c / a1 + zeta * s / a2)
        out = (mu ** 2 * t ** 2 / (2 * b) * k * s2 + (lin if printed else -lin)
               + (1 / a1 - 1 / a2) / (2 * b) * ((pi1 ** 2 - pi2 ** 2) * s2 - 2 * pi1 * pi2 * c2)
               - (mu / b) * (xi * c - eta * s)
               + (pi1 / b) * (chi * s / a1 + zeta * c / a2) - (pi2 / b) * (chi * c / a1 - zeta * s / a2))
        if printed:
            out -= (mu / b) * (xi * c - eta * c)
        return out

    rng = np.random.default_rng(6)
    for u in _states(10, seed=7):
        t = float(rng.uniform(0, 5))
        p1, p2, m, phi, x, y = u
        s, c = math.sin(phi), math.cos(phi)
        pi1 = p1 * c - p2 * s + zeta * s - chi * c                      # p_x (lam = 0)
        pi2 = p1 * s + p2 * c - zeta * c - chi * s + mu * t             # p_y = pi2 - mu t
        want = r1_field(u, np.array([P[n] for n in model.PARAM_NAMES]))[2] / b
        assert ur17(phi, t, pi1, pi2, printed=False) == pytest.approx(want, rel=1e-12, abs=1e-12)
        # as printed, even with the seed's own convention p_y = pi2 + mu t:
        assert abs(ur17(phi, t, pi1, pi2 - 2 * mu * t, printed=True) - want) > 1e-6


def _bracket(f, g, z, P, eps=1e-6):
    """{f, g} for functions of z = (p1, p2, M, phi) with the Poisson tensor of ur8:
    {p1, p2} = -lam, {M, p1} = -(p2 - zeta), {M, p2} = p1 - chi, {M, phi} = -1."""
    a1, a2, b, lam, chi, zeta = P[:6]
    p1, p2, m, phi = z
    Pi = np.zeros((4, 4))
    Pi[0, 1], Pi[2, 0], Pi[2, 1], Pi[2, 3] = -lam, -(p2 - zeta), p1 - chi, -1.0
    Pi = Pi - Pi.T
    gf = np.array([(f(z + eps * e) - f(z - eps * e)) / (2 * eps) for e in np.eye(4)])
    gg = np.array([(g(z + eps * e) - g(z - eps * e)) / (2 * eps) for e in np.eye(4)])
    return float(gf @ Pi @ gg)


def test_canonical_variables_cos_l_and_the_conjugate_pairs():
    """The seed's canonical variables: M = L, p1 - chi = sqrt(2 lam (G - L)) cos l (printed
    cos phi, inside the root), p2 - zeta = sqrt(2 lam (G - L)) sin l, G = M + |p - s|^2/(2 lam),
    g = phi.  With cos l the parametrisation is consistent (cos phi is not).  The bracket ur8
    (which reproduces R3 at mu = 0) gives {l, L} = -1 and {g, L} = 1 for these: they are not
    canonical as printed; (l, G - M), (g, G) are ({l, G - M} = {g, G} = 1, the others 0)."""
    P = ASYM.with_(lam=0.8, mu=0.0).as_array()
    a1, a2, b, lam, chi, zeta = P[:6]
    rng = np.random.default_rng(8)
    H = lambda z: 0.5 * (z[0] ** 2 / a1 + z[1] ** 2 / a2 + z[2] ** 2 / b)   # noqa: E731
    ell = lambda z: math.atan2(z[1] - zeta, z[0] - chi)                      # noqa: E731
    L = lambda z: z[2]                                                       # noqa: E731
    G = lambda z: z[2] + ((z[0] - chi) ** 2 + (z[1] - zeta) ** 2) / (2 * lam)  # noqa: E731
    g = lambda z: z[3]                                                       # noqa: E731
    Lc = lambda z: G(z) - z[2]                                               # noqa: E731
    for z in rng.normal(size=(6, 4)):
        # the bracket reproduces R3 at mu = 0 (so the test's tensor is ur8's)
        y5 = np.array([z[0], z[1], z[2], math.sin(z[3]), math.cos(z[3])])
        f = model.rhs(model.Params.from_array(P), y5)
        for i in range(3):
            assert _bracket(lambda q: q[i], H, z, P) == pytest.approx(f[i], abs=1e-8)
        rho = math.sqrt(2 * lam * (G(z) - L(z)))
        assert rho * math.cos(ell(z)) == pytest.approx(z[0] - chi, abs=1e-12)
        assert rho * math.sin(ell(z)) == pytest.approx(z[1] - zeta, abs=1e-12)
        if math.cos(z[3]) > 0 and abs(math.cos(z[3]) - math.cos(ell(z)) ** 2) > 1e-3:
            assert abs(math.sqrt(2 * lam * (G(z) - L(z)) * math.cos(z[3])) - (z[0] - chi)) > 1e-6
        assert _bracket(ell, L, z, P) == pytest.approx(-1.0, abs=1e-7)
        assert _bracket(g, L, z, P) == pytest.approx(1.0, abs=1e-7)
        for a, bb, want in ((ell, Lc, 1.0), (g, G, 1.0), (ell, G, 0.0), (g, Lc, 0.0), (ell, g, 0.0),
                            (Lc, G, 0.0)):
            assert _bracket(a, bb, z, P) == pytest.approx(want, abs=1e-7)


def test_the_registry_lists_every_figure_module_once_with_its_builder():
    """One module per figure: each non-private module of explorer.app.paper is in the registry
    under its NAME, with a description and a build function; the CLI lists the same names."""
    import importlib
    import pkgutil

    from explorer.app import cli
    from explorer.app.paper import registry

    pkg = importlib.import_module("explorer.app.paper")
    # registry itself and chaplygin (the analysis of R6 shared by figures 2 and 3) are not figures
    modules = {m.name for m in pkgutil.iter_modules(pkg.__path__) if not m.name.startswith("_")}
    modules -= {"registry", "chaplygin"}
    assert set(registry.MODULES.values()) == {f"explorer.app.paper.{m}" for m in modules}
    for name in registry.FIGURES:
        mod = registry.module(name)
        assert mod.NAME == name and mod.DESCRIPTION and callable(mod.build)
    helptext = cli.build_parser()._subparsers._group_actions[0].choices["figures"].format_help()
    assert all(name in " ".join(helptext.split()) for name in registry.FIGURES)
    with pytest.raises(model.ParameterError, match="unknown figure 'figure9'; names: figure2, figure3"):
        registry.module("figure9")
