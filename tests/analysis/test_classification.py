"""explorer.analysis.classification (docs/chaos_map.md): one rule classifies an orbit, chaotic
beyond the indicator's threshold or stopped early, valid when stopped early or finite and
integrated to the end; Indicators.chaotic, a chaos map's cells and a sweep's panels give the same
classes for the same orbits."""
import numpy as np
import pytest

import explorer as ex
from explorer.analysis import sweep
from explorer.analysis.classification import RULES, class_text, default_threshold, fraction, orbit_classes

K = 2.0
N = 16
T = 200.0


def test_orbits_beyond_the_threshold_are_chaotic_above_it_for_megno_and_below_it_for_sali():
    v = np.array([0.5, 3.9, 4.1, 30.0])
    assert orbit_classes(v, "megno", 4.0)[0].tolist() == [False, False, True, True]
    assert orbit_classes(v, "sali", 4.0)[0].tolist() == [True, True, False, False]
    assert [RULES[n].above for n in ("mlce", "megno", "fli", "sali", "gali2", "frequency_diffusion")] == \
        [True, True, True, False, False, True]
    assert class_text("megno", 4.0) == "MEGNO > 4" and class_text("sali", 1e-8) == "SALI < 1e-08"


def test_an_orbit_stopped_early_is_chaotic_and_valid_and_a_nonfinite_or_unfinished_one_is_invalid():
    v = np.array([np.nan, np.nan, 1.0, 1.0, 10.0])
    early = np.array([1, 0, 0, 0, 0])
    ok = np.array([True, True, False, True, True])
    chaotic, valid = orbit_classes(v, "megno", 4.0, early, ok)
    assert chaotic.tolist() == [True, False, False, False, True]
    assert valid.tolist() == [True, False, False, True, True]


def test_a_fraction_has_the_binomial_error_and_never_claims_none():
    chaotic = np.array([True] * 30 + [False] * 70 + [True] * 5)
    valid = np.array([True] * 100 + [False] * 5)
    p, err, n = fraction(chaotic, valid)
    assert (p, n) == (0.3, 100) and err == pytest.approx(np.sqrt(0.3 * 0.7 / 100))
    assert fraction(np.ones(8, bool), np.ones(8, bool))[1] == pytest.approx(1 / 16)
    assert np.isnan(fraction(chaotic, np.zeros(105, bool))[0])
    megno = np.array([1.0, 5.0, np.nan, 9.0])
    assert ex.chaotic_fraction(megno, 4.0)[:2] == fraction(np.array([0, 1, 0, 1]), np.array([1, 1, 0, 1]))[:2]


def test_default_thresholds_follow_the_regular_envelopes_of_their_time():
    T_ = 1000.0
    assert default_threshold("megno", T_) == 4.0
    assert default_threshold("mlce", T_) == pytest.approx(3 * np.log(T_) / T_)
    assert default_threshold("fli", T_) == pytest.approx(2 * np.log(T_))
    assert default_threshold("sali", T_) == default_threshold("gali2", T_) == 1e-8


@pytest.mark.parametrize("indicator", ["megno", "fli"])
def test_indicators_a_chaos_map_and_a_sweep_panel_classify_the_same_orbits_alike(indicator):
    smap = ex.StandardMap(K)
    m = ex.chaos_map(smap, N, indicator=indicator, tmax=T, exact=True, early_stop=True)
    r = ex.indicators(smap, m.centres().reshape(-1, 2), tmax=T, which=(indicator,), early_stop=True)
    thr = m.threshold
    by_indicators = r.chaotic(thr, indicator).reshape(N, N)
    assert 0 < by_indicators.sum() < by_indicators.size    # both classes: the agreement means something
    assert 0 < (r.early > 0).sum() < by_indicators.sum()   # some chaotic orbits stopped early, not all
    assert np.array_equal(by_indicators, m.chaotic)
    arrays = {indicator: r.values[indicator], "lyapunov_status": r.status, "lyapunov_early": r.early}
    chaotic, valid = sweep.classify(arrays, indicator, thr)
    assert valid.all() and np.array_equal(chaotic.reshape(N, N), m.chaotic)


def test_indicators_chaotic_refuses_an_indicator_it_did_not_compute():
    r = ex.indicators(ex.StandardMap(K), np.array([[0.1, 0.2]]), tmax=50, which=("megno",))
    with pytest.raises(ex.ParameterError, match="indicator must be one of the computed indicators"):
        r.chaotic(1e-8, "sali")
