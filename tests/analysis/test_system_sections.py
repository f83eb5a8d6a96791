"""Crossings of a System's section EXPR = 0 (docs/systems.md, "Crossings"): times and states
against scipy's DOP853 with events, the energy at each crossing, any hyperplane and direction,
thread independence, statuses and the refusals."""
import numpy as np
import pytest
import sympy as sp
from systems import henon_heiles, lam, pole, x, y

import explorer as ex
from explorer.kernels import Status
from explorer.model import ParameterError

E = 1.0 / 8.0


def starts(points):
    """States on x = 0 at energy E with px > 0 from (y, py) (lam = 1)."""
    out = []
    for yy, pyy in points:
        out.append([0.0, yy, np.sqrt(2*E - pyy**2 - yy**2 + 2*yy**3/3), pyy])
    return np.array(out)


def scipy_crossings(system, y0, a, b, direction, n, t_end):
    """(times, states) of the first n crossings of a . y + b = 0 by DOP853 at rtol = atol = 1e-13."""
    from scipy.integrate import solve_ivp

    from explorer.integrate import codegen

    mod = codegen.load(system)
    P = system.parameter_array()

    def f(_, yy):
        dy = np.empty(len(yy))
        mod.rhs(yy, P, dy)
        return dy

    def event(_, yy):
        return float(np.dot(a, yy) + b)

    event.direction = direction
    sol = solve_ivp(f, (0.0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-13, events=event)
    t, ys = sol.t_events[0], sol.y_events[0]
    if np.dot(a, y0) + b == 0.0 and t.size and t[0] == 0.0:   # scipy may report the start on the section
        t, ys = t[1:], ys[1:]
    return t[:n], ys[:n]


# three regular orbits at E = 1/8 (a chaotic one separates from any reference exponentially)
POINTS = [(0.1, 0.1), (-0.1, 0.2), (0.3, 0.0)]


def test_henon_heiles_crossings_of_x_equal_0_agree_with_dop853_and_conserve_the_energy():
    hh = henon_heiles()
    Y0 = starts(POINTS)
    res = ex.crossings(hh, states=Y0, n_crossings=50, section=x, direction=+1)
    assert isinstance(res, ex.Crossings) and res.data.shape == (3, 50, 6)
    assert np.all(res.count == 50) and all(res.status_of(i) == Status.DONE for i in range(3))
    worst_t = worst_y = 0.0
    for i in range(3):
        t, ys = scipy_crossings(hh, Y0[i], np.array([1.0, 0, 0, 0]), 0.0, +1, 50, res.data[i, -1, 0] + 1.0)
        rows = res.orbit(i)
        assert t.size == 50
        worst_t = max(worst_t, np.max(np.abs(rows[:, 0] - t)))
        worst_y = max(worst_y, np.max(np.abs(rows[:, 1:5] - ys)))
        assert np.all(rows[:, 3] > 0.0)                       # dx/dt = px > 0 at every crossing
    # DOP853 at 1e-13 over t ~ 320 is the larger error (9e-10 in t on the second orbit, 2e-10 in the
    # state), the Taylor method's own tightening (tol 1e-16, order 20) moves them by 1.2e-11
    assert worst_t <= 2e-9, worst_t
    assert worst_y <= 1e-9, worst_y
    tight = ex.crossings(hh, states=Y0, n_crossings=50, section=x, direction=+1, tol=1e-16)
    assert np.max(np.abs(tight.data[..., :5] - res.data[..., :5])) <= 1e-10
    assert np.max(np.abs(res.data[..., 1])) <= 1e-15           # on the section x = 0
    assert np.max(np.abs(res.data[..., 5])) <= 1e-12           # E - E0 at every crossing
    assert res.settings["columns"] == ["t", "x", "y", "px", "py", "E - E0"]


def test_a_section_x_plus_y_equal_0_1_crossed_downwards_agrees_with_dop853():
    hh = henon_heiles()
    Y0 = starts(POINTS[:2])
    a, b = np.array([1.0, 1.0, 0.0, 0.0]), -0.1
    res = ex.crossings(hh, states=Y0, n_crossings=30, section=x + y - 0.1, direction=-1)
    assert np.all(res.count == 30)
    for i in range(2):
        rows = res.data[i, :30]
        t, ys = scipy_crossings(hh, Y0[i], a, b, -1, 30, rows[-1, 0] + 1.0)
        assert np.max(np.abs(rows[:, 0] - t)) <= 1e-9
        assert np.max(np.abs(rows[:, 1:5] - ys)) <= 1e-9
        assert np.max(np.abs(rows[:, 1:5] @ a + b)) <= 1e-14   # on the section
        assert np.all(rows[:, 3] + rows[:, 4] < 0.0)           # ds/dt = px + py < 0


def test_crossings_of_a_system_are_identical_with_one_and_two_threads():
    hh = henon_heiles()
    Y0 = starts(POINTS + [(0.0, 0.35), (-0.2, -0.1)])
    one = ex.crossings(hh, states=Y0, n_crossings=20, section=x, direction=+1, threads=1)
    two = ex.crossings(hh, states=Y0, n_crossings=20, section=x, direction=+1, threads=2)
    np.testing.assert_array_equal(one.data, two.data)
    np.testing.assert_array_equal(one.final, two.final)
    np.testing.assert_array_equal(one.info, two.info)


def test_the_rows_do_not_depend_on_the_driver():
    from explorer.analysis.system_sections import driver_for

    hh = henon_heiles()
    Y0 = starts(POINTS + [(0.0, 0.35), (-0.2, -0.1)])
    runs = [ex.crossings(hh, states=Y0[:n], n_crossings=20, section=x, direction=+1, driver=d)
            for n in (1, 5) for d in ("auto", "lanes", "scalar")]
    for first, other in ((runs[0], runs[1]), (runs[0], runs[2]), (runs[3], runs[4]), (runs[3], runs[5])):
        for name in ("data", "count", "status", "final", "info"):
            np.testing.assert_array_equal(getattr(first, name), getattr(other, name), strict=True)
    # auto is the lanes, for any number of orbits (one group of lanes per thread, at most ceil(n / LANES))
    assert driver_for(1) == 1 and driver_for(40, "lanes") >= 1 and driver_for(40, "scalar") == 0


def test_a_parameter_in_the_section_takes_its_value():
    hh = henon_heiles()
    res = ex.crossings(hh.with_(lam=0.5), states=starts(POINTS[:1]), n_crossings=5, section=x - lam / 10,
                       direction=+1)
    assert np.max(np.abs(res.data[0, :, 1] - 0.05)) <= 1e-15


# ---------------------------------------------------------------------- statuses
def test_an_orbit_that_never_crosses_ends_with_the_budget_status():
    # lam = 0: two harmonic oscillators of period 2 pi; from x = 1 at rest, x = cos t never reaches 2
    lin = henon_heiles(0.0)
    rest = [[1.0, 0.0, 0.0, 0.0]]
    res = ex.crossings(lin, states=rest, n_crossings=3, section=x - 2, direction=+1, tmax=20.0)
    assert res.count[0] == 0 and res.status_of(0) == Status.TMAX and res.info[0, 0] == 20.0
    res = ex.crossings(lin, states=rest, n_crossings=3, section=x - 2, direction=+1, max_steps=7)
    assert res.count[0] == 0 and res.status_of(0) == Status.MAX_STEPS and res.info[0, 1] == 7
    # the same orbit crosses x = 0.5 upwards once per period 2 pi
    res = ex.crossings(lin, states=rest, n_crossings=3, section=2*x - 1, direction=+1)
    assert res.status_of(0) == Status.DONE
    np.testing.assert_allclose(res.data[0, :, 0], 2*np.pi*np.arange(1, 4) - np.pi/3, rtol=0, atol=1e-12)


def test_a_division_by_a_zero_denominator_gives_the_non_finite_status():
    system, _, w = pole()
    res = ex.crossings(system, states=[[0.0, 0.0], [-1.0, 0.0]], n_crossings=1, section=w - 100, direction=+1)
    assert res.status_of(0) == Status.NONFINITE and res.count[0] == 0
    # approached continuously, the steps shrink with the radius of convergence |s| (a fixed
    # fraction of the distance to the pole): the orbit stops at the pole, t = 1 to rounding, with
    # the step underflow, and never crosses past it
    assert res.status_of(1) == Status.STEP_UNDERFLOW and res.count[1] == 0
    assert 1.0 - 1e-12 <= res.info[1, 0] <= 1.0


# ---------------------------------------------------------------------- refusals
@pytest.mark.parametrize(("kw", "match"), [
    (dict(section=x * y), "section x\\*y is not linear in the state"),
    (dict(section=sp.sin(x)), "is not linear in the state"),
    (dict(section=x - sp.Symbol("z")), "uses z, which is neither a state variable"),
    (dict(section=sp.Integer(2)), "does not depend on the state"),
    (dict(section="x"), "section must be a sympy expression"),
    (dict(section=None), "section is missing"),
    (dict(section=x, direction=0), "direction must be \\+1 .* or -1"),
    (dict(section=x, direction=2), "direction must be"),
    (dict(section=x, direction=True), "direction must be"),
    (dict(section=x, n_crossings=0), "n_crossings must be"),
    (dict(section=x, states=np.zeros((2, 3))), "states must have shape \\(N, 4\\) = \\(x, y, px, py\\)"),
    (dict(section=x, states=[[0.0, np.nan, 0.0, 0.0]]), "states must be finite"),
    (dict(section=x, method="dop853"), "method must be 'taylor' for a System"),
    (dict(section=x, phi0=1.0), "phi0 do\\(es\\) not apply"),
    (dict(section=x, tol=0.5), "tol must be"),
    (dict(section=x, driver="simd"), "driver must be one of 'auto', 'lanes', 'scalar', got 'simd'"),
])
def test_a_bad_request_is_refused_with_a_message_naming_the_parameter(kw, match):
    args = dict(states=starts(POINTS[:1]), n_crossings=5, direction=+1)
    args.update(kw)
    with pytest.raises(ParameterError, match=match):
        ex.crossings(henon_heiles(), **args)


def test_the_example_of_docs_systems_md_runs():
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "systems.md").read_text()
    block = page.split("## Crossings of a section", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    namespace = {}
    exec(compile(block, "docs/systems.md", "exec"), namespace)   # its own asserts check the result
    assert namespace["res"].data.shape == (3, 500, 6)
    assert namespace["other"].settings["section"] == "x + y - 0.1"


def test_section_is_refused_for_chaplygins_model_which_takes_phi0():
    with pytest.raises(ParameterError, match="section= is the hyperplane EXPR = 0 of a System"):
        ex.crossings(ex.FIGURE4, ex.FIGURE4_H, [(0.1, 0.0)], n_crossings=2, section=x)


def streamed(blocks, n_orbits):
    """Per orbit, the rows of ``blocks`` joined in order (each block's start must follow the last),
    and the last block's state."""
    rows, state = [[] for _ in range(n_orbits)], None
    for blk in blocks:
        for k, i in enumerate(blk.index):
            assert blk.start[k] == sum(len(r) for r in rows[i])
            rows[i].append(blk.rows(k))
        state = blk.state
    return [np.concatenate(r) if r else np.zeros((0, 6)) for r in rows], state


@pytest.mark.parametrize("driver", ["auto", "scalar"])
def test_a_systems_crossings_streamed_in_blocks_of_any_size_are_one_runs_rows_bit_for_bit(driver):
    """sections.iter_crossings streams a System from its drivers' carry (docs/architecture.md, "Streaming"):
    blocks of 1, 7 or all crossings, and a run resumed from a block's state, concatenate to one run's rows,
    counts, statuses, final states and info bit for bit, also for orbits the time budget stops mid-run."""
    from explorer.analysis import sections

    hh = henon_heiles()
    Y0 = starts(POINTS + [(0.0, 0.35), (-0.2, -0.1)])
    K, n = 30, len(Y0)
    tmax = float(np.median(ex.crossings(hh, states=Y0, n_crossings=K, section=x).data[:, K - 1, 0]))
    kw = dict(states=Y0, n_crossings=K, section=x, direction=+1, tmax=tmax, driver=driver)
    one = ex.crossings(hh, **kw)
    assert 0 < np.sum(one.status == Status.TMAX) < n        # some orbits are cut by the time budget
    first = next(sections.iter_crossings(hh, block=7, **kw))
    runs = [sections.iter_crossings(hh, block=b, **kw) for b in (1, 7, K)]
    runs.append(iter([first, *sections.iter_crossings(hh, block=7, state=first.state, **kw)]))
    for blocks in runs:
        rows, state = streamed(blocks, n)
        for i in range(n):
            np.testing.assert_array_equal(rows[i], one.orbit(i), strict=True)
        for name, got in (("count", state.done), ("status", state.status), ("final", state.y), ("info", state.info)):
            np.testing.assert_array_equal(got, getattr(one, name), err_msg=name, strict=True)
        assert state.finished.all()


@pytest.mark.parametrize("driver", ["auto", "scalar"])
def test_a_systems_blocks_cut_at_their_steps_are_one_runs_rows_and_keep_the_runs_step_budget(driver):
    """step_block ends a System's block once the least advanced orbit took that many steps in it (as
    Chaplygin's, test_streaming.py): the blocks resume to one run's rows, counts, statuses, final states
    and info bit for bit, a run's own max_steps still ends it, and no block takes an orbit more than
    step_block steps beyond the least advanced one."""
    from explorer.analysis import sections
    from explorer.integrate import layout

    hh = henon_heiles()
    Y0 = starts(POINTS + [(0.0, 0.35)])
    for max_steps in (10**6, 400):
        kw = dict(states=Y0, n_crossings=30, section=x, max_steps=max_steps, driver=driver)
        one = ex.crossings(hh, **kw)
        blocks = list(sections.iter_crossings(hh, block=20, step_block=37, **kw))
        rows, state = streamed(blocks, len(Y0))
        for i in range(len(Y0)):
            np.testing.assert_array_equal(rows[i], one.orbit(i), strict=True)
        for name, got in (("count", state.done), ("status", state.status), ("final", state.y), ("info", state.info)):
            np.testing.assert_array_equal(got, getattr(one, name), err_msg=name, strict=True)
        steps = [b.state.carry[:, layout.CARRY_STEPS] for b in blocks]
        assert all(np.max(b - a) <= 37 + np.ptp(a) for a, b in zip(steps, steps[1:]))
        assert len(blocks) > 2 and state.finished.all()     # the step cap, not only the crossing count, cut blocks
    assert np.any(one.status == Status.MAX_STEPS)           # 400 steps end the run, not a block's cap
    with pytest.raises(ParameterError, match="step_block"):
        next(sections.iter_crossings(hh, block=20, step_block=0, **kw))
