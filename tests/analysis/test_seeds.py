"""explorer.analysis.seeds: initial conditions inside the allowed region of the section (R9)."""
import dataclasses
import math

import numpy as np
import pytest
from conftest import PARAM_SETS

from explorer import model
from explorer.analysis import seeds
from explorer.analysis.seeds import seed_points
from explorer.io.scene import SeedSpec

SEED_CASES = [(name, prm, h, phi0)
              for name, prm in list(PARAM_SETS.items()) + [("figure4_mu0", model.FIGURE4),
                                                           ("figure4_mu2", model.FIGURE4.with_(mu=2.0))]
              for h, phi0 in ((2.0, math.pi), (1.5, 0.7), (3.0, -2.3))]
SEED_IDS = [f"{c[0]}-h{c[2]}-phi{c[3]:.2f}" for c in SEED_CASES]

SPECS = {
    "grid": SeedSpec(kind="grid", n=300),
    "grid_margin1": SeedSpec(kind="grid", n=500, margin=1.0),
    "random": SeedSpec(kind="random", n=500, seed=3),
    "random_margin1": SeedSpec(kind="random", n=500, margin=1.0, seed=4),
    "lines": SeedSpec(kind="lines", n=101, margin=0.7,
                      lines=((-1.0, 0.0, 1.0, 0.0), (-1.0, -1.0, 1.0, 1.0), (0.0, 1.0, 0.0, -1.0))),
    "lines_margin1": SeedSpec(kind="lines", n=101, margin=1.0,
                      lines=((-1.0, 0.0, 1.0, 0.0), (-1.0, -1.0, 1.0, 1.0), (0.0, 1.0, 0.0, -1.0))),
    "points": SeedSpec(kind="points", points=((0.0, 0.0), (0.3, -0.2), (5.0, 5.0), (-1.0, 0.5), (1e3, 0.0))),
}


def _in_scaled_ellipse(prm, h, phi0, p1, p2, margin):
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h, phi0)
    return ((p1 - c1) / (margin * r1)) ** 2 + ((p2 - c2) / (margin * r2)) ** 2 <= 1.0 + 1e-12


@pytest.mark.parametrize("kind", sorted(SPECS))
@pytest.mark.parametrize("name,prm,h,phi0", SEED_CASES, ids=SEED_IDS)
def test_seeds_lie_strictly_inside_the_allowed_region(kind, name, prm, h, phi0):
    spec = SPECS[kind]
    p1, p2, dropped = seed_points(spec, prm, h, phi0)
    assert p1.dtype == p2.dtype == np.float64 and p1.shape == p2.shape and p1.ndim == 1
    assert np.all(model.section_M2(prm, p1, p2, h, phi0) > 0.0)
    if spec.kind == "points":
        m2 = model.section_M2(prm, [p[0] for p in spec.points], [p[1] for p in spec.points], h, phi0)
        assert p1.size == np.count_nonzero(m2 > 0) and dropped == len(spec.points) - p1.size
        assert p1.size < len(spec.points)   # (1e3, 0) is outside every region here
    else:
        assert p1.size > 0
        assert np.all(_in_scaled_ellipse(prm, h, phi0, p1, p2, spec.margin))


@pytest.mark.parametrize("kind", sorted(SPECS))
def test_seeding_is_deterministic_bitwise(kind):
    prm = PARAM_SETS["asym_lam_neg"]
    a = seed_points(SPECS[kind], prm, 2.0, 0.7)
    b = seed_points(dataclasses.replace(SPECS[kind]), prm, 2.0, 0.7)
    assert a[0].tobytes() == b[0].tobytes() and a[1].tobytes() == b[1].tobytes() and a[2] == b[2]


@pytest.mark.parametrize("n", [50, 64, 100, 200, 333, 1000, 5000, 20000])
def test_grid_count_within_ten_percent_of_n(n):
    for prm, h, phi0 in ((model.FIGURE4, 2.0, math.pi), (PARAM_SETS["asym_lam_pos"], 1.5, 0.7)):
        p1, _p2, dropped = seed_points(SeedSpec(kind="grid", n=n), prm, h, phi0)
        assert abs(p1.size - n) <= 0.1 * n and dropped == 0


def test_grid_is_equally_spaced_in_region_units_and_row_major():
    prm, h, margin = PARAM_SETS["asym_lam_neg"], 2.0, 0.9
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h)
    p1, p2, _ = seed_points(SeedSpec(kind="grid", n=400, margin=margin), prm, h)
    u, v = (p1 - c1) / (margin * r1), (p2 - c2) / (margin * r2)
    d = seeds.grid_spacing(400)
    assert np.allclose(u / d, np.round(u / d), atol=1e-9) and np.allclose(v / d, np.round(v / d), atol=1e-9)
    order = np.lexsort((p1, p2))          # sort by p2, then p1
    assert np.array_equal(order, np.arange(p1.size))
    assert np.any(np.isclose(u, 0.0) & np.isclose(v, 0.0))   # the lattice is centred


def test_random_is_reproducible_and_changes_with_the_seed():
    prm = PARAM_SETS["asym_lam_pos"]
    a = seed_points(SeedSpec(kind="random", n=200, seed=1), prm, 2.0)
    b = seed_points(SeedSpec(kind="random", n=200, seed=1), prm, 2.0)
    c = seed_points(SeedSpec(kind="random", n=200, seed=2), prm, 2.0)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0])
    assert a[0].size == 200 and a[2] == 0


def test_random_is_uniform_in_the_ellipse_area():
    # uniform in a disc: E[rho^2] = 1/2 (a uniform radius would give 1/3)
    prm, h, margin = model.FIGURE4.with_(mu=0.5), 2.0, 0.8
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h)
    p1, p2, _ = seed_points(SeedSpec(kind="random", n=20000, margin=margin, seed=5), prm, h)
    rho2 = ((p1 - c1) / (margin * r1)) ** 2 + ((p2 - c2) / (margin * r2)) ** 2
    assert abs(rho2.mean() - 0.5) < 0.01
    assert abs(np.mean(p1 - c1)) < 0.02 * r1 and abs(np.mean(p2 - c2)) < 0.02 * r2


def test_lines_are_in_units_of_the_scaled_region_with_ends_included():
    prm, h = model.FIGURE4.with_(mu=0.5), 2.0
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h)
    p1, p2, dropped = seed_points(SeedSpec(kind="lines", n=11, margin=0.5, lines=((-1.0, 0.0, 1.0, 0.0),)), prm, h)
    assert dropped == 0 and p1.size == 11
    assert np.allclose(p1, c1 + 0.5 * r1 * np.linspace(-1, 1, 11), rtol=0, atol=1e-15) and np.all(p2 == c2)
    # the diagonal leaves the unit disc for |t| > 1/sqrt(2): 4 of 11 points dropped and counted
    p1, p2, dropped = seed_points(SeedSpec(kind="lines", n=11, margin=0.5, lines=((-1.0, -1.0, 1.0, 1.0),)), prm, h)
    assert p1.size == 7 and dropped == 4
    assert np.allclose((p1 - c1) / (0.5 * r1), np.linspace(-0.6, 0.6, 7), rtol=0, atol=1e-12)
    # at margin 1 the ends lie on the boundary (M^2 ~ 0): never returned unless M^2 > 0
    p1, p2, dropped = seed_points(SeedSpec(kind="lines", n=11, margin=1.0, lines=((-1.0, 0.0, 1.0, 0.0),)), prm, h)
    assert p1.size + dropped == 11 and p1.size >= 9 and np.all(model.section_M2(prm, p1, p2, h) > 0)


def test_points_are_kept_as_given_and_outside_ones_counted():
    pts = ((0.1, 0.0), (9.0, 9.0), (0.3, 0.2))
    p1, p2, dropped = seed_points(SeedSpec(kind="points", points=pts), model.FIGURE4, 2.0)
    assert p1.tolist() == [0.1, 0.3] and p2.tolist() == [0.0, 0.2] and dropped == 1


def test_seeding_an_empty_region_raises():
    with pytest.raises(model.ParameterError, match="allowed region .* is empty"):
        seed_points(SeedSpec(), model.FIGURE4, -1.0)


def test_seeding_needs_a_seed_specification():
    with pytest.raises(TypeError, match="SeedSpec"):
        seed_points({"kind": "grid"}, model.FIGURE4, 2.0)


