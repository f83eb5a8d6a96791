"""Greene's residue criterion on a System's section map (docs/greene.md, "Greene on a System"):
Hénon–Heiles (lam = 1) on x = 0, px > 0, in (y, py), with its reversor (x, y, px, py) -> (-x, y, px, -py)
(tests/systems.py), the noble curve nu = 1/(5 + golden) around the elliptic fixed point, broken by
the energy.  Independent checks: at each convergent's energy E_n the symmetric orbit closes under
scipy's DOP853 and the monodromy of the flow, integrated with its variational equations there, has
the residue (4 - tr Phi)/4 = R* (the flow's multipliers are 1, 1 and the map's); Newton on the whole
orbit (periodic.py) gives the same residue."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from systems import henon_heiles, henon_heiles_without_reversor, px, py, x, y

import explorer as ex
from explorer.analysis import greene_core
from explorer.analysis import greene_section as gs
from explorer.analysis import periodic as pr
from explorer.model import ParameterError

E0 = 0.1
AROUND = (0.3, 0.0)


@pytest.fixture(scope="module")
def smap():
    return ex.SectionMap(henon_heiles(), E0, section=x, direction=+1, coords=(y, py), solve=px)


@pytest.fixture(scope="module")
def breakup(smap):
    return ex.greene(smap, "noble:5", qmax=11, around=AROUND, param="energy")


def flow_with_variations(t, s):
    X, Y, PX, PY = s[:4]
    J = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0],
                  [-1.0 - 2.0 * Y, -2.0 * X, 0.0, 0.0], [-2.0 * X, -1.0 + 2.0 * Y, 0.0, 0.0]])
    return np.concatenate([[PX, PY, -X - 2.0 * X * Y, -Y - (X**2 - Y**2)], (J @ s[4:].reshape(4, 4)).ravel()])


def test_each_convergents_orbit_has_mackays_residue_at_its_energy_by_dop853_and_by_newton(smap, breakup):
    assert breakup.param == "energy" and breakup.line == 1.0
    assert [(c["p"], c["q"]) for c in breakup.convergents] == [(1, 5), (1, 6), (2, 11)]
    energies = [c["param_n"] for c in breakup.convergents]
    assert all(E0 < e < 1.0 / 6.0 for e in energies)
    for row in breakup.convergents[1:]:                      # an even and an odd period
        start = row["line_start"]                            # the orbit at the critical energy, continued to E_n
        for e in np.linspace(breakup.critical, row["param_n"], 4)[1:]:
            m = smap.with_value("energy", e)
            orb = gs.section_symmetric_orbit(m, row["q"], start)
            start = orb.line_start
        assert orb.residue == pytest.approx(greene_core.CRITICAL_RESIDUE, abs=1e-9)
        assert orb.rotation(m, gs.island_centre(m, AROUND)) * row["q"] == pytest.approx(row["p"], abs=1e-9)
        newton = pr.find_periodic_orbit(m, orb.points, row["q"])
        assert newton.period == row["q"] and newton.residue == pytest.approx(orb.residue, abs=1e-8)
        assert newton.det == pytest.approx(1.0, abs=1e-9)
        period = sum(m(p, jacobian=False).time for p in orb.points)
        s0 = m.state(orb.points[0])
        sol = solve_ivp(flow_with_variations, (0.0, period), np.concatenate([s0, np.eye(4).ravel()]),
                        method="DOP853", rtol=1e-12, atol=1e-12)
        assert np.max(np.abs(sol.y[:4, -1] - s0)) <= 1e-8          # the orbit closes after Q returns
        monodromy = sol.y[4:, -1].reshape(4, 4)
        assert (4.0 - np.trace(monodromy)) / 4.0 == pytest.approx(greene_core.CRITICAL_RESIDUE, abs=1e-6)


def test_a_map_without_a_reversor_or_a_system_itself_is_refused_naming_what_is_missing():
    plain = ex.SectionMap(henon_heiles_without_reversor(), E0, section=x, direction=+1, coords=(y, py), solve=px)
    with pytest.raises(ParameterError, match=r"reversor.*System\(\.\.\., reversor="):
        ex.greene(plain, "noble:5", qmax=11, around=AROUND, param="energy")
    with pytest.raises(ParameterError, match="greene takes a map.*SectionMap"):
        ex.greene(henon_heiles(), "noble:5")
    reversible = ex.SectionMap(henon_heiles(), E0, section=x, direction=+1, coords=(y, py), solve=px)
    with pytest.raises(ParameterError, match="param must be one of lam, energy"):
        ex.greene(reversible, "noble:5", qmax=11, around=AROUND, param="mu")
