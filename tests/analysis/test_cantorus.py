"""The flux through the golden cantorus of the standard map above k_c (explorer.analysis.cantorus):
MacKay, Meiss & Percival 1984, Delta W ~ (k - k_c)^3.0117."""
import math

import numpy as np
import pytest

from explorer import model
from explorer.analysis import cantorus as ca
from explorer.analysis import greene as gm
from explorer.analysis.maps import StandardMap
from explorer.analysis.section_map import SectionMap

#: the critical k of the golden curve (explorer's, docs/greene.md: 0.971635405749 +- 3.9e-10)
K_C = 0.971635405749
#: MacKay, Meiss & Percival (1984, Physica D 13, 55): Delta W ~ (k - k_c)^eta, eta from renormalisation
ETA_PUBLISHED = 3.0117


@pytest.mark.cpu_dependent
def test_the_golden_cantorus_flux_grows_as_the_published_power_of_k_minus_k_c():
    """The action differences of the golden convergents' minimax and minimizing orbits, extrapolated
    (Aitken) before double precision loses the orbits, at k - k_c = 0.01, 0.02, 0.04: a power law
    with exponent 3.0117 to 0.1 (measured 3.03 over 0.01 .. 0.04), and the same prefactor at each
    (Delta W / (k - k_c)^3.0117 = 0.78 .. 0.82 in (theta, p) units)."""
    dk = np.array([0.01, 0.02, 0.04])
    runs = [ca.cantorus_flux(StandardMap(K_C + d)) for d in dk]
    for r in runs:
        assert all(w > 0 for w in r.delta_w)           # the minimax orbit's action is above the minimizer's
        assert r.q[-1] >= 233 and len(r.q) >= 6        # the sequence went far enough to extrapolate
    flux = np.array([r.flux for r in runs])
    eta, _ = np.polyfit(np.log(dk), np.log(flux), 1)
    assert abs(eta - ETA_PUBLISHED) < 0.1
    c = flux / dk ** ETA_PUBLISHED
    assert np.max(c) / np.min(c) < 1.1


def test_below_the_breakup_the_action_differences_vanish():
    """Below k_c the golden circle exists and nothing crosses it: Delta W_n -> 0 faster than
    geometrically (2e-9 at q = 89 for k = 0.9, the ratio of successive terms falling to 0.02),
    where above k_c it tends to a positive limit (ratio -> 1)."""
    r = ca.cantorus_flux(StandardMap(0.9), qmax=233)
    ratios = np.array(r.delta_w[1:]) / np.array(r.delta_w[:-1])
    assert r.delta_w[-1] < 1e-8 and abs(r.flux) < 1e-8
    assert ratios[-1] < 0.1 and np.all(np.diff(ratios[-4:]) < 0)
    above = ca.cantorus_flux(StandardMap(K_C + 0.02))
    assert np.array(above.delta_w[-1]) / above.delta_w[-2] > 0.8


def test_the_minimizing_orbits_are_periodic_and_have_less_action_than_the_minimax_ones():
    """minimizing_orbit: both parities of q close after q steps, with negative residue (hyperbolic:
    the minimizer of an area-preserving twist map), and less action than the minimax orbit."""
    m = StandardMap(1.0)
    guess = {0: None, 1: None, "max": None}
    for P, Q in gm.convergents("golden", 89):
        pts = ca.minimizing_orbit(m, P, Q, guess=guess[Q % 2])
        guess[Q % 2] = pts[0, 1]
        end = m.iterate(pts[0], Q)[-1]
        assert abs(end[0] - pts[0, 0] - 2 * math.pi * P) < 1e-9 and abs(end[1] - pts[0, 1]) < 1e-9
        M = np.eye(2)
        for x in pts:
            M = m.jacobian(x) @ M
        assert (2.0 - np.trace(M)) / 4.0 < 0.0
        mx = gm.symmetric_orbit(m, P, Q, guess=guess["max"])
        guess["max"] = mx.points[0, 1]
        assert ca.action(m, pts, P) < ca.action(m, mx.points, P)


def test_a_map_without_a_generating_function_is_refused_naming_what_it_lacks():
    """The flux is the action difference of a twist map's orbits: a section map has no generating function."""
    with pytest.raises(model.ParameterError, match="angle coordinate.*generating_function"):
        ca.cantorus_flux(SectionMap(model.FIGURE4, model.FIGURE4_H))
