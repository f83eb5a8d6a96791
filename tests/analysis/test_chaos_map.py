"""ex.chaos_map (docs/chaos_map.md): the adaptive map's computed cells are the exact map's bit for
bit, it agrees with the exact map in class, marks its filled cells, and refuses bad input; the
standard map's indicators from its tangent map."""
import math

import numpy as np
import pytest

import explorer as ex

K = 2.0
N = 64
T = 200.0


@pytest.fixture(scope="module")
def standard():
    return ex.StandardMap(K)


@pytest.fixture(scope="module")
def exact(standard):
    return ex.chaos_map(standard, N, tmax=T, exact=True)


@pytest.fixture(scope="module")
def adaptive(standard):
    return ex.chaos_map(standard, N, tmax=T, coarse=16)


def test_adaptive_computed_cells_are_the_exact_maps_bit_for_bit(exact, adaptive):
    c = adaptive.computed
    assert 0 < c.sum() < 0.7 * c.size
    assert np.array_equal(adaptive.values[c], exact.values[c])
    assert np.array_equal(adaptive.chaotic[c], exact.chaotic[c])


def test_adaptive_agrees_with_exact_in_class_and_chaotic_fraction(exact, adaptive):
    assert 0.2 < exact.chaotic_fraction < 0.8      # both classes fill the map: the agreement means something
    assert np.mean(adaptive.chaotic == exact.chaotic) >= 0.995
    assert abs(adaptive.chaotic_fraction - exact.chaotic_fraction) <= 0.003


def test_mask_marks_filled_cells_and_exact_computes_every_cell(exact, adaptive):
    assert exact.computed.all() and exact.exact and not adaptive.exact
    filled = adaptive.allowed & ~adaptive.computed
    assert filled.any()
    assert np.all(np.isfinite(adaptive.values[filled]))
    assert adaptive.computed_fraction == pytest.approx(adaptive.computed.sum() / adaptive.computed.size)
    assert adaptive.values.shape == adaptive.chaotic.shape == adaptive.computed.shape == (N, N)


def test_no_filled_cell_lies_within_reach_of_a_computed_cell_of_the_other_class(adaptive):
    """docs/chaos_map.md, the rule's step 4: the boundary grew until no filled cell was left within
    reach of a computed cell of the other class (at the last level: REACH[class] and at least
    REACH_CELLS cells, 2 around a regular cell and 1 around a chaotic one)."""
    from explorer.analysis.chaos_map import CHAOTIC, REACH, REACH_CELLS, REGULAR

    n = adaptive.resolution
    filled = adaptive.allowed & ~adaptive.computed
    for kind, chaotic in ((REGULAR, False), (CHAOTIC, True)):
        r = max(REACH[kind], REACH_CELLS)
        source = np.pad(adaptive.computed & adaptive.allowed & (adaptive.chaotic == chaotic), r)
        for di in range(-r, r + 1):
            for dj in range(-r, r + 1):
                near = source[r + di:r + di + n, r + dj:r + dj + n]
                assert not (filled & near & (adaptive.chaotic != chaotic)).any()


def test_threads_and_batches_do_not_change_a_cell(standard, adaptive, monkeypatch):
    from explorer.analysis import chaos_map as cm

    monkeypatch.setattr(cm, "BATCH", 97)
    one = ex.chaos_map(standard, N, tmax=T, coarse=16, threads=1)
    assert np.array_equal(one.values, adaptive.values, equal_nan=True)
    assert np.array_equal(one.computed, adaptive.computed)


def test_max_cells_bounds_the_refinement(standard):
    m = ex.chaos_map(standard, 32, tmax=50.0, coarse=8, max_cells=100)
    assert 81 <= m.computed.sum() <= 100    # the 9 x 9 coarse lattice, then no level beyond the budget
    assert np.all(np.isfinite(m.values))


def test_section_map_cells_outside_the_allowed_region_are_nan_and_neither_computed_nor_chaotic():
    smap = ex.SectionMap(ex.FIGURE4.with_(mu=0.03), ex.FIGURE4_H, tol=1e-10)
    a = ex.chaos_map(smap, 24, tmax=40.0, coarse=6)
    e = ex.chaos_map(smap, 24, tmax=40.0, exact=True)
    assert np.array_equal(a.allowed, e.allowed) and 0.5 < a.allowed.mean() < 0.95
    out = ~a.allowed
    assert np.all(np.isnan(a.values[out])) and not a.chaotic[out].any() and not a.computed[out].any()
    assert np.array_equal(a.values[a.computed], e.values[a.computed])
    (p1lo, p1hi), (p2lo, p2hi) = smap.domain
    assert a.window == (p1lo, p1hi, p2lo, p2hi)
    centres = a.centres()[a.allowed]
    assert np.all(smap.allowed(centres))


@pytest.mark.parametrize("kw, name", [({"resolution": 1}, "resolution"), ({"indicator": "megnoo"}, "indicator"),
                                      ({"tmax": 0.0}, "tmax"), ({"window": (1.0, 0.0, 0.0, 1.0)}, "window"),
                                      ({"tolerance": -1.0}, "tolerance"), ({"max_cells": 0}, "max_cells"),
                                      ({"exact": "yes"}, "exact"), ({"coarse": 1}, "coarse"),
                                      ({"early_megno": 1.0}, "early_megno")])
def test_bad_input_names_the_parameter(standard, kw, name):
    with pytest.raises(ex.ParameterError, match=name):
        ex.chaos_map(standard, **{"resolution": 8, "tmax": 10.0, **kw})


def test_frequency_diffusion_map_computes_each_cell_as_frequency_diffusion_and_classifies_above_the_threshold():
    """docs/chaos_map.md, "Frequency diffusion": a computed cell is explorer.frequency_diffusion of
    its centre (N = tmax returns per half), bit for bit in the adaptive and the exact map; chaotic
    where log10 |nu1 - nu2| > -6."""
    from explorer.analysis.rotation import frequency_diffusion

    smap = ex.StandardMap(K)
    a = ex.chaos_map(smap, 24, indicator="frequency_diffusion", tmax=200, coarse=6)
    e = ex.chaos_map(smap, 24, indicator="frequency_diffusion", tmax=200, exact=True)
    direct = frequency_diffusion(smap, e.centres().reshape(-1, 2), center=None, iterates=200).reshape(24, 24)
    assert np.array_equal(e.values, direct) and e.threshold == -6.0
    assert np.array_equal(e.chaotic, direct > -6.0) and 0.1 < e.chaotic_fraction < 0.9
    assert 0 < a.computed.sum() < a.computed.size
    assert np.array_equal(a.values[a.computed], e.values[a.computed])
    with pytest.raises(ex.ParameterError, match="center"):
        ex.chaos_map(smap, 8, tmax=10.0, center=(1.0, 0.0))


def test_standard_map_megno_is_two_on_a_torus_and_zero_near_the_elliptic_point():
    """<Y> -> 2 on a quasi-periodic orbit and -> 0 near a stable periodic orbit (Cincotta & Simo 2000);
    (pi, 0) is the elliptic fixed point of p' = p + k sin(theta) for 0 < k < 4."""
    r = ex.indicators(ex.StandardMap(0.3), [(1.0, 2.0), (math.pi + 0.01, 0.0)], tmax=4000.0)
    assert r.megno[0] == pytest.approx(2.0, abs=0.15)
    assert r.megno[1] < 0.3


def test_standard_map_mlce_of_strong_chaos_is_chirikovs_ln_half_k():
    """lambda ~ ln(k / 2) for k >> 1 (Chirikov 1979, Phys. Rep. 52, 263)."""
    r = ex.indicators(ex.StandardMap(20.0), [(0.3, 0.1), (2.0, 1.0)], tmax=20000.0)
    assert np.all(np.abs(r.mlce - math.log(10.0)) < 0.05 * math.log(10.0))


def test_standard_map_refuses_what_belongs_to_a_flow():
    with pytest.raises(ex.ParameterError, match="tol"):
        ex.indicators(ex.StandardMap(1.0), [(0.1, 0.1)], tmax=10.0, tol=1e-9)
    with pytest.raises(ex.ParameterError, match="sali"):
        ex.indicators(ex.StandardMap(1.0), [(0.1, 0.1)], tmax=10.0, which=("sali",))


def test_a_systems_section_map_takes_the_same_rule():
    from systems import henon_heiles_map

    smap = henon_heiles_map()
    a = ex.chaos_map(smap, 24, tmax=100.0, coarse=6)
    e = ex.chaos_map(smap, 24, tmax=100.0, exact=True)
    assert np.array_equal(a.allowed, smap.allowed(a.centres())) and 0.5 < a.allowed.mean() < 1.0
    assert np.array_equal(a.values[a.computed], e.values[a.computed])
    assert not a.chaotic[~a.allowed].any()


def test_early_stop_keeps_computed_cells_exact_and_stopped_cells_chaotic(standard):
    a = ex.chaos_map(standard, 32, tmax=T, coarse=8, early_stop=True)
    e = ex.chaos_map(standard, 32, tmax=T, exact=True, early_stop=True)
    assert np.array_equal(a.values[a.computed], e.values[a.computed])
    r = ex.indicators(standard, e.centres().reshape(-1, 2), tmax=T, which=("megno",), early_stop=True)
    stopped = (r.early > 0).reshape(32, 32)
    assert stopped.any() and e.chaotic[stopped].all()


#: the cells of Figure 4's mu = 0.03 map (512^2, the megno_map preset) stopped early at <Y> > 5 whose
#: <Y> at T = 1000 is closest to the threshold 4: sticky orbits at the islands' rims
STICKY = [(-0.033906689428408354, -0.665749627423012), (-0.2058010242783841, -0.6436500547284723),
          (-0.6277234825465068, -0.09116073736497676), (1.325621231657764, 0.4558036868248838)]


def test_megno_early_stop_at_five_keeps_the_class_of_sticky_orbits_at_t_1000():
    """The megno_map preset's early stop (<Y> > 5 over [t/2, t], t >= 100) classifies the stickiest
    stopped orbits as the full T = 1000 integration does (docs/chaos_map.md)."""
    smap = ex.SectionMap(ex.FIGURE4.with_(mu=0.03), 2.0, tol=1e-12)
    seeds = np.array(STICKY)
    stop = ex.indicators(smap, seeds, tmax=1000.0, which=("megno",), early_stop=True, early_megno=5.0)
    full = ex.indicators(smap, seeds, tmax=1000.0, which=("megno",))
    assert (stop.early > 0).all() and (stop.time < 1000.0).all()
    assert (full.megno > 4.0).all()
