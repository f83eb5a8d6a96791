"""Lobes of a System's homoclinic tangle (docs/manifolds.md, "Lobes and flux"; docs/greene.md, "Lobes
of a System"): Hénon–Heiles (lam = 1) at E = 1/8 on x = 0, px > 0, in (y, py), its hyperbolic fixed
point on the reversor's line py = 0.  The invariant: the two lobes of the turnstile have equal areas
(the map preserves dy ^ dpy), each by Green's theorem on its arcs with a Richardson error estimate."""
import pytest
from systems import henon_heiles, px, py, x, y

import explorer as ex
from explorer.analysis import manifolds as mf
from explorer.analysis import transport as tr
from explorer.model import ParameterError


@pytest.fixture(scope="module")
def smap():
    return ex.SectionMap(henon_heiles(), 1.0 / 8.0, section=x, direction=+1, coords=(y, py), solve=px)


def test_the_two_lobes_of_a_systems_turnstile_have_equal_areas(smap):
    hyperbolic = ex.find_fixed_point(smap, (-0.18, 0.0))
    assert not hyperbolic.stable and abs(hyperbolic.point[1]) < 1e-12
    res = tr.turnstile(mf.saddle(smap, hyperbolic), arclength=1.5, sign=1, max_arclength=1.5)
    a, b = res["lobes"]
    assert a.area * b.area < 0                                  # one lobe enters, the other leaves
    assert abs(a.area) > 1e-4 and max(a.error, b.error) < 1e-3 * abs(a.area)
    assert abs(abs(a.area) - abs(b.area)) <= 3 * (a.error + b.error)


def test_flux_curve_refuses_a_systems_map_pointing_to_the_turnstile(smap):
    with pytest.raises(ParameterError, match=r"flux_curve is for Chaplygin's model.*turnstile"):
        tr.flux_curve(smap)
