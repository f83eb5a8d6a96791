"""The explorer's state without a window: no matplotlib, and every action checked on its numbers."""
import subprocess
import sys

import numpy as np
import pytest

from explorer import model
from explorer.analysis import sections
from explorer.app.explore.state import STATUS_RUNNING, ExplorerState

H = model.FIGURE4_H
MU = model.FIGURE4.with_(mu=0.5)


def test_the_state_imports_no_matplotlib():
    code = ("import sys; import explorer.app.explore.state as s; "
            "print(any(m.startswith('matplotlib') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_a_click_runs_an_orbit_on_the_energy_level_equal_to_one_long_run():
    st = ExplorerState(MU, H, chunk=20, max_crossings=60, indicators=False)
    o = st.click(0.3, 0.1)
    assert o is not None and st.seeds == [(0.3, 0.1)] and st.running
    steps = st.run_until_done()
    assert steps == 3 and not st.running and o.main.count == 60 and o.main.status == 0
    assert np.max(np.abs(o.crossings[:, 4])) < 1e-10            # |H - H(y0)| at every crossing
    ref = sections.section_crossings(MU, [0.3], [0.1], H, 60, tol=st.tol)
    # taylor's step depends on the state alone: the chunks are one long run (time sums aside)
    np.testing.assert_allclose(o.crossings[:, 1:4], ref.orbit(0)[:, 1:4], rtol=0, atol=1e-11)
    first, msg = st.status_lines()
    assert "60/60 crossings, done" in first and "orbit 1 started" in msg


def test_a_click_outside_the_region_adds_nothing_and_says_why():
    st = ExplorerState(MU, H, indicators=False)
    c1, c2, r1, r2 = st.region
    assert st.click(c1 + 1.01 * r1, c2) is None
    assert st.seeds == [] and st.orbits == [] and "outside the allowed region" in st.message


def test_a_parameter_change_removes_orbits_keeps_seeds_and_rerun_restarts_the_admissible_ones():
    st = ExplorerState(model.FIGURE4, H, chunk=5, max_crossings=5, indicators=False)
    st.click(0.2, 0.0)
    c1, c2, r1, r2 = st.region
    edge = (c1 + 0.99 * r1, c2)
    st.click(*edge)
    assert len(st.orbits) == 2
    assert st.set_params(st.parse_assignments("mu=0.5; h=1.5")) is True
    assert st.params.mu == 0.5 and st.h == 1.5 and st.orbits == [] and len(st.seeds) == 2
    assert not st.admissible(*edge)                               # the region shrank
    started = st.rerun()
    assert [o.seed for o in started] == [(0.2, 0.0)] and "1 outside the allowed region" in st.message
    assert st.set_params({"mu": 0.5}) is False                    # nothing changed
    with pytest.raises(model.ParameterError, match="unknown parameter 'nope'"):
        st.set_params({"nope": 1})
    with pytest.raises(model.ParameterError, match="write name=value"):
        st.parse_assignments("mu 3")


def test_the_panel_arrays_hold_what_was_computed_and_mark_running_orbits():
    st = ExplorerState(MU, H, chunk=10, max_crossings=30, indicators=False)
    st.click(0.3, 0.1)
    st.click(-0.2, 0.2)
    st.step()
    a = st.panel_arrays()
    assert a["count"].tolist() == [10, 10] and a["offsets"].tolist() == [0, 10, 20]
    assert a["status"].tolist() == [STATUS_RUNNING, STATUS_RUNNING]
    np.testing.assert_array_equal(a["crossings"][:10], st.orbits[0].crossings)
    st.run_until_done()
    assert st.panel_arrays()["status"].tolist() == [0, 0]
    assert st.clear() == 2 and st.orbits == [] and st.seeds == []
