"""Chaplygin's chaos indicators on the indicators template of every System (integrate/codegen_indicators.py,
docs/systems.md "Chaos indicators"): the generated module of chaplygin.variational (tangent.indicators_module)
holds R3's recurrence in its orbit rows and the engine's variational recurrence in its vector rows, bit for bit;
its SIMD lanes give the template's scalar driver bit for bit (one and two deviation vectors, early
classification, history rows, orbits stopping for every reason) for 1 and 2 threads and any orbit order; the
generated file is up to date."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import PARAM_SETS, random_states

from explorer import model
from explorer.analysis import lyapunov
from explorer.analysis.system_sections import run_driver
from explorer.integrate import _tangent_lanes_generated as G
from explorer.integrate import lanes, tangent
from explorer.kernels import STATUS_CANCELLED, STATUS_MAX_STEPS, STATUS_NONFINITE
from explorer.kernels import indicator_table as table
from explorer.kernels import taylor as tk

ROOT = Path(__file__).resolve().parents[2]
L = lanes.LANES


def test_generated_tangent_file_is_up_to_date(tmp_path):
    out = tmp_path / "gen.py"
    tout = tmp_path / "tgen.py"
    subprocess.run([sys.executable, str(ROOT / "tools" / "gen_lanes.py"), "-o", str(out), "--tangent-output",
                    str(tout)], check=True, capture_output=True)
    assert tout.read_text() == (ROOT / "src/explorer/integrate/_tangent_lanes_generated.py").read_text(), \
        "src/explorer/integrate/_tangent_lanes_generated.py is stale: run tools/gen_lanes.py"


@pytest.mark.parametrize("name", sorted(PARAM_SETS))
@pytest.mark.parametrize("order", [4, 20])
def test_tangent_lane_kernels_match_the_scalar_recurrence_bitwise(name, order):
    """Every lane of the indicator module's recurrence (one and two vectors) is its scalar twin, its orbit
    and first vector rows the engine's tangent recurrence (_tangent_lanes_generated, the orbit's
    decomposition extended: explorer.integrate.codegen.decompose_extending), and the module's Horner on
    lanes (``_evaluate_lanes``) is kernels.taylor.evaluate on each lane's rows."""
    P = PARAM_SETS[name].as_array()
    rng = np.random.default_rng(order)
    Z0 = np.zeros((15, L))
    Z0[:5] = random_states(PARAM_SETS[name], L, seed=order, scale=2.0).T
    Z0[5:] = rng.normal(size=(10, L))
    Z0[:, 0] = 0.0      # an idle lane
    h = rng.uniform(0.0, 0.5, L)
    for nvec in (1, 2):
        mod = tangent.indicators_module(nvec)
        rows = 5 * (1 + nvec)
        X = np.zeros((order + 1, rows, L))
        X[0] = Z0[:rows]
        mod.taylor_coefficients_lanes(P, X, order, np.zeros((order + 1, max(mod.N_WORK, 1), L)))
        out = np.empty((rows, L))
        mod._evaluate_lanes(X, order, h, out)
        for l in range(L):
            S = np.zeros((rows, order + 1))
            S[:, 0] = Z0[:rows, l]
            mod.taylor_coefficients(P, S, order)
            np.testing.assert_array_equal(S.T, X[:, :, l])
            E = np.zeros((10, order + 1))
            E[:, 0] = Z0[:10, l]
            G.tangent_coefficients(P, E, order)
            np.testing.assert_array_equal(E, S[:10])
            for r in range(0, rows, 5):
                y = np.empty(5)
                tk.evaluate(S[r:r + 5], order, h[l], y)
                np.testing.assert_array_equal(y, out[r:r + 5, l])


# ---------------------------------------------------------------- whole batches
def _orbits(n, seed=3):
    """Orbits of Figure 4 at mu = 1 (regular and chaotic), with their default deviation vectors."""
    prm = model.FIGURE4.with_(mu=1.0)
    c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
    rng = np.random.default_rng(seed)
    rad = np.sqrt(rng.uniform(0, 0.8, n))
    ang = rng.uniform(0, 2 * np.pi, n)
    Y0 = model.section_state(prm, c1 + r1 * rad * np.cos(ang), c2 + r2 * rad * np.sin(ang), 2.0)
    P = prm.as_array()
    V0 = lyapunov.deviation_vector(P, Y0)
    W0 = lyapunov.second_deviation_vector(P, Y0)
    return P, np.ascontiguousarray(Y0), np.ascontiguousarray(V0), np.ascontiguousarray(W0)


def _run(driver, threads, P, Y0, V0, W0, nvec, early, T=60.0, order=16, max_steps=10**9, H=4, stop=0):
    """The indicator module's driver (``lanes`` or ``scalar``) as lyapunov.indicators calls it, its stop
    switch set to ``stop``."""
    n = Y0.shape[0]
    hist_t = np.geomspace(1.0, T, H)
    out = (np.full((n, H, table.N_RES), np.nan), np.zeros((n, table.N_RES)), np.full((n, table.N_EXT), np.nan),
           np.zeros(n, np.int64), np.zeros((n, 5)), np.zeros(n, np.int64), np.full((n, 2, 5), np.nan))
    run_driver(tangent.indicators_module(nvec), "indicators", n, driver, threads,
               (Y0, V0, W0, 5, nvec, P, T, order, max_steps, early, 1e-8, 6.0, 10.0, hist_t, *out,
                np.full(1, stop, np.int64)))
    return out


def _assert_same(a, b):
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("nvec,early", [(1, False), (2, True)])
def test_lane_batches_equal_the_scalar_reference_for_any_threads_lanes_and_order(nvec, early):
    """The lanes (1 and 2 threads, orbits permuted) give the template's scalar driver bit for bit."""
    P, Y0, V0, W0 = _orbits(19)
    ref = _run("scalar", 1, P, Y0, V0, W0, nvec, early)
    if early:
        assert np.any(ref[2][:, table.EXT_EARLY] > 0) and np.any(ref[2][:, table.EXT_EARLY] == 0)
    for threads in (1, 2):
        _assert_same(_run("lanes", threads, P, Y0, V0, W0, nvec, early), ref)
    perm = np.random.default_rng(0).permutation(len(Y0))
    got = _run("lanes", 2, P, Y0[perm], V0[perm], W0[perm], nvec, early)
    _assert_same([g[np.argsort(perm)] for g in got], ref)


def test_vector_step_end_is_the_scalar_one_and_leaves_stops_and_history_rows_to_the_scalar_loop():
    """Many history rows, early stops, step budgets that end orbits mid-run and a non-finite start: the
    lanes (whose vector step end hands these steps to the per-lane code) give the scalar driver's rows."""
    P, Y0, V0, W0 = _orbits(11, seed=7)
    Y0[4, 2] = 1e200          # coefficients overflow: non-finite
    for max_steps in (0, 7, 10**9):
        ref = _run("scalar", 1, P, Y0, V0, W0, 2, True, max_steps=max_steps, H=25)
        _assert_same(_run("lanes", 1, P, Y0, V0, W0, 2, True, max_steps=max_steps, H=25), ref)
    assert ref[3][4] == STATUS_NONFINITE
    ref = _run("scalar", 1, P, Y0, V0, W0, 2, False, max_steps=7)
    assert np.all(ref[3][np.arange(11) != 4] == STATUS_MAX_STEPS)


@pytest.mark.parametrize("driver", ["lanes", "scalar"])
def test_a_set_stop_switch_ends_every_orbit_before_its_first_step_on_either_driver(driver):
    """More orbits than the lanes of both threads hold: those in a lane and those still queued all end
    cancelled, with no step taken (analysis.budget reads the status and raises BudgetExceeded)."""
    from explorer.integrate.simd import LANES

    P, Y0, V0, W0 = _orbits(3 * LANES)
    out = _run(driver, 2, P, Y0, V0, W0, 2, False, stop=1)
    status, steps = out[3], out[5]
    assert np.all(status == STATUS_CANCELLED) and np.all(steps == 0), (status, steps)
