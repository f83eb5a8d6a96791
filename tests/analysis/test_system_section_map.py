"""The section map of a System on an energy level (docs/systems.md, "Section map"): the lifted
state, the branch the direction selects, the refusal outside the energy surface, its crossings
against the flow's, the analyses that refuse a System, and the energy column of a result."""
import numpy as np
import pytest
from systems import henon_heiles, lam, pole, px, py, x, y

import explorer as ex
from explorer.analysis import sections
from explorer.model import ParameterError

E = 1.0 / 8.0
POINTS = [(0.1, 0.1), (-0.1, 0.2), (0.3, 0.0)]


def energy(Y):
    """Hénon–Heiles' H (lam = 1) at the states Y (N, 4), in Python floats' order of docs/systems.md."""
    X, Yv, PX, PY = Y.T
    return (PX**2 + PY**2)/2 + (X**2 + Yv**2)/2 + (X**2*Yv - Yv**3/3)


def by_hand(points):
    """States on x = 0 at energy E with px > 0 from (y, py)."""
    return np.array([[0.0, yy, np.sqrt(2*E - pyy**2 - yy**2 + 2*yy**3/3), pyy] for yy, pyy in points])


def test_the_lifted_state_lies_on_the_section_at_the_energy_with_px_of_the_directions_sign():
    hh = henon_heiles()
    up = ex.SectionMap(hh, E, section=x, direction=+1, coords=(y, py), solve=px)
    down = ex.SectionMap(hh, E, section=x, direction=-1, coords=(y, py), solve=px)
    Y, Z = up.states(POINTS), down.states(POINTS)
    assert np.all(Y[:, 0] == 0.0) and np.all(Y[:, 2] > 0.0) and np.all(Z[:, 2] < 0.0)
    assert np.max(np.abs(energy(Y) - E)) <= 1e-15 and np.max(np.abs(energy(Z) - E)) <= 1e-15
    assert np.array_equal(Y[:, [1, 3]], np.array(POINTS))
    assert np.max(np.abs(Y - by_hand(POINTS))) <= 1e-15
    assert np.array_equal(Z[:, 2], -Y[:, 2])


def test_a_tilted_section_fixes_its_own_variable_and_keeps_the_energy():
    # x + y - 0.1 = 0 crossed downwards: x = 0.1 - y, px from the energy with d(x + y)/dt = px + py < 0
    smap = ex.SectionMap(henon_heiles(), E, section=x + y - 0.1, direction=-1, coords=(y, py), solve=px)
    Y = smap.states([(0.0, 0.1), (0.2, -0.1)])
    assert np.max(np.abs(Y[:, 0] + Y[:, 1] - 0.1)) <= 1e-16
    assert np.max(np.abs(energy(Y) - E)) <= 1e-15
    assert np.all(Y[:, 2] + Y[:, 3] < 0.0)


def test_a_point_outside_the_energy_surface_is_refused_naming_the_point_and_the_energy():
    smap = ex.SectionMap(henon_heiles(), E, section=x, direction=+1, coords=(y, py), solve=px)
    # py**2 = 0.36 > 2E: no real px
    with pytest.raises(ParameterError, match=r"energy level E = 0.125 has no solution for px at \(y, py\) = "
                                             r"\(0.1, 0.6\)"):
        smap.states([(0.1, 0.1), (0.1, 0.6)])


@pytest.mark.parametrize("kw, match", [
    (dict(coords=(y, y), solve=px), "two different state variables"),
    (dict(coords=(y, py), solve=py), "solve must not be one of coords"),
    (dict(coords=(y, lam), solve=px), "coords must be a state variable"),
    (dict(coords=(y, py), solve=px, direction=0), "direction must be"),
    (dict(coords=(x, py), solve=px), "must involve y"),
])
def test_a_bad_map_is_refused_with_a_message_naming_the_parameter(kw, match):
    args = dict(section=x, direction=+1)
    args.update(kw)
    with pytest.raises(ParameterError, match=match):
        ex.SectionMap(henon_heiles(), E, **args)


def test_a_system_without_an_energy_has_no_section_map():
    hh = henon_heiles()
    bare = ex.System(dict(zip(hh.states, hh.rhs)), parameters={lam: 1.0})
    with pytest.raises(ParameterError, match="has no energy"):
        ex.SectionMap(bare, E, section=x, direction=+1, coords=(y, py), solve=px)


def test_crossings_of_the_map_equal_the_flows_crossings_from_the_states_built_by_hand():
    hh = henon_heiles()
    smap = ex.SectionMap(hh, E, section=x, direction=+1, coords=(y, py), solve=px)
    res = ex.crossings(smap, POINTS, n_crossings=30)
    flow = ex.crossings(hh, states=by_hand(POINTS), n_crossings=30, section=x, direction=+1, tol=smap.tol)
    assert isinstance(res, ex.Crossings) and np.all(res.count == 30)
    for name in ("data", "count", "status", "final", "info"):
        assert np.array_equal(getattr(res, name), getattr(flow, name), equal_nan=True), name
    assert res.settings["energy"] == E and res.settings["solve"] == "px" and res.settings["section"] == "x"
    # the map's iterates are the (y, py) columns of its crossings (both at the map's tolerance)
    it = smap.iterate(POINTS[0], 30)
    assert np.array_equal(it[0], POINTS[0]) and np.array_equal(it[1:], res.orbit(0)[:, [2, 4]])
    with pytest.raises(ParameterError, match="belong\\(s\\) to the map"):
        ex.crossings(smap, POINTS, n_crossings=3, direction=-1)


def test_the_maps_crossings_are_the_systems_at_the_maps_tol_and_another_tol_is_the_map_with_tol():
    hh = henon_heiles()
    smap = ex.SectionMap(hh, E, section=x, direction=+1, coords=(y, py), solve=px)
    loose = smap.with_tol(1e-10)
    res = ex.crossings(loose, POINTS, n_crossings=20)
    flow = ex.crossings(hh, states=loose.states(POINTS), n_crossings=20, section=x, direction=+1, tol=1e-10)
    for name in ("data", "count", "status", "final", "info"):
        assert np.array_equal(getattr(res, name), getattr(flow, name), equal_nan=True), name
    blocks = list(ex.iter_crossings(loose, POINTS, n_crossings=20, block=7))
    assert np.array_equal(np.concatenate([b.rows(0) for b in blocks]), res.orbit(0))
    tight = ex.crossings(smap, POINTS, n_crossings=20)
    assert res.settings["tol"] == 1e-10 and tight.settings["tol"] == smap.tol == 1e-15
    assert not np.array_equal(res.data, tight.data) and np.max(np.abs(res.data - tight.data)) < 1e-6


@pytest.mark.parametrize("run", ["crossings", "iter_crossings"])
def test_a_tol_beside_a_systems_map_is_refused_naming_tol_and_pointing_to_with_tol(run):
    smap = ex.SectionMap(henon_heiles(), E, section=x, direction=+1, coords=(y, py), solve=px)
    with pytest.raises(ParameterError, match=r"tol belong\(s\) to the map.*smap\.with_tol\(tol\)"):
        getattr(ex, run)(smap, POINTS, n_crossings=3, tol=smap.tol)


@pytest.mark.parametrize("system", ["chaplygin", "henon_heiles"])
def test_a_maps_crossings_streamed_in_blocks_are_its_crossings_rows_bit_for_bit_and_columns_name_a_b_solve(system):
    if system == "chaplygin":
        smap, pts, kw = ex.SectionMap(ex.FIGURE4, ex.FIGURE4_H, tol=1e-12), [(0.3, 0.1)], {"direction": -1}
    else:
        smap = ex.SectionMap(henon_heiles(), E, section=x, direction=-1, coords=(y, py), solve=px)
        pts, kw = POINTS[:1], {}
    one = ex.crossings(smap, pts, n_crossings=12, **kw)
    blocks = list(ex.iter_crossings(smap, pts, n_crossings=12, block=5, **kw))
    assert len(blocks) == 3 and np.array_equal(np.concatenate([b.rows(0) for b in blocks]), one.orbit(0))
    cols = one.orbit(0)[:, list(smap.columns)]                         # (t, a, b, solve, E - E0)
    if system != "chaplygin":                                           # the map's own iterates at its tol
        assert np.array_equal(cols[:, 1:3], smap.iterate(pts[0], 12)[1:])
    assert np.all(cols[:, 3] < 0.0) and np.max(np.abs(cols[:, 4])) < 1e-9   # solve's sign is the direction's


def test_analyses_that_do_not_take_a_system_say_so_naming_the_function():
    hh = henon_heiles()
    smap = ex.SectionMap(hh, E, section=x, direction=+1, coords=(y, py), solve=px)
    Y0 = by_hand(POINTS[:1])
    calls = {   # each names the function and what to use for a System instead (iter_crossings streams
        # a System: tests/analysis/test_system_sections.py)
        "propagate": (lambda: ex.propagate(hh, states=Y0, t=1.0), "explorer.flow"),
    }
    for name, (call, instead) in calls.items():
        with pytest.raises(ParameterError, match=f"^{name} is for Chaplygin's model; of a System, {instead}"):
            call()
    from explorer.analysis.transport import flux_curve

    with pytest.raises(ParameterError, match="^flux_curve is for Chaplygin's model; .*transport.turnstile"):
        flux_curve(smap, [0.1])


def test_max_energy_error_reads_the_energy_column_of_a_system_and_of_chaplygins_rows():
    hh = henon_heiles()
    res = ex.crossings(hh, states=by_hand(POINTS), n_crossings=5, section=x, direction=+1)
    assert sections.max_energy_error(res) == np.nanmax(np.abs(res.data[..., 5]))
    assert sections.max_energy_error(res) <= 1e-14       # column 4 (py) would be of order 0.1
    rows = np.zeros((2, 3, 5))
    rows[1, 2, 4] = -3e-9
    assert sections.max_energy_error(rows) == 3e-9
    system, _, w = pole()                             # a System without an energy: no energy column
    plain = ex.crossings(system, states=[[1.0, 0.0]], n_crossings=1, section=w - 1, direction=+1)
    assert plain.data.shape == (1, 1, 3) and abs(plain.data[0, 0, 0] - (np.e - 1)) <= 1e-12   # w = ln(1 + t)
    with pytest.raises(ParameterError, match="no energy column"):
        sections.max_energy_error(plain)


def test_chaplygins_section_map_is_unchanged_and_pickles():
    import pickle

    smap = ex.SectionMap(ex.FIGURE4, ex.FIGURE4_H)
    assert type(smap) is ex.SectionMap and smap.h == ex.FIGURE4_H
    back = pickle.loads(pickle.dumps(smap))
    assert type(back) is ex.SectionMap and back.h == smap.h and back.params == smap.params


def test_the_example_of_docs_systems_md_section_map_runs():
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "systems.md").read_text()
    block = page.split("## Section map", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    namespace = {}
    exec(compile(block, "docs/systems.md", "exec"), namespace)   # its own asserts check the result
    assert namespace["points"].shape == (2, 200, 2)
    assert "E = 0.125 has no solution for px at (y, py) = (0.1, 0.6)" in namespace["refused"]


def test_another_parameter_value_lifts_onto_its_own_energy_surface():
    # the roots are cached with lam as a symbol: lam = 0.5 must use its value, not the first map's
    hh = henon_heiles()
    ex.SectionMap(hh, E, section=x, direction=+1, coords=(y, py), solve=px).states(POINTS)
    half = ex.SectionMap(hh.with_(lam=0.5), E, section=x, direction=+1, coords=(y, py), solve=px)
    Y = half.states(POINTS)
    X, Yv, PX, PY = Y.T
    H = (PX**2 + PY**2)/2 + (X**2 + Yv**2)/2 + 0.5*(X**2*Yv - Yv**3/3)
    assert np.max(np.abs(H - E)) <= 1e-15 and np.all(PX > 0.0)
    assert np.max(np.abs(energy(Y) - E)) > 1e-4          # not on lam = 1's surface


@pytest.mark.parametrize("system", ["chaplygin", "henon_heiles"])
def test_with_tol_is_the_same_map_at_that_tolerance_and_its_returns_agree_to_it(system):
    if system == "chaplygin":
        smap, x0 = ex.SectionMap(ex.FIGURE4, ex.FIGURE4_H, phi0=0.5), (0.3, 0.1)
    else:
        smap, x0 = ex.SectionMap(henon_heiles(), E, section=x, direction=-1, coords=(y, py), solve=px), POINTS[0]
    loose = smap.with_tol(1e-9)
    assert loose.tol == 1e-9 and smap.with_tol(smap.tol) is smap and type(loose) is type(smap)
    assert [loose.value_of(n) for n in smap.parameters] == [smap.value_of(n) for n in smap.parameters]
    assert loose.tmax == smap.tmax and loose.section_label == smap.section_label
    assert np.max(np.abs(loose(x0).point - smap(x0).point)) < 1e-7
    with pytest.raises(ParameterError, match="tol"):
        smap.with_tol(0.5)


def test_a_map_rebuilt_with_the_same_values_is_equal_and_any_other_value_makes_another_map():
    hh = henon_heiles()
    smap = ex.SectionMap(hh, E, section=x, direction=+1, coords=(y, py), solve=px)
    again = ex.SectionMap(henon_heiles(), E, section=x, direction=+1, coords=(y, py), solve=px)
    assert again == smap and hash(again) == hash(smap) and again is not smap
    assert smap.with_value("lam", 0.5).with_value("lam", 1.0) == smap
    assert smap.with_value("energy", 0.1).with_value("energy", E) == smap
    others = (smap.with_value("lam", 0.5), smap.with_value("energy", 0.1), smap.opposite(), smap.with_tol(1e-9),
              smap.with_tmax(10.0), ex.SectionMap(hh, E, section=x, direction=+1, coords=(py, y), solve=px))
    assert all(o != smap for o in others) and smap != ex.SectionMap(ex.FIGURE4, ex.FIGURE4_H)
